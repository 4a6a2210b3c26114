"""The soft-soil tyre model (mftyre.soil): seed 003's worked numbers, analytic limits, physical trends, CasADi,
the ground switch and bad input."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from conftest import MFEVAL_DIR, SHARED, TIR_FILES, require_shared
from mftyre.backend import NUMPY
from mftyre.errors import DataError, ModelInputError
from mftyre.model import load_tir
from mftyre.soil import ConeIndexTyre, Ground, SinkageError, Soil, SoftSoilTyre, builtin_soils, read_soils, soil
from mftyre.soil.equations import (bulldozing_coefficients, compaction_resistance, critical_pressure,
                                   hard_ground_footprint, rigid_wheel_sinkage)

AGRI = TIR_FILES / "agri_460_85R34_mf61.tir"
AGRI_SMALL = TIR_FILES / "agri_420_85R24_mf61.tir"
AGRI_TYRE_WIDTH = 0.46  # WIDTH of the 460/85 R34 file
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


def test_seed003_sinkage_and_thrust_of_the_flotation_tyre():
    """Seed 003's flotation tyre (29x12.50-15 at 68.95 kPa) on its paddy soil at W = 3.5 kN. The seed treats it as
    a rigid wheel (Bekker's closed form: 0.1230 m, above). In the model the tyre flattens a little (the flat part
    carries ~20 % of the load, the .tir's deflection relation of a car tyre scaled to the seed's size) and the
    whole contact is balanced exactly (the circle, not Bekker's parabola and first-order expansion): 0.1256 m,
    2 % from Bekker's 0.1230 m and 0.5 % from the seed's rounded 0.125 m (as a rigid wheel the exact balance
    needs 0.144 m, see the next test; the small flat part takes that back). The thrust at i = 0.14, 1.47 kN,
    lies between Wong's closed form with the seed's static chord (1.28 kN) and the seed's eq. 5 (2.14 kN, the
    shear displacement i L taken over the whole contact)."""
    c, phi, K = PADDY.c, PADDY.phi, PADDY.K
    W, L, i, b = 3.5e3, 0.55, 0.14, SEED_B
    seed = (c * b * L + W * math.tan(phi)) * (1 - math.exp(-i * L / K))
    assert seed == pytest.approx(2.14e3, rel=0.005)
    wong = (c * b * L + W * math.tan(phi)) * (1 - K / (i * L) * (1 - math.exp(-i * L / K)))
    assert wong == pytest.approx(1.28e3, rel=0.01)
    out = SoftSoilTyre(_seed_tyre(), PADDY).evaluate(fz=W, slip=i)
    assert float(out.sinkage) == pytest.approx(0.1230, rel=0.03)
    assert float(out.sinkage) == pytest.approx(0.125, rel=0.01)
    assert 0.1 < float(out.flat_load) / W < 0.3
    assert wong < float(out.gross_traction) < seed


def _seed_tyre():
    return load_tir(CAR).with_params(UNLOADED_RADIUS=SEED_D / 2, WIDTH=SEED_B, Q_RE0=1.0, INFLPRES=68.95e3,
                                     NOMPRES=68.95e3, PRESMIN=5e4)


def _rigid_wheel_sinkage_exact(s, fz, r, b):
    """The sinkage at which Bekker's normal stress on the front arc of a rigid circle carries fz (scipy)."""
    k = s.modulus(b)

    def carried(z):
        end = math.sqrt(r * r - (r - z) ** 2)
        return b * quad(lambda x: k * max(math.sqrt(r * r - x * x) - (r - z), 0.0) ** s.n, 0, end, limit=200)[0]

    return brentq(lambda z: carried(z) - fz, 1e-6, r)


def test_stiff_tyre_is_the_rigid_wheel_of_the_exact_balance():
    """A tyre far stiffer than the soil (Cz x 1e4) carries (almost) nothing on a flat part: its sinkage is that of
    the rigid circle whose front arc carries the load (an independent scipy solve), its compaction resistance
    Bekker's rut work b k z^(n+1)/(n+1) at that depth, and Bekker's closed-form rigid-wheel sinkage (a parabola
    and a first-order expansion) is 8-14 % shallower than that exact balance."""
    base = load_tir(AGRI)
    tyre = SoftSoilTyre(base.with_params(VERTICAL_STIFFNESS=base.params.VERTICAL_STIFFNESS * 1e4), "paddy_soil")
    prm, s = tyre.params, tyre.soil
    W = np.array([5e3, 10e3, 15e3])
    out = tyre.evaluate(fz=W, slip=0.1)
    assert np.all(out.flat_load < 1e-3 * W)
    r, b = prm.UNLOADED_RADIUS * prm.Q_RE0, prm.WIDTH
    exact = np.array([_rigid_wheel_sinkage_exact(s, w, r, b) for w in W])
    np.testing.assert_allclose(out.sinkage, exact, rtol=2e-3)
    np.testing.assert_allclose(out.motion_resistance, compaction_resistance(s, out.sinkage, b, NUMPY), rtol=1e-12)
    bekker = rigid_wheel_sinkage(s, W, 2 * r, b, NUMPY)
    assert np.all((bekker / exact > 0.84) & (bekker / exact < 0.94)), bekker / exact


