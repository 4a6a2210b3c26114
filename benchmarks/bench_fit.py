"""Wall time of a full staged fit (all stages, pressure terms) on about 40 000 trailer points, against a baseline
measured in the same run: one evaluation of the model over the same points (the unit cost of a residual).

    python benchmarks/bench_fit.py [--tir FILE.tir] [--points-per-sweep 321] [--compare]

The data: :func:`mftyre.data.trailer_programme` of the tyre (5 loads x 3 pressures x 5 cambers, realistic noise,
seed 1). The fit starts from generic values (:func:`mftyre.fit.start_parameters`). ``--compare`` adds the
lower/upper-bound pressure comparison (another 1 + 3 fits of pure Fx, Fy, Mz). BLAS is pinned to one thread.
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import mftyre  # noqa: E402
from mftyre.data import trailer_programme  # noqa: E402
from mftyre.fit import fit_tir, normalised_rms  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tir_files" / "car_205_60R15_mf61.tir"))
    ap.add_argument("--points-per-sweep", type=int, default=321)
    ap.add_argument("--compare", action="store_true", help="also run the lower/upper-bound comparison")
    args = ap.parse_args()
    truth = mftyre.load_tir(args.tir)
    data = trailer_programme(truth, loads=(0.4, 0.7, 1.0, 1.3, 1.6), pressures=(0.85, 1.0, 1.15),
                             cambers_deg=(-4.0, -2.0, 0.0, 2.0, 4.0), points=args.points_per_sweep, noise=1.0, seed=1)
    inputs = data.inputs()
    best = min(_timed(lambda: truth.evaluate(**inputs)) for _ in range(3))
    print(f"data: {len(data)} points; baseline: one model evaluation over all points {best * 1e3:.1f} ms")
    t0 = time.perf_counter()
    result = fit_tir(data, compare=args.compare)
    wall = time.perf_counter() - t0
    evals = sum(res.nfev for st in result.stages.values() for _, res in st.passes)
    print(f"full staged fit{' with pressure comparison' if args.compare else ''}: {wall:.1f} s wall "
          f"= {wall / best:.0f} x baseline; {evals} residual evaluations of the stage data (main fit)")
    for name, st in result.stages.items():
        print(f"  {name:<15} {st.n_points:6d} points {len(st.fitted):3d} parameters {st.seconds:6.1f} s  "
              f"fit error {st.fit_error:.3f} %")
    if result.comparison is not None:
        print(result.comparison[["stage", "lower", "upper", "extended", "recovered"]].round(3).to_string(index=False))
    F, P, A = np.meshgrid([2000.0, 4000.0, 6000.0], [1.9e5, 2.2e5, 2.5e5], np.radians(np.linspace(-12, 12, 49)),
                          indexing="ij")
    a, b = result.model.evaluate(F, 0.0, A, p=P), truth.evaluate(F, 0.0, A, p=P)
    print(f"check grid: Fy {normalised_rms(a.fy, b.fy):.3f} %, Mz {normalised_rms(a.mz, b.mz):.3f} %")


def _timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
