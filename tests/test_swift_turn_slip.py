"""SWIFT turn slip from the contact patch's yaw rate (``SwiftTyre(turn_slip=True)``, swift.ring): the MF's turn-slip
increment at the relaxed spin phi = psi_dot/V of the patch, zero at zero yaw rate (the steady state stays the
Magic Formula's), with the sign of the file's own camber spin (a wheel rolling along its cone needs no camber
thrust), and every mode damped where the file's turn-slip moment resists the yaw; a TurnSlipWarning names the file
and parameters where it does not (opt-in: on the sample and TNO files a belt mode grows at 8 kN)."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import mftyre
from mftyre.errors import TurnSlipWarning
from swift import OUTPUT_NAMES, Flat, StepInputs, SwiftTyre
from swift.modes import scan
from swift.ring import STATE_NAMES, TURN_SLIP_REFERENCE, turn_slip_warning

from conftest import MFEVAL_DIR, SHARED, TIR_FILES, require_shared

SAMPLE = TIR_FILES / "car_205_60R15_mf62_swift.tir"
_S = {n: i for i, n in enumerate(STATE_NAMES)}
_O = {n: i for i, n in enumerate(OUTPUT_NAMES)}
V, FZ = 10.0, 4000.0


def _tyre(model, turn_slip, rim="speed"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return SwiftTyre(model, Flat(), axle="height", rim=rim, x_range=(0.0, 3.0), compiled=False,
                         turn_slip=turn_slip)


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(SAMPLE)


@pytest.fixture(scope="module")
def tyres(model):
    return _tyre(model, False), _tyre(model, True)


def _inputs(model, vx=V, alpha=0.0, gamma=0.0):
    rl, _ = model.loaded_radius(FZ)
    re = float(model.evaluate(FZ, 0.0, 0.0, vx=abs(vx)).re)
    return StepInputs(x=1.0, vx=vx, vy=abs(vx) * math.tan(alpha), z=float(rl), omega=vx / re, gamma=gamma)


@pytest.mark.parametrize("vx, alpha, gamma", [(V, 0.05, 0.03), (-V, -0.03, 0.02), (0.3, 0.0, 0.0)])
def test_zero_yaw_rate_leaves_the_ring_unchanged(model, tyres, vx, alpha, gamma):
    """Steady rolling (cornering, camber, reversing, creeping) without yaw rate: the same equilibrium, outputs and
    state derivative with and without turn slip (to 1e-12): the steady state is still the Magic Formula's."""
    off, on = tyres
    u = _inputs(model, vx, alpha, gamma)
    x_off, x_on = off.initial_state(u), on.initial_state(u)
    assert abs(x_on[_S["phi"]]) < 1e-20
    np.testing.assert_allclose(x_on, x_off, rtol=1e-12, atol=1e-12)
    y_off, y_on = off.outputs(x_off, u), on.outputs(x_off, u)
    np.testing.assert_allclose(y_on, y_off, rtol=1e-12, atol=1e-12 * FZ)
    np.testing.assert_allclose(on.derivative(x_off, u), off.derivative(x_off, u), rtol=1e-12, atol=1e-9)


def test_turn_slip_is_the_mf_increment_at_the_patch_spin(model, tyres):
    """A state with turn slip phi: the contact forces are those without it plus the MF's turn-slip increment
    MF(phit = phi) - MF(phit = 0) (MFModel.evaluate(turn_slip=True), about the reference spin) at the ring's own
    contact load, slips, camber and speed."""
    off, on = tyres
    u = _inputs(model, V, 0.04, 0.02)
    x = off.initial_state(u)
    phi = 0.3 / V  # a yaw rate of 0.3 rad/s at 10 m/s
    x[_S["phi"]] = phi
    y_off, y_on = off.outputs(x, u), on.outputs(x, u)
    ref = TURN_SLIP_REFERENCE / model.params.UNLOADED_RADIUS
    args = dict(fz=y_off[_O["fz_c"]], kappa=y_off[_O["kappa"]], alpha=y_off[_O["alpha"]], gamma=u.gamma,
                vx=max(abs(y_off[_O["vcx"]]), model.params.VXLOW), omega=x[_S["omb"]], turn_slip=True)
    with_spin, without = model.evaluate(phit=phi + ref, **args), model.evaluate(phit=ref, **args)
    for name, out in (("fx_c", "fx"), ("fy_c", "fy"), ("mz_c", "mz")):
        increment = float(getattr(with_spin, out) - getattr(without, out))
        assert y_on[_O[name]] - y_off[_O[name]] == pytest.approx(increment, rel=1e-9, abs=1e-9)
    assert abs(y_on[_O["fy_c"]] - y_off[_O["fy_c"]]) > 20.0  # and it matters: 55 N here


