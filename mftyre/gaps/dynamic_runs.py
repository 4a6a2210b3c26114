"""Dynamic tyre tests for the gap finder: runs (inputs and measured outputs over time), their CSV layout, the SWIFT
wheel driven by exactly those inputs, and a generator of synthetic runs as messy as a rig's.

A run (:class:`DynamicRun`) is one drive over a road at one condition, sampled at a fixed rate:

========== ====== =================================================================================================
column     unit   meaning
========== ====== =================================================================================================
RUN        -      run name (one file with several runs; in a folder of CSV files each file is a run, named by stem)
TIME       s      sample time, equally spaced within a run
X          m      axle position along the road (optional: integrated from VX, starting at 0)
VX         m/s    forward speed of the axle
Z          m      axle height above the road's zero (axle height imposed) - or -
LOAD       N      downward force on the axle (axle load imposed)
OMEGA      rad/s  rim spin (imposed; forward rolling > 0) - or - TORQUE [N m] drive/brake torque on the rim
PSI        rad    yaw (heading of the wheel relative to the x axis; a steer step); optional, default 0
P          Pa     inflation pressure; optional, default the .tir's NOMPRES
ROAD       -      the road, the same in every row of a run: ``cleat(x0=1.5, length=0.02, height=0.01)``, a sum of
                  such obstacles or a CSV profile (:func:`swift.road.parse_road`); empty = flat
FX FY FZ   N      measured forces of the tyre on the axle (ISO-W; Fz > 0 pressing the tyre on the road: the
MZ         N m    model's ``fz`` output), self-aligning moment; any subset, at least one. SPIN [rad/s]: measured
                  rim spin (torque mode)
========== ====== =================================================================================================

Units SI, axes ISO-W unless ``--units``/``--axes`` say otherwise. :func:`read_runs` reads one CSV (with RUN) or a
folder of CSVs through the one reader of data files (:func:`mftyre.data.read_time_histories`); :func:`write_runs`
writes one;
:func:`simulate` drives the SWIFT wheel (:class:`swift.SwiftTyre`, compiled) with the runs' inputs and returns the
model's outputs at the runs' sample times; :func:`synthetic_runs` builds cleat and step-steer programmes from a
model with measurement noise, a causal anti-alias filter and a time offset.
"""
from __future__ import annotations

import functools
import math
import threading
import warnings
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import DataError, ModelInputError

__all__ = ["DynamicRun", "SwiftTyres", "RelaxedWheels", "read_runs", "write_runs", "runs_frame", "simulate", "simulate_relaxed",
           "synthetic_runs", "OUTPUT_CHANNELS", "MODEL_OUTPUT", "RELAXED_OUTPUT", "MODEL_KINDS", "RUN_LEVELS",
           "run_levels"]

#: Measured channels the dynamic gap finder compares, and the SWIFT output each one is.
MODEL_OUTPUT = {"FX": "fx", "FY": "fy", "FZ": "fz", "MZ": "mz", "SPIN": "omb"}
#: ... and the relaxed wheel's (:mod:`mftyre.transient`, the wheel-centre loads); it has no belt spin.
RELAXED_OUTPUT = {"FX": "Fx", "FY": "Fy", "FZ": "Fz", "MZ": "Mz"}
#: The dynamic models: the SWIFT wheel (rigid ring, tandem cams; any run) and the relaxed wheel (the MF behind
#: first-order relaxation of the contact deflections, :mod:`mftyre.transient`; flat-road runs with the rim speed
#: imposed).
MODEL_KINDS = ("swift", "relaxed")
OUTPUT_CHANNELS = tuple(MODEL_OUTPUT)
_INPUTS = ("TIME", "X", "VX", "Z", "LOAD", "OMEGA", "TORQUE", "PSI", "P")


