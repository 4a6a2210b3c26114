"""A minimum-time lane change of a four-wheel car on Magic Formula tyres, by direct collocation (CasADi + IPOPT).

    >>> from mftyre.lane_change import LaneChange
    >>> problem = LaneChange.from_tir("tir_files/car_205_60R15_mf61.tir", intervals=30)
    >>> result = problem.solve()                        # route "expand": no compiler needed
    >>> result = problem.solve(route="external")        # the fastest per iteration (compiled once, cached)
    >>> result.time, result.p_front, result.stats

Model (planar, ISO body axes at the CoG, as :mod:`mftyre.vehicle`): states X, Y, heading psi, body velocities vx,
vy and yaw rate r; controls: the steer angle delta of the front wheels and the longitudinal slip kappa of the two
driven rear wheels (the front wheels roll freely, kappa = 0); design variables: the front and rear inflation
pressures within PRESMIN..PRESMAX, and the manoeuvre time T (the objective):

    m (dvx/dt - vy r) = sum Fx_i,   m (dvy/dt + vx r) = sum Fy_i,   Izz dr/dt = sum (x_i Fy_i - y_i Fx_i + Mz_i),
    dX/dt = vx cos psi - vy sin psi,   dY/dt = vx sin psi + vy cos psi,   dpsi/dt = r.

Wheel kinematics, slip angles and the rotation of the tyre forces into body axes are those of
:meth:`mftyre.vehicle.Vehicle.wheel_states`; the loads are the static axle loads plus the lateral load transfer of
the quasi-steady lateral acceleration vx r (split by the front roll-stiffness share), no pitch. The manoeuvre:
from straight running at ``speed`` to ``width`` to the left after ``length`` metres, heading, vy and r back to zero,
|delta| <= 0.5 rad, |kappa| <= 0.15, |alpha| <= 0.3 rad at every wheel (a trust region well beyond the force
peaks). Trapezoidal collocation on ``intervals`` equal intervals: the tyres are evaluated at every node, all
4 (intervals + 1) calls as one mapped call.

Tyres and routes. ``tyre="mf"``: :meth:`mftyre.MFModel.casadi_function` with ``limits="smooth"`` (the pressures are
decision variables: full slope at and a hair beyond their bounds) and ``smooth=True`` (per-quantity widths);
``tyre="simple"``: a 4-parameter Magic Formula (B, C, D, E; D the friction coefficient, Fx and Fy independent,
Mz = -t Fy with a constant trail) whose peaks match the MF tyre's at the nominal load, the yardstick of the
cost per iteration. ``route`` (how CasADi evaluates the problem; benchmarks/bench_ocp.py measures them side by
side): ``"sx"`` the MX graph calling the SX tyre function, ``"expand"`` the whole NLP expanded to one SX graph
(``expand=True``), ``"external"`` the tyre compiled to C with its Jacobian and Hessian
(:func:`mftyre.compiled.compile_external`, ``hessian=True``; the fastest measured), ``"external-expand"`` the
same inside the expanded NLP (CasADi's SX call nodes: 4x slower per iteration), ``"external-lbfgs"`` the same without the Hessian
and IPOPT's limited-memory quasi-Newton, ``"jit"`` the expanded NLP compiled to C by CasADi's just-in-time
compiler (seconds of gcc per problem size).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .errors import ModelInputError
from .model import MFModel, load_tir
from .vehicle import WHEELS, VehicleParams

__all__ = ["LaneChange", "LaneChangeResult", "ROUTES", "simple_tyre_function"]

ROUTES = ("sx", "expand", "external", "assembled", "external-expand", "external-lbfgs", "jit")
TYRES = ("mf", "simple", "simple-p")
_STATES = ("X", "Y", "psi", "vx", "vy", "r")
_CONTROLS = ("delta", "kappa")


def simple_tyre_function(model: MFModel, name: str = "simple_tyre", pressure: bool = False):
    """A 4-parameter Magic Formula tyre (fz, kappa, alpha, vx, p) -> (fx, fy, mz) as a ``casadi.Function``:
    F = D Fz sin(C atan(B s - E (B s - atan(B s)))) for s = kappa (Fx) and s = -alpha (Fy), Mz = -t Fy, with D
    and the slip stiffness B C D of ``model``'s pure-slip curves at the nominal load (C = 1.3 lateral, 1.65
    longitudinal, E = 0, t = 0.03 m); no speed effect. ``pressure=False``: no pressure effect either (the p input
    unused). ``pressure=True``: D and the slip stiffness vary with the inflation pressure to first order in
    dpi = (p - NOMPRES) / NOMPRES as the MF tyre's do at the nominal load and pressure: the friction by the
    linear terms of the MF's mu factors (1 + PPX3 dpi, 1 + PPY3 dpi; (4.E13), (4.E23)), the slip stiffnesses by
    their pressure slopes measured on ``model`` (central differences at NOMPRES +- 1 %), so the problem couples
    the pressure to every node as the MF problem does."""
    import casadi as ca

    prm = model.params
    fz0, p0 = float(prm.FNOMIN), float(prm.NOMPRES)

    def stiffnesses(p):
        out = model.evaluate(fz0, np.array([0.0, 1e-4, 0.0, 0.0]), np.array([0.0, 0.0, 0.0, 1e-4]), p=p)
        return (out.fx[1] - out.fx[0]) / 1e-4 / fz0, abs(out.fy[3] - out.fy[2]) / 1e-4 / fz0

    kx, ky = stiffnesses(p0)
    dx = float(prm.PDX1 * prm.LMUX)
    dy = float(abs(prm.PDY1) * prm.LMUY)
    fz, kappa, alpha, vx, p = (ca.SX.sym(n) for n in ("fz", "kappa", "alpha", "vx", "p"))
    if pressure:
        (kx_hi, ky_hi), (kx_lo, ky_lo) = stiffnesses(1.01 * p0), stiffnesses(0.99 * p0)
        dpi = (p - p0) / p0
        kx = kx * (1 + (kx_hi - kx_lo) / (0.02 * kx) * dpi)
        ky = ky * (1 + (ky_hi - ky_lo) / (0.02 * ky) * dpi)
        dx = dx * (1 + float(prm.PPX3) * dpi)
        dy = dy * (1 + float(prm.PPY3) * dpi)

    def curve(slip, b, c, d):
        return d * fz * ca.sin(c * ca.atan(b * slip))

    fx = curve(kappa, kx / (1.65 * dx), 1.65, dx)
    fy = curve(-alpha, ky / (1.3 * dy), 1.3, dy)
    return ca.Function(name, [fz, kappa, alpha, vx, p], [fx, fy, -0.03 * fy],
                       ["fz", "kappa", "alpha", "vx", "p"], ["fx", "fy", "mz"])


def assembled_nlp(w, f, g, inputs, outputs, tyres):
    """The NLP min f(w) s.t. g(w) for tyre functions called over many points, with its exact constraint Jacobian
    and Hessian of the Lagrangian assembled by the chain rule from the SX vehicle part and the tyres' own
    derivative functions, each mapped over all points in one call (route ``"assembled"``).

    ``w``: the SX decision variables; ``f``, ``g``: SX expressions of ``w`` and of the tyres' outputs, the SX
    symbols ``outputs[k]`` (n_out x n, one column per point) of tyre ``tyres[k]`` (a ``casadi.Function`` of
    n_in scalar inputs and n_out scalar outputs, e.g. :func:`mftyre.compiled.compile_external` with
    ``hessian=True``) at ``inputs[k]`` (n_in x n SX expressions of ``w``). Returns ``(nlp, options)`` for
    ``casadi.nlpsol``: the MX problem (the tyre's value mapped) and its ``jac_g`` and ``hess_lag``.

    With u(w) the tyre inputs, J the tyre Jacobians there and H(mu) the Hessians of mu^T y (mu: the multipliers
    the Lagrangian gives the tyre outputs, dL/dy), the NLP's derivatives are those of the local model
    y(w) ~ y + J d + (d^T H d)/2 in d = u(w) - u(w0) at w0 = w, which SX differentiates: the constraint Jacobian
    g_w + g_y J u_w, the Hessian L_ww + L_wy J u_w + (...)^T + u_w^T (J^T L_yy J + H(mu)) u_w + sum (J^T mu)_i
    u_i,ww. Per iteration the tyres cost one value and Jacobian call (constraint Jacobian) and one value and
    Jacobian-of-adjoint call (the Hessian, whose blocks also hold J), mapped; the rest is SX."""
    import casadi as ca

    w0, lam_f, lam_g = ca.SX.sym("w0", w.sparsity()), ca.SX.sym("lam_f"), ca.SX.sym("lam_g", g.numel())
    n_in = [u.size1() for u in inputs]
    n_out = [y.size1() for y in outputs]
    jac = [ca.SX.sym(f"jac{k}", n_out[k] * n_in[k], y.size2()) for k, y in enumerate(outputs)]  # row o * n_in + i
    hess = [ca.SX.sym(f"hess{k}", n_in[k] * n_in[k], y.size2()) for k, y in enumerate(outputs)]  # row i * n_in + j
    local, quadratic = [], 0.0
    for k, (u, y) in enumerate(zip(inputs, outputs)):
        d = u - ca.substitute(u, w, w0)  # zero at w0 = w, its derivatives those of u
        local.append(ca.vertcat(*(y[o, :] + sum(jac[k][o * n_in[k] + i, :] * d[i, :] for i in range(n_in[k]))
                                  for o in range(n_out[k]))))
        quadratic += 0.5 * sum(ca.sum2(hess[k][i * n_in[k] + j, :] * d[i, :] * d[j, :])
                               for i in range(n_in[k]) for j in range(n_in[k]))
    y_all = ca.vertcat(*(ca.vec(y) for y in outputs))
    local_all = ca.vertcat(*(ca.vec(y) for y in local))
    f_local, g_local = (ca.substitute(e, y_all, local_all) for e in (f, g))
    lagrangian = lam_f * f_local + ca.dot(lam_g, g_local) + quadratic
    hessian = ca.triu(ca.hessian(lagrangian, w)[0])
    multipliers = ca.jacobian(ca.dot(lam_g, g) + lam_f * f, y_all).T  # dL/dy at the tyres' outputs
    sx_in = [w, w0, *outputs, *jac]
    jacobian_part = ca.Function("nlp_jac_g_local", sx_in, [g_local, ca.jacobian(g_local, w)])
    hessian_part = ca.Function("nlp_hess_l_local", [*sx_in, lam_f, lam_g, *hess], [hessian])
    tyre_inputs = ca.Function("tyre_inputs", [w], inputs)
    mu_function = ca.Function("tyre_multipliers", [w, *outputs, lam_g, lam_f], [multipliers])
    objective = ca.Function("nlp_f_local", [w, *outputs], [f])
    constraints = ca.Function("nlp_g_local", [w, *outputs], [g])

    x, p = ca.MX.sym("x", w.sparsity()), ca.MX.sym("p", 0, 1)
    mx_lam_f, mx_lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", g.numel())
    u = tyre_inputs(x)
    u = u if isinstance(u, (list, tuple)) else [u]
    n = [y.size2() for y in outputs]
    rows = [ca.vertsplit(u[k], list(range(n_in[k] + 1))) for k in range(len(tyres))]
    values = [ca.vertcat(*tyre.map(n[k])(*rows[k])) for k, tyre in enumerate(tyres)]
    g_mx = constraints(x, *values)
    f_mx = objective(x, *values) if ca.depends_on(f, y_all) else objective(x, *[ca.MX(y.sparsity()) for y in outputs])

    jacobians = []
    for k, tyre in enumerate(tyres):  # blocks d y_o / d u_i, output-major
        jacobians.append(ca.vertcat(*tyre.jacobian().map(n[k])(*rows[k], *ca.vertsplit(values[k], list(range(n_out[k] + 1))))))
    jac_g = ca.Function("nlp_jac_g", [x, p], jacobian_part(x, x, *values, *jacobians), ["x", "p"], ["g", "jac_g_x"])

    mu = ca.vertsplit(mu_function(x, *values, mx_lam_g, mx_lam_f), list(np.cumsum([0] + [o * m for o, m in zip(n_out, n)])))
    hessians, jacobians = [], []
    for k, tyre in enumerate(tyres):
        second = tyre.reverse(1).jacobian()  # d (J^T mu)_i / d (inputs_j, outputs, mu_o), input-major
        seeds = ca.vertsplit(ca.reshape(mu[k], n_out[k], n[k]), list(range(n_out[k] + 1)))
        blocks = second.map(n[k])(*rows[k], *ca.vertsplit(values[k], list(range(n_out[k] + 1))), *seeds,
                                  *[ca.MX.zeros(1, n[k])] * n_in[k])
        stride = n_in[k] + 2 * n_out[k]
        hessians.append(ca.vertcat(*(blocks[i * stride + j] for i in range(n_in[k]) for j in range(n_in[k]))))
        jacobians.append(ca.vertcat(*(blocks[i * stride + n_in[k] + n_out[k] + o]
                                      for o in range(n_out[k]) for i in range(n_in[k]))))
    hess_lag = ca.Function("nlp_hess_l", [x, p, mx_lam_f, mx_lam_g],
                           [hessian_part(x, x, *values, *jacobians, mx_lam_f, mx_lam_g, *hessians)],
                           ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    return {"x": x, "f": f_mx, "g": g_mx}, {"jac_g": jac_g, "hess_lag": hess_lag}


@dataclass(frozen=True)
class LaneChangeResult:
    """The optimum: manoeuvre time [s], pressures [Pa], the trajectory (arrays over the nodes) and IPOPT's
    figures (``iterations``, ``solve_time`` the CPU time of the solve in the calling thread [s],
    ``time_per_iteration``)."""

    success: bool
    status: str
    time: float
    p_front: float
    p_rear: float
    states: dict
    controls: dict
    iterations: int
    solve_time: float

    @property
    def time_per_iteration(self) -> float:
        return self.solve_time / max(self.iterations, 1)

    def __str__(self):
        return (f"T = {self.time:.4f} s, p = {self.p_front / 1e5:.3f}/{self.p_rear / 1e5:.3f} bar, {self.status}, "
                f"{self.iterations} iterations, {1e3 * self.solve_time:.0f} ms "
                f"({1e3 * self.time_per_iteration:.2f} ms/iteration)")


class LaneChange:
    """The minimum-time lane change (see the module notes) of a car on ``tyres`` (FL, FR, RL, RR)."""

    def __init__(self, tyres: dict, params: VehicleParams | None = None, *, speed: float = 20.0,
                 length: float = 50.0, width: float = 3.5, intervals: int = 30, yaw_inertia: float | None = None):
        self.params = params or VehicleParams()
        if not isinstance(tyres, dict) or sorted(tyres) != sorted(WHEELS):
            raise ModelInputError(f"tyres must map each of {', '.join(WHEELS)} to an MFModel")
        for w, model in tyres.items():
            if not isinstance(model, MFModel):
                raise ModelInputError(f"tyre {w} must be an MFModel, got {type(model).__name__}")
            if model.side != ("left" if w[1] == "L" else "right"):
                raise ModelInputError(f"tyre {w} is mounted on the {model.side} side; use model.with_side(...)")
        self.tyres = tyres
        if not intervals >= 4:
            raise ModelInputError(f"intervals must be at least 4, got {intervals!r}")
        if not (speed > 0 and length > 0 and width > 0):
            raise ModelInputError("speed, length and width of the lane change must be positive")
        self.speed, self.length, self.width, self.intervals = float(speed), float(length), float(width), intervals
        P = self.params
        self.yaw_inertia = float(yaw_inertia) if yaw_inertia is not None else P.mass * P.a * P.b
        lo = max(float(t.params.PRESMIN) for t in tyres.values())
        hi = min(float(t.params.PRESMAX) for t in tyres.values())
        self.pressure_bounds = (lo, hi)

    @classmethod
    def from_tir(cls, path, params: VehicleParams | None = None, **kwargs) -> "LaneChange":
        left = load_tir(path, side="left")
        right = left.with_side("right")
        return cls({"FL": left, "FR": right, "RL": left, "RR": right}, params, **kwargs)

    # ---------------------------------------------------------------------------------------------- tyres
    def _tyre_function(self, wheel: str, tyre: str, route: str):
        model = self.tyres[wheel]
        if tyre in ("simple", "simple-p"):
            return simple_tyre_function(model, f"simple_{wheel}", pressure=tyre == "simple-p")
        inputs, outputs = ("fz", "kappa", "alpha", "vx", "p"), ("fx", "fy", "mz")
        options = dict(limits="smooth", smooth=True)
        if route in ("external", "external-expand", "external-lbfgs", "assembled"):
            from .compiled import compile_external

            return compile_external(model, inputs, outputs, hessian=route != "external-lbfgs",
                                    name=f"mf_{wheel}", **options)
        return model.casadi_function(inputs, outputs, name=f"mf_{wheel}", **options)

    # ---------------------------------------------------------------------------------------------- problem
    def _equations(self, X, U, T, pv, tyres):
        """(objective, constraints, lbg, ubg) of the trajectory X (states x nodes), U (controls x nodes), time T and
        pressures pv [bar], MX or SX; ``tyres(rows)`` returns the (fx, fy, mz) rows of each wheel (in
        :data:`WHEELS` order) for ``rows``, each wheel's (fz, kappa, alpha, vx, p) rows over the nodes."""
        import casadi as ca

        P, n = self.params, self.intervals + 1
        psi, vx, vy, r = X[2, :], X[3, :], X[4, :], X[5, :]
        delta, kappa = U[0, :], U[1, :]
        L = P.wheelbase
        ay = vx * r
        h_ra = (P.b * P.roll_centre_front + P.a * P.roll_centre_rear) / L
        transfer = {"F": P.mass * ay / P.track_front * (P.b / L * P.roll_centre_front
                                                        + P.roll_stiffness_front * (P.h_cog - h_ra)),
                    "R": P.mass * ay / P.track_rear * (P.a / L * P.roll_centre_rear
                                                       + (1 - P.roll_stiffness_front) * (P.h_cog - h_ra))}
        static = {"F": P.mass * P.g * P.b / L / 2, "R": P.mass * P.g * P.a / L / 2}
        rows, geometry = [], []
        for w in WHEELS:
            x, y = P.positions()[w]
            front = w[0] == "F"
            d = delta if front else 0.0 * delta
            vxw_body, vyw_body = vx - r * y, vy + r * x
            sd, cd = ca.sin(d), ca.cos(d)
            vxw = vxw_body * cd + vyw_body * sd
            vyw = -vxw_body * sd + vyw_body * cd
            axle = "F" if front else "R"
            rows.append((static[axle] + (-1.0 if y > 0 else 1.0) * transfer[axle],
                         0.0 * kappa if front == (P.drive == "rear") else kappa, ca.atan(vyw / vxw), vxw,
                         ca.repmat(pv[0 if front else 1] * 1e5, 1, n)))
            geometry.append((x, y, sd, cd))
        sum_fx = sum_fy = yaw = 0.0
        for (x, y, sd, cd), (fx, fy, mz) in zip(geometry, tyres(rows)):
            fx_b = fx * cd - fy * sd
            fy_b = fx * sd + fy * cd
            sum_fx, sum_fy = sum_fx + fx_b, sum_fy + fy_b
            yaw = yaw + x * fy_b - y * fx_b + mz
        xdot = ca.vertcat(vx * ca.cos(psi) - vy * ca.sin(psi), vx * ca.sin(psi) + vy * ca.cos(psi), r,
                          sum_fx / P.mass + vy * r, sum_fy / P.mass - vx * r, yaw / self.yaw_inertia)
        h = T / self.intervals
        defects = X[:, 1:] - X[:, :-1] - 0.5 * h * (xdot[:, 1:] + xdot[:, :-1])
        scale = ca.DM([self.length, self.width, 0.1, self.speed, 1.0, 0.5])
        # objective: the time, and a small penalty on the control changes (no chattering between nodes)
        smoothness = ca.sumsqr(ca.diff(delta, 1, 1)) + ca.sumsqr(ca.diff(kappa, 1, 1))
        objective = T + 1e-2 * smoothness
        alpha_all = ca.vertcat(*(row[2] for row in rows))
        g = ca.vertcat(ca.vec(defects / ca.repmat(scale, 1, self.intervals)), ca.vec(alpha_all))
        lbg = np.r_[np.zeros(defects.numel()), np.full(alpha_all.numel(), -0.3)]
        ubg = np.r_[np.zeros(defects.numel()), np.full(alpha_all.numel(), 0.3)]
        return objective, g, lbg, ubg

    def _symbols(self, kind):
        import casadi as ca

        n = self.intervals + 1
        X, U, T, pv = kind.sym("x", len(_STATES), n), kind.sym("u", len(_CONTROLS), n), kind.sym("T"), kind.sym("p", 2)
        return X, U, T, pv, ca.vertcat(ca.vec(X), ca.vec(U), T, pv)

    def build(self, tyre: str = "mf", route: str = "expand", ipopt_options: dict | None = None):
        """(solver, initial guess, bounds, unpack) of the NLP; see :meth:`solve`."""
        import casadi as ca

        if tyre not in TYRES:
            raise ModelInputError(f"tyre must be one of {TYRES}, got {tyre!r}")
        if route not in ROUTES:
            raise ModelInputError(f"route must be one of {ROUTES}, got {route!r}")
        n = self.intervals + 1
        functions = [self._tyre_function(w, tyre, route) for w in WHEELS]
        options = {}
        if route == "assembled":
            X, U, T, pv, w = self._symbols(ca.SX)
            inputs, outputs = [], [ca.SX.sym(f"y_{wheel}", 3, n) for wheel in WHEELS]

            def tyres(rows):  # the tyres' outputs as symbols: the vehicle part alone in SX
                inputs.extend(ca.vertcat(*row) for row in rows)
                return [(y[0, :], y[1, :], y[2, :]) for y in outputs]

            objective, g, lbg, ubg = self._equations(X, U, T, pv, tyres)
            nlp, options = assembled_nlp(w, objective, g, inputs, outputs, functions)
        else:
            X, U, T, pv, w = self._symbols(ca.MX)

            def tyres(rows):  # one mapped call per wheel over every node
                return [f.map(n)(*row) for f, row in zip(functions, rows)]

            objective, g, lbg, ubg = self._equations(X, U, T, pv, tyres)
            nlp = {"x": w, "f": objective, "g": g}
        options.update({"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})
        if route in ("expand", "external-expand", "jit"):
            options["expand"] = True
        if route == "jit":
            options.update(jit=True, compiler="shell", jit_options={"flags": ["-O1"], "verbose": False})
        if route == "external-lbfgs":
            options["ipopt.hessian_approximation"] = "limited-memory"
        options.update({f"ipopt.{k}": v for k, v in (ipopt_options or {}).items()})
        solver = ca.nlpsol("lane_change", "ipopt", nlp, options)
        # bounds and the initial guess (straight line at constant speed, the lateral offset as a smooth step)
        lbx = np.full((len(_STATES), n), -np.inf)
        ubx = np.full((len(_STATES), n), np.inf)
        lbx[3, :] = 0.25 * self.speed
        start = [0.0, 0.0, 0.0, self.speed, 0.0, 0.0]
        end = {0: self.length, 1: self.width, 2: 0.0, 4: 0.0, 5: 0.0}
        lbx[:, 0] = ubx[:, 0] = start
        for i, v in end.items():
            lbx[i, -1] = ubx[i, -1] = v
        lbu = np.tile([[-0.5], [-0.15]], (1, n))
        ubu = -lbu
        p_lo, p_hi = (v / 1e5 for v in self.pressure_bounds)
        lb = np.r_[lbx.ravel(order="F"), lbu.ravel(order="F"), 0.2 * self.length / self.speed, p_lo, p_lo]
        ub = np.r_[ubx.ravel(order="F"), ubu.ravel(order="F"), 5.0 * self.length / self.speed, p_hi, p_hi]
        s = np.linspace(0.0, 1.0, n)
        step = s**2 * (3 - 2 * s)
        T0 = self.length / self.speed
        x0 = np.vstack([s * self.length, self.width * step, self.width / self.length * 6 * s * (1 - s),
                        np.full(n, self.speed), np.zeros(n), np.zeros(n)])
        p0 = 0.5 * (p_lo + p_hi)
        guess = np.r_[x0.ravel(order="F"), np.zeros(2 * n), T0, p0, p0]

        def unpack(values):
            values = np.asarray(values, dtype=float).ravel()
            states = values[:len(_STATES) * n].reshape((len(_STATES), n), order="F")
            controls = values[len(_STATES) * n:(len(_STATES) + 2) * n].reshape((2, n), order="F")
            return (dict(zip(_STATES, states)), dict(zip(_CONTROLS, controls)), float(values[-3]),
                    float(values[-2]) * 1e5, float(values[-1]) * 1e5)

        return solver, dict(x0=guess, lbx=lb, ubx=ub, lbg=lbg, ubg=ubg), unpack

    def solve(self, tyre: str = "mf", route: str = "expand", ipopt_options: dict | None = None) -> LaneChangeResult:
        """Solve the lane change (IPOPT with its default settings unless ``ipopt_options``); see the module notes
        for ``tyre`` and ``route``."""
        solver, arguments, unpack = self.build(tyre, route, ipopt_options)
        t0 = time.thread_time()  # (CPU time of this thread, where IPOPT runs: robust on a loaded machine)
        sol = solver(**arguments)
        wall = time.thread_time() - t0
        stats = solver.stats()
        states, controls, T, pf, pr = unpack(sol["x"])
        pf, pr = (min(max(p, self.pressure_bounds[0]), self.pressure_bounds[1]) for p in (pf, pr))
        return LaneChangeResult(bool(stats.get("success", False)), str(stats.get("return_status", "")), T, pf, pr,
                                states, controls, int(stats.get("iter_count", 0)), wall)
