"""The soft-soil tyre model (mftyre.soil): seed 003's worked numbers, analytic limits, physical trends, CasADi,
the ground switch and bad input."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from conftest import TIR_FILES
from mftyre.backend import NUMPY
from mftyre.errors import DataError, ModelInputError
from mftyre.model import load_tir
from mftyre.soil import Ground, SinkageError, Soil, SoftSoilTyre, builtin_soils, read_soils, soil
from mftyre.soil.equations import (bulldozing_coefficients, compaction_resistance, critical_pressure,
                                   rigid_wheel_sinkage)

AGRI = TIR_FILES / "agri_460_85R34_mf61.tir"
AGRI_SMALL = TIR_FILES / "agri_420_85R24_mf61.tir"
CAR = TIR_FILES / "car_205_60R15_mf61.tir"
PADDY = soil("paddy_soil")
# seed 003's flotation tyre (29x12.50-15): diameter and width
SEED_D, SEED_B = 0.73, 0.305


# ------------------------------------------------------------------------------------------------ seed 003
def test_seed003_rigid_wheel_sinkage_at_3_5_kN():
    """Seed 003, eq. 2: z = 0.125 m at W = 3.5 kN (D 0.73 m, b 0.305 m, n 0.4, k_c 1.87 kN/m^1.4, k_phi 96.08
    kN/m^2.4). The exponent is printed as 2/(2n-1) in the seed (an extraction garble: with n = 0.4 that is -10 and
    gives z = 1.6e8 m); Bekker's original rigid-wheel formula has 2/(2n+1) and gives 0.1230 m, which the seed
    rounds to 0.125 m (1.6 % apart)."""
    z = rigid_wheel_sinkage(PADDY, 3.5e3, SEED_D, SEED_B, NUMPY)
    assert z == pytest.approx(0.1230, abs=5e-4)
    assert z == pytest.approx(0.125, rel=0.02)
    # the seed's geometric contact length (its eq. 3) with its rounded z = 0.125 m is 0.55 m; ours with 0.123 m
    r = SEED_D / 2
    assert 2 * math.sqrt(r**2 - (r - z) ** 2) == pytest.approx(0.55, rel=0.01)


def test_seed003_critical_pressure_at_5_kN():
    """Seed 003, eq. 1 quotes p_cr = 29.65 kPa at W = 5 kN. Not reproduced: Wong's critical pressure
    p_cr = (k_c/b + k_phi)^(1/(2n+1)) [3W / ((3-n) b sqrt(D))]^(2n/(2n+1)) = k z_r^n, the pressure under the
    rigid wheel, is 51.8 kPa with these constants. Dropping b from the second bracket (dimensionally wrong: the
    result is then not in Pa) gives 30.6 kPa, within 3 % of the seed's number, so the seed most likely lost that b;
    its printed exponents (n/(2n+1) on the first bracket) give 6.5 kPa. The seed's conclusion holds either way:
    the tyre's 68.95 kPa inflation pressure exceeds p_cr, so it behaves as a rigid wheel."""
    n, k = PADDY.n, PADDY.modulus(SEED_B) / 1e3  # kN/m^(n+2)
    p_cr = critical_pressure(PADDY, 5e3, SEED_D, SEED_B, NUMPY)
    assert p_cr == pytest.approx(51.8e3, rel=2e-3)
    z5 = rigid_wheel_sinkage(PADDY, 5e3, SEED_D, SEED_B, NUMPY)
    assert p_cr == pytest.approx(PADDY.modulus(SEED_B) * z5**n, rel=1e-12)
    without_b = k ** (1 / (2 * n + 1)) * (3 * 5.0 / ((3 - n) * math.sqrt(SEED_D))) ** (2 * n / (2 * n + 1))
    assert without_b == pytest.approx(29.65, rel=0.035)
    assert 68.95e3 > p_cr


def test_seed003_sinkage_grows_with_load_against_fe():
    """Seed 003's FE sinkages (Drucker-Prager paddy soil, 29x12.50-15 at 10 psi, rigid mode per the seed):
    1.5/2.8/3.6/4.8/5.6 kN -> 48/62/102/148/180 mm. Bekker's rigid wheel with the seed's constants gives
    48/96/127/175/207 mm: the same growth with load and the same value at 1.5 kN, but 15-55 % deeper at 2.8-5.6 kN
    (worst at 2.8 kN, where the FE curve has a kink). FE with Drucker-Prager soil is not Bekker: agreement within a
    factor 1.6 is what this test holds, and the growth z ~ W^(2/(2n+1)) = W^1.11."""
    loads = np.array([1.5, 2.8, 3.6, 4.8, 5.6]) * 1e3
    fe = np.array([48, 62, 102, 148, 180]) * 1e-3
    z = rigid_wheel_sinkage(PADDY, loads, SEED_D, SEED_B, NUMPY)
    assert np.all(np.diff(z) > 0)
    assert z[0] == pytest.approx(fe[0], rel=0.02)
    ratio = z / fe
    assert np.all((ratio > 1 / 1.6) & (ratio < 1.6)), ratio
    assert np.log(z[-1] / z[0]) / np.log(loads[-1] / loads[0]) == pytest.approx(2 / (2 * PADDY.n + 1), rel=1e-9)


