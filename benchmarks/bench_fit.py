"""Wall time of full staged fits (all stages, pressure terms) on one core, each against a baseline measured in the
same run: one evaluation of the model over the same rows (the unit cost of a residual), and the target of issue 11.

    python benchmarks/bench_fit.py [--tir FILE.tir] [--compare]

Cases:

* ``rig 100 Hz``: :func:`mftyre.rig.rig_programme` of the tyre, about 60 000 samples at 100 Hz (4 loads x 3
  pressures x 3 cambers, slip-angle, slip-ratio and combined sweeps, speed and load sweeps, realistic AR(1)
  noise, relaxation hysteresis, friction drift, load scatter), seed 1; reduced per sweep before fitting. Target
  60 s.
* ``points 5k``: :func:`mftyre.data.trailer_programme`, about 5 000 points (4 loads x 3 pressures x 3 cambers,
  65 points per sweep, realistic noise), seed 1, fitted point by point. Target 15 s.

Both fits start from generic values (:func:`mftyre.fit.start_parameters`). The accuracy against the noise-free
tyre on a check grid is printed too. ``--compare`` adds the lower/upper-bound pressure comparison. BLAS is
pinned to one thread.
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
from mftyre.rig import rig_programme  # noqa: E402

from timing import best_time  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TARGETS = {"rig 100 Hz": 60.0, "points 5k": 15.0}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tir_files" / "car_205_60R15_mf61.tir"))
    ap.add_argument("--compare", action="store_true", help="also run the lower/upper-bound comparison")
    args = ap.parse_args()
    truth = mftyre.load_tir(args.tir)
    cases = {
        "rig 100 Hz": rig_programme(truth, loads=(0.45, 0.8, 1.15, 1.5), pressures=(0.86, 1.0, 1.14),
                                    slip_angle_rate_deg=12.0, slip_ratio_rate=0.2, seed=1),
        "points 5k": trailer_programme(truth, loads=(0.45, 0.8, 1.15, 1.5), pressures=(0.85, 1.0, 1.15),
                                       cambers_deg=(-3.0, 0.0, 3.0), points=65, noise=1.0, seed=1),
    }
    print(f"{'case':<12} {'rows':>7} {'fitted':>7} {'eval [ms]':>10} {'fit [s]':>8} {'x eval':>8} "
          f"{'x target':>9}  check grid (normalised RMS vs noise-free tyre)")
    for name, data in cases.items():
        inputs = data.inputs()
        base = best_time(lambda: truth.evaluate(**inputs), 3)
        t0 = time.perf_counter()
        result = fit_tir(data, compare=args.compare)
        wall = time.perf_counter() - t0
        err = _check_grid(result.model, truth)
        print(f"{name:<12} {len(data):7d} {len(result.data):7d} {base * 1e3:10.1f} {wall:8.1f} {wall / base:8.0f} "
              f"{wall / TARGETS[name]:9.2f}  " + ", ".join(f"{k} {v:.2f} %" for k, v in err.items()))
        rejected = {n: st.rejected for n, st in result.stages.items() if st.rejected}
        if rejected:
            print(f"{'':12} rejected stages: {rejected}")
        print(f"{'':12} per stage [s]: " + ", ".join(f"{n} {st.seconds:.1f}" for n, st in result.stages.items()))


def _check_grid(model, truth) -> dict:
    prm = truth.params
    fz0, p0 = prm.FNOMIN, prm.NOMPRES
    loads, press = np.array([0.5, 1.0, 1.5]) * fz0, np.array([0.87, 1.0, 1.13]) * p0
    F, P, G, A = np.meshgrid(loads, press, np.radians([-3.0, 0.0, 3.0]), np.radians(np.linspace(-12, 12, 25)),
                             indexing="ij")
    a, b = model.evaluate(F, 0.0, A, G, p=P), truth.evaluate(F, 0.0, A, G, p=P)
    F2, P2, K = np.meshgrid(loads, press, np.linspace(-0.2, 0.2, 21), indexing="ij")
    c, d = model.evaluate(F2, K, 0.0, p=P2), truth.evaluate(F2, K, 0.0, p=P2)
    F3, V = np.meshgrid(loads, np.linspace(1.0, 40.0, 14), indexing="ij")
    e, f = model.evaluate(F3, 0.0, 0.0, vx=V), truth.evaluate(F3, 0.0, 0.0, vx=V)
    return dict(Fx=normalised_rms(c.fx, d.fx), Fy=normalised_rms(a.fy, b.fy), Mz=normalised_rms(a.mz, b.mz),
                Mx=normalised_rms(a.mx, b.mx), My=normalised_rms(e.my, f.my), RL=normalised_rms(e.rl, f.rl))


if __name__ == "__main__":
    main()
