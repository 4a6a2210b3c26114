"""SWIFT rigid ring from standstill to 200 km/h and over 50 mm obstacles (issue 13): the static vertical relation
to bottoming, creep equal to the quasi-static model, kerb, pothole, standstill, slope, reversing, run() = step(),
belt-yaw slip, pressure-aware sidewall damping, warnings for unmodelled parameters."""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import mftyre
from mftyre.backend import NUMPY
from mftyre.errors import ModelInputError
from mftyre.formula import vertical
from swift import Cleat, Flat, Sampled, Step, StepInputs, SwiftTyre, quasi_static
from swift.ring import STATE_NAMES, RingConstants

from conftest import SHARED, TIR_FILES, require_shared

S = {n: i for i, n in enumerate(STATE_NAMES)}
pytestmark = pytest.mark.filterwarnings("ignore:Q_BV", "ignore:road height range")


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")


def _with(model, **changes):
    return mftyre.MFModel(model.params.replace(**changes))


def test_static_force_equals_vertical_relation_to_bottoming(model):
    """Rim at a fixed height, static equilibrium (no gravity on the belt): the wheel-centre force is the MF
    Fz(rho) of the .tir, through 90 mm and into bottoming (old: 130 kN instead of 21.7 kN at 90 mm, LinAlgError
    from 70 mm)."""
    m = _with(model, GRAVITY=0.0)
    tyre = SwiftTyre(m, Flat(), x_range=(0.0, 3.0))
    V, omega = 5.0, 5.0 / 0.3
    r_omega = float(vertical.free_radius(m.params, omega, NUMPY))
    for rho in (0.005, 0.02, 0.05, 0.07, 0.09, 0.12):
        u = StepInputs(x=1.0, vx=V, z=r_omega - rho, omega=omega)
        out = tyre.step(tyre.initial_state(u), u, 0.0)[1]
        assert out["rho"] == pytest.approx(rho, abs=1e-12)
        assert out["fz"] == pytest.approx(float(m.vertical_force(r_omega - rho, omega=omega)), rel=1e-6)


def test_creep_over_cleat_equals_quasi_static(model):
    """0.1 m/s over a 10 x 20 mm cleat, free-rolling rim, fixed axle: the dynamic model is the quasi-static one
    (tandem under the wheel centre, tandem base at the contact load in both): Fz within 5 % of the peak, Fx within
    5 % of its range, l_s within 1.5 mm (old: l_s 143 mm against 121 mm, dFz 112 N against 653 N at the cleat centre)."""
    rl, _ = model.loaded_radius(4000.0)
    road = Cleat(0.4, 0.02, 0.01)
    tyre = SwiftTyre(model, road, rim="torque", x_range=(0.0, 1.2))
    V = 0.1
    res = tyre.run(3.0, StepInputs(x=0.25, vx=V, z=float(rl), omega=V / 0.3044), dt=2e-3)
    qs = quasi_static(model, road, res.x, 4000.0)
    peak = np.max(qs.fz - qs.fz[0])
    assert peak > 500.0
    assert np.max(np.abs((res["fz"] - res["fz"][0]) - (qs.fz - qs.fz[0]))) < 0.05 * peak
    assert np.max(np.abs(res["ls"] - qs.ls)) < 1.5e-3
    # Fx: the quasi-static tyre rolls freely (F'_x = 0), the dynamic one carries its rolling resistance
    assert np.max(np.abs((res["fx"] - res["fx"][0]) - (qs.fx - qs.fx[0]))) < 0.05 * np.ptp(qs.fx)
    centre = np.argmin(np.abs(res.x - 0.41))
    assert res["fz"][centre] - res["fz"][0] > 0.9 * (qs.fz[centre] - qs.fz[0])


@pytest.mark.parametrize("kmh", [10.0, 30.0, 60.0])
def test_kerb_50mm_finite_and_bounded(model, kmh):
    """A 50 mm kerb at fixed axle height: finite, contact force >= 0, peak within 1.5x the quasi-static peak
    (old: 45.6 kN against 16 kN at 10 km/h, non-finite at 60 km/h)."""
    rl, _ = model.loaded_radius(4000.0)
    road = Step(1.0, 0.05)
    qs = quasi_static(model, road, np.linspace(0.5, 1.6, 221), 4000.0)
    V = kmh / 3.6
    tyre = SwiftTyre(model, road, x_range=(0.0, 3.0))
    res = tyre.run(1.2 / V, StepInputs(x=0.5, vx=V, z=float(rl), omega=V / 0.3044))
    assert np.all(np.isfinite(res.states))
    assert res["fz_c"].min() >= 0.0
    assert res["fz"].max() > 0.95 * qs.fz.max()  # the kerb was climbed
    assert res["fz"].max() < 1.5 * qs.fz.max()


