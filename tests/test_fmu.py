"""The pythonfmu tyre FMU (fmu, `mftyre fmu build --backend pythonfmu`): built into tmp paths, run with fmpy.

Evidence used: MFModel.evaluate / vertical_force on the slips, load and radius the FMU reports (1e-9), the
kinematic slip definitions and their signs written out independently, fmpy's model-description validation, and
FMI call sequences (initialisation, reset, variable steps, error statuses).
"""
from __future__ import annotations

import argparse
import os
import math
import tempfile
from ctypes import byref
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pythonfmu")
fmpy = pytest.importorskip("fmpy")

import mftyre  # noqa: E402
from mftyre.fmu_command import fmu_sources, register  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TIR61 = ROOT / "tir_files" / "car_205_60R15_mf61.tir"
TIR62 = ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir"
FORCES = ("Fx", "Fy", "Fz")


def _build(args):
    parser = argparse.ArgumentParser(prog="mftyre")
    register(parser.add_subparsers(dest="command"))
    ns = parser.parse_args(["fmu", "build", "--backend", "pythonfmu", *map(str, args)])
    return ns.func(ns)


@pytest.fixture(scope="module")
def fmus(built_fmu):
    return {"61": built_fmu(TIR61, "--backend", "pythonfmu", "--vertical", "load"),
            "62r": built_fmu(TIR62, "--backend", "pythonfmu", "--side", "right", "--vertical", "position")}


@pytest.fixture(scope="module")
def native61(built_fmu):
    """The native (default backend) steady FMU of the same tyre and vertical input as ``fmus["61"]``."""
    return built_fmu(TIR61, "--vertical", "load")


class Slave:
    """An FMU instance driven call by call (fmpy FMU2Slave), with its log messages collected."""

    def __init__(self, path, tmp_path, start=None, initialise=True):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
        from fmpy.fmi1 import calloc, free
        from fmpy.logging import addLoggerProxy

        self.md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.unzipped = extract(path, unzipdir=tempfile.mkdtemp(prefix="unz_", dir=tmp_path))
        self.messages = []

        def logger(env, name, status, category, message):
            self.messages.append((status, message.decode()))

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(callbacks))
        self._callbacks = callbacks
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipped,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="tyre")
        self.fmu.instantiate(callbacks=callbacks, loggingOn=True)
        if initialise:
            self.initialise(start)

    def initialise(self, start=None):
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.set(**(start or {}))
        self.fmu.exitInitializationMode()

    def set(self, **values):
        for name, value in values.items():
            if self.types[name] == "String":
                self.fmu.setString([self.vr[name]], [value])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, *names):
        return dict(zip(names, self.fmu.getReal([self.vr[n] for n in names])))

    def status(self):
        return self.fmu.getInteger([self.vr["status"]])[0]

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


OUT = ("Fx", "Fy", "Fz", "Mx", "My", "Mz", "Mx_c", "My_c", "Mz_c", "kappa", "alpha", "Vsx", "Vsy", "omega_used",
       "rho", "Rl", "Re", "contact_length", "contact_width", "trail", "mux", "muy", "Fz_c", "road_w", "road_slope",
       "x_road", "u_x", "u_y", "Fx_c", "Fy_c", "road_curvature", "Re_variation", "road_camber_eff",
       "x_contact")


def _compare_with_evaluate(model, out, gamma, vx, p, omega, *, rig=False, rl=None):
    """The FMU outputs against MFModel.evaluate on the same load and slips (1e-9 relative to FNOMIN, R0)."""
    prm = model.params
    ref = model.evaluate(out["Fz"], out["kappa"], out["alpha"], gamma, 0.0, vx, p, None if rig else omega)
    F, L = prm.FNOMIN, prm.UNLOADED_RADIUS
    pairs = [("Fx", "fx", F), ("Fy", "fy", F), ("Fz", "fz", F), ("Mx_c", "mx", F * L), ("My_c", "my", F * L),
             ("Mz_c", "mz", F * L), ("Re", "re", L), ("contact_length", "a", L / 2), ("contact_width", "b", L / 2),
             ("trail", "t", L), ("mux", "mux", 1), ("muy", "muy", 1), ("omega_used", "omega", 100)]
    if rl is None:
        pairs += [("Rl", "rl", L), ("rho", "rho", L)]
    for name, key, scale in pairs:
        factor = 2.0 if name.startswith("contact") else 1.0
        assert out[name] == pytest.approx(factor * float(ref[key]), rel=1e-9, abs=1e-9 * scale), name
    # wheel-centre moments from the contact-point loads and the lever arm (see fmu/README.md)
    lever = out["Rl"] if rl is None else rl
    c, s = math.cos(gamma), math.sin(gamma)
    assert out["Mx"] == pytest.approx(out["Mx_c"] + lever * (out["Fy"] * c + out["Fz"] * s), abs=1e-9 * F * L)
    assert out["My"] == pytest.approx(out["My_c"] - lever * out["Fx"] * c, abs=1e-9 * F * L)
    assert out["Mz"] == pytest.approx(out["Mz_c"] - lever * out["Fx"] * s, abs=1e-9 * F * L)
    return ref


