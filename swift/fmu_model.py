"""The SWIFT tyre on a wheel, driven the way a vehicle simulator drives it (and the native FMU runs it): the
rigid ring of :mod:`swift.ring` stepped by :class:`swift.simulate.SwiftTyre`'s RK4 step over a road table.

    import mftyre
    from mftyre.transient import free_rolling_start
    from swift.fmu_model import SwiftWheel
    model = mftyre.load_tir("tir_files/car_205_60R15_mf62_swift.tir")
    wheel = SwiftWheel(model, "cleat(x0=3.0, length=0.05, height=0.01)")
    omega, z = free_rolling_start(model, 10.0)     # free rolling under FNOMIN (also the FMU's start inputs)
    wheel.set_inputs(vx=10.0, omega=omega, z=z)
    wheel.set_parameters(x_start=0.0)
    wheel.initialise()
    wheel.step(1e-3); wheel.outputs()["Fz"]

Modes: axle height imposed (input ``z``, wheel-centre height above the road datum, moving with ``vz`` within a
step) or (``axle="load"``) the axle of AXLE_MASS pushed down by the input ``Fz_in``; spin imposed (``omega``) or
(``rim="torque"``) the rim driven by the input ``torque``; the road is the profile lifted by ``road_z`` (held over a step) and tilted by
``road_camber`` (the ring's input, added to the multi-track camber of a 3D profile). The wheel starts at
``x_start`` on the road (x_road = x_start + integral of vx dt: obstacles are met where they are, whatever the
start) in static equilibrium (the Newton iteration of
:meth:`swift.simulate.SwiftTyre.equilibrium_function`, 30 steps). A step of length h is split into
n = max(ceil(h / min(max_step, MAX_RK4_STEP)), ceil(|vx| h / MAX_TRAVEL)) equal RK4 steps (``SUBSTEPS``; RK4 steps
above MAX_RK4_STEP = 1 ms let a parked tyre drift, see swift.simulate); before each the
cam-height window (``WINDOW`` samples of the table, step ``TABLE_DX``) is placed around the belt, clamped to the table, whose
ends are constant road (the table spans the obstacles plus the cam reach plus a window on each side), so any
distance can be driven. The rim's lateral position is the frame origin (the belt's y is moved back by vy dt
after each step). The same functions are generated as C for the native FMU; this class evaluates them with
CasADi, so both give the same numbers.
"""
from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass

import numpy as np

from mftyre.errors import ModelInputError
from mftyre.inputs import check_speed_limits
from mftyre.transient import StateFunctions, start_inputs
from mftyre.variables import pick

from .enveloping import Cams
from .ring import INPUT_NAMES, OUTPUT_NAMES, STATE_NAMES, check_pressure, pressure_coefficients
from .road import parse_road
from .simulate import COMPILER_FLAGS, EQUILIBRIUM_TOL, MAX_RK4_STEP, NO_EQUILIBRIUM, GeneratedFunction, \
    no_rolling_root_template

__all__ = ["SwiftWheel", "swift_functions", "internal_steps", "input_table", "RIM_MODES", "INPUTS", "OUTPUTS",
           "PARAMETERS", "TABLE_DX", "WINDOW",
           "MAX_TRAVEL", "SUBSTEPS", "STEP_RATE_LIMIT", "MAX_STEPS_PER_CALL"]

TABLE_DX = 1e-3
WINDOW = 1024
#: Largest wheel travel [m] within one RK4 step (the cam-height window is fixed over a step).
MAX_TRAVEL = 0.2
NEWTON_STEPS = 30
#: RK4 steps per internal step of max_step: one, so max_step is the RK4 step. The default max_step = 1 ms keeps
#: Fz over a 10 mm cleat at 10 m/s within 1.7 % of its swing from a 0.25 ms solution; max_step = 0.5 ms gives
#: swift.SwiftTyre's default accuracy (two RK4 steps per ms: 0.9 %) at twice the cost.
SUBSTEPS = 1
#: Internal steps per simulated second one communication step may take (the time budget of a step).
STEP_RATE_LIMIT = 1e6
#: Most internal steps one communication step may take, whatever its length (the work of one call, at about 10 us
#: of CPU per internal step: ~2 s, what a host waits for; a 9,999 s step took 1e7 steps and 109 s). At the default
#: max_step of 1 ms a step may be up to 200 s long. docs/resource-limits.md.
MAX_STEPS_PER_CALL = 200_000