@pytest.mark.parametrize("kmh", [30.0, 60.0])
def test_pothole_lift_off_and_landing(model, kmh):
    """Constant load over a 30 mm deep, 0.5 m long pothole: the tyre leaves the road (contact force 0) and lands;
    everything finite, contact force never negative, slips bounded (old: kappa' 1e12-1e254 in the air, NaN)."""
    road = Cleat(1.0, 0.5, -0.03)
    V = kmh / 3.6
    tyre = SwiftTyre(model, road, axle="load", x_range=(0.0, 3.0))
    res = tyre.run(1.5 / V, StepInputs(x=0.5, vx=V, load=4000.0, omega=V / 0.3044))
    assert np.all(np.isfinite(res.states))
    assert np.any(res["fz_c"] == 0.0)  # lift-off
    assert res["fz_c"].min() >= 0.0 and res["fz_c"][res.x > 1.55].max() > 4000.0  # landed
    assert res["fz_c"].max() < 5 * 4000.0
    assert np.max(np.abs(res["kappa"])) < 0.2 and np.max(np.abs(res["alpha"])) < 0.2


def test_standstill_initialisation_and_rest(model):
    """vx = 0: finite static equilibrium (old: NaN Jacobian, LinAlgError) that stays at rest; from near standstill
    the forces stay smooth (old: +-30 kN)."""
    tyre = SwiftTyre(model, Flat(), axle="load", rim="speed", x_range=(0.0, 3.0))
    u = StepInputs(x=1.0, vx=0.0, load=4000.0, omega=0.0)
    state = tyre.initial_state(u)
    assert np.all(np.isfinite(state))
    res = tyre.run(1.0, u)
    assert res["fz"] == pytest.approx(np.full(res.t.size, 4000.0), rel=1e-9)
    assert np.ptp(res["fx"]) < 1e-3
    V = 0.05
    res = tyre.run(2.0, StepInputs(x=1.0, vx=V, load=4000.0, omega=V / 0.3044))
    assert np.all(np.isfinite(res.states)) and np.ptp(res["fx"]) < 20.0 and np.ptp(res["fz"]) < 20.0


def test_parked_on_a_20_percent_slope(model):
    """Locked wheel at rest on a 20 % grade, axle pushed down with 4 kN: the contact holds (static grip, old: Fx =
    0 at vx = 0) and the belt drifts less than 1 mm in 10 s."""
    grade = Sampled([-10.0, 10.0], [-2.0, 2.0])
    tyre = SwiftTyre(model, grade, axle="load", rim="speed", x_range=(0.0, 3.0))
    res = tyre.run(10.0, StepInputs(x=1.0, vx=0.0, load=4000.0, omega=0.0), dt=2e-3)
    assert np.all(np.isfinite(res.states))
    assert res["beta"][-1] == pytest.approx(np.arctan(0.2), abs=1e-3)
    assert np.ptp(res["xb"]) < 1e-3 and np.ptp(res["zb"]) < 1e-3


def test_torque_at_standstill_does_not_spin_the_wheel(model):
    """50 N m on a free rim at rest: the tyre's static grip holds it after a small rotation (old: the MF low-speed
    reduction gave Fx = 0 and the wheel spun up freely)."""
    tyre = SwiftTyre(model, Flat(), axle="load", rim="torque", x_range=(0.0, 3.0))
    res = tyre.run(2.0, StepInputs(x=1.0, vx=0.0, load=4000.0, omega=0.0, torque=50.0))
    rotation = np.sum(res["oma"][1:]) * 1e-3
    assert abs(rotation) < 5e-3 and abs(res["oma"][-1]) < 1e-3
    assert res["fx"][-1] == pytest.approx(50.0 / res["rl"][-1], rel=0.05)  # the contact carries the torque


