"""A minimum-time lane change of a four-wheel car on Magic Formula tyres, by direct collocation (CasADi + IPOPT).

    >>> from mftyre.lane_change import LaneChange
    >>> problem = LaneChange.from_tir("tir_files/car_205_60R15_mf61.tir", intervals=30)
    >>> result = problem.solve()                        # route "expand": no compiler needed
    >>> result = problem.solve(route="assembled")       # the fastest per iteration (kernels compiled once, cached)
    >>> result.time, result.p_front, result.iterations

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
decision variables: full slope at and a hair beyond their bounds) and ``smooth=True`` (per-quantity widths); on the
free-rolling axle specialised to kappa = 0 (``fixed=``: the same equations, 30 % fewer operations in the Hessian).
Yardsticks of the cost per iteration: ``tyre="simple"``, a 4-parameter Magic Formula (B, C, D, E; D the friction
coefficient, Fx and Fy independent, Mz = -t Fy with a constant trail) whose peaks and slip stiffnesses match the MF
tyre's at the nominal load and pressure, no pressure effect (its NLP has empty pressure columns); ``"simple-p"``
the same with the friction and slip stiffnesses following the pressure to first order as the MF tyre's do
(:func:`simple_tyre_function`), so that its NLP has the MF problem's sparsity. ``route`` (how CasADi evaluates the
problem; ``python benchmarks/bench_ocp.py`` measures them side by side):

* ``"assembled"``, the fastest per iteration: the vehicle part in SX and the tyre's kernels (value; value and
  Jacobian; value, Jacobian and Hessian of mu^T y) compiled to C once (:func:`mftyre.compiled.compile_tyre_kernels`,
  ~3 s of gcc per wheel, cached), each mapped over all nodes in one call; the NLP's exact constraint Jacobian and
  Hessian of the Lagrangian assembled by the chain rule (:func:`mftyre.ocp.assembled_nlp`) and given to nlpsol;
  the same NLP and optimum as ``"expand"``;
* ``"expand"`` the whole NLP expanded to one SX graph (``expand=True``; no compiler);
* ``"sx"`` the MX graph calling the SX tyre function;
* ``"external"`` the tyre compiled with its Jacobian and Hessian (:func:`mftyre.compiled.compile_external`,
  ``hessian=True``) and CasADi differentiating the MX graph around it; ``"external-expand"`` the same inside the
  expanded NLP (CasADi's SX call nodes); ``"external-lbfgs"`` ``hessian=False`` and IPOPT's limited-memory
  quasi-Newton;
* ``"jit"`` the expanded NLP compiled to C by CasADi's just-in-time compiler (gcc at every new problem).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .errors import ModelInputError
from .model import MFModel, load_tir
from .ocp import assembled_nlp
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
    longitudinal, E = 0, t = 0.03 m); no speed effect. ``pressure=False``: the curves at INFLPRES and no pressure
    effect (the p input unused). ``pressure=True``: the curves at NOMPRES, D and the slip stiffness varying with
    the inflation pressure to first order in dpi = (p - NOMPRES) / NOMPRES as the MF tyre's do at the nominal load
    and pressure: the friction by the linear terms of the MF's mu factors (1 + PPX3 dpi, 1 + PPY3 dpi; (4.E13),
    (4.E23)), the slip stiffnesses by their pressure slopes measured on ``model`` (central differences at
    NOMPRES +- 1 %, ``limits=False``), so the problem couples the pressure to every node as the MF problem does."""
    import casadi as ca

    prm = model.params
    fz0, p0 = float(prm.FNOMIN), float(prm.NOMPRES)

    def stiffnesses(p, **options):
        out = model.evaluate(fz0, np.array([0.0, 1e-4, 0.0, 0.0]), np.array([0.0, 0.0, 0.0, 1e-4]), p=p, **options)
        return (out.fx[1] - out.fx[0]) / 1e-4 / fz0, abs(out.fy[3] - out.fy[2]) / 1e-4 / fz0

    kx, ky = stiffnesses(p0, limits=False) if pressure else stiffnesses(None)
    dx = float(prm.PDX1 * prm.LMUX)
    dy = float(abs(prm.PDY1) * prm.LMUY)
    fz, kappa, alpha, vx, p = (ca.SX.sym(n) for n in ("fz", "kappa", "alpha", "vx", "p"))
    if pressure:
        (kx_hi, ky_hi), (kx_lo, ky_lo) = (stiffnesses(f * p0, limits=False) for f in (1.01, 0.99))
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


