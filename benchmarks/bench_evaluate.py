"""Throughput and latency of MFModel.evaluate (every output), against a baseline measured in the same run.

    python benchmarks/bench_evaluate.py [--tir FILE.tir] [--sizes 1000,10000,100000,1000000] [--repeat 5]

Baseline: the bare pure-slip Magic Formula Fy = D sin(C atan(B a - E (B a - atan(B a)))) with fixed
coefficients on the same NumPy arrays: six transcendental/arithmetic array passes, the cost floor of any
NumPy Magic Formula. The ratio says how many such passes the full model (combined slip, Mx, My, Mz,
radii, patch, stiffnesses, relaxation lengths; 29 outputs) costs. Single-point latency is compared with the
same bare formula evaluated on Python floats. Timings are the best of ``--repeat`` runs, on one core
(the script pins BLAS threads to 1; NumPy ufuncs are single-threaded).
"""
from __future__ import annotations

import argparse
import os
import tracemalloc
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import math  # noqa: E402  (baseline only)

import numpy as np  # noqa: E402

import mftyre  # noqa: E402

from timing import best_time  # noqa: E402  (benchmarks/timing.py)

ROOT = Path(__file__).resolve().parents[1]


def baseline_numpy(alpha, fz):
    B, C, D, E = 10.0, 1.3, 1.0 * fz, -0.5
    ba = B * alpha
    return D * np.sin(C * np.arctan(ba - E * (ba - np.arctan(ba))))


def baseline_scalar(alpha, fz):
    B, C, D, E = 10.0, 1.3, 1.0 * fz, -0.5
    ba = B * alpha
    return D * math.sin(C * math.atan(ba - E * (ba - math.atan(ba))))




def inputs(model, n, seed=0):
    prm = model.params
    rng = np.random.default_rng(seed)
    return dict(fz=rng.uniform(0.25, 2.0, n) * prm.FNOMIN, kappa=rng.uniform(-0.3, 0.3, n),
                alpha=rng.uniform(-0.3, 0.3, n), gamma=rng.uniform(-0.05, 0.05, n),
                vx=rng.uniform(5.0, 35.0, n), p=rng.uniform(prm.PRESMIN, prm.PRESMAX, n))  # inside the .tir range


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", action="append", help="property file(s); default: the two sample files")
    ap.add_argument("--sizes", default="1000,10000,100000,1000000")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    files = args.tir or [ROOT / "tir_files" / "car_205_60R15_mf61.tir", ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir"]
    sizes = [int(s) for s in args.sizes.split(",")]
    for path in files:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = mftyre.load_tir(path)
        print(f"\n{Path(path).name} (FITTYP {model.params.fittyp}): full output set, {len(mftyre.model.OUTPUT_UNITS)} outputs")
        print(f"{'points':>9} {'model [ms]':>11} {'[us/pt]':>9} {'baseline [ms]':>14} {'ratio':>7} {'peak MB':>8}")
        for n in sizes:
            x = inputs(model, n)
            model.evaluate(**{k: v[:10] for k, v in x.items()})  # warm-up
            t_model = best_time(lambda: model.evaluate(**x), args.repeat if n <= 100_000 else max(1, args.repeat // 2))
            t_base = best_time(lambda: baseline_numpy(x["alpha"], x["fz"]), args.repeat)
            tracemalloc.start()
            model.evaluate(**x)
            peak = tracemalloc.get_traced_memory()[1] / 1e6
            tracemalloc.stop()
            print(f"{n:>9} {t_model * 1e3:>11.2f} {t_model / n * 1e6:>9.3f} {t_base * 1e3:>14.3f} "
                  f"{t_model / t_base:>7.1f} {peak:>8.0f}")
        one = {k: float(v[0]) for k, v in inputs(model, 1).items()}
        reps = 2000
        t_single = best_time(lambda: [model.evaluate(**one) for _ in range(reps)], 3) / reps
        t_scalar = best_time(lambda: [baseline_scalar(one["alpha"], one["fz"]) for _ in range(reps)], 3) / reps
        print(f"single point: {t_single * 1e6:.1f} us (bare scalar formula {t_scalar * 1e6:.2f} us, "
              f"ratio {t_single / t_scalar:.0f})")


if __name__ == "__main__":
    main()