def test_reversing_at_30_kmh(model):
    """-30 km/h: free rolling stays at the rolling speed (old: spin from -27.4 to +1915 rad/s); a brake torque
    (positive when reversing) gives a positive Fx (opposing the motion) at a positive kappa'."""
    V = -30 / 3.6
    tyre = SwiftTyre(model, Flat(), axle="load", rim="torque", x_range=(-12.0, 3.0))
    res = tyre.run(1.0, StepInputs(x=1.0, vx=V, load=4000.0, omega=V / 0.3044))
    assert np.all(np.isfinite(res.states))
    assert np.all(np.abs(res["omb"] * res["re"] / V - 1.0) < 0.01)
    res = tyre.run(1.0, StepInputs(x=1.0, vx=V, load=4000.0, omega=V / 0.3044, torque=300.0))
    assert res["fx"][-1] == pytest.approx(300.0 / res["rl"][-1], rel=0.1) and res["kappa"][-1] > 0


def test_run_equals_step_at_200_kmh(model):
    """200 km/h over a cleat: run() (blocks of steps) equals the step() loop (old: run read a fixed road window per
    call of 10 steps: dFz 750-9422 N against 2692-3332 N)."""
    rl, _ = model.loaded_radius(4000.0)
    V = 200 / 3.6
    tyre = SwiftTyre(model, Cleat(2.14, 0.05, 0.01), x_range=(0.0, 6.0))  # near the end of a block of 10 steps
    u = StepInputs(x=0.5, vx=V, z=float(rl), omega=V / 0.3044)
    res = tyre.run(0.05, u)
    state = tyre.initial_state(u)
    fz = []
    for k in range(50):
        state, out = tyre.step(state, StepInputs(x=0.5 + V * k * 1e-3, vx=V, z=float(rl), omega=V / 0.3044), 1e-3)
        fz.append(out["fz"])
    assert np.ptp(fz) > 1000.0
    assert res["fz"][1:] == pytest.approx(np.array(fz), rel=1e-9, abs=1e-6)


def test_yaw_compliance_acts_on_transient_not_steady_forces(model):
    """Belt-based slip: the belt's yaw compliance (FREQ_YAW) changes the side-force build-up after a heading
    step, the steady state stays the Magic Formula's. (YAW_STIFFNESS alone no longer does, issue 19: the static
    twist Mz/C_psi is added back from the moment the residual spring carries, so the residual yaw spring's share
    cancels and only the belt's yaw dynamics remain; test_swift_modes.)"""
    V = 20.0
    results = []
    for freq in (53.49, 30.0):
        m = _with(model, FREQ_YAW=freq)
        tyre = SwiftTyre(m, Flat(), axle="load", x_range=(0.0, 12.0))
        res = tyre.run(0.5, lambda t: StepInputs(x=V * t, vx=V, load=4000.0, omega=V / 0.3044,
                                                 psi=0.02 if t > 0.02 else 0.0))
        results.append(res["fy"])
    steady = np.mean(results[0][-100:])  # over the last 0.1 s: the belt yaw mode (DAMP_YAW 0.007) still rings
    assert np.mean(results[1][-100:]) == pytest.approx(steady, rel=5e-3)
    assert np.max(np.abs(results[0] - results[1])) > 0.02 * abs(steady)


