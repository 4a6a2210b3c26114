"""A user's minimum-time lane change written from the README (not mftyre.lane_change): four MF tyres from
``casadi_function`` with its default options (``limits=True``), front and rear inflation pressure [Pa] as design
variables bounded to the file's PRESMIN..PRESMAX, IPOPT with its default options; trapezoidal collocation, static
loads, the rear axle driven. Side by side in one run: the saturation of today (full slope LIMITS_SLACK beyond each
bound) and the old plain clip (LIMITS_SLACK = 0, flat beyond the bound); then the rear PRESMIN multiplier against
second-order finite differences of the re-solved optimum (bound moved inwards by h, 2h).

    python benchmarks/bench_user_lane_change.py [--intervals 150] [--speed 40] [--length 60] [--width 3.5]

Measured (issue 31; 2 shared cores): 150 intervals, 40 m/s, 3.5 m over 60 m: both pressures end on PRESMIN, both
saturations converge (75-132 iterations, 10-17 s CPU) with the same multipliers (rear 7.9e-7 s/Pa): IPOPT's last
iterates lie 3e-3..1e-2 Pa inside PRESMIN, where the clip is not flat, so this problem does not reproduce the
issue's Restoration_Failed. (IPOPT ends within mu/z of the relaxed bound PRESMIN - 1e-8 PRESMIN; the clip bites
only where z PRESMIN exceeds ~mu/1e-8 at the end, ~0.1-0.4 s for T ~ 1.5 s.) 5 m over 60 m at 20 intervals ends
Infeasible_Problem_Detected with both (the manoeuvre is beyond the tyres).
"""
from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import casadi as ca
import numpy as np

import mftyre
import mftyre.backend

TIR = Path(__file__).resolve().parents[1] / "tir_files" / "car_205_60R15_mf61.tir"

#: The car: mass [kg], yaw inertia [kg m^2], CoG to front and rear axle [m], half track [m].
MASS, IZZ, A, B, HALF_TRACK = 1300.0, 1800.0, 1.2, 1.4, 0.75
WHEELS = {"FL": (A, HALF_TRACK), "FR": (A, -HALF_TRACK), "RL": (-B, HALF_TRACK), "RR": (-B, -HALF_TRACK)}


