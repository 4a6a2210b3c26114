"""The native FMI 2.0 co-simulation FMU (`mftyre fmu build`, default backend): steady, transient and SWIFT tyres
as compiled C, checked through fmpy, a C host of our own, and against the Python implementations."""
from __future__ import annotations

import argparse
import math
import shutil
import subprocess
import tempfile
import warnings
import zipfile
from ctypes import byref
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")

import mftyre  # noqa: E402
from mftyre.fmu_command import register  # noqa: E402
from mftyre.transient import WheelTyre  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TIR61 = ROOT / "tir_files" / "car_205_60R15_mf61.tir"
TIR62 = ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir"
CLEAT = "cleat(x0=3.0, length=0.05, height=0.01)"
RE0 = 0.305
pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) to build native FMUs")


def _build(args):
    parser = argparse.ArgumentParser(prog="mftyre")
    register(parser.add_subparsers(dest="command"))
    ns = parser.parse_args(["fmu", "build", *map(str, args)])
    return ns.func(ns)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    out = tmp_path_factory.mktemp("native")
    paths = {m: out / f"{m}.fmu" for m in ("steady", "transient", "swift")}
    assert _build([TIR61, "-o", paths["steady"]]) == 0
    assert _build([TIR61, "-o", paths["transient"], "--model", "transient"]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _build([TIR62, "-o", paths["swift"], "--model", "swift", "--road", CLEAT]) == 0
    return paths


@pytest.fixture(scope="module")
def models():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {"61": mftyre.load_tir(TIR61), "62": mftyre.load_tir(TIR62)}


@pytest.fixture(scope="module")
def swift_wheel(models):
    from swift.fmu_model import SwiftWheel

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return SwiftWheel(models["62"], CLEAT)


def _callbacks(messages: list):
    """fmpy callbacks whose logger appends (status, message) to ``messages``; the caller keeps them alive. fmpy's
    logger proxy holds a pointer to the last Python logger registered, so an instance must not log through fmpy's
    default callbacks once another instance's logger may have been freed."""
    from fmpy.fmi1 import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)
    from fmpy.logging import addLoggerProxy

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(lambda env, inst, status, category, msg: messages.append((status,
                                                                                                  msg.decode())))
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    addLoggerProxy(byref(cb))
    return cb


class Slave:
    """One FMU instance driven call by call through fmpy, its log messages collected."""

    def __init__(self, path, tmp_path, name="tyre"):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        self.unzipped = extract(path, unzipdir=tempfile.mkdtemp(prefix=f"unz_{name}_", dir=tmp_path))
        self.messages = []
        self._cb = cb = _callbacks(self.messages)
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipped,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate(callbacks=cb, loggingOn=True)
        self.t = 0.0

    def initialise(self, **start):
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.set(**start)
        self.fmu.exitInitializationMode()
        return self

    def set(self, **values):
        if values:
            self.fmu.setReal([self.vr[k] for k in values], [float(v) for v in values.values()])

    def get(self, *names):
        names = names or self.outputs
        return dict(zip(names, self.fmu.getReal([self.vr[n] for n in names])))

    def step(self, h=1e-3):
        self.fmu.doStep(self.t, h)
        self.t += h

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def _swift_start(x_start):
    return dict(vx=10.0, omega=10.0 / RE0, z=0.29, x_start=x_start)


# ---------------------------------------------------------------------------------------------- description
def test_validate_and_describe(fmus):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    for kind, path in fmus.items():
        assert validate_fmu(str(path)) == [], kind
        md = read_model_description(path)
        cs = md.coSimulation
        assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
        assert cs.providesDirectionalDerivative == (kind != "swift")
        names = {v.name: v for v in md.modelVariables}
        assert names["Fx"].unit == "N" and names["vx"].unit == "m/s" and "ISO-W" in names["Fx"].description
        with zipfile.ZipFile(path) as zf:
            files = zf.namelist()
        assert f"binaries/linux64/mftyre_{kind}.so" in files
        assert {"sources/buildDescription.xml", "sources/fmi2_tyre.c", "sources/tyre_model.c", "sources/tyre_start.c"} <= set(files)
        assert not any(f.endswith(".py") for f in files)  # no Python at run time
        deps = {u.variable.name: {d.name for d in (u.dependencies or [])} for u in md.outputs}
        if kind == "swift":  # belt forces through the sidewall: rim speed inputs act directly, the height not
            assert "vx" in deps["Fx"] and "z" not in deps["Fz"] and deps["x_road"] == set()
            # the road acts on the contact at once (Fy on the rim only through the sidewall), on the rim through
            # bottoming
            assert {"road_z", "road_camber"} <= deps["Fy_c"] and "road_camber" not in deps["Fy"]
            assert "road_z" in deps["Fz"] and "road_z" in deps["road_w"]
            assert names["road_curvature"].unit == "1/m" and "road datum" in names["road_z"].description
        else:
            assert {"z", "road_z", "p"} <= deps["Fz"] and "vy" not in deps["Fz"]
            assert "vy" in deps["Fy"]  # transient: through the low-speed damping of the deflection
            assert deps["u_y"] == set()  # transient: a state, no direct dependency


def test_fmpy_simulate_each_model(fmus):
    starts = {"steady": dict(vx=20.0, omega=20.0 / RE0, vy=0.3), "transient": dict(vx=20.0, omega=20.0 / RE0, vy=0.3),
              "swift": _swift_start(2.0)}
    for kind, path in fmus.items():
        res = fmpy.simulate_fmu(str(path), stop_time=0.2, output_interval=1e-3, start_values=starts[kind])
        assert len(res) == 201
        for name in ("Fx", "Fy", "Fz", "My"):
            assert np.all(np.isfinite(res[name])), (kind, name)
        assert 2000 < res["Fz"][-1] < 8000


# ----------------------------------------------------------------------------------------- Python = native
def _braking(t):
    vx = 30.0 - 6.0 * t
    return dict(vx=vx, omega=vx * (1.0 - 0.15 * min(t / 0.3, 1.0)) / RE0, vy=0.0, z=0.29)


def _to_standstill(t):  # through VXLOW (low-speed damping, slip sign at rest) to rest
    vx = max(3.0 - 4.0 * t, 0.0)
    return dict(vx=vx, omega=0.9 * vx / RE0, vy=0.05 * math.sin(8.0 * t), z=0.29)


