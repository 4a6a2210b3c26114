"""Both FMU backends (native C and the pythonfmu slave) are translations of one wheel: they speak one vocabulary
(mftyre.variables.WHEEL: a name has one unit and causality in both) and, driven by fmpy with the same inputs in
the same mode, give the same outputs. Modes: steady with the load imposed, steady on a rig (load and slips
imposed), SWIFT with axle height and spin imposed over a cleat; with --turn-slip (steady_ts, swift_ts) steady from
the input yaw_rate and SWIFT over the cleat with a lateral step.

What the backends do not share is pinned below (ONLY_NATIVE: nothing left; ONLY_PYTHONFMU: the pythonfmu FMU is
one FMU for every mode, so it has the other modes' variables), so that a new gap shows here."""
from __future__ import annotations

import argparse
import math
import shutil

import numpy as np
import pytest

pytest.importorskip("pythonfmu")
fmpy = pytest.importorskip("fmpy")

from mftyre.variables import WHEEL  # noqa: E402
from test_fmu import TIR61, TIR62, Slave  # noqa: E402

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) to build native FMUs")

CLEAT = "cleat(x0=0.8, length=0.05, height=0.01)"

#: Variables one backend has in a mode and the other has not (the gaps left; see fmu/README.md).
ONLY_NATIVE = {"steady": set(), "rig": set(), "swift": set(), "swift_load_torque": set(), "steady_ts": set(),
               "swift_ts": set()}
#: pythonfmu: one FMU for every mode (String parameters choose), so its extra variables are the other modes' too.
ONLY_PYTHONFMU = {"vy", "omega", "z", "vz", "road_z", "torque", "kappa_in", "alpha_in", "Fz_in", "axle_mass",
                  "mu_scale", "u_x", "u_y", "Fx_c", "Fy_c", "road_curvature", "Re_variation", "road_camber_eff",
                  "x_contact",
                  "x_start", "max_step", "Vsx", "Vsy", "omega_used", "contact_width", "Fz_c", "road_w", "road_slope",
                  "x_road", "Mx_c", "My_c", "trail", "mux", "muy", "yaw_rate"}


_PYTHONFMU_STEADY = [TIR61, "--backend", "pythonfmu", "--vertical", "load"]
_PYTHONFMU_SWIFT = [TIR62, "--backend", "pythonfmu", "--model", "swift", "--vertical", "position"]
#: (backend, mode) -> the options of ``mftyre fmu build``. The pythonfmu steady and swift FMUs and the native steady
#: one are test_fmu's and test_fmu_swift's; the pythonfmu FMU is one FMU for several modes (input_mode,
#: vertical_input, rim chosen at run time).
BUILDS = {
    ("native", "steady"): [TIR61, "--vertical", "load"],
    ("native", "rig"): [TIR61, "--input-mode", "rig"],
    ("native", "swift"): [TIR62, "--model", "swift", "--road", CLEAT],
    ("native", "swift_load_torque"): [TIR62, "--model", "swift", "--road", CLEAT, "--vertical", "load", "--rim",
                                      "torque"],
    ("pythonfmu", "steady"): _PYTHONFMU_STEADY,
    ("pythonfmu", "rig"): _PYTHONFMU_STEADY,
    ("pythonfmu", "swift"): _PYTHONFMU_SWIFT,
    ("pythonfmu", "swift_load_torque"): _PYTHONFMU_SWIFT,
    ("native", "steady_ts"): [TIR61, "--vertical", "load", "--turn-slip"],
    ("native", "swift_ts"): [TIR62, "--model", "swift", "--road", CLEAT, "--turn-slip"],
    ("pythonfmu", "steady_ts"): [*_PYTHONFMU_STEADY, "--turn-slip"],
    ("pythonfmu", "swift_ts"): [*_PYTHONFMU_SWIFT, "--turn-slip"],
}


