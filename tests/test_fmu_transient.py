"""The transient wheel tyre (mftyre.transient) the native FMU runs: relaxation, steady-state limit, low speed."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mftyre
from mftyre.transient import WheelTyre, default_tau_vlow

TIR61 = Path(__file__).resolve().parent.parent / "tir_files" / "car_205_60R15_mf61.tir"


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(TIR61)


def test_steady_state_equals_steady_model(model):
    steady, transient = WheelTyre(model, "steady"), WheelTyre(model, "transient")
    for tyre in (steady, transient):
        tyre.set_inputs(vx=25.0, omega=25.0 / 0.305 * 0.95, vy=0.6, gamma=0.02, z=0.285)
        tyre.initialise()
        for _ in range(2000):
            tyre.step(1e-3)
    a, b = steady.outputs(), transient.outputs()
    for k in ("Fx", "Fy", "Mz", "My", "Mx"):
        assert b[k] == pytest.approx(a[k], rel=1e-9, abs=1e-6), k


@pytest.mark.parametrize("spin", [0.0, 1.0, 0.9, -0.5, 1.1])  # omega Re / vx: locked, free, +-0.1 slip, spun fwd
def test_reversing_wheel_brakes_the_motion_and_mirrors_forwards(model, spin):
    """vx = -10 m/s: the steady and the transient wheel (in its steady state) give Fx with the sign of the ISO-W
    slip (omega Re - vx)/|vx| (locked: Fx > 0, against the motion), and exactly minus the force of the same wheel
    driven forwards with vx and omega mirrored: fore and aft mirrored, the same vy gives the same Fy, and the
    aligning moment turns round with the trail (Mz -> -Mz)."""
    out = {}
    for kind in ("steady", "transient"):
        for vx in (-10.0, 10.0):
            tyre = WheelTyre(model, kind, vertical="load")
            re = 0.3
            for _ in range(3):
                tyre.set_inputs(vx=vx, vy=0.4, omega=spin * vx / re, Fz_in=4000.0)
                tyre.initialise()
                re = tyre.outputs()["Re"]
            for _ in range(200 if kind == "transient" else 1):
                tyre.step(1e-2)
            out[kind, vx] = tyre.outputs()
    iso_kappa = 1.0 - spin
    for kind in ("steady", "transient"):
        back, fwd = out[kind, -10.0], out[kind, 10.0]
        assert back["Fx"] == pytest.approx(-fwd["Fx"], rel=1e-9, abs=1e-6), kind
        assert (back["Fy"], back["Mz_c"]) == pytest.approx((fwd["Fy"], -fwd["Mz_c"]), rel=1e-9, abs=1e-6), kind
        if spin == 1.0:
            assert abs(back["Fx"]) < 0.01 * 4000.0
        else:
            assert np.sign(back["Fx"]) == np.sign(iso_kappa) and abs(back["Fx"]) > 1000.0, kind
        assert back["Fx"] == pytest.approx(out["steady", -10.0]["Fx"], rel=1e-6, abs=1e-3), kind


def test_lateral_force_lags_by_the_relaxation_length(model):
    """A small step in vy at 20 m/s: the slip angle builds up as 1 - exp(-s / sigma_alpha) over the distance s
    travelled (Pacejka (7.12)), sigma_alpha the evaluator's sigmay at this load."""
    vx, vy = 20.0, 0.02
    tyre = WheelTyre(model, "transient")
    tyre.set_inputs(vx=vx, omega=vx / 0.305, z=0.29)
    tyre.initialise()
    tyre.set_inputs(vy=vy)
    fz = tyre.outputs()["Fz"]
    sigma = float(model.evaluate(fz, 0.0, 0.0, 0.0, 0.0, vx).sigmay)
    h = 1e-3
    for k in range(1, 101):
        tyre.step(h)
        s = vx * k * h
        expected = math.atan(vy / vx * (1.0 - math.exp(-s / sigma)))
        assert tyre.outputs()["alpha"] == pytest.approx(expected, rel=1e-9, abs=1e-12)