def test_model_description_validates(fmus):
    from fmpy.validation import validate_fmu

    for path in fmus.values():
        assert validate_fmu(str(path)) == []
    md = fmpy.read_model_description(fmus["61"])
    assert md.version == mftyre.__version__  # the one version string
    units = {v.name: v.unit for v in md.modelVariables}
    assert units["Fx"] == "N" and units["Mz"] == "N.m" and units["p"] == "Pa" and units["omega"] == "rad/s"
    causality = {v.name: v.causality for v in md.modelVariables}
    assert {n for n, c in causality.items() if c == "parameter"} == {
        "tir_file", "model", "side", "input_mode", "vertical_input", "evaluator", "road", "rim", "x_start",
        "max_step", "axle_mass"}
    assert len(md.initialUnknowns) == len(md.outputs) == len(OUT) + 1


def test_cli_errors(tmp_path, capsys):
    assert fmu_sources().is_dir()
    assert _build([tmp_path / "missing.tir", "-o", tmp_path / "m.fmu"]) == 1
    assert "no such property file" in capsys.readouterr().err
    assert _build([TIR61, "-o", tmp_path / "tyre.zip"]) == 1


def test_vehicle_load_mode_equals_evaluate(fmus, tmp_path):
    model = mftyre.load_tir(TIR61)
    fmu = Slave(fmus["61"], tmp_path)
    rng = np.random.default_rng(7)
    t = x_road = 0.0
    for i in range(60):
        vx = rng.uniform(-30, 30) if i % 7 else rng.uniform(-1.5, 1.5)  # some points in the low-speed range
        vy = rng.uniform(-3, 3)
        omega = vx / 0.3 * rng.uniform(0.8, 1.2)
        gamma = rng.uniform(-0.08, 0.08)
        fz = rng.uniform(-500, 9000)
        p = rng.uniform(1.7e5, 2.7e5)
        fmu.set(vx=vx, vy=vy, omega=omega, gamma=gamma, Fz_in=fz, p=p)
        h = rng.choice([1e-4, 1e-3, 0.013])  # varying communication step
        fmu.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
        x_road += vx * h
        out = fmu.get(*OUT)
        assert out["Fz"] == max(fz, 0.0) == out["Fz_c"]
        assert out["x_road"] == pytest.approx(x_road, rel=1e-12) and out["road_w"] == out["road_slope"] == 0.0
        _compare_with_evaluate(model, out, gamma, vx, p, omega)
        # the slips, written out: kappa given to the MF = (omega Re - vx)/vx (relative to the travel direction;
        # ISO-W's (omega Re - vx)/|vx| times sign(vx)), tan(alpha) = vy/|vx|
        assert out["kappa"] == pytest.approx((omega * out["Re"] - vx) / math.copysign(max(abs(vx), 1e-3), vx),
                                             rel=1e-12, abs=1e-12)
        assert math.tan(out["alpha"]) == pytest.approx(vy / abs(vx), rel=1e-12)
    assert fmu.status() == 0
    fmu.close()


def test_slip_signs_and_wheel_centre_moment(fmus, tmp_path):
    fmu = Slave(fmus["61"], tmp_path)
    fmu.set(vx=20.0, vy=0.0, omega=20.0 / 0.30 * 1.05, gamma=0.0, Fz_in=4000.0)  # driving
    fmu.fmu.doStep(0.0, 1e-3)
    drive = fmu.get(*OUT)
    assert drive["kappa"] > 0 and drive["Fx"] > 0 and drive["Vsx"] < 0
    # the road pushes the contact point forwards, below the centre: a moment turning the wheel backwards
    assert drive["My"] < 0 and drive["My"] == pytest.approx(drive["My_c"] - drive["Rl"] * drive["Fx"])
    fmu.set(omega=20.0 / 0.30 * 0.95)  # braking
    fmu.fmu.doStep(1e-3, 1e-3)
    assert fmu.get("Fx")["Fx"] < 0
    re = drive["Re"]
    for i in range(4):  # free rolling (omega Re(omega) = vx), sliding to the left
        fmu.set(omega=20.0 / re, vy=1.0)
        fmu.fmu.doStep(2e-3 * (i + 1), 1e-3)
        side = fmu.get(*OUT)
        re = side["Re"]
    assert abs(side["kappa"]) < 1e-9 and side["alpha"] > 0 and side["Fy"] < 0
    fmu.close()