@dataclass
class DynamicRun:
    """One run: ``name``, ``t`` (s, equally spaced), ``inputs`` (column -> array: VX, X, Z or LOAD, OMEGA or TORQUE,
    PSI, P), ``road`` (text, :func:`swift.road.parse_road`), ``measured`` (channel -> array)."""

    name: str
    t: np.ndarray
    inputs: dict
    road: str
    measured: dict
    source: str = ""
    meta: dict = field(default_factory=dict)

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    @property
    def axle(self) -> str:
        return "height" if "Z" in self.inputs else "load"

    @property
    def rim(self) -> str:
        return "speed" if "OMEGA" in self.inputs else "torque"

    @property
    def kind(self) -> str:
        """``cleat`` (an obstacle on the road), ``steer`` (a yaw change on a flat road), ``brake`` (a change of
        the rim's slip on a flat road: the ratio OMEGA/VX changes by more than 0.1 %, or TORQUE by more than
        1 N m) or ``flat``."""
        if self.road.strip() not in ("", "flat()", "flat(0)"):
            return "cleat"
        psi = self.inputs.get("PSI")
        if psi is not None and np.ptp(psi) > 1e-4:
            return "steer"
        if "OMEGA" in self.inputs:
            ratio = self.inputs["OMEGA"] / np.maximum(np.abs(self.inputs["VX"]), 1e-3)
            if np.ptp(ratio) > 1e-3 * max(np.max(np.abs(ratio)), 1e-12):
                return "brake"
        elif np.ptp(self.inputs["TORQUE"]) > 1.0:
            return "brake"
        return "flat"

    @property
    def condition(self) -> dict:
        """Speed [km/h], load [N] (LOAD, or the measured Fz before the event), pressure [bar], as engineers name a
        test condition."""
        fz = self.inputs["LOAD"] if "LOAD" in self.inputs else self.measured.get("FZ")
        n0 = max(3, int(0.1 * self.t.size))
        load = float(np.median(fz[:n0])) if fz is not None else math.nan
        p = self.inputs.get("P")
        return dict(speed=round(float(np.mean(self.inputs["VX"])) * 3.6, 1), load=round(load, -1),
                    pressure=round(float(np.mean(p)) / 1e5, 2) if p is not None else math.nan)

    def label(self) -> str:
        c = self.condition
        return f"{self.name} ({self.kind}, {c['speed']:g} km/h, {c['load']:.0f} N, {c['pressure']:g} bar)"


#: Level steps of the run conditions (absolute, relative to the largest): speed [km/h], load [N], pressure [bar].
#: Values closer than this are one level: a load read from the measured FZ moves with the noise and the load cell's
#: gain (distinct values counted as levels found eight loads in runs at one, and let a load slope be refitted).
RUN_LEVELS = {"speed": (1.0, 0.03), "load": (0.0, 0.05), "pressure": (0.0, 0.03)}


def run_levels(runs, key: str) -> np.ndarray:
    """Level index of each run's condition ``key`` (:data:`RUN_LEVELS`; grouped by the steady finder's rule,
    :func:`mftyre.gaps.residuals.condition_levels`; a missing value counts as 0)."""
    from .residuals import condition_levels

    return condition_levels(np.nan_to_num([r.condition[key] for r in runs]), *RUN_LEVELS[key])


#: The lowest sample rate [Hz] a run may have: the belt's in-plane modes (30-100 Hz) and an anti-alias filter below
#: Nyquist need it.
MIN_RATE = 200.0


def _check_run(run: DynamicRun, line: int | None = None) -> None:
    where = f"run {run.name!r}" + (f" in {run.source}" if run.source else "") + (
        f" (from line {line})" if line is not None else "")
    t = np.asarray(run.t, float)
    if t.size < 20:
        raise DataError(f"{where}: {t.size} samples; a dynamic run needs at least 20")
    d = np.diff(t)
    if not (np.all(np.isfinite(t)) and d.min() > 0 and np.ptp(d) < 1e-3 * d.mean()):
        raise DataError(f"{where}: TIME must increase in equal steps (found steps {d.min():.3g} to {d.max():.3g} s)")
    if 1.0 / d.mean() < MIN_RATE * (1 - 1e-6):
        raise DataError(f"{where}: sampled at {1.0 / d.mean():.4g} Hz; dynamic runs need at least {MIN_RATE:g} Hz "
                        f"(a TIME step of at most {1e3 / MIN_RATE:g} ms; TIME in ms? give --units TIME=ms)")
    if "VX" not in run.inputs:
        raise DataError(f"{where}: column VX (forward speed, m/s) is missing")
    if ("Z" in run.inputs) == ("LOAD" in run.inputs):
        raise DataError(f"{where}: give exactly one of Z (axle height, m) and LOAD (axle load, N)")
    if ("OMEGA" in run.inputs) == ("TORQUE" in run.inputs):
        raise DataError(f"{where}: give exactly one of OMEGA (rim spin, rad/s) and TORQUE (rim torque, N m)")
    for k, v in run.inputs.items():
        if not np.all(np.isfinite(v)):
            raise DataError(f"{where}: column {k} has missing or non-finite values (first at TIME = "
                            f"{t[np.flatnonzero(~np.isfinite(v))[0]]:.4g} s)")
    if "LOAD" in run.inputs and not np.all(run.inputs["LOAD"] > 0):
        raise DataError(f"{where}: LOAD is the downward force on the axle, positive; found {run.inputs['LOAD'].min():.4g}")
    if "P" in run.inputs and not np.all(run.inputs["P"] > 1e4):
        raise DataError(f"{where}: P is the inflation pressure in Pa (e.g. 220000); found {run.inputs['P'].min():.4g}")
    if not run.measured:
        raise DataError(f"{where}: no measured output; give at least one of {', '.join(OUTPUT_CHANNELS)}")
    for k, v in run.measured.items():
        if np.mean(np.isfinite(v)) < 0.9:
            raise DataError(f"{where}: channel {k} is missing in more than 10 % of the samples")