def test_seed003_thrust_formula_and_what_the_model_does_instead():
    """Seed 003, eq. 5: F = (c b L + W tan phi)(1 - exp(-i L / k)) = 2.14 kN at i = 0.14, W = 3.5 kN, L = 0.55 m,
    with the paddy constants of our table (c 6.25 kPa, phi 30.2 deg, k = K 0.065 m). That form takes the shear
    displacement at the rear end of the contact (i L) for the whole contact. The model integrates the
    Janosi-Hanamoto stress along the contact instead (Wong's form, 1.28 kN with the same L), and a rolling rigid
    wheel touches the soil only on its front arc (0.27 m, not the seed's static chord 0.55 m), with Bekker's
    normal stress there: 0.68 kN for a 0.73 m x 0.305 m tyre at 68.95 kPa (rigid mode, as the seed says)."""
    c, phi, K = PADDY.c, PADDY.phi, PADDY.K
    W, L, i, b = 3.5e3, 0.55, 0.14, SEED_B
    seed = (c * b * L + W * math.tan(phi)) * (1 - math.exp(-i * L / K))
    assert seed == pytest.approx(2.14e3, rel=0.005)
    wong = (c * b * L + W * math.tan(phi)) * (1 - K / (i * L) * (1 - math.exp(-i * L / K)))
    assert wong == pytest.approx(1.28e3, rel=0.01)
    seed_tyre = load_tir(CAR).with_params(UNLOADED_RADIUS=SEED_D / 2, WIDTH=SEED_B, Q_RE0=1.0, INFLPRES=68.95e3,
                                          NOMPRES=68.95e3, PRESMIN=5e4)
    out = SoftSoilTyre(seed_tyre, PADDY).evaluate(fz=W, slip=i)
    assert float(out.flexible) == 0.0
    assert float(out.contact_length) == pytest.approx(math.sqrt(SEED_D * 0.12295 - 0.12295**2), rel=1e-3)
    assert 0.25 * seed < float(out.gross_traction) < 0.6 * wong


# ------------------------------------------------------------------------------------------ analytic checks
def _tread_slip(out, vx):
    return 1.0 - vx / (out.omega * out.rolling_radius)


def _arc_extent(tyre, out):
    """Horizontal extent of the front arc, r (sin theta_e - sin theta_f), from the outputs."""
    r = tyre.params.UNLOADED_RADIUS * tyre.params.Q_RE0
    cos_f = (r - out.deflection) / r
    cos_e = cos_f - out.sinkage / r
    return r * (np.sqrt(1 - cos_e**2) - np.sqrt(1 - cos_f**2)), r


@pytest.mark.parametrize("soil_name, p", [("sandy_loam", 1.2e5), ("paddy_soil", 1.6e5)])
def test_thrust_equals_janosi_hanamoto_closed_form_for_uniform_strength(soil_name, p):
    """With phi = 0 the shear strength is c everywhere and the thrust has a closed form. Rigid mode (paddy):
    Wong's H = sign(i) c b L [1 - K/(|i| L)(1 - exp(-|i| L / K))] with the arc's tread slip i = 1 - V/(omega r).
    Flexible mode (sandy loam): the arc (length X, tread slip i_a = 1 - V/(omega r)) is followed by the flat part
    (length 2a, tread slip i_f = 1 - V/(omega Re)) with j = i_a X + i_f s there, so
    H / (c b) = X - K/|i_a| (1 - e^(-|i_a| X/K)) + 2a - K/|i_f| e^(-|i_a| X/K) (1 - e^(-2a |i_f|/K))
    (signs as the slips; at these slips both parts shear the same way)."""
    base = soil(soil_name)
    cohesive = Soil("cohesive", base.n, base.k_c, base.k_phi, 5e3, 0.0, base.K)
    tyre = SoftSoilTyre(AGRI, cohesive)
    slip = np.array([-0.3, 0.02, 0.1, 0.3, 0.7])
    out = tyre.evaluate(fz=20e3, slip=slip, p=p, vx=2.0)
    arc, r = _arc_extent(tyre, out)
    flat = out.contact_length - arc
    i_a, i_f = 1 - 2.0 / (out.omega * r), _tread_slip(out, 2.0)
    assert np.all(np.sign(i_a) == np.sign(i_f))
    K, b = cohesive.K, out.contact_width
    with np.errstate(all="ignore"):
        on_arc = arc - K / np.abs(i_a) * (1 - np.exp(-np.abs(i_a) * arc / K))
        on_flat = np.where(flat > 0, flat - K / np.abs(i_f) * np.exp(-np.abs(i_a) * arc / K)
                           * (1 - np.exp(-np.abs(i_f) * flat / K)), 0.0)
    closed = np.sign(i_a) * cohesive.c * b * (on_arc + on_flat)
    np.testing.assert_allclose(out.gross_traction, closed, rtol=1e-8)
    assert set(out.flexible) == ({1.0} if soil_name == "sandy_loam" else {0.0})
    if soil_name == "paddy_soil":  # no flat part: Wong's one-slip form
        L, u = out.contact_length, np.abs(i_a) * out.contact_length / K
        np.testing.assert_allclose(out.gross_traction, np.sign(i_a) * cohesive.c * b * L * (1 - (1 - np.exp(-u)) / u),
                                   rtol=1e-8)