def _slalom(t):
    return dict(vx=20.0, omega=20.0 / RE0, vy=1.5 * math.sin(2 * math.pi * 1.5 * t), gamma=0.02 * math.sin(
        2 * math.pi * 1.5 * t), z=0.29 + 0.005 * math.sin(2 * math.pi * 3 * t))


#: Floors of the 1e-9 relative comparison, by unit: FNOMIN-sized forces, FNOMIN R0 moments, R0 lengths (1/R0
#: curvatures), 30 m/s speeds (slip speeds) and their spin.
SCALE = {"N": 4000.0, "N.m": 4000.0 * 0.3, "m": 0.3, "rad": 1.0, "1": 1.0, "1/m": 1.0 / 0.3, "m/s": 30.0,
         "rad/s": 30.0 / 0.3}


def _assert_close(py, nat, units, where):
    for k, v in py.items():
        floor = 1e-9 * SCALE[units[k]]
        assert abs(nat[k] - v) <= 1e-9 * abs(v) + floor, f"{where}: {k} native {nat[k]!r} python {v!r}"


@pytest.mark.parametrize("kind", ["steady", "transient"])
@pytest.mark.parametrize("scenario", [_braking, _slalom, _to_standstill])
def test_native_equals_python_wheel(fmus, models, tmp_path, kind, scenario):
    nat = Slave(fmus[kind], tmp_path).initialise(**scenario(0.0))
    units = {v.name: v.unit or "1" for v in nat.md.modelVariables}
    py = WheelTyre(models["61"], kind)
    py.set_inputs(**scenario(0.0))
    py.initialise()
    _assert_close(py.outputs(), nat.get(), units, "t=0")
    for k in range(1, 1001):
        u = scenario(k * 1e-3)
        nat.set(**u)
        nat.step()
        py.set_inputs(**u)
        py.step(1e-3)
        if k % 50 == 0:
            _assert_close(py.outputs(), nat.get(), units, f"step {k}")
    nat.close()


@pytest.mark.parametrize("before", [0.5, 5.0])
def test_native_equals_python_swift_cleat(fmus, swift_wheel, tmp_path, before):
    start = _swift_start(3.0 - before)
    nat = Slave(fmus["swift"], tmp_path).initialise(**start)
    units = {v.name: v.unit or "1" for v in nat.md.modelVariables}
    f = swift_wheel.functions
    swift_wheel.set_inputs(**dict(zip(f.input_names, f.input_starts)))  # the fixture is shared: start values
    swift_wheel.set_inputs(**{k: v for k, v in start.items() if k != "x_start"})
    swift_wheel.set_parameters(x_start=start["x_start"])
    swift_wheel.initialise()
    n = int(round((before + 0.3) / 10.0 / 1e-3))
    fz_nat = []
    for k in range(1, n + 1):
        nat.step()
        swift_wheel.step(1e-3)
        out = nat.get()
        fz_nat.append(out["Fz"])
        if k % 25 == 0 or k == n:
            _assert_close(swift_wheel.outputs(), out, units, f"step {k}")
    # the cleat is met where it is: the load peaks while the tandem cams ride over it (the front cam climbs the
    # cleat up to 0.11 m before the wheel centre reaches it: reach = cam half-length + half the tandem base)
    t_peak = (int(np.argmax(fz_nat)) + 1) * 1e-3
    assert before / 10.0 - 0.015 < t_peak < before / 10.0 + 0.015
    assert max(fz_nat) > fz_nat[0] + 1000.0
    nat.close()


def _on_moving_road(scenario):  # the vehicle simulator's road under the wheel: height offset and camber
    def inputs(t):
        return dict(scenario(t), road_z=0.004 * math.sin(2 * math.pi * 2 * t), road_camber=0.03 * math.sin(5 * t))
    return inputs


@pytest.mark.parametrize("scenario", [_braking, _slalom, _to_standstill])
def test_native_equals_python_swift(fmus, swift_wheel, tmp_path, scenario):
    """Braking (over the cleat at 30 m/s), slalom and slowing to rest, with road height and camber inputs: native =
    Python twin."""
    inputs = _on_moving_road(scenario)
    nat = Slave(fmus["swift"], tmp_path).initialise(x_start=0.0, **inputs(0.0))
    units = {v.name: v.unit or "1" for v in nat.md.modelVariables}
    f = swift_wheel.functions
    swift_wheel.set_inputs(**dict(zip(f.input_names, f.input_starts)))  # the fixture is shared: start values
    swift_wheel.set_inputs(**inputs(0.0))
    swift_wheel.set_parameters(x_start=0.0)
    swift_wheel.initialise()
    _assert_close(swift_wheel.outputs(), nat.get(), units, "t=0")
    for k in range(1, 401):
        u = inputs(k * 1e-3)
        nat.set(**u)
        nat.step()
        swift_wheel.set_inputs(**u)
        swift_wheel.step(1e-3)
        if k % 40 == 0:
            _assert_close(swift_wheel.outputs(), nat.get(), units, f"step {k}")
    nat.close()


def test_native_swift_starts_at_standstill(fmus, models, swift_wheel):
    """vx = 0, omega = 0 (old: "no static equilibrium found" from the FMU, CasADi "Evaluation failed" from
    SwiftWheel: the equilibrium's QR solve met the Jacobian that is singular at standstill): the native FMU and its
    Python twin start from swift.SwiftTyre.initial_state's static state, Fz is the contact load plus the belt's
    weight and nothing moves over 1 s (5 ms communication steps)."""
    from swift import CamTable, StepInputs, SwiftTyre
    from swift.ring import OUTPUT_NAMES, RingConstants

    z, x0 = 0.29, 2.3  # on the flat before the cleat, within the wheel's cam table
    res = fmpy.simulate_fmu(str(fmus["swift"]), stop_time=1.0, output_interval=5e-3,
                            start_values=dict(vx=0.0, omega=0.0, z=z, x_start=x0))
    f = swift_wheel.functions
    table = CamTable(f.table_x0, f.table_dx, f.table_h[0::2], f.table_h[1::2])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = SwiftTyre(models["62"], table, substeps=1)
    u = StepInputs(x=x0, vx=0.0, z=z, omega=0.0)
    out = dict(zip(OUTPUT_NAMES, ref.outputs(ref.initial_state(u), u)))
    prm = models["62"].params
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        belt_weight = RingConstants.from_model(models["62"], 30.0, 0.3).mb * prm.GRAVITY
    # Fx: the undetermined slip/deflection of standstill stays at its start up to the frozen-Jacobian steps of
    # initial_state (1.5e-5 N apart)
    assert res["Fz"][0] == pytest.approx(out["fz"], rel=1e-9) and res["Fx"][0] == pytest.approx(out["fx"], abs=1e-4)
    assert res["Fz"][0] == pytest.approx(res["Fz_c"][0] + belt_weight, rel=1e-12)
    assert res["Fz"][0] > 0.8 * float(models["62"].vertical_force(z))  # loaded, near the static relation
    assert np.ptp(res["Fz"]) < 1e-6 and np.ptp(res["Fx"]) < 1e-6 and np.ptp(res["x_road"]) == 0.0
    swift_wheel.set_inputs(**dict(zip(f.input_names, f.input_starts)))  # the fixture is shared: start values
    swift_wheel.set_inputs(vx=0.0, omega=0.0, z=z)
    swift_wheel.set_parameters(x_start=x0)
    swift_wheel.initialise()
    for _ in range(20):
        swift_wheel.step(5e-3)
    twin = swift_wheel.outputs()
    for name in ("Fx", "Fy", "Fz", "My", "Mz"):
        assert twin[name] == pytest.approx(res[name][20], rel=1e-9, abs=1e-9), name