@pytest.fixture(scope="module")
def fmus(built_fmu):
    """(backend, mode) -> the FMU's path, built when a test first asks for it (built_fmu builds equal options
    once), so that a selection of tests builds only the FMUs it runs."""

    class Built(dict):
        def __missing__(self, key):
            self[key] = built_fmu(*BUILDS[key])
            return self[key]

    return Built()


def _variables(path):
    return {v.name: v for v in fmpy.read_model_description(path).modelVariables if v.type == "Real"}


@pytest.mark.parametrize("mode", ["steady", "rig", "swift", "swift_load_torque", "steady_ts", "swift_ts"])
def test_both_backends_speak_one_vocabulary(fmus, mode):
    native, python = _variables(fmus["native", mode]), _variables(fmus["pythonfmu", mode])
    for name, v in {**native, **python}.items():  # every Real variable of both is a word of the vocabulary
        assert name in WHEEL, name
        assert (v.unit or "1") == WHEEL[name].unit, name
        assert v.causality == WHEEL[name].causality, name
    for name in native.keys() & python.keys():
        assert native[name].causality == python[name].causality and native[name].unit == python[name].unit, name
        if native[name].start is not None or python[name].start is not None:  # the same defaults (free rolling)
            assert float(native[name].start) == pytest.approx(float(python[name].start), rel=1e-12), name
    assert native.keys() - python.keys() == ONLY_NATIVE[mode]
    assert python.keys() - native.keys() <= ONLY_PYTHONFMU
    assert ("yaw_rate" in native) == (mode == "steady_ts")  # the native SWIFT wheel takes no yaw rate
    assert ("yaw_rate" in python) == mode.endswith("_ts")  # pythonfmu: built with turn slip (for its steady model)


def _run(path, tmp_path, start, steps, h):
    """Initialise with ``start``, then step with each dict of ``steps`` (inputs set before the step); the Real
    outputs after initialisation and after every step."""
    s = Slave(path, tmp_path, start=start)
    outputs = [n for n, v in _variables(path).items() if v.causality == "output"]
    rows = [s.get(*outputs)]
    t = 0.0
    for inputs in steps:
        s.set(**inputs)
        s.fmu.doStep(t, h)  # fmpy raises on a failed step
        t += h
        rows.append(s.get(*outputs))
    s.close()
    return rows


def _steady_inputs(rng, n, rig, turn_slip=False):
    for _ in range(n):
        row = {"vx": rng.uniform(-30, 30), "gamma": rng.uniform(-0.05, 0.05), "p": rng.uniform(1.9e5, 2.5e5),
               "Fz_in": rng.uniform(500, 8000)}
        if rig:
            row.update(kappa_in=rng.uniform(-0.3, 0.3), alpha_in=rng.uniform(-0.2, 0.2))
        else:
            row.update(vy=rng.uniform(-2, 2), omega=row["vx"] / 0.3 * rng.uniform(0.9, 1.1))
        if turn_slip:  # a car's yaw rate, up to a tight turn at low speed
            row.update(yaw_rate=rng.choice([-1.0, 1.0]) * rng.uniform(0.2, 1.5))
        yield row


