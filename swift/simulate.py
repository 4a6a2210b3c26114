"""Time integration of the rigid-ring tyre: a compiled fixed-step stepper (real time, FMU) and an adaptive
SciPy reference, both from the equations of :mod:`swift.ring`.

    import mftyre
    from mftyre.transient import free_rolling_start
    from swift import SwiftTyre, StepInputs, Cleat
    model = mftyre.load_tir("tir_files/car_205_60R15_mf62_swift.tir")
    tyre = SwiftTyre(model, Cleat(x0=1.0, length=0.05, height=0.01), x_range=(0.0, 25.0))
    omega, z = free_rolling_start(model, 11.1)                     # free rolling under FNOMIN
    u = StepInputs(vx=11.1, z=z, omega=omega)                      # axle height fixed, spin imposed
    state = tyre.initial_state(u)                                  # static equilibrium on the road
    state, out = tyre.step(state, u, 1e-3)                        # one step: state_next, outputs by name
    res = tyre.run(2.0, u)                                         # 2 s, outputs every 1 ms (SimResult)
    ref = tyre.run_adaptive(0.3, u)                                # scipy DOP853, tight tolerances

Step API (for an FMU): ``state_next, outputs = step(state, inputs, dt)``.

* ``state``: float array, :data:`swift.ring.STATE_NAMES`. Compiled, ``state_next`` is a view of a row of a
  preallocated block that no later step writes; passing it back (as a loop does) it is read in place, not copied.
* ``inputs``: :class:`StepInputs` - axle x position and speed ``x``, ``vx``; axle height ``z``, ``vz`` (mode
  ``axle="height"``) or downward axle force ``load`` (``axle="load"``, with the axle mass of
  :class:`swift.ring.RingConstants`); rim spin ``omega`` (``rim="speed"``) or drive/brake ``torque``
  (``rim="torque"``); inflation pressure ``p``; rim lateral position/speed ``y``, ``vy``, camber ``gamma``, yaw
  (heading relative to the x axis) ``psi``; road camber ``road_camber``. Imposed positions move with their
  speeds inside the step (first-order hold).
* The road: a :class:`swift.road.Road` or a precomputed :class:`swift.enveloping.CamTable` (the cam heights
  along x: the effective-road sample; the tandem base follows the current load inside the step).
* ``outputs``: :data:`swift.ring.OUTPUT_NAMES` - forces and moments of the tyre on the rim (wheel centre,
  ISO-W), contact forces in the effective plane, deflection rho, lever arm rl, effective rolling radius re,
  half contact length a, tandem base ls, effective height w and slope beta, transient slips, contact speed: an
  :class:`Outputs` mapping (name -> float; ``.array`` the row, a view).
* Bad inputs: every input the configuration uses must be finite, ``p`` positive, ``dt`` finite and >= 0, else
  :class:`~mftyre.errors.ModelInputError` naming the input (checked in C on the compiled path).
* Threads: tyres (also several of one model sharing one compiled library) and one tyre may be stepped from several
  threads at once: each call works on buffers of its own (a pool per tyre), and the C releases the GIL. Whatever
  calls CasADi (building a tyre, the initial state, ``compiled=False``) runs one thread at a time
  (:data:`mftyre.compiled.CASADI_LOCK`).

Integration: classical Runge-Kutta (RK4), ``substeps`` per step, all in one compiled CasADi function (C, built
and loaded through :func:`mftyre.compiled.cached_library`: verified before loading, keyed by the model's structure
and the equations' source, not by the parameter values: those are a run-time input ``theta``, so a changed
parameter set (a refit's trial) compiles nothing and adds nothing to the cache); the cam heights come from a window of ``window`` samples of the cam-height table around the
wheel, passed by pointer (no copy), so one compiled function serves any road. The window must cover the wheel's
travel in one step plus ``TANDEM_REACH``: a longer step is split into equal parts, so results do not depend on
speed, step size or start position; so is a step longer than ``substeps`` RK4 steps of :data:`MAX_RK4_STEP` (the
stiff patch and slip states at standstill). :meth:`SwiftTyre.run` runs the whole loop of steps in C (:data:`_DRIVER`,
the same steps as :meth:`SwiftTyre.step`, which makes one ctypes call per step). ``SwiftTyre.step_function`` is the
CasADi step itself, for code generation (FMU).
"""
from __future__ import annotations

import ctypes
import functools
import hashlib
import json
import math
import os
import struct
import threading
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np

from mftyre.compiled import CASADI_LOCK, cached_library  # the verified cache of every compiled library
from mftyre.backend import NUMPY
from mftyre.errors import ModelInputError, TurnSlipWarning
from mftyre.inputs import check_speed_limits
from mftyre.model import ParametricModel, run_time_parameter_names, structure_of
from mftyre.params import swift_invalid_values
from mftyre.formula import vertical

from .enveloping import Cams, CamTable
from .ring import CONTACT_PASSES, INPUT_NAMES, OUTPUT_NAMES, STATE_NAMES, RingConstants, contact_geometry, \
    check_pressure, contact_start, pressure_coefficients, ring_equations, turn_slip_warning
from .road import Road

__all__ = ["StepInputs", "StepSeries", "SwiftTyre", "SimResult", "Outputs"]

_S = {n: i for i, n in enumerate(STATE_NAMES)}
#: The compiled functions' cache key includes the equations' source, so an edit never reuses an old library.
_SOURCE_HASH = hashlib.sha256(b"".join(Path(__file__).with_name(n).read_bytes()
                                       for n in ("ring.py", "simulate.py"))).hexdigest()
#: Distance [m] the cam lookups may reach beyond the belt centre: half the tandem base (0.25 m would need a
#: 2a of 0.6 m), with margin.
TANDEM_REACH = 0.25
#: Longest RK4 step [s]. At standstill the patch deflections and transient slips form a stiff loop (the lateral one
#: (alpha', u_y with the belt's lateral and camber motion) decays at up to ~1700 1/s on the sample file parked on a
#: 0-15 % grade, a rate the speed-based relaxation length does not bound); classical RK4 is stable for
#: |lambda| h < 2.78, so 2.5 ms steps (5 ms calls of 2 substeps) grew it from round-off into mm of drift. 1 ms
#: keeps a margin of 1.6; a longer step is split into equal parts (1 ms output steps are never split).
MAX_RK4_STEP = 1e-3
#: Newton passes of the contact solution in the stepper, from the solution of the previous RK stage.
WARM_PASSES = 1
#: Largest derivative (SI units of each state's rate) that :meth:`SwiftTyre.initial_state` accepts as static
#: equilibrium; converged solutions reach ~1e-11, inputs without an equilibrium leave 1e1-1e3 (a torque the tyre
#: cannot hold: the Newton iteration ran off to the axle 26 m above the road or 2260 rad/s).
EQUILIBRIUM_TOL = 1e-6
#: The refusal of a start without static equilibrium (:meth:`SwiftTyre.initial_state`, the FMUs' initialisation:
#: the largest derivative of :attr:`SwiftTyre.equilibrium_unknowns`' equations above EQUILIBRIUM_TOL), printf-style
#: as NO_ROLLING_ROOT: the inputs, the Newton steps, the state whose derivative is largest, the derivative, the
#: tolerance.
NO_EQUILIBRIUM = ("no static equilibrium at the inputs (%s): after %d Newton steps d(%s)/dt = %.3g (tolerance %g); "
                  "e.g. a drive/brake torque beyond what the tyre transmits at this load, or the tyre off the road")
#: The refusal of a static root that is no rolling tyre (:attr:`SwiftTyre.rolling_root_function`), printf-style
#: (the native FMU's glue prints it with the same facts): the inputs (%s), then kappa, belt spin, free radius and
#: belt height; the file's values in braces (:func:`no_rolling_root_template`).
NO_ROLLING_ROOT = (
    "no static equilibrium within the file's slip range at the inputs (%s): the equations' root has the slip kappa "
    "= %.3g outside KPUMIN..KPUMAX = {KPUMIN:g}..{KPUMAX:g}, belt spin %.4g rad/s (free radius %.3g m with Q_V1 = "
    "{Q_V1:g}, LONGVL = {LONGVL:g} m/s), belt centre %.3g m above the road: no rolling tyre (a torque beyond what "
    "the tyre transmits, or speed terms that run away: the rolling resistance QSY3/QSY4 and the radius growth Q_V1 "
    "scale with the speed over LONGVL)")


def no_rolling_root_template(prm) -> str:
    """:data:`NO_ROLLING_ROOT` with the file's KPUMIN, KPUMAX, Q_V1 and LONGVL filled in (Python's ``g`` format is
    C's ``%g``); the rest is printf-style, for ``%`` in Python and ``snprintf`` in the native FMU."""
    return NO_ROLLING_ROOT.format(KPUMIN=float(prm.KPUMIN), KPUMAX=float(prm.KPUMAX), Q_V1=float(prm.Q_V1),
                                  LONGVL=float(prm.LONGVL))


def _with_casadi(method):
    """``method`` calls CasADi (builds graphs or evaluates on its virtual machine): under
    :data:`mftyre.compiled.CASADI_LOCK`, one thread at a time. The compiled step never needs it."""
    @functools.wraps(method)
    def locked(*args, **kwargs):
        with CASADI_LOCK:
            return method(*args, **kwargs)
    return locked


@dataclass(frozen=True, init=False)
class StepInputs:
    """Inputs of one step (SI, ISO-W); fields not used by the chosen modes are ignored. Immutable; a changed copy:
    ``dataclasses.replace(inputs, x=...)``."""

    x: float
    vx: float
    z: float
    vz: float
    load: float
    omega: float
    torque: float
    p: float | None
    y: float
    vy: float
    gamma: float
    psi: float
    road_camber: float

    def __init__(self, x=0.0, vx=10.0, z=0.0, vz=0.0, load=4000.0, omega=0.0, torque=0.0, p=None, y=0.0, vy=0.0,
                 gamma=0.0, psi=0.0, road_camber=0.0):
        # written into the instance dict: a third of the cost of a frozen dataclass's setattr per field (a master
        # builds one per step)
        d = self.__dict__
        d["x"], d["vx"], d["z"], d["vz"], d["load"], d["omega"], d["torque"] = x, vx, z, vz, load, omega, torque
        d["p"], d["y"], d["vy"], d["gamma"], d["psi"], d["road_camber"] = p, y, vy, gamma, psi, road_camber


