"""Compiled C (mftyre.compiled) against NumPy MFModel.evaluate, every output, measured side by side in one run.

    python benchmarks/bench_casadi.py [--tir FILE.tir] [--sizes 1000,10000,100000] [--repeat 5] [--fresh] [--cpu]

Columns: one point (microseconds per call from Python: ``model.evaluate(...)`` on floats, ``compiled(...)``)
and batches of 1e3, 1e4, 1e5 points (nanoseconds per point: ``model.evaluate`` on arrays,
``compiled.batch``). Rows: NumPy (the baseline of every ratio), compiled C on one core, compiled C with
``threads=0`` (every core). All 29 outputs in every row, inputs drawn at random inside the .tir ranges.
Targets (issue 10): compiled batch <= 150 ns/point MF 6.1, <= 300 ns/point MF 6.2 on one core; a single point <=
2 us; NumPy 1e5 batch <= 500 ns/point MF 6.1, <= 800 MF 6.2 (printed with their ratios, measured/target; issue 24 asks
for a 10 % margin: ratio <= 0.90, marked "margin met"). Files: the two samples and, when ../shared is beside the
checkout, its MF 6.2 file whose vertical relation uses the side-force term. Libraries come from the compile cache
(``--fresh``: a new temporary cache, compile time shown).
``--cpu``: the one-core rows in thread CPU time (see timing.py; on a busy shared machine a 1e5-point run is
always interrupted and its wall time overstates the cost), the threads row always in wall time.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import mftyre  # noqa: E402
from mftyre.compiled import compile_model  # noqa: E402

from timing import best_time  # noqa: E402  (benchmarks/timing.py)
#: NumPy evaluate at the largest size (1e5), one core: ns/point (issue 10)
NUMPY_TARGET_NS = {"61": 500.0, "62": 800.0}

ROOT = Path(__file__).resolve().parents[1]
TARGET_NS = {"61": 150.0, "62": 300.0}
POINT_TARGET_US = 2.0  # one point, compiled, every output
MARGIN = 0.90  # issue 24: every speed target met with >= 10 % to spare on a loaded machine
#: an MF 6.2 file whose vertical relation uses the side-force term (the dearer loaded-radius solve), when ../shared
#: is beside the checkout
TNO_MF62 = ROOT.parent / "shared" / "reference" / "tir" / "TNO_car205_60R15.tir"


def inputs(model, n, seed=0):
    prm = model.params
    rng = np.random.default_rng(seed)
    return [rng.uniform(0.25, 2.0, n) * prm.FNOMIN, rng.uniform(-0.3, 0.3, n), rng.uniform(-0.3, 0.3, n),
            rng.uniform(-0.05, 0.05, n), np.zeros(n), rng.uniform(5.0, 35.0, n), rng.uniform(0.9, 1.1, n) * prm.NOMPRES]


def _verdict(measured, target):
    """``(ratio r, met / NOT met, 10 % margin met / NOT)``: measured/target, and the margin issue 24 asks for."""
    ratio = measured / target
    return (f"(ratio {ratio:.2f}, {'met' if ratio <= 1.0 else 'NOT met'}, "
            f"{'10 % margin met' if ratio <= MARGIN else '10 % margin NOT met'})")


def _repeat(call, times):
    """``times`` calls, each result dropped at once (as a caller would use it)."""
    for _ in range(times):
        call()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", action="append")
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--fresh", action="store_true", help="compile into a new temporary cache (shows compile time)")
    ap.add_argument("--cpu", action="store_true", help="one-core rows in thread CPU time instead of wall time")
    args = ap.parse_args(argv)
    samples = ("car_205_60R15_mf61.tir", "car_205_60R15_mf62_swift.tir")
    files = args.tir or [ROOT / "tir_files" / name for name in samples] + [p for p in [TNO_MF62] if p.is_file()]
    sizes = [int(s) for s in args.sizes.split(",")]
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    fresh = tempfile.TemporaryDirectory() if args.fresh else None
    header = f"{'':34}{'1 point [us]':>13}" + "".join(f"{f'{n:.0e} [ns/pt]':>15}" for n in sizes)
    for path in files:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = mftyre.load_tir(path)
        version = model.params.version
        t0 = time.perf_counter()
        compiled = compile_model(model, directory=fresh.name if fresh else None)
        t_compile = time.perf_counter() - t0
        one = [float(v[0]) for v in inputs(model, 1, seed=1)]
        reps = 5000
        cpu = args.cpu
        t_np1 = best_time(lambda: _repeat(lambda: model.evaluate(*one[:5], vx=one[5], p=one[6]), 50), 3, cpu) / 50
        t_c1 = best_time(lambda: _repeat(lambda: compiled(*one), reps), 2 * args.repeat, cpu) / reps
        rows = {"NumPy evaluate (baseline)": [t_np1 * 1e6], "compiled C, 1 core": [t_c1 * 1e6],
                f"compiled C, threads=0 ({cores} cores)": [None]}
        for n in sizes:
            x = inputs(model, n)
            repeat = args.repeat if n <= 10_000 else max(2, args.repeat // 2)
            rows["NumPy evaluate (baseline)"].append(best_time(lambda: model.evaluate(*x[:5], vx=x[5], p=x[6]),
                                                               repeat, cpu) / n * 1e9)
            # the compiled rows are cheap: more repeats, so that a busy machine disturbs them less
            rows["compiled C, 1 core"].append(best_time(lambda: compiled.batch(*x), 3 * args.repeat, cpu) / n * 1e9)
            rows[f"compiled C, threads=0 ({cores} cores)"].append(
                best_time(lambda: compiled.batch(*x, threads=0), 3 * args.repeat) / n * 1e9)
        base = rows["NumPy evaluate (baseline)"]
        entry = "C entry" if getattr(compiled, "fast_point", False) else "ctypes"
        print(f"\n{Path(path).name} (MF {version[0]}.{version[1:]}), all {len(compiled.outputs)} outputs; "
              f"compile {'(fresh)' if fresh else '(or cache)'}: {t_compile:.1f} s; one-core rows in "
              f"{'thread CPU' if cpu else 'wall'} time; one point through the {entry}")
        print(header)
        for label, values in rows.items():
            first = f"{values[0]:>13.2f}" if values[0] else f"{'':>13}"
            print(f"{label:34}{first}" + "".join(f"{v:>15.0f}" for v in values[1:]))
            if label != "NumPy evaluate (baseline)":
                first = f"{base[0] / values[0]:>13.0f}" if values[0] else f"{'':>13}"
                print(f"{'  speed-up over NumPy':34}{first}"
                      + "".join(f"{b / v:>15.1f}" for b, v in zip(base[1:], values[1:])))
        numpy_target = NUMPY_TARGET_NS.get(version)
        if numpy_target:
            print(f"NumPy target: batch <= {numpy_target:.0f} ns/pt -> {base[-1]:.0f} ns/pt at {sizes[-1]:.0e} "
                  f"{_verdict(base[-1], numpy_target)}")
        c1 = rows["compiled C, 1 core"]
        target = TARGET_NS.get(version)
        if target:
            print(f"targets: batch <= {target:.0f} ns/pt on one core -> {c1[-1]:.0f} ns/pt at {sizes[-1]:.0e} "
                  f"{_verdict(c1[-1], target)}; single point <= {POINT_TARGET_US:.0f} us -> {c1[0]:.2f} us "
                  f"{_verdict(c1[0], POINT_TARGET_US)}")
    if fresh:
        fresh.cleanup()


if __name__ == "__main__":
    main()