def runs_from_frame(frame: pd.DataFrame, source: str = "", name: str | None = None) -> list:
    """Runs from a table in the documented layout, its channels in SI and ISO-W (:func:`mftyre.data.read_time_histories`;
    index = line - 2: errors name the line), a RUN column, or one run named ``name``."""
    where = source or "data"
    if "RUN" not in frame:
        if name is None:
            raise DataError(f"{where}: column RUN is missing (one file holding several runs needs it)")
        frame = frame.assign(RUN=name)
    empty = frame["RUN"].isna() | (frame["RUN"].astype(str).str.strip() == "")
    if empty.any():
        raise DataError(f"{where}: line {int(frame.index[np.flatnonzero(empty.to_numpy())[0]]) + 2}: column RUN is "
                        f"empty ({int(empty.sum())} rows): every row names its run")
    runs = []
    for run_name, grp in frame.groupby(frame["RUN"].astype(str).str.strip(), sort=False):
        road = grp["ROAD"].astype(object).fillna("").astype(str).str.strip().unique() if "ROAD" in grp else \
            np.array([""])
        if road.size != 1:
            raise DataError(f"{where}: run {run_name!r} has {road.size} different ROAD values; a run is one road")
        # a column empty throughout a run is absent from it (a file mixing cleat runs and steer runs)
        inputs = {c: grp[c].to_numpy(float) for c in _INPUTS[1:] if c in grp and grp[c].notna().any()}
        t = grp["TIME"].to_numpy(float)
        if "X" not in inputs and "VX" in inputs:
            inputs["X"] = np.concatenate([[0.0], np.cumsum(0.5 * (inputs["VX"][1:] + inputs["VX"][:-1]) * np.diff(t))])
        measured = {c: grp[c].to_numpy(float) for c in OUTPUT_CHANNELS if c in grp and grp[c].notna().any()}
        run = DynamicRun(str(run_name), t, inputs, str(road[0]), measured, source=source)
        _check_run(run, line=int(grp.index[0]) + 2)
        runs.append(run)
    return runs


def read_runs(path, *, columns: dict | None = None, units: dict | None = None, axes: str | None = None,
              check: bool = True, drop=()) -> list:
    """Runs from one CSV file (with a RUN column) or a folder of CSV files (one run each, named by the file), read
    by the one reader of data files (:func:`mftyre.data.read_time_histories`: ``columns`` file column -> channel,
    ``units`` channel -> unit, ``axes`` the file's axis system, ``check`` plausibility); ``drop``: measured
    channels (:data:`OUTPUT_CHANNELS`) to leave out, e.g. a dead load cell (the inputs drive the model: none of
    them can be left out)."""
    from ..data import read_time_histories

    inputs = [c for c in drop if c not in OUTPUT_CHANNELS]
    if inputs:
        raise DataError(f"{path}: cannot drop {', '.join(inputs)}: only measured outputs "
                        f"({', '.join(OUTPUT_CHANNELS)}) can be left out of dynamic runs; the inputs drive the model")
    options = dict(columns=columns, units=units, axes=axes or "ISO-W", check=check)

    def frame(f):
        table = read_time_histories(f, **options)[0]
        return table.drop(columns=[c for c in drop if c in table.columns])

    path = Path(path)
    if path.is_dir():
        files = sorted(f for f in path.glob("*.csv") if not f.name.startswith("."))
        if not files:
            raise DataError(f"{path}: no .csv files in the folder")
        return [r for f in files for r in runs_from_frame(frame(f), str(f), f.stem)]
    return runs_from_frame(frame(path), str(path))