class StepSeries:
    """The inputs of every step of a run as columns: ``name -> array`` (one value per step, at t = k dt; the fields
    of :class:`StepInputs`, a field not given: its default); for :meth:`SwiftTyre.run`, which builds the compiled
    loop's input rows from the columns at once instead of one :class:`StepInputs` per step (a measured run of a
    gap search: 2 000 steps per run, 12 runs per simulation). Past its last step the last one holds."""

    FIELDS = tuple(f.name for f in fields(StepInputs))

    def __init__(self, **columns):
        bad = sorted(set(columns) - set(self.FIELDS))
        if bad:
            raise ModelInputError(f"StepSeries: unknown input(s) {', '.join(bad)}; expected some of "
                                  f"{', '.join(self.FIELDS)}")
        self.columns = {k: np.asarray(v, dtype=float) for k, v in columns.items()}
        sizes = {v.shape for v in self.columns.values()}
        if len(sizes) != 1 or len(next(iter(sizes))) != 1 or not next(iter(sizes))[0]:
            raise ModelInputError(f"StepSeries: every column one value per step, all of one length; got shapes "
                                  f"{sorted(sizes)}")
        self.steps = next(iter(sizes))[0]

    def at(self, k: int) -> StepInputs:
        k = min(k, self.steps - 1)
        return StepInputs(**{name: float(v[k]) for name, v in self.columns.items()})

    def rows(self, n: int, default_row) -> np.ndarray:
        """The compiled loop's rows (:data:`_ROW`) of steps 0 .. n-1: the columns given, and where a column is
        not given the entry of ``default_row`` (:meth:`SwiftTyre._row` of ``StepInputs()``): the rows ``_row`` gives
        for :meth:`at` of each step."""
        idx = np.minimum(np.arange(n), self.steps - 1)
        rows = np.empty((n, _NI))
        for i, name in enumerate(_ROW):
            rows[:, i] = self.columns[name][idx] if name in self.columns else default_row[i]
        return rows


@dataclass
class SimResult:
    """Time histories: ``t``, ``states`` (n x len(STATE_NAMES)), ``outputs`` dict of arrays, wheel position
    ``x`` (axle x)."""

    t: np.ndarray
    states: np.ndarray
    outputs: dict

    @property
    def x(self):
        return self.states[:, _S["xa"]]

    def __getitem__(self, name):
        return self.outputs[name] if name in self.outputs else self.states[:, _S[name]]


