"""Staged least-squares fitting of Magic Formula parameters with lmfit (trust-region reflective,
``scipy.optimize.least_squares``), and the lower/upper-bound comparison of Schmeitz et al. (2005), Table 2.

Residuals: every residual evaluation runs the model once over the whole stage data (one vectorised
:meth:`mftyre.MFModel.evaluate` call), residual_i = w_i (model_i - measured_i) / s with s the RMS of the
measured channel over the stage data, so the cost is the squared normalised RMS error of
:func:`mftyre.fit.normalised_rms` for uniform weights; w_i = 1 (``weighting="uniform"``) or FNOMIN / Fz_i
(``"load"``: every load level counts alike). Shape conditions (:func:`mftyre.fit.stages.shape_violations`)
enter as penalty residuals, 10 sqrt(n) times the violation, at the corners of the data's load, pressure and
camber range. Model outputs that are not finite give the residual 10 (the step is rejected).
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import lmfit
import numpy as np
import pandas as pd

from ..data import TyreData, levels, read_csv, read_tydex
from ..errors import DataError
from ..model import MFModel
from ..params import TyreParameters
from ..tir import read_tir, write_tir
from .metrics import normalised_rms
from .stages import STAGE_NAMES, STAGES, Stage, conditions, shape_violations, stage_parameters, stage_rows
from .start import estimate_stage, start_parameters

__all__ = ["fit_tir", "FitResult", "StageResult", "load_data", "COMPARED_STAGES", "BOUNDS", "bounded_parameters"]

#: Bounds (min, max) of fitted parameters; parameters not listed are free.
BOUNDS: dict[str, tuple[float, float]] = {
    "PCX1": (0.3, 3.0), "PCY1": (0.3, 3.0), "QCZ1": (0.3, 3.0), "RCX1": (0.3, 3.0), "RCY1": (0.3, 3.0),
    "PDX1": (0.05, 5.0), "PDY1": (0.05, 5.0), "PKX1": (0.5, 300.0), "PKY1": (-300.0, -0.5), "PKY2": (0.1, 20.0),
    "PKY4": (0.5, 3.0), "PEX1": (-30.0, 1.0), "PEY1": (-30.0, 1.0), "QEZ1": (-30.0, 1.0), "REX1": (-30.0, 1.0),
    "REY1": (-30.0, 1.0), "QDZ1": (0.0, 1.0), "QBZ1": (0.3, 200.0), "QBZ9": (0.0, 200.0), "RBX1": (0.1, 300.0),
    "RBY1": (0.1, 300.0), "RVY4": (0.0, 500.0), "RVY5": (-3.0, 3.0), "RVY6": (0.0, 200.0), "RBX2": (-300.0, 300.0),
    "VERTICAL_STIFFNESS": (1.0e4, 1.0e7), "Q_FZ2": (0.0, 60.0), "Q_RE0": (0.8, 1.2), "BREFF": (0.0, 100.0),
    "DREFF": (0.0, 5.0), "FREFF": (-2.0, 2.0), "QSY1": (-0.1, 0.1), "QSY7": (0.0, 3.0), "PFZ1": (-5.0, 5.0),
    "QSX11": (0.0, 100.0),
}
#: The characteristics of the paper's Table 2 (pure Fx, pure Fy, pure Mz).
COMPARED_STAGES = ("pure_fx", "pure_fy", "mz")


@dataclass
class StageResult:
    """One fitted stage: its passes' lmfit results, the final values and standard errors, the fit error."""

    name: str
    title: str
    channel: str
    n_points: int
    fitted: list
    skipped: dict
    start: dict
    values: dict
    stderr: dict
    correlations: dict
    fit_error: float
    passes: list = field(default_factory=list)  # [(label, lmfit.MinimizerResult)]
    seconds: float = 0.0

    @property
    def result(self):
        """The lmfit result of the last pass (all parameters, all data of the stage)."""
        return self.passes[-1][1] if self.passes else None