# ------------------------------------------------------------------------------------------ analytic checks
def _rebuilt(tyre, out, vx, alpha):
    """The documented stress distribution rebuilt from the outputs, integrated by scipy's adaptive quadrature:
    (vertical normal force, H, torque without hysteresis, Fy, shear-slip power)."""
    prm, s = tyre.params, tyre.soil
    r, B = prm.UNLOADED_RADIUS * prm.Q_RE0, prm.WIDTH
    z, a = float(out.sinkage), 0.5 * float(out.flat_length)
    k, tan_phi = s.modulus(B), math.tan(s.phi)
    c = math.sqrt(r * r - a * a)
    theta_e, theta_f = math.acos((c - z) / r), math.atan(a / c)
    omega, r_f = float(out.omega), float(out.rolling_radius)
    ratio, vy = vx / omega, vx * math.tan(alpha)

    def tau(jx, jy, sigma):
        j = math.hypot(jx, jy)
        strength = (s.c + sigma * tan_phi) * (1 - math.exp(-j / s.K)) / j if j > 0 else 0.0
        return strength * jx, strength * jy

    def arc(theta):
        sigma = k * max(r * math.cos(theta) - (c - z), 0.0) ** s.n
        jx = r * (theta_e - theta) - ratio * (math.sin(theta_e) - math.sin(theta))
        tx, ty = tau(jx, vy / omega * (theta_e - theta), sigma)
        return sigma, tx, ty, omega * r - vx * math.cos(theta)

    jx_f = r * (theta_e - theta_f) - ratio * (math.sin(theta_e) - math.sin(theta_f))
    jy_f = vy / omega * (theta_e - theta_f)
    sigma_f = float(out.ground_pressure)

    def flat(x):
        return tau(jx_f + (1 - ratio / r_f) * x, jy_f + vy / (omega * r_f) * x, sigma_f)

    def integral(f, lo, hi):
        return quad(f, lo, hi, epsabs=0.0, epsrel=1e-10, limit=400)[0]

    vertical = B * r * integral(lambda t: arc(t)[0] * math.cos(t), theta_f, theta_e) + sigma_f * 2 * a * B
    on_flat = integral(lambda x: flat(x)[0], 0, 2 * a)
    h = B * (r * integral(lambda t: arc(t)[1] * math.cos(t), theta_f, theta_e) + on_flat)
    torque = B * (r * r * integral(lambda t: arc(t)[1], theta_f, theta_e) + r_f * on_flat)
    fy = -B * (r * integral(lambda t: arc(t)[2], theta_f, theta_e) + integral(lambda x: flat(x)[1], 0, 2 * a))
    loss = B * (r * integral(lambda t: arc(t)[1] * arc(t)[3] + arc(t)[2] * vy, theta_f, theta_e)
                + integral(lambda x: flat(x)[0] * (omega * r_f - vx) + flat(x)[1] * vy, 0, 2 * a))
    return vertical, h, torque, fy, loss


@pytest.mark.parametrize("tir, soil_name, fz, p", [(AGRI, "sandy_loam", 25e3, 1.2e5), (AGRI, "paddy_soil", 15e3, 1.6e5),
                                                   (AGRI, "dry_sand", 25e3, 1.0e5), (CAR, "clayey_soil", 4e3, 2.4e5)])
def test_forces_balance_and_losses_against_adaptive_quadrature(tir, soil_name, fz, p):
    """Vertical equilibrium and every integral against scipy's adaptive quadrature of the documented stresses
    (rebuilt from the outputs: sinkage, flat length, ground pressure, rolling radius, spin): the normal stress over
    the whole contact equals Fz (1e-5), and H, the torque, Fy and the shear-slip loss agree (2e-4). This fails on
    the earlier model: its front arc added 7-15 % of the load in normal stress on top of the flat part's full load."""
    tyre = SoftSoilTyre(tir, soil_name)
    for slip, alpha in ((0.15, 0.0), (0.4, 0.05), (-0.2, -0.1)):
        out = tyre.evaluate(fz=fz, slip=slip, alpha=alpha, p=p, vx=2.0)
        vertical, h, torque, fy, loss = _rebuilt(tyre, out, 2.0, alpha)
        assert vertical == pytest.approx(fz, rel=1e-5)
        assert float(out.gross_traction) == pytest.approx(h, rel=2e-4)
        assert float(out.torque - out.hysteresis_moment) == pytest.approx(torque, rel=2e-4)
        assert float(out.slip_power) == pytest.approx(loss, rel=2e-4)
        if alpha:
            assert float(out.fy) == pytest.approx(fy, rel=2e-4)
            assert np.sign(float(out.fy)) == -np.sign(alpha)  # ISO-W: Fy opposes the slip angle


_ENERGY_SOILS = ("dry_sand", "sandy_loam", "clayey_soil", "clayey_soil_wet", "heavy_clay", "heavy_clay_wet",
                 "lean_clay_wet", "lete_sand", "paddy_soil")