def runs_frame(runs) -> pd.DataFrame:
    """The runs as one table in the documented layout."""
    parts = []
    for r in runs:
        d = {"RUN": r.name, "TIME": r.t, **r.inputs, "ROAD": r.road, **r.measured}
        parts.append(pd.DataFrame(d))
    return pd.concat(parts, ignore_index=True)


def write_runs(runs, path, *, overwrite: bool = False) -> Path:
    """Write ``runs`` to one CSV file (RUN column); an existing file needs ``overwrite``."""
    from ..files import write_atomically

    path = Path(path)
    if path.exists() and not overwrite:
        raise DataError(f"{path} exists: pass overwrite=True to replace it")
    return write_atomically(path, runs_frame(runs).to_csv(index=False, float_format="%.7g"))


# ---------------------------------------------------------------------------------------------------- the model
def road_layout(runs) -> dict:
    """(road, axle mode, rim mode) -> the x range (m) its SWIFT tyre's road table must cover: the runs on that
    road, 1 m either side. Plain data: a worker given it builds the tyres :class:`SwiftTyres` builds here."""
    layout = {}
    for r in runs:
        key = (r.road, r.axle, r.rim)
        lo, hi = layout.get(key, (math.inf, -math.inf))
        x = r.inputs["X"]
        layout[key] = (min(lo, float(x.min()) - 1.0), max(hi, float(x.max()) + 1.0))
    return layout


class SwiftTyres:
    """SWIFT tyres of one model, one per (road, axle mode, rim mode) of :func:`road_layout` (of ``runs``, or
    ``layout`` as given): built once, reused by every run on that road; the tyres of one mode share their equations
    (:meth:`swift.SwiftTyre.share_equations`), their static equilibrium the structure's (``equilibrium="structure"``:
    one graph for every parameter set). ``tables``: the cam-height tables kept across models (a dict, or anything with
    its ``get`` and item assignment; (road, range, cams) -> :class:`swift.enveloping.CamTable`): a model with the same
    cams over a flat-track road reuses them."""

    def __init__(self, model, runs=(), tables: dict | None = None, *, layout: dict | None = None):
        from swift import SwiftTyre
        from swift.enveloping import Cams
        from swift.road import parse_road

        self.tyres = {}
        tables = {} if tables is None else tables
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the .tir's unmodelled parameters: said once by the caller
            cams, modes = Cams.from_params(model.params, warn=False), {}
            for key, xr in (road_layout(runs) if layout is None else layout).items():
                try:
                    road = parse_road(key[0])
                    flat_track = not road.varies_with_y  # its table depends on the cams alone
                    tkey = (key[0], xr, cams)
                    tyre = SwiftTyre(model, tables.get(tkey, road) if flat_track else road, axle=key[1],
                                     rim=key[2], x_range=xr, equilibrium="structure")
                except ModelInputError as exc:
                    raise ModelInputError(f"road {key[0]!r}: {exc}") from None
                if flat_track:
                    tables[tkey] = tyre.table
                if key[1:] in modes:
                    tyre.share_equations(modes[key[1:]])
                modes.setdefault(key[1:], tyre)
                self.tyres[key] = (tyre, xr)

    def tyre(self, run):
        return self.tyres[(run.road, run.axle, run.rim)][0]


def _step_inputs(run: DynamicRun, p_nominal: float):
    """The run's inputs per sample as the SWIFT wheel's :class:`swift.StepSeries` (the axle's vertical speed from
    its height by central differences; the pressure ``p_nominal`` where the run has none)."""
    from swift import StepSeries

    i = run.inputs
    z = i.get("Z")
    cols = dict(x=i["X"], vx=i["VX"], z=z, vz=np.gradient(z, run.t) if z is not None else None, load=i.get("LOAD"),
                omega=i.get("OMEGA"), torque=i.get("TORQUE"), psi=i.get("PSI"), p=i.get("P"))
    cols = {k: v for k, v in cols.items() if v is not None}
    if "p" not in cols:
        cols["p"] = np.full(run.t.size, float(p_nominal))
    return StepSeries(**cols)