class FitResult:
    """The outcome of :func:`fit_tir`: ``model``, ``params``, ``stages`` (name -> :class:`StageResult`),
    ``comparison`` (Table-2 DataFrame or None), ``data``, ``start``; ``report`` (Markdown),
    ``save_report(path)`` (Markdown and PNG plots), ``write_tir(path)``."""

    def __init__(self, params, data, start, stages, comparison, notes, seconds):
        self.params = params
        self.model = MFModel(params)
        self.data, self.start, self.stages = data, start, stages
        self.comparison, self.notes, self.seconds = comparison, notes, seconds

    @property
    def fit_errors(self) -> dict:
        """Stage name -> normalised RMS error [%] on the stage's data."""
        return {name: st.fit_error for name, st in self.stages.items()}

    @property
    def report(self) -> str:
        from .report import markdown_report

        return markdown_report(self, plot_names=None)

    def save_report(self, path) -> Path:
        from .report import save_report

        return save_report(self, path)

    def write_tir(self, path, *, overwrite: bool = False) -> Path:
        return write_tir(self.params, path, overwrite=overwrite)

    def __repr__(self):
        errs = ", ".join(f"{k} {v:.2f}%" for k, v in self.fit_errors.items())
        return f"FitResult({errs})"


def load_data(source) -> TyreData:
    """TyreData as is, or read from a ``.tdx`` / ``.csv`` path."""
    if isinstance(source, TyreData):
        return source
    path = Path(source)
    suffix = path.suffix.lower()
    if suffix in (".tdx", ".tydex"):
        return read_tydex(path)
    if suffix == ".csv":
        return read_csv(path)
    raise DataError(f"{path}: unknown data format {suffix!r}: expected .tdx (TYDEX) or .csv")


def _start(data: TyreData, start):
    if start is None:
        return start_parameters(data), True
    if isinstance(start, MFModel):
        return start.params, False
    if isinstance(start, TyreParameters):
        return start, False
    return read_tir(start), False


# ------------------------------------------------------------------------------------------ prediction
def _predict(stage: Stage, model: MFModel, data: TyreData, inputs: dict) -> np.ndarray:
    if stage.output == "fz_from_rl":
        def chan(name):
            return np.nan_to_num(data.array(name)) if name in data else 0.0
        return model.vertical_force(data.array("RL"), p=inputs["p"], omega=chan("OMEGA"), fx=chan("FX"),
                                    fy=chan("FY"), gamma=inputs["gamma"])
    omega = data.array("OMEGA") if stage.output == "re" and data.has("OMEGA") else None
    return model.evaluate(**inputs, omega=omega)[stage.output]


def _corners(data: TyreData, prm) -> dict:
    fz, p, g = data.array("FZ"), data.array("P"), data.array("IA")
    fz0 = prm.FNOMIN * prm.LFZO
    grid = np.array(np.meshgrid([fz.min(), fz.max()], [p.min(), p.max()], [g.min(), 0.0, g.max()])).reshape(3, -1)
    return dict(dfz=(grid[0] - fz0) / fz0, dpi=(grid[1] - prm.NOMPRES) / prm.NOMPRES, gamma=grid[2])


def bounded_parameters(prm, names) -> lmfit.Parameters:
    """lmfit parameters ``names`` started at their values in ``prm``, clipped into :data:`BOUNDS`."""
    params = lmfit.Parameters()
    for n in names:
        lo, hi = BOUNDS.get(n, (-np.inf, np.inf))
        params.add(n, value=min(max(float(prm[n]), lo), hi), min=lo, max=hi)
    return params