_FOREIGN = [SHARED / "reference" / "tir" / "TNO_car205_60R15.tir", MFEVAL_DIR / "MagicFormula61_Parameters.tir"]


@pytest.mark.parametrize("tir", [AGRI, AGRI_SMALL, CAR, *_FOREIGN], ids=lambda p: p.name)
def test_power_balance_over_soils_pressures_slips_loads(tir):
    """Energy: T omega - Fy V tan(alpha) = DP V + (R_c + R_b) V + P_slip + M_h omega to 1e-6 of the input power
    on every built-in soil the tyre does not sink into, at 4 pressures x 4 loads x 9 slips x 2 slip angles, and
    the tractive efficiency stays below 1 - i wherever the wheel is driven (T omega > 0 and DP > 0). (The
    shear-slip loss is not positive at every point: Janosi-Hanamoto's stress follows the displacement, not its
    rate, so where the tread's slip velocity reverses along the contact near i = 0 the soil gives a little back.)"""
    model = load_tir(require_shared(tir) if tir in _FOREIGN else tir)
    prm = model.params
    p = np.linspace(prm.PRESMIN, prm.PRESMAX, 4)[:, None, None, None]
    fz = np.linspace(0.4, 1.4, 4)[None, :, None, None] * prm.FNOMIN
    slip = np.array([-0.5, -0.1, -0.01, 0.0, 0.02, 0.05, 0.15, 0.4, 0.8])[None, None, :, None]
    alpha = np.array([0.0, 0.08])[None, None, None, :]
    vx = 2.5
    tested = 0
    for name in _ENERGY_SOILS:
        tyre = SoftSoilTyre(model, name, bulldozing_depth=0.02 if name == "paddy_soil" else math.inf)
        try:
            out = tyre.evaluate(fz=fz, slip=slip, alpha=alpha, p=p, vx=vx)
        except SinkageError:
            continue
        tested += 1
        lhs = out.torque * out.omega - out.fy * vx * np.tan(alpha)
        rhs = out.drawbar_pull * vx + out.motion_resistance * vx + out.slip_power + out.hysteresis_moment * out.omega
        scale = np.abs(out.torque * out.omega) + np.abs(out.drawbar_pull * vx) + 1e-9
        assert np.max(np.abs(lhs - rhs) / scale) < 1e-6, name
        driven = (out.power > 0) & (out.drawbar_pull > 0)
        assert np.all(out.efficiency[driven] <= 1 - np.broadcast_to(slip, out.efficiency.shape)[driven] + 1e-12), name
    assert tested >= 6


def test_efficiency_never_exceeds_one_minus_slip():
    """The review's case (issue 20): the 460/85 R34 at 25 kN reached an efficiency of 0.996 at 2 % slip on LETE
    sand (bound 0.98) and 1.041 on heavy clay at 1.0 bar: the flat part's shear acted on the lever r - delta while
    its tread moved at omega Re. Only outputs the earlier model had are used here."""
    slip = np.linspace(0.005, 0.6, 120)
    for name in ("lete_sand", "heavy_clay", "sandy_loam", "clayey_soil"):
        for p in (1.0e5, 1.6e5):
            out = SoftSoilTyre(AGRI, name).evaluate(fz=25e3, slip=slip, p=p, vx=2.0)
            ok = out.power > 0
            assert np.all(out.efficiency[ok] <= 1 - slip[ok]), (name, p)


# ---------------------------------------------------------------------------------------------- trends
@pytest.mark.parametrize("tir", [AGRI, AGRI_SMALL, CAR, *_FOREIGN], ids=lambda p: p.name)
def test_pressure_acts_for_every_tyre_on_every_soil(tir):
    """The tyre deflects as its .tir says under the soil's pressure-sinkage response: on every built-in soil
    (the car tyre on clays too, which Wong's rigid/flexible switch left rigid at every pressure) lower pressure
    gives less sinkage and less compaction resistance, and the flat part carries more of the load."""
    model = load_tir(require_shared(tir) if tir in _FOREIGN else tir)
    prm = model.params
    p = np.linspace(prm.PRESMIN, prm.PRESMAX, 6)
    for name in builtin_soils():
        tyre = SoftSoilTyre(model, name)
        try:
            out = tyre.evaluate(fz=0.6 * prm.FNOMIN, slip=0.15, p=p)
        except SinkageError:
            assert name == "sandy_loam_wet"        # the one soil every tyre here sinks into
            continue
        assert np.all(np.diff(out.sinkage) > 0), (name, out.sinkage)
        assert np.all(np.diff(out.motion_resistance) > 0), name
        assert np.all(np.diff(out.flat_load) < 0), name