@pytest.mark.parametrize("mode", ["steady", "rig", "steady_ts"])
def test_both_backends_give_the_same_steady_results(fmus, tmp_path, mode):
    rng = np.random.default_rng(22)
    steps = list(_steady_inputs(rng, 12, mode == "rig", turn_slip=mode == "steady_ts"))
    # the backends' start values differ (native: vx 10 m/s, pythonfmu: LONGVL): both start from the first inputs
    native = _run(fmus["native", mode], tmp_path, steps[0], steps, 1e-3)
    python = _run(fmus["pythonfmu", mode], tmp_path, {**steps[0], "input_mode": "rig" if mode == "rig" else "vehicle"},
                  steps, 1e-3)
    shared = native[0].keys() & python[0].keys()
    assert {"Fx", "Fy", "Fz", "Mx", "My", "Mz", "Mz_c", "kappa", "alpha", "Rl", "Re", "rho", "Vsx", "Vsy", "omega_used",
            "contact_width", "trail", "mux", "muy"} <= shared
    for i, (a, b) in enumerate(zip(native, python)):
        for name in shared:
            assert a[name] == pytest.approx(b[name], rel=1e-9, abs=1e-7), (mode, i, name, steps[i - 1] if i else {})
    if mode == "steady_ts":  # the yaw rate is felt: the same motion without it gives other Fy and Mz
        still = _run(fmus["native", mode], tmp_path, steps[0], [{**row, "yaw_rate": 0.0} for row in steps], 1e-3)
        d_fy, d_mz = ([abs(a[n] - b[n]) for a, b in zip(native[1:], still[1:])] for n in ("Fy", "Mz"))
        assert min(d_fy) > 1.0 and min(d_mz) > 0.1 and max(d_fy) > 200.0 and max(d_mz) > 10.0, (d_fy, d_mz)


@pytest.mark.parametrize("mode", ["swift", "swift_load_torque"])
def test_both_backends_give_the_same_swift_run_over_a_cleat(fmus, tmp_path, mode):
    """The wheel rolling over a 10 mm cleat at 10 m/s in 5 ms communication steps, with the axle height and the
    spin imposed (swift), or the axle pushed down by a load of 4000 N and the rim driven by a torque (100 N m from
    0.1 s; swift_load_torque): both backends step the same rigid ring with the same internal step (max_step 1 ms)."""
    from mftyre import load_tir
    from mftyre.transient import free_rolling_start

    omega, z = free_rolling_start(load_tir(TIR62), 10.0)
    loaded = mode == "swift_load_torque"
    start = {"vx": 10.0, "omega": omega, **({"Fz_in": 4000.0} if loaded else {"z": z})}
    steps = [{}] * 20 + [{"torque": 100.0}] * 10 if loaded else [{}] * 30  # 0.15 s: over the cleat at 0.8 m
    native = _run(fmus["native", mode], tmp_path, start, steps, 5e-3)
    python = _run(fmus["pythonfmu", mode], tmp_path, {**start, "road": CLEAT, "rim": "torque" if loaded else "speed",
                                                      "vertical_input": "load" if loaded else "position"}, steps, 5e-3)
    swing = max(r["Fz"] for r in native) - min(r["Fz"] for r in native)
    assert swing > 300.0  # the cleat is felt
    shared = native[0].keys() & python[0].keys()
    assert {"Fx", "Fz", "My", "kappa", "rho", "Rl", "Re", "road_w", "road_slope", "x_road", "Mx_c", "My_c", "trail",
            "mux", "contact_width", "Vsx", "omega_used", "Fx_c", "x_contact", "road_curvature"} <= shared
    for i, (a, b) in enumerate(zip(native, python)):
        for name in shared:
            scale = 1e-6 * (swing if name[0] in "FM" else 1.0)
            assert a[name] == pytest.approx(b[name], rel=1e-6, abs=scale), (i, name)
    assert math.isclose(native[-1]["x_road"], 10.0 * 0.15, rel_tol=1e-9)