@pytest.mark.parametrize("soil_name, p", [("sandy_loam", 1.2e5), ("paddy_soil", 1.6e5), ("dry_sand", 1.0e5)])
def test_thrust_and_lateral_force_against_adaptive_quadrature(soil_name, p):
    """The Gauss sums against scipy's adaptive quadrature of the same integrand, rebuilt from the documented
    equations and the outputs (sinkage, deflection, contact length): tau = (c + sigma tan phi)(1 - exp(-j/K))
    along (j_x, j_y), sigma = k (r (cos theta - cos theta_e))^n on the arc and k z^n on the flat part, with the
    arc's tread slip i_a = 1 - V/(omega r) and the flat part's i_f = 1 - V/(omega Re) (j_x = i_a X + i_f (x - X)
    there); and the torque about the axle r H_arc + (r - delta) H_flat."""
    s = soil(soil_name)
    tyre = SoftSoilTyre(AGRI, s)
    prm = tyre.params
    r = prm.UNLOADED_RADIUS * prm.Q_RE0
    for slip, alpha in ((0.15, 0.0), (0.4, 0.05), (-0.2, -0.1)):
        out = tyre.evaluate(fz=25e3, slip=slip, alpha=alpha, p=p, vx=2.0)
        z, delta, L, b = (float(out[k]) for k in ("sinkage", "deflection", "contact_length", "contact_width"))
        i_f, i_a = float(_tread_slip(out, 2.0)), float(1 - 2.0 / (out.omega * r))
        k = s.modulus(b)
        cos_f, cos_e = (r - delta) / r, (r - delta - z) / r
        arc = r * (math.sqrt(1 - cos_e**2) - math.sqrt(1 - cos_f**2))

        def sigma(x):
            if x >= arc:
                return k * z**s.n
            sin_t = math.sqrt(1 - cos_e**2) - x / r
            return k * max(r * (math.sqrt(1 - sin_t**2) - cos_e), 0.0) ** s.n

        def tau(x, component):
            on_arc, on_flat = min(x, arc), max(x - arc, 0.0)
            jx = i_a * on_arc + i_f * on_flat
            jy = ((1 - i_a) * on_arc + (1 - i_f) * on_flat) * math.tan(alpha)
            j = math.hypot(jx, jy)
            return (s.c + sigma(x) * math.tan(s.phi)) * (1 - math.exp(-j / s.K)) * (jx, jy)[component] / j

        h_arc, h_flat = (b * quad(tau, lo, hi, args=(0,), epsabs=1e-10, limit=200)[0] for lo, hi in ((0, arc), (arc, L)))
        h = h_arc + h_flat
        assert float(out.torque) == pytest.approx(r * h_arc + (r - delta) * h_flat, rel=2e-4)
        fy = -b * sum(quad(tau, lo, hi, args=(1,), epsabs=1e-10, limit=200)[0] for lo, hi in ((0, arc), (arc, L)))
        assert float(out.gross_traction) == pytest.approx(h, rel=2e-4)
        if alpha:
            assert float(out.fy) == pytest.approx(fy, rel=2e-4)
            assert np.sign(float(out.fy)) == -np.sign(alpha)  # ISO-W: Fy opposes the slip angle


def test_rigid_wheel_limit_matches_bekker_closed_forms():
    """A tyre far stiffer than the soil (p_g >> p_cr) is a rigid wheel: its sinkage is Bekker's rigid-wheel
    sinkage, its compaction resistance Bekker's closed form in W,
    R_c = (3W/sqrt(D))^((2n+2)/(2n+1)) / [(3-n)^((2n+2)/(2n+1)) (n+1) (k_c + b k_phi)^(1/(2n+1))],
    and the vertical reaction of the front arc, b int k (r(cos theta - cos theta_e))^n dx, carries the load to
    within Bekker's approximation (7-10 % here: his formula replaces the circle by a parabola and expands
    (z - x^2/D)^n to first order)."""
    tyre = SoftSoilTyre(load_tir(AGRI).with_params(INFLPRES=2.4e5), "paddy_soil")
    prm, s = tyre.params, tyre.soil
    W = np.array([5e3, 10e3, 15e3])
    out = tyre.evaluate(fz=W, slip=0.1)
    assert np.all(out.flexible == 0) and np.all(out.deflection == 0)
    D, b, n = 2 * prm.UNLOADED_RADIUS * prm.Q_RE0, prm.WIDTH, s.n
    e = (2 * n + 2) / (2 * n + 1)
    bekker = (3 * W / np.sqrt(D)) ** e / ((3 - n) ** e * (n + 1) * (s.k_c + b * s.k_phi) ** (1 / (2 * n + 1)))
    np.testing.assert_allclose(out.motion_resistance, bekker, rtol=1e-10)
    np.testing.assert_allclose(out.sinkage, rigid_wheel_sinkage(s, W, D, b, NUMPY), rtol=1e-12)
    np.testing.assert_allclose(out.ground_pressure, out.critical_pressure, rtol=1e-12)
    r = D / 2
    for w, z, L in zip(W, out.sinkage, out.contact_length):
        carried = b * quad(lambda x: s.modulus(b) * (np.sqrt(r**2 - x**2) - (r - z)) ** n, 0, L)[0]
        assert carried == pytest.approx(w, rel=0.12)


# ---------------------------------------------------------------------------------------------- trends
def test_lower_pressure_less_sinkage_and_resistance_once_flexible():
    """Seed 001 (driven FE tyre) and Wong: once the tyre flattens, lower pressure -> larger footprint -> lower
    ground pressure -> less sinkage and less compaction resistance; at the same slip more drawbar pull."""
    for tir in (AGRI, AGRI_SMALL):
        for name in ("sandy_loam", "clayey_soil"):
            tyre = SoftSoilTyre(tir, name)
            p = np.array([1.0e5, 1.2e5, 1.4e5, 1.6e5])
            out = tyre.evaluate(fz=0.8 * tyre.params.FNOMIN, slip=0.15, p=p)
            assert np.all(out.flexible > 0.9), (tir.name, name)  # flexible (one point just inside the switch band)
            for key in ("sinkage", "motion_resistance", "ground_pressure"):
                assert np.all(np.diff(out[key]) > 0), (tir.name, name, key)
            assert np.all(np.diff(out.deflection) < 0)


def test_rigid_mode_is_independent_of_pressure():
    """Above the critical pressure the tyre is a rigid wheel: pressure no longer changes sinkage or resistance."""
    tyre = SoftSoilTyre(AGRI, "paddy_soil")
    out = tyre.evaluate(fz=30e3, slip=0.2, p=np.array([1.0e5, 1.6e5, 2.4e5]))
    assert np.all(out.flexible == 0)
    assert np.ptp(out.sinkage) == 0 and np.ptp(out.motion_resistance) == 0