def _fit_pass(stage, prm, side, data, names, weighting, progress, label, max_nfev):
    """One least-squares pass over ``data`` varying ``names``; returns (new parameters, lmfit result)."""
    measured = data.array(stage.channel)
    inputs = data.inputs()
    scale = float(np.sqrt(np.mean(measured**2))) or 1.0
    weights = prm.FNOMIN / data.array("FZ") if weighting == "load" else np.ones(len(data))
    corners = _corners(data, prm)
    penalty = 10.0 * math.sqrt(len(data))
    params = bounded_parameters(prm, names)

    def residual(p):
        trial = prm.replace(**{n: p[n].value for n in names})
        pred = _predict(stage, MFModel(trial, side=side), data, inputs)
        r = weights * (pred - measured) / scale
        r = np.where(np.isfinite(r), r, 10.0)
        return np.concatenate([r, penalty * shape_violations(stage.name, trial, corners)])

    counter = {"n": 0, "t": time.perf_counter()}

    def iter_cb(p, it, resid, *a, **k):
        counter["n"] += 1
        if progress is not None and (counter["n"] % 25 == 0):
            progress(stage.name, label, counter["n"], float(np.sum(resid**2)))

    nfev = max_nfev or 60 * (len(names) + 1)
    minimizer = lmfit.Minimizer(residual, params, iter_cb=iter_cb)
    with warnings.catch_warnings():  # a singular covariance leaves the standard errors undefined (None/NaN)
        warnings.simplefilter("ignore", RuntimeWarning)
        result = minimizer.minimize(method="least_squares", max_nfev=nfev, x_scale="jac", ftol=1e-7, xtol=1e-7)
    new = prm.replace(**{n: float(result.params[n].value) for n in names})
    if progress is not None:
        progress(stage.name, label, counter["n"], float(result.chisqr))
    return new, result


def _fit_stage(stage, prm, side, data, fit_pressure, generic, weighting, progress, max_nfev):
    rows = stage_rows(stage, data)
    sub = data.select(rows)
    cond = conditions(sub)
    groups, skipped = stage_parameters(stage, cond, fit_pressure)
    names_all = groups["base"] + groups["pressure"] + groups["camber"]
    t0 = time.perf_counter()
    if len(sub) < max(len(names_all) + 1, 5) or not names_all:
        reason = "no data for this stage" if len(sub) == 0 else (
            f"{len(sub)} points, too few for {len(names_all)} parameters" if names_all else "no parameter to fit")
        skipped.update({n: reason for needs, names in stage.groups for n in names if n not in skipped})
        return prm, StageResult(stage.name, stage.title, stage.channel, len(sub), [], skipped, {}, {}, {}, {},
                                float("nan"))
    if generic:
        est = {k: v for k, v in estimate_stage(stage.name, prm, sub).items() if k in names_all}
        prm = prm.replace(**est)
    start = {n: float(prm[n]) for n in names_all}
    g, p = sub.array("IA"), sub.array("P")
    flat = np.abs(g) < math.radians(0.25)
    nominal = flat & (np.abs(p - prm.NOMPRES) <= 0.02 * prm.NOMPRES)
    passes = []
    plan = []
    if (groups["pressure"] or groups["camber"]) and nominal.sum() > len(groups["base"]) + 5 and not nominal.all():
        plan.append(("zero camber, nominal pressure", groups["base"], nominal))
    if groups["pressure"] and groups["camber"] and flat.sum() > len(groups["base"] + groups["pressure"]) + 5:
        plan.append(("zero camber, all pressures", groups["base"] + groups["pressure"], flat))
    plan.append(("all data", names_all, np.ones(len(sub), bool)))
    for label, names, mask in plan:
        part = sub if mask.all() else sub.select(mask)
        prm, res = _fit_pass(stage, prm, side, part, names, weighting, progress, label, max_nfev)
        passes.append((label, res))
    last = passes[-1][1]
    values = {n: float(last.params[n].value) for n in names_all}
    stderr = {n: (None if last.params[n].stderr is None or not np.isfinite(last.params[n].stderr)
                  else float(last.params[n].stderr)) for n in names_all}
    corr = {}
    for n in names_all:
        for m, c in (last.params[n].correl or {}).items():
            if n < m and abs(c) >= 0.95:
                corr[(n, m)] = float(c)
    pred = _predict(stage, MFModel(prm, side=side), sub, sub.inputs())
    err = normalised_rms(pred, sub.array(stage.channel))
    return prm, StageResult(stage.name, stage.title, stage.channel, len(sub), names_all, skipped, start, values,
                            stderr, corr, err, passes, time.perf_counter() - t0)