@pytest.mark.parametrize("vx", [V, -V])
def test_yaw_rate_drives_the_spin_in_the_direction_of_travel(model, tyres, vx):
    """phi relaxes towards psi_dot / V with V signed by the direction of travel: a left-turning patch (psi_dot > 0
    about z up) has positive spin forward, negative in reverse; and at 4 kN, where the file's turn-slip moment
    resists the yaw (dMz/dphit = -48 N m per 1/m), the contact moment opposes the yaw rate in both directions."""
    off, on = tyres
    u = _inputs(model, vx)
    x = on.initial_state(u)
    x[_S["wpsb"]] = 0.5
    assert np.sign(on.derivative(x, u)[_S["phi"]]) == np.sign(vx)
    x[_S["phi"]] = 0.5 / vx
    moment = on.outputs(x, u)[_O["mz_c"]] - off.outputs(x, u)[_O["mz_c"]]
    assert moment < -0.5  # -48 N m per 1/m x 0.05 1/m


@pytest.mark.parametrize("gamma", [0.03, -0.05])
def test_a_wheel_rolling_along_its_cone_needs_no_camber_thrust(model, tyres, gamma):
    """The sign of the spin (ISO-W, z up): a wheel leaning by gamma rolls freely along the circle of its cone,
    yawing at psi_dot = -(1 - eps_gamma) Omega sin(gamma) (leaning right, gamma > 0, it turns right); at the spin
    that yaw rate relaxes to, camber spin and turn spin cancel and the side force is that of the upright wheel (the
    MF's pure camber thrust, 3.6 kN per rad here, is gone to within 10 %). With the opposite sign (phit =
    -psi_dot/V, the last round's attempt) it doubles."""
    off, on = tyres
    u, upright = _inputs(model, V, 0.0, gamma), _inputs(model, V)
    x = off.initial_state(u)
    prm = model.params
    fz = off.outputs(x, u)[_O["fz_c"]]
    eps = prm.PECP1 * (1.0 + prm.PECP2 * (fz - prm.FNOMIN) / prm.FNOMIN)
    x[_S["wpsb"]] = -(1.0 - eps) * x[_S["omb"]] * math.sin(gamma)  # the belt yaws at the cone's rate
    settle = [_S["psr"], _S["phi"]]  # the patch settled at that yaw rate: its residual yaw and spin at rest
    for _ in range(6):  # Newton, finite-difference slopes
        r = on.derivative(x, u)[settle]
        jac = np.empty((2, 2))
        for k, i in enumerate(settle):
            xp = x.copy()
            xp[i] += 1e-7
            jac[:, k] = (on.derivative(xp, u)[settle] - r) / 1e-7
        x[settle] -= np.linalg.solve(jac, r)
    assert np.abs(on.derivative(x, u)[settle]).max() < 1e-6
    thrust = off.outputs(x, u)[_O["fy_c"]] - off.outputs(off.initial_state(upright), upright)[_O["fy_c"]]
    left = on.outputs(x, u)[_O["fy_c"]] - off.outputs(off.initial_state(upright), upright)[_O["fy_c"]]
    assert abs(thrust) > 50.0
    assert abs(left) < 0.1 * abs(thrust)


def _damped_files():
    """(name, path, loads [N], pressures [bar]): the sample file up to FZMAX at INFLPRES and PRESMAX (at 10 kN,
    2.55 bar its belt yaw grows without turn slip: tests/test_swift_modes.py); TNO to 2 FNOMIN (the turn-slip side
    force fed its 93 Hz camber mode at 0.5 m/s, 8 kN, +1.1 1/s, before it faded below VXLOW); MFeval 6.2 to 10 kN,
    below the load where its camber moment turns (11.2 kN)."""
    return [("sample", lambda: SAMPLE, (2000.0, 8000.0, 10000.0), (2.2, 2.55)),
            ("tno", lambda: require_shared(SHARED / "reference" / "tir" / "TNO_car205_60R15.tir"),
             (2000.0, 4000.0, 8000.0), (2.2,)),
            ("mfeval62", lambda: require_shared(MFEVAL_DIR / "MagicFormula62_Parameters.tir"),
             (3376.0, 6752.0, 10000.0), (2.0,))]


