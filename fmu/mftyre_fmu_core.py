"""The SWIFT tyre of the pythonfmu FMU (``--backend pythonfmu``, model=swift), free of any FMI machinery, and the
compiled libraries the FMU ships.

The steady tyre of both FMU backends is one definition, :mod:`mftyre.transient` (``wheel_functions``; the
pythonfmu slave drives :class:`mftyre.transient.WheelTyre`, the native FMU its generated C). The SWIFT tyre of the
native FMU is :mod:`swift.fmu_model`; the pythonfmu slave still drives :class:`swift.SwiftTyre` here (SwiftCore:
it has the axle-load mode the native wheel lacks), with the native FMU's stepping rule.

    core = SwiftCore(model, road="cleat(x0=2, length=0.05, height=0.01)", vertical="position")   # SWIFT
    out = core.initialise(inputs)        # static equilibrium; inputs: dict of the FMU inputs by name
    out = core.advance(inputs, h)        # one communication step (see SwiftCore)

Axes and units: ISO-W (TYDEX W), SI.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path

#: MF outputs taken from the model (names of :data:`mftyre.model.OUTPUT_UNITS`).
MF_OUTPUTS = ("fx", "fy", "fz", "mx", "my", "mz", "omega", "re", "rho", "rl", "a", "b", "t", "mux", "muy")

#: Outputs the FMU adds to the wheel's (mftyre.transient.OUTPUTS), in every mode (the SWIFT wheel's).
EXTRA_OUTPUTS = ("Fz_c", "road_w", "road_slope", "x_road", "Fx_c", "Fy_c", "road_curvature", "Re_variation",
                 "road_camber_eff", "x_contact")
#: What the pythonfmu FMU says more about some outputs than the vocabulary (its modes: steady vehicle/rig, swift).
OUTPUT_NOTES = {
    "Fz": "vertical force on the tyre, >= 0 (at the wheel centre, ISO-W axes)",
    "My": "moment about y at the wheel centre, ISO-W axes (-Rl Fx + rolling resistance)",
    "kappa": "longitudinal slip given to the MF, -Vsx / Vx (kinematic or the rig input: relative to the direction of "
             "travel, -1 = locked wheel; swift: the transient slip -Vsx / |Vcx|, its MF runs at |Vcx|)",
    "alpha": "slip angle given to the MF (kinematic, or the rig input)",
    "Vsx": "longitudinal slip speed of the contact point, -kappa vx (swift: -kappa |Vcx|)",
    "Vsy": "lateral slip speed of the contact point, tan(alpha) |vx|",
    "omega_used": "spin speed used (the input; in rig mode estimated from kappa and vx)",
    "Fz_c": "normal contact force (swift: normal to the effective road plane; steady: = Fz)",
    "road_w": "effective road height under the wheel (swift: tandem cams + road_z; steady: road_z, or 0 with "
              "vertical_input=load)",
    "road_slope": "effective forward road slope beta_y (swift; 0 in steady mode)",
}


def outputs():
    """The outputs: name -> Variable (needs mftyre importable: the host's or the FMU's vendored copy)."""
    from mftyre.transient import OUTPUTS
    from mftyre.variables import pick

    return pick("output", *OUTPUTS, *EXTRA_OUTPUTS, describe=OUTPUT_NOTES)


EVALUATORS = ("auto", "compiled", "casadi")


class TyreFMUError(Exception):
    """A configuration of the tyre FMU that cannot be used (message says what to change)."""


# --------------------------------------------------------------------------------------- CasADi functions
def casadi_functions(model) -> dict:
    """The CasADi function SwiftCore evaluates for the outputs the ring does not report, from the model's one set
    of equations: mf(fz, kappa, alpha, gamma, vx, p, omega) -> MF_OUTPUTS (spin given)."""
    mf = model.casadi_function(inputs=("fz", "kappa", "alpha", "gamma", "vx", "p", "omega"), outputs=MF_OUTPUTS,
                               name="mf")
    return {"mf": mf}


def function_key(tir_text: str, side: str) -> str:
    """Identifies the shipped functions: the .tir text, the side, and the versions of mftyre and CasADi."""
    import casadi as ca
    import mftyre

    payload = json.dumps({"tir": tir_text, "side": side, "mftyre": mftyre.__version__, "casadi": ca.__version__})
    return hashlib.sha256(payload.encode()).hexdigest()[:24]


def export_functions(model, directory, *, compile_c: bool = True) -> dict:
    """Write the functions to ``directory``: ``<name>.casadi`` (serialised, run on CasADi's virtual machine) and,
    with ``compile_c``, ``<name>.so`` + ``.json`` compiled by :mod:`mftyre.compiled` (platform specific).
    Returns {name: {"casadi": file, "compiled": file or None}} relative to ``directory``."""
    from mftyre.compiled import compile_function

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    index = {}
    for name, f in casadi_functions(model).items():
        f.save(str(directory / f"{name}.casadi"))
        entry = {"casadi": f"{name}.casadi", "compiled": None}
        if compile_c:
            lib = compile_function(f, f"{name}_{os.urandom(8).hex()}", directory, f.name_out())
            final = directory / f"{name}.so"
            os.replace(lib, final)
            os.replace(lib.with_suffix(".json"), final.with_suffix(".json"))
            entry["compiled"] = final.name
        index[name] = entry
    return index


# --------------------------------------------------------------------------------------------- evaluators
class _CasadiEval:
    """A CasADi function on its virtual machine, floats in -> tuple of floats out."""

    def __init__(self, function):
        self.f = function
        self.n_out = function.n_out()

    def __call__(self, *values):
        res = self.f.call(list(values))
        return tuple(float(r) for r in res)


def load_evaluators(model, evaluator="auto", functions_dir=None, index=None, log=None):
    """(name of the path used, object with the callable mf).

    ``compiled``: the shipped C libraries (``functions_dir``), else compiled now with the C compiler (cached);
    ``casadi``: the shipped serialised functions, else built now from the model; ``auto``: compiled, falling back
    to casadi."""
    log = log or (lambda msg: None)
    if evaluator not in EVALUATORS:
        raise TyreFMUError(f"parameter evaluator must be one of {', '.join(EVALUATORS)}; got {evaluator!r}")
    names = ("mf",)
    errors = []
    if evaluator in ("auto", "compiled"):
        from mftyre.compiled import CompiledFunction

        try:
            if functions_dir is not None and index is not None and all(index[n]["compiled"] for n in names):
                fns = {n: CompiledFunction(Path(functions_dir) / index[n]["compiled"]) for n in names}
                return "compiled", _Bundle(fns)
            errors.append("no shipped compiled functions for this tyre and side")
        except Exception as exc:  # another platform, missing file...
            errors.append(f"shipped compiled functions unusable: {exc}")
        try:
            from mftyre.compiled import cache_dir, compile_function

            key = function_key(_tir_identity(model), model.side)
            fns = {}
            for n, f in casadi_functions(model).items():
                lib = compile_function(f, f"fmu_{n}_{key}", cache_dir(), f.name_out())
                fns[n] = CompiledFunction(lib)
            return "compiled", _Bundle(fns)
        except Exception as exc:
            errors.append(f"compiling now failed: {exc}")
        if evaluator == "compiled":
            raise TyreFMUError("compiled evaluator unavailable: " + "; ".join(errors))
        log("compiled evaluator unavailable (" + "; ".join(errors) + "); using CasADi's virtual machine")
    import casadi as ca

    try:
        if functions_dir is not None and index is not None:
            fns = {n: _CasadiEval(ca.Function.load(str(Path(functions_dir) / index[n]["casadi"]))) for n in names}
            return "casadi", _Bundle(fns)
    except Exception as exc:
        log(f"shipped CasADi functions unusable ({exc}); building them from the model")
    return "casadi", _Bundle({n: _CasadiEval(f) for n, f in casadi_functions(model).items()})


def _tir_identity(model) -> str:
    prm = model.params
    return json.dumps({k: repr(prm[k]) for k in prm}, sort_keys=True)


class _Bundle:
    def __init__(self, fns):
        self.mf = fns["mf"]


# ------------------------------------------------------------------------------------------ SWIFT (rigid ring)
# The SWIFT road table (grid step, window), the stepping rule and its constants are those of the native FMU's
# wheel: swift.fmu_model (TABLE_DX, WINDOW, SUBSTEPS, internal_steps).


def parse_road(spec, base_dir=None):
    """The road of the ``road`` parameter (:func:`swift.road.parse_road`: a sum of obstacles like
    ``cleat(x0=2, length=0.05, height=0.01)``, ``csv("profile.csv")`` relative to ``base_dir``,
    ``points([[x, z], ...])``); None for a flat road. Errors become :class:`TyreFMUError`."""
    from mftyre.errors import MFTyreError
    from swift.road import Flat
    from swift.road import parse_road as parse

    try:
        road = parse(spec, base_dir)
    except MFTyreError as exc:
        raise TyreFMUError(str(exc)) from None
    return None if isinstance(road, Flat) and road.z == 0 else road


def _platform() -> str:
    import platform
    import sys

    return f"{sys.platform}-{platform.machine()}-py{sys.version_info[0]}.{sys.version_info[1]}"


def export_swift_libraries(model, directory) -> dict:
    """Compile the SWIFT step of ``model`` for the FMU's configurations (axle height/load x rim speed/torque,
    default axle mass) and copy the libraries to ``directory``: shipped in the FMU so that swift mode needs no C
    compiler on the build platform. Returns {"platform": ..., "files": [names]}."""
    import shutil

    from swift import Flat, SwiftTyre
    from swift.fmu_model import SUBSTEPS, TABLE_DX, WINDOW

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    names = []
    for axle in ("height", "load"):
        for rim in ("speed", "torque"):
            tyre = SwiftTyre(model, Flat(), axle=axle, rim=rim, x_range=(0.0, 1.0), table_dx=TABLE_DX,
                             window=WINDOW, substeps=SUBSTEPS, compiled=True)
            library = Path(tyre._compiled._lib._name)
            for src in (library, library.with_suffix(".json")):  # the library and its verified description
                shutil.copy2(src, directory / src.name)
                names.append(src.name)
    return {"platform": _platform(), "files": names}


def export_wheel_libraries(model, directory) -> dict:
    """Compile the steady wheel's outputs (mftyre.transient.WheelTyre, evaluator compiled) for the FMU's modes
    (vertical load, vertical position, rig) and copy the libraries to ``directory``, as
    :func:`export_swift_libraries`. Returns {"platform": ..., "files": [names]}."""
    import shutil
    import warnings

    from mftyre.transient import WheelTyre

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    names = []
    for vertical, mode in (("load", "vehicle"), ("position", "vehicle"), ("load", "rig")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            library = WheelTyre(model, "steady", vertical, input_mode=mode, evaluator="compiled")._compiled.library
        for src in (library, library.with_suffix(".json")):
            shutil.copy2(src, directory / src.name)
            names.append(src.name)
    return {"platform": _platform(), "files": names}


def install_libraries(directory, entry) -> int:
    """Copy shipped libraries (see :func:`export_swift_libraries`, :func:`export_wheel_libraries`) into mftyre's
    compile cache, where the tyres find them, when built for this platform and not there yet; returns how many."""
    import shutil

    from mftyre.compiled import cache_dir

    if not entry or entry.get("platform") != _platform():
        return 0
    cache = cache_dir()
    cache.mkdir(parents=True, exist_ok=True)
    n = 0
    for name in entry.get("files", ()):  # each library before its description (mftyre.compiled checks the pair)
        target = cache / name
        if not target.exists() and (Path(directory) / name).is_file():
            tmp = cache / f".{name}.{os.getpid()}.tmp"
            shutil.copyfile(Path(directory) / name, tmp)
            os.chmod(tmp, 0o644)
            os.replace(tmp, target)
            n += 1
    return n


class SwiftCore:
    """The SWIFT rigid-ring tyre (:class:`swift.SwiftTyre`) with the FMU's inputs, state and outputs.

        core = SwiftCore(model, road="cleat(x0=2, length=0.05, height=0.01)", vertical="position")
        out = core.initialise(inputs)        # static equilibrium; inputs: dict of the FMU inputs
        out = core.advance(inputs, h)        # one communication step of length h (any h >= 0)

    Mapping (see README.md here): ``vertical`` "position" -> axle height imposed (``z - road_z``, moving with
    ``vz`` inside the step), "load" -> ``Fz_in`` pushes the axle (mass ``axle_mass``) down; ``rim`` "speed" ->
    spin ``omega`` imposed, "torque" -> drive torque ``torque`` on the rim. The road is the profile ``road``
    (:func:`parse_road`) plus the input ``road_z``. The communication step is split into equal steps of
    :meth:`swift.SwiftTyre.step` by the native FMU's rule (:func:`swift.fmu_model.internal_steps`, with its RK4
    substeps, road table and window). Inputs are held over the step (zero-order hold) except the axle height in
    position mode (first-order hold with ``vz``) and the positions x, y, which advance with vx, vy.

    State frames (exact, no approximation): vertical positions are kept relative to ``road_z`` (a change of
    ``road_z`` moves the stored belt/axle heights by the opposite amount), the lateral position relative to the rim
    (the rim's y is 0 at every step start), and where the road is constant (beyond its first and last
    obstacles, flat roads everywhere) the wheel's x is moved back into the cam-height table, which keeps the
    table short and the run unbounded in distance.
    """

    def __init__(self, model, road="", *, vertical="load", rim="speed", x_start=0.0, max_step=1e-3,
                 axle_mass=30.0, evaluator="auto", functions_dir=None, index=None, log=None, base_dir=None):
        import numpy as np
        from mftyre.backend import NUMPY
        from swift import Cams, SwiftTyre
        from swift.fmu_model import SUBSTEPS, TABLE_DX, WINDOW
        from swift.ring import STATE_NAMES

        self.be = NUMPY  # the wheel's equations (swift.fmu_model.contact_extras), on floats

        log = log or (lambda msg: None)
        if vertical not in ("load", "position"):
            raise TyreFMUError(f"parameter vertical_input must be load or position, got {vertical!r}")
        if rim not in ("speed", "torque"):
            raise TyreFMUError(f"parameter rim must be speed or torque, got {rim!r}")
        for name, value in (("max_step", max_step), ("axle_mass", axle_mass)):
            if not (math.isfinite(value) and value > 0):
                raise TyreFMUError(f"parameter {name} must be positive, got {value!r}")
        if not math.isfinite(x_start):
            raise TyreFMUError(f"parameter x_start must be finite, got {x_start!r}")
        self.model, self.vertical, self.rim = model, vertical, rim
        self.max_step = float(max_step)
        self.road = parse_road(road, base_dir)
        self.S = {n: i for i, n in enumerate(STATE_NAMES)}
        cams = Cams.from_params(model.params)
        dx, span = TABLE_DX, WINDOW * TABLE_DX
        bps = self.road.breakpoints if self.road is not None else ()
        reach = cams.ae + 2 * dx  # beyond, the cam height is constant (the road is)
        lo, hi = (min(bps) - reach, max(bps) + reach) if bps else (float(x_start), float(x_start))
        # the table reaches back to the start: the wheel is never moved towards the obstacles at initialisation
        lo, hi = min(lo, float(x_start)), max(hi, float(x_start))
        # wheel positions where the whole step window lies on the constant part: the wheel is moved back to them
        self._x_lo, self._x_hi = lo - span, hi + span
        x_range = (math.floor(self._x_lo / dx) * dx, math.ceil(self._x_hi / dx) * dx)  # nodes on multiples of dx
        from swift import Flat

        road_obj = self.road if self.road is not None else Flat()
        if functions_dir is not None and index is not None and index.get("swift"):
            try:
                install_libraries(Path(functions_dir) / "swift", index["swift"])
            except Exception as exc:  # read-only cache...: compiled now instead
                log(f"shipped SWIFT libraries not installed: {exc}")
        kwargs = dict(axle="height" if vertical == "position" else "load", rim=rim, x_range=x_range, table_dx=dx,
                      window=WINDOW, substeps=SUBSTEPS, axle_mass=float(axle_mass))
        self.path = "casadi"
        if evaluator in ("auto", "compiled"):
            try:
                self.tyre = SwiftTyre(model, road_obj, compiled=True, **kwargs)
                self.path = "compiled"
            except Exception as exc:  # no C compiler...
                if evaluator == "compiled":
                    raise TyreFMUError(f"compiled SWIFT step unavailable: {exc}") from None
                log(f"compiled SWIFT step unavailable ({exc}); using CasADi's virtual machine (slow)")
        if self.path == "casadi":
            self.tyre = SwiftTyre(model, road_obj, compiled=False, **kwargs)
        # the MF at the contact-patch state gives the outputs the ring does not report (Mx_c, My_c, b, trail, mu)
        self.mf_path, self.fn = load_evaluators(model, evaluator, functions_dir, index, log)
        self._np = np
        self.x_offset = 0.0  # road x = state x + x_offset
        self.road_z = 0.0  # vertical positions in the state are relative to this road height
        self.state = None
        self.x_start = float(x_start)

    # ------------------------------------------------------------------------------------------------ frames
    def _recentre_x(self, state):
        xb = state[self.S["xb"]]
        shift = xb - self._x_hi if xb > self._x_hi else xb - self._x_lo if xb < self._x_lo else 0.0
        if shift:
            state[self.S["xa"]] -= shift
            state[self.S["xb"]] -= shift
            self.x_offset += shift

    def _set_road_z(self, state, road_z):
        d = road_z - self.road_z
        if d:
            state[self.S["zb"]] -= d
            state[self.S["za"]] -= d
            self.road_z = road_z

    def _inputs(self, u, state, dz=0.0):
        from swift import StepInputs

        return StepInputs(x=float(state[self.S["xa"]]), vx=u["vx"], z=u["z"] - self.road_z + dz, vz=u["vz"],
                          load=u["Fz_in"], omega=u["omega"], torque=u["torque"], p=u["p"], y=0.0, vy=u["vy"],
                          gamma=u["gamma"], psi=0.0, road_camber=u["road_camber"])

    # ------------------------------------------------------------------------------------------------ stepping
    def initialise(self, u):
        """Static equilibrium (steady rolling at the inputs) at x_start; returns the outputs."""
        np = self._np
        self.road_z = u["road_z"]
        x_local = min(max(self.x_start, self._x_lo), self._x_hi)
        self.x_offset = self.x_start - x_local
        state = np.zeros(len(self.S))
        state[self.S["xa"]] = x_local
        state = self.tyre.initial_state(self._inputs(u, state))
        state, out = self.tyre.step(state, self._inputs(u, state), 0.0)
        if not (np.all(np.isfinite(state)) and all(math.isfinite(v) for v in out.values())):
            raise TyreFMUError("no static equilibrium found for the initial inputs")
        self.state = state
        return self._outputs(state, out, u)

    def advance(self, u, h):
        """Advance over a communication step of length ``h`` with the inputs ``u``; returns the outputs. On an
        error the state is left as it was (the exception says why)."""
        from swift.fmu_model import internal_steps

        np = self._np
        S = self.S
        saved = (self.x_offset, self.road_z)
        state = self.state.copy()
        try:
            self._set_road_z(state, u["road_z"])
            n = internal_steps(h, self.max_step, u["vx"])  # the native FMU's rule (glue_swift.c)
            dt = h / n
            out = None
            for k in range(n):
                self._recentre_x(state)
                state, out = self.tyre.step(state, self._inputs(u, state, u["vz"] * k * dt), dt)
                state[S["yb"]] -= u["vy"] * dt  # the rim moved by vy dt: keep its y at 0
                state[S["ya"]] -= u["vy"] * dt
            if h <= 0 or out is None:
                state, out = self.tyre.step(state, self._inputs(u, state), 0.0)
            self._recentre_x(state)
            if not (np.all(np.isfinite(state)) and all(math.isfinite(v) for v in out.values())):
                raise ArithmeticError("the SWIFT state became non-finite (step too long for the tyre's "
                                      "frequencies? lower max_step)")
        except Exception:
            self.x_offset, self.road_z = saved
            raise
        self.state = state
        return self._outputs(state, out, u)

    def _outputs(self, state, o, u):
        from swift.fmu_model import contact_extras

        S = self.S
        picked = [MF_OUTPUTS.index(n) for n in ("mx", "my", "b", "t", "mux", "muy")]

        def mf(*args):  # the MF extras of the native wheel (swift.fmu_model.contact_extras), on this evaluator
            values = self.fn.mf(*(float(a) for a in args))
            return [values[i] for i in picked]

        extras = contact_extras(self.model, o, u["gamma"], u["p"], float(state[S["omb"]]), self.be, mf)
        beta = float(o["beta"])
        out = {
            "Fx": o["fx"], "Fy": o["fy"], "Fz": o["fz"], "Mx": o["mx"], "My": o["my"], "Mz": o["mz"],
            "Fx_c": o["fx_c"], "Fy_c": o["fy_c"], "Fz_c": o["fz_c"], "Mz_c": o["mz_c"],
            "kappa": o["kappa"], "alpha": o["alpha"], "omega_used": state[S["oma"]],
            "rho": o["rho"], "Rl": (float(state[S["za"]]) - float(o["w"])) * math.cos(beta),  # the loaded radius
            "Re": o["re"], "contact_length": 2.0 * float(o["a"]),
            "road_w": float(o["w"]) + self.road_z, "road_slope": beta, "road_curvature": o["curvature"],
            "Re_variation": o["dre"], "road_camber_eff": o["beta_x"],
            "x_road": float(state[S["xa"]]) + self.x_offset, "x_contact": float(o["x_c"]) + self.x_offset, **extras,
        }
        return {k: float(v) for k, v in out.items()}
