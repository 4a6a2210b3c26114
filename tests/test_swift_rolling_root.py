"""The same rules for the SWIFT tyre's static start in every path: swift.SwiftTyre.initial_state,
swift.fmu_model.SwiftWheel (CasADi and compiled) and the native FMU (fmpy) refuse with the same text
* a speed beyond the input policy's limits (mftyre.inputs.check_limits, the text MFModel.evaluate raises): the
  agricultural file at 40 m/s (13 LONGVL), beyond 31.1 m/s where its QSY3/QSY4 terms make My = Fz0 R0;
* a root of the equilibrium equations that is no rolling tyre (rolling, |vx| >= VXLOW, with the slip outside
  KPUMIN..KPUMAX; :attr:`swift.simulate.SwiftTyre.rolling_root_function`): the same file at 20 m/s and FNOMIN with
  a drive torque of 80 kN m on a free rim (kappa 4.23);
* a start whose equilibrium equations keep a derivative above EQUILIBRIUM_TOL (swift.simulate.NO_EQUILIBRIUM): the
  same at 30 m/s with a brake torque of 20 kN m, beyond what the tyre holds (d(oma)/dt = -1.75e3 after 30 Newton
  steps).
At 20 m/s every path starts, whatever the spin it is given as a guess (a free rim starts at free rolling,
swift.simulate.free_rolling_spin): from 13.5 times free rolling (vx over the deflection; before, the iteration
stalled there at kappa -5e6 with d(kappa)/dt = 1.5e-4) the start is the same."""
from __future__ import annotations

import functools
import re
import shutil
import warnings

import numpy as np
import pytest

import mftyre
from mftyre.transient import free_rolling_start
from swift import Flat, StepInputs, SwiftTyre
from swift.fmu_model import SwiftWheel

from conftest import TIR_FILES

AGRI = TIR_FILES / "agri_460_85R34_mf61.tir"
#: The rules' part of the messages (after the inputs, which each path names in its own terms).
NO_EQUILIBRIUM = re.compile(r"no static equilibrium at the inputs \((.*)\): (after 30 Newton steps d\((\w+)\)/dt = "
                            r"(\S+) \(tolerance 1e-06\); e\.g\. a drive/brake torque .*)")
RULE = re.compile(r"no static equilibrium within the file's slip range at the inputs \((.*)\): (the equations' root "
                  r"has the slip kappa = .* no rolling tyre .*)")


@pytest.fixture(scope="module")
def agri():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(AGRI)


def _start(model, vx):
    """Axle height at the loaded radius under FNOMIN, and the spin vx/R0 (a free rim starts at free rolling)."""
    omega = vx / model.params.UNLOADED_RADIUS
    return float(model.loaded_radius(model.params.FNOMIN, omega=omega)[0]), omega


def _wrong_spin(model, vx):
    """vx over the deflection at FNOMIN (the spin this file's tests gave before: 13.5 times free rolling at 20 m/s,
    its rim speed 8 times the file's rim-speed limit)."""
    return vx / float(model.loaded_radius(model.params.FNOMIN, omega=vx / model.params.UNLOADED_RADIUS)[1])


@functools.cache
def _tyre(model, compiled):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return SwiftTyre(model, Flat(), axle="height", rim="torque", x_range=(0.0, 3.0), compiled=compiled)


@functools.cache
def _wheel(model, compiled):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return SwiftWheel(model, None, rim="torque", compiled=compiled)


def _tyre_result(model, vx, compiled, torque=0.0, omega=None):
    z, free = _start(model, vx)
    try:
        return _tyre(model, compiled).initial_state(StepInputs(x=0.0, vx=vx, z=z, omega=free if omega is None
                                                               else omega, torque=torque))
    except mftyre.ModelInputError as exc:
        return str(exc)


def _wheel_result(model, vx, compiled, torque=0.0, omega=None):
    z, free = _start(model, vx)
    wheel = _wheel(model, compiled)
    wheel.set_inputs(vx=vx, z=z, omega=free if omega is None else omega, torque=torque)
    try:
        wheel.initialise()
    except mftyre.ModelInputError as exc:
        return str(exc)
    return wheel.outputs()


@pytest.fixture(scope="module")
def agri_fmu(tmp_path_factory):
    if shutil.which("cc") is None:
        pytest.skip("no C compiler (cc) to build native FMUs")
    pytest.importorskip("fmpy")
    from test_fmu_native import _build

    path = tmp_path_factory.mktemp("agri") / "agri.fmu"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _build([AGRI, "-o", path, "--model", "swift", "--rim", "torque"]) == 0
    return path


def _fmu_result(path, model, vx, tmp_path, torque=0.0):
    from fmpy.fmi1 import FMICallException
    from test_fmu_native import Slave

    z, omega = _start(model, vx)
    s = Slave(path, tmp_path)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.set(vx=vx, z=z, omega=omega, torque=torque)
    try:
        s.fmu.exitInitializationMode()
    except FMICallException as exc:
        assert exc.status == 3  # fmi2Error, as for every failed initialisation
        errors = [msg for status, msg in s.messages if status == 3]
        s.fmu.freeInstance()
        assert len(errors) == 1 and errors[0].startswith("initialisation failed: "), s.messages
        return errors[0][len("initialisation failed: "):]
    outputs = s.get("Fz", "kappa")
    s.fmu.freeInstance()
    return outputs


