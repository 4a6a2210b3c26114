"""CasADi evaluation against NumPy: single-point latency and batch throughput, measured side by side.

    python benchmarks/bench_casadi.py [--tir FILE.tir] [--n 100000] [--repeat 5]

Rows: NumPy ``MFModel.evaluate`` (the baseline of every ratio), the CasADi SX function on its virtual machine
(``f(...)`` per point, ``f.map(n)`` per batch), and the C code generated from it and compiled
(``mftyre.compiled``: ctypes call of the point function, and of its 256-point map in a loop). All outputs
(29) are evaluated in every row. The compile time of the first (uncached) build is printed too.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import mftyre  # noqa: E402
from mftyre.compiled import compile_model  # noqa: E402

from timing import best_time  # noqa: E402  (benchmarks/timing.py)

ROOT = Path(__file__).resolve().parents[1]




def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", action="append")
    ap.add_argument("--n", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    files = args.tir or [ROOT / "tir_files" / "car_205_60R15_mf61.tir", ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir"]
    for path in files:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = mftyre.load_tir(path)
        prm = model.params
        f = model.casadi_function()
        with tempfile.TemporaryDirectory() as cache:
            t0 = time.perf_counter()
            compiled = compile_model(model, directory=cache)
            t_compile = time.perf_counter() - t0
            point = (prm.FNOMIN, 0.02, 0.05, 0.01, 0.0, 20.0, prm.NOMPRES)
            reps = 5000
            t_np = best_time(lambda: [model.evaluate(*point[:5], vx=point[5], p=point[6]) for _ in range(200)], 3) / 200
            t_vm = best_time(lambda: [f(*point) for _ in range(reps)], 3) / reps
            t_c = best_time(lambda: [compiled(*point) for _ in range(reps)], 3) / reps

            n = args.n
            rng = np.random.default_rng(0)
            x = [rng.uniform(0.25, 2, n) * prm.FNOMIN, rng.uniform(-0.3, 0.3, n), rng.uniform(-0.3, 0.3, n),
                 rng.uniform(-0.05, 0.05, n), np.zeros(n), rng.uniform(5, 35, n), rng.uniform(0.8, 1.2, n) * prm.NOMPRES]
            fmap = f.map(n)
            xrow = [v[None, :] for v in x]
            b_np = best_time(lambda: model.evaluate(*x[:5], vx=x[5], p=x[6]), args.repeat)
            b_vm = best_time(lambda: fmap(*xrow), max(1, args.repeat // 2))
            b_c = best_time(lambda: compiled.batch(*x), args.repeat)
        print(f"\n{Path(path).name} (FITTYP {prm.fittyp}); compile (uncached): {t_compile:.2f} s")
        print(f"{'':28}{'single point [us]':>18}{'ratio':>8}{'batch [us/pt]':>16}{'ratio':>8}")
        for label, t1, tb in (("NumPy evaluate (baseline)", t_np, b_np), ("CasADi SX virtual machine", t_vm, b_vm),
                              ("compiled C (ctypes)", t_c, b_c)):
            print(f"{label:28}{t1 * 1e6:>18.2f}{t1 / t_np:>8.3f}{tb / n * 1e6:>16.3f}{tb / b_np:>8.2f}")


if __name__ == "__main__":
    main()