def test_drawbar_pull_rises_with_slip_to_a_saturating_maximum():
    """DP(i) rises monotonically, concave, and saturates at the Mohr-Coulomb limit less the resistance,
    b int (c + sigma tan phi) dx - R_c, less the K/(iL) shortfall of the Janosi-Hanamoto integral. (That limit
    exceeds c A + W tan(phi) by the front arc's normal stress, which the model does not add to the load balance;
    see the module notes.)"""
    tyre = SoftSoilTyre(AGRI, "sandy_loam")
    slip = np.linspace(0.0, 0.95, 96)
    out = tyre.evaluate(fz=25e3, slip=slip, p=1.2e5)
    dp = out.drawbar_pull
    towed = tyre.towed(fz=25e3, p=1.2e5)
    assert float(towed.slip) < 0 and float(towed.drawbar_pull) < 0
    # DP rises through zero between the towed slip and 0: against the hard-ground Re the self-propelled point
    # is a small skid here, because the front arc runs at omega r > omega Re (see the module notes)
    assert float(tyre.evaluate(fz=25e3, slip=float(towed.slip), p=1.2e5).drawbar_pull) < 0 < dp[0]
    assert np.all(np.diff(dp) > 0) and np.all(np.diff(dp, 2) < 0)
    gain_late = dp[-1] - dp[60]                      # i 0.6 -> 0.95
    gain_early = dp[60] - dp[0]                      # i 0 -> 0.6
    assert gain_late < 0.1 * gain_early
    s = tyre.soil
    rigid_plastic = SoftSoilTyre(AGRI, Soil("stiff", s.n, s.k_c, s.k_phi, s.c, s.phi, 1e-9))  # K -> 0: tau = tau_max
    limit = float(rigid_plastic.evaluate(fz=25e3, slip=0.5, p=1.2e5).drawbar_pull)
    assert 0.9 * limit < dp[-1] < limit
    assert np.nanargmax(out.efficiency) < 30           # efficiency peaks at a moderate slip
    assert np.all(np.diff(out.sinkage) == 0)           # no slip sinkage in this model (documented)


def test_sinkage_grows_with_load():
    """Sinkage and compaction resistance grow with load, in the flexible mode (sandy loam) and in the rigid mode
    (paddy soil: z ~ W^(2/(2n+1)))."""
    out = SoftSoilTyre(AGRI, "sandy_loam").evaluate(fz=np.linspace(10e3, 40e3, 13), slip=0.1, p=1.2e5)
    assert np.all(out.flexible > 0.9)  # flexible (the lightest load just inside the switch band)
    assert np.all(np.diff(out.sinkage) > 0) and np.all(np.diff(out.motion_resistance) > 0)
    out = SoftSoilTyre(AGRI, "paddy_soil").evaluate(fz=np.linspace(5e3, 40e3, 15), slip=0.1, p=1.2e5)
    assert np.all(out.flexible == 0)
    assert np.all(np.diff(out.sinkage) > 0) and np.all(np.diff(out.motion_resistance) > 0)


def test_towed_wheel_on_soft_soil_turns_slower_than_on_hard_ground():
    """Seed 001 (FE P235/75R17 at 242 kPa, towed at 10 km/h on soft cohesive soil): the towed wheel turns slower
    on the soil than on the rigid road (its Fig. 12, until it stops turning). The model: zero torque
    r H_arc + (r - delta) H_flat = 0 (solved by SoftSoilTyre.towed). Rigid mode (the car tyre on wet heavy clay):
    the wheel turns at V / r, slower than V / Re. Flexible mode (the agricultural tyre on sandy loam): the
    front arc runs at omega r > omega Re, so the flat part must skid (slip < 0) to balance it: slower than on hard
    ground too. This failed before: the flexible towed wheel turned exactly at V / Re."""
    car = load_tir(CAR)
    v = 10 / 3.6
    hard = car.evaluate(fz=5e3, kappa=0.0, alpha=0.0, vx=v, p=2.42e5)
    towed = SoftSoilTyre(car, "heavy_clay_wet").towed(5e3, p=2.42e5, vx=v)
    assert float(towed.flexible) == 0.0
    assert abs(float(towed.torque)) < 1e-9 * 5e3
    assert float(towed.omega) < float(hard.omega)
    assert float(towed.omega) == pytest.approx(v / (car.params.UNLOADED_RADIUS * car.params.Q_RE0), rel=1e-12)

    agri = load_tir(AGRI)
    p = np.array([1.0e5, 1.2e5, 1.4e5, 1.6e5])
    towed = SoftSoilTyre(agri, "sandy_loam").towed(20e3, p=p, vx=2.0)
    hard = agri.evaluate(fz=20e3, kappa=0.0, alpha=0.0, vx=2.0, p=p)
    assert np.all(towed.flexible == 1)
    np.testing.assert_allclose(towed.torque, 0.0, atol=1e-9 * 20e3 * agri.params.UNLOADED_RADIUS)
    assert np.all(towed.slip < -0.005)
    assert np.all(towed.omega < hard.omega)
    # the torque really changes sign across the solution (a root, not a flat spot)
    soft = SoftSoilTyre(agri, "sandy_loam")
    assert np.all(soft.evaluate(fz=20e3, slip=towed.slip - 1e-3, p=p, vx=2.0).torque < 0)
    assert np.all(soft.evaluate(fz=20e3, slip=towed.slip + 1e-3, p=p, vx=2.0).torque > 0)


def test_towed_wheel_skids_less_at_lower_pressure():
    """Seed 001, Fig. 13: at 200 kPa the towed tyre travels farther on the soil before it stops turning than at
    242 kPa (larger footprint, lower ground pressure). The model's steady towed wheel (the agricultural tyre on
    sandy loam and on clayey soil, flexible mode): lower pressure -> less sinkage -> shorter front arc against a
    longer flat part -> less skid (slip closer to 0). Seed 001's FE wheel ends up not turning at all; the model has
    no soil flow ahead of the wheel and cannot stop it: only the trend is compared."""
    p = np.array([1.0e5, 1.15e5, 1.3e5, 1.45e5])
    for name in ("sandy_loam", "clayey_soil"):
        towed = SoftSoilTyre(AGRI, name).towed(20e3, p=p, vx=2.0)
        assert np.all(towed.flexible > 0.9), name
        assert np.all(np.diff(towed.slip) < 0), (name, towed.slip)