def test_seed001_trends_car_tyre_on_cohesive_soil():
    """Seed 001 (FE P235/75R17 on a cohesive soil, 120-242 kPa, 10 km/h): (a) driven at a fixed wheel speed
    (7.46 rad/s) the tyre sinks deeper and, self-propelled (DP = 0), travels slower at higher pressure (its
    Fig. 14); (b) more load, more sinkage (Fig. 15); (c) the towed wheel meets more resistance at higher pressure
    and more load (lower pressure spreads the load: Figs. 12-13), and turns slower than on hard ground. The car
    tyre of tir_files on the cohesive soils of the table (the seed's FE soil has no Bekker constants): signs
    only, FE with Drucker-Prager soil is not Bekker. Fails on the earlier model: the car tyre stayed rigid."""
    model = load_tir(CAR)
    p = np.array([1.2e5, 1.6e5, 2.0e5, 2.42e5])
    v = 10 / 3.6
    slip = np.linspace(-0.3, 0.6, 451)
    for name in ("clayey_soil", "clayey_soil_wet", "heavy_clay_wet", "lean_clay_wet"):
        tyre = SoftSoilTyre(model, name)
        speed = []
        for pi in p:
            out = tyre.evaluate(fz=3e3, slip=slip, p=pi, vx=v)
            assert np.all(np.diff(out.drawbar_pull) > 0)
            self_propelled = np.interp(0.0, out.drawbar_pull, slip)
            r_e = v / ((1 - slip[0]) * out.omega[0])
            speed.append(7.46 * (1 - self_propelled) * r_e)
        assert np.all(np.diff(speed) < 0), (name, speed)
        loads = np.array([2e3, 3e3, 5e3])[:, None]
        out = tyre.evaluate(fz=loads, slip=0.1, p=p[None, :], vx=v)
        assert np.all(np.diff(out.sinkage, axis=0) > 0) and np.all(np.diff(out.sinkage, axis=1) > 0), name
        towed = tyre.towed(fz=loads, p=p[None, :], vx=v)
        resistance = -towed.drawbar_pull
        assert np.all(np.diff(resistance, axis=0) > 0) and np.all(np.diff(resistance, axis=1) > 0), name
        hard = model.evaluate(fz=loads, kappa=0.0, alpha=0.0, vx=v, p=p[None, :], limits=False)
        assert np.all(towed.omega < hard.omega), name


def test_tyre_hysteresis_on_soil():
    """The .tir's rolling-resistance moment is carried on soil at the load the carcass carries on its flat part:
    M_h = -My(F_t) (MFModel.evaluate at that load, free rolling), and on a soil almost as firm as a road (heavy
    clay at 25 % moisture: the rut is microns deep) the towed wheel meets the hard-ground rolling resistance
    -My / Re within 2 %. Fails on the earlier model, which left My out on soil."""
    model = load_tir(AGRI)
    tyre = SoftSoilTyre(model, "heavy_clay")
    p = np.array([1.0e5, 1.6e5])
    towed = tyre.towed(fz=25e3, p=p, vx=3.0)
    hard = model.evaluate(fz=25e3, kappa=0.0, alpha=0.0, vx=3.0, p=p)
    assert np.all(towed.sinkage < 1e-4)
    np.testing.assert_allclose(-towed.drawbar_pull, -hard.my / hard.re, rtol=0.02)
    soft = SoftSoilTyre(model, "sandy_loam").evaluate(fz=25e3, slip=0.1, p=p, vx=3.0)
    at_flat = model.evaluate(fz=soft.flat_load, kappa=0.0, alpha=0.0, vx=3.0, p=p)
    np.testing.assert_allclose(soft.hysteresis_moment, -at_flat.my, rtol=1e-9)


@pytest.mark.parametrize("tir", [AGRI, AGRI_SMALL], ids=lambda p: p.name)
def test_agricultural_contact_width_and_carcass_pressure(tir):
    """Issue 20: the 420/85 R24's contact width on hard ground was 426 mm at 1.0 bar (section 420 mm) and its
    carcass pressure p_c = Fz/(4ab) - p_i was 0 at half load and 1.6 bar, negative below. Over 0.25-2 FNOMIN and
    PRESMIN-PRESMAX the files' contact width now stays within the section width and p_c > 0; on soil the contact
    width is the section width."""
    model = load_tir(tir)
    prm = model.params
    fz = np.linspace(0.25, 2.0, 15)[:, None] * prm.FNOMIN
    p = np.linspace(prm.PRESMIN, prm.PRESMAX, 10)[None, :]
    _, a, b = hard_ground_footprint(prm, fz, p, NUMPY)
    assert np.all(2 * b <= prm.WIDTH)
    out = SoftSoilTyre(model, "lete_sand").evaluate(fz=fz, slip=0.1, p=p)
    assert np.all(out.carcass_pressure > 0)
    np.testing.assert_allclose(out.carcass_pressure, fz / (4 * a * b) - p, rtol=1e-12)
    assert np.all(out.contact_width == prm.WIDTH)


