"""SWIFT at standstill (issue 13): the static equilibrium at vx = 0 through the one Newton step of initial_state and
the compiled/FMU equilibrium (old: QR on a singular Jacobian, "no static equilibrium found"), and a tyre parked on
a 5-20 % grade held for every step size an FMU master uses (old: 0.85-2.75 mm drift at dt = 5 ms)."""
from __future__ import annotations

import numpy as np
import pytest

import mftyre
from swift import Flat, Sampled, StepInputs, SwiftTyre
from swift.ring import STATE_NAMES

from conftest import TIR_FILES

S = {n: i for i, n in enumerate(STATE_NAMES)}
pytestmark = pytest.mark.filterwarnings("ignore:Q_BV", "ignore:road height range", "ignore:ELLIPS_NLENGTH")
GRADES = (0.05, 0.10, 0.15, 0.20)


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")


@pytest.fixture(scope="module")
def parked(model):
    """Tyres on constant grades (one compiled library: the road is not part of it), locked rim, 4 kN axle load."""
    return {g: SwiftTyre(model, Sampled([-10.0, 10.0], [-10.0 * g, 10.0 * g]), axle="load", rim="speed",
                         x_range=(0.0, 3.0)) for g in GRADES}


@pytest.mark.parametrize("dt", [1e-3, 3e-3, 5e-3])
@pytest.mark.parametrize("grade", GRADES)
def test_parked_on_a_grade_holds_for_any_step(parked, grade, dt):
    """10 s at rest from the static equilibrium, and from it with the patch disturbed (transient slips and patch
    deflections 1 % of their static values off, 0.1 mm belt offset): the belt moves less than 1 mm and the load
    stays put (old, dt = 5 ms: 0.85 / 2.07 / 2.75 mm drift at 5 / 10 / 15 %, Fz swinging 3812-4233 N)."""
    tyre = parked[grade]
    u = StepInputs(x=1.0, vx=0.0, load=4000.0, omega=0.0)
    res = tyre.run(10.0, u, dt=dt)
    assert res["beta"][-1] == pytest.approx(np.arctan(grade), abs=1e-3)
    assert np.ptp(res["xb"]) < 1e-3 and np.ptp(res["zb"]) < 1e-3 and np.ptp(res["yb"]) < 1e-3
    assert np.ptp(res["fz"]) < 1.0 and abs(res["fx"][0]) > 0.9 * 4000.0 * grade / np.hypot(1.0, grade)
    state = tyre.initial_state(u)
    start = state.copy()
    for name in ("kappa", "alpha", "ux", "uy"):
        state[S[name]] *= 1.01
    state[S["xb"]] += 1e-4
    xb = [state[S["xb"]]]
    for _ in range(int(round(10.0 / dt))):
        state, out = tyre.step(state, u, dt)
        xb.append(state[S["xb"]])
    assert np.all(np.isfinite(state))
    assert np.max(np.abs(np.array(xb) - start[S["xb"]])) < 1e-3
    assert abs(state[S["zb"]] - start[S["zb"]]) < 1e-4 and abs(out["fz"] - res["fz"][0]) < 10.0


def test_standstill_equilibrium_one_solve(model):
    """vx = 0, omega = 0, axle height imposed, flat road: initial_state and the code-generated equilibrium of the
    FMU (equilibrium_function) find the same static state, at rest (derivatives ~0); old: the latter NaN."""
    rl, _ = model.loaded_radius(4000.0)
    tyre = SwiftTyre(model, Flat(), x_range=(0.0, 3.0))
    for vx in (0.0, 1e-3):
        u = StepInputs(x=1.0, vx=vx, z=float(rl), omega=vx / 0.3044)
        state = tyre.initial_state(u)
        rest = np.delete(tyre.derivative(state, u), [S["xa"], S["xb"]])  # imposed axle travel, belt following
        assert np.max(np.abs(rest)) < 1e-8
        equilibrium = tyre.equilibrium_function(30)
        x0w, grid, hw, _ = tyre._rhs_args(state)
        generated = np.asarray(equilibrium(1.0, float(rl), 0.0, u.omega, tyre._u(u), x0w, grid, hw)).ravel()
        assert np.all(np.isfinite(generated))
        np.testing.assert_allclose(generated, state, rtol=0, atol=1e-8)
        assert tyre.outputs(generated, u)[2] == pytest.approx(tyre.outputs(state, u)[2], rel=1e-9)