def _fit_stages(data, prm, side, stages, fit_pressure, generic, weighting, progress, max_nfev):
    results = {}
    for name in stages:
        if name not in STAGES:
            raise ValueError(f"unknown stage {name!r}; stages are {', '.join(STAGE_NAMES)}")
        prm, results[name] = _fit_stage(STAGES[name], prm, side, data, fit_pressure, generic, weighting, progress,
                                        max_nfev)
        if name == "mz_combined" and results[name].fitted and "mz" in results and results["mz"].fitted:
            # the pure-Mz stage ran with the moment arm s = 0 and took the moment s Fx (paper A56) of the small
            # Fx at zero slip into the trail and residual torque; refit it now that s is known
            prm, results["mz"] = _fit_stage(STAGES["mz"], prm, side, data, fit_pressure, False, weighting, progress,
                                            max_nfev)
    return prm, results


def fit_tir(data, start=None, stages=STAGE_NAMES, fit_pressure: bool = True, *, weighting: str = "uniform",
            compare: bool | None = None, progress=None, max_nfev: int | None = None) -> FitResult:
    """Fit MF 6.1 parameters to tyre measurements, stage by stage.

    ``data``: :class:`mftyre.data.TyreData` or a ``.tdx``/``.csv`` path. ``start``: None (neutral parameters
    sized to the tyre plus estimates from the data, :func:`mftyre.fit.start_parameters`), an
    :class:`mftyre.MFModel`, a :class:`mftyre.params.TyreParameters` or a ``.tir`` path (its values start every
    stage; parameters of stages not run are kept). ``stages``: names from :data:`mftyre.fit.STAGE_NAMES`, run in
    the order given. ``fit_pressure``: fit the inflation-pressure terms (needs two or more pressures).
    ``weighting``: "uniform" or "load". ``compare``: run the lower/upper-bound comparison of Schmeitz et al.
    (2005) for pure Fx, Fy, Mz (default: when pressure terms are fitted). ``progress``: callable
    (stage, pass, evaluations, cost) called every 25 residual evaluations and after each pass.
    ``max_nfev``: evaluations per pass (default 60 x (parameters + 1)).
    """
    t0 = time.perf_counter()
    data = load_data(data)
    if weighting not in ("uniform", "load"):
        raise ValueError(f"weighting must be 'uniform' or 'load', got {weighting!r}")
    prm, generic = _start(data, start)
    side = None
    start_prm = prm
    prm, results = _fit_stages(data, prm, side, stages, fit_pressure, generic, weighting, progress, max_nfev)
    notes = list(data.history)
    n_p = len(levels(data.array("P"), 0.02 * float(np.max(data.array("P"))))[1])
    if compare is None:
        compare = fit_pressure and n_p >= 2
    comparison = None
    compared = [s for s in COMPARED_STAGES if s in results and results[s].fitted]
    if compare and n_p >= 2 and compared:
        comparison = _pressure_comparison(data, start_prm, generic, side, compared, results, weighting, progress,
                                          max_nfev)
    elif compare:
        notes.append("pressure comparison not run: one pressure in the data")
    return FitResult(prm.replace(INFLPRES=prm.NOMPRES), data, start_prm, results, comparison, notes,
                     time.perf_counter() - t0)


def _pressure_comparison(data, start_prm, generic, side, compared, extended, weighting, progress, max_nfev):
    """Table 2 of Schmeitz et al. (2005): lower bound = mean fit error of separate fits per pressure (no
    pressure terms), upper bound = one fit of all pressures without pressure terms, and the extended fit
    (with pressure terms); recovered = (upper - extended) / (upper - lower)."""
    _, upper = _fit_stages(data, start_prm, side, compared, False, generic, weighting, progress, max_nfev)
    p = data.array("P")
    labels, centres = levels(p, 0.02 * float(np.max(p)))
    lower = {s: [] for s in compared}
    for k in range(len(centres)):
        part = data.select(labels == k)
        _, res = _fit_stages(part, start_prm, side, compared, False, generic, weighting, progress, max_nfev)
        for s in compared:
            if np.isfinite(res[s].fit_error):
                lower[s].append(res[s].fit_error)
    rows = []
    for s in compared:
        lo = float(np.mean(lower[s])) if lower[s] else float("nan")
        up, ext = upper[s].fit_error, extended[s].fit_error
        room = up - lo
        rows.append(dict(characteristic=STAGES[s].title.split(" (")[0], stage=s, lower=lo, upper=up, extended=ext,
                         recovered=(up - ext) / room if room > 0 else float("nan"), pressures=len(centres)))
    return pd.DataFrame(rows)