def test_native_swift_rk4_step_never_above_the_stable_limit(fmus, swift_wheel):
    """max_step above swift.simulate.MAX_RK4_STEP (1 ms) still steps RK4 at <= 1 ms: a 5 ms max_step gives the
    1 ms run exactly (old: RK4 steps of 5 ms, at which a parked tyre on a 5-15 % grade drifts by millimetres), in
    the native FMU and in its Python twin alike."""
    from swift.simulate import MAX_RK4_STEP

    runs = {m: fmpy.simulate_fmu(str(fmus["swift"]), stop_time=0.3, output_interval=5e-3,
                                 start_values=dict(vx=10.0, omega=10.0 / 0.3, x_start=2.3, max_step=m))
            for m in (MAX_RK4_STEP, 5 * MAX_RK4_STEP)}
    for name in ("Fx", "Fz", "My"):
        np.testing.assert_array_equal(runs[MAX_RK4_STEP][name], runs[5 * MAX_RK4_STEP][name], err_msg=name)
    f = swift_wheel.functions
    twins = {}
    for m in (MAX_RK4_STEP, 5 * MAX_RK4_STEP):
        swift_wheel.set_inputs(**dict(zip(f.input_names, f.input_starts)))  # the fixture is shared: start values
        swift_wheel.set_inputs(vx=10.0, omega=10.0 / 0.3)
        swift_wheel.set_parameters(x_start=2.3, max_step=m)
        swift_wheel.initialise()
        for _ in range(20):
            swift_wheel.step(5e-3)
        twins[m] = swift_wheel.outputs()
    swift_wheel.set_parameters(max_step=MAX_RK4_STEP)
    for name in ("Fx", "Fz"):
        assert twins[5 * MAX_RK4_STEP][name] == twins[MAX_RK4_STEP][name], name
        assert twins[MAX_RK4_STEP][name] == pytest.approx(runs[MAX_RK4_STEP][name][20], rel=1e-9, abs=1e-9), name


def test_native_swift_road_inputs_equal_swift_tyre(fmus, models, swift_wheel, tmp_path):
    """road_z and road_camber mean what modelDescription says: the FMU = swift.SwiftTyre.step on the same cam table
    with the axle height taken above the lifted road (z - road_z) and the ring's road_camber input."""
    from swift import CamTable, StepInputs, SwiftTyre
    from swift.ring import OUTPUT_NAMES, STATE_NAMES

    f = swift_wheel.functions
    table = CamTable(f.table_x0, f.table_dx, f.table_h[0::2], f.table_h[1::2])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = SwiftTyre(models["62"], table, substeps=1, compiled=False)
    vx, vy, z, road_z, camber, x0 = 10.0, 0.2, 0.30, 0.012, 0.05, 2.5
    nat = Slave(fmus["swift"], tmp_path).initialise(vx=vx, vy=vy, omega=vx / RE0, z=z, road_z=road_z,
                                                    road_camber=camber, x_start=x0)
    units = {v.name: v.unit or "1" for v in nat.md.modelVariables}

    def u(t):
        return StepInputs(x=x0 + vx * t, vx=vx, z=z - road_z, omega=vx / RE0, y=vy * t, vy=vy,
                          road_camber=camber)

    state = ref.initial_state(u(0.0))  # the FMU's equilibrium (equilibrium_function) = initial_state
    out = dict(zip(OUTPUT_NAMES, ref.outputs(state, u(0.0))))
    _assert_close({"Fx": out["fx"], "Fy": out["fy"], "Fz": out["fz"], "My": out["my"], "Mz": out["mz"],
                   "x_contact": out["x_c"]}, nat.get(), units, "t=0")
    fz = []
    for k in range(1, 101):
        state, _ = ref.step(state, u((k - 1) * 1e-3), 1e-3)
        nat.step()
        got = nat.get()
        fz.append(got["Fz"])
        if k % 20 == 0:  # the outputs at the end of the step: the rim moved on to y = vy t
            out = dict(zip(OUTPUT_NAMES, ref.outputs(state, u(k * 1e-3))))
            expect = {"Fx": out["fx"], "Fy": out["fy"], "Fz": out["fz"], "Mz": out["mz"], "road_w": out["w"] + road_z,
                      "road_camber_eff": out["beta_x"], "x_contact": out["x_c"],
                      "road_curvature": out["curvature"], "x_road": state[STATE_NAMES.index("xa")]}
            _assert_close(expect, got, units, f"step {k}")
    assert got["road_camber_eff"] == pytest.approx(camber, abs=1e-12)
    assert abs(got["Fy"]) > 100.0 and max(fz) > fz[0] + 1000.0  # the camber pushes sideways; the cleat was felt
    nat.close()


def test_swift_meets_cleat_where_it_is_for_any_start(fmus):
    """x_start 0, -2.6 and 1.0 m at 10 m/s: the hits are (3.0 - x_start)/10 s apart, x_road agrees."""
    peaks, where = [], []
    for xs in (0.0, -2.6, 1.0):
        res = fmpy.simulate_fmu(str(fmus["swift"]), stop_time=0.7, output_interval=1e-3,
                                start_values=_swift_start(xs))
        i = int(np.argmax(res["Fz"]))
        peaks.append(res["time"][i])
        where.append(res["x_road"][i])
        assert res["x_road"][0] == pytest.approx(xs, abs=1e-12)
    assert peaks[1] - peaks[0] == pytest.approx(0.26, abs=1.5e-3)
    assert peaks[0] - peaks[2] == pytest.approx(0.10, abs=1.5e-3)
    assert np.ptp(where) < 0.015 and 2.85 < where[0] < 3.15  # within the tandem's reach of the cleat [3, 3.05]