class SwiftTyre:
    """SWIFT tyre on a road: rigid ring + tandem-cam effective road + Magic Formula slip model.

    ``axle``: "height" (imposed) or "load"; ``rim``: "speed" (imposed) or "torque"; ``x_range``: wheel
    positions the cam-height table covers; ``table_dx`` its step; ``substeps`` RK4 steps per call of
    :meth:`step`; ``window`` cam-height samples visible to one step (covers the tandem and the travel).
    ``theta``: the parameter values the compiled step takes at run time (:func:`_run_time_parameters`).
    ``turn_slip``: the contact patch's turn slip from its yaw rate through the MF's turn-slip equations
    (:mod:`swift.ring`); off by default: on the sample and TNO files the MF's own turn-slip moment makes a belt mode
    grow at 8 kN (a :class:`mftyre.errors.TurnSlipWarning` names the file and parameters where the moment is
    anti-damping).
    """

    def __init__(self, model, road: Road | CamTable, *, axle: str = "height", rim: str = "speed",
                 x_range=(0.0, 10.0), table_dx: float = 1e-3, substeps: int = 2, window: int = 1024,
                 axle_mass: float = 30.0, rim_extra_inertia: float = 0.3, compiled: bool = True,
                 turn_slip: bool = False, equilibrium: str = "model"):
        if axle not in ("height", "load") or rim not in ("speed", "torque"):
            raise ModelInputError(f"axle must be 'height' or 'load', rim 'speed' or 'torque'; got {axle!r}, {rim!r}")
        if equilibrium not in ("model", "structure"):
            raise ModelInputError(f"equilibrium must be 'model' or 'structure'; got {equilibrium!r}")
        self.model, self.axle, self.rim, self.turn_slip = model, axle, rim, bool(turn_slip)
        # the Jacobian of the static equilibrium from the graph with this model's values ("model", as the FMU's
        # equilibrium_function), or ("structure", compiled only) from the structure's graph with the values as an
        # input: built once for every parameter set of the structure (a refit simulating many); the same root, the
        # Newton steps differing by round-off (at standstill, where the Jacobian is singular, by ~1e-7 m)
        self._equilibrium_kind = equilibrium if compiled else "model"
        self._p_nominal = model.params.INFLPRES  # the default inflation pressure (the parameters are immutable)
        self._p_factors, self._p_range = model.pressure_factors, model.input_range("p")
        for name, message in swift_invalid_values(model.params):  # parameters built by hand skip the reader's check
            raise ModelInputError(f"SWIFT parameter {name} {message}")
        self.constants = RingConstants.from_model(model, axle_mass, rim_extra_inertia)
        if self.turn_slip and (message := turn_slip_warning(model)):
            warnings.warn(message, TurnSlipWarning, stacklevel=2)
        self.cams = Cams.from_params(model.params)
        margin = window * table_dx
        if isinstance(road, CamTable):
            self.table = road
        else:
            _, b = vertical.contact_patch(model.params, model.params.FNOMIN, 0.0, NUMPY)  # tracks over 2b [chosen]
            self.table = CamTable.build(road, self.cams, x_range[0] - margin, x_range[1] + margin, table_dx,
                                        half_width=float(b))
        if self.table.h.size < window:
            raise ModelInputError(f"the cam-height table ({self.table.h.size} samples) is shorter than the window "
                                  f"({window})")
        self.window, self.substeps = int(window), int(substeps)
        self._grid = np.ascontiguousarray(self.table.dx * np.arange(self.window))
        camber = np.zeros(self.table.h.size) if self.table.camber is None else self.table.camber
        self._h = np.ascontiguousarray(np.column_stack([self.table.h, camber]).ravel(), dtype=float)  # interleaved
        # a road with road camber (3D): else the compiled step leaves the cams' road-camber slope out (0: keyed)
        self._road_camber = bool(np.any(camber))
        self._numeric = {}  # the equations with this model's values in the graph (CasADi VM, FMU), built on first use
        self._names, self.theta = _run_time_parameters(model.params, self.constants)
        self._structure = _structure(self) if compiled else None  # not compiled: the numeric graphs only
        self._compiled = _Compiled(self, self._structure.key) if compiled else None

    # ------------------------------------------------------------------ equations
    @_with_casadi
    def _rhs(self, n_window, warm=False, stage=False, parametric=False, hoisted=False):
        """rhs(x, u, x0w, grid, hw, h) -> (dx, out): MX graph, so that the cam-height lookups stay compiled
        constant-time table accesses (an index computed from x into the window, no search). ``h``: the integration
        step that bounds the relaxation rate (0: the exact model). The contact solution: ``CONTACT_PASSES`` Newton
        passes from an estimate, or (``warm``, the stepper) ``WARM_PASSES`` from the solution stored in the state.
        ``stage`` (an RK stage of the stepper): (dx, the tandem base l_s) instead, without the expressions only the
        outputs need. ``parametric``: the numeric parameters are a further input ``theta`` (:attr:`theta`: run-time
        values, one graph per model structure) instead of numbers in the graph. ``hoisted`` (the stepper):
        (rhs_outputs, rhs_stage, hoisted) instead: the outputs alone (without the expressions only dx needs, e.g. the
        MF's Mx and My: ~17 % fewer operations) and the stage, whose last input ``q`` holds the parts of the equations
        that depend on theta, the inputs ``u`` and ``h`` only (pressure factors, products of parameters...): constant
        over a step, the stepper computes them once, ``q = hoisted(u, h, theta)``, not at each RK stage (~5 % of the
        operations)."""
        import casadi as ca

        x = ca.MX.sym("x", len(STATE_NAMES))
        u = ca.MX.sym("u", len(INPUT_NAMES))
        x0w, grid, h = ca.MX.sym("x0w"), ca.MX.sym("grid", n_window), ca.MX.sym("h")
        hw = ca.MX.sym("hw", 2 * n_window)  # cam height and road-camber slope, interleaved
        theta = ca.MX.sym("theta", len(self.theta)) if parametric else ca.MX(0, 1)

        # the physics as SX functions (compact C), the table lookups as MX calls between them
        ts = ca.SX.sym("theta", len(self.theta) if parametric else 0)
        m = _ParametricModel(self.model, self._names, self.constants, ts) if parametric else self.model
        c = m.constants if parametric else self.constants
        xs, us, hs = ca.SX.sym("x", len(STATE_NAMES)), ca.SX.sym("u", len(INPUT_NAMES)), ca.SX.sym("h", 6)
        hstep = ca.SX.sym("hstep")
        # the cams' road camber: 0 in the compiled library of a road without (keyed; its beta_x then depends on the
        # inputs only); the numeric graphs (virtual machine, FMU, whose keys do not name the road) always look it up
        road_camber = ca.atan(hs[5]) if self._road_camber or not parametric else 0.0
        with warnings.catch_warnings():  # numpy's sqrt of a parameter (a symbol here): CasADi's notice, not ours
            warnings.simplefilter("ignore", FutureWarning)
            start_sx = contact_start(m, c, xs, us, hs[0])
            geometry_sx = contact_geometry(m, c, xs, us, *(hs[i] for i in range(5)))
            dx_sx, out_sx = ring_equations(m, c, xs, us, *(hs[i] for i in range(5)), axle=self.axle, rim=self.rim,
                                           h=hstep, road_camber=road_camber, turn_slip=self.turn_slip)
        if hoisted:  # the parts constant over a step: the input q (both functions take the same q)
            (geometry_sx, dx_sx, out_sx), q_sx, q_values = ca.extract_parametric(
                ca.cse([geometry_sx, dx_sx, out_sx]), ca.vertcat(ts, us, hstep))
            qs, q = ca.vertcat(*q_sx), ca.MX.sym("q", len(q_sx))
        else:
            qs, q = ca.SX(0, 1), ca.MX(0, 1)
        start = ca.Function("contact_start", [xs, us, hs[0], ts], [start_sx], {"cse": True})
        geometry = ca.Function("contact_geometry", [xs, us, hs[:5], ts, qs], [geometry_sx], {"cse": True})

        spacing = grid[1] - grid[0]

        def cam(xc):  # (height, its slope along x, road-camber slope) at xc: linear between the uniform samples
            t = (xc - x0w - grid[0]) / spacing
            i = ca.fmin(ca.fmax(ca.floor(t), 0), n_window - 2)  # the sample left of xc (the end segments extrapolate)
            w = t - i
            h0, h1, c0, c1 = hw[2 * i], hw[2 * i + 2], hw[2 * i + 1], hw[2 * i + 3]
            return h0 + w * (h1 - h0), (h1 - h0) / spacing, c0 + w * (c1 - c0)

        xc = x[_S["xb"]]  # the tandem under the belt centre
        if warm:
            ls, passes = x[_S["lsm"]], WARM_PASSES
        else:
            ls, passes = start(x, u, cam(xc)[0], theta), CONTACT_PASSES
        for _ in range(passes):  # the tandem base at the current load
            (hf, dhf, _), (hr, dhr, _) = cam(xc + ls / 2), cam(xc - ls / 2)
            ls = geometry(x, u, ca.vertcat(hf, dhf, hr, dhr, ls), theta, q)
        (hf, dhf, cf), (hr, dhr, cr) = cam(xc + ls / 2), cam(xc - ls / 2)
        extra = ([theta] if parametric else []) + ([q] if hoisted else [])

        def rhs(name, outputs):  # outputs: dx, out
            physics = ca.Function("ring", [xs, us, hs, hstep, ts, qs], [(dx_sx, out_sx)[i] for i in outputs],
                                  {"cse": True})
            results = physics.call([x, u, ca.vertcat(hf, dhf, hr, dhr, ls, (cf + cr) / 2), h, theta, q])
            return ca.Function(name, [x, u, x0w, grid, hw, h, *extra], [results[0], ls] if name == "rhs_stage"
                               else results)

        if hoisted:
            return (rhs("rhs_outputs", (1,)), rhs("rhs_stage", (0,)),
                    ca.Function("hoisted", [us, hstep, ts], [ca.vertcat(*q_values)], {"cse": True}))
        return rhs("rhs_stage", (0,)) if stage else rhs("rhs", (0, 1))

    @_with_casadi
    def _build_step(self, parametric=False):
        """``swift_step(x, u, dt, x0w, grid, hw[, theta]) -> (x_next, out)`` (:attr:`step_function`)."""
        import casadi as ca

        rhs_outputs, rhs_stage, hoisted = self._rhs(self.window, warm=True, parametric=parametric, hoisted=True)
        x = ca.MX.sym("x", len(STATE_NAMES))
        u = ca.MX.sym("u", len(INPUT_NAMES))
        dt, x0w = ca.MX.sym("dt"), ca.MX.sym("x0w")
        grid, hw = ca.MX.sym("grid", self.window), ca.MX.sym("hw", 2 * self.window)
        extra = [ca.MX.sym("theta", len(self.theta))] if parametric else []
        h = dt / self.substeps
        stages = [*extra, hoisted(u, h, *(extra or [ca.MX(0, 1)]))]  # (theta,) q: computed once a step

        def with_memory(s, memory):  # s with its tandem base to start from
            return ca.vertcat(s[:_S["lsm"]], memory, s[_S["lsm"] + 1:])

        def f(s, memory):  # (dx, the tandem base) at s, its tandem base started from ``memory``
            return rhs_stage(with_memory(s, memory), u, x0w, grid, hw, h, *stages)

        xs, memory = x, x[_S["lsm"]]
        for _ in range(self.substeps):  # classical RK4; each stage starts from the previous stage's contact
            k1, memory = f(xs, memory)
            k2, memory = f(xs + h / 2 * k1, memory)
            k3, memory = f(xs + h / 2 * k2, memory)
            k4, memory = f(xs + h * k3, memory)
            xs = xs + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out = rhs_outputs(with_memory(xs, memory), u, x0w, grid, hw, h, *stages)
        xs = _remember_contact(xs, out)  # the contact solution for the next step
        return ca.Function("swift_step", [x, u, dt, x0w, grid, hw, *extra], [xs, out],
                           ["x", "u", "dt", "x0w", "grid", "hw", *(["theta"] if parametric else [])],
                           ["x_next", "out"])

    def share_equations(self, other: "SwiftTyre") -> None:
        """Use the numeric graphs of ``other`` (built on first use), a tyre of the same model in the same modes on
        another road: the graphs read the road through their window inputs only, so the tyres of one model on
        several roads need them built once (the dynamic gap finder simulates each candidate on every run)."""
        same = (other.model is self.model and (other.axle, other.rim, other.turn_slip, other.window, other.substeps)
                == (self.axle, self.rim, self.turn_slip, self.window, self.substeps))
        if not same:
            raise ModelInputError("share_equations: the other tyre has another model or other modes")
        self._numeric = other._numeric

    def _numeric_function(self, name):
        """The equations with this model's values in the graph, built on first use: ``rhs`` (exact model, contact
        solved afresh), ``warm`` (contact from the state's memory), ``step``."""
        with CASADI_LOCK:
            if name not in self._numeric:
                self._numeric[name] = (self._build_step() if name == "step"
                                       else self._rhs(self.window, warm=name == "warm"))
            return self._numeric[name]

    def _equilibrium_function(self, unknown, eqs):
        """(x, u, x0w, grid, hw) -> (the static equations, the Newton step's matrix in the unknowns), for
        :meth:`initial_state`; built on first use."""
        if self._equilibrium_kind == "structure":
            fn = self._structure.equilibrium(self, tuple(unknown), tuple(eqs))
            return lambda *args: fn(*args, self.theta)
        rhs = self._rhs_window
        with CASADI_LOCK:
            key = ("equilibrium", tuple(unknown), tuple(eqs))
            if key not in self._numeric:
                self._numeric[key] = _equilibrium_graph(rhs, self.window, unknown, eqs)
            return self._numeric[key]

    @functools.cached_property
    def _grid_dm(self):
        """The window's grid (:attr:`_grid`) as a CasADi matrix, for the virtual-machine calls (under the lock)."""
        import casadi as ca

        return ca.DM(self._grid)

    @property
    def _rhs_window(self):
        return self._numeric_function("rhs")

    @property
    def _rhs_warm(self):
        return self._numeric_function("warm")

    @property
    def _step_fn(self):
        return self._numeric_function("step")

    @property
    def step_function(self):
        """The CasADi step ``swift_step(x, u, dt, x0w, grid, hw) -> (x_next, out)`` that :meth:`step` runs
        (compiled): state and inputs in the order of STATE_NAMES / INPUT_NAMES, the window ``hw`` of ``window``
        samples of (cam height, road-camber slope) pairs, interleaved (:class:`swift.enveloping.CamTable`), on
        the local grid ``grid`` (= table.dx * arange(window)) starting at x = ``x0w``. The state's ``lsm`` entry
        carries the tandem base from step to step (:meth:`initial_state` sets them; l_s must be
        positive). For code generation (FMU)."""
        return self._step_fn

    def _key(self, kind):
        """The key of the model's structure: everything that shapes the equations' code (the parameters that select
        a form of the equations, which are absent, the run-time parameters' names and order, the modes, the
        integration, the equations' source, CasADi, the compiler flags), not the run-time values :attr:`theta`."""
        import casadi as ca

        payload = {**structure_of(self.model, self._names),  # (the values of the parameters not at run time...)
                   "axle": self.axle, "rim": self.rim, "turn_slip": self.turn_slip, "window": self.window,
                   "road_camber": self._road_camber, "substeps": self.substeps,
                   "lever": (self.constants.lever_x, self.constants.lever_y), "kind": kind,
                   "passes": (CONTACT_PASSES, WARM_PASSES), "cflags": COMPILER_FLAGS,
                   "equations": _SOURCE_HASH, "casadi": ca.__version__}
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()

    @property
    def cam_pairs(self) -> np.ndarray:
        """The whole cam table as :attr:`step_function` reads its window ``hw``: (cam height, road-camber slope)
        per sample of ``table``, interleaved (do not modify)."""
        return self._h

    @property
    @_with_casadi
    def output_function(self):
        """The outputs :meth:`step` reports at a state, as a CasADi function ``(x, u, x0w, grid, hw) -> out``
        (= ``step_function`` with dt = 0 at a quarter of the cost: the contact solution from the state's memory);
        for code generation (FMU)."""
        import casadi as ca

        x, u = ca.MX.sym("x", len(STATE_NAMES)), ca.MX.sym("u", len(INPUT_NAMES))
        x0w, grid, hw = ca.MX.sym("x0w"), ca.MX.sym("grid", self.window), ca.MX.sym("hw", 2 * self.window)
        return ca.Function("swift_outputs", [x, u, x0w, grid, hw], [self._rhs_warm(x, u, x0w, grid, hw, 0.0)[1]],
                           ["x", "u", "x0w", "grid", "hw"], ["out"])

    @property
    def rhs_function(self):
        """The right-hand side over a cam-height window as a CasADi function (x, u, x0w, grid, hw, h) -> (dx, out)
        (``h``: the integration step bounding the relaxation rate, 0 for the exact model; contact solved afresh)."""
        return self._rhs_window

    # ------------------------------------------------------------------ stepping
    def _row(self, inputs: StepInputs):
        """One step's inputs for the compiled loop: the ring's input vector (order of INPUT_NAMES), then the imposed
        axle x, z, vz and rim spin."""
        p = self._p_nominal if inputs.p is None else inputs.p
        return (inputs.vx, inputs.load, inputs.torque, p, inputs.y, inputs.vy, inputs.gamma, inputs.psi,
                inputs.road_camber, inputs.x, inputs.z, inputs.vz, inputs.omega)

    def _u(self, inputs: StepInputs):  # the ring's input vector
        return np.array(self._row(inputs)[:_NU], dtype=float)

    def _impose(self, state, inputs: StepInputs):
        state = np.array(state, dtype=float)
        state[_S["xa"]], state[_S["ya"]] = inputs.x, inputs.y
        if self.axle == "height":
            state[_S["za"]], state[_S["vza"]] = inputs.z, inputs.vz
        if self.rim == "speed":
            state[_S["oma"]] = inputs.omega
        if not state[_S["lsm"]] > 0:  # no contact solution stored yet (a state built by hand): solve it afresh
            self._store_contact(state, self._u(inputs))
        return state

    @_with_casadi
    def _store_contact(self, state, u):
        """Write the converged tandem base l_s of ``state`` into its memory entry."""
        if self._compiled is not None:
            out = self._compiled.rhs(state, u, self._rhs_args(state)[0], self._window_start(state[_S["xb"]]))[1]
        else:
            out = np.asarray(self._rhs_window(state, u, *self._rhs_args(state))[1]).ravel()
        state[_S["lsm"]] = out[OUTPUT_NAMES.index("ls")]

    def _window_start(self, xb):
        if not math.isfinite(xb):  # e.g. a stiffness of 1e308 made the equilibrium or a step overflow
            raise ModelInputError(f"the SWIFT ring's position is not finite ({float(xb)!r}): no finite solution with these "
                                  "parameters (check the [STRUCTURAL], [CONTACT_PATCH] and SWIFT_* values)")
        i0 = math.floor((xb - self.table.x0) / self.table.dx) - self.window // 2
        if i0 < 0 or i0 + self.window > self.table.h.size:
            raise self._outside_table(xb)
        return i0

    def _outside_table(self, xb):
        return ModelInputError(f"wheel at x = {xb:.3f} m is outside the road table "
                               f"[{self.table.x0 + self.window // 2 * self.table.dx:.3f}, "
                               f"{self.table.x[-1] - self.window // 2 * self.table.dx:.3f}] m (x_range)")

    @property
    def _reach(self):
        """Largest wheel travel [m] one compiled call may cover: the window half-width less ``TANDEM_REACH``."""
        return self.window // 2 * self.table.dx - TANDEM_REACH

    @property
    def _max_call(self):
        """Longest step [s] one compiled call may cover: ``substeps`` RK4 steps of at most :data:`MAX_RK4_STEP`."""
        return self.substeps * MAX_RK4_STEP

    def step(self, state, inputs: StepInputs, dt: float):
        """One step of length ``dt``: (state_next, :class:`Outputs`: the outputs by name). See the module notes for
        the API. A step over which the wheel would travel further than the cam-height window reaches is split into
        equal parts. Compiled: one C call (:data:`_DRIVER`) checks the inputs, imposes them, places the window and
        splits the step (travel, :data:`MAX_RK4_STEP`); state_next and the outputs are views of preallocated blocks,
        never overwritten later."""
        c = self._compiled
        if c is None:
            return self._step_casadi(state, inputs, dt)
        try:  # the compiled step inline (one Python frame per step): buffers from the tyre's pool
            b = c.free.pop()
        except IndexError:  # another thread is stepping this tyre: buffers of its own
            b = _StepBuffers(c)
        try:
            k = b.row
            if k == _BLOCK_ROWS:
                b.new_block()
                k = 0
            if state is b.last:  # the state returned last: read in place, in its block row
                src = k - 1
            else:
                b.x[:] = state
                src = -1
            p = inputs.p
            try:
                c.pack(b.io, 0, inputs.vx, inputs.load, inputs.torque, self._p_nominal if p is None else p, inputs.y,
                       inputs.vy, inputs.gamma, inputs.psi, inputs.road_camber, inputs.x, inputs.z, inputs.vz,
                       inputs.omega, dt, 1.0, src, k)
            except struct.error:
                raise _not_a_number(inputs, dt) from None
            if p is not None and not self._p_factors.low < p < self._p_factors.high:
                self._warn_pressure(p, p)
            code = c.step1(b.args)
            if not code:
                b.row, b.last = k + 1, b.xs[k]
                return b.last, Outputs(b.ys, k)
            if code != -4:
                c.check(code, b.x[_S["xb"]] if src < 0 else b.xs[src, _S["xb"]], [b.io[:_NI]], dt)
        finally:
            c.free.append(b)
        # a state without a stored contact solution (built by hand): solved first
        return self.step(self._impose(state, inputs), inputs, dt)

    @_with_casadi
    def _step_casadi(self, state, inputs: StepInputs, dt: float):
        if not (math.isfinite(dt) and dt >= 0):
            raise ModelInputError(f"the step dt must be finite and >= 0; got dt = {dt!r}")
        row = self._row(inputs)
        try:
            bad = [name for name, value, used in zip(_ROW, row, _used(self)) if used and not math.isfinite(value)]
        except TypeError:
            raise _not_a_number(inputs, dt) from None
        if bad:
            raise ModelInputError(f"input {bad[0]!r} must be finite, got {row[_ROW.index(bad[0])]!r}")
        if not row[INPUT_NAMES.index("p")] > 0:
            raise ModelInputError(f"input 'p' (inflation pressure) must be positive [Pa], got {inputs.p!r}")
        check_pressure(self.model.params, row[INPUT_NAMES.index("p")])
        self._warn_pressure(row[INPUT_NAMES.index("p")], row[INPUT_NAMES.index("p")])
        state = self._impose(state, inputs)
        u = self._u(inputs)
        n = max(1, math.ceil(abs(inputs.vx) * dt / self._reach), math.ceil(dt / self._max_call - 1e-9))
        for _ in range(n):
            i0 = self._window_start(state[_S["xb"]])
            x0w = self.table.x0 + i0 * self.table.dx
            res = self._step_fn(state, u, dt / n, x0w, self._grid, self._h[2 * i0:2 * (i0 + self.window)])
            state, out = (np.asarray(r).ravel() for r in res)
        return state, Outputs(out[None])

    def run(self, t_end: float, inputs, dt: float = 1e-3) -> SimResult:
        """Fixed-step run from the static equilibrium. ``inputs``: a :class:`StepInputs` (constant speeds; the
        imposed positions advance with them), a callable ``t -> StepInputs`` or a :class:`StepSeries` (the inputs
        of each step); outputs every ``dt``. Each step is :meth:`step` with the inputs at its start; compiled, the
        whole loop runs in C."""
        n = int(round(t_end / dt))
        series = inputs if isinstance(inputs, StepSeries) else None
        if series is not None:
            get = lambda t: series.at(int(round(t / dt)))  # noqa: E731
        else:
            get = inputs if callable(inputs) else _advancing(inputs)
        first = get(0.0)
        state = self.initial_state(first)
        states, outs = np.empty((n + 1, len(STATE_NAMES))), np.empty((n + 1, len(OUTPUT_NAMES)))
        states[0], outs[0] = state, self.outputs(state, first)
        if self._compiled is None:
            for k in range(n):
                state, out = self.step(state, get(k * dt), dt)
                states[k + 1], outs[k + 1] = state, out.array
        else:
            if series is not None:
                rows = series.rows(n, self._row(StepInputs()))
            elif callable(inputs):
                rows = np.array([self._row(get(k * dt)) for k in range(n)], dtype=float).reshape(n, _NI)
            else:  # constant speeds: the imposed positions advance as in _advancing
                t = dt * np.arange(n)
                rows = np.tile(np.array(self._row(inputs), dtype=float), (n, 1))
                for i, speed in ((_U_Y, inputs.vy), (_NU, inputs.vx), (_NU + 1, inputs.vz)):
                    rows[:, i] += speed * t
            if n:
                self._warn_pressure(float(np.min(rows[:, _U_P])), float(np.max(rows[:, _U_P])))
            states[1:], outs[1:] = self._compiled.run(state, rows, dt)
        return SimResult(dt * np.arange(n + 1), states, dict(zip(OUTPUT_NAMES, outs.T)))

    def _warn_pressure(self, p_min, p_max):
        """The model's warning (once per factor) where a pressure factor of the file has changed sign at the pressures
        used (saturated to PRESMIN..PRESMAX as the slip model uses them): :class:`mftyre.inputs.PressureFactorCheck`."""
        lo, hi = self._p_range
        self._p_factors(min(max(p_min, lo), hi), min(max(p_max, lo), hi), stacklevel=4)

    def outputs(self, state, inputs: StepInputs) -> np.ndarray:
        """Outputs at ``state`` (no time step), in the order of OUTPUT_NAMES."""
        return self.step(state, inputs, 0.0)[1].array.copy()

    # ------------------------------------------------------------------ reference and statics
    def _rhs_args(self, state):
        i0 = self._window_start(state[_S["xb"]])
        return self.table.x0 + i0 * self.table.dx, self._grid, self._h[2 * i0:2 * (i0 + self.window)], 0.0

    @_with_casadi
    def derivative(self, state, inputs: StepInputs):
        """State derivative (CasADi VM on the same right-hand side): for the reference run and checks."""
        state = self._impose(state, inputs)
        return np.asarray(self._rhs_window(state, self._u(inputs), *self._rhs_args(state))[0]).ravel()

    @_with_casadi
    def run_adaptive(self, t_end: float, inputs: StepInputs, dt: float = 1e-3, rtol: float = 1e-8,
                     atol: float = 1e-10) -> SimResult:
        """Accuracy reference: scipy ``solve_ivp`` (DOP853, tight tolerances) on the same right-hand side,
        constant input speeds, outputs every ``dt``."""
        from scipy.integrate import solve_ivp

        u = self._u(inputs)
        x0 = self.initial_state(inputs)
        t_eval = dt * np.arange(int(round(t_end / dt)) + 1)
        sol = solve_ivp(lambda t, s: np.asarray(self._rhs_window(s, u, *self._rhs_args(s))[0]).ravel(),
                        (0.0, t_eval[-1]), x0, method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol,
                        first_step=1e-6, max_step=dt / 2)
        if not sol.success:
            raise ArithmeticError(f"adaptive reference failed: {sol.message}")
        outs = np.array([np.asarray(self._rhs_window(s, u, *self._rhs_args(s))[1]).ravel() for s in sol.y.T])
        return SimResult(sol.t, sol.y.T, dict(zip(OUTPUT_NAMES, outs.T)))

    @_with_casadi
    def jacobian(self, state, inputs: StepInputs):
        """d(state derivative)/d(state) at ``state``: the linearised model (eigenvalues, stability)."""
        import casadi as ca

        state = self._impose(state, inputs)
        xs = ca.MX.sym("x", len(STATE_NAMES))
        d = self._rhs_window(xs, self._u(inputs), *self._rhs_args(state))[0]
        return np.asarray(ca.Function("linearised", [xs], [ca.jacobian(d, xs)])(state))

    @property
    def equilibrium_unknowns(self):
        """(unknowns, equations) of the static equilibrium: state indices solved for and the derivatives (in the
        order of STATE_NAMES) that vanish there, for :meth:`initial_state` and the FMU's initialisation."""
        unknown = [_S[n] for n in ("xb", "zb", "thw", "yb", "gb", "psb", "ux", "uy", "kappa", "alpha", "psr",
                                   "betaf")]
        eqs = [_S[n] for n in ("vxb", "vzb", "omb", "vyb", "wgb", "wpsb", "ux", "uy", "kappa", "alpha", "psr",
                               "betaf")]
        if self.turn_slip:
            unknown.append(_S["phi"])
            eqs.append(_S["phi"])
        if self.axle == "load":
            unknown.append(_S["za"])
            eqs.append(_S["vza"])
        if self.rim == "torque":  # the spin follows the torque: rim at rest relative to the belt, torques balanced
            unknown += [_S["oma"], _S["omb"]]
            eqs += [_S["oma"], _S["thw"]]
        return unknown, eqs

    @_with_casadi
    def equilibrium_function(self, iterations: int = 30):
        """:meth:`initial_state` as one CasADi function for code generation (FMU):
        ``(xa, za, vza, omega, u, x0w, grid, hw) -> x`` at the axle position ``xa``, height ``za`` (above the cam
        table's road; with ``axle="load"`` unused: the axle height is solved for from the input load, as
        initial_state), vertical speed ``vza`` and spin ``omega`` (with ``rim="torque"`` not used: the spin starts at
        free rolling, :func:`free_rolling_spin`), ring inputs ``u`` (INPUT_NAMES) and the window of
        :attr:`step_function`: the same start (the steady-state load at the deflection under the axle),
        ``iterations`` Newton steps (:func:`_newton_inverse`, as initial_state) on :attr:`equilibrium_unknowns`,
        then the contact solution stored in the memory entries."""
        import casadi as ca

        from mftyre.backend import casadi_backend

        be, prm, n = casadi_backend(), self.model.params, self.window
        inputs = xa, za, vza, omega = [ca.MX.sym(name) for name in ("xa", "za", "vza", "omega")]
        u = ca.MX.sym("u", len(INPUT_NAMES))
        x0w, grid, hw = ca.MX.sym("x0w"), ca.MX.sym("grid", n), ca.MX.sym("hw", 2 * n)
        U = {name: u[i] for i, name in enumerate(INPUT_NAMES)}
        h = ca.interpolant("cam", "linear", [n], 2, {"lookup_mode": ["exact"]})(xa - x0w, grid, hw)[0]
        r0, dpi = vertical.free_radius(prm, 0.0, be), vertical.pressure_increment(prm, U["p"])
        if self.axle == "load":  # as initial_state: the axle at the loaded radius of the load on the tyre, at rest
            fz = U["load"] - self.constants.mb * prm.GRAVITY
            za = h + vertical.loaded_radius(prm, be.fmax(fz, 0.0), r0, 0.0, 0.0, 0.0, 0.0, dpi, be)[0]
            vza = 0.0
        else:
            rl = be.fmin(za - h, prm.UNLOADED_RADIUS)  # as initial_state: model.vertical_force at no spin or slip
            fz = vertical.vertical_force(prm, rl, r0, 0.0, 0.0, 0.0, 0.0, dpi, be)
        if self.rim == "torque":  # as initial_state: the spin starts at free rolling (omega is not used)
            omega = free_rolling_spin(prm, fz, U["vx"], dpi, be)
        guess = dict.fromkeys(STATE_NAMES, 0.0)
        guess.update(xa=xa, xb=xa, za=za, vza=vza, zb=za + be.fmax(fz, 0.0) / self.constants.cbx, vxb=U["vx"],
                     vyb=U["vy"], oma=omega, omb=omega, yb=U["y"], ya=U["y"], gb=U["gamma"], psb=U["psi"])

        unknown, eqs = self.equilibrium_unknowns
        s = ca.MX.sym("s", len(STATE_NAMES))
        r = self._rhs_window(s, u, x0w, grid, hw, 0.0)[0][eqs]
        delta = -ca.mtimes(_newton_inverse(ca.jacobian(r, s)[:, unknown]), r)
        parts = ca.vertsplit(s)
        for k, i in enumerate(unknown):
            parts[i] = parts[i] + delta[k]
        newton = ca.Function("swift_newton", [s, u, x0w, grid, hw], [ca.vertcat(*parts)])
        xi = ca.vertcat(*(guess[name] for name in STATE_NAMES))
        for _ in range(iterations):
            xi = newton(xi, u, x0w, grid, hw)
        xi = _remember_contact(xi, self._rhs_window(xi, u, x0w, grid, hw, 0.0)[1])
        return ca.Function("swift_equilibrium", [*inputs, u, x0w, grid, hw], [xi],
                           ["xa", "za", "vza", "omega", "u", "x0w", "grid", "hw"], ["x"])

    @functools.cached_property
    @_with_casadi
    def equilibrium_residual_function(self):
        """The derivatives that vanish in static equilibrium (:attr:`equilibrium_unknowns`' equations, in their
        order) at a state: ``(x, u, x0w, grid, hw) -> r``, as :meth:`initial_state` tests them against
        :data:`EQUILIBRIUM_TOL` (:data:`NO_EQUILIBRIUM`); for the FMUs' initialisation."""
        import casadi as ca

        n = self.window
        x, u = ca.MX.sym("x", len(STATE_NAMES)), ca.MX.sym("u", len(INPUT_NAMES))
        x0w, grid, hw = ca.MX.sym("x0w"), ca.MX.sym("grid", n), ca.MX.sym("hw", 2 * n)
        d = self._rhs_window(x, u, x0w, grid, hw, 0.0)[0]
        return ca.Function("swift_residual", [x, u, x0w, grid, hw], [d[self.equilibrium_unknowns[1]]],
                           ["x", "u", "x0w", "grid", "hw"], ["r"])

    @functools.cached_property
    @_with_casadi
    def rolling_root_function(self):
        """The rule that a static root is a rolling tyre, one definition for :meth:`initial_state`,
        :class:`swift.fmu_model.SwiftWheel` and the native FMU (generated C): ``(x, u, x0w, grid, hw) -> facts``
        (the window of :attr:`step_function`), facts = [refused (1 or 0), kappa, belt spin, free radius, belt centre
        above the cam road under the axle]. Refused: rolling (|vx| >= VXLOW) with the slip kappa outside
        KPUMIN..KPUMAX (at standstill kappa is a deflection, not a slip). The message: :func:`no_rolling_root_template`
        of the facts."""
        import casadi as ca

        from mftyre.backend import casadi_backend

        prm, n = self.model.params, self.window
        x, u = ca.MX.sym("x", len(STATE_NAMES)), ca.MX.sym("u", len(INPUT_NAMES))
        x0w, grid, hw = ca.MX.sym("x0w"), ca.MX.sym("grid", n), ca.MX.sym("hw", 2 * n)
        h = ca.interpolant("cam", "linear", [n], 2, {"lookup_mode": ["exact"]})(x[_S["xa"]] - x0w, grid, hw)[0]
        kappa, omega_belt = x[_S["kappa"]], x[_S["omb"]]
        refused = ca.logic_and(ca.fabs(u[INPUT_NAMES.index("vx")]) >= prm.VXLOW,
                               ca.logic_or(kappa < prm.KPUMIN, kappa > prm.KPUMAX))
        facts = ca.vertcat(refused, kappa, omega_belt, vertical.free_radius(prm, omega_belt, casadi_backend()),
                           x[_S["zb"]] - h)
        return ca.Function("swift_root", [x, u, x0w, grid, hw], [facts], ["x", "u", "x0w", "grid", "hw"], ["facts"])

    @_with_casadi
    def initial_state(self, inputs: StepInputs, iterations: int = 30) -> np.ndarray:
        """Static equilibrium (steady rolling at the input speeds) at the axle position of ``inputs``: Newton
        on the accelerations and patch rates, from the steady-state model's deflection. With ``rim="torque"`` the
        spin is an unknown too, started at free rolling (:func:`free_rolling_spin`; ``inputs.omega`` is not used): the
        rim torque balances the input torque.
        Raises :class:`~mftyre.errors.ModelInputError` where the iteration ends without equilibrium (residual above
        :data:`EQUILIBRIUM_TOL`), and where it ends at a root that is no rolling tyre (:attr:`rolling_root_function`,
        the rule the FMUs apply too): rolling (|vx| >= VXLOW), a slip outside KPUMIN..KPUMAX (the agricultural
        sample files at 40-70 m/s, 4-20 times their LONGVL and beyond their speed rating: rolling resistance
        (QSY4 (V/LONGVL)^4) and radius growth (Q_V1) run away, the root spins backwards at kappa -100..-600 with a
        free radius of 8-36 m and had growing modes of +200..+640 1/s)."""
        import casadi as ca

        prm = self.model.params
        c = self.constants
        p = prm.INFLPRES if inputs.p is None else inputs.p
        check_pressure(prm, p)
        # the model's speed limits (mftyre.inputs.check_limits): beyond them no tyre rolls (docs/model-input-policy.md)
        check_speed_limits(prm, inputs.vx, inputs.omega, omega_given=self.rim == "speed")
        self._warn_pressure(p, p)
        s = np.zeros(len(STATE_NAMES))
        s[_S["xa"]] = s[_S["xb"]] = inputs.x
        h = float(self.table(inputs.x))
        if self.axle == "load":
            fz = inputs.load - c.mb * prm.GRAVITY
            rl, _ = self.model.loaded_radius(fz, p=p)
            s[_S["za"]] = h + float(rl)
        else:
            s[_S["za"]], s[_S["vza"]] = inputs.z, inputs.vz
            fz = float(self.model.vertical_force(min(inputs.z - h, prm.UNLOADED_RADIUS), p=p))
        s[_S["zb"]] = s[_S["za"]] + max(fz, 0.0) / c.cbx
        s[_S["vxb"]], s[_S["vyb"]] = inputs.vx, inputs.vy
        s[_S["oma"]] = s[_S["omb"]] = (inputs.omega if self.rim == "speed" else float(
            free_rolling_spin(prm, fz, inputs.vx, vertical.pressure_increment(prm, p), NUMPY)))
        s[_S["yb"]] = s[_S["ya"]] = inputs.y
        s[_S["gb"]], s[_S["psb"]] = inputs.gamma, inputs.psi
        unknown, eqs = self.equilibrium_unknowns
        # the Jacobian from the graph with this model's values, as the FMU's equilibrium_function: at standstill it
        # is singular and the regularised step amplifies the round-off in which two graphs differ (~1e-7 m)
        equilibrium = self._equilibrium_function(unknown, eqs)
        x0w, _, hw = self._rhs_args(s)[:3]
        # the window as CasADi matrices once for every virtual-machine call below (numpy's 3k values took ~70 us a call)
        u, window, i0 = self._u(inputs), (x0w, self._grid_dm, ca.DM(hw)), self._window_start(s[_S["xb"]])
        inverse, last = None, np.inf
        for _ in range(iterations):  # Newton; compiled, the Jacobian is kept while the steps shrink tenfold
            if inverse is None or self._compiled is None:
                r, inverse = (np.asarray(v) for v in equilibrium(s, u, *window))
            else:
                r = self._compiled.rhs(s, u, window[0], i0)[0][eqs]
            step = -inverse @ r.ravel()
            s[unknown] += step
            size = np.max(np.abs(step))
            if size < 1e-13:
                break
            if not size < 0.1 * last:
                inverse = None
            last = size
        r = (self._compiled.rhs(s, u, window[0], i0)[0][eqs] if self._compiled is not None
             else np.asarray(equilibrium(s, u, *window)[0])).ravel()
        finite = bool(np.all(np.isfinite(r)) and np.all(np.isfinite(s)))
        worst = int(np.argmax(np.abs(r))) if finite else int(np.argmin(np.isfinite(r)))
        at = (f"vx = {inputs.vx} m/s, " + (f"load = {inputs.load} N" if self.axle == "load" else f"z = {inputs.z} m")
              + (f", torque = {inputs.torque} N m" if self.rim == "torque" else f", omega = {inputs.omega} rad/s")
              + f", p = {p:g} Pa")
        if not finite:  # overflow in the ring's constants or equations: no input can help
            raise ModelInputError(
                f"the SWIFT equations are not finite with these parameters (d({STATE_NAMES[eqs[worst]]})/dt = "
                f"{float(r[worst])!r} at the inputs {at}): check the [STRUCTURAL] (FREQ_*, DAMP_*, BELT_*), "
                f"[VERTICAL] and [CONTACT_PATCH] values and SWIFT_* for one no tyre has")
        if not abs(r[worst]) <= EQUILIBRIUM_TOL:
            raise ModelInputError(NO_EQUILIBRIUM % (at, iterations, STATE_NAMES[eqs[worst]], r[worst], EQUILIBRIUM_TOL))
        facts = np.asarray(self.rolling_root_function(s, u, *window), dtype=float).ravel()
        if facts[0]:
            raise ModelInputError(no_rolling_root_template(prm) % (at, *facts[1:]))
        self._store_contact(s, u)
        return s