def simulate(model, runs, tyres: SwiftTyres | RelaxedWheels | None = None, *, model_kind: str = "swift") -> dict:
    """The SWIFT wheel (or with ``model_kind="relaxed"`` the relaxed wheel, :func:`simulate_relaxed`) driven by
    each run's inputs: run name -> channel -> model output at the run's sample times (the channels the run
    measured). ``model``: an :class:`mftyre.MFModel` with [STRUCTURAL] and [CONTACT_PATCH] sections; ``tyres``: its
    :class:`SwiftTyres`, or for the relaxed wheel the :class:`RelaxedWheels` to build through (default: the model's
    own). Raises :class:`ModelInputError` when the model cannot be built or a run leaves the road table."""
    if model_kind == "relaxed":
        return simulate_relaxed(model, runs, tyres)
    if model_kind != "swift":
        raise ModelInputError(f"model kind must be one of {', '.join(MODEL_KINDS)}; got {model_kind!r}")
    tyres = tyres or SwiftTyres(model, runs)
    out = {}
    for r in runs:
        tyre = tyres.tyre(r)
        res = tyre.run(r.t[-1] - r.t[0], _step_inputs(r, model.params.NOMPRES), dt=r.dt)
        n = r.t.size
        out[r.name] = {c: np.asarray(res[MODEL_OUTPUT[c]][:n], float) for c in r.measured}
    return out


def relaxed_inputs(run: DynamicRun, names, p_nominal: float) -> np.ndarray:
    """The relaxed wheel's input vectors (rows: ``names``, :func:`mftyre.transient.input_table`) for every sample
    of ``run``: the axle's road velocity (VX along x) in the wheel's axes turned by the yaw PSI (vx = VX cos PSI,
    vy = -VX sin PSI), the rim spin, the axle height over a flat road (or the load), the pressure."""
    i, n = run.inputs, run.t.size
    psi = i.get("PSI", np.zeros(n))
    cols = dict(vx=i["VX"] * np.cos(psi), vy=-i["VX"] * np.sin(psi), omega=i["OMEGA"], gamma=np.zeros(n),
                road_camber=np.zeros(n), p=i.get("P", np.full(n, p_nominal)), mu_scale=np.ones(n), road_z=np.zeros(n))
    if "Z" in i:
        cols["z"] = i["Z"]
    else:
        cols["Fz_in"] = i["LOAD"]
    return np.array([cols[k] for k in names], dtype=float)


class RelaxedWheels:
    """The relaxed wheel's functions (:func:`mftyre.transient.wheel_functions`, kind "transient") for models near
    ``reference``: the parameters in which a model differs from the reference are run-time parameters (entries of
    q), the others numbers in the graph, so the models of one refit (which move the same few parameters) share one
    graph per vertical mode and structure (:func:`mftyre.model.structure_of`): one build, not one per trial (the
    build took about two thirds of a relaxed search's simulation time). Not every parameter at run time: the
    graph's constants unfolded, it evaluated ten times slower. A parameter at 0 in the model or the reference stays a
    number (it switches a form on or off). The ``kept`` most recent graphs are kept; thread-safe."""

    def __init__(self, reference, kept: int = 8):
        from ..model import run_time_parameter_names

        self.reference = reference
        self._runtime = set(run_time_parameter_names(reference.params))
        self._built = _Recent(kept)

    def functions(self, model, vertical: str):
        """The functions for ``model`` with the ``vertical`` input mode ("position" or "load")."""
        import json

        from ..model import run_time_parameter_names, structure_of
        from ..transient import wheel_functions

        ref = self.reference.params
        names = tuple(n for n in run_time_parameter_names(model.params) if n in self._runtime
                      and model.params[n] != ref[n])
        key = json.dumps([structure_of(model, names), vertical], sort_keys=True)
        found = self._built.get(key)
        if found is None:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the file's unmodelled parameters: said once by the caller
                found = self._built[key] = wheel_functions(model, "transient", vertical, run_time=names)
        return found

    @staticmethod
    def parameters(functions, model) -> np.ndarray:
        """The q of ``model`` for its ``functions``: the low-speed damping time of the model
        (:func:`mftyre.transient.default_tau_vlow`), then its values of the run-time parameters."""
        from ..transient import default_tau_vlow

        return np.array([default_tau_vlow(model), *(model.params[n] for n in functions.run_time)], dtype=float)


