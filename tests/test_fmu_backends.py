"""Both FMU backends (native C and the pythonfmu slave) are translations of one wheel: they speak one vocabulary
(mftyre.variables.WHEEL: a name has one unit and causality in both) and, driven by fmpy with the same inputs in
the same mode, give the same outputs. Modes: steady with the load imposed, steady on a rig (load and slips
imposed), SWIFT with axle height and spin imposed over a cleat.

What the backends do not share is pinned below (ONLY_NATIVE: nothing left; ONLY_PYTHONFMU: the pythonfmu FMU is
one FMU for every mode, so it has the other modes' variables), so that a new gap shows here."""
from __future__ import annotations

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
ONLY_NATIVE = {"steady": set(), "rig": set(), "swift": set(), "swift_load_torque": set()}
#: pythonfmu: one FMU for every mode (String parameters choose), so its extra variables are the other modes' too.
ONLY_PYTHONFMU = {"vy", "omega", "z", "vz", "road_z", "torque", "kappa_in", "alpha_in", "Fz_in", "axle_mass",
                  "mu_scale", "u_x", "u_y", "Fx_c", "Fy_c", "road_curvature", "Re_variation", "road_camber_eff",
                  "x_contact",
                  "x_start", "max_step", "Vsx", "Vsy", "omega_used", "contact_width", "Fz_c", "road_w", "road_slope",
                  "x_road", "Mx_c", "My_c", "trail", "mux", "muy"}


@pytest.fixture(scope="module")
def fmus(built_fmu):
    builds = {  # the pythonfmu steady and swift FMUs and the native steady one are test_fmu's and test_fmu_swift's
        ("native", "steady"): [TIR61, "--vertical", "load"],
        ("native", "rig"): [TIR61, "--input-mode", "rig"],
        ("native", "swift"): [TIR62, "--model", "swift", "--road", CLEAT],
        ("native", "swift_load_torque"): [TIR62, "--model", "swift", "--road", CLEAT, "--vertical", "load", "--rim",
                                          "torque"],
        ("pythonfmu", "steady"): [TIR61, "--backend", "pythonfmu", "--vertical", "load"],
        ("pythonfmu", "swift"): [TIR62, "--backend", "pythonfmu", "--model", "swift", "--vertical", "position"],
    }
    paths = {key: built_fmu(*args) for key, args in builds.items()}
    paths["pythonfmu", "rig"] = paths["pythonfmu", "steady"]  # one FMU, input_mode chosen at run time
    paths["pythonfmu", "swift_load_torque"] = paths["pythonfmu", "swift"]  # vertical_input, rim chosen at run time
    return paths


def _variables(path):
    return {v.name: v for v in fmpy.read_model_description(path).modelVariables if v.type == "Real"}


@pytest.mark.parametrize("mode", ["steady", "rig", "swift", "swift_load_torque"])
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


def _steady_inputs(rng, n, rig):
    for _ in range(n):
        row = {"vx": rng.uniform(-30, 30), "gamma": rng.uniform(-0.05, 0.05), "p": rng.uniform(1.9e5, 2.5e5),
               "Fz_in": rng.uniform(500, 8000)}
        if rig:
            row.update(kappa_in=rng.uniform(-0.3, 0.3), alpha_in=rng.uniform(-0.2, 0.2))
        else:
            row.update(vy=rng.uniform(-2, 2), omega=row["vx"] / 0.3 * rng.uniform(0.9, 1.1))
        yield row


@pytest.mark.parametrize("mode", ["steady", "rig"])
def test_both_backends_give_the_same_steady_results(fmus, tmp_path, mode):
    rng = np.random.default_rng(22)
    steps = list(_steady_inputs(rng, 12, mode == "rig"))
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
