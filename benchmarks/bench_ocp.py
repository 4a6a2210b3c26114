"""The minimum-time lane change (mftyre.lane_change) on four MF tyres against a simple 4-parameter tyre, per IPOPT
iteration, for every route CasADi offers, side by side in one run.

    python benchmarks/bench_ocp.py [--tir FILE.tir] [--intervals 30] [--repeat 3] [--jit]

Rows: tyre x route (see mftyre.lane_change: "sx" MX graph calling the SX tyre, "expand" one SX graph,
"external" compile_external(hessian=True), "external-expand" the same inside an expanded NLP (SX call nodes),
"external-fd" compile_external(hessian=False) under IPOPT's exact mode
(second derivatives by differences of the compiled Jacobian), "external-lbfgs" hessian=False with IPOPT's
limited-memory quasi-Newton, "jit" (--jit only: the expanded NLP compiled by CasADi's jit, minutes of gcc for the
MF tyre). Columns: iterations, CPU time of the solve in this thread (best of --repeat; IPOPT and the tyre run in
it), per iteration, its ratio to the simple tyre's fastest route, and the one-off build time (graph, compile or
cache). Target (issue 24): the MF tyre <= 1.15x the simple tyre per iteration on the fastest routes. Then where
the time per iteration goes (nlpsol's statistics per callback, IPOPT's own work) and the compiled MF tyre's own cost
per point (the tyre, its Jacobian, its second derivatives).
"""
from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from mftyre.lane_change import LaneChange  # noqa: E402

from timing import best_time  # noqa: E402  (benchmarks/timing.py)

ROOT = Path(__file__).resolve().parents[1]
TARGET_RATIO = 1.15


def _external_fd(problem):
    """The problem's tyre function with compile_external(hessian=False) under IPOPT's exact-Hessian mode."""
    from mftyre.compiled import compile_external

    def tyre_function(wheel, tyre, route):
        return compile_external(problem.tyres[wheel], ("fz", "kappa", "alpha", "vx", "p"), ("fx", "fy", "mz"),
                                hessian=False, name=f"mf_{wheel}", limits="smooth", smooth=True)
    return tyre_function


def _callbacks(stats, solve):
    """(Hessian, constraint Jacobian, other callbacks, the rest of ``solve``) in seconds, from nlpsol's stats."""
    hessian, jacobian = stats.get("t_proc_nlp_hess_l", 0.0), stats.get("t_proc_nlp_jac_g", 0.0)
    other = sum(v for k, v in stats.items() if k.startswith("t_proc_nlp_")) - hessian - jacobian
    return hessian, jacobian, other, max(solve - hessian - jacobian - other, 0.0)


def _kernels(problem):
    """The compiled MF tyre alone (route "external"): thread CPU time per point of the tyre, its Jacobian and its
    second derivatives (Jacobian of the adjoint), each mapped over the problem's 4 x (intervals + 1) points."""
    import casadi as ca
    import numpy as np

    tyre = problem._tyre_function("FL", "mf", "external")
    n = 4 * (problem.intervals + 1)
    rng = np.random.default_rng(0)
    lo, hi = problem.pressure_bounds
    x = [rng.uniform(2500.0, 5500.0, n), rng.uniform(-0.1, 0.1, n), rng.uniform(-0.2, 0.2, n),
         rng.uniform(10.0, 25.0, n), rng.uniform(lo, hi, n)]
    print(f"\nthe compiled MF tyre over {n} points (thread CPU time, per point):")
    for label, function in (("tyre (fx, fy, mz)", tyre), ("Jacobian", tyre.jacobian()),
                            ("Jacobian of the adjoint (Hessian)", tyre.reverse(1).jacobian())):
        mapped = function.map(n)
        args = [ca.DM(v).T for v in x] + [ca.DM.ones(1, n)] * (function.n_in() - len(x))
        t = best_time(lambda: mapped(*args), 5, cpu=True)
        print(f"  {label:36}{1e6 * t / n:>7.2f} us  ({1e3 * t:.2f} ms for all)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tir_files" / "car_205_60R15_mf61.tir"))
    ap.add_argument("--intervals", type=int, default=30)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--jit", action="store_true", help="also the jit route (minutes of gcc)")
    args = ap.parse_args(argv)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        problem = LaneChange.from_tir(args.tir, intervals=args.intervals)
    routes = {"simple": ["expand", "sx"] + (["jit"] if args.jit else []),
              "mf": ["external", "expand", "sx", "external-expand", "external-fd", "external-lbfgs"]
              + (["jit"] if args.jit else [])}
    rows = []
    for tyre, names in routes.items():
        for route in names:
            t0 = time.perf_counter()
            original = problem._tyre_function
            if route == "external-fd":
                problem._tyre_function = _external_fd(problem)
            try:
                solver, arguments, unpack = problem.build(tyre, "external" if route == "external-fd" else route)
            finally:
                problem._tyre_function = original
            build = time.perf_counter() - t0
            solve = best_time(lambda: solver(**arguments), args.repeat, cpu=True)
            stats = solver.stats()
            iterations = int(stats["iter_count"])
            t0 = time.thread_time()  # one more solve: its callbacks and its own time, for where the time goes
            T = unpack(solver(**arguments)["x"])[2]
            parts = _callbacks(solver.stats(), time.thread_time() - t0)
            rows.append((tyre, route, iterations, solve, solve / max(iterations, 1), build, stats["return_status"],
                         T, parts))
    simple_best = min(r[4] for r in rows if r[0] == "simple")
    mf_best = min(rows, key=lambda r: r[3] if r[0] == "mf" and r[6] == "Solve_Succeeded" else float("inf"))
    print(f"\nminimum-time lane change, {args.intervals} intervals, 4 tyres x {args.intervals + 1} nodes, "
          f"{Path(args.tir).name}; CPU time of this thread, best of {args.repeat} (machine possibly loaded: "
          "compare the ratios)")
    print(f"{'tyre':7}{'route':16}{'iterations':>11}{'solve [ms]':>12}{'ms/iter':>9}{'/simple':>9}{'build [s]':>11}"
          f"  {'T [s]':>8}  status")
    for tyre, route, iterations, solve, per, build, status, T, _ in rows:
        print(f"{tyre:7}{route:16}{iterations:>11}{1e3 * solve:>12.1f}{1e3 * per:>9.2f}{per / simple_best:>9.2f}"
              f"{build:>11.1f}  {T:>8.4f}  {status}")
    print("\nwhere the time per iteration goes [ms/iter] (one more solve, CasADi's statistics: the Hessian of the "
          "Lagrangian, the constraint Jacobian, the other callbacks; IPOPT: the rest of that solve, its own work)")
    print(f"{'tyre':7}{'route':16}{'Hessian':>9}{'Jacobian':>10}{'other':>8}{'IPOPT':>8}")
    for tyre, route, iterations, *_, parts in rows:
        print(f"{tyre:7}{route:16}" + "".join(f"{1e3 * v / max(iterations, 1):>{w}.2f}"
                                              for v, w in zip(parts, (9, 10, 8, 8))))
    _kernels(problem)
    ratio = mf_best[4] / simple_best
    print(f"fastest MF route by solve time: {mf_best[1]} ({1e3 * mf_best[3]:.1f} ms, {mf_best[2]} iterations); "
          f"per iteration {ratio:.2f}x the simple tyre's fastest route (target <= {TARGET_RATIO}: "
          f"{'met' if ratio <= TARGET_RATIO else 'NOT met'})")


if __name__ == "__main__":
    main()