def simulate_relaxed(model, runs, wheels: RelaxedWheels | None = None) -> dict:
    """The relaxed wheel (:func:`mftyre.transient.wheel_functions`, kind "transient": the same state functions as
    its FMU) driven by each run's inputs, started in its steady state at the first sample, inputs held over each
    step: run name -> channel -> output (:data:`RELAXED_OUTPUT`) at the run's sample times. Flat-road runs with
    the rim speed imposed only (it has no road enveloping and no rim dynamics): else :class:`ModelInputError`.
    ``wheels``: the functions of models near one reference, shared (:class:`RelaxedWheels`; default: this model's
    own, its values in the graph). CasADi is called under :data:`mftyre.compiled.CASADI_LOCK` (thread-safe)."""
    import casadi as ca

    from ..compiled import CASADI_LOCK

    bad = [r.name for r in runs if r.kind == "cleat" or "OMEGA" not in r.inputs]
    if bad:
        raise ModelInputError(f"the relaxed wheel runs on a flat road with the rim speed (OMEGA) imposed; run(s) "
                              f"{', '.join(bad[:3])} have an obstacle or a rim torque: use the SWIFT model")
    for r in runs:
        missing = [c for c in r.measured if c not in RELAXED_OUTPUT]
        if missing:
            raise ModelInputError(f"run {r.name!r}: the relaxed wheel has no output for {', '.join(missing)} (it has "
                                  f"{', '.join(RELAXED_OUTPUT)})")
    wheels = wheels or RelaxedWheels(model)
    out = {}
    with CASADI_LOCK:
        for r in runs:
            f = wheels.functions(model, "position" if "Z" in r.inputs else "load")
            u = relaxed_inputs(r, f.input_names, model.params.NOMPRES)
            n = r.t.size
            q = wheels.parameters(f, model)
            x0 = f.init(u[:, 0], q)
            xs = f.step.mapaccum(n - 1)(x0, u[:, :-1], ca.repmat(q, 1, n - 1), r.dt)  # the state after each step
            ys = np.asarray(f.out.map(n)(ca.horzcat(x0, xs), u, ca.repmat(q, 1, n)))
            names = list(f.output_names)
            out[r.name] = {c: ys[names.index(RELAXED_OUTPUT[c])].copy() for c in r.measured}
    return out


# ------------------------------------------------------------------------------- simulation tasks (mftyre.runner)
def run_data(run: DynamicRun) -> dict:
    """A run as the plain data of a task (:mod:`mftyre.runner`): what :func:`simulate_task` rebuilds it from."""
    return dict(name=run.name, t=run.t, inputs=dict(run.inputs), road=run.road, measured=dict(run.measured))


class _Recent:
    """The ``kept`` most recently used entries of a cache (``get``, ``[key] = value``): a read marks an entry used, a
    write beyond ``kept`` drops the least recently used. Thread-safe."""

    def __init__(self, kept: int):
        self.kept, self._entries, self._lock = kept, OrderedDict(), threading.Lock()

    def get(self, key, default=None):
        with self._lock:
            if key in self._entries:
                self._entries.move_to_end(key)
                return self._entries[key]
        return default

    def __setitem__(self, key, value):
        with self._lock:
            self._entries[key] = value
            self._entries.move_to_end(key)
            while len(self._entries) > self.kept:
                self._entries.popitem(last=False)


#: Per process: (the .tir text's SHA-256, side, model kind, road layout) -> (model, SwiftTyres) of the last few
#: models, and the cam tables (as :class:`SwiftTyres` reads and writes them) of the process's tasks.
_TASK_TYRES = _Recent(6)
_TASK_TABLES = _Recent(64)