class _ParametricModel(ParametricModel):
    """The model with run-time parameters (:class:`mftyre.model.ParametricModel`, the entries of ``theta`` for
    ``names``) and the ring constants as the entries of ``theta`` after the parameters (``constants``)."""

    def __init__(self, model, names, constants, theta):
        super().__init__(model, names, [theta[i] for i in range(len(names))])
        self.constants = replace(constants, **{f: theta[len(names) + i] for i, f in enumerate(_RING_FIELDS)})


#: The numeric fields of :class:`swift.ring.RingConstants`, run-time parameters after the .tir's.
_RING_FIELDS = ("mb", "ibx", "iby", "cbx", "cby", "cbg", "cbth", "kbx", "kby", "kbg", "kbth", "axle_mass",
                "rim_inertia")


def _run_time_parameters(params, constants):
    """(names, values): the .tir parameters the compiled step takes at run time
    (:func:`mftyre.model.run_time_parameter_names`; which are 0 is part of the structure, :meth:`SwiftTyre._key`: a
    refit that moves one away from 0 builds one more library) and their values, followed by the ring constants
    (:data:`_RING_FIELDS`)."""
    names = run_time_parameter_names(params)
    values = [params[n] for n in names] + [float(getattr(constants, f)) for f in _RING_FIELDS]
    return names, np.ascontiguousarray(values, dtype=float)


