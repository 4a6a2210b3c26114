"""Steady cornering of the SWIFT tyre equals the Magic Formula at the rim's slip, through every path and at 1 ms and
5 ms steps: ``SwiftTyre.run`` (the compiled loop), ``SwiftTyre.step`` and :class:`swift.fmu_model.SwiftWheel` (the
native FMU's functions, evaluated by CasADi); the FMUs themselves in test_fmu_native.py / test_fmu_swift.py.

The rim moves sideways at vy; its lateral position was held over a step while the belt moved on, so the sidewall
was stretched by vy t within each step: an error of c_by vy h/2 that grew with the step (the FMU's Fy 10-21 % off
at 1 ms, the Python run 9-24 % at 1 ms and 43-119 % at 5 ms on the sample file). Reference: the MF at the ring's
contact load Fz_c, the slip angle atan(vy / vx) and the longitudinal slip omega R_e / vx - 1 of the imposed spin."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import mftyre
from swift import OUTPUT_NAMES, Flat, StepInputs, SwiftTyre

from conftest import TIR_FILES

V, T_END = 20.0, 0.4
CASES = [(1.0, 0.0), (4.0, 0.0), (10.0, 0.0), (4.0, 0.1), (4.0, -0.1)]


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")


@pytest.fixture(scope="module")
def tyre(model):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return SwiftTyre(model, Flat(), axle="height", rim="speed", x_range=(0.0, V * T_END + 2.0))


def _spin(model, kappa, fz=4300.0):
    re = float(model.evaluate(fz, kappa, 0.0, vx=V).re)
    for _ in range(3):
        re = float(model.evaluate(fz, kappa, 0.0, vx=V, omega=(1 + kappa) * V / re).re)
    return (1 + kappa) * V / re


def assert_magic_formula(model, fx, fy, fz_c, re, vy, omega, where=""):
    """Rim forces (fx, fy) against the MF at (fz_c, omega re / V - 1, atan(vy / V)): within 1 % of the larger."""
    ref = model.evaluate(fz_c, omega * re / V - 1.0, math.atan(vy / V), vx=V, omega=omega)
    scale = max(abs(float(ref.fx)), abs(float(ref.fy)))
    assert abs(fy - float(ref.fy)) < 0.01 * scale, f"Fy {fy:.1f} vs MF {float(ref.fy):.1f} {where}"
    assert abs(fx - float(ref.fx)) < 0.01 * scale, f"Fx {fx:.1f} vs MF {float(ref.fx):.1f} {where}"


@pytest.mark.parametrize("dt", [1e-3, 5e-3])
def test_run_and_step_cornering_equal_magic_formula(model, tyre, dt):
    rl, _ = model.loaded_radius(4000.0)
    for deg, kappa in CASES:
        vy = -V * math.tan(math.radians(deg))
        u = StepInputs(x=1.0, vx=V, vy=vy, z=float(rl), omega=_spin(model, kappa))
        res = tyre.run(T_END, u, dt)
        o = {n: res[n][-1] for n in ("fx", "fy", "fz_c", "re")}
        assert_magic_formula(model, o["fx"], o["fy"], o["fz_c"], o["re"], vy, u.omega, f"run {deg} deg {kappa}")
        if kappa == 0.0:  # the step API: the same C step, called per step from Python
            state = tyre.initial_state(u)
            for k in range(int(round(T_END / dt))):
                state, out = tyre.step(state, StepInputs(x=1.0 + V * k * dt, vx=V, vy=vy, y=vy * k * dt,
                                                         z=float(rl), omega=u.omega), dt)
            assert_magic_formula(model, out["fx"], out["fy"], out["fz_c"], out["re"], vy, u.omega,
                                 f"step {deg} deg")


@pytest.mark.parametrize("dt", [1e-3, 5e-3])
def test_fmu_functions_cornering_equal_magic_formula(model, dt):
    """The native FMU's CasADi functions (SwiftWheel; the rim's y is the frame origin at every step)."""
    from swift.fmu_model import SwiftWheel

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        wheel = SwiftWheel(model, "flat()")
    rl, _ = model.loaded_radius(4000.0)
    for deg, kappa in ((4.0, 0.0), (10.0, 0.1)):
        vy = -V * math.tan(math.radians(deg))
        omega = _spin(model, kappa)
        wheel.set_inputs(vx=V, vy=vy, z=float(rl), omega=omega)
        wheel.initialise()
        for _ in range(int(round(0.25 / dt))):
            wheel.step(dt)
        out = wheel.outputs()
        assert_magic_formula(model, out["Fx"], out["Fy"], out["Fz_c"], out["Re"], vy, omega, f"{deg} deg {kappa}")


@pytest.mark.parametrize("vx, torque", [(0.0, 2000.0), (0.0, -2000.0), (10.0, 2000.0)])
def test_initial_state_raises_without_equilibrium(model, vx, torque):
    """A drive/brake torque beyond what the tyre transmits at 4 kN (mu Fz R ~ 1.3 kN m) has no static state: a clear
    error naming the inputs (old: a 'state' with the axle 25.8 m above the road, or 165 m up at 2260 rad/s); a
    torque it can hold still gives the equilibrium."""
    from mftyre.errors import ModelInputError

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tyre = SwiftTyre(model, Flat(), axle="load", rim="torque", x_range=(0.0, 3.0))
    with pytest.raises(ModelInputError, match=r"no static equilibrium .*torque = -?2000"):
        tyre.initial_state(StepInputs(x=1.0, vx=vx, load=4000.0, torque=torque, omega=vx / 0.3))
    u = StepInputs(x=1.0, vx=vx, load=4000.0, torque=200.0, omega=vx / 0.3)
    state = tyre.initial_state(u)
    out = dict(zip(OUTPUT_NAMES, tyre.outputs(state, u)))
    assert out["fz"] == pytest.approx(4000.0, rel=1e-6)
    assert out["my"] == pytest.approx(-200.0, rel=1e-6)