def test_pressure_aware_sidewall_damping(model):
    """SWIFT_PSTIFF / SWIFT_PDAMP absent from the file (as in the sample file): derived from its vertical pressure
    term, PFZ1 and f_d = 1/sqrt(f_c) (swift.ring notes), the vertical belt mode stiffens and its damping ratio falls with
    pressure, as the FE tyre of seed 001 decays fastest at the lowest pressure (issue 19; old default 0: the ratio
    rose, 0.112 -> 0.125 over PRESMIN..PRESMAX). Written as 0 in the file: no pressure effect on the sidewall (the
    ratio then rises through the stiffness-proportional residual damping); SWIFT_PDAMP < 0 alone also reverses it.
    All pressure effects vanish at NOMPRES."""
    from swift.ring import pressure_coefficients

    prm = model.params

    def vertical_mode(m, p):
        tyre = SwiftTyre(m, Flat(), x_range=(0.0, 3.0))
        rl_p, _ = m.loaded_radius(4000.0, p=p)
        u = StepInputs(x=1.0, vx=10.0, z=float(rl_p), omega=10.0 / 0.3044, p=p)
        ev = np.linalg.eigvals(tyre.jacobian(tyre.initial_state(u), u))
        ev = ev[ev.imag > 1.0]
        mode = ev[np.argmin(np.abs(np.abs(ev) / (2 * np.pi) - 82.0))]
        return -mode.real / abs(mode), abs(mode) / (2 * np.pi)

    assert "SWIFT_PSTIFF" in prm.missing and pressure_coefficients(prm) == (prm.PFZ1, None)
    low, high = prm.PRESMIN, prm.PRESMAX
    (z_low, f_low), (z_high, f_high) = vertical_mode(model, low), vertical_mode(model, high)
    assert z_low > z_high and f_low < f_high
    off = _with(model, SWIFT_PSTIFF=0.0, SWIFT_PDAMP=0.0)
    assert vertical_mode(off, low)[0] < vertical_mode(off, high)[0]
    tuned = _with(off, SWIFT_PDAMP=-1.5)  # (-2 is refused: f_d = 0 at 1.5 NOMPRES)
    assert vertical_mode(tuned, low)[0] > vertical_mode(tuned, high)[0]
    for m in (off, tuned):
        assert vertical_mode(m, prm.NOMPRES)[0] == pytest.approx(vertical_mode(model, prm.NOMPRES)[0], rel=1e-9)