@pytest.mark.parametrize("tir", [CAR, *_FOREIGN], ids=lambda p: p.name)
def test_carcass_pressure_never_negative_on_car_tyres(tir):
    """The car files' gross patch 4ab carries less than the inflation pressure at most loads and pressures
    (Fz / (4ab) - p_i down to -0.5 p_i on the TNO file): p_c is 0 there, never negative, in both soil models."""
    model = load_tir(require_shared(tir) if tir in _FOREIGN else tir)
    prm = model.params
    fz = np.linspace(0.25, 2.0, 8)[:, None] * prm.FNOMIN
    p = np.linspace(prm.PRESMIN, prm.PRESMAX, 6)[None, :]
    _, a, b = hard_ground_footprint(prm, fz, p, NUMPY)
    assert np.any(fz / (4 * a * b) < p)                     # the case this is about
    for out in (SoftSoilTyre(model, "clayey_soil").evaluate(fz=fz, slip=0.1, p=p),
                ConeIndexTyre(model, 1.0e6).evaluate(fz=fz, slip=0.1, p=p)):
        assert np.all(out.carcass_pressure >= 0)
        np.testing.assert_allclose(out.carcass_pressure, np.maximum(fz / (4 * a * b) - p, 0.0), rtol=1e-12)


def test_drawbar_pull_rises_with_slip_to_a_saturating_maximum():
    """DP(i) rises monotonically and saturates at the Mohr-Coulomb limit less the resistance (the limit: the
    same model with K -> 0, tau = tau_max everywhere); the efficiency peaks at a moderate slip; no slip sinkage
    unless asked."""
    tyre = SoftSoilTyre(AGRI, "sandy_loam")
    slip = np.linspace(0.0, 0.95, 96)
    out = tyre.evaluate(fz=25e3, slip=slip, p=1.2e5)
    dp = out.drawbar_pull
    assert np.all(np.diff(dp) > 0)
    gain_late = dp[-1] - dp[60]                      # i 0.6 -> 0.95
    gain_early = dp[60] - dp[0]                      # i 0 -> 0.6
    assert gain_late < 0.1 * gain_early
    s = tyre.soil
    rigid_plastic = SoftSoilTyre(AGRI, Soil("stiff", s.n, s.k_c, s.k_phi, s.c, s.phi, 1e-9))  # K -> 0: tau = tau_max
    limit = float(rigid_plastic.evaluate(fz=25e3, slip=0.5, p=1.2e5).drawbar_pull)
    assert 0.9 * limit < dp[-1] < limit
    assert np.nanargmax(out.efficiency) < 30
    assert np.all(np.diff(out.sinkage) == 0)


def test_sinkage_grows_with_load():
    for name in ("sandy_loam", "paddy_soil", "clayey_soil"):
        out = SoftSoilTyre(AGRI, name).evaluate(fz=np.linspace(5e3, 30e3, 11), slip=0.1, p=1.2e5)
        assert np.all(np.diff(out.sinkage) > 0) and np.all(np.diff(out.motion_resistance) > 0), name


def test_towed_wheel_turns_slower_than_on_hard_ground_and_skids_less_at_lower_pressure():
    """Seed 001 (FE tyre towed on soft soil): the towed wheel turns slower than on the road (its Fig. 12) and
    the tyre at lower pressure keeps turning longer (Fig. 13). The steady model: zero torque needs the flat part to
    skid against the front arc (slip < 0), less so at lower pressure (a shorter arc against a longer flat part).
    Seed 001's FE wheel ends up not turning at all; this steady model has no soil flow ahead of the wheel."""
    agri = load_tir(AGRI)
    p = np.array([1.0e5, 1.15e5, 1.3e5, 1.45e5])
    for name in ("sandy_loam", "clayey_soil"):
        soft = SoftSoilTyre(agri, name)
        towed = soft.towed(20e3, p=p, vx=2.0)
        hard = agri.evaluate(fz=20e3, kappa=0.0, alpha=0.0, vx=2.0, p=p)
        np.testing.assert_allclose(towed.torque, 0.0, atol=1e-9 * 20e3 * agri.params.UNLOADED_RADIUS)
        assert np.all(towed.omega < hard.omega) and np.all(towed.slip < 0)
        assert np.all(np.diff(towed.slip) < 0), (name, towed.slip)
        assert np.all(soft.evaluate(fz=20e3, slip=towed.slip - 1e-3, p=p, vx=2.0).torque < 0)
        assert np.all(soft.evaluate(fz=20e3, slip=towed.slip + 1e-3, p=p, vx=2.0).torque > 0)


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
    if soil_name == "paddy_soil":  # a soft soil: loads the tyre does not sink into to its axle
        pts = dict(pts, fz=pts["fz"] / 2)
    out = tyre.evaluate(**pts)
    got = f.map(40)(*(pts[k][None, :] for k in ("fz", "slip", "alpha", "p")))
    names = f.name_out()
    for k, value in zip(names, got):
        key = k[:-4] if k.endswith("_out") else k
        np.testing.assert_allclose(np.ravel(value.full()), np.ravel(out[key]), rtol=1e-11, atol=1e-9, err_msg=key)


def test_casadi_derivatives_match_finite_differences():
    """d(drawbar pull, Fy, sinkage)/d(fz, slip, alpha, p) from CasADi against central differences of the NumPy
    model, in the flexible mode (sandy loam) and in the rigid mode (paddy soil)."""
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
    ("bad,0.8,10,800,3.5,95,0.02", r"mine.csv:3: soil 'bad': phi must be in \[0, 60\] deg"),
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
        tyre.evaluate(fz=[4e3, 8e3, 9e3], slip=0.1, p=2.2e5)
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