class _Structure:
    """The equations of one model structure (:meth:`SwiftTyre._key`) with the parameters as the run-time input
    ``theta``: ``step`` and ``rhs``, compiled into the library. Shared by every tyre of the structure."""

    def __init__(self, key, tyre):
        self.key = key
        self.step = tyre._build_step(parametric=True)
        self.rhs = tyre._rhs(tyre.window, parametric=True)
        self._equilibria = {}

    def equilibrium(self, tyre, unknown: tuple, eqs: tuple):
        """(x, u, x0w, grid, hw, theta) -> (the static equations, the Newton step's matrix in the unknowns): the
        structure's :meth:`SwiftTyre._equilibrium_function`, built on first use."""
        with CASADI_LOCK:
            if (unknown, eqs) not in self._equilibria:
                self._equilibria[(unknown, eqs)] = _equilibrium_graph(self.rhs, tyre.window, unknown, eqs,
                                                                      len(tyre.theta))
            return self._equilibria[(unknown, eqs)]


#: Model structures built in this process (key -> :class:`_Structure`): a tyre of a known structure builds no
#: equations and compiles nothing; its parameters are passed per call.
_STRUCTURES: dict = {}


def _structure(tyre) -> _Structure:
    key = tyre._key("step")
    with CASADI_LOCK:
        if key not in _STRUCTURES:
            _STRUCTURES[key] = _Structure(key, tyre)
        return _STRUCTURES[key]