def test_default_damping_factor_stays_positive_over_the_declared_pressures():
    """SWIFT_PDAMP absent: f_d = 1/sqrt(f_c) (the damping coefficients k_b = 2 DAMP f_d sqrt(c_b M) f_c-independent),
    first-order slope -PFZ1/2 at NOMPRES as the old linear default; the linear one gave f_d = 1 - PFZ1/2 dpi =
    -0.26 (negative damping) at the TNO file's PRESMAX 10 bar (dpi 3.5)."""
    from swift.ring import _pressure_factors

    tno = mftyre.load_tir(require_shared(SHARED / "reference" / "tir" / "TNO_car205_60R15.tir")).params
    for prm in (tno, mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir").params):
        for p in np.linspace(prm.PRESMIN, prm.PRESMAX, 9):
            f_c, f_d = _pressure_factors(prm, (p - prm.NOMPRES) / prm.NOMPRES, NUMPY)
            assert f_c > 0 and f_d > 0 and np.sqrt(f_c) * f_d == pytest.approx(1.0, rel=1e-12)
        h = 1e-6
        slope = (_pressure_factors(prm, h, NUMPY)[1] - _pressure_factors(prm, -h, NUMPY)[1]) / (2 * h)
        assert slope == pytest.approx(-prm.PFZ1 / 2, rel=1e-6)


@pytest.mark.parametrize("changes, p_ratio, blamed", [({"SWIFT_PSTIFF": 1.5}, 0.3, "SWIFT_PSTIFF"),
                                                      ({"SWIFT_PDAMP": -0.5}, 4.0, "SWIFT_PDAMP")])
@pytest.mark.parametrize("compiled", [False, True])
def test_pressure_with_a_non_positive_sidewall_factor_is_refused(model, changes, p_ratio, blamed, compiled):
    """Explicit linear coefficients (legal over 0.5-1.5 NOMPRES) at a pressure where f_c = 1 + SWIFT_PSTIFF dpi or
    f_d = 1 + SWIFT_PDAMP dpi <= 0: a ModelInputError naming the parameter and the pressure, from initial_state and
    from a step (compiled: the C loop checks the factors), instead of a ring with negative stiffness or damping."""
    m = model.with_params(**changes)
    tyre = SwiftTyre(m, Flat(), x_range=(0.0, 3.0), compiled=compiled)
    p = p_ratio * m.params.NOMPRES
    u = StepInputs(x=1.0, vx=10.0, z=0.29, omega=33.0, p=p)
    with pytest.raises(ModelInputError, match=rf"p = {p:g} Pa .*{blamed} dpi = -[0-9.]+ <= 0"):
        tyre.initial_state(u)
    state = tyre.initial_state(replace(u, p=m.params.NOMPRES))
    with pytest.raises(ModelInputError, match=rf"p = {p:g} Pa .*{blamed}"):
        tyre.step(state, u, 1e-3)


def test_unmodelled_sidewall_parameters_warn(model):
    with pytest.warns(UserWarning, match="Q_BVX"):
        RingConstants.from_model(model)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        RingConstants.from_model(_with(model, Q_BVX=0.0, Q_BVT=0.0))


def test_multi_track_road_camber_in_the_ring(model):
    """ELLIPS_NWIDTH tracks in the dynamic model (old: one track at y = 0): over a cleat under the left half only,
    the ring's road camber equals the offline multi-track tandem (effective_road_3d at the ring's contact centre
    and tandem base); on a uniformly banked road the normal force tilts and the MF sees the camber relative to
    the road, so the lateral force is the in-plane MF side force less F'_z sin(beta_x)."""
    from swift import TwoTrack, effective_road_3d

    _, b = vertical.contact_patch(model.params, model.params.FNOMIN, 0.0, NUMPY)
    road = TwoTrack(Flat(0.0) + Cleat(1.0, 0.05, 0.01), Flat(0.0), 0.2)
    tyre = SwiftTyre(model, road, axle="load", x_range=(0.0, 2.5))
    V = 5.0
    res = tyre.run(0.4, StepInputs(x=0.3, vx=V, load=4000.0, omega=V / 0.3044))
    ref = effective_road_3d(road, res.states[:, S["xb"]], res["ls"], float(b), tyre.cams)  # tandem under the belt
    assert np.max(np.abs(ref.beta_x)) > 0.03
    assert np.max(np.abs(res["beta_x"] - ref.beta_x)) < 2e-4
    bank = np.arctan(0.05)
    tyre = SwiftTyre(model, TwoTrack(Flat(0.01), Flat(0.0), 0.2), axle="load", x_range=(0.0, 2.5))
    res = tyre.run(0.3, StepInputs(x=0.5, vx=V, load=4000.0, omega=V / 0.3044))
    assert res["beta_x"][-1] == pytest.approx(bank, abs=1e-9)
    fz_c, fy_c = res["fz_c"][-1], res["fy_c"][-1]
    mf = model.evaluate(fz_c, res["kappa"][-1], res["alpha"][-1], gamma=-bank, vx=V, omega=res["omb"][-1])
    assert fy_c == pytest.approx(float(mf.fy), rel=1e-6)
    assert res["fy"][-1] == pytest.approx(fy_c * np.cos(bank) - fz_c * np.sin(bank), rel=1e-3, abs=1.0)


def test_unused_ellips_nlength_warns_once_per_model(model, tmp_path):
    """ELLIPS_NLENGTH has no published role (module notes of swift.enveloping): a value set in the file is reported
    once per model, naming the parameter, the file and its line (old: silently ignored); a file without it is
    quiet. The FMU's functions build the cams twice and still warn once."""
    from swift.fmu_model import swift_functions

    def nlength_warnings(build):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            build()
        return [str(w.message) for w in caught if "ELLIPS_NLENGTH" in str(w.message)]

    source = TIR_FILES / "car_205_60R15_mf62_swift.tir"
    line = model.params.lines["ELLIPS_NLENGTH"]
    for build in (lambda: SwiftTyre(model, Flat(), x_range=(0.0, 1.0)), lambda: swift_functions(model)):
        found = nlength_warnings(build)
        assert len(found) == 1
        assert f"line {line}" in found[0] and source.name in found[0] and "not used" in found[0]
    text = source.read_text().splitlines(keepends=True)
    stripped = tmp_path / "no_nlength.tir"
    stripped.write_text("".join(t for t in text if not t.lstrip().startswith("ELLIPS_NLENGTH")))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        quiet = mftyre.load_tir(stripped)
    assert nlength_warnings(lambda: SwiftTyre(quiet, Flat(), x_range=(0.0, 1.0))) == []


def _consistency(model, road, qs, z_axle):
    """(distance, load, base) residuals of a fixed-axle quasi-static solution from the exact cam heights under the
    wheel centre: d = (z_axle - w) cos(beta), F'_z = Fz(d), l_s = ELLIPS_SHIFT 2a(F'_z)."""
    from swift.enveloping import Cams, effective_road, tandem_base
    prm = model.params
    eff = effective_road(road, qs.x, qs.ls, Cams.from_params(prm, warn=False))
    r_omega = float(vertical.free_radius(prm, 0.0, NUMPY))
    d = r_omega - qs.rho
    distance = d - np.minimum((z_axle - eff.w) * np.cos(eff.beta), r_omega)
    load = np.maximum(model.vertical_force(d), 0.0) - qs.fz_normal
    base = qs.ls - tandem_base(prm, qs.fz_normal, (prm.INFLPRES - prm.NOMPRES) / prm.NOMPRES)
    return distance, load, base


def test_quasi_static_converged_on_mfeval_file():
    """MFeval's MF 6.2 file, 20 x 10 mm cleat at fixed axle: the answer does not depend on the iteration setting and
    satisfies the consistency equations (old: 4000 N at x = 0.511 with 12 and 200 passes, 4805 N with 50; 4000 N
    at x = 0.29 where the only consistent load was 4754 N)."""
    from conftest import MFEVAL_DIR, require_shared
    m = mftyre.load_tir(require_shared(MFEVAL_DIR / "MagicFormula62_Parameters.tir"))
    road = Cleat(0.4, 0.02, 0.01)
    x = np.linspace(0.1, 0.7, 601)
    a, b = (quasi_static(m, road, x, 4000.0, iterations=n) for n in (40, 70))
    assert np.max(np.abs(a.fz - b.fz)) < 1e-6
    distance, load, base = _consistency(m, road, a, float(m.loaded_radius(4000.0)[0]))
    # exact cam heights against the solver's 0.1 mm table: residuals of interpolation size
    assert np.max(np.abs(distance)) < 1e-5 and np.max(np.abs(load)) < 10.0 and np.max(np.abs(base)) < 1e-4
    assert a.fz[0] == pytest.approx(4000.0, rel=1e-6) and np.max(a.fz) > 5000.0


def _creep_errors(model, road, x0=0.15, t_end=5.5):
    """0.1 m/s, fixed axle, free rim, 2 ms steps (the errors are the same at 0.5 ms): (the largest Fz error, the
    largest l_s error relative to l_s, the quasi-static peak)."""
    rl, _ = model.loaded_radius(4000.0)
    tyre = SwiftTyre(model, road, rim="torque", x_range=(-0.5, 1.2))
    res = tyre.run(t_end, StepInputs(x=x0, vx=0.1, z=float(rl), omega=0.1 / model.params.UNLOADED_RADIUS), dt=2e-3)
    qs = quasi_static(model, road, res.x, 4000.0)
    peak = np.max(qs.fz - qs.fz[0])
    err = np.abs((res["fz"] - res["fz"][0]) - (qs.fz - qs.fz[0]))
    return err.max(), np.max(np.abs(res["ls"] / qs.ls - 1.0)), peak


_CLEATS = {"20x10": Cleat(0.4, 0.02, 0.01), "20x15": Cleat(0.4, 0.02, 0.015), "10x20": Cleat(0.4, 0.01, 0.02),
           "20x20": Cleat(0.4, 0.02, 0.02), "50x20": Cleat(0.4, 0.05, 0.02), "step20": Step(0.4, 0.02),
           "step50": Step(0.4, 0.05)}


@pytest.mark.parametrize("name", list(_CLEATS))
def test_creep_equals_converged_quasi_static(model, name):
    """Creep over cleats and steps up to 20 x 20 mm and 50 mm equals the converged quasi-static model within 3 % of
    the peak everywhere (1 % measured), l_s within 1 % (0.5 %) (with the tandem at the foot of the normal the
    solution folded: 5 % away from the jumps, up to 30 % at them; before that 18-41 % anywhere and l_s up to
    2.15 m: the contact solution stayed on a root that had vanished)."""
    anywhere, ls, peak = _creep_errors(model, _CLEATS[name])
    assert anywhere < 0.03 * peak and ls < 0.01


@pytest.mark.parametrize("where", [("reference", "tir", "TNO_car205_60R15.tir"),
                                   ("reference", "mfeval", "MagicFormula62_Parameters.tir")], ids=["tno", "mfeval"])
def test_creep_equals_converged_quasi_static_other_files(where):
    """The 20 x 10 mm cleat on the TNO and MFeval MF 6.2 files (MFeval old: 48 %, the reference not converged)."""
    from conftest import SHARED, require_shared
    m = mftyre.load_tir(require_shared(SHARED.joinpath(*where)))
    anywhere, ls, peak = _creep_errors(m, _CLEATS["20x10"])
    assert anywhere < 0.03 * peak and ls < 0.01