# ------------------------------------------------------------------------------ continuity in pressure
def test_outputs_continuous_and_smooth_in_pressure():
    """No switch: over a fine pressure sweep (the 420/85 R24 on clayey soil at 0.8 FNOMIN, where Wong's switch
    jumped by 0.2 m of contact length near 1.6 bar) every output changes by at most a few times its mean step
    between neighbours, and the second differences stay small (no kink)."""
    tyre = SoftSoilTyre(AGRI_SMALL, "clayey_soil")
    p = np.linspace(0.8e5, 2.4e5, 2001)
    out = tyre.evaluate(fz=0.8 * tyre.params.FNOMIN, slip=0.15, alpha=0.02, p=p)
    for key in ("contact_length", "flat_length", "sinkage", "deflection", "gross_traction", "drawbar_pull",
                "torque", "fy", "motion_resistance", "rolling_radius", "ground_pressure", "flat_load"):
        steps = np.diff(out[key])
        mean = abs(out[key][-1] - out[key][0]) / (p.size - 1) + 1e-12 * np.abs(out[key]).max()
        assert np.abs(steps).max() < 5 * mean, (key, np.abs(steps).max(), mean)
        assert np.abs(np.diff(steps)).max() < 0.05 * np.abs(steps).max() + 1e-9 * np.abs(out[key]).max(), key


def test_casadi_derivatives_in_pressure():
    """d(outputs)/dp from CasADi (through the unrolled vertical balance and its last Newton step) against central
    differences of the NumPy model, and their integral over a pressure range against the change of the outputs."""
    import casadi as ca

    tyre = SoftSoilTyre(AGRI_SMALL, "clayey_soil")
    fz = 0.8 * tyre.params.FNOMIN
    keys = ("contact_length", "drawbar_pull", "torque", "sinkage")
    f = tyre.casadi_function(inputs=("p",), outputs=keys, fixed=dict(fz=fz, slip=0.15, alpha=0.02))
    x = ca.SX.sym("p")
    jac = ca.Function("d", [x], [ca.jacobian(ca.vertcat(*f(x)), x)])
    for point in (0.9e5, 1.3e5, 1.7e5, 2.3e5):
        analytic = np.ravel(jac(point).full())
        h = 1.0
        hi, lo = (tyre.evaluate(fz=fz, slip=0.15, alpha=0.02, p=point + d) for d in (h, -h))
        fd = np.array([(hi[k] - lo[k]) / (2 * h) for k in keys], dtype=float).ravel()
        np.testing.assert_allclose(analytic, fd, rtol=2e-4, atol=1e-6 * np.abs(fd).max() + 1e-12)
    grid = np.linspace(1.0e5, 2.0e5, 401)
    slopes = np.array([np.ravel(jac(q).full()) for q in grid])
    values = tyre.evaluate(fz=fz, slip=0.15, alpha=0.02, p=grid)
    for col, key in enumerate(keys):
        change = values[key][-1] - values[key][0]
        integral = np.sum(0.5 * (slopes[1:, col] + slopes[:-1, col]) * np.diff(grid))
        assert integral == pytest.approx(change, rel=1e-4, abs=1e-9), key


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
    """s_j = 1: Lyasko's factor f = (1 + i)/(1 - 0.5 i) for driving slip, none for braking. The dug part of the rut
    carries nothing (sigma = k (d/f)^n), so the balance shifts load to the longer front arc: the sinkage grows with
    the slip by less than f, the compaction resistance R_c = B k f^-n z^(n+1)/(n+1) grows, the pull falls at high
    slip; s_j = 0.5 lies in between; braking changes nothing."""
    slip = np.array([-0.3, 0.0, 0.1, 0.3, 0.6])
    kw = dict(fz=25e3, slip=slip, p=1.2e5)
    static = SoftSoilTyre(AGRI, "sandy_loam").evaluate(**kw)
    lyasko = SoftSoilTyre(AGRI, "sandy_loam", slip_sinkage=1.0).evaluate(**kw)
    half = SoftSoilTyre(AGRI, "sandy_loam", slip_sinkage=0.5).evaluate(**kw)
    factor = np.where(slip > 0, (1 + slip) / (1 - 0.5 * slip), 1.0)
    ratio = lyasko.sinkage / static.sinkage
    np.testing.assert_array_equal(ratio[:2], 1.0)
    assert np.all((ratio[2:] > 1) & (ratio[2:] < factor[2:])) and np.all(np.diff(ratio[1:]) > 0)
    assert np.all((half.sinkage[2:] > static.sinkage[2:]) & (half.sinkage[2:] < lyasko.sinkage[2:]))
    n, B = soil("sandy_loam").n, AGRI_TYRE_WIDTH
    k = soil("sandy_loam").modulus(B)
    np.testing.assert_allclose(lyasko.compaction_resistance,
                               B * k * factor ** -n * lyasko.sinkage ** (n + 1) / (n + 1), rtol=1e-12)
    assert np.all(np.diff(lyasko.motion_resistance[1:]) > 0)
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