#: Tikhonov weight of the static Newton step on the equilibrated Jacobian (rows and columns of unit norm): small
#: against the squared singular values of the determined directions (away from standstill the step is Newton's: the
#: equilibrium converges to round-off), large against the round-off of the normal equations (condition <= n / 1e-12).
_TIKHONOV = 1e-12


def free_rolling_spin(prm, fz, vx, dpi, be):
    """The spin [rad/s] of free rolling (no slip) at the speed ``vx`` under the load ``fz`` (<= 0: none) with the
    steady-state model's effective rolling radius (omega Re = vx, (2.5) with (1) and (7):
    :func:`mftyre.formula.vertical.spin_and_radius`): where the static Newton iteration of a free rim
    (:meth:`SwiftTyre.initial_state`, :meth:`SwiftTyre.equilibrium_function`) starts. A start spin given by the
    caller is not used there: one 13 times free rolling (vx over the deflection instead of over Re; rim speed 273 m/s
    on the agricultural sample file at 20 m/s, 8 times its rim-speed limit, free radius 6.1 m) put the first Newton
    iterate 94 m into the belt (loads of MN, where My and Re at the load as given are steep), and the iteration
    stalled at kappa = -5e6 (d(kappa)/dt = 1.5e-4 after 30 steps)."""
    from types import SimpleNamespace

    state = SimpleNamespace(uFz=be.fmax(fz, 0.0), dpi=dpi, ukappa=0.0, vx=vx)
    return vertical.spin_and_radius(prm, state, 0.0, False, be)[0]


def _equilibrium_graph(rhs, window: int, unknown, eqs, n_theta: int | None = None):
    """(x, u, x0w, grid, hw[, theta]) -> (the static equations ``eqs`` of the right-hand side ``rhs``, the Newton
    step's matrix in the ``unknown`` states, :func:`_newton_inverse`): with ``n_theta`` the parameter values are the
    last input (the structure's graph), without them in the graph (the model's)."""
    import casadi as ca

    xs, us = ca.MX.sym("x", len(STATE_NAMES)), ca.MX.sym("u", len(INPUT_NAMES))
    x0w, grid, hw = ca.MX.sym("x0w"), ca.MX.sym("grid", window), ca.MX.sym("hw", 2 * window)
    theta = [] if n_theta is None else [ca.MX.sym("theta", n_theta)]
    d = rhs(xs, us, x0w, grid, hw, 0.0, *theta)[0][list(eqs)]
    return ca.Function("equilibrium", [xs, us, x0w, grid, hw, *theta],
                       [d, _newton_inverse(ca.jacobian(d, xs)[:, list(unknown)])])