#: The wheel's variables: name -> Variable (mftyre.variables), in the order of the vectors.
INPUTS = pick("input", "vx", "vy", "omega", "gamma", "z", "vz", "p", "road_z", "road_camber", describe={
    "omega": "rim spin speed (imposed; positive rolling forwards; start: free rolling at the start vx under FNOMIN)",
    "gamma": "rim inclination (camber) about ISO-W x",
    "z": "wheel-centre height above the road datum, ISO-W z (imposed; start: the loaded radius at FNOMIN)",
    "road_z": "height of the whole road profile above the road datum (the tyre meets z - road_z)",
    "road_camber": "road camber angle about ISO-W x (> 0: the road rises to the left), added to the profile's own "
                   "multi-track camber"})
#: speed: the rim spins at the input omega; torque: the input torque drives the rim (from the static equilibrium
#: started at free rolling, swift.simulate.free_rolling_spin; the input omega is not used).
RIM_MODES = ("speed", "torque")
#: height: the axle height z (and vz) imposed; load: the downward force Fz_in on the axle (mass AXLE_MASS) moves it.
AXLE_MODES = ("height", "load")
#: Mass [kg] of the axle the load input pushes down (axle="load"; swift.SwiftTyre's default, the pythonfmu FMU's
#: axle_mass start).
AXLE_MASS = 30.0


def input_table(rim: str = "speed", axle: str = "height") -> dict:
    """The wheel's inputs (name -> Variable) with the rim mode ``rim`` and the axle mode ``axle``."""
    table = dict(INPUTS)
    if rim == "torque":
        table["omega"] = INPUTS["omega"].but(description="not used: the rim starts in static equilibrium (the "
                                                         "spin solved for from free rolling) and the torque "
                                                         "drives it afterwards")
        table.update(pick("input", "torque"))
    if axle == "load":
        del table["z"], table["vz"]
        table.update(pick("input", "Fz_in", describe={"Fz_in": f"downward force on the axle (mass {AXLE_MASS:g} kg), "
                                                                "which moves under it and the tyre's force"}))
    return table


PARAMETERS = pick("parameter", "x_start", "max_step")
OUTPUTS = pick(
    "output", "Fx", "Fy", "Fz", "Mx", "My", "Mz", "Fx_c", "Fy_c", "Fz_c", "Mz_c", "kappa", "alpha", "rho", "Rl", "Re",
    "contact_length", "road_w", "road_slope", "road_curvature", "Re_variation", "road_camber_eff", "x_contact",
    "x_road", "Mx_c", "My_c", "contact_width", "trail", "mux", "muy", "Vsx", "Vsy", "omega_used", describe={
        "Fx": "force on the rim along ISO-W x, at the wheel centre",
        "Fy": "force on the rim along ISO-W y, at the wheel centre",
        "Fz": "force on the rim along ISO-W z (up), at the wheel centre",
        "Mx": "moment on the rim about ISO-W x", "My": "moment on the rim about ISO-W y (about the axle)",
        "Mz": "moment on the rim about ISO-W z", "Mz_c": "self-aligning moment of the contact patch",
        "kappa": "transient longitudinal slip of the contact patch",
        "alpha": "transient slip angle of the contact patch",
        "rho": "tyre deflection normal to the effective road",
        "Rl": "loaded radius: wheel centre to the effective road plane, (z - road_w) cos(road_slope)",
        "Vsx": "longitudinal slip speed of the contact patch, -kappa |Vcx|",
        "Vsy": "lateral slip speed of the contact patch, tan(alpha) |Vcx|",
        "omega_used": "rim spin speed (the input, or driven by the torque)",
        "road_w": "effective road height (tandem cams)"})
