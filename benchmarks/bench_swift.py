"""SWIFT real-time factor: a 2 s cleat run (10 x 50 mm cleat, 40 km/h, fixed axle height, 4 kN) with 1 kHz
output, on one core, side by side:

    python benchmarks/bench_swift.py [--tir FILE.tir] [--repeat 5]

Rows: ``SwiftTyre.run`` (compiled C, 10 steps per call: the simulation loop), the FMU-style loop of single
``SwiftTyre.step`` calls (compiled), and the same equations on the CasADi virtual machine (not compiled, a
0.1 s run scaled to 2 s). Real-time factor = simulated time / wall time; the ratios are against the compiled
run. Compilation (cached after the first build) and the static initialisation are printed separately.
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import mftyre  # noqa: E402
from swift import Cleat, StepInputs, SwiftTyre  # noqa: E402

from timing import best_time  # noqa: E402  (benchmarks/timing.py)

ROOT = Path(__file__).resolve().parents[1]




def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    model = mftyre.load_tir(args.tir)
    V, t_end, dt = 40 / 3.6, 2.0, 1e-3
    rl, _ = model.loaded_radius(4000.0)
    t0 = time.perf_counter()
    tyre = SwiftTyre(model, Cleat(1.0, 0.05, 0.01), axle="height", rim="speed", x_range=(0.0, 24.0))
    t_build = time.perf_counter() - t0
    u = StepInputs(x=0.0, vx=V, z=float(rl), omega=V / 0.3044)
    t_init = best_time(lambda: tyre.initial_state(u), args.repeat)
    t_run = best_time(lambda: tyre.run(t_end, u, dt), args.repeat)

    def step_loop():
        s = tyre.initial_state(u)
        for k in range(int(t_end / dt)):
            s, _ = tyre.step(s, StepInputs(x=V * k * dt, vx=V, z=float(rl), omega=V / 0.3044), dt)

    t_step = best_time(step_loop, max(1, args.repeat // 2))
    vm = SwiftTyre(model, Cleat(1.0, 0.05, 0.01), axle="height", rim="speed", x_range=(0.0, 24.0), compiled=False)
    t_vm = best_time(lambda: vm.run(0.1, u, dt), 1) * (t_end / 0.1)
    print(f"SWIFT cleat run, {t_end:.0f} s simulated, output every {dt * 1e3:.0f} ms, RK4 with "
          f"{tyre.substeps} substeps ({dt / tyre.substeps * 1e3:.2f} ms), one core")
    print(f"  build + compile (cached after the first time): {t_build:.2f} s; static initialisation "
          f"{t_init * 1e3:.1f} ms (included in the rows below)")
    print(f"{'row':44s} {'wall [ms]':>10s} {'real-time factor':>17s} {'time / compiled run':>20s}")
    for name, t in (("run(): compiled, 10 steps per call", t_run), ("step() loop: compiled, FMU-style", t_step),
                    ("run(): CasADi VM, not compiled", t_vm)):
        print(f"{name:44s} {t * 1e3:10.1f} {t_end / t:17.1f} {t / t_run:20.2f}")
    for name, t in (("run()", t_run), ("step() loop", t_step)):
        print(f"target: real-time factor >= 100 for {name}: {'met' if t_end / t >= 100 else 'NOT met'}")
    return np.array([t_run, t_step, t_vm])


if __name__ == "__main__":
    main()