def _newton_inverse(jac):
    """M with the static Newton step = -M r (CasADi, the one home of the step of :meth:`SwiftTyre.initial_state`
    and :meth:`SwiftTyre.equilibrium_function`): regularised least squares (Levenberg-Marquardt with a fixed small
    weight) on the Jacobian scaled to rows and columns of unit norm. At standstill the Jacobian is singular (the
    slip states and patch deflections are undetermined: any preload the static grip holds is an equilibrium);
    the step then has no component in its null space, so those states keep their start (no slip, no deflection)
    where a plain solve fails (old: QR, "no static equilibrium found" at vx = 0)."""
    import casadi as ca

    rows = 1.0 / ca.fmax(ca.sqrt(ca.sum2(jac**2)), 1e-300)
    scaled = ca.mtimes(ca.diag(rows), jac)
    cols = 1.0 / ca.fmax(ca.sqrt(ca.sum1(scaled**2)), 1e-300).T
    scaled = ca.mtimes(scaled, ca.diag(cols))
    normal = ca.mtimes(scaled.T, scaled) + _TIKHONOV * ca.DM.eye(jac.shape[1])
    return ca.mtimes(ca.diag(cols), ca.mtimes(ca.solve(normal, scaled.T, "qr"), ca.diag(rows)))


def _remember_contact(x, out):
    """The state ``x`` (CasADi) with the tandem base of its outputs ``out`` in the memory entry lsm."""
    import casadi as ca

    return ca.vertcat(x[:_S["lsm"]], out[OUTPUT_NAMES.index("ls")], x[_S["lsm"] + 1:])


_NU = len(INPUT_NAMES)
_U_Y = INPUT_NAMES.index("y")  # the lateral position in the input vector
_U_P = INPUT_NAMES.index("p")  # the inflation pressure in the input vector
#: One row of the compiled loop (:meth:`SwiftTyre._row`): the ring's inputs, then the imposed axle x, z, vz, spin.
_ROW = (*INPUT_NAMES, "x", "z", "vz", "omega")
_NI = len(_ROW)


def _used(tyre):
    """Per entry of :data:`_ROW`: does the tyre's configuration use it (checked finite)?"""
    unused = {"height": {"load"}, "load": {"z", "vz"}}[tyre.axle] | {"speed": {"torque"}, "torque": {"omega"}}[tyre.rim]
    return [name not in unused for name in _ROW]


def _advancing(inputs: StepInputs):
    """Constant speeds: the imposed positions advance with them."""
    def get(t):
        return replace(inputs, x=inputs.x + inputs.vx * t, z=inputs.z + inputs.vz * t, y=inputs.y + inputs.vy * t)
    return get


#: The stepping loop around the generated ``swift_step`` (appended to its C file): per step, the inputs the
#: configuration uses (``USED``) are checked (finite, p > 0), the imposed axle x, z, vz and rim spin are written into
#: the state (as :meth:`SwiftTyre._impose`), the step is split into equal parts where the wheel would travel
#: further than ``reach`` (cfg[3]) or the step is longer than ``substeps`` RK4 steps of MAX_RK4_STEP (cfg[4]), and
#: the window of the cam table (``table``, cfg: x0, dx, samples, reach, longest call, then NOMPRES and the sidewall
#: pressure coefficients of the check) starts ``WINDOW / 2`` samples behind the belt centre; p[12]: the run-time
#: parameters ``theta`` (:attr:`SwiftTyre.theta`). ``in``: one row of NI values per step (:data:`_ROW`); ``scal``: dt,
#: number of steps; all pointers in one array ``p`` (one argument: the cheapest ctypes call). Returns 0, k + 1
#: when step k leaves the table, -1 for a non-finite or negative step or a travel beyond 1e6 windows, -2 for an
#: evaluation error, -3 for a bad input (:meth:`_Compiled._bad_input` says which), -4 when the state holds no
#: contact solution. ``swift_step1``: one step of :meth:`SwiftTyre.step` into the rows of preallocated blocks.
_DRIVER = """
#define NX %(nx)d
#define NY %(ny)d
#define NU %(nu)d
#define NI %(ni)d
#define WINDOW %(window)d
#define P_NOM cfg[5]
#define P_STIFF cfg[6]
#define P_DAMP cfg[7]
static const int USED[NI] = {%(used)s};
CASADI_SYMBOL_EXPORT int swift_run(void** p) {
  const casadi_real *x_init = p[0], *in = p[1], *scal = p[2], *cfg = p[3], *grid = p[4], *table = p[5];
  const casadi_real* theta = p[12];
  casadi_real *xs = p[6], *ys = p[7], *w = p[11], s[NX], dt = scal[0], h, x0w, parts, start;
  const casadi_real** arg = p[8];
  casadi_real** res = p[9];
  casadi_int* iw = p[10];
  casadi_int n = (casadi_int) scal[1], k, j, m, i;
  if (!(dt >= 0 && dt - dt == 0)) return -1;
  for (i = 0; i < NX; ++i) s[i] = x_init[i];
  if (!(s[%(lsm)d] > 0)) return -4;
  for (k = 0; k < n; ++k) {
    const casadi_real* u = in + k * NI;
    for (i = 0; i < NI; ++i) if (USED[i] && !(u[i] - u[i] == 0)) return -3;
    if (!(u[%(p)d] > 0 && 1 + P_STIFF * ((u[%(p)d] - P_NOM) / P_NOM) > 0 && 1 + P_DAMP * ((u[%(p)d] - P_NOM) / P_NOM) > 0))
      return -3;
    s[%(xa)d] = u[NU];
    s[%(ya)d] = u[%(y)d];
    if (%(height)d) { s[%(za)d] = u[NU + 1]; s[%(vza)d] = u[NU + 2]; }
    if (%(speed)d) s[%(oma)d] = u[NU + 3];
    parts = fmax(ceil(fabs(u[0]) * dt / cfg[3]), ceil(dt / cfg[4] - 1e-9));
    if (!(parts < 1e6)) return -1;
    m = parts < 1 ? 1 : (casadi_int) parts;
    h = dt / m;
    for (j = 0; j < m; ++j) {
      start = floor((s[%(xb)d] - cfg[0]) / cfg[1]) - WINDOW / 2;
      if (!(start >= 0 && start + WINDOW <= cfg[2])) return k + 1;
      x0w = cfg[0] + start * cfg[1];
      arg[0] = s; arg[1] = u; arg[2] = &h; arg[3] = &x0w; arg[4] = grid; arg[5] = table + 2 * (casadi_int) start;
      arg[6] = theta;
      res[0] = xs + k * NX; res[1] = ys + k * NY;
      if (swift_step(arg, res, iw, w, 0)) return -2;
      for (i = 0; i < NX; ++i) s[i] = xs[k * NX + i];
    }
  }
  return 0;
}
/* one step: p as for swift_run, but p[1] = io: the NI inputs, dt, 1, the row of the state in the block p[6]
   (< 0: the state is p[0]), the row of p[6] and p[7] to write */
CASADI_SYMBOL_EXPORT int swift_step1(void** p) {
  void* q[13];
  casadi_real* io = p[1];
  casadi_int src = (casadi_int) io[NI + 2], dst = (casadi_int) io[NI + 3], i;
  for (i = 0; i < 13; ++i) q[i] = p[i];
  if (src >= 0) q[0] = (casadi_real*) p[6] + src * NX;
  q[2] = io + NI;
  q[6] = (casadi_real*) p[6] + dst * NX;
  q[7] = (casadi_real*) p[7] + dst * NY;
  return swift_run(q);
}
"""


#: Compiler flags of the SWIFT library: ~15 % fewer instructions per step than -O2 (-fno-math-errno: sqrt and
#: friends inline, errno is never read; gnu89: CasADi's fmax/fmin become comparisons instead of libm calls,
#: equal for all non-NaN arguments); of the fast-math family only mftyre.compiled's two (-fno-trapping-math,
#: -freciprocal-math: multiplication by a reciprocal, at most 1 ulp per division; ~4 % faster), no reassociation,
#: no finite-math assumptions; portable (no -march), as the FMU ships the library. -fno-semantic-interposition:
#: CasADi's helpers (casadi_sq, _fmax, _fmin, _fabs, _sign, _copy) are global functions of the library, which
#: -fPIC otherwise calls through the PLT at ~230 places per right-hand side, each call spilling every live
#: floating-point register (all are caller-saved); inlined, the turn-slip cleat run is ~5 % faster (round-off:
#: the reciprocals then apply across them, outputs within 2e-13 of their range).
COMPILER_FLAGS = ("-O3", "-fno-math-errno", "-fno-trapping-math", "-freciprocal-math", "-std=gnu89",
                  "-fno-semantic-interposition")


def _library(tyre, key: str) -> Path:
    """The tyre's library through :func:`mftyre.compiled.cached_library` (verified before it is loaded, built
    when missing or damaged): C code of the MX step as it is (no SX expansion) and the right-hand side, plus
    :data:`_DRIVER`."""
    import casadi as ca

    structure = tyre._structure or _structure(tyre)

    def generate(folder):
        gen = ca.CodeGenerator("swift.c", {"with_header": False})
        for function in (structure.step, structure.rhs):
            gen.add(function)
        source = Path(gen.generate(str(folder) + os.sep))
        with source.open("a") as f:
            f.write(_DRIVER % dict(nx=len(STATE_NAMES), ny=len(OUTPUT_NAMES), nu=_NU, ni=_NI, window=tyre.window,
                                   height=int(tyre.axle == "height"), speed=int(tyre.rim == "speed"),
                                   used=", ".join(str(int(u)) for u in _used(tyre)), p=INPUT_NAMES.index("p"),
                                   y=INPUT_NAMES.index("y"), **_S))
        meta = {"inputs": list(INPUT_NAMES), "outputs": list(OUTPUT_NAMES), "checks": [], "states": list(STATE_NAMES)}
        return source, (*COMPILER_FLAGS, "-fPIC", "-shared"), ("-lm",), meta

    return cached_library("swift", key, generate)