# ------------------------------------------------------------------------------------------------ state
@pytest.mark.parametrize("kind", ["steady", "transient", "swift"])
def test_replay_after_restore_and_serialise(fmus, tmp_path, kind):
    start = _swift_start(2.5) if kind == "swift" else _slalom(0.0)
    a = Slave(fmus[kind], tmp_path, "a").initialise(**start)
    inputs = (lambda t: dict(vx=10.0 + t, vy=0.2 * math.sin(20 * t))) if kind == "swift" else _slalom
    for k in range(50):
        a.set(**inputs(k * 1e-3))
        a.step()
    state = a.fmu.getFMUstate()
    blob = a.fmu.serializeFMUstate(state)
    t0, first = a.t, []
    for k in range(50, 150):
        a.set(**inputs(k * 1e-3))
        a.step()
        first.append(a.get())
    a.fmu.setFMUstate(state)
    a.t = t0
    for k in range(50, 150):
        a.set(**inputs(k * 1e-3))
        a.step()
        assert a.get() == first[k - 50]  # bit for bit
    # a second instance restored from the serialised bytes continues the same way
    b = Slave(fmus[kind], tmp_path, "b").initialise(**start)
    restored = b.fmu.deSerializeFMUstate(blob)
    b.fmu.setFMUstate(restored)
    b.t = t0
    for k in range(50, 150):
        b.set(**inputs(k * 1e-3))
        b.step()
    for name, v in first[-1].items():
        assert abs(b.get(name)[name] - v) <= 1e-12 * max(1.0, abs(v))
    a.fmu.freeFMUstate(state)
    b.fmu.freeFMUstate(restored)
    a.close()
    b.close()


# ------------------------------------------------------------------------------------------------ errors
@pytest.mark.parametrize("kind,start,text", [
    ("steady", dict(p=-1.0), "input p"),
    ("transient", dict(tau_vlow=float("nan")), "parameter tau_vlow"),
    ("transient", dict(tau_vlow=-0.1), "tau_vlow must be >= 0"),
    ("swift", dict(max_step=0.0), "max_step"),
    ("swift", dict(z=float("inf")), "input z"),
])
def test_failed_initialisation_is_an_error(fmus, tmp_path, kind, start, text):
    from fmpy.fmi1 import FMICallException

    s = Slave(fmus[kind], tmp_path)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.set(**start)
    with pytest.raises(FMICallException) as exc:
        s.fmu.exitInitializationMode()
    assert exc.value.status == 3  # fmi2Error
    assert any(status == 3 and text in msg for status, msg in s.messages), s.messages
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.0, 1e-3)  # the instance stays in the error state
    s.fmu.reset()  # and can be reset and used again
    s.initialise()
    s.step()
    s.fmu.freeInstance()


def test_swift_pressure_with_a_negative_sidewall_factor_is_an_error(tmp_path):
    """An explicit SWIFT_PSTIFF = 1.5 (legal over 0.5-1.5 NOMPRES) at p = 0.3 NOMPRES makes f_c = 1 + SWIFT_PSTIFF
    dpi = -0.05: the native FMU refuses it with fmi2Error naming the parameter (glue_validate, as
    swift.ring.check_pressure in Python) instead of simulating a ring with negative stiffness."""
    from fmpy.fmi1 import FMICallException

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(TIR62).with_params(SWIFT_PSTIFF=1.5)
        mftyre.write_tir(model.params, tmp_path / "stiff.tir")
        assert _build([tmp_path / "stiff.tir", "-o", tmp_path / "s.fmu", "--model", "swift"]) == 0
    s = Slave(tmp_path / "s.fmu", tmp_path)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.set(p=0.3 * model.params.NOMPRES)
    with pytest.raises(FMICallException):
        s.fmu.exitInitializationMode()
    assert any(status == 3 and "SWIFT_PSTIFF dpi = -0.05 <= 0" in msg for status, msg in s.messages), s.messages
    s.fmu.reset()
    s.initialise()  # at the file's pressure it runs
    s.step()
    s.fmu.freeInstance()