#: Reversing at 10 m/s, 4 kN: the wheel's spin as omega Re / vx (0 locked, 1 free rolling, 0.9 spinning backwards
#: slower than it rolls: ISO-W kappa = +0.1, -0.5 spun forwards, 1.1 spinning backwards faster: kappa = -0.1).
REVERSING = {"locked": 0.0, "free": 1.0, "spin excess": 0.9, "driven forwards": -0.5, "spun backwards": 1.1}


def _reversing(path, tmp_path, spin, vy=0.0, vx=-10.0):
    """The FMU's outputs at vx with omega = spin vx / Re (Re from the FMU at that point, a few passes)."""
    fmu = Slave(path, tmp_path)
    re, t = 0.3, 0.0
    for _ in range(4):
        fmu.set(vx=vx, vy=vy, omega=spin * vx / re, gamma=0.0, Fz_in=4000.0)
        fmu.fmu.doStep(t, 1e-3)
        t += 1e-3
        out = fmu.get("Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa", "Re")
        re = out["Re"]
    fmu.close()
    return out


def test_reversing_forces_oppose_the_slip_and_equal_the_native_fmu(fmus, native61, tmp_path):
    """vx < 0: Fx has the sign of the ISO-W slip (omega Re - vx)/|vx| (a locked wheel brakes the backwards motion,
    Fx > 0; a wheel spun forwards pulls forwards), free rolling gives only the rolling-resistance shift, the
    forces are those forwards with everything mirrored (Fx(-vx, -omega) = -Fx(vx, omega)), and the pythonfmu and
    native FMUs of the same tyre give the same Fx, Fy, Fz, Mx, My, Mz (they disagreed in sign before)."""
    for name, spin in REVERSING.items():
        py = _reversing(fmus["61"], tmp_path, spin)
        iso_kappa = (spin * -10.0 - -10.0) / 10.0  # (omega Re - vx) / |vx|
        assert py["kappa"] == pytest.approx(-iso_kappa, abs=1e-9), name  # relative to the travel direction
        if name == "free":
            assert abs(py["Fx"]) < 0.01 * py["Fz"], name
        else:
            assert math.copysign(1.0, py["Fx"]) == math.copysign(1.0, iso_kappa), name
            assert abs(py["Fx"]) > 0.5 * py["Fz"], name
        forwards = _reversing(fmus["61"], tmp_path, spin, vx=10.0)  # the same wheel, mirrored fore and aft
        assert py["Fx"] == pytest.approx(-forwards["Fx"], rel=1e-9, abs=1e-6), name
        for vy in (0.0, 0.5):
            py = _reversing(fmus["61"], tmp_path, spin, vy)
            nat = _reversing(native61, tmp_path, spin, vy)
            for k in ("Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa"):
                assert py[k] == pytest.approx(nat[k], rel=1e-9, abs=1e-6), (name, vy, k)


def test_position_mode_right_side_mf62(fmus, tmp_path):
    model = mftyre.load_tir(TIR62, side="right")
    fmu = Slave(fmus["62r"], tmp_path)
    rng = np.random.default_rng(3)
    for i in range(30):
        vx, vy, gamma = rng.uniform(3, 35), rng.uniform(-2, 2), rng.uniform(-0.06, 0.06)
        omega = vx / 0.3 * rng.uniform(0.9, 1.1)
        p, road = rng.uniform(1.9e5, 2.5e5), rng.uniform(-0.05, 0.05)
        height = rng.uniform(0.27, 0.305)
        fmu.set(vx=vx, vy=vy, omega=omega, gamma=gamma, p=p, road_z=road, z=road + height)
        fmu.fmu.doStep(0.01 * i, 0.01)
        out = fmu.get(*OUT)
        rl = height / math.cos(gamma)
        assert out["Rl"] == pytest.approx(rl, rel=1e-12)
        fz = max(float(model.vertical_force(rl, p, omega, out["Fx"], out["Fy"], gamma)), 0.0)
        assert out["Fz"] == pytest.approx(fz, rel=1e-9, abs=1e-9 * model.params.FNOMIN)
        _compare_with_evaluate(model, out, gamma, vx, p, omega, rl=rl)
    fmu.set(z=1.0)  # wheel in the air
    fmu.fmu.doStep(1.0, 0.01)
    air = fmu.get("Fx", "Fy", "Fz", "rho")
    assert air == {"Fx": 0.0, "Fy": 0.0, "Fz": 0.0, "rho": 0.0}
    fmu.close()