# ------------------------------------------------------------------------------------------------ multi-pass
# Wong's unloading slope k_u = k_0 + A_u z_u: sandy terrain k_0 = 0, A_u = 503 MN/m^4 (the value as recalled from
# Wong's text; the tests use it as an input, they do not check it)
SANDY_UNLOADING = (0.0, 503e6)


def test_rear_tyre_in_the_front_rut_repetitive_loading():
    """Multi-pass: the rear tyre (same load and pressure) in the front tyre's rut meets soil that rebounded along
    Wong's unloading line and reloads along it: it sinks further than the front (repetitive loading deepens the
    rut) but by less than the front's rut, and meets less compaction resistance; the rut work is the integral of
    the piecewise stress over depth (scipy); with rut=0 nothing changes, bit for bit; a stiffer unloading line
    (less rebound) leaves less to re-compress."""
    model = load_tir(AGRI)
    front_tyre = SoftSoilTyre(model, "sandy_loam", unloading=SANDY_UNLOADING)
    front = front_tyre.evaluate(fz=25e3, slip=0.15, p=1.2e5)
    plain = SoftSoilTyre(model, "sandy_loam").evaluate(fz=25e3, slip=0.15, p=1.2e5)
    for key in front.keys():
        np.testing.assert_array_equal(front[key], plain[key], err_msg=key)
    rear_tyre = front_tyre.following(front)
    rear = rear_tyre.evaluate(fz=25e3, slip=0.15, p=1.2e5)
    z_1, z_2 = float(front.sinkage), float(rear.sinkage)
    assert z_1 < z_2 < 2 * z_1
    assert float(rear.compaction_resistance) < 0.5 * float(front.compaction_resistance)
    s, B = soil("sandy_loam"), model.params.WIDTH
    k = s.modulus(B)
    sigma_1, k_u = k * z_1**s.n, SANDY_UNLOADING[1] * z_1

    def stress(d):
        return max(k_u * (d - z_1) + sigma_1, 0.0) if d < z_1 else k * d**s.n

    work = B * quad(stress, 0.0, z_2, points=[z_1 - sigma_1 / k_u, z_1], limit=200)[0]
    assert float(rear.compaction_resistance) == pytest.approx(work, rel=1e-10)
    stiffer = SoftSoilTyre(model, "sandy_loam", unloading=(0.0, 10 * SANDY_UNLOADING[1])).following(front)
    less = float(stiffer.evaluate(fz=25e3, slip=0.15, p=1.2e5).compaction_resistance)
    assert less < float(rear.compaction_resistance)
    out = rear_tyre.evaluate(fz=25e3, slip=np.array([0.05, 0.3]), alpha=0.05, p=1.2e5, vx=2.0)   # energy in the rut
    lhs = out.torque * out.omega - out.fy * 2.0 * np.tan(0.05)
    rhs = (out.drawbar_pull + out.motion_resistance) * 2.0 + out.slip_power + out.hysteresis_moment * out.omega
    np.testing.assert_allclose(lhs, rhs, rtol=1e-9)


def test_rear_tyre_where_the_soil_would_spring_back_above_its_surface():
    """On firm LETE sand with Wong's sand unloading constants sigma_1 / k_u exceeds the rut depth z_1: the soil
    rebounds to its surface, no further. The reloading line then starts from zero stress at the surface (it
    started at 99 kPa there: the rear tyre sank less than the front and met more compaction resistance)."""
    model = load_tir(AGRI)
    front_tyre = SoftSoilTyre(model, "lete_sand", unloading=SANDY_UNLOADING)
    front = front_tyre.evaluate(fz=25e3, slip=0.1, p=1.2e5)
    s = soil("lete_sand")
    z_1 = float(front.sinkage)
    sigma_1 = s.modulus(model.params.WIDTH) * z_1**s.n
    assert sigma_1 / (SANDY_UNLOADING[1] * z_1) > z_1                      # the case this is about
    rear = front_tyre.following(front).evaluate(fz=25e3, slip=0.1, p=1.2e5)
    z_2 = float(rear.sinkage)
    assert z_1 < z_2 < 2 * z_1
    assert float(rear.compaction_resistance) < float(front.compaction_resistance)
    work = model.params.WIDTH * quad(lambda d: sigma_1 * d / z_1 if d < z_1 else s.modulus(model.params.WIDTH)
                                     * d**s.n, 0.0, z_2, points=[z_1], limit=200)[0]
    assert float(rear.compaction_resistance) == pytest.approx(work, rel=1e-10)


def test_multi_pass_bad_input():
    with pytest.raises(ModelInputError, match="needs unloading"):
        SoftSoilTyre(AGRI, "sandy_loam", rut=0.03)
    with pytest.raises(ModelInputError, match="unloading must be"):
        SoftSoilTyre(AGRI, "sandy_loam", unloading=(0.0, -1.0))
    with pytest.raises(ModelInputError, match="cannot be combined"):
        SoftSoilTyre(AGRI, "sandy_loam", rut=0.03, unloading=SANDY_UNLOADING, slip_sinkage=1.0)
    front = SoftSoilTyre(AGRI, "sandy_loam").evaluate(fz=[20e3, 25e3], slip=0.1)
    with pytest.raises(ModelInputError, match="one point"):
        SoftSoilTyre(AGRI, "sandy_loam", unloading=SANDY_UNLOADING).following(front)