@pytest.mark.parametrize("name, path, loads, bars", _damped_files(), ids=[f[0] for f in _damped_files()])
def test_every_mode_damped_where_the_moment_resists_the_yaw(name, path, loads, bars):
    """Where the file's turn-slip moment resists the yaw (dMz/dphit < 0), the ring with turn slip keeps every mode
    damped, 0.5-70 m/s forward and reverse, free rim. Fails before the MF's trail took F'y at gamma = phi = 0 (the
    sample grew at +2.7 1/s, 8 kN, 15 m/s) and, on TNO, before the turn slip faded below VXLOW."""
    model = mftyre.load_tir(path())
    tyre = _tyre(model, True, rim="torque")
    speeds = [s * v for v in (0.5, 1.0, 2.0, 4.0, 7.0, 9.0, 15.0, 30.0, 70.0) for s in (1.0, -1.0)]
    worst = max(scan(tyre, speeds, loads, [b * 1e5 for b in bars]), key=lambda r: r.max_real)
    assert worst.max_real < 0.0, f"{name}: {worst.max_real:.3g} 1/s at {worst.vx} m/s, {worst.fz} N, {worst.p} Pa"


def test_warning_names_the_file_and_parameters_where_the_moment_drives_the_yaw(model):
    """MFeval's MF 6.2 file: its camber moment QDZ8 + QDZ9 dfz changes sign at 1.66 FNOMIN (11.2 kN), and with it the
    MF's turn-slip moment at zero slip: SwiftTyre(turn_slip=True) warns, naming the file, the loads and the QDZ
    parameters. The sample file's moment resists the yaw at every load up to 2 FNOMIN (until the trail multiplied
    F'y with the camber spin's side force in it, it pushed above ~6 kN): no warning, with or without turn slip."""
    path = require_shared(MFEVAL_DIR / "MagicFormula62_Parameters.tir")
    for tyre_model, expected in ((mftyre.load_tir(path), True), (model, False)):
        for turn_slip in (True, False):
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                SwiftTyre(tyre_model, Flat(), x_range=(0.0, 1.0), compiled=False, turn_slip=turn_slip)
            messages = [str(w.message) for w in caught if w.category is TurnSlipWarning]
            assert len(messages) == int(expected and turn_slip), (tyre_model.params.source, turn_slip, messages)
    message = turn_slip_warning(mftyre.load_tir(path))
    for part in ("MagicFormula62_Parameters.tir", "QDZ8 = -0.34545", "QDZ9 = 0.52144", "13504 N",
                 "swift.modes.scan"):
        assert part in message
    assert turn_slip_warning(model) is None


def test_the_fmu_wheel_takes_the_option(model):
    """swift.fmu_model.SwiftWheel (the native FMU's functions, ``mftyre fmu build --model swift --turn-slip``):
    steady cornering is unchanged; after a step of the lateral speed the belt yaws and the turn slip changes the
    transient side force, the wheel settling to the same steady state."""
    from mftyre.transient import free_rolling_start
    from swift.fmu_model import SwiftWheel

    omega, z = free_rolling_start(model, V)
    runs = []
    for turn_slip in (False, True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            wheel = SwiftWheel(model, turn_slip=turn_slip)
        assert wheel.functions.state_names == STATE_NAMES
        wheel.set_inputs(vx=V, omega=omega, z=z, vy=0.3)
        wheel.initialise()
        fy = [wheel.outputs()["Fy_c"]]
        wheel.set_inputs(vy=0.8)
        for _ in range(150):
            wheel.step(1e-3)
            fy.append(wheel.outputs()["Fy_c"])
        runs.append(np.array(fy))
    off, on = runs
    assert on[0] == pytest.approx(off[0], rel=1e-12)
    assert np.abs(on - off).max() > 1.0
    assert on[-1] == pytest.approx(off[-1], rel=2e-3)