def test_wrong_guid_is_refused(fmus, tmp_path):
    """fmi2Instantiate with another GUID returns NULL and logs the cause (through the test's own logger, see
    :func:`_callbacks`)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    messages = []
    cb = _callbacks(messages)
    md = read_model_description(fmus["steady"])
    fmu = FMU2Slave(guid="{00000000-0000-0000-0000-000000000000}", unzipDirectory=extract(
        fmus["steady"], unzipdir=str(tmp_path / "g")), modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="x")
    with pytest.raises(Exception):
        fmu.instantiate(callbacks=cb)
    assert any("GUID {00000000-0000-0000-0000-000000000000} does not match" in m for _, m in messages), messages


@pytest.mark.parametrize("kind", ["steady", "transient", "swift"])
def test_bad_steps_and_inputs_are_discarded_with_outputs_held(fmus, tmp_path, kind):
    from fmpy.fmi1 import FMICallException

    s = Slave(fmus[kind], tmp_path).initialise(**(_swift_start(0.0) if kind == "swift" else {}))
    s.step()
    held = s.get()
    for h in (0.0, -1e-3, float("nan"), float("inf")):
        with pytest.raises(FMICallException) as exc:
            s.fmu.doStep(s.t, h)
        assert exc.value.status == 2  # fmi2Discard
        assert s.get() == held
    assert any("step size" in m for _, m in s.messages)
    s.set(vx=float("nan"))
    with pytest.raises(FMICallException) as exc:
        s.fmu.doStep(s.t, 1e-3)
    assert exc.value.status == 2 and any("input vx is not finite" in m for _, m in s.messages)
    s.set(vx=10.0)
    s.step()  # recovers with valid inputs
    assert all(math.isfinite(v) for v in s.get().values())
    s.close()


def test_directional_derivatives_equal_finite_differences(fmus, tmp_path):
    for kind in ("steady", "transient"):
        s = Slave(fmus[kind], tmp_path).initialise(vx=15.0, omega=15.0 / RE0 * 1.03, vy=0.4, z=0.288)
        s.step()
        outs = ["Fx", "Fy", "Fz", "Mz", "My"]
        for name, dv in (("vx", 1e-4), ("vy", 1e-5), ("z", 1e-7), ("omega", 1e-4)):
            vr_out = [s.vr[o] for o in outs]
            dd = s.fmu.getDirectionalDerivative(vr_out, [s.vr[name]], [1.0])
            base = s.get(name)[name]
            s.set(**{name: base + dv})
            up = s.fmu.getReal(vr_out)
            s.set(**{name: base - dv})
            down = s.fmu.getReal(vr_out)
            s.set(**{name: base})
            for o, d, a, b in zip(outs, dd, up, down):
                fd = (a - b) / (2 * dv)
                assert d == pytest.approx(fd, rel=1e-4, abs=1e-3 * 4000 / (1 if name != "z" else 1e-3)), (kind, o, name)
        s.close()



def test_a_directional_derivative_at_a_nan_input_is_discarded_like_the_step(fmus, tmp_path):
    """After a NaN input fmi2DoStep returns Discard, but fmi2GetDirectionalDerivative returned fmi2OK with NaN
    derivatives (issue 34): now it is Discard too, naming the input, a non-finite seed is an error, and valid
    inputs give finite derivatives again."""
    from fmpy.fmi1 import FMICallException

    for kind in ("steady", "transient"):
        s = Slave(fmus[kind], tmp_path).initialise(vx=15.0, omega=15.0 / RE0, z=0.288)
        s.step()
        outs = [s.vr[o] for o in ("Fx", "Fy", "Fz", "Mz")]
        s.set(vx=float("nan"))
        with pytest.raises(FMICallException) as exc:
            s.fmu.getDirectionalDerivative(outs, [s.vr["vx"]], [1.0])
        assert exc.value.status == 2, kind  # fmi2Discard
        assert any("fmi2GetDirectionalDerivative: input vx is not finite" in m for _, m in s.messages), kind
        s.set(vx=15.0)
        with pytest.raises(FMICallException) as exc:
            s.fmu.getDirectionalDerivative(outs, [s.vr["vx"]], [float("nan")])
        assert exc.value.status == 3, kind  # fmi2Error: the seed is the caller's mistake
        assert all(math.isfinite(v) for v in s.fmu.getDirectionalDerivative(outs, [s.vr["vx"]], [1.0])), kind
        s.close()

# ------------------------------------------------------------------------------------------ C host, sources
C_HOST = r"""
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String f, ...) {
    (void)e; (void)n; (void)s; (void)c; (void)f;
}