def test_step_size_does_not_change_the_result(model):
    """Exact integration of the deflections: 1 step of 50 ms = 50 steps of 1 ms (inputs held)."""
    runs = []
    for n in (1, 50):
        tyre = WheelTyre(model, "transient")
        tyre.set_inputs(vx=15.0, omega=15.0 / 0.305, z=0.29)
        tyre.initialise()
        tyre.set_inputs(vy=0.5, omega=15.0 / 0.305 * 0.9)
        for _ in range(n):
            tyre.step(0.05 / n)
        runs.append(tyre.state.copy())
    np.testing.assert_allclose(runs[0], runs[1], rtol=1e-12)


def _parked(model, slope, t_end=4.0, h=1e-3):
    """A quarter car (FNOMIN / g) with a locked wheel released on a slope at rest: x, v over time."""
    mass = model.params.FNOMIN / 9.81
    tyre = WheelTyre(model, "transient", vertical="load")
    tyre.set_inputs(vx=0.0, omega=0.0, Fz_in=model.params.FNOMIN * math.cos(slope))
    tyre.initialise()
    x = v = 0.0
    xs, vs = [], []
    for _ in range(int(t_end / h)):
        tyre.set_inputs(vx=v)
        tyre.step(h)
        fx = tyre.outputs()["Fx"]
        v += h * (-9.81 * math.sin(slope) + fx / mass)  # semi-implicit Euler
        x += h * v
        xs.append(x)
        vs.append(v)
    return np.array(xs), np.array(vs)


def test_parked_car_stands_on_a_slope_without_creep_or_oscillation(model):
    slope = math.atan(0.15)
    x, v = _parked(model, slope)
    n = len(x)
    # comes to rest on the tyre spring: a few mm down the slope, then no creep
    assert -0.02 < x[-1] < 0.0
    assert abs(x[-1] - x[n // 2]) < 1e-6  # no creep over the last 2 s
    assert np.max(np.abs(v[n // 2:])) < 1e-6
    # no oscillation: the velocity changes sign at most once, the overshoot is small
    signs = np.sign(v[np.abs(v) > 1e-5])
    assert np.count_nonzero(np.diff(signs)) <= 1
    assert np.min(x) > 1.1 * x[-1]


def test_start_from_standstill_without_jerk(model):
    """Driving away: spin ramped from 0, the car accelerates; the force follows without oscillation."""
    mass = model.params.FNOMIN / 9.81
    tyre = WheelTyre(model, "transient", vertical="load")
    tyre.set_inputs(vx=0.0, omega=0.0, Fz_in=model.params.FNOMIN)
    tyre.initialise()
    v, h, fx = 0.0, 1e-3, []
    for k in range(3000):
        tyre.set_inputs(vx=v, omega=2.0 * k * h / 0.305 * 1.05)
        tyre.step(h)
        fx.append(tyre.outputs()["Fx"])
        v += h * fx[-1] / mass
    fx = np.array(fx)
    assert v == pytest.approx(2.0 * 3.0 / 1.05, rel=0.1)  # follows the wheel with a few % slip
    assert np.all(fx > 0)
    final = fx[-1]
    assert np.max(fx) < 1.15 * final  # a small overshoot while the deflection builds up
    assert np.max(np.abs(fx[500:] - final)) < 0.005 * final  # then no ringing


def test_default_low_speed_damping_and_bad_inputs(model):
    tau = default_tau_vlow(model)
    assert 0.01 < tau < 0.2
    tyre = WheelTyre(model, "transient")
    with pytest.raises(mftyre.errors.ModelInputError):
        tyre.set_inputs(vx=float("nan"))
    with pytest.raises(mftyre.errors.ModelInputError):
        tyre.step(0.0)
    with pytest.raises(mftyre.errors.ModelInputError):
        tyre.set_inputs(speed=1.0)