def simulate_task(tir: str, side: str, model_kind: str, layout: list, runs: list) -> dict:
    """Runs of one model simulated where a task lands (a worker of :mod:`mftyre.runner`): the model built from its
    .tir text (``tir``, written by :func:`mftyre.tir.tir_text`: every value with all its digits) on ``side``, its
    SWIFT tyres from ``layout`` (:func:`road_layout` of every run of the search, as ``[road, axle, rim, x_lo,
    x_hi]`` rows: the same tyres as in the process that sent it, so the same outputs bit for bit) and kept for the
    model's next runs; ``runs``: :func:`run_data` of each. ``{"outputs": run name -> channel -> the history as
    :func:`mftyre.runner.pack` text}``,
    or ``{"error": the message}`` when the model cannot be built or simulated on a run (:class:`ModelInputError`)."""
    import hashlib

    from ..model import MFModel
    from ..runner import pack
    from ..tir import parse_tir

    todo = [DynamicRun(**r) for r in runs]
    key = (hashlib.sha256(tir.encode()).hexdigest(), side, model_kind, tuple(map(tuple, layout)))
    try:
        built = _TASK_TYRES.get(key)
        if built is None:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the file's unmodelled parameters: said once by the caller
                model = MFModel(parse_tir(tir, "<task>"), side=side)
                tyres = None if model_kind != "swift" else SwiftTyres(
                    model, tables=_TASK_TABLES, layout={(road, axle, rim): (lo, hi) for road, axle, rim, lo, hi
                                                           in layout})
            built = _TASK_TYRES[key] = (model, tyres)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = simulate(built[0], todo, built[1], model_kind=model_kind)
    except ModelInputError as exc:
        return {"error": str(exc)}
    return {"outputs": {name: {c: pack(v) for c, v in channels.items()} for name, channels in out.items()}}


# ---------------------------------------------------------------------------------------------------- synthetic
#: Measurement noise (standard deviation at the sensor, before the anti-alias filter) of the generator.
NOISE = {"FX": 20.0, "FY": 20.0, "FZ": 30.0, "MZ": 1.5, "SPIN": 0.05}


@functools.lru_cache(maxsize=256)
def _butterworth(order: int, cutoff: float, rate: float):
    """The Butterworth low-pass as second-order sections and its unit-step initial state (designed once per
    order, cutoff and sample rate: a gap search filters every channel of every run at each evaluation); shared: never
    written to (scipy's sosfilt reads the sections, and the caller scales the state into a new array)."""
    from scipy import signal as sps

    sos = sps.butter(order, cutoff, fs=rate, output="sos")
    return sos, sps.sosfilt_zi(sos)


def measurement_chain(signal: np.ndarray, dt: float, cutoff: float | None, delay: float, order: int = 4):
    """What a rig's acquisition does to a true signal: a causal Butterworth low-pass (anti-alias; ``cutoff`` Hz,
    None = none) started from rest at the first value, then a time delay (s, linear interpolation; the first value
    held before)."""
    from scipy import signal as sps

    y = np.asarray(signal, float)
    if cutoff and not cutoff < 0.5 / dt:
        raise ModelInputError(f"anti-alias cutoff {cutoff:g} Hz at or above the Nyquist frequency {0.5 / dt:g} Hz of "
                              f"data sampled at {1 / dt:g} Hz: a filter's cutoff lies below it")
    if cutoff:
        sos, zi_unit = _butterworth(order, float(cutoff), 1.0 / dt)
        zi = zi_unit * y[0]
        y = sps.sosfilt(sos, y, zi=zi)[0]
    if delay:
        k = np.arange(y.size) - delay / dt
        y = np.interp(k, np.arange(y.size), y)
    return y