#define N 4
#define STEPS 10000
/* argv: per model: library guid vr_vx vr_omega vr_Fx vr_Fz vr_vy */
static int run_model(char **a) {
    void *lib = dlopen(a[0], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { printf("dlopen %s\n", dlerror()); return 1; }
#define SYM(name) name##TYPE *name = (name##TYPE *)dlsym(lib, #name); if (!name) return 2;
    SYM(fmi2Instantiate) SYM(fmi2SetupExperiment) SYM(fmi2EnterInitializationMode)
    SYM(fmi2ExitInitializationMode) SYM(fmi2SetReal) SYM(fmi2GetReal) SYM(fmi2DoStep) SYM(fmi2FreeInstance)
    SYM(fmi2Terminate)
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2ValueReference vx = atoi(a[2]), om = atoi(a[3]), fx = atoi(a[4]), fz = atoi(a[5]), vy = atoi(a[6]);
    double last[N + 1][2];
    for (int pass = 0; pass < 2; pass++) {  /* pass 0: four together; pass 1: instance 2 alone */
        fmi2Component c[N];
        int lo = pass ? 2 : 0, hi = pass ? 3 : N;
        for (int i = lo; i < hi; i++) {
            char name[16]; sprintf(name, "tyre%d", i);
            c[i] = fmi2Instantiate(name, fmi2CoSimulation, a[1], "", &cb, fmi2False, fmi2False);
            if (!c[i]) return 3;
            double u[2] = {10.0 + 3.0 * i, (10.0 + 3.0 * i) / 0.305};
            fmi2ValueReference vr[2] = {vx, om};
            if (fmi2SetupExperiment(c[i], fmi2False, 0, 0, fmi2False, 0) || fmi2EnterInitializationMode(c[i]) ||
                fmi2SetReal(c[i], vr, 2, u) || fmi2ExitInitializationMode(c[i])) return 4;
        }
        for (int k = 0; k < STEPS; k++)
            for (int i = lo; i < hi; i++) {
                double t = k * 1e-3, v = 0.3 * (i + 1) * sin(6.0 * t);
                if (fmi2SetReal(c[i], &vy, 1, &v) || fmi2DoStep(c[i], t, 1e-3, fmi2True)) return 5;
            }
        for (int i = lo; i < hi; i++) {
            fmi2ValueReference vr[2] = {fx, fz};
            if (fmi2GetReal(c[i], vr, 2, last[pass ? N : i])) return 6;
            if (!isfinite(last[pass ? N : i][0]) || !isfinite(last[pass ? N : i][1])) return 7;
            fmi2Terminate(c[i]);
            fmi2FreeInstance(c[i]);
        }
    }
    if (memcmp(last[2], last[N], sizeof last[N]) != 0) { printf("instance 2 depends on the others\n"); return 8; }
    for (int i = 1; i < N; i++)
        if (last[i][0] == last[0][0]) { printf("instances %d and 0 identical\n", i); return 9; }
    printf("%s ok Fx %g %g %g %g\n", a[0], last[0][0], last[1][0], last[2][0], last[3][0]);
    return 0;
}

int main(int argc, char **argv) {
    for (int i = 1; i + 6 < argc; i += 7) {
        int rc = run_model(argv + i);
        if (rc) { printf("model %s failed: %d\n", argv[i], rc); return rc; }
    }
    return 0;
}
"""


def test_c_host_runs_four_instances_of_each_model(fmus, tmp_path):
    from fmpy import extract, read_model_description

    src = tmp_path / "host.c"
    src.write_text(C_HOST)
    exe = tmp_path / "host"
    headers = Path(fmpy.__file__).parent / "c-code"
    subprocess.run(["cc", "-O2", "-I", str(headers), str(src), "-o", str(exe), "-ldl", "-lm"],
                   check=True)
    args = []
    for kind, path in fmus.items():
        md = read_model_description(path)
        vr = {v.name: v.valueReference for v in md.modelVariables}
        d = extract(path, unzipdir=str(tmp_path / kind))
        lib = Path(d) / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
        args += [str(lib), md.guid] + [str(vr[n]) for n in ("vx", "omega", "Fx", "Fz", "vy")]
    res = subprocess.run([str(exe), *args], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert res.stdout.count(" ok ") == 3


def test_source_fmu_compiles_in_clean_folder_with_identical_outputs(fmus, tmp_path):
    from fmpy import extract
    from fmpy.build import build_platform_binary

    if shutil.which("cmake") is None:
        pytest.skip("cmake (used by fmpy to compile source FMUs) is not installed")
    clean = Path(extract(fmus["transient"], unzipdir=str(tmp_path / "clean")))
    shutil.rmtree(clean / "binaries")
    (tmp_path / "cmake").mkdir()
    build_platform_binary(clean, build_dir=tmp_path / "cmake")
    assert (clean / "binaries" / "linux64" / "mftyre_transient.so").is_file()
    start = dict(vx=20.0, omega=20.0 / RE0 * 0.97, vy=0.5)
    ref = fmpy.simulate_fmu(str(fmus["transient"]), stop_time=0.1, output_interval=1e-3, start_values=start)
    rebuilt = fmpy.simulate_fmu(str(clean), stop_time=0.1, output_interval=1e-3, start_values=start)
    for name in ("Fx", "Fy", "Fz", "Mz", "u_x", "u_y"):
        np.testing.assert_allclose(rebuilt[name], ref[name], rtol=1e-12, atol=1e-9)


def test_libcosim_runs_four_tyres_of_each_model(fmus):
    """A second, independent importer (OSP libcosim via libcosimpy): four instances of each model together give
    the outputs fmpy gives for the same inputs."""
    pytest.importorskip("libcosimpy")
    from fmpy import read_model_description
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    ex = CosimExecution.from_step_size(step_size=1_000_000)  # 1 ms in ns
    obs = CosimObserver.create_last_value()
    ex.add_observer(observer=obs)
    runs = []
    for kind, path in fmus.items():
        vr = {v.name: v.valueReference for v in read_model_description(path).modelVariables}
        for i in range(4):
            start = {"vx": 8.0 + 2.0 * i, "omega": (8.0 + 2.0 * i) / RE0 * 1.02}
            if kind == "swift":
                start["x_start"] = 2.0 + 0.2 * i
            idx = ex.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(path), instance_name=f"{kind}{i}"))
            for name, value in start.items():
                assert ex.real_initial_value(slave_index=idx, variable_reference=vr[name], value=value)
            runs.append((kind, path, idx, vr, start))
    assert ex.simulate_until(target_time=200_000_000)  # 0.2 s
    for kind, path, idx, vr, start in runs:
        got = obs.last_real_values(slave_index=idx, variable_references=[vr["Fx"], vr["Fz"], vr["My"]])
        ref = fmpy.simulate_fmu(str(path), stop_time=0.2, output_interval=1e-3, start_values=start)
        for value, name in zip(got, ("Fx", "Fz", "My")):
            # rel 1e-10: the hosts' step sizes differ in the last bit (libcosim: integer ns; fmpy: float times),
            # which the SWIFT ring's stiff patch loop carries to ~1e-12 of Fx over 200 steps (1.5e-9 N of 1476 N)
            assert value == pytest.approx(ref[name][-1], rel=1e-10, abs=1e-9), (kind, idx, name)


@pytest.mark.parametrize("args, text", [
    (["--model", "swift", "--road", "cleat(x0=1.0)"], "cleat needs length, height"),
    (["--model", "swift", "--road", "__import__('os').system('true')"], "each term must be one of"),
    (["--model", "swift", "--road", "missing_profile.csv"], "not found"),
    (["--model", "steady", "--road", "cleat(x0=1, length=0.05, height=0.01)"], "only used by --model swift"),
])
def test_build_errors_name_the_cause(tmp_path, capsys, args, text):
    out = tmp_path / "t.fmu"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _build([TIR62, "-o", out, *args]) == 1
    assert text in capsys.readouterr().err
    assert not out.exists()


def test_existing_output_needs_overwrite(fmus, tmp_path, capsys):
    out = tmp_path / "t.fmu"
    out.write_bytes(b"keep")
    assert _build([TIR61, "-o", out]) == 2  # the output rule of mftyre.files: refused before any work, exit status 2
    assert "--overwrite" in capsys.readouterr().err and out.read_bytes() == b"keep"
    assert _build([TIR61, "-o", out, "--overwrite"]) == 0
    assert zipfile.is_zipfile(out)


def test_state_of_another_fmu_is_refused(fmus, tmp_path):
    """An FMU state (or its bytes) belongs to the FMU that made it: another .tir or model is refused."""
    from fmpy.fmi1 import FMICallException

    other = tmp_path / "steady62.fmu"
    assert _build([TIR62, "-o", other]) == 0
    a = Slave(fmus["steady"], tmp_path, "a").initialise()
    b = Slave(other, tmp_path, "b").initialise()
    blob = a.fmu.serializeFMUstate(a.fmu.getFMUstate())
    with pytest.raises(FMICallException):
        b.fmu.deSerializeFMUstate(blob)
    with pytest.raises(FMICallException):
        b.fmu.setFMUstate(a.fmu.getFMUstate())  # same layout, another .tir
    assert any("not a state of this FMU" in m for _, m in b.messages)
    a.close()
    b.close()


def test_calls_out_of_order_are_errors_not_crashes(fmus, tmp_path):
    from fmpy.fmi1 import FMICallException

    s = Slave(fmus["swift"], tmp_path)
    with pytest.raises(FMICallException):
        s.fmu.doStep(0.0, 1e-3)  # before initialisation
    with pytest.raises(FMICallException):
        s.fmu.setReal([10_000], [1.0])  # unknown value reference
    with pytest.raises(FMICallException):
        s.fmu.getInteger([0])  # no Integer variables
    s.initialise(**_swift_start(0.0))
    with pytest.raises(FMICallException):
        s.fmu.setReal([s.vr["x_start"]], [1.0])  # a fixed parameter after initialisation
    with pytest.raises(FMICallException):  # swift provides no directional derivatives
        s.fmu.getDirectionalDerivative([s.vr["Fz"]], [s.vr["vx"]], [1.0])
    s.step()
    s.fmu.terminate()
    with pytest.raises(FMICallException):
        s.fmu.doStep(s.t, 1e-3)  # after fmi2Terminate
    assert all(st == 3 for st, _ in s.messages)
    s.fmu.freeInstance()


def test_get_set_and_status_calls_share_one_check(fmus, tmp_path):
    """Every get/set call checks its arrays and value references the same way (fmi2_tyre.c: var_kind,
    arrays_given): null arrays and references of the wrong kind are logged errors naming the call, never a
    crash; the status calls answer the last successful time and 'not terminated', Discard otherwise."""
    from fmpy.fmi2 import fmi2Boolean, fmi2Integer, fmi2Real, fmi2Status

    s = Slave(fmus["transient"], tmp_path)
    s.initialise(vx=10.0, omega=10.0 / RE0, z=0.29)
    s.step()
    inst, none = s.fmu.component, None
    for name in ("fmi2GetReal", "fmi2SetReal", "fmi2GetInteger", "fmi2SetInteger", "fmi2GetBoolean",
                 "fmi2SetBoolean", "fmi2GetString", "fmi2SetString"):
        s.messages.clear()
        assert getattr(s.fmu.dll, name)(inst, none, 1, none) == 3, name  # fmi2Error, no crash
        assert s.messages == [(3, f"{name}: null value reference or value array for 1 variables")]
    for name in ("fmi2GetInteger", "fmi2SetInteger", "fmi2GetBoolean", "fmi2SetBoolean"):
        assert getattr(s.fmu.dll, name)(inst, none, 0, none) == 0, name  # nothing asked: OK
    vr = s.vr
    assert s.fmu.getReal([vr["tau_vlow"], vr["vx"], vr["Fx"]])[1] == 10.0  # one call reads q, u and y
    s.messages.clear()
    from fmpy.fmi1 import FMICallException

    with pytest.raises(FMICallException):
        s.fmu.setReal([vr["Fx"]], [1.0])  # an output
    with pytest.raises(FMICallException):
        s.fmu.getDirectionalDerivative([vr["vx"]], [vr["vx"]], [1.0])  # an input as the unknown
    with pytest.raises(FMICallException):
        s.fmu.getDirectionalDerivative([vr["Fx"]], [vr["Fx"]], [1.0])  # an output as the known
    assert [m for _, m in s.messages] == [
        f"fmi2SetReal: value reference {vr['Fx']} is not a parameter or an input",
        f"fmi2GetDirectionalDerivative: unknown {vr['vx']} is not an output",
        f"fmi2GetDirectionalDerivative: known {vr['Fx']} is not an input"]
    real, boolean, status = fmi2Real(), fmi2Boolean(), fmi2Status()
    assert s.fmu.dll.fmi2GetRealStatus(inst, 2, byref(real)) == 0 and real.value == pytest.approx(1e-3)
    assert s.fmu.dll.fmi2GetBooleanStatus(inst, 3, byref(boolean)) == 0 and boolean.value == 0
    s.messages.clear()
    assert s.fmu.dll.fmi2GetStatus(inst, 0, byref(status)) == 2  # fmi2Discard: no asynchronous step
    assert s.fmu.dll.fmi2GetIntegerStatus(inst, 0, byref(fmi2Integer())) == 2
    assert s.fmu.dll.fmi2GetRealStatus(inst, 0, byref(real)) == 2
    assert [m for _, m in s.messages] == [f"{f}: no asynchronous step is running; no status to report"
                                          for f in ("fmi2GetStatus", "fmi2GetIntegerStatus", "fmi2GetRealStatus")]
    s.close()


def test_turn_slip_from_the_yaw_rate(models, tmp_path):
    """--turn-slip: the yaw_rate input gives the MF's turn slip phit = +yaw_rate / Vc; the native FMU equals
    MFModel.evaluate with that phit (steady) and the Python twin (transient)."""
    path = tmp_path / "ts.fmu"
    assert _build([TIR61, "-o", path, "--model", "steady", "--turn-slip", "--vertical", "load"]) == 0
    vx, yaw_rate, fz = 15.0, 0.8, 4500.0
    s = Slave(path, tmp_path).initialise(vx=vx, omega=vx / RE0, Fz_in=fz, yaw_rate=yaw_rate)
    out = s.get("Fx", "Fy", "Mz_c", "kappa")
    ref = models["61"].evaluate(fz, out["kappa"], 0.0, 0.0, yaw_rate / vx, vx, omega=vx / RE0, turn_slip=True)
    assert out["Fy"] == pytest.approx(float(ref.fy), rel=1e-9) and abs(out["Fy"]) > 50.0
    assert out["Mz_c"] == pytest.approx(float(ref.mz), rel=1e-9, abs=1e-9)
    s.set(yaw_rate=0.0)
    assert abs(s.get("Fy")["Fy"] - out["Fy"]) > 50.0  # the yaw rate matters
    s.close()
    py = WheelTyre(models["61"], "transient", vertical="load", turn_slip=True)
    assert "yaw_rate" in py.functions.input_names


def test_transient_needs_the_native_backend(tmp_path, capsys):
    """The pythonfmu slave has no transient wheel (its turn slip: tests/test_fmu_backends.py)."""
    out = tmp_path / "b.fmu"
    assert _build([TIR61, "-o", out, "--model", "transient", "--turn-slip", "--backend", "pythonfmu"]) == 1
    assert "--model transient is only available with --backend native" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("kind", ["transient", "swift"])
def test_outputs_in_initialisation_mode_are_those_of_the_initial_state(fmus, tmp_path, kind):
    start = _swift_start(1.0) if kind == "swift" else dict(vx=20.0, omega=20.0 / RE0 * 0.95, vy=0.4)
    s = Slave(fmus[kind], tmp_path)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.enterInitializationMode()
    s.set(**start)
    during = s.get()
    s.fmu.exitInitializationMode()
    assert s.get() == during
    assert abs(during["Fx"]) > 100.0
    s.close()


@pytest.mark.parametrize("args, text", [
    (["--model", "transient", "--input-mode", "rig"], "rig mode (slips and load imposed) is a mode of the steady"),
    (["--model", "swift", "--input-mode", "rig"], "--input-mode rig is a mode of --model steady"),
    (["--model", "transient", "--rim", "torque"], "--rim torque is a mode of --model swift"),
    (["--backend", "pythonfmu", "--rim", "torque"], "set at run time"),
    (["--backend", "pythonfmu", "--road", "cleat(x0=1, length=0.05, height=0.01)"], "set at run time"),
])
def test_options_of_the_other_backend_are_refused(tmp_path, capsys, args, text):
    assert _build([TIR62, "-o", tmp_path / "x.fmu", *args]) == 1
    assert text in capsys.readouterr().err


@pytest.mark.parametrize("h", [1e-3, 5e-3])
def test_native_swift_steady_cornering_equals_magic_formula(fmus, models, tmp_path, h):
    """Constant lateral axle speed (4 and 10 deg, kappa 0 and 0.1), imposed spin, axle height fixed: the native
    SWIFT FMU's rim forces equal the MF at its own Fz_c, slip angle and spin within 1 % at 1 and 5 ms steps (old:
    Fy 10-21 % off, growing with the internal step: the rim's y was held over a step while the belt moved on)."""
    from test_swift_steady import V, _spin, assert_magic_formula

    model = models["62"]
    rl, _ = model.loaded_radius(4000.0)
    for deg, kappa in ((4.0, 0.0), (10.0, 0.1)):
        vy, omega = -V * math.tan(math.radians(deg)), _spin(model, kappa)
        nat = Slave(fmus["swift"], tmp_path).initialise(vx=V, vy=vy, omega=omega, z=float(rl), x_start=-10.0)
        for _ in range(int(round(0.3 / h))):
            nat.step(h)
        out = nat.get()
        assert_magic_formula(model, out["Fx"], out["Fy"], out["Fz_c"], out["Re"], vy, omega, f"{deg} deg {kappa}")
        nat.close()


def test_default_inputs_roll_freely(fmus, tmp_path):
    """No inputs set: the steady, transient and SWIFT FMUs roll freely under the nominal load (start omega R_e = vx,
    z at the loaded radius of FNOMIN): slip ~0 and |Fx| no more than the MF's own force at zero slip (old: omega
    10/0.3 rad/s at 10 m/s, a 1.4 % drive slip: Fx 794 N steady, 1362 N SWIFT)."""
    for kind, path in fmus.items():
        nat = Slave(path, tmp_path, name=kind).initialise()
        for _ in range(50):
            nat.step(1e-3)
        out = nat.get()
        assert abs(out["kappa"]) < 1e-4, kind
        assert abs(out["Fx"]) < 0.01 * out["Fz"], kind
        assert out["Fz"] == pytest.approx(4000.0, rel=0.05), kind  # FNOMIN of the files (rim: less the belt)
        nat.close()


def test_a_yawing_wheel_spins_like_an_inclined_one(models):
    """The tread in the contact patch spins at yaw_rate + omega sin(gamma) about the road normal (ISO-W: z up,
    gamma about x, omega forwards about the axle): a wheel yawing to the left (yaw_rate > 0) at zero slip angle
    spins the way a wheel inclined by gamma > 0 does, so the turn-slip side force and moment it gets have the signs
    of the file's camber thrust and camber moment (Fy < 0 and Mz < 0 on the car file at 2-4 kN: the force points out
    of the turn, as in the brush model, and the moment resists the yaw). Fails with phit = -yaw_rate / Vc."""
    vx = 15.0
    yawing = WheelTyre(models["61"], "steady", vertical="load", turn_slip=True)
    for fz in (2000.0, 4000.0):
        yawing.set_inputs(vx=vx, omega=vx / RE0, Fz_in=fz, yaw_rate=0.0, gamma=0.0)
        yawing.initialise()
        straight = yawing.outputs()
        yawing.set_inputs(yaw_rate=0.3)
        turning = yawing.outputs()
        yawing.set_inputs(yaw_rate=0.0, gamma=0.02)
        inclined = yawing.outputs()
        for name in ("Fy", "Mz_c"):
            by_yaw, by_camber = turning[name] - straight[name], inclined[name] - straight[name]
            assert by_yaw * by_camber > 0, (fz, name, by_yaw, by_camber)
        assert turning["Fy"] - straight["Fy"] < -5.0 and turning["Mz_c"] - straight["Mz_c"] < 0.0


@pytest.mark.parametrize("kind", ["steady", "transient"])
def test_the_input_policy_speed_limits_refuse_as_in_python(fmus, models, tmp_path, kind):
    """The speed limits of mftyre.inputs.check_limits (this file: |vx| <= 173 m/s, rim speed |omega R0| <= 190 m/s)
    in the native wheel FMU and mftyre.transient.WheelTyre, with the text MFModel.evaluate raises: a start beyond them
    fails (fmi2Error), a step is discarded (fmi2Discard, state and outputs held) and the next valid step runs."""
    from fmpy.fmi1 import FMICallException

    from mftyre.transient import StepError, WheelTyre

    model = models["61"]
    cases = {"vx": dict(vx=200.0, omega=200.0 / RE0), "omega": dict(vx=150.0, omega=650.0)}
    texts, wheel = {}, WheelTyre(model, kind)
    for name, inputs in cases.items():
        with pytest.raises(mftyre.ModelInputError) as policy:
            model.evaluate(4000.0, 0.0, 0.0, **inputs)
        texts[name] = str(policy.value)
        assert texts[name].startswith(f"input {name} = "), texts[name]
        wheel.set_inputs(**inputs)
        with pytest.raises(mftyre.ModelInputError) as start:
            wheel.initialise()
        assert str(start.value) == texts[name]
        s = Slave(fmus[kind], tmp_path)
        with pytest.raises(FMICallException) as exc:
            s.initialise(**inputs)
        assert exc.value.status == 3 and [m for _, m in s.messages] == [f"initialisation failed: {texts[name]}"]
        s.fmu.freeInstance()
    wheel.set_inputs(vx=10.0, omega=10.0 / RE0)
    wheel.initialise()
    wheel.step(1e-3)
    s = Slave(fmus[kind], tmp_path).initialise()
    s.step()
    held = s.get()
    for name, inputs in cases.items():
        wheel.set_inputs(**inputs)
        with pytest.raises(StepError) as step:
            wheel.step(1e-3)
        assert str(step.value) == texts[name]
        s.set(**inputs)
        with pytest.raises(FMICallException) as exc:
            s.fmu.doStep(s.t, 1e-3)
        assert exc.value.status == 2 and s.messages[-1][1] == f"fmi2DoStep at t = {s.t:g}: {texts[name]}; state and " \
                                                              "outputs held", s.messages[-1]
        assert s.get(*held) == held
    s.set(vx=10.0, omega=10.0 / RE0)
    s.step()  # recovers with valid inputs
    assert all(math.isfinite(v) for v in s.get().values())
    s.close()