def test_rig_mode_equals_evaluate(fmus, tmp_path):
    model = mftyre.load_tir(TIR61)
    fmu = Slave(fmus["61"], tmp_path, start={"input_mode": "rig"})
    for i, (fz, kappa, alpha, gamma, vx, p) in enumerate([(4000, 0.05, 0.1, 0.02, 20, 2.2e5),
                                                          (6500, -0.2, -0.05, -0.05, 8, 2.5e5),
                                                          (2000, 0.0, 0.3, 0.0, 0.5, 1.9e5)]):
        fmu.set(Fz_in=fz, kappa_in=kappa, alpha_in=alpha, gamma=gamma, vx=vx, p=p)
        fmu.fmu.doStep(0.1 * i, 0.1)
        out = fmu.get(*OUT)
        assert (out["kappa"], out["alpha"]) == (kappa, alpha)
        _compare_with_evaluate(model, out, gamma, vx, p, None, rig=True)
    fmu.close()


def test_outputs_valid_after_initialisation_and_reset(fmus, tmp_path):
    model = mftyre.load_tir(TIR61)
    fmu = Slave(fmus["61"], tmp_path, start={"vy": 0.4, "Fz_in": 5000.0})
    first = fmu.get(*OUT)
    assert first["Fz"] == 5000.0 and first["Fy"] < 0 and fmu.status() == 0
    start = {v.name: float(v.start) for v in fmu.md.modelVariables if v.causality == "input"}
    _compare_with_evaluate(model, first, 0.0, start["vx"], start["p"], start["omega"])
    fmu.set(vy=-1.0, Fz_in=3000.0, vertical_input="position")
    fmu.fmu.doStep(0.0, 0.5)
    assert fmu.get("Fz")["Fz"] != 5000.0
    fmu.fmu.reset()  # back to the instantiated state: start values, default parameters
    fmu.initialise({"vy": 0.4, "Fz_in": 5000.0})
    assert fmu.get(*OUT) == first
    fmu.close()


def test_errors_reported_through_status_and_log(fmus, tmp_path):
    from fmpy.fmi1 import FMICallException

    fmu = Slave(fmus["61"], tmp_path)
    fmu.fmu.doStep(0.0, 0.01)
    good = fmu.get(*OUT)
    for bad in ({"vx": float("nan")}, {"omega": float("inf")}, {"p": -1.0}):
        fmu.set(**bad)
        with pytest.raises(FMICallException, match="discard"):
            fmu.fmu.doStep(0.01, 0.01)
        assert fmu.get(*OUT) == good and fmu.status() == 1
        assert fmu.messages[-1][0] == 3 and "input rejected" in fmu.messages[-1][1]
        fmu.set(vx=good["omega_used"] * 0 + 16.7, omega=54.0, p=2.2e5)
    fmu.fmu.doStep(0.02, 0.01)  # valid inputs again: computed normally
    assert fmu.status() == 0
    fmu.close()

    # a failed initialisation is reported as a failure, never as OK, with the cause in the log worded as the
    # native FMU words it (tests/test_fmu_native.py): "initialisation failed: parameter NAME ...", no traceback.
    # The status is fmi2Fatal, not fmi2Error: pythonfmu 0.7.0's binary maps every Python exception to fmi2Fatal
    # (MFTyre.py notes); should pythonfmu ever answer fmi2Error, this fails and the notes need updating.
    missing, fifo = tmp_path / "none.tir", tmp_path / "fifo.tir"
    os.mkfifo(fifo)  # exists, but is no regular file (old: reported as "no such file")
    for params, text in (({"side": "up"}, "parameter side must be 'left' or 'right', got 'up'"),
                         ({"tir_file": str(fifo)}, f"{fifo}: not a regular file (a device, FIFO or socket): "
                                                   "expected a .tir property file"),
                         ({"model": "rigid"}, "parameter model must be 'steady' or 'swift', got 'rigid'"),
                         ({"tir_file": str(missing)}, f"parameter tir_file: no such file {str(missing)!r}"),
                         ({"evaluator": "numpy"}, "parameter evaluator must be one of auto, compiled, casadi; "
                                                  "got 'numpy'")):
        fmu = Slave(fmus["61"], tmp_path, initialise=False)
        with pytest.raises(FMICallException) as exc:
            fmu.initialise(params)
        assert exc.value.status == 4 and "fmi2ExitInitializationMode" in str(exc.value)
        assert (3, "initialisation failed: " + text) in fmu.messages, fmu.messages


