"""SWIFT real-time factor: a 2 s cleat run (10 x 50 mm cleat, 40 km/h, fixed axle height, 4 kN) with 1 kHz
output, on one core, side by side:

    python benchmarks/bench_swift.py [--tir FILE.tir] [--repeat 5] [--against GIT_REF] [--cpu] [--turn-slip]

Rows: ``SwiftTyre.run`` (compiled C: the whole loop of steps in one call), the FMU-style loop of single
``SwiftTyre.step`` calls (compiled; one StepInputs per step, as a co-simulation master would pass them), and the
same equations on the CasADi virtual machine (not compiled, a 0.1 s run scaled to 2 s). Real-time factor =
simulated time / wall time (the static initialisation is included in the rows). ``--against REF``: the same rows
for the ``swift`` package of git ref REF (e.g. ``main``), timed alternately with the current code in the same run,
and the speed-up of the current code. ``--cpu``: thread CPU time instead of wall time (a busy shared machine disturbs
it far less). ``--turn-slip``: also a row of the current code with the contact patch's turn slip on (with
``--against``, of REF too, and its speed-up). Compilation (cached after the first build) is printed separately.
"""
from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys
import tarfile
import tempfile
import time
import warnings
from io import BytesIO
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import mftyre  # noqa: E402

from timing import best_time  # noqa: E402  (benchmarks/timing.py)

ROOT = Path(__file__).resolve().parents[1]
V, T_END, DT = 40 / 3.6, 2.0, 1e-3


def _swift_at(ref: str, directory: Path):
    """The ``swift`` package as it is at git ref ``ref``, imported under the name ``swift_<ref>``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", ref, "swift"], check=True,
                             capture_output=True).stdout
    name = "swift_" + "".join(c if c.isalnum() else "_" for c in ref)
    with tarfile.open(fileobj=BytesIO(archive)) as tar:
        tar.extractall(directory / "extract", filter="data")
    (directory / "extract" / "swift").rename(directory / name)
    sys.path.insert(0, str(directory))
    return importlib.import_module(name)


def _rows(swift, model, repeat: int, cpu: bool, **options):
    """Wall times [s]: build, run(), step() loop, CasADi VM run (scaled to T_END), functions to re-time them."""
    rl, _ = model.loaded_radius(4000.0)
    road = swift.Cleat(1.0, 0.05, 0.01)
    t0 = time.perf_counter()
    tyre = swift.SwiftTyre(model, road, axle="height", rim="speed", x_range=(0.0, 24.0), **options)
    t_build = time.perf_counter() - t0
    u = swift.StepInputs(x=0.0, vx=V, z=float(rl), omega=V / 0.3044)
    StepInputs = swift.StepInputs

    def step_loop():  # a co-simulation master: new inputs (floats) every step
        s, z, omega = tyre.initial_state(u), float(rl), V / 0.3044
        for k in range(int(round(T_END / DT))):
            s, _ = tyre.step(s, StepInputs(x=V * k * DT, vx=V, z=z, omega=omega), DT)

    vm = swift.SwiftTyre(model, road, axle="height", rim="speed", x_range=(0.0, 24.0), compiled=False, **options)
    vm.run(DT, u, DT)  # its graphs built (on first use since the compiled tyres share one parametric library)
    t_vm = best_time(lambda: vm.run(0.1, u, DT), 1, cpu) * (T_END / 0.1)
    return t_build, t_vm, (lambda: best_time(lambda: tyre.run(T_END, u, DT), repeat, cpu),
                           lambda: best_time(step_loop, repeat, cpu))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--against", metavar="GIT_REF", help="also time the swift package of this git ref (e.g. main)")
    ap.add_argument("--cpu", action="store_true", help="thread CPU time instead of wall time")
    ap.add_argument("--turn-slip", action="store_true", help="also the current code with turn slip (row 'turn slip')")
    args = ap.parse_args(argv)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    warnings.simplefilter("ignore", UserWarning)  # the sample file's unmodelled parameters
    model = mftyre.load_tir(args.tir)
    import swift

    variants = {"current": swift}
    with tempfile.TemporaryDirectory() as tmp:
        if args.against:
            variants[args.against] = _swift_at(args.against, Path(tmp))
        setups = {name: _rows(pkg, model, args.repeat, args.cpu) for name, pkg in variants.items()}
        if args.turn_slip:
            setups["turn slip"] = _rows(swift, model, args.repeat, args.cpu, turn_slip=True)
            if args.against:
                setups[f"{args.against} ts"] = _rows(variants[args.against], model, args.repeat, args.cpu,
                                                     turn_slip=True)
        times = {name: [np.inf, np.inf] for name in setups}
        for _ in range(2):  # alternate the variants, keep each one's best
            for name, (_, _, timers) in setups.items():
                times[name] = [min(a, timer()) for a, timer in zip(times[name], timers)]
    print(f"SWIFT cleat run, {T_END:.0f} s simulated, output every {DT * 1e3:.0f} ms, RK4 with 2 substeps "
          f"(0.50 ms), one core; real-time factor = simulated time / {'CPU' if args.cpu else 'wall'} time")
    print(f"{'code':12s} {'build [s]':>9s} {'run() [ms]':>11s} {'run() RTF':>10s} {'step() [ms]':>12s} "
          f"{'step() RTF':>11s} {'VM run RTF':>11s}")
    for name, (t_build, t_vm, _) in setups.items():
        t_run, t_step = times[name]
        print(f"{name:12s} {t_build:9.2f} {t_run * 1e3:11.1f} {T_END / t_run:10.1f} {t_step * 1e3:12.1f} "
              f"{T_END / t_step:11.1f} {T_END / t_vm:11.2f}")
    n_steps = T_END / DT
    for name in setups:
        t_run, t_step = times[name]
        print(f"{name}: per step (initialisation included) run() {t_run / n_steps * 1e6:.2f} us, step() loop "
              f"{t_step / n_steps * 1e6:.2f} us")
    if args.against:
        pairs = [("current", args.against, "")] + ([("turn slip", f"{args.against} ts", ", turn slip")]
                                                   if args.turn_slip else [])
        for new, old, what in pairs:
            (new_run, new_step), (old_run, old_step) = times[new], times[old]
            print(f"speed-up of the current code over {args.against}{what}: run() {old_run / new_run:.2f}x, "
                  f"step() loop {old_step / new_step:.2f}x")
    for row in ("current", "turn slip") if args.turn_slip else ("current",):
        t_run, t_step = times[row]
        for name, t in (("run()", t_run), ("step() loop", t_step)):
            print(f"target: real-time factor >= 100 for {name}{', turn slip' if row != 'current' else ''}: "
                  f"{'met' if T_END / t >= 100 else 'NOT met'}")
    return times


if __name__ == "__main__":
    main()
