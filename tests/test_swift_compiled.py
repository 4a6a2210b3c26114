"""The compiled SWIFT paths (C step loop, ctypes step, compiled right-hand side) against the CasADi virtual machine
running the same CasADi functions, their errors, and their use from threads."""
from __future__ import annotations

import threading
import warnings
from dataclasses import replace

import numpy as np
import pytest

import mftyre
from mftyre.errors import ModelInputError
from swift import OUTPUT_NAMES, Cleat, StepInputs, SwiftTyre

from conftest import TIR_FILES

V = 40 / 3.6


@pytest.fixture(scope="module")
def setup():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the sample file's unmodelled parameters
        model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")
        road = Cleat(0.3, 0.05, 0.01)
        compiled = SwiftTyre(model, road, x_range=(0.0, 1.0))
        vm = SwiftTyre(model, road, x_range=(0.0, 1.0), compiled=False)
    rl, _ = model.loaded_radius(4000.0)
    return compiled, vm, StepInputs(x=0.0, vx=V, z=float(rl), omega=V / 0.3044)


def test_compiled_run_and_step_equal_the_casadi_vm_over_a_cleat(setup):
    compiled, vm, u = setup
    get = lambda t: replace(u, x=u.x + V * t, z=u.z + 0.002 * np.sin(60 * t))  # noqa: E731  (a moving axle)
    fast, slow = compiled.run(0.03, get), vm.run(0.03, get)  # the wheel reaches the cleat (x_c 0.3 m)
    assert np.ptp(slow["fz"]) > 300.0
    np.testing.assert_allclose(fast.states, slow.states, rtol=1e-9, atol=1e-9)
    for name in ("fx", "fz", "my"):
        np.testing.assert_allclose(fast[name], slow[name], rtol=1e-9, atol=1e-6)
    state, out = compiled.step(slow.states[10], get(0.01), 1e-3)  # step() = the step run() took
    np.testing.assert_allclose(state, slow.states[11], rtol=1e-9, atol=1e-9)
    assert list(out) == list(OUTPUT_NAMES)
    np.testing.assert_allclose(list(out.values()), [slow[n][11] for n in OUTPUT_NAMES], rtol=1e-9, atol=1e-6)


def test_compiled_initial_state_equals_the_vm_newton(setup):
    compiled, vm, u = setup
    for inputs in (u, replace(u, vx=0.0, omega=0.0), replace(u, vx=-8.0, omega=-8.0 / 0.3044, gamma=0.03)):
        np.testing.assert_allclose(compiled.initial_state(inputs), vm.initial_state(inputs), rtol=1e-9,
                                   atol=1e-9)


def test_leaving_the_road_table_in_the_c_loop_is_a_model_input_error(setup):
    compiled, _, u = setup
    with pytest.raises(ModelInputError, match="outside the road table"):
        compiled.run(0.2, replace(u, x=0.6))  # the table ends 0.512 m past x = 1.0
    with pytest.raises(ModelInputError, match="finite"):
        compiled.step(compiled.initial_state(u), replace(u, vx=float("nan")), 1e-3)


def test_one_tyre_stepped_from_threads_gives_the_sequential_results(setup):
    compiled, _, u = setup
    speeds = (V, 0.5 * V, 1.5 * V, 0.8 * V)

    def trajectory(vx):
        inputs = replace(u, vx=vx, omega=vx / 0.3044)
        s = compiled.initial_state(inputs)
        for k in range(60):
            s, _ = compiled.step(s, replace(inputs, x=vx * k * 1e-3), 1e-3)
        return s

    expected = [trajectory(vx) for vx in speeds]
    results = [None] * len(speeds)

    def work(i):
        results[i] = trajectory(speeds[i])

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(speeds))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for got, want in zip(results, expected):
        np.testing.assert_array_equal(got, want)