def test_step_sizes_checked_and_state_restored(fmus, tmp_path):
    """Zero, negative or NaN step sizes are discarded with a message; the FMU state is the whole state."""
    from fmpy.fmi1 import FMICallException

    fmu = Slave(fmus["62r"], tmp_path, start={"vertical_input": "position"})
    fmu.fmu.doStep(0.0, 1e-3)
    held = fmu.get(*OUT)
    for h in (0.0, -1e-3, float("nan")):
        with pytest.raises(FMICallException, match="discard"):
            fmu.fmu.doStep(1e-3, h)
        assert fmu.get(*OUT) == held and "step size" in fmu.messages[-1][1]
    fmu.close()


def test_other_tir_and_evaluators(fmus, tmp_path):
    """A tir_file parameter other than the embedded one, and each evaluator, give the same outputs."""
    results = {}
    for evaluator in ("compiled", "casadi"):
        fmu = Slave(fmus["61"], tmp_path, start={"evaluator": evaluator, "tir_file": str(TIR62), "vy": 0.3})
        assert fmu.status() == 0
        assert any(f"evaluator {evaluator}" in m for _, m in fmu.messages)
        results[evaluator] = fmu.get(*OUT)
        fmu.close()
    model = mftyre.load_tir(TIR62, side="left")
    start = {v.name: float(v.start) for v in fmu.md.modelVariables if v.causality == "input"}
    for out in results.values():
        _compare_with_evaluate(model, out, 0.0, start["vx"], start["p"], start["omega"])


def _rss_bytes():
    try:
        with open("/proc/self/statm") as fh:
            import os

            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:  # not Linux: peak RSS (kB on Linux/BSD, bytes on macOS)
        import resource

        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def run_long(fmu, set_names, get_names, inputs_at, h, n=100_000, blocks=10):
    """``n`` co-simulation steps of ``h`` with the inputs ``inputs_at(k)`` of step k; per block of n/blocks steps
    the time per step (the thread's CPU time: on a shared machine the wall time also counts the time the thread
    waits for a core) and the memory afterwards, and the last outputs. Each block is timed as ten chunks and keeps
    its fastest: a load spike slows some chunks, a real drift slows all of them (:func:`assert_no_time_drift`)."""
    import time

    set_vr, get_vr = [fmu.vr[k] for k in set_names], [fmu.vr[k] for k in get_names]
    real_set, real_get, do_step = fmu.fmu.setReal, fmu.fmu.getReal, fmu.fmu.doStep
    times, rss, out, t = [], [], None, 0.0
    per_block = n // blocks
    chunk = per_block // 10
    for b in range(blocks):
        chunk_times = []
        t0 = time.thread_time()
        for i in range(per_block):
            if i and i % chunk == 0:
                chunk_times.append(time.thread_time() - t0)
                t0 = time.thread_time()
            real_set(set_vr, inputs_at(b * per_block + i))
            do_step(t, h)
            t += h
            out = real_get(get_vr)
        chunk_times.append(time.thread_time() - t0)
        times.append(min(chunk_times) / chunk)
        rss.append(_rss_bytes())
    return times, rss, out


def assert_no_time_drift(times):
    """A drift (work growing with the steps taken) slows every later block: the fastest of the last three blocks
    stays within 1.5x (+ 20 us) of the fastest of the first three; noise would have to slow three blocks in a row."""
    assert min(times[-3:]) < 1.5 * min(times[:3]) + 20e-6, times


def test_100000_steps_no_drift_in_memory_or_time(fmus, tmp_path):
    fmu = Slave(fmus["62r"], tmp_path, start={"vertical_input": "position"})

    def inputs_at(k):
        s = 1e-3 * k
        return [20.0 + math.sin(s), 0.5 * math.sin(3 * s), 68.0 + 2 * math.cos(s), 0.01,
                0.29 + 0.003 * math.sin(7 * s), 2.2e5]

    times, rss, _ = run_long(fmu, ("vx", "vy", "omega", "gamma", "z", "p"), ("Fx", "Fy", "Fz", "Mx", "My", "Mz"),
                             inputs_at, 1e-4)
    assert fmu.status() == 0
    fmu.close()
    print(f"time per step {[round(x * 1e6, 1) for x in times]} us; RSS {[r >> 20 for r in rss]} MiB")
    # first and last 10% of the steps: no growth in time per step (margin for a shared machine) or memory
    assert_no_time_drift(times)
    assert rss[-1] - rss[0] < 8 << 20