# ------------------------------------------------------------------------------------------------ cone index
def test_cone_index_model_follows_brixius():
    """Brixius (1987; ASAE D497): the outputs against the published equations evaluated here by hand from the
    mobility number B_n = (CI b d/W)(1 + 5 delta/h)/(1 + 3 b/d); the power balance T omega = DP V + MR V + slip
    loss; the towed wheel's closed-form slip has zero torque; a higher cone index (firmer soil) gives more pull
    and less resistance; and Ground runs it like the Bekker-Wong model."""
    from mftyre.soil import ConeIndexTyre
    from mftyre.soil.cone_index import mobility_number

    model = load_tir(AGRI)
    prm = model.params
    tyre = ConeIndexTyre(model, cone_index=1.2e6)
    slip = np.array([0.0, 0.05, 0.15, 0.3])
    out = tyre.evaluate(fz=25e3, slip=slip, p=1.2e5, vx=2.0)
    rho, _, _ = hard_ground_footprint(prm, 25e3, 1.2e5, NUMPY)
    h, b, d = prm.UNLOADED_RADIUS - prm.RIM_RADIUS, prm.WIDTH, 2 * prm.UNLOADED_RADIUS
    bn = 1.2e6 * b * d / 25e3 * (1 + 5 * rho / h) / (1 + 3 * b / d)
    assert mobility_number(1.2e6, b, d, 25e3, rho, h) == pytest.approx(bn, rel=1e-14)
    gtr = 0.88 * (1 - np.exp(-0.1 * bn)) * (1 - np.exp(-7.5 * slip)) + 0.04
    mrr = 1 / bn + 0.04 + 0.5 * slip / np.sqrt(bn)
    np.testing.assert_allclose(out.gross_traction / 25e3, gtr, rtol=1e-12)
    np.testing.assert_allclose(out.motion_resistance / 25e3, mrr, rtol=1e-12)
    np.testing.assert_allclose(out.drawbar_pull / 25e3, gtr - mrr, rtol=1e-12)
    np.testing.assert_allclose(out.torque * out.omega,
                               out.drawbar_pull * 2.0 + out.motion_resistance * 2.0 + out.slip_power, rtol=1e-12)
    ok = out.power > 0
    assert np.all(out.efficiency[ok] <= 1 - slip[ok])
    towed = tyre.towed(25e3, p=1.2e5, vx=2.0)
    assert abs(float(towed.torque)) < 1e-9 * 25e3 and float(towed.slip) < 0 and float(towed.drawbar_pull) < 0
    firmer = ConeIndexTyre(model, cone_index=2.4e6).evaluate(fz=25e3, slip=slip, p=1.2e5, vx=2.0)
    assert np.all(firmer.drawbar_pull > out.drawbar_pull) and np.all(firmer.motion_resistance < out.motion_resistance)
    forces = Ground(model, tyre).forces(fz=25e3, kappa=slip / (1 - slip), vx=2.0, p=1.2e5)
    np.testing.assert_allclose(forces.fx, out.drawbar_pull, rtol=1e-12)
    with pytest.raises(ModelInputError, match="cone_index must be a positive number"):
        ConeIndexTyre(model, cone_index=-1.0)


def test_balance_without_a_root_in_the_bracket_is_a_typed_error():
    """A tyre absurdly stiff (Cz x 1e30) would need a flat load below 1e-30 Fz: an error, not a silent clip;
    Cz x 1e8 still balances (the rigid-wheel limit)."""
    model = load_tir(AGRI)
    stiff = model.with_params(VERTICAL_STIFFNESS=model.params.VERTICAL_STIFFNESS * 1e8)
    assert float(SoftSoilTyre(stiff, "paddy_soil").evaluate(fz=10e3, slip=0.1).flat_load) < 1e-3
    absurd = model.with_params(VERTICAL_STIFFNESS=model.params.VERTICAL_STIFFNESS * 1e30)
    with pytest.raises(ModelInputError, match="flat load below 1e-30 Fz"):
        SoftSoilTyre(absurd, "paddy_soil").evaluate(fz=10e3, slip=0.1)


def test_towed_outside_the_bracket_says_where_and_why():
    """A tyre sunk to near its axle needs driving torque even at slip -1: the error names the operating point and
    the sinkage (it said 'the soil cannot turn the wheel', the opposite of what happens)."""
    tyre = SoftSoilTyre(AGRI_SMALL, "lean_clay_wet")
    fz = tyre.params.FNOMIN * np.array([1.0, 1.5])
    with pytest.raises(ModelInputError, match=r"at fz = 33832.5 N, p = 150000 Pa the wheel needs a driving torque "
                                              r"even turning at half its free-rolling speed \(slip -1; sinkage 0.6"):
        tyre.towed(fz=fz, p=1.5e5, vx=0.5, alpha=0.05)