# ---------------------------------------------------------------------------------------------- casadi
def _points(rng, size):
    return dict(fz=rng.uniform(5e3, 40e3, size), slip=rng.uniform(-0.5, 0.9, size),
                alpha=rng.uniform(-0.2, 0.2, size), p=rng.uniform(0.8e5, 2.4e5, size))


@pytest.mark.parametrize("tir, soil_name", [(AGRI, "sandy_loam"), (AGRI, "paddy_soil"), (AGRI, "dry_sand"),
                                            (TIR_FILES / "car_205_60R15_mf62_swift.tir", "sandy_loam")])
def test_casadi_matches_numpy(tir, soil_name):
    """Same equations through both backends (MF 6.1 and, with its loaded-radius root solve, MF 6.2)."""
    tyre = SoftSoilTyre(tir, soil_name)
    f = tyre.casadi_function(inputs=("fz", "slip", "alpha", "p"))
    pts = _points(np.random.default_rng(1), 40)
    if tyre.params.FNOMIN < 1e4:  # the car tyre: car loads and pressures
        pts = dict(pts, fz=pts["fz"] / 5, p=pts["p"] + 1e5)
    out = tyre.evaluate(**pts)
    got = f.map(40)(*(pts[k][None, :] for k in ("fz", "slip", "alpha", "p")))
    names = f.name_out()
    for k, value in zip(names, got):
        key = k[:-4] if k.endswith("_out") else k
        np.testing.assert_allclose(np.ravel(value.full()), np.ravel(out[key]), rtol=1e-11, atol=1e-9, err_msg=key)


def test_casadi_derivatives_match_finite_differences():
    """d(drawbar pull, Fy, sinkage)/d(fz, slip, alpha, p) from CasADi against central differences of the NumPy
    model, in the flexible mode (sandy loam) and in the rigid mode (paddy soil)."""
    import casadi as ca

    for name, points in (("sandy_loam", ([20e3, 0.15, 0.05, 1.2e5], [30e3, 0.4, -0.1, 1.6e5])),
                         ("paddy_soil", ([15e3, 0.2, 0.05, 1.6e5],))):
        _check_derivatives(SoftSoilTyre(AGRI, name), points)


def _check_derivatives(tyre, points):
    import casadi as ca

    f = tyre.casadi_function(inputs=("fz", "slip", "alpha", "p"), outputs=("drawbar_pull", "fy", "sinkage"))
    x = ca.SX.sym("x", 4)
    jac = ca.Function("dfdx", [x], [ca.jacobian(ca.vertcat(*f(x[0], x[1], x[2], x[3])), x)])
    steps = np.array([1.0, 1e-6, 1e-6, 1.0])
    for point in points:
        analytic = jac(point).full()
        assert np.all(np.isfinite(analytic))
        for col in range(4):
            hi, lo = np.array(point, float), np.array(point, float)
            hi[col] += steps[col]
            lo[col] -= steps[col]
            o_hi, o_lo = (tyre.evaluate(*v) for v in (hi, lo))
            fd = [(o_hi[k] - o_lo[k]) / (2 * steps[col]) for k in ("drawbar_pull", "fy", "sinkage")]
            np.testing.assert_allclose(analytic[:, col], np.ravel(fd), rtol=1e-5, atol=1e-7 * np.abs(analytic).max())


# ---------------------------------------------------------------------------------------------- ground
def test_ground_switch_hard_soft_blend():
    model = load_tir(AGRI)
    args = dict(fz=25e3, kappa=np.array([0.05, 0.2]), alpha=0.03, vx=2.0, p=1.2e5)
    hard = model.evaluate(**args)
    soft = SoftSoilTyre(model, "sandy_loam").evaluate(fz=25e3, slip=args["kappa"] / (1 + args["kappa"]),
                                                      alpha=0.03, vx=2.0, p=1.2e5)
    on_hard = Ground(model).forces(**args)
    on_soil = Ground(model, "sandy_loam").forces(**args)
    half = Ground(model, "sandy_loam", blend=0.5).forces(**args)
    np.testing.assert_array_equal(on_hard.fx, hard.fx)
    np.testing.assert_array_equal(on_hard.sinkage, 0.0)
    np.testing.assert_allclose(on_soil.fx, soft.drawbar_pull, rtol=1e-14)
    np.testing.assert_allclose(on_soil.fy, soft.fy, rtol=1e-14)
    np.testing.assert_allclose(half.fx, 0.5 * (hard.fx + soft.drawbar_pull), rtol=1e-14)
    np.testing.assert_allclose(half.sinkage, 0.5 * soft.sinkage, rtol=1e-14)
    # the soil slip and the MF slip describe the same wheel spin (to the centrifugal growth of Re in the MF,
    # Q_V1 at 2 m/s, which the soil model, using the radius at rest, leaves out)
    np.testing.assert_allclose(soft.omega, hard.omega, rtol=1e-3)
    with pytest.raises(ModelInputError, match="blend must be in"):
        Ground(model, "sandy_loam", blend=1.5)
    with pytest.raises(ModelInputError, match="needs a soil"):
        Ground(model, blend=0.3)


# ------------------------------------------------------------------------------------------- soil table
def test_builtin_soils_have_sources_and_si_units():
    table = builtin_soils()
    assert {"paddy_soil", "dry_sand", "sandy_loam", "clayey_soil", "heavy_clay"} <= set(table)
    for s in table.values():
        assert s.source, s.name
    paddy = table["paddy_soil"]
    assert (paddy.n, paddy.k_c, paddy.k_phi, paddy.c, paddy.K) == (0.4, 1870.0, 96080.0, 6250.0, 0.065)
    assert math.degrees(paddy.phi) == pytest.approx(30.2)