def user_lane_change(model, intervals: int, speed: float, length: float, width: float = 3.5):
    """(solve, bounds): a minimum-time lane change by trapezoidal collocation, ``solve(p_bounds)`` -> (T [s], x,
    lam_x, stats) with ``p_bounds`` = ((front lo, hi), (rear lo, hi)) [bar]; x[-3:] = (T, p_front, p_rear)."""
    tyre = model.casadi_function(("fz", "kappa", "alpha", "vx", "p"), ("fx", "fy", "mz"))  # default options
    n = intervals + 1
    X = ca.MX.sym("X", 6, n)  # X, Y, psi, vx, vy, r
    U = ca.MX.sym("U", 2, n)  # steer, rear slip
    T, pf, pr = ca.MX.sym("T"), ca.MX.sym("pf"), ca.MX.sym("pr")
    g = 9.81
    fz = {"F": MASS * g * B / (A + B) / 2, "R": MASS * g * A / (A + B) / 2}
    fx_body = fy_body = mz_body = 0
    args = {k: [] for k in ("fz", "kappa", "alpha", "vx", "p")}
    geometry = []
    for w, (x, y) in WHEELS.items():
        front = w[0] == "F"
        delta = U[0, :] if front else 0 * U[0, :]
        vx, vy = X[3, :] - X[5, :] * y, X[4, :] + X[5, :] * x  # wheel centre in body axes
        c, s = ca.cos(delta), ca.sin(delta)
        vxw, vyw = vx * c + vy * s, -vx * s + vy * c
        args["fz"].append(ca.DM.ones(1, n) * fz[w[0]])
        args["kappa"].append(0 * U[1, :] if front else U[1, :])
        args["alpha"].append(ca.atan(vyw / vxw))
        args["vx"].append(vxw)
        args["p"].append(ca.DM.ones(1, n) * (pf if front else pr))
        geometry.append((x, y, c, s))
    forces = tyre.map(4 * n)(*(ca.horzcat(*args[k]) for k in ("fz", "kappa", "alpha", "vx", "p")))
    for i, (x, y, c, s) in enumerate(geometry):
        fx, fy, mz = (f[:, i * n:(i + 1) * n] for f in forces)
        Fx, Fy = fx * c - fy * s, fx * s + fy * c
        fx_body, fy_body, mz_body = fx_body + Fx, fy_body + Fy, mz_body + x * Fy - y * Fx + mz
    psi, vx, vy, r = X[2, :], X[3, :], X[4, :], X[5, :]
    f = ca.vertcat(vx * ca.cos(psi) - vy * ca.sin(psi), vx * ca.sin(psi) + vy * ca.cos(psi), r,
                   fx_body / MASS + vy * r, fy_body / MASS - vx * r, mz_body / IZZ)
    h = T / intervals
    defects = X[:, 1:] - X[:, :-1] - 0.5 * h * (f[:, 1:] + f[:, :-1])
    start = [0.0, 0.0, 0.0, speed, 0.0, 0.0]
    w = ca.veccat(X, U, T, pf, pr)
    cons = ca.vertcat(ca.vec(defects), X[:, 0] - ca.DM(start), X[0, -1] - length, X[1, -1] - width, X[2, -1],
                      X[4, -1], X[5, -1], ca.vec(ca.horzcat(*args["alpha"])))
    nlp = {"x": w, "f": T, "g": cons}
    solver = ca.nlpsol("lane", "ipopt", nlp, {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes"})
    ng = cons.numel() - 4 * n
    t0 = length / speed
    x0 = np.concatenate([np.vstack([np.linspace(0, length, n), np.linspace(0, width, n), np.zeros(n),
                                    np.full(n, speed), np.zeros(n), np.zeros(n)]).ravel(order="F"),
                         np.zeros(2 * n), [t0]])
    lbx = np.concatenate([np.full(6 * n, -np.inf), np.tile([-0.5, -0.15], n), [0.1 * t0]])
    ubx = np.concatenate([np.full(6 * n, np.inf), np.tile([0.5, 0.15], n), [10 * t0]])
    lbg = np.concatenate([np.zeros(ng), np.full(4 * n, -0.3)])
    ubg = np.concatenate([np.zeros(ng), np.full(4 * n, 0.3)])

    def solve(p_bounds):
        (flo, fhi), (rlo, rhi) = p_bounds
        r = solver(x0=np.concatenate([x0, [0.5 * (flo + fhi), 0.5 * (rlo + rhi)]]), lbg=lbg, ubg=ubg,
                   lbx=np.concatenate([lbx, [flo, rlo]]), ubx=np.concatenate([ubx, [fhi, rhi]]))
        return float(r["f"]), np.asarray(r["x"]).ravel(), np.asarray(r["lam_x"]).ravel(), solver.stats()

    prm = model.params
    return solve, ((prm.PRESMIN, prm.PRESMAX),) * 2


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--intervals", type=int, default=150)
    ap.add_argument("--speed", type=float, default=40.0)
    ap.add_argument("--length", type=float, default=60.0)
    ap.add_argument("--width", type=float, default=3.5)
    a = ap.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(TIR)
    saved = mftyre.backend.LIMITS_SLACK
    print(f"{a.intervals} intervals, {a.speed:g} m/s, {a.width:g} m over {a.length:g} m; pressures in "
          f"[{model.params.PRESMIN:g}, {model.params.PRESMAX:g}] Pa")
    print(f"{'saturation':<26}{'status':<28}{'iter':>6}{'CPU s':>8}{'T [s]':>10}{'p_front - PRESMIN':>19}"
          f"{'p_rear - PRESMIN':>18}{'lam_rear [s/Pa]':>17}")
    for name, slack in (("full slope (LIMITS_SLACK)", saved), ("plain clip (old)", 0.0)):
        mftyre.backend.LIMITS_SLACK = slack  # read when the graph is built
        try:
            solve, bounds = user_lane_change(model, a.intervals, a.speed, a.length, a.width)
        finally:
            mftyre.backend.LIMITS_SLACK = saved
        t0 = time.process_time()
        best, x, lam, stats = solve(bounds)
        cpu = time.process_time() - t0
        lo = model.params.PRESMIN
        print(f"{name:<26}{stats['return_status']:<28}{stats['iter_count']:>6}{cpu:>8.1f}{best:>10.5f}"
              f"{x[-2] - lo:>19.3g}{x[-1] - lo:>18.3g}{-lam[-1]:>17.4g}")
        if slack == saved and stats["success"]:
            h, times = 20.0, []
            for step in (h, 2 * h):
                moved = [list(bounds[0]), [lo + step, bounds[1][1]]]
                times.append(solve(moved)[0])
            fd = (4.0 * (times[0] - best) - (times[1] - best)) / (2.0 * h)
            print(f"{'':<26}rear multiplier {-lam[-1]:.6g} s/Pa, finite differences {fd:.6g} s/Pa "
                  f"(ratio {-lam[-1] / fd:.5f})")


if __name__ == "__main__":
    main()