#: The outputs taken from the MF at the ring's contact state (the ring does not report them).
_MF_EXTRAS = {"Mx_c": "mx", "My_c": "my", "contact_width": "b", "trail": "t", "mux": "mux", "muy": "muy"}
_RING = {"Fx": "fx", "Fy": "fy", "Fz": "fz", "Mx": "mx", "My": "my", "Mz": "mz", "Fx_c": "fx_c", "Fy_c": "fy_c",
         "Fz_c": "fz_c", "Mz_c": "mz_c", "kappa": "kappa", "alpha": "alpha", "rho": "rho", "Re": "re",
         "road_slope": "beta", "road_curvature": "curvature", "Re_variation": "dre", "road_camber_eff": "beta_x",
         "x_contact": "x_c"}
_S = {n: i for i, n in enumerate(STATE_NAMES)}


def internal_steps(h: float, max_step: float, vx: float) -> int:
    """How many equal RK4 steps a communication step of ``h`` [s] is split into (module notes; the C wrapper
    glue_swift.c spells the same rule): steps of at most ``max_step`` and MAX_RK4_STEP, and short enough that the
    wheel travels at most MAX_TRAVEL in one. A step that would need more than STEP_RATE_LIMIT internal steps per
    simulated second, or more than MAX_STEPS_PER_CALL in all, is refused (ModelInputError)."""
    n = max(math.ceil(h / min(max_step, MAX_RK4_STEP) - 1e-9), math.ceil(abs(vx) * h / MAX_TRAVEL))
    if not (n <= math.ceil(h * STEP_RATE_LIMIT) and n <= MAX_STEPS_PER_CALL):
        raise ModelInputError(f"the step of {h!r} s needs {n:.3g} internal steps, more than its time budget "
                              f"({STEP_RATE_LIMIT:g} per simulated second, {MAX_STEPS_PER_CALL:,} per call): max_step "
                              "too small, the speed too high or the step too long for this model (split it)")
    return max(1, n)


def contact_extras(model, ring_out, gamma, p, omega_belt, be, mf=None) -> dict:
    """The outputs the ring does not report, from the MF at its contact state (``ring_out``: the ring's outputs by
    name): Mx_c, My_c, contact_width, trail, mux, muy at the load Fz_c (at least 1 mN), the slip -Vsx / Vcx given
    as the wheel's (:func:`mftyre.transient.mf_slip`), the belt spin; Vsx, Vsy of the ring's slips at |Vcx|.
    ``mf``: the MF (fz, kappa, alpha, gamma, vx, p, omega) -> (mx, my, b, t, mux, muy), default the model's."""
    from mftyre.transient import mf_slip, slip_speeds

    if mf is None:
        mf = model.casadi_function(inputs=("fz", "kappa", "alpha", "gamma", "vx", "p", "omega"),
                                   outputs=tuple(_MF_EXTRAS.values()), name="mf_extras")
    kappa, alpha, vcx = ring_out["kappa"], ring_out["alpha"], ring_out["vcx"]
    values = mf(be.fmax(ring_out["fz_c"], 1e-3), mf_slip(kappa, vcx, be), alpha, gamma, vcx, p, omega_belt)
    extras = dict(zip(_MF_EXTRAS, values))
    extras["contact_width"] = 2.0 * extras["contact_width"]
    extras["Vsx"], extras["Vsy"] = slip_speeds(kappa, alpha, be.abs(vcx), be)
    return extras