def test_user_soil_file(tmp_path):
    path = tmp_path / "mine.csv"
    path.write_text("# my field\nname,n,k_c,k_phi,c,phi,K\nfield_7,0.8,10,800,3.5,25,0.02\n")
    s = soil("field_7", path)
    assert (s.k_c, s.k_phi, s.c, s.K) == (10e3, 800e3, 3.5e3, 0.02)
    assert SoftSoilTyre(AGRI, s).evaluate(fz=20e3, slip=0.1).drawbar_pull > 0


# ------------------------------------------------------------------------------------------------ errors
def test_unknown_soil_is_a_typed_error():
    with pytest.raises(ModelInputError, match=r"unknown soil 'moon_dust'.*paddy_soil"):
        soil("moon_dust")
    with pytest.raises(ModelInputError, match="unknown soil"):
        SoftSoilTyre(AGRI, "moon_dust")


@pytest.mark.parametrize("row, message", [
    ("bad,0.8,-10,800,3.5,25,0.02", r"mine.csv:3: column k_c of soil 'bad' must be a finite number >= 0"),
    ("bad,0.8,10,800,x,25,0.02", r"mine.csv:3: column c: cannot read 'x'"),
    ("bad,0,10,800,3.5,25,0.02", r"mine.csv:3: soil 'bad': n must be positive"),
    ("bad,0.8,10,800,3.5,95,0.02", r"mine.csv:3: soil 'bad': phi must be in \[0, 90\)"),
    ("bad,0.8,10,800", r"mine.csv:3: 4 fields, the header has 7"),
])
def test_bad_soil_file_names_file_line_and_column(tmp_path, row, message):
    path = tmp_path / "mine.csv"
    path.write_text(f"# comment\nname,n,k_c,k_phi,c,phi,K\n{row}\n")
    with pytest.raises(DataError, match=message):
        read_soils(path)


def test_negative_constants_rejected_in_code_too():
    with pytest.raises(ModelInputError, match="K must be positive"):
        Soil("x", 0.8, 1e3, 1e5, 1e3, 0.3, -0.01)
    with pytest.raises(ModelInputError, match="k_phi must be >= 0"):
        Soil("x", 0.8, 1e3, -1e5, 1e3, 0.3, 0.01)


def test_sinkage_beyond_the_radius_is_a_typed_error():
    tyre = SoftSoilTyre(CAR, "paddy_soil")
    tyre.evaluate(fz=4e3, slip=0.1)  # deep but possible
    with pytest.raises(SinkageError, match=r"fz = 8000 N.*reaches the axle.*index 1"):
        tyre.evaluate(fz=[4e3, 8e3, 9e3], slip=0.1)
    assert issubclass(SinkageError, ModelInputError)


@pytest.mark.parametrize("kwargs, message", [
    (dict(fz=-1.0, slip=0.1), "fz must be finite and positive"),
    (dict(fz=1e4, slip=1.0), "slip must be finite and below 1"),
    (dict(fz=1e4, slip=0.1, p=0.0), "p must be finite and positive"),
    (dict(fz=np.nan, slip=0.1), "fz must be finite"),
    (dict(fz=[1e4, 2e4], slip=[0.1, 0.2, 0.3]), "do not broadcast"),
])
def test_bad_operating_points(kwargs, message):
    with pytest.raises(ModelInputError, match=message):
        SoftSoilTyre(AGRI, "sandy_loam").evaluate(**kwargs)


def test_compaction_resistance_is_the_rut_work():
    """R_c = b int_0^z k z'^n dz' (the work per unit travel of pressing the rut), by quadrature."""
    s = soil("clayey_soil")
    z, b = 0.07, 0.4
    work = b * quad(lambda d: s.modulus(b) * d**s.n, 0, z)[0]
    assert compaction_resistance(s, z, b, NUMPY) == pytest.approx(work, rel=1e-10)


# ------------------------------------------------------------------------------ rigid/flexible switch: continuity
def _switch_sweep(size):
    """The 420/85 R24 on clayey soil at 0.8 FNOMIN crosses p_cr near 1.6 bar: pressures across the switch band."""
    tyre = SoftSoilTyre(AGRI_SMALL, "clayey_soil")
    return tyre, 0.8 * tyre.params.FNOMIN, np.linspace(1.3e5, 2.2e5, size)


def test_switch_is_continuous_in_pressure():
    """Wong's switch is a step (rigid: no flat part, width WIDTH; flexible: flat part 2a, deflection rho):
    before the blend the contact length jumped by about 0.2 m and the traction by kN between two pressures
    1 Pa apart. Now every output is continuous: over a fine pressure sweep through the band the largest change
    between neighbours is of the order of the mean change (no step), and the band is crossed (w from 1 to 0)."""
    tyre, fz, p = _switch_sweep(4001)
    out = tyre.evaluate(fz=fz, slip=0.15, alpha=0.02, p=p)
    assert out.flexible[0] == 1.0 and out.flexible[-1] == 0.0
    assert np.all(np.diff(out.flexible) <= 0)
    for key in ("contact_length", "contact_width", "sinkage", "deflection", "gross_traction", "drawbar_pull",
                "torque", "fy", "motion_resistance", "rolling_radius", "ground_pressure"):
        steps = np.abs(np.diff(out[key]))
        mean = abs(out[key][-1] - out[key][0]) / (p.size - 1) + 1e-12 * np.abs(out[key]).max()
        assert steps.max() < 60 * mean, (key, steps.max(), mean)
    # at the band's edges the blend meets Wong's modes exactly: just outside them w is exactly 0 or 1
    ratio = (out.critical_pressure - out.carcass_pressure - p) / out.critical_pressure  # 1 - p_g / p_cr
    assert np.all(out.flexible[ratio >= 0.05] == 1.0) and np.all(out.flexible[ratio <= -0.05] == 0.0)
    inside = np.abs(ratio) < 0.045
    assert np.all((out.flexible[inside] > 0) & (out.flexible[inside] < 1))