def test_both_backends_give_the_same_swift_run_with_turn_slip(fmus, tmp_path):
    """--turn-slip, SWIFT: a lateral step (vy 0 -> 0.5 m/s at 10 m/s) that yaws the belt, then the 10 mm cleat, in
    5 ms communication steps: both backends step the same ring with the contact patch's turn slip; without turn
    slip (the native FMU built without it) the side force and the aligning moment are others."""
    from mftyre import load_tir
    from mftyre.transient import free_rolling_start

    omega, z = free_rolling_start(load_tir(TIR62), 10.0)
    start = {"vx": 10.0, "omega": omega, "z": z}
    steps = [{}] * 4 + [{"vy": 0.5}] * 26  # 0.15 s: over the cleat at 0.8 m
    native = _run(fmus["native", "swift_ts"], tmp_path, start, steps, 5e-3)
    python = _run(fmus["pythonfmu", "swift_ts"], tmp_path, {**start, "road": CLEAT}, steps, 5e-3)
    plain = _run(fmus["native", "swift"], tmp_path, start, steps, 5e-3)
    swing = max(r["Fz"] for r in native) - min(r["Fz"] for r in native)
    assert swing > 300.0  # the cleat is felt
    shared = native[0].keys() & python[0].keys()
    assert {"Fx", "Fy", "Fz", "Mz", "Mz_c", "alpha", "kappa", "rho", "road_w", "trail", "muy", "Vsy"} <= shared
    for i, (a, b) in enumerate(zip(native, python)):
        for name in shared:
            scale = 1e-6 * (swing if name[0] in "FM" else 1.0)
            assert a[name] == pytest.approx(b[name], rel=1e-6, abs=scale), (i, name)
    assert max(abs(a["Fy"] - b["Fy"]) for a, b in zip(native, plain)) > 20.0
    assert max(abs(a["Mz"] - b["Mz"]) for a, b in zip(native, plain)) > 5.0


def test_pythonfmu_turn_slip_refuses_what_it_cannot_do(fmus, tmp_path, capsys):
    """Built with --turn-slip, the pythonfmu FMU has no rig mode (its slips are imposed: refused at build time and
    at initialisation) and its SWIFT model takes no yaw rate (the native SWIFT FMU has no such input: a step with
    yaw_rate != 0 is rejected, not run without it); --model transient stays a native model."""
    from fmpy.fmi1 import FMICallException

    from mftyre.fmu_command import register

    parser = argparse.ArgumentParser(prog="mftyre")
    register(parser.add_subparsers(dest="command"))
    for option, text in ((["--input-mode", "rig"], "--input-mode rig (slips and load imposed) has no turn slip"),
                         (["--model", "transient"], "--model transient is only available with --backend native")):
        out = tmp_path / "refused.fmu"
        ns = parser.parse_args(["fmu", "build", str(TIR61), "-o", str(out), "--backend", "pythonfmu", "--turn-slip",
                                *option])
        assert ns.func(ns) == 1 and text in capsys.readouterr().err and not out.exists()

    s = Slave(fmus["pythonfmu", "steady_ts"], tmp_path, initialise=False)
    with pytest.raises(FMICallException):
        s.initialise({"input_mode": "rig"})
    assert any("initialisation failed: parameter input_mode='rig' has no turn slip" in m for _, m in s.messages)
    # No call after fmi2Fatal (FMI 2.0, 2.1.3: the instance may not be used again, not even freed): pythonfmu 0.7.0's
    # fmi2FreeInstance after a failed initialisation leaves the host's Python heap corrupt (a segfault at the next
    # garbage collection, which took the test worker down). fmpy.simulate_fmu does not free after an error either.

    from mftyre import load_tir
    from mftyre.transient import free_rolling_start

    omega, z = free_rolling_start(load_tir(TIR62), 10.0)
    s = Slave(fmus["pythonfmu", "swift_ts"], tmp_path, start={"vx": 10.0, "omega": omega, "z": z})
    s.fmu.doStep(0.0, 5e-3)
    good = s.get("Fx", "Fy", "Fz", "x_road")
    s.set(yaw_rate=0.3)
    with pytest.raises(FMICallException, match="discard"):
        s.fmu.doStep(5e-3, 5e-3)
    assert s.get("Fx", "Fy", "Fz", "x_road") == good and s.status() == 1
    assert "yaw_rate=0.3 (the SWIFT wheel frame does not yaw" in s.messages[-1][1]
    s.set(yaw_rate=0.0)
    s.fmu.doStep(5e-3, 5e-3)
    assert s.status() == 0
    s.close()
