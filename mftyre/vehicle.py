"""A steady-state two-track (four-wheel) vehicle on Magic Formula tyres, for optimisation examples.

    >>> from mftyre.vehicle import Vehicle, optimal_braking_slip
    >>> car = Vehicle.from_tir("tir_files/car_205_60R15_mf61.tir")      # default ~1300 kg passenger car
    >>> ss = car.steady_state(V=20.0, delta=0.03)                        # solve equilibrium for a given steer
    >>> best = car.max_lateral_acceleration(20.0)                        # IPOPT: maximise ay
    >>> best_p = car.max_lateral_acceleration(20.0, pressures="optimise")
    >>> check = car.brute_force_max_lateral_acceleration(20.0)           # an independent search
    >>> brake = optimal_braking_slip(car.tyres["FL"], fz=4000.0, alpha=0.05)

Model (steady-state cornering at constant speed ``V`` on a flat road)
-------------------------------------------------------------------
Axes: ISO body axes at the centre of gravity (CoG), x forward, y left, z up; yaw rate ``r`` positive to the
left (counter-clockwise seen from above). A left turn therefore has r > 0 and lateral acceleration ay = V r > 0.

Unknowns: steer angle ``delta`` of the front wheels (both the same, no Ackermann; positive = to the left),
body sideslip angle ``beta`` (direction of the CoG velocity from the x axis, positive = to the left), yaw
rate ``r`` and the longitudinal slip ``kappa`` shared by the two wheels of the driven axle (``drive``: 'rear'
(default) or 'front'). The wheels of the other axle roll with kappa = 0 (free rolling; they carry only the
tyre's small zero-slip force offset, rolling resistance is neglected). The driven slip is the simple stand-in
for a differential: it balances the drag the tyres and the air produce, so that the speed stays constant.

Kinematics. Wheel i sits at (x_i, y_i): FL (a, +tf/2), FR (a, -tf/2), RL (-b, +tr/2), RR (-b, -tr/2). Its centre
moves with (body axes)

    vx_i = V cos(beta) - r y_i,        vy_i = V sin(beta) + r x_i,

and in the axes of the wheel, steered by delta_i (delta for the front wheels, 0 for the rear),

    vxw_i = vx_i cos(delta_i) + vy_i sin(delta_i),     vyw_i = -vx_i sin(delta_i) + vy_i cos(delta_i).

Slip angle (ISO-W, the convention of :class:`mftyre.MFModel`): alpha_i = atan(vyw_i / vxw_i). A wheel whose
centre moves to its own left (vyw > 0) has alpha > 0 and the tyre pushes it to the right (Fy < 0), as in ISO-W.
Check with a left turn: steering left (delta > 0) at beta = r = 0 gives vyw = -V sin(delta) < 0, so alpha < 0
and Fy > 0 (to the left, towards the centre of the turn); the rear wheels reach alpha < 0 through
vy = V sin(beta) - r b < 0, i.e. the body yaws into the turn (at speed beta < 0). The tyre speed input is vxw_i.

Loads. Vertical loads are algebraic (no suspension states). Equilibrium fixes the total ground forces the tyres
must carry in body axes, from the centripetal acceleration (-V r sin(beta), V r cos(beta)) and the drag
D = rho/2 CdA V^2 acting against the velocity at CoG height:

    FX = -m V r sin(beta) + D cos(beta),    FY = m V r cos(beta) + D sin(beta).

Pitch balance about the CoG gives the axle loads Fz_f = (m g b - h FX) / L + share_f * Lift, Fz_r = (m g a + h FX)
/ L + (1 - share_f) * Lift (Lift = rho/2 ClA V^2 downforce, split by ``aero_balance_front``). The lateral load
transfer of each axle (to the right wheels in a left turn) is the roll-centre part plus the roll-stiffness part:

    dFz_f = FY / tf * (b/L h_rcf + phi_f (h - h_ra)),   dFz_r = FY / tr * (a/L h_rcr + (1 - phi_f) (h - h_ra)),

with h_ra = (b h_rcf + a h_rcr) / L the roll-axis height under the CoG and phi_f the front share of the roll
stiffness (the axle lateral forces are taken in the static ratio b/L : a/L). The two parts add up to FY h.
Camber is zero and the tyres' overturning and rolling-resistance moments are not used.

Equilibrium residuals (:meth:`Vehicle.residuals`, N and N m): with the tyre forces (fx, fy, mz) of each wheel
rotated into body axes, Fx_i = fx cos(delta_i) - fy sin(delta_i), Fy_i = fx sin(delta_i) + fy cos(delta_i),

    R_x = sum Fx_i - FX,     R_y = sum Fy_i - FY,     R_n = sum (x_i Fy_i - y_i Fx_i + mz_i)

(the aligning moments are included; the air forces act at the CoG and add no yaw moment). At speed V the three
equations leave one degree of freedom: fixing the steer angle gives :meth:`Vehicle.steady_state`; maximising
ay = V r over the remaining freedom gives :meth:`Vehicle.max_lateral_acceleration`.

Numeric and symbolic paths. The same Python code (:meth:`Vehicle.wheel_states`) computes both: with NumPy
floats/arrays (broadcasting) it calls the tyres through :meth:`mftyre.MFModel.evaluate`; when any input is a
CasADi ``SX``/``MX`` symbol it calls the tyres' :meth:`mftyre.MFModel.casadi_function` (built once per vehicle)
and the elementary functions of CasADi. The two paths are checked against each other in the tests.

Optimisation. :meth:`Vehicle.max_lateral_acceleration` uses ``casadi.Opti`` with IPOPT and exact derivatives
(CasADi algorithmic differentiation through the Magic Formula); the inflation pressures of the front and rear
tyres can be design variables bounded by the .tir range [PRESMIN, PRESMAX]. The independent check
:meth:`Vehicle.brute_force_max_lateral_acceleration` uses only the NumPy path: it walks the curve of steady
states from straight running by pseudo-arclength continuation (finite-difference Newton of its own) and takes
its highest point (no CasADi, no optimiser, no exact derivatives). Near the limit that curve can fold back in
the steer angle (the car oversteers at the limit): the highest ay is then reached while the steer decreases,
and :meth:`Vehicle.steady_state` at a given steer has two solutions (or none beyond the fold). :func:`optimal_braking_slip`
maximises the braking force -Fx of one tyre over kappa at a given slip angle (IPOPT), checked by
:func:`brute_force_braking_slip` on a fine kappa grid.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from types import SimpleNamespace

import numpy as np

from .errors import ModelInputError
from .model import MFModel, load_tir

__all__ = ["VehicleParams", "Vehicle", "SolverStats", "SteadyState", "MaxLateralResult", "BruteForceResult",
           "BrakingSlipResult", "BruteForceBrakingResult", "optimal_braking_slip", "brute_force_braking_slip",
           "WHEELS"]

#: Wheel order used everywhere: front-left, front-right, rear-left, rear-right.
WHEELS = ("FL", "FR", "RL", "RR")
_MOUNT = {"FL": "left", "FR": "right", "RL": "left", "RR": "right"}
_TURN = {"left": 1.0, "right": -1.0}


# ----------------------------------------------------------------------------------------------- parameters
@dataclass(frozen=True)
class VehicleParams:
    """Vehicle data (SI). The default is a ~1300 kg front-heavy passenger car on 205/60 R15 tyres."""

    mass: float = 1300.0                 #: total mass [kg]
    a: float = 1.10                      #: CoG to front axle [m]
    b: float = 1.50                      #: CoG to rear axle [m]
    track_front: float = 1.48            #: front track width [m]
    track_rear: float = 1.46             #: rear track width [m]
    h_cog: float = 0.55                  #: CoG height [m]
    roll_stiffness_front: float = 0.60   #: front share of the total roll stiffness [-] (0..1)
    roll_centre_front: float = 0.0       #: front roll-centre height [m] (0: all transfer through roll stiffness)
    roll_centre_rear: float = 0.0        #: rear roll-centre height [m]
    max_steer: float = 0.6               #: steer lock of the front wheels [rad] (bound of the optimisation)
    drive: str = "rear"                  #: driven axle, 'rear' or 'front' (its two wheels share one slip)
    cd_area: float = 0.0                 #: drag coefficient x frontal area [m^2] (0: no drag)
    cl_area: float = 0.0                 #: downforce coefficient x area [m^2] (positive = downforce)
    aero_balance_front: float = 0.5      #: front share of the downforce [-]
    rho_air: float = 1.205               #: air density [kg/m^3]
    g: float = 9.81                      #: gravitational acceleration [m/s^2]

    def __post_init__(self):
        positive = ("mass", "a", "b", "track_front", "track_rear", "h_cog", "max_steer", "rho_air", "g")
        bad = [n for n in positive if not getattr(self, n) > 0]
        if bad:
            raise ModelInputError(f"vehicle parameter(s) {bad} must be positive")
        for n in ("roll_stiffness_front", "aero_balance_front"):
            if not 0.0 <= getattr(self, n) <= 1.0:
                raise ModelInputError(f"{n} must lie in [0, 1], got {getattr(self, n)!r}")
        if self.cd_area < 0:
            raise ModelInputError(f"cd_area must be >= 0, got {self.cd_area!r}")
        if self.drive not in ("rear", "front"):
            raise ModelInputError(f"drive must be 'rear' or 'front', got {self.drive!r}")

    @property
    def wheelbase(self) -> float:
        return self.a + self.b

    def positions(self) -> dict:
        """(x, y) of each wheel centre relative to the CoG [m]."""
        return {"FL": (self.a, self.track_front / 2), "FR": (self.a, -self.track_front / 2),
                "RL": (-self.b, self.track_rear / 2), "RR": (-self.b, -self.track_rear / 2)}


# ----------------------------------------------------------------------------------------------- results
@dataclass(frozen=True)
class SolverStats:
    """What a solver reported: name, success flag, return status, iteration count, wall time [s] of the solve
    call(s) (the first IPOPT solve of a cached problem also builds the solver) and the number of solver runs."""

    solver: str
    success: bool
    return_status: str
    iterations: int
    solve_time: float
    attempts: int = 1

    def __str__(self):
        more = f" in {self.attempts} attempts" if self.attempts > 1 else ""
        return (f"{self.solver}: {self.return_status} ({'ok' if self.success else 'FAILED'}), "
                f"{self.iterations} iterations{more}, {1e3 * self.solve_time:.1f} ms")


@dataclass(frozen=True)
class SteadyState:
    """A steady-state cornering point, re-evaluated with the NumPy path.

    ``wheels[name]`` holds the wheel quantities (fz, kappa, alpha, vx, fx, fy, mz in wheel axes; Fx, Fy in body
    axes); ``residuals`` are (R_x [N], R_y [N], R_n [N m]) of :meth:`Vehicle.residuals` at this point.
    """

    V: float
    delta: float
    beta: float
    r: float
    kappa: float
    p_front: float
    p_rear: float
    wheels: dict
    residuals: np.ndarray
    stats: SolverStats | None = None
    g: float = 9.81

    @property
    def ay(self) -> float:
        """Lateral (centripetal) acceleration V r [m/s^2]."""
        return self.V * self.r

    @property
    def ay_g(self) -> float:
        return self.ay / self.g

    @property
    def radius(self) -> float:
        """Path radius V / r [m] (inf when driving straight)."""
        return self.V / self.r if self.r != 0 else math.inf

    def summary(self) -> str:
        return (f"V={self.V:.2f} m/s  ay={self.ay:.3f} m/s^2 ({self.ay_g:.3f} g)"
                f"  delta={math.degrees(self.delta):.3f} deg  beta={math.degrees(self.beta):.3f} deg  r={self.r:.4f} rad/s  kappa={self.kappa:.5f}"
                f"  p=({self.p_front / 1e5:.3f}, {self.p_rear / 1e5:.3f}) bar")


@dataclass(frozen=True)
class MaxLateralResult:
    """The largest steady-state lateral acceleration at speed V (IPOPT)."""

    ay: float
    state: SteadyState
    pressures_optimised: bool
    stats: SolverStats
    active_bounds: tuple = ()      #: bounds active at the optimum (steer lock, slip-angle trust region, PRESMIN...)
    #: with optimised pressures: d(ay/g)/dp [1/Pa] of the front and rear pressure at their optimum from IPOPT's
    #: multipliers of the PRESMIN..PRESMAX bounds: what moving an active bound would gain (0 where inactive)
    pressure_sensitivity: tuple = ()

    @property
    def ay_g(self) -> float:
        return self.state.ay_g

    @property
    def p_front(self) -> float:
        return self.state.p_front

    @property
    def p_rear(self) -> float:
        return self.state.p_rear


@dataclass(frozen=True)
class BruteForceResult:
    """The largest lateral acceleration on the traced curve of steady states (no optimiser).

    ``curve``: the steady states of the first (coarse) walk in the order walked, arrays ``delta``, ``beta``,
    ``r``, ``kappa``, ``ay``. ``n_points``: steady states solved in all; ``n_evaluations``: residual evaluations
    (each evaluates the four tyres on a small batch of points).
    """

    ay: float
    state: SteadyState
    curve: dict
    n_points: int
    n_evaluations: int
    solve_time: float

    @property
    def ay_g(self) -> float:
        return self.state.ay_g


@dataclass(frozen=True)
class BrakingSlipResult:
    """The slip that maximises the braking force -Fx of one tyre at given load and slip angle (IPOPT)."""

    kappa: float
    fx: float
    fy: float
    fz: float
    alpha: float
    stats: SolverStats

    @property
    def mu_x(self) -> float:
        """Braking force over load, -Fx / Fz."""
        return -self.fx / self.fz


@dataclass(frozen=True)
class BruteForceBrakingResult:
    """The best slip of a kappa grid; ``kappa_grid``/``fx_grid`` hold the whole grid."""

    kappa: float
    fx: float
    kappa_grid: np.ndarray
    fx_grid: np.ndarray


# ----------------------------------------------------------------------------------------------- vehicle
def _is_symbolic(*values) -> bool:
    try:
        import casadi as ca
    except ImportError:  # pragma: no cover - casadi is a dependency
        return False
    return any(isinstance(v, (ca.SX, ca.MX)) for v in values)


def _ops(symbolic: bool):
    if symbolic:
        import casadi as ca

        return SimpleNamespace(sin=ca.sin, cos=ca.cos, atan=ca.atan)
    return SimpleNamespace(sin=np.sin, cos=np.cos, atan=np.arctan)


def _numeric(value):
    """A float array from a float, array or casadi.DM."""
    if hasattr(value, "full"):
        value = value.full()
    return np.asarray(value, dtype=float)


class Vehicle:
    """A steady-state two-track vehicle: :class:`VehicleParams` and four :class:`mftyre.MFModel` tyres.

    ``tyres``: a mapping with keys FL, FR, RL, RR (or a sequence in that order) of models mounted on the matching
    side (FL, RL 'left'; FR, RR 'right'), so that a vehicle with mirrored tyres is symmetric. See the module
    docstring for the equations and sign conventions.
    """

    def __init__(self, params: VehicleParams | None = None, tyres=None, *, limits: bool = True):
        self.params = params if params is not None else VehicleParams()
        if tyres is None:
            raise ModelInputError("Vehicle needs four tyres; use Vehicle.from_tir(path) for one .tir on all wheels")
        if not isinstance(tyres, dict):
            tyres = list(tyres)
            if len(tyres) != 4:
                raise ModelInputError(f"Vehicle needs 4 tyres (FL, FR, RL, RR), got {len(tyres)}")
            tyres = dict(zip(WHEELS, tyres))
        missing = [w for w in WHEELS if w not in tyres]
        if missing:
            raise ModelInputError(f"tyre(s) {missing} missing; keys are {', '.join(WHEELS)}")
        for w in WHEELS:
            if not isinstance(tyres[w], MFModel):
                raise ModelInputError(f"tyre {w} must be an MFModel, got {type(tyres[w]).__name__}")
            if tyres[w].side != _MOUNT[w]:
                raise ModelInputError(f"tyre {w} is mounted on the {tyres[w].side} side; use "
                                      f"model.with_side({_MOUNT[w]!r}) so that left and right are mirror images")
        self.tyres = {w: tyres[w] for w in WHEELS}
        self.limits = limits
        self._casadi_tyres = {}  # limits mode -> {wheel: casadi.Function}
        self._opti_cache = {}
        self._rootfinder = None

    @classmethod
    def from_tir(cls, path, params: VehicleParams | None = None, **kwargs) -> "Vehicle":
        """The same .tir on all four wheels, mounted left (FL, RL) and right (FR, RR)."""
        left = load_tir(path, side="left")
        right = left.with_side("right")
        return cls(params, {"FL": left, "FR": right, "RL": left, "RR": right}, **kwargs)

    def with_params(self, **changes) -> "Vehicle":
        """The same tyres on a vehicle with some parameters changed."""
        return Vehicle(replace(self.params, **changes), self.tyres, limits=self.limits)

    # ------------------------------------------------------------------------------------ pressures
    def pressure_bounds(self) -> tuple[float, float]:
        """[PRESMIN, PRESMAX] valid for all four tyres [Pa]."""
        lo = max(float(t.params.PRESMIN) for t in self.tyres.values())
        hi = min(float(t.params.PRESMAX) for t in self.tyres.values())
        return lo, hi

    def _pressures(self, p_front, p_rear):
        pf = float(self.tyres["FL"].params.INFLPRES) if p_front is None else p_front
        pr = float(self.tyres["RL"].params.INFLPRES) if p_rear is None else p_rear
        return pf, pr

    # ------------------------------------------------------------------------------------ equations
    def _tyre_forces(self, wheel, fz, kappa, alpha, vx, p, symbolic, limits=None):
        if symbolic:
            limits = self.limits if limits is None else limits
            if limits not in self._casadi_tyres:
                self._casadi_tyres[limits] = {
                    w: t.casadi_function(inputs=("fz", "kappa", "alpha", "vx", "p"), outputs=("fx", "fy", "mz"),
                                         limits=limits, name=f"tyre_{w}")
                    for w, t in self.tyres.items()}
            fx, fy, mz = self._casadi_tyres[limits][wheel](fz, kappa, alpha, vx, p)
            return fx, fy, mz
        out = self.tyres[wheel].evaluate(fz, kappa, alpha, vx=vx, p=p, limits=self.limits)
        return out.fx, out.fy, out.mz

    def wheel_states(self, V, delta, beta, r, kappa, p_front=None, p_rear=None, *, tyre_limits=None) -> dict:
        """Per-wheel kinematics, loads and forces (NumPy arrays, broadcast; or CasADi expressions).

        ``tyre_limits``: the symbolic tyres' ``limits`` mode (default: the vehicle's ``limits``).
        Returns ``{wheel: {vx, vy (wheel axes), alpha, kappa, fz, fx, fy, mz (wheel axes), Fx, Fy (body axes),
        x, y}}`` plus ``"total": {FX, FY}`` (the ground forces equilibrium requires).
        """
        P = self.params
        symbolic = _is_symbolic(V, delta, beta, r, kappa, p_front, p_rear)
        m = _ops(symbolic)
        p_front, p_rear = self._pressures(p_front, p_rear)
        if not symbolic:
            V, delta, beta, r, kappa, p_front, p_rear = (
                _numeric(v) for v in (V, delta, beta, r, kappa, p_front, p_rear))
        L = P.wheelbase
        q = 0.5 * P.rho_air * V * V
        drag, lift = P.cd_area * q, P.cl_area * q
        sb, cb = m.sin(beta), m.cos(beta)
        FX = -P.mass * V * r * sb + drag * cb
        FY = P.mass * V * r * cb + drag * sb
        fz_f = (P.mass * P.g * P.b - P.h_cog * FX) / L + P.aero_balance_front * lift
        fz_r = (P.mass * P.g * P.a + P.h_cog * FX) / L + (1.0 - P.aero_balance_front) * lift
        h_ra = (P.b * P.roll_centre_front + P.a * P.roll_centre_rear) / L
        dfz_f = FY / P.track_front * (P.b / L * P.roll_centre_front + P.roll_stiffness_front * (P.h_cog - h_ra))
        dfz_r = FY / P.track_rear * (P.a / L * P.roll_centre_rear + (1 - P.roll_stiffness_front) * (P.h_cog - h_ra))
        fz = {"FL": fz_f / 2 - dfz_f, "FR": fz_f / 2 + dfz_f, "RL": fz_r / 2 - dfz_r, "RR": fz_r / 2 + dfz_r}
        states = {}
        for w, (x, y) in P.positions().items():
            front = w[0] == "F"
            d = delta if front else 0.0
            driven = front == (P.drive == "front")
            k = kappa if driven else 0.0 * kappa
            vx = V * cb - r * y
            vy = V * sb + r * x
            sd, cd = (m.sin(d), m.cos(d)) if front else (0.0, 1.0)
            vxw = vx * cd + vy * sd
            vyw = -vx * sd + vy * cd
            alpha = m.atan(vyw / vxw)
            p = p_front if front else p_rear
            fx, fy, mz = self._tyre_forces(w, fz[w], k, alpha, vxw, p, symbolic, tyre_limits)
            states[w] = dict(x=x, y=y, vx=vxw, vy=vyw, alpha=alpha, kappa=k, fz=fz[w], p=p, fx=fx, fy=fy, mz=mz,
                             Fx=fx * cd - fy * sd, Fy=fx * sd + fy * cd)
        states["total"] = dict(FX=FX, FY=FY)
        return states

    def residuals(self, V, delta, beta, r, kappa, p_front=None, p_rear=None):
        """Equilibrium residuals (R_x [N], R_y [N], R_n [N m]); zero in steady state.

        Numeric inputs (floats or broadcastable arrays) give a NumPy array of shape (3, *broadcast shape);
        any CasADi SX/MX input gives a 3x1 CasADi expression. Pressures default to the tyres' INFLPRES.
        """
        return self._residuals_of(self.wheel_states(V, delta, beta, r, kappa, p_front, p_rear))

    @staticmethod
    def _residuals_of(s):
        rx = sum(s[w]["Fx"] for w in WHEELS) - s["total"]["FX"]
        ry = sum(s[w]["Fy"] for w in WHEELS) - s["total"]["FY"]
        rn = sum(s[w]["x"] * s[w]["Fy"] - s[w]["y"] * s[w]["Fx"] + s[w]["mz"] for w in WHEELS)
        if _is_symbolic(rx, ry, rn):
            import casadi as ca

            return ca.vertcat(rx, ry, rn)
        return np.stack(np.broadcast_arrays(rx, ry, rn))

    def _scales(self):
        P = self.params
        w = P.mass * P.g
        return np.array([w, w, w * P.wheelbase])

    def scaled_residuals(self, V, delta, beta, r, kappa, p_front=None, p_rear=None):
        """:meth:`residuals` divided by (m g, m g, m g L): the form the solvers use."""
        res = self.residuals(V, delta, beta, r, kappa, p_front, p_rear)
        sc = self._scales()
        if _is_symbolic(res):
            return res / sc
        return res / sc.reshape((3,) + (1,) * (res.ndim - 1))

    def state(self, V, delta, beta, r, kappa, p_front=None, p_rear=None, stats=None) -> SteadyState:
        """A :class:`SteadyState` evaluated (NumPy path) at the given point."""
        V, delta, beta, r, kappa = (float(_numeric(v)) for v in (V, delta, beta, r, kappa))
        p_front, p_rear = (float(_numeric(p)) for p in self._pressures(p_front, p_rear))
        s = self.wheel_states(V, delta, beta, r, kappa, p_front, p_rear)
        wheels = {w: {k: float(v) for k, v in s[w].items()} for w in WHEELS}
        res = self.residuals(V, delta, beta, r, kappa, p_front, p_rear)
        return SteadyState(V, delta, beta, r, kappa, p_front, p_rear, wheels, np.asarray(res, float), stats,
                           self.params.g)

    # ------------------------------------------------------------------------------------ initial guess
    def linear_guess(self, V, delta, p_front=None, p_rear=None):
        """(beta, r, kappa) of the linear single-track model at steer ``delta``: a starting point."""
        P = self.params
        L = P.wheelbase
        pf, pr = self._pressures(p_front, p_rear)
        fzf, fzr = P.mass * P.g * P.b / L / 2, P.mass * P.g * P.a / L / 2
        cf = 2 * abs(float(self.tyres["FL"].evaluate(fzf, 0.0, 0.0, vx=V, p=pf).kya))
        cr = 2 * abs(float(self.tyres["RL"].evaluate(fzr, 0.0, 0.0, vx=V, p=pr).kya))
        k_us = P.mass / L * (P.b / cf - P.a / cr)
        r = V * delta / (L + k_us * V * V)
        beta = P.b * r / V - P.mass * P.a * V * r / (L * cr)
        return beta, r, 0.0

    def _start_point(self, V, sign, pf, pr, ay0_g=0.5):
        """(delta, beta, r, kappa) of the steady state at the steer that the linear single-track model needs
        for ay = ``ay0_g`` g: a feasible point well inside the limit, from which IPOPT starts."""
        P = self.params
        _, r1, _ = self.linear_guess(V, 1e-3, pf, pr)        # linear: everything proportional to steer
        d0 = sign * 1e-3 * ay0_g * P.g / (V * r1)
        ss = self.steady_state(V, d0, pf, pr)
        if ss.stats.success:
            return (d0, ss.beta, ss.r, ss.kappa)
        return (d0, *self.linear_guess(V, d0, pf, pr))

    # ------------------------------------------------------------------------------------ steady state
    def _get_rootfinder(self):
        if self._rootfinder is None:
            import casadi as ca

            x = ca.SX.sym("x", 3)      # beta, r, kappa
            prm = ca.SX.sym("prm", 4)  # V, delta, p_front, p_rear
            res = self.scaled_residuals(prm[0], prm[1], x[0], x[1], x[2], prm[2], prm[3])
            g = ca.Function("equilibrium", [x, prm], [res])
            self._rootfinder = ca.rootfinder("steady_state", "newton", g,
                                             {"abstol": 1e-11, "max_iter": 50, "error_on_fail": False,
                                              "line_search": True})
        return self._rootfinder

    def steady_state(self, V, delta, p_front=None, p_rear=None, x0=None, *, max_continuation: int = 16) -> SteadyState:
        """Solve the equilibrium for (beta, r, kappa) at speed ``V`` [m/s] and steer ``delta`` [rad].

        CasADi Newton rootfinder with exact Jacobian, started from ``x0`` = (beta, r, kappa) or the linear
        single-track guess. If Newton fails from there, the steer is ramped up from zero in up to
        ``max_continuation`` steps (warm-started). ``stats.success`` says whether a solution was found; when
        there is none (beyond the limit), the last iterate is returned with ``success=False``. Where the
        steady-state curve folds back in steer (see the module docstring), one steer has two steady states;
        from the default start Newton finds the one of lower ay.
        """
        rf = self._get_rootfinder()
        pf, pr = self._pressures(p_front, p_rear)
        t0 = time.perf_counter()
        iters = 0

        def solve(d, guess):
            nonlocal iters
            x = rf(guess, [V, d, pf, pr])
            st = rf.stats()
            iters += int(st.get("iter_count", 0))
            x = np.asarray(x.full(), float).ravel()
            ok = bool(st.get("success", False)) and np.all(np.isfinite(x))
            if ok:
                ok = np.max(np.abs(_numeric(self.scaled_residuals(V, d, *x, pf, pr)))) < 1e-8
            return x, ok, str(st.get("return_status", ""))

        guess = np.asarray(x0 if x0 is not None else self.linear_guess(V, delta, pf, pr), float)
        x, ok, status = solve(delta, guess)
        n = 2
        while not ok and n <= max_continuation:
            guess = np.zeros(3)
            for d in np.linspace(0.0, delta, n + 1)[1:]:
                x, ok, status = solve(d, guess)
                if not ok:
                    break
                guess = x
            n *= 2
        stats = SolverStats("casadi rootfinder (newton)", bool(ok), status, iters, time.perf_counter() - t0)
        return self.state(V, delta, *x, pf, pr, stats=stats)

    # ------------------------------------------------------------------------------------ max ay (IPOPT)
    def _build_max_ay(self, optimise_pressures: bool, sign: float, slip_angle_max, ipopt_options: dict | None):
        import casadi as ca

        P = self.params
        opti = ca.Opti()
        x = opti.variable(4)                         # delta, beta, r, kappa
        V = opti.parameter()
        if optimise_pressures:
            p_scale = 1e5                            # pressures in bar inside the NLP
            pv = opti.variable(2)
            p_lo, p_hi = self.pressure_bounds()
            pressure_bounds = (pv >= p_lo / p_scale, pv <= p_hi / p_scale)
            opti.subject_to(pressure_bounds[0])
            opti.subject_to(pressure_bounds[1])
        else:
            p_scale = 1.0
            pv = opti.parameter(2)
            pressure_bounds = None
        delta, beta, r, kappa = x[0], x[1], x[2], x[3]
        # pressures as decision variables: limits="smooth" gives them the full slope at and a hair beyond their
        # bounds (IPOPT relaxes bounds by ~1e-8), where True's saturation would leave them none
        tyre_limits = "smooth" if optimise_pressures and self.limits is True else self.limits
        s = self.wheel_states(V, delta, beta, r, kappa, pv[0] * p_scale, pv[1] * p_scale, tyre_limits=tyre_limits)
        opti.minimize(-sign * V * r / P.g)
        opti.subject_to(self._residuals_of(s) / self._scales() == 0)
        opti.subject_to(opti.bounded(-P.max_steer, delta, P.max_steer))
        opti.subject_to(opti.bounded(-0.5, beta, 0.5))
        opti.subject_to(opti.bounded(-0.15, kappa, 0.15))
        opti.subject_to(sign * r >= 0)
        if slip_angle_max:
            for w in WHEELS:
                opti.subject_to(opti.bounded(-slip_angle_max, s[w]["alpha"], slip_angle_max))
        options = {"print_level": 0, "tol": 1e-10, "acceptable_tol": 1e-8, "max_iter": 200, "sb": "yes"}
        options.update(ipopt_options or {})
        opti.solver("ipopt", {"expand": True, "print_time": False}, options)
        return SimpleNamespace(opti=opti, x=x, V=V, pv=pv, p_scale=p_scale, pressure_bounds=pressure_bounds)

    def max_lateral_acceleration(self, V, pressures=None, *, turn: str = "left", x0=None,
                                 slip_angle_max: float | None = 0.35, starts=(0.5, 0.7, 0.3),
                                 ipopt_options: dict | None = None) -> MaxLateralResult:
        """The largest steady-state lateral acceleration ay = V r at speed ``V`` [m/s] (IPOPT, exact derivatives).

        Decision variables: steer delta, sideslip beta, yaw rate r, driven slip kappa; constraints: the three
        equilibrium equations (scaled by m g, m g, m g L), |delta| <= ``params.max_steer``, |beta| <= 0.5,
        |kappa| <= 0.15 and, unless ``slip_angle_max`` is None, |alpha| <= ``slip_angle_max`` [rad] at every
        wheel: a trust region that keeps IPOPT's early steps on the physical branch (the tyres' force peaks lie
        well inside it; :attr:`MaxLateralResult.active_bounds` names any bound active at the optimum).

        ``pressures``: None (the tyres' INFLPRES), a pair (p_front, p_rear) [Pa], or 'optimise' (both become
        design variables within the tyres' [PRESMIN, PRESMAX]). ``turn``: 'left' (r > 0) or 'right'.

        Start: ``x0`` = (delta, beta, r, kappa[, p_front, p_rear]), else the steady state (solved) at the steer
        the linear single-track model needs for ay = ``starts[0]`` g; if IPOPT fails from there, it is
        restarted from the next entry of ``starts`` (``stats.attempts`` counts the solves, ``stats.iterations``
        and ``stats.solve_time`` add them up). The Opti problem is built once per mode and re-solved with new
        parameter values, so sweeps are cheap. ``ay`` is signed (negative in a right turn).
        """
        if turn not in _TURN:
            raise ModelInputError(f"turn must be 'left' or 'right', got {turn!r}")
        sign = _TURN[turn]
        optimise = isinstance(pressures, str)
        if optimise and pressures not in ("optimise", "optimize"):
            raise ModelInputError(f"pressures must be None, (p_front, p_rear) or 'optimise', got {pressures!r}")
        key = (optimise, sign, slip_angle_max, tuple(sorted((ipopt_options or {}).items())))
        if key not in self._opti_cache:
            self._opti_cache[key] = self._build_max_ay(optimise, sign, slip_angle_max, ipopt_options)
        prob = self._opti_cache[key]
        opti = prob.opti
        pf, pr = self._pressures(*(pressures if (pressures is not None and not optimise) else (None, None)))
        opti.set_value(prob.V, V)
        if not optimise:
            opti.set_value(prob.pv, [pf, pr])
        guesses = [x0] if x0 is not None else [None] * len(starts)
        iters, wall, attempts = 0, 0.0, 0
        for k, guess in enumerate(guesses):
            if guess is None:
                guess = self._start_point(V, sign, pf, pr, starts[k])
            guess = list(guess)
            opti.set_initial(prob.x, guess[:4])
            if optimise:
                p0 = guess[4:6] if len(guess) >= 6 else [pf, pr]
                opti.set_initial(prob.pv, [p / prob.p_scale for p in p0])
            t0 = time.perf_counter()
            try:
                sol = opti.solve()
                values, pvals = sol.value(prob.x), sol.value(prob.pv)
            except RuntimeError:  # not converged: keep the last iterate and the solver's status
                sol = opti.debug
                values, pvals = sol.value(prob.x), sol.value(prob.pv)
            # the multipliers (>= 0) of p >= PRESMIN and p <= PRESMAX: d(-ay/g)/d(bound) is +lower, -upper (pressures
            # in units of p_scale inside the NLP)
            sensitivity = (tuple(float(v) for v in (np.ravel(sol.value(opti.dual(prob.pressure_bounds[1])))
                                  - np.ravel(sol.value(opti.dual(prob.pressure_bounds[0])))) / prob.p_scale)
                           if optimise else ())
            wall += time.perf_counter() - t0
            st = opti.stats()
            iters += int(st.get("iter_count", 0))
            attempts += 1
            success = bool(st.get("success", False))
            if success:
                break
        stats = SolverStats("ipopt", success, str(st.get("return_status", "")), iters, wall, attempts)
        values = np.atleast_1d(values).astype(float)
        pvals = np.atleast_1d(pvals).astype(float) * prob.p_scale
        if optimise:  # IPOPT relaxes bounds by ~1e-8 relative: put the pressures back into the .tir range
            pvals = np.clip(pvals, *self.pressure_bounds())
        state = self.state(V, *values, pvals[0], pvals[1], stats=stats)
        active = self._active_bounds(state, optimise, slip_angle_max)
        return MaxLateralResult(ay=state.ay, state=state, pressures_optimised=optimise, stats=stats,
                                active_bounds=active, pressure_sensitivity=sensitivity)

    def _active_bounds(self, state, optimise, slip_angle_max, tol=1e-6):
        P = self.params
        active = []
        if abs(state.delta) > P.max_steer - tol:
            active.append("max_steer")
        if abs(state.beta) > 0.5 - tol:
            active.append("beta")
        if abs(state.kappa) > 0.15 - tol:
            active.append("kappa")
        if slip_angle_max:
            active += [f"slip_angle_{w}" for w in WHEELS if abs(state.wheels[w]["alpha"]) > slip_angle_max - tol]
        if optimise:
            lo, hi = self.pressure_bounds()
            for name, p in (("front", state.p_front), ("rear", state.p_rear)):
                if p < lo + tol * 1e5:
                    active.append(f"PRESMIN_{name}")
                if p > hi - tol * 1e5:
                    active.append(f"PRESMAX_{name}")
        return tuple(active)

    # ------------------------------------------------------------------------------------ brute force
    def _curve_residuals(self, U, V, pf, pr):
        """Scaled residuals at points U = (delta, beta, r L / V, kappa) (columns); NumPy path only."""
        U = np.asarray(U, float)
        r = U[2] * V / self.params.wheelbase
        return _numeric(self.scaled_residuals(V, U[0], U[1], r, U[3], pf, pr))

    def _correct(self, u_pred, t, V, pf, pr, tol=1e-11, max_iter=30, h=1e-7):
        """Newton (forward-difference Jacobian, backtracking) on {residuals = 0, t . (u - u_pred) = 0}.

        Returns (u, jacobian at u, converged, residual evaluations)."""
        u = np.array(u_pred, float)
        n_eval = 0
        eye = np.hstack([np.zeros((4, 1)), np.eye(4)])
        for _ in range(max_iter):
            fs = self._curve_residuals(u[:, None] + h * eye, V, pf, pr)      # base + 4 perturbations at once
            n_eval += 5
            f, jac = fs[:, 0], (fs[:, 1:] - fs[:, :1]) / h
            g = np.append(f, t @ (u - u_pred))
            if not np.all(np.isfinite(g)):
                return u, jac, False, n_eval
            if np.max(np.abs(g)) < tol:
                return u, jac, True, n_eval
            try:
                du = np.linalg.solve(np.vstack([jac, t]), -g)
            except np.linalg.LinAlgError:
                return u, jac, False, n_eval
            norm0, lam = np.linalg.norm(g), 1.0
            while lam > 1e-3:
                un = u + lam * du
                fn = self._curve_residuals(un, V, pf, pr)
                n_eval += 1
                gn = np.append(fn, t @ (un - u_pred))
                if np.all(np.isfinite(gn)) and np.linalg.norm(gn) < (1 - 1e-4 * lam) * norm0:
                    break
                lam *= 0.5
            else:
                return u, jac, False, n_eval
            u = un
        return u, jac, False, n_eval

    @staticmethod
    def _tangent(jac, t_prev):
        """Unit tangent of the solution curve (null vector of the 3x4 Jacobian), oriented like ``t_prev``."""
        tau = np.linalg.solve(np.vstack([jac, t_prev]), np.array([0.0, 0.0, 0.0, 1.0]))
        return tau / np.linalg.norm(tau)

    def brute_force_max_lateral_acceleration(self, V, pressures=None, *, turn: str = "left", step: float = 0.004,
                                             refine: int = 10, max_steps: int = 1000) -> BruteForceResult:
        """An independent search for the largest ay: walk the curve of steady states and take its highest point.

        At speed V the equilibrium equations leave a one-dimensional set of steady states (delta, beta, r, kappa).
        It is traced from straight running into the turn by pseudo-arclength continuation (predictor along the
        tangent, corrector by Newton with a finite-difference Jacobian and the arclength condition, step halving
        on failure), using only the NumPy path: no CasADi, no exact derivatives, no optimiser. Arclength makes
        the walk indifferent to folds in steer or sideslip. Coordinates: (delta, beta, r L/V, kappa), ``step``
        their arclength per step. Once ay falls, the walk restarts two points back with ``step / refine`` until ay
        falls again, and the largest ay is located by a parabola through the best three points and a last
        corrector solve there. ``curve`` holds every point walked.
        """
        if turn not in _TURN:
            raise ModelInputError(f"turn must be 'left' or 'right', got {turn!r}")
        sign = _TURN[turn]
        pf, pr = self._pressures(*(pressures if pressures is not None else (None, None)))
        L = self.params.wheelbase
        t0 = time.perf_counter()
        n_eval = n_points = 0

        def ay_of(u):
            return sign * V * u[2] * V / L

        def walk(u, t, ds, n_fall_stop):
            """Continue from (u, t) with step ds until ay has fallen ``n_fall_stop`` times in a row."""
            nonlocal n_eval, n_points
            path = [(u, t)]
            fall, steps, h = 0, 0, ds
            while steps < max_steps:
                u_new, jac, ok, n = self._correct(u + h * t, t, V, pf, pr)
                n_eval += n
                if not ok:
                    h /= 2
                    if h < ds / 64:
                        raise ArithmeticError(f"continuation stalled at {u} (no equilibrium found near it)")
                    continue
                t = self._tangent(jac, t)
                u, h, steps = u_new, min(2 * h, ds), steps + 1
                path.append((u, t))
                n_points += 1
                fall = fall + 1 if ay_of(u) < ay_of(path[-2][0]) else 0
                if fall >= n_fall_stop:
                    return path
            raise ArithmeticError(f"no maximum of ay within {max_steps} continuation steps")

        # straight running: the steady state with delta = 0
        e_delta = np.array([1.0, 0.0, 0.0, 0.0])
        u0, jac, ok, n = self._correct(np.zeros(4), e_delta, V, pf, pr)
        n_eval += n
        if not ok:
            raise ArithmeticError("no straight-running steady state found")
        t = self._tangent(jac, e_delta)
        t = t if sign * t[2] > 0 else -t             # into the requested turn
        n_points += 1
        path = walk(u0, t, step, 1)
        coarse = [p[0] for p in path]
        u, t = path[-3] if len(path) >= 3 else path[0]
        path = walk(u, t, step / refine, 1)
        # parabola through the best three (ay against the distance along the middle point's tangent)
        (ua, _), (um, tm), (ub, _) = path[-3:]
        sig = np.array([tm @ (ua - um), 0.0, tm @ (ub - um)])
        c = np.polyfit(sig, [ay_of(ua), ay_of(um), ay_of(ub)], 2)
        best = um
        if c[0] < 0:
            s_star = -c[1] / (2 * c[0])
            u_star, _, ok, n = self._correct(um + s_star * tm, tm, V, pf, pr)
            n_eval += n
            if ok and ay_of(u_star) >= ay_of(um):
                best = u_star
                n_points += 1
        wall = time.perf_counter() - t0
        delta, beta, r, kappa = best[0], best[1], best[2] * V / L, best[3]
        stats = SolverStats("pseudo-arclength continuation + finite-difference Newton", True, "curve maximum",
                            n_points, wall)
        state = self.state(V, delta, beta, r, kappa, pf, pr, stats=stats)
        pts = np.array(coarse)
        curve = dict(delta=pts[:, 0], beta=pts[:, 1], r=pts[:, 2] * V / L, kappa=pts[:, 3])
        curve["ay"] = V * curve["r"]
        return BruteForceResult(ay=state.ay, state=state, curve=curve, n_points=n_points, n_evaluations=n_eval,
                                solve_time=wall)


# ----------------------------------------------------------------------------------------------- braking slip
def optimal_braking_slip(model: MFModel, fz, alpha, *, gamma=0.0, vx=None, p=None, kappa_min=None, kappa0=-0.05,
                         limits: bool = True, ipopt_options: dict | None = None) -> BrakingSlipResult:
    """The longitudinal slip that maximises the braking force -Fx at load ``fz`` [N] and slip angle ``alpha``.

    Combined slip: the tyre keeps the slip angle ``alpha`` [rad] while braking. IPOPT over kappa in
    [kappa_min, 0] (default kappa_min: the .tir KPUMIN, at least -1), started at ``kappa0``, with the exact
    derivative of Fx from :meth:`mftyre.MFModel.casadi_function`.
    """
    import casadi as ca

    prm = model.params
    lo = max(float(getattr(prm, "KPUMIN", -1.0)), -1.0) if kappa_min is None else float(kappa_min)
    fixed = dict(fz=float(fz), alpha=float(alpha), gamma=float(gamma))
    if vx is not None:
        fixed["vx"] = float(vx)
    if p is not None:
        fixed["p"] = float(p)
    f = model.casadi_function(inputs=("kappa",), outputs=("fx", "fy"), fixed=fixed, limits=limits, name="tyre")
    opti = ca.Opti()
    kappa = opti.variable()
    fx_scale = max(abs(float(fz)), 1.0)
    opti.minimize(f(kappa)[0] / fx_scale)
    opti.subject_to(opti.bounded(lo, kappa, 0.0))
    opti.set_initial(kappa, kappa0)
    options = {"print_level": 0, "tol": 1e-12, "max_iter": 200, "sb": "yes"}
    options.update(ipopt_options or {})
    opti.solver("ipopt", {"expand": True, "print_time": False}, options)
    t0 = time.perf_counter()
    try:
        k = float(opti.solve().value(kappa))
    except RuntimeError:
        k = float(opti.debug.value(kappa))
    wall = time.perf_counter() - t0
    st = opti.stats()
    stats = SolverStats("ipopt", bool(st.get("success", False)), str(st.get("return_status", "")),
                        int(st.get("iter_count", -1)), wall)
    out = model.evaluate(fz, k, alpha, gamma=gamma, vx=vx, p=p, limits=limits)
    return BrakingSlipResult(kappa=k, fx=float(out.fx), fy=float(out.fy), fz=float(fz), alpha=float(alpha),
                             stats=stats)


def brute_force_braking_slip(model: MFModel, fz, alpha, *, gamma=0.0, vx=None, p=None, kappa_min=None,
                             n: int = 20001, limits: bool = True) -> BruteForceBrakingResult:
    """The best kappa of an evenly spaced grid of ``n`` slips in [kappa_min, 0] (NumPy path)."""
    prm = model.params
    lo = max(float(getattr(prm, "KPUMIN", -1.0)), -1.0) if kappa_min is None else float(kappa_min)
    grid = np.linspace(lo, 0.0, n)
    fx = model.evaluate(fz, grid, alpha, gamma=gamma, vx=vx, p=p, limits=limits).fx
    i = int(np.argmin(fx))
    return BruteForceBrakingResult(kappa=float(grid[i]), fx=float(fx[i]), kappa_grid=grid, fx_grid=fx)