def test_casadi_derivatives_finite_and_right_across_the_switch():
    """d(outputs)/dp from CasADi at pressures in and at the edges of the switch band: finite and equal to central
    differences of the NumPy model (the blend is C1, so even at the band's edges the one-sided slopes agree)."""
    import casadi as ca

    tyre, fz, _ = _switch_sweep(2)
    keys = ("contact_length", "drawbar_pull", "torque", "sinkage")
    f = tyre.casadi_function(inputs=("p",), outputs=keys, fixed=dict(fz=fz, slip=0.15, alpha=0.02))
    x = ca.SX.sym("p")
    jac = ca.Function("d", [x], [ca.jacobian(ca.vertcat(*f(x)), x)])
    # the band edges: p_g / p_cr = 1 +- 0.05, located on the NumPy model by bisection of the flexible fraction
    p = np.linspace(1.3e5, 2.2e5, 20001)
    w = tyre.evaluate(fz=fz, slip=0.15, alpha=0.02, p=p).flexible
    edges = [p[np.argmax(w < 1)], p[np.argmax(w == 0)]]
    for point in (edges[0], 0.5 * (edges[0] + edges[1]), edges[1], 0.3 * edges[0] + 0.7 * edges[1]):
        analytic = np.ravel(jac(point).full())
        assert np.all(np.isfinite(analytic))
        h = 0.5
        hi, lo = (tyre.evaluate(fz=fz, slip=0.15, alpha=0.02, p=point + d) for d in (h, -h))
        fd = np.array([(hi[k] - lo[k]) / (2 * h) for k in keys], dtype=float).ravel()
        np.testing.assert_allclose(analytic, fd, rtol=2e-3, atol=1e-6 * np.abs(fd).max() + 1e-12)
        assert np.any(analytic != 0)
    # the derivatives account for the whole change across the band (no step that they cannot see): the
    # trapezoidal integral of dX/dp from below to above the band equals X(p_b) - X(p_a)
    grid = np.linspace(edges[0] - 2e3, edges[1] + 2e3, 2001)
    slopes = np.array([np.ravel(jac(q).full()) for q in grid])
    values = tyre.evaluate(fz=fz, slip=0.15, alpha=0.02, p=grid)
    for col, key in enumerate(keys):
        change = values[key][-1] - values[key][0]
        integral = np.sum(0.5 * (slopes[1:, col] + slopes[:-1, col]) * np.diff(grid))
        assert integral == pytest.approx(change, rel=2e-3, abs=1e-9), key


# ------------------------------------------------------------------------------------- optional effects
def test_neutral_effect_parameters_give_identical_outputs():
    """slip_sinkage 0 and a bulldozing depth the rut never reaches change nothing, bit for bit."""
    slip = np.linspace(-0.3, 0.8, 12)
    base = SoftSoilTyre(AGRI, "paddy_soil").evaluate(fz=20e3, slip=slip, alpha=0.03, p=1.2e5)
    for kwargs in (dict(slip_sinkage=0.0), dict(bulldozing_depth=math.inf), dict(bulldozing_depth=0.8)):
        out = SoftSoilTyre(AGRI, "paddy_soil", **kwargs).evaluate(fz=20e3, slip=slip, alpha=0.03, p=1.2e5)
        for key in out.keys():
            np.testing.assert_array_equal(out[key], base[key], err_msg=f"{kwargs} {key}")
    assert np.all(base.bulldozing_resistance == 0)


def test_slip_sinkage_follows_lyasko_and_deepens_the_rut():
    """s_j = 1: z(i) = z(0) (1 + i)/(1 - 0.5 i) for driving slip (Lyasko), none for braking; the compaction
    resistance grows as z^(n+1); the load-bearing ground pressure does not change; s_j = 0.5 is the square root."""
    slip = np.array([-0.3, 0.0, 0.1, 0.3, 0.6])
    kw = dict(fz=25e3, slip=slip, p=1.2e5)
    static = SoftSoilTyre(AGRI, "sandy_loam").evaluate(**kw)
    lyasko = SoftSoilTyre(AGRI, "sandy_loam", slip_sinkage=1.0).evaluate(**kw)
    half = SoftSoilTyre(AGRI, "sandy_loam", slip_sinkage=0.5).evaluate(**kw)
    factor = np.where(slip > 0, (1 + slip) / (1 - 0.5 * slip), 1.0)
    np.testing.assert_allclose(lyasko.sinkage / static.sinkage, factor, rtol=1e-12)
    np.testing.assert_allclose(half.sinkage / static.sinkage, np.sqrt(factor), rtol=1e-12)
    n = soil("sandy_loam").n
    np.testing.assert_allclose(lyasko.motion_resistance / static.motion_resistance, factor ** (n + 1), rtol=1e-12)
    np.testing.assert_allclose(lyasko.ground_pressure, static.ground_pressure, rtol=1e-14)
    assert np.all(np.diff(lyasko.sinkage[1:]) > 0)
    assert np.all(lyasko.contact_length[2:] > static.contact_length[2:])
    assert lyasko.drawbar_pull[-1] < static.drawbar_pull[-1]   # the deeper rut costs pull at high slip


def test_bearing_capacity_coefficients_against_textbook_values():
    """At phi = 30 deg the textbook factors are N_c = 30.14 (Prandtl), N_q = 18.40, N_gamma = 15.67 (Meyerhof):
    K_pc = (N_c - tan phi) cos^2 phi = 22.17, K_pgamma = (2 N_gamma / tan phi + 1) cos^2 phi = 41.46; at phi = 0
    the limits pi + 2 and 1, and the formula is continuous there."""
    k_pc, k_pg = bulldozing_coefficients(math.radians(30.0))
    assert k_pc == pytest.approx((30.14 - math.tan(math.radians(30))) * 0.75, rel=2e-4)
    assert k_pg == pytest.approx((2 * 15.67 / math.tan(math.radians(30)) + 1) * 0.75, rel=2e-4)
    assert bulldozing_coefficients(0.0) == (math.pi + 2, 1.0)
    np.testing.assert_allclose(bulldozing_coefficients(1e-7), (math.pi + 2, 1.0), rtol=1e-5)