@dataclass(frozen=True)
class LaneChangeResult:
    """The optimum: manoeuvre time [s], pressures [Pa], the trajectory (arrays over the nodes) and IPOPT's
    figures (``success``, ``status`` its return status, ``iterations``, ``solve_time`` the CPU time of the solve in
    the calling thread [s], ``time_per_iteration``). Every value is the one IPOPT returned: at an active bound an
    interior-point solver may end a hair outside it (bound_relax_factor, 1e-8 relative by default)."""

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
    def _inputs(self, wheel: str) -> tuple:
        """The tyre inputs that vary over the manoeuvre: all but kappa on the undriven axle (free rolling, the MF
        tyre's functions are specialised to kappa = 0 there: 30 % fewer operations in its Hessian)."""
        driven = (wheel[0] == "F") == (self.params.drive == "front")
        return ("fz", "kappa", "alpha", "vx", "p") if driven else ("fz", "alpha", "vx", "p")

    def _tyre_function(self, wheel: str, tyre: str, route: str):
        """The tyre of ``wheel`` as a casadi.Function of :meth:`_inputs` -> (fx, fy, mz); for route "assembled"
        its kernels (:mod:`mftyre.ocp`)."""
        import casadi as ca

        from .compiled import compile_tyre_kernels, tyre_kernels

        model, inputs, outputs = self.tyres[wheel], self._inputs(wheel), ("fx", "fy", "mz")
        if tyre in ("simple", "simple-p"):
            f = simple_tyre_function(model, f"simple_{wheel}", pressure=tyre == "simple-p")
            sx = [ca.SX.sym(name) if name in inputs else ca.SX(0.0) for name in f.name_in()]
            f = ca.Function(f.name(), [v for v in sx if v.is_symbolic()], f.call(sx), list(inputs), list(outputs))
            return tyre_kernels(f) if route == "assembled" else f
        fixed = {} if "kappa" in inputs else {"fixed": {"kappa": 0.0}}
        options = dict(limits="smooth", smooth=True, **fixed)
        if route == "assembled":
            return compile_tyre_kernels(model, inputs, outputs, name=f"mf_{wheel}", **options)
        if route in ("external", "external-expand", "external-lbfgs"):
            from .compiled import compile_external

            return compile_external(model, inputs, outputs, hessian=route != "external-lbfgs",
                                    name=f"mf_{wheel}", **options)
        return model.casadi_function(inputs, outputs, name=f"mf_{wheel}", **options)

    # ---------------------------------------------------------------------------------------------- problem
    def _equations(self, X, U, T, pv, tyres):
        """(objective, constraints, lbg, ubg) of the trajectory X (states x nodes), U (controls x nodes), time T and
        pressures pv [bar], MX or SX; ``tyres(rows)`` returns the (fx, fy, mz) rows of each wheel (in
        :data:`WHEELS` order) for ``rows``, each wheel's rows of :meth:`_inputs` over the nodes."""
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
            row = dict(fz=static[axle] + (-1.0 if y > 0 else 1.0) * transfer[axle], kappa=kappa,
                       alpha=ca.atan(vyw / vxw), vx=vxw, p=ca.repmat(pv[0 if front else 1] * 1e5, 1, n))
            rows.append(tuple(row[name] for name in self._inputs(w)))
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
        alpha_all = ca.vertcat(*(row[-3] for row in rows))
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
            nlp, options = assembled_nlp(w, objective, g, inputs, outputs, functions)  # (the tyres' kernels)
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
        states, controls, T, pf, pr = unpack(sol["x"])  # as IPOPT returned them (no clipping into the bounds)
        return LaneChangeResult(bool(stats.get("success", False)), str(stats.get("return_status", "")), T, pf, pr,
                                states, controls, int(stats.get("iter_count", 0)), wall)