def synthetic_runs(model, *, speeds=(20.0, 40.0, 60.0), pressures=None, loads=None, steer_speeds=(40.0,),
                   steer_angle=2.0, cleat=(0.02, 0.01), duration=0.8, dt=1e-3, lead=0.3, noise=NOISE,
                   cutoff: float | None = 150.0, delay: float = 5e-3, seed: int = 0, truth=None, brake_speeds=(),
                   brake_slip=-0.05, model_kind: str = "swift", order: int = 4, gain=None, drift=None,
                   ar: float = 0.0, roads=None) -> list:
    """Cleat runs (every speed [km/h] x pressure [Pa] x load [N]; axle height fixed at the static loaded radius,
    rim spin at the free-rolling speed), step-steer runs (yaw step of ``steer_angle`` deg at every steer speed,
    nominal pressure and first load) and braking steps (the rim's slip ramped from free rolling to ``brake_slip``
    in 20 ms at every brake speed, each load, nominal pressure) from ``truth`` (default ``model``) simulated as
    ``model_kind`` (:data:`MODEL_KINDS`) through :func:`measurement_chain` (noise at the sensor, a causal
    anti-alias filter at ``cutoff`` Hz, a ``delay`` of the outputs in s); the obstacle, the steer step or the
    braking step comes ``lead`` s after the start. The inputs are recorded exactly; the ROAD column names the
    cleat (``cleat`` = (length, height) m). A rig's further errors: ``order`` of the filter, ``gain`` (channel ->
    load-cell gain, e.g. 1.015), ``drift`` (channel -> offset drift per second since the run's start, the cell zeroed
    before it), ``ar`` the AR(1) coefficient of the sensor noise (its standard deviation stays ``noise``);
    ``roads``: obstacles instead of the cleat (texts of :func:`swift.road.parse_road` with ``{x0}`` for the position
    of the leading edge), each driven at every speed, pressure and load."""
    truth = truth or model
    prm = truth.params
    rng = np.random.default_rng(seed)
    pressures = tuple(pressures or (prm.NOMPRES,))
    loads = tuple(loads or (prm.FNOMIN,))
    n = int(round(duration / dt)) + 1
    t = dt * np.arange(n)
    runs = []

    def static(load, p, v):
        rl = float(np.squeeze(model.evaluate(load, 0.0, 0.0, 0.0, 0.0, v, p)["rl"]))  # loaded radius of the file
        re = float(np.squeeze(model.evaluate(load, 0.0, 0.0, 0.0, 0.0, v, p)["re"]))
        return rl, re

    def sensor_noise(c):
        e = rng.standard_normal(n)
        if ar:  # AR(1): e_k = ar e_(k-1) + sqrt(1 - ar^2) w_k, unit variance
            from scipy import signal as sps

            e = sps.lfilter([math.sqrt(1 - ar**2)], [1.0, -ar], e)
        return noise[c] * e

    def measure(name, inputs, road, channels):
        inputs = {k: np.asarray(v, float) for k, v in inputs.items()}
        run = DynamicRun(name, t.copy(), inputs, road, {c: np.zeros(n) for c in channels})
        true = simulate(truth, [run], model_kind=model_kind)[name]
        run.measured = {c: (gain or {}).get(c, 1.0) * measurement_chain(true[c] + sensor_noise(c), dt, cutoff, delay,
                                                                        order) + (drift or {}).get(c, 0.0) * t
                        for c in channels}
        run.meta = dict(delay=delay, cutoff=cutoff, order=order, gain=gain, drift=drift)
        return run

    obstacles = roads or ("cleat(x0={x0}, length=%g, height=%g)" % cleat,)
    for v_kmh in speeds:
        v = v_kmh / 3.6
        x0 = v * lead + 0.25  # the obstacle's leading edge: the tyre's front reaches it about lead s after the start
        for i, shape in enumerate(obstacles):
            road = shape.format(x0=f"{x0:.4f}")
            tag = "cleat" if roads is None else f"road{i}"
            for p in pressures:
                for load in loads:
                    rl, re = static(load, p, v)
                    inputs = dict(X=v * t, VX=np.full(n, v), Z=np.full(n, rl), OMEGA=np.full(n, v / re),
                                  P=np.full(n, p))
                    runs.append(measure(f"{tag}_{v_kmh:g}kmh_{p / 1e5:g}bar_{load:.0f}N", inputs, road,
                                        ("FX", "FZ")))
    for v_kmh in steer_speeds:
        v = v_kmh / 3.6
        rl, re = static(loads[0], prm.NOMPRES, v)
        psi = math.radians(steer_angle) * np.clip((t - lead) / 0.02, 0.0, 1.0)
        inputs = dict(X=v * t, VX=np.full(n, v), Z=np.full(n, rl), OMEGA=np.full(n, v / re), PSI=psi,
                      P=np.full(n, prm.NOMPRES))
        runs.append(measure(f"steer_{v_kmh:g}kmh_{steer_angle:g}deg", inputs, "", ("FY", "MZ", "FZ")))
    for v_kmh in brake_speeds:
        v = v_kmh / 3.6
        for load in loads:
            rl, re = static(load, prm.NOMPRES, v)
            slip = brake_slip * np.clip((t - lead) / 0.02, 0.0, 1.0)
            inputs = dict(X=v * t, VX=np.full(n, v), Z=np.full(n, rl), OMEGA=v * (1.0 + slip) / re,
                          P=np.full(n, prm.NOMPRES))
            runs.append(measure(f"brake_{v_kmh:g}kmh_{load:.0f}N_{100 * brake_slip:g}pct", inputs, "",
                                ("FX", "FZ")))
    return runs