def test_bulldozing_resistance_beyond_the_threshold_depth():
    """Bekker's R_b = b (0.67 c z_b K_pc + 0.5 gamma z_b^2 K_pgamma) on the rut depth z_b beyond z_bd: zero while
    the rut is shallower, continuous at the threshold, growing with depth; it adds to the motion resistance and
    takes from the drawbar pull, and leaves the torque alone (it acts through the axle). Checked for a purely
    cohesive soil (phi = 0: K_pc = pi + 2, K_pgamma = 1) by hand."""
    clay = Soil("clay", 0.5, 13.19e3, 692.15e3, 4.14e3, 0.0, 0.025, gamma=16e3)
    loads = np.linspace(10e3, 40e3, 31)
    base = SoftSoilTyre(AGRI, clay).evaluate(fz=loads, slip=0.2, p=1.2e5)
    z_bd = float(np.median(base.sinkage))
    out = SoftSoilTyre(AGRI, clay, bulldozing_depth=z_bd).evaluate(fz=loads, slip=0.2, p=1.2e5)
    wedge = np.maximum(base.sinkage - z_bd, 0)
    hand = base.contact_width * (0.67 * clay.c * wedge * (math.pi + 2) + 0.5 * clay.gamma * wedge**2)
    np.testing.assert_allclose(out.bulldozing_resistance, hand, rtol=1e-12)
    assert np.all(out.bulldozing_resistance[base.sinkage <= z_bd] == 0)
    assert np.all(np.diff(out.bulldozing_resistance[base.sinkage > z_bd]) > 0)
    np.testing.assert_allclose(out.motion_resistance - base.motion_resistance, hand, rtol=1e-12)
    np.testing.assert_allclose(base.drawbar_pull - out.drawbar_pull, hand, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(out.torque, base.torque)


def test_effect_parameters_bad_input():
    with pytest.raises(ModelInputError, match="needs the unit weight gamma of soil 'sandy_loam'"):
        SoftSoilTyre(AGRI, "sandy_loam", bulldozing_depth=0.05)
    with pytest.raises(ModelInputError, match="slip_sinkage must be a number >= 0"):
        SoftSoilTyre(AGRI, "sandy_loam", slip_sinkage=-1.0)
    with pytest.raises(ModelInputError, match="gamma"):
        Soil("x", 0.8, 1e3, 1e5, 1e3, 0.3, 0.01, gamma=-5.0)
    assert soil("paddy_soil").gamma == pytest.approx(1240 * 9.81, rel=1e-3)   # seed 003, Table 3


def test_casadi_matches_numpy_with_effects():
    tyre = SoftSoilTyre(AGRI, "paddy_soil", slip_sinkage=1.0, bulldozing_depth=0.05)
    f = tyre.casadi_function(inputs=("fz", "slip", "alpha", "p"))
    pts = _points(np.random.default_rng(3), 30)
    pts["fz"] = pts["fz"] / 4
    out = tyre.evaluate(**pts)
    got = f.map(30)(*(pts[k][None, :] for k in ("fz", "slip", "alpha", "p")))
    assert np.any(out.bulldozing_resistance > 0)
    for name, value in zip(f.name_out(), got):
        key = name[:-4] if name.endswith("_out") else name
        np.testing.assert_allclose(np.ravel(value.full()), np.ravel(out[key]), rtol=1e-11, atol=1e-9, err_msg=key)


# ------------------------------------------------------------------------------- agricultural .tir files
@pytest.mark.parametrize("tir", [AGRI, AGRI_SMALL], ids=lambda p: p.name)
def test_agricultural_header_names_exactly_the_placeholders(tir):
    """The force coefficients of the agricultural files are a car tyre's: the header must say plainly which
    sections and parameters those are. Its 'PLACEHOLDER SECTIONS' and 'PLACEHOLDER PARAMETERS' lists must equal
    the sections whose every value is tagged [CAR] and the [CAR]-tagged parameters of the other sections, and the
    separator line of each placeholder section says so too."""
    import re

    lines = tir.read_text().splitlines()
    section, values, tagged = None, {}, {}
    for line in lines:
        if line.startswith("["):
            section = line.strip()
        match = re.match(r"^([A-Z_0-9]+)\s*=", line)
        if match:
            values.setdefault(section, []).append(match.group(1))
            if "[CAR]" in line:
                tagged.setdefault(section, []).append(match.group(1))
    whole = {s for s in values if tagged.get(s) == values[s]}
    partly = {s: set(names) for s, names in tagged.items() if s not in whole}
    header = "\n".join(line for line in lines if line.startswith("!"))
    listed = header.split("! PLACEHOLDER SECTIONS (every value [CAR]):")[1].split("! PLACEHOLDER PARAMETERS")[0]
    assert set(re.findall(r"\[[A-Z_]+\]", listed)) == whole
    params = header.split("! PLACEHOLDER PARAMETERS in otherwise estimated sections:")[1].split("\n!\n")[0]
    for s, names in partly.items():
        block = params.split(s)[1].split("[")[0]
        assert set(re.findall(r"[A-Z][A-Z_0-9]+", block)) >= names, s
    assert {"[LONGITUDINAL_COEFFICIENTS]", "[LATERAL_COEFFICIENTS]", "[ALIGNING_COEFFICIENTS]"} <= whole
    for i, line in enumerate(lines[:-1]):
        if lines[i + 1].strip() in whole:
            assert line.startswith("$") and "PLACEHOLDER" in line, lines[i + 1]
    # the file still loads and checks clean (the marks are comments)
    assert load_tir(tir).params.FNOMIN > 2e4