@dataclass(frozen=True)
class SwiftFunctions(StateFunctions):
    """The SWIFT wheel's CasADi functions (window arguments ``x0w``, ``grid``, ``hw``: the table window, see module
    notes; ``hw`` holds (cam height, road-camber slope) pairs, interleaved, as ``table_h``):
    ``init(u, q, x0w, grid, hw) -> x``, ``step(x, u, dt, x0w, grid, hw) -> x_next`` (one RK4 step),
    ``out(x, u, x0w, grid, hw) -> y``, ``residual(x, u, x0w, grid, hw) -> r`` (the equilibrium equations'
    derivatives ``residual_names``, refused above EQUILIBRIUM_TOL with NO_EQUILIBRIUM, as
    :meth:`swift.simulate.SwiftTyre.initial_state`), ``root(x, u, x0w, grid, hw) -> facts`` (the rule that a static
    root is a rolling tyre, :attr:`swift.simulate.SwiftTyre.rolling_root_function`; the refusal
    ``root_message % (start_text(u, q), *facts[1:])``); the road table and the C definitions (``config_extra``) of
    the native glue."""

    table_x0: float
    table_dx: float
    table_h: np.ndarray
    grid: np.ndarray
    output_dependencies: list
    config_extra: str
    rim: str = "speed"
    axle: str = "height"
    root: object = None
    root_message: str = ""
    residual: object = None
    residual_names: tuple = ()

    def start_text(self, u, q) -> str:
        """The start's values (:func:`start_description`) as the native glue prints them."""
        names = {"u": self.input_names, "q": self.parameter_names}
        values = {"u": u, "q": q}
        form, described = start_description(self.rim, self.axle)
        return form % tuple(float(values[vec][names[vec].index(name)]) for name, vec in described)

    def window_start(self, xb: float) -> int:
        """First table sample of the window around the belt at ``xb``, clamped to the table."""
        i0 = math.floor((xb - self.table_x0) / self.table_dx) - WINDOW // 2
        return min(max(i0, 0), self.table_h.size // 2 - WINDOW)


def start_description(rim: str, axle: str) -> tuple:
    """(printf format, ((name, "u" or "q"), ...)) of the values that describe a start in a refusal: speed, axle,
    rim, pressure and position; the native glue prints the same (SWIFT_START_TEXT, SWIFT_START_VALUES)."""
    described = (("vx", "m/s", "u"), ("z", "m", "u") if axle == "height" else ("Fz_in", "N", "u"),
                 ("omega", "rad/s", "u") if rim == "speed" else ("torque", "N m", "u"), ("p", "Pa", "u"),
                 ("x_start", "m", "q"))
    return ", ".join(f"{name} = %g {unit}" for name, unit, _ in described), tuple((n, v) for n, _, v in described)


def swift_functions(model, road=None, *, x_start: float = 0.0, rim: str = "speed",
                    axle: str = "height", axle_mass: float = AXLE_MASS, turn_slip: bool = False) -> SwiftFunctions:
    """The functions of the SWIFT wheel of ``model`` on ``road`` (a :class:`swift.road.Road`, an expression or a
    CSV file, see :func:`swift.road.parse_road`); ``x_start``: default start position; ``rim``, ``axle``: the modes
    (:data:`RIM_MODES`, :data:`AXLE_MODES`); ``axle_mass``: the axle's mass [kg] in the load mode; ``turn_slip``:
    the contact patch's turn slip from its yaw rate (:class:`swift.simulate.SwiftTyre`; the wheel frame does not
    turn: the belt's yaw rate relative to the rim). The ring is
    :class:`swift.simulate.SwiftTyre`'s (its step, outputs and static equilibrium); here only the FMU's inputs are
    mapped onto it: the state holds heights above the road datum, the ring sees them above ``road_z``."""
    import casadi as ca

    from mftyre.backend import casadi_backend

    from .simulate import SwiftTyre

    if rim not in RIM_MODES:
        raise ModelInputError(f"rim must be one of {', '.join(RIM_MODES)}; got {rim!r}")
    if axle not in AXLE_MODES:
        raise ModelInputError(f"axle must be one of {', '.join(AXLE_MODES)}; got {axle!r}")
    table_u = input_table(rim, axle)
    road = parse_road(road)
    prm = model.params
    cams = Cams.from_params(prm, warn=False)  # the tyre below warns
    dx = TABLE_DX
    bps = tuple(road.breakpoints)
    reach = cams.ae + 2 * dx
    lo, hi = (min(bps) - reach, max(bps) + reach) if bps else (0.0, 1.0)
    tyre = SwiftTyre(model, road, axle=axle, rim=rim, x_range=(math.floor(lo / dx) * dx,
                     math.ceil(hi / dx) * dx), table_dx=dx, window=WINDOW, substeps=SUBSTEPS, axle_mass=axle_mass,
                     compiled=False, turn_slip=turn_slip)
    nx = len(STATE_NAMES)
    x, u, q = ca.MX.sym("x", nx), ca.MX.sym("u", len(table_u)), ca.MX.sym("q", len(PARAMETERS))
    x0w, grid, hw, dt = ca.MX.sym("x0w"), ca.MX.sym("grid", WINDOW), ca.MX.sym("hw", 2 * WINDOW), ca.MX.sym("dt")
    U = {n: u[i] for i, n in enumerate(table_u)}
    ring_u = {"vx": U["vx"], "load": U.get("Fz_in", 0), "torque": U.get("torque", 0), "p": U["p"], "y": 0, "vy": U["vy"],
              "gamma": U["gamma"], "psi": 0, "road_camber": U["road_camber"]}
    uring = ca.vertcat(*(ring_u[n] for n in INPUT_NAMES))

    def lifted(state, dz):  # belt and axle heights moved by dz (between the datum and the ring's road frame)
        parts = ca.vertsplit(state)
        for n in ("zb", "za"):
            parts[_S[n]] = parts[_S[n]] + dz
        return ca.vertcat(*parts)

    # one RK4 step in the road frame, then the rim's lateral position back to the frame origin
    xn = lifted(tyre.step_function(lifted(x, -U["road_z"]), uring, dt, x0w, grid, hw)[0], U["road_z"])
    parts = ca.vertsplit(xn)
    for n in ("yb", "ya"):
        parts[_S[n]] = parts[_S[n]] - U["vy"] * dt
    xn = ca.vertcat(*parts)
    step = ca.Function("swift_substep", [x, u, dt, x0w, grid, hw], [xn], ["x", "u", "dt", "x0w", "grid", "hw"],
                       ["x_next"])
    ring_out = dict(zip(OUTPUT_NAMES, ca.vertsplit(tyre.output_function(lifted(x, -U["road_z"]), uring, x0w,
                                                                         grid, hw))))
    special = {"contact_length": 2 * ring_out["a"], "x_road": x[_S["xa"]], "road_w": ring_out["w"] + U["road_z"],
               "Rl": (x[_S["za"]] - U["road_z"] - ring_out["w"]) * ca.cos(ring_out["beta"]),
               "omega_used": x[_S["oma"]]}
    special.update(contact_extras(model, ring_out, U["gamma"], U["p"], x[_S["omb"]], be=casadi_backend()))
    y = [special[n] if n in special else ring_out[_RING[n]] for n in OUTPUTS]
    y = [ca.MX(v) if not isinstance(v, ca.MX) else v for v in y]
    outw = ca.Function("swift_out", [x, u, x0w, grid, hw], [ca.vertcat(*y)], ["x", "u", "x0w", "grid", "hw"], ["y"])

    # static equilibrium at x_start (SwiftTyre's), in the road frame
    equilibrium = tyre.equilibrium_function(NEWTON_STEPS)
    height = (U["z"] - U["road_z"], U["vz"]) if axle == "height" else (0.0, 0.0)  # load: solved for
    x_eq = equilibrium(q[0], *height, U["omega"], uring, x0w, grid, hw)
    init = ca.Function("swift_init", [u, q, x0w, grid, hw], [lifted(x_eq, U["road_z"])],
                       ["u", "q", "x0w", "grid", "hw"], ["x0"])
    root = ca.Function("swift_root", [x, u, x0w, grid, hw],
                       [tyre.rolling_root_function(lifted(x, -U["road_z"]), uring, x0w, grid, hw)],
                       ["x", "u", "x0w", "grid", "hw"], ["facts"])
    root_message = no_rolling_root_template(prm)
    residual = ca.Function("swift_residual", [x, u, x0w, grid, hw],
                           [tyre.equilibrium_residual_function(lifted(x, -U["road_z"]), uring, x0w, grid, hw)],
                           ["x", "u", "x0w", "grid", "hw"], ["r"])
    residual_names = tuple(STATE_NAMES[i] for i in tyre.equilibrium_unknowns[1])

    # direct feedthrough of the inputs to the outputs (structural)
    jac = ca.jacobian(outw(x, u, x0w, grid, hw), u).sparsity()
    deps = [[i for i in range(jac.size2()) if jac.has_nz(j, i)] for j in range(jac.size1())]
    table = tyre.table
    h = tyre.cam_pairs
    grid_v = np.ascontiguousarray(table.dx * np.arange(WINDOW))
    pstiff, pdamp = pressure_coefficients(prm)  # the factors' signs checked by glue_validate (ring.check_pressure)
    start_form, described = start_description(rim, axle)
    refusal = (f"#define SWIFT_NO_EQUILIBRIUM {json.dumps(NO_EQUILIBRIUM)}\n#define SWIFT_EQUILIBRIUM_TOL "
               f"{EQUILIBRIUM_TOL!r}\n#define SWIFT_NEWTON_STEPS {NEWTON_STEPS}\n"
               f"#define SWIFT_NEQ {len(residual_names)}\n"
               "static const char *const SWIFT_EQ_NAMES[SWIFT_NEQ] = {"
               + ", ".join(json.dumps(n) for n in residual_names) + "};\n"
               f"#define SWIFT_NO_ROLLING_ROOT {json.dumps(root_message)}\n#define SWIFT_START_TEXT "
               f"{json.dumps(start_form)}\n#define SWIFT_START_VALUES(u, q) "
               + ", ".join(f"{vec}[TYRE_{vec.upper()}_{name.upper()}]" for name, vec in described) + "\n")
    extra = (refusal + f"#define ROAD_N {table.h.size}\n#define ROAD_WINDOW {WINDOW}\n#define ROAD_X0 {table.x0!r}\n"
             f"#define ROAD_DX {table.dx!r}\n#define SWIFT_MAX_TRAVEL {MAX_TRAVEL!r}\n"
             f"#define SWIFT_MAX_RK4_STEP {MAX_RK4_STEP!r}\n#define STEP_RATE_LIMIT {STEP_RATE_LIMIT!r}\n"
             f"#define SWIFT_MAX_STEPS_PER_CALL {MAX_STEPS_PER_CALL!r}\n"
             f"#define SWIFT_P_NOM {float(prm.NOMPRES)!r}\n#define SWIFT_P_STIFF {pstiff!r}\n"
             f"#define SWIFT_P_DAMP {0.0 if pdamp is None else pdamp!r}\n"
             + "".join(f"#define S_{n.upper()} {i}\n" for i, n in enumerate(STATE_NAMES))
             + "/* cam height and road-camber slope per sample, interleaved */\n"
             + "static const double ROAD_H[2 * ROAD_N] = {" + ",".join(repr(float(v)) for v in h) + "};\n"
             + "static const double ROAD_GRID[ROAD_WINDOW] = {" + ",".join(repr(float(v)) for v in grid_v) + "};\n")
    computed = start_inputs(model)
    inputs = tuple(v.but(start=computed[n]) if n in computed else v for n, v in table_u.items())
    parameters = (PARAMETERS["x_start"].but(start=float(x_start)), PARAMETERS["max_step"])
    return SwiftFunctions(init=init, step=step, out=outw, state_names=STATE_NAMES, inputs=inputs,
                          parameters=parameters, outputs=tuple(OUTPUTS.values()), table_x0=float(table.x0),
                          table_dx=float(table.dx), table_h=h, grid=grid_v, output_dependencies=deps,
                          config_extra=extra, rim=rim, axle=axle, root=root, root_message=root_message,
                          residual=residual, residual_names=residual_names)


#: Compiler flags of the wheel's library (those of swift.simulate's compiled step).
_CFLAGS = (*COMPILER_FLAGS, "-fPIC", "-shared")


@functools.cache
def _sources_digest() -> str:
    """SHA-256 of the source of the swift and mftyre packages, read once per process."""
    import hashlib
    from pathlib import Path

    import mftyre

    sources = hashlib.sha256()
    for package in (Path(__file__).parent, Path(mftyre.__file__).parent):
        for file in sorted(package.rglob("*.py")):
            sources.update(file.read_bytes())
    return sources.hexdigest()


def wheel_key(model, rim: str, axle: str, axle_mass: float, turn_slip: bool = False) -> str:
    """The key of the compiled step and outputs of :func:`swift_functions` (they do not depend on the road, which
    they take as the window arguments): the .tir values, the side, the modes, the axle mass, the integration and
    table constants, the source of the swift and mftyre packages, CasADi and the compiler flags."""
    import hashlib
    import json

    import casadi as ca

    prm = model.params
    payload = {"tir": {k: repr(prm[k]) for k in prm}, "missing": sorted(prm.missing), "side": model.side,
               "rim": rim, "axle": axle, "axle_mass": float(axle_mass), "turn_slip": bool(turn_slip),
               "window": WINDOW, "substeps": SUBSTEPS,
               "newton": NEWTON_STEPS, "sources": _sources_digest(), "casadi": ca.__version__, "cflags": _CFLAGS}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def compiled_library(functions: SwiftFunctions, key: str):
    """The wheel's ``step`` and ``out`` as C (CasADi's code generator, as the native FMU), compiled and cached by
    :func:`mftyre.compiled.cached_library` under ``key`` (:func:`wheel_key`); returns the verified library."""
    import os
    from pathlib import Path

    import casadi as ca

    from mftyre.compiled import cached_library

    def generate(folder):
        gen = ca.CodeGenerator("swift_wheel.c", {"with_header": False})
        gen.add(functions.step)
        gen.add(functions.out)
        source = Path(gen.generate(str(folder) + os.sep))
        meta = {"inputs": list(functions.input_names), "outputs": list(functions.output_names), "checks": [],
                "states": list(STATE_NAMES)}
        return source, _CFLAGS, ("-lm",), meta

    return cached_library("swiftwheel", key, generate)


class SwiftWheel:
    """The SWIFT wheel in Python (module notes): ``set_inputs``, ``set_parameters``, ``initialise``, ``step``,
    ``outputs``, ``state``. The same functions and the same window placement as the native FMU.

    ``compiled``: False, the functions on CasADi's virtual machine; True, ``step`` and ``out`` from the compiled
    library (:func:`compiled_library`, cached; the static equilibrium ``init`` stays on the virtual machine)."""

    def __init__(self, model, road=None, *, x_start: float = 0.0, rim: str = "speed", axle: str = "height",
                 axle_mass: float = AXLE_MASS, compiled: bool = False, turn_slip: bool = False):
        self.functions = f = swift_functions(model, road, x_start=x_start, rim=rim, axle=axle, axle_mass=axle_mass,
                                             turn_slip=turn_slip)
        self._params = model.params
        self.u = np.array(f.input_starts, dtype=float)
        self.q = np.array(f.parameter_starts, dtype=float)
        self.state = np.zeros(len(STATE_NAMES))
        self._step, self._out = f.step, f.out
        self.library = None
        if compiled:
            import ctypes

            self.library = compiled_library(f, wheel_key(model, rim, axle, axle_mass, turn_slip))
            lib = ctypes.CDLL(str(self.library))
            step, out = (GeneratedFunction(lib, g, by_address=(-2, -1)) for g in (f.step, f.out))
            self._step, self._out = (lambda *a: step(*a)[0]), (lambda *a: out(*a)[0])

    def set_inputs(self, **values):
        for k, v in values.items():
            if k not in self.functions.input_names:
                raise ModelInputError(f"unknown input {k!r}; inputs are {', '.join(self.functions.input_names)}")
            if not math.isfinite(v):
                raise ModelInputError(f"input {k} must be finite, got {v!r}")
            self.u[self.functions.input_names.index(k)] = v

    def set_parameters(self, **values):
        for k, v in values.items():
            if k not in PARAMETERS:
                raise ModelInputError(f"unknown parameter {k!r}; parameters are {', '.join(PARAMETERS)}")
            self.q[self.functions.parameter_names.index(k)] = v

    def _window(self, xb):
        f = self.functions
        i0 = f.window_start(xb)
        return f.table_x0 + i0 * f.table_dx, f.grid, f.table_h[2 * i0:2 * (i0 + WINDOW)]

    def initialise(self):
        check_pressure(self._params, float(self.u[self.functions.input_names.index("p")]))
        U = dict(zip(self.functions.input_names, self.u))  # the input policy's speed limits, as SwiftTyre's start
        check_speed_limits(self._params, U["vx"], U["omega"], omega_given=self.functions.rim == "speed")
        x = np.asarray(self.functions.init(self.u, self.q, *self._window(self.q[0])), dtype=float).ravel()
        if not np.all(np.isfinite(x)):
            raise ModelInputError("no static equilibrium found at the initial inputs")
        f, window = self.functions, self._window(self.q[0])
        r = np.asarray(f.residual(x, self.u, *window), dtype=float).ravel()
        worst = int(np.argmax(np.abs(r))) if np.all(np.isfinite(r)) else int(np.argmin(np.isfinite(r)))
        if not abs(r[worst]) <= EQUILIBRIUM_TOL:  # as swift.simulate.SwiftTyre.initial_state
            raise ModelInputError(NO_EQUILIBRIUM % (f.start_text(self.u, self.q), NEWTON_STEPS,
                                                    f.residual_names[worst], r[worst], EQUILIBRIUM_TOL))
        facts = np.asarray(self.functions.root(x, self.u, *window), dtype=float).ravel()
        if facts[0]:  # a root, but no rolling tyre (swift.simulate.SwiftTyre.rolling_root_function)
            raise ModelInputError(self.functions.root_message % (self.functions.start_text(self.u, self.q),
                                                                 *facts[1:]))
        self.state = x

    def step(self, h: float):
        if not (math.isfinite(h) and h > 0):
            raise ModelInputError(f"step size must be positive and finite, got {h!r}")
        check_pressure(self._params, float(self.u[self.functions.input_names.index("p")]))
        U = dict(zip(self.functions.input_names, self.u))
        x = self.state.copy()
        if self.functions.axle == "height":  # the axle height imposed (as glue_swift.c)
            x[_S["za"]], x[_S["vza"]] = U["z"], U["vz"]
        if self.functions.rim == "speed":  # the rim spin imposed (as glue_swift.c)
            x[_S["oma"]] = U["omega"]
        n = internal_steps(h, self.q[1], U["vx"])
        for _ in range(n):
            x = np.asarray(self._step(x, self.u, h / n, *self._window(x[_S["xb"]])), dtype=float).ravel()
        if not np.all(np.isfinite(x)):
            raise ArithmeticError("the SWIFT state became non-finite (step too long for the tyre's frequencies? "
                                  "lower max_step)")
        self.state = x

    def outputs(self) -> dict:
        y = np.asarray(self._out(self.state, self.u, *self._window(self.state[_S["xb"]])),
                       dtype=float).ravel()
        return dict(zip(self.functions.output_names, y))