def test_every_path_refuses_a_speed_beyond_the_input_policy_with_the_same_text(agri, agri_fmu, tmp_path):
    with pytest.raises(mftyre.ModelInputError) as policy:  # the one policy, as MFModel.evaluate applies it
        agri.evaluate(agri.params.FNOMIN, 0.0, 0.0, vx=40.0)
    results = {"SwiftTyre": _tyre_result(agri, 40.0, compiled=False),
               "SwiftTyre compiled": _tyre_result(agri, 40.0, compiled=True),
               "SwiftWheel": _wheel_result(agri, 40.0, compiled=False),
               "SwiftWheel compiled": _wheel_result(agri, 40.0, compiled=True),
               "native FMU": _fmu_result(agri_fmu, agri, 40.0, tmp_path)}
    assert set(results.values()) == {str(policy.value)}, results  # the same text, to the digit
    assert str(policy.value).startswith("input vx = 40 is beyond the limit of ") and \
        "|vx| <= 31.1078 m/s" in str(policy.value), policy.value


def test_a_fixed_rim_spin_beyond_the_rim_speed_limit_is_refused_as_evaluate_refuses_it(agri):
    """rim="speed": 20 m/s (inside the speed limit) with omega = 45 rad/s, rim speed 37 m/s beyond the file's 34.1."""
    with pytest.raises(mftyre.ModelInputError) as policy:
        agri.evaluate(agri.params.FNOMIN, 0.0, 0.0, vx=20.0, omega=45.0)
    z, _ = _start(agri, 20.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tyre = SwiftTyre(agri, Flat(), axle="height", rim="speed", x_range=(0.0, 3.0), compiled=False)
        wheel = SwiftWheel(agri, None, rim="speed")
    with pytest.raises(mftyre.ModelInputError) as by_tyre:
        tyre.initial_state(StepInputs(x=0.0, vx=20.0, z=z, omega=45.0))
    wheel.set_inputs(vx=20.0, z=z, omega=45.0)
    with pytest.raises(mftyre.ModelInputError) as by_wheel:
        wheel.initialise()
    assert str(by_tyre.value) == str(by_wheel.value) == str(policy.value)
    assert str(policy.value).startswith("input omega = 45 (rim speed 37.026 m/s) is beyond the limit"), policy.value


def test_every_path_refuses_a_root_that_is_no_rolling_tyre_with_the_same_text(agri, agri_fmu, tmp_path):
    results = {"SwiftTyre": _tyre_result(agri, 20.0, compiled=False, torque=80e3),
               "SwiftTyre compiled": _tyre_result(agri, 20.0, compiled=True, torque=80e3),
               "SwiftWheel": _wheel_result(agri, 20.0, compiled=False, torque=80e3),
               "SwiftWheel compiled": _wheel_result(agri, 20.0, compiled=True, torque=80e3),
               "native FMU": _fmu_result(agri_fmu, agri, 20.0, tmp_path, torque=80e3)}
    matches = {path: RULE.fullmatch(text) if isinstance(text, str) else None for path, text in results.items()}
    assert all(matches.values()), results
    rules = {m.group(2) for m in matches.values()}
    assert len(rules) == 1, rules  # the same text, to the digit
    rule = rules.pop()
    assert "kappa = 4.23 outside KPUMIN..KPUMAX = -1..1" in rule, rule
    for path, m in matches.items():
        assert "vx = 20" in m.group(1) and "torque = 80000" in m.group(1) and "p = 160000 Pa" in m.group(1), (path, m)


def test_every_path_refuses_a_start_without_equilibrium_with_the_same_text(agri, agri_fmu, tmp_path):
    results = {"SwiftTyre": _tyre_result(agri, 30.0, compiled=False, torque=-20e3),
               "SwiftWheel": _wheel_result(agri, 30.0, compiled=False, torque=-20e3),
               "SwiftWheel compiled": _wheel_result(agri, 30.0, compiled=True, torque=-20e3),
               "native FMU": _fmu_result(agri_fmu, agri, 30.0, tmp_path, torque=-20e3)}
    matches = {path: NO_EQUILIBRIUM.fullmatch(text) if isinstance(text, str) else None
               for path, text in results.items()}
    assert all(matches.values()), results
    assert {m.group(3) for m in matches.values()} == {"oma"}, results  # the rim's spin is not in balance
    residuals = [float(m.group(4)) for m in matches.values()]
    assert max(residuals) == pytest.approx(min(residuals), rel=0.02) and abs(residuals[0]) > 1e-4, residuals
    for path, m in matches.items():
        assert "vx = 30" in m.group(1) and "torque = -20000" in m.group(1), (path, m)


def test_every_path_starts_at_a_normal_speed(agri, agri_fmu, tmp_path):
    """20 m/s (the same start): every path initialises; the FMUs' contact force and slip agree; the start does not
    depend on the spin given as a guess."""
    state = _tyre_result(agri, 20.0, compiled=False)
    assert not isinstance(state, str), state
    wheel = _wheel_result(agri, 20.0, compiled=False)
    native = _fmu_result(agri_fmu, agri, 20.0, tmp_path)
    assert isinstance(wheel, dict) and not isinstance(native, str), (wheel, native)
    assert native["Fz"] == pytest.approx(wheel["Fz"], rel=1e-9) and abs(native["kappa"]) < 0.02
    assert wheel["Fz"] == pytest.approx(agri.params.FNOMIN, rel=0.1)
    wrong = _wrong_spin(agri, 20.0)
    assert wrong > 13 * free_rolling_start(agri, 20.0)[0]
    from_wrong = _tyre_result(agri, 20.0, compiled=False, omega=wrong)
    assert not isinstance(from_wrong, str), from_wrong
    np.testing.assert_allclose(from_wrong, state, rtol=1e-12, atol=1e-12)
    assert _wheel_result(agri, 20.0, compiled=False, omega=wrong) == pytest.approx(wheel, rel=1e-12, abs=1e-12)