#: States and outputs per block of :meth:`_Compiled.step`: the C writes each step's results into the next row.
_BLOCK_ROWS = 256
_OUT = {name: i for i, name in enumerate(OUTPUT_NAMES)}


def _not_a_number(inputs, dt):
    for name, value in (*((n, getattr(inputs, n)) for n in _ROW), ("dt", dt)):
        if value is None and name == "p":
            continue
        try:
            float(value)
        except (TypeError, ValueError):
            return ModelInputError(f"input {name!r} must be a real number, got {value!r}")
    return ModelInputError(f"inputs must be real numbers: {inputs!r}, dt = {dt!r}")


class Outputs(Mapping):
    """The outputs of one step by name (:data:`swift.ring.OUTPUT_NAMES`, floats): a read-only view of row ``row``
    of ``block`` (no copy; the compiled step never overwrites a row it has returned). ``array``: the row."""

    __slots__ = ("_block", "_row")

    def __init__(self, block, row=0):
        self._block, self._row = block, row

    @property
    def array(self) -> np.ndarray:
        """The outputs as an array in the order of OUTPUT_NAMES (a view: do not modify)."""
        return self._block[self._row]

    def __getitem__(self, name):
        return self._block.item(self._row, _OUT[name])

    def __iter__(self):
        return iter(OUTPUT_NAMES)

    def __len__(self):
        return len(OUTPUT_NAMES)

    def values(self):
        """The values in the order of OUTPUT_NAMES (a list of floats)."""
        return self._block[self._row].tolist()

    def __repr__(self):
        return f"Outputs({dict(zip(OUTPUT_NAMES, self.values()))})"


class _Compiled:
    """The compiled step and loop (:data:`_DRIVER`) of one tyre, called through ctypes. The cam grid and table are
    passed by pointer. Every call works on buffers of its own (:class:`_StepBuffers`, taken from the pool ``free``
    and put back: threads stepping one tyre at once each take their own, and the C releases the GIL); the
    right-hand side (:meth:`rhs`, statics only) is serialised by ``lock``."""

    def __init__(self, tyre, key):
        self._lib = ctypes.CDLL(str(_library(tyre, key)))
        ll = ctypes.c_longlong
        sz = [ll() for _ in range(4)]
        work = self._lib.swift_step_work
        work.argtypes = [ctypes.POINTER(ll)] * 4
        work(*(ctypes.byref(v) for v in sz))
        self.work_sizes = tuple(v.value for v in sz)
        self._tyre, self.lock = tyre, threading.Lock()
        self._used = np.array(_used(tyre))
        stiff, damp = pressure_coefficients(tyre.model.params)  # (f_d = 1/sqrt(f_c) is positive where f_c is)
        self._cfg = np.array([tyre.table.x0, tyre.table.dx, tyre.table.h.size, tyre._reach, tyre._max_call,
                              tyre.model.params.NOMPRES, stiff, 0.0 if damp is None else damp])
        self._fn = self._lib.swift_run  # called with one ctypes array of 13 pointers (no argtypes: no conversion)
        self.step1 = self._lib.swift_step1  # one step: inputs, dt, 1, source and target rows in io
        self.pack = struct.Struct(f"{_NI + 4}d").pack_into
        self.free = [_StepBuffers(self)]
        self._rhs = GeneratedFunction(self._lib, tyre._structure.rhs, by_address=(3, 4))

    def rhs(self, state, u, x0w, i0):
        """The right-hand side (:attr:`SwiftTyre.rhs_function`, the exact model: h = 0) on the cam window that
        starts at sample ``i0`` (x = ``x0w``): (dx, out)."""
        with self.lock:
            return self._rhs(state, u, x0w, self._tyre._grid.ctypes.data, self._tyre._h.ctypes.data + 16 * i0, 0.0,
                             self._tyre.theta)

    def pointers(self, x, rows, scal, xs, ys, work):  # the driver's argument array (addresses of the buffers)
        t = self._tyre
        return (ctypes.c_void_p * 13)(x, rows, scal, self._cfg.ctypes.data, t._grid.ctypes.data, t._h.ctypes.data,
                                      xs, ys, *(ctypes.addressof(v) for v in work), t.theta.ctypes.data)

    def work(self):
        """Fresh work arrays of the generated step (arg, res, iw, w)."""
        sz_arg, sz_res, sz_iw, sz_w = self.work_sizes
        return ((ctypes.c_void_p * max(sz_arg, 7))(), (ctypes.c_void_p * max(sz_res, 2))(),
                (ctypes.c_longlong * max(sz_iw, 1))(), (ctypes.c_double * max(sz_w, 1))())

    def check(self, code, xb, rows, dt):
        """Raise the error the driver's return ``code`` stands for (``xb``: the belt's x at the failed step)."""
        if code > 0:
            raise self._tyre._outside_table(xb)
        if code == -1:
            raise ModelInputError(f"the step dt must be finite and >= 0 and the travel |vx| dt finite; got dt = {dt!r}"
                                  + (f", vx = {rows[0][0]!r}" if len(rows) else ""))
        if code == -3:
            raise self._bad_input(rows, dt)
        if code:
            raise ArithmeticError("compiled SWIFT step reported an evaluation error")

    def _bad_input(self, rows, dt):
        rows = np.asarray(rows, dtype=float).reshape(-1, _NI)
        bad = ~np.isfinite(rows) & self._used
        if bad.any():
            k, i = np.argwhere(bad)[0]
            return ModelInputError(f"input {_ROW[i]!r} must be finite, got {float(rows[k, i])!r}"
                                   + (f" (step {k}, t = {k * dt:g} s)" if len(rows) > 1 else ""))
        for k, p in enumerate(rows[:, INPUT_NAMES.index("p")]):
            where = f" (step {k}, t = {k * dt:g} s)" if len(rows) > 1 else ""
            if not p > 0:
                return ModelInputError(f"input 'p' (inflation pressure) must be positive [Pa], got {float(p)!r}{where}")
            try:
                check_pressure(self._tyre.model.params, float(p))
            except ModelInputError as error:
                return ModelInputError(f"{error}{where}")
        return ModelInputError("compiled SWIFT step refused its inputs")

    def run(self, state, rows, dt):
        """``len(rows)`` steps from ``state``: (states, outputs) after each step."""
        n = len(rows)
        x, rows = np.array(state, dtype=float), np.ascontiguousarray(rows, dtype=float)
        xs, ys, scal = np.empty((n, len(STATE_NAMES))), np.empty((n, len(OUTPUT_NAMES))), np.array([dt, n])
        work = self.work()  # its own work arrays (referenced until the call returns)
        code = self._fn(self.pointers(*(a.ctypes.data for a in (x, rows, scal, xs, ys)), work))
        if code:
            self.check(code, (xs[code - 2] if code > 1 else x)[_S["xb"]], rows, dt)
        return xs, ys


class _StepBuffers:
    """One caller's buffers for :meth:`SwiftTyre.step`: ``x`` (the state copied in unless it is ``last``, the state
    returned last, read in place in its block row), ``io`` (inputs, dt, 1, source and target rows), the generated
    step's work arrays, and the blocks ``xs``, ``ys`` into whose row ``row`` the C writes the new state and outputs;
    they are returned as views (a row is never written twice: earlier results stay valid). ``args``: the pointers,
    bound once."""

    __slots__ = ("x", "io", "args", "xs", "ys", "row", "last", "_work")

    def __init__(self, compiled):
        self.x, self.io, self._work = np.zeros(len(STATE_NAMES)), (ctypes.c_double * (_NI + 4))(), compiled.work()
        self.args = compiled.pointers(self.x.ctypes.data, ctypes.addressof(self.io), 0, 0, 0, self._work)
        self.new_block()

    def new_block(self):
        """Fresh blocks for the states and outputs of the next steps (the old ones live on in the views)."""
        self.xs, self.ys = np.empty((_BLOCK_ROWS, len(STATE_NAMES))), np.empty((_BLOCK_ROWS, len(OUTPUT_NAMES)))
        self.args[6], self.args[7] = self.xs.ctypes.data, self.ys.ctypes.data
        self.row, self.last = 0, None


class GeneratedFunction:
    """A function of a CasADi-generated library called through ctypes, with buffers of its own (the caller
    serialises the calls): ``f(*args)`` with every argument in order, those at ``by_address`` (the cam grid and
    window) given as arrays or addresses and passed by pointer, the others copied in; returns every output (a
    matrix in its shape)."""

    def __init__(self, lib, function, by_address):
        self._fn = getattr(lib, function.name())
        self._fn.argtypes = [ctypes.c_void_p] * 4 + [ctypes.c_int]
        self._fn.restype = ctypes.c_int
        n_in, n_out = function.n_in(), function.n_out()
        self._by_address = tuple(i % n_in for i in by_address)
        self._in = [np.zeros(function.nnz_in(i)) for i in range(n_in)]
        self._out = [np.zeros(function.nnz_out(i)) for i in range(n_out)]
        self._shapes = [function.size_out(i) for i in range(n_out)]
        self._arg = (ctypes.c_void_p * max(function.sz_arg(), n_in))(*[a.ctypes.data for a in self._in])
        self._res = (ctypes.c_void_p * max(function.sz_res(), n_out))(*[r.ctypes.data for r in self._out])
        self._iw = (ctypes.c_longlong * max(function.sz_iw(), 1))()
        self._w = (ctypes.c_double * max(function.sz_w(), 1))()

    def __call__(self, *args):
        for i, value in enumerate(args):
            if i in self._by_address:
                self._arg[i] = value if isinstance(value, int) else value.ctypes.data
            else:
                self._in[i][:] = value
        if self._fn(self._arg, self._res, self._iw, self._w, 0):
            raise ArithmeticError(f"compiled SWIFT function {self._fn.__name__} reported an evaluation error")
        return [r.reshape(shape, order="F").copy() if shape[1] > 1 else r.copy()
                for r, shape in zip(self._out, self._shapes)]
