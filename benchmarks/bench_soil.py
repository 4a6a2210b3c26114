"""Throughput of the soft-soil model (SoftSoilTyre.evaluate, every output) beside MFModel.evaluate of the same
operating points on hard ground, measured in the same run.

    python benchmarks/bench_soil.py [--tir FILE.tir] [--soil NAME] [--sizes 10000,100000] [--repeat 3] [--load-max 1.5]
                                    [--cpu]

Target: 1e5 operating points in under a second. The points are random loads, slips, slip angles and pressures
over the tyre's range (soil slip i and MF kappa = i / (1 - i) describe the same wheel spin). Timings are the best
of ``--repeat`` runs on one core (BLAS threads pinned to 1); ``--cpu`` takes the thread's CPU time instead of the
wall time (steadier on a shared machine).
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from mftyre.soil import SoftSoilTyre  # noqa: E402

from timing import best_time  # noqa: E402  (benchmarks/timing.py)

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tir", default=str(ROOT / "tir_files" / "agri_460_85R34_mf61.tir"))
    parser.add_argument("--soil", default="sandy_loam")
    parser.add_argument("--sizes", default="10000,100000")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--load-max", type=float, default=1.5,
                        help="largest load as a multiple of FNOMIN (lower it for soils the tyre sinks into)")
    parser.add_argument("--cpu", action="store_true", help="time with the thread's CPU time (see timing.py)")
    args = parser.parse_args()
    tyre = SoftSoilTyre(args.tir, args.soil)
    prm = tyre.params
    print(f"{Path(args.tir).name} on {args.soil}; best of {args.repeat} ({'CPU' if args.cpu else 'wall'} time)")
    print(f"{'points':>8} {'soil [s]':>9} {'MF [s]':>8} {'soil/MF':>8} {'soil us/pt':>11} {'< 1 s for 1e5':>14}")
    for n in (int(s) for s in args.sizes.split(",")):
        rng = np.random.default_rng(0)
        fz = rng.uniform(0.2, args.load_max, n) * prm.FNOMIN
        slip = rng.uniform(-0.3, 0.8, n)
        alpha = rng.uniform(-0.15, 0.15, n)
        p = rng.uniform(1.0e5, 1.6e5, n)
        t_soil = best_time(lambda: tyre.evaluate(fz=fz, slip=slip, alpha=alpha, p=p, vx=2.0), args.repeat, args.cpu)
        t_mf = best_time(lambda: tyre.tyre.evaluate(fz=fz, kappa=slip / (1 - slip), alpha=alpha, p=p, vx=2.0),
                         args.repeat, args.cpu)
        verdict = ("yes" if t_soil * 1e5 / n < 1.0 else "no") if n >= 1e4 else "-"
        print(f"{n:>8} {t_soil:>9.3f} {t_mf:>8.3f} {t_soil / t_mf:>8.2f} {t_soil / n * 1e6:>11.2f} {verdict:>14}")


if __name__ == "__main__":
    main()
