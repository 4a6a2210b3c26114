"""Staged least-squares fitting of Magic Formula parameters with lmfit (trust-region reflective,
``scipy.optimize.least_squares``), and the lower/upper-bound comparison of Schmeitz et al. (2005), Table 2.

Before the stages: the test programme is recognised (:func:`mftyre.programme.recognise`) and a time series is
reduced per sweep to binned means with the up and down branches averaged (:func:`mftyre.timeseries.reduce_sweeps`).

Residuals: residual_i = w_i (model_i - measured_i) / s with s the RMS of the measured channel over the stage
data, so the cost is the squared normalised RMS error of :func:`mftyre.fit.normalised_rms` for uniform weights;
w_i = 1 (``weighting="uniform"``) or FNOMIN / Fz_i (``"load"``: every load level counts alike). Shape
conditions (:func:`mftyre.fit.stages.shape_violations`) enter as penalty residuals, 10 sqrt(n) times the
violation, at the corners of the data's load, pressure and camber range; a weak prior holds each parameter
near its start value (:data:`PRIOR_WEIGHT`: worth 1e-4 of what the data say of it alone, so that directions the
data hardly see stay put instead of following the optimiser's path). Model outputs that are not finite
give the residual 10 (the step is rejected). The model is evaluated for all parameter vectors of a
finite-difference Jacobian at once (:class:`mftyre.fit.predict.BatchPredictor`: parameters as column vectors against the data as
a row), the optimiser stops on a relative cost change of 1e-6, BLAS runs on one thread.

After each stage: undetermined parameters go back to their start values (:func:`_undetermined`), standard errors
use the effective number of independent samples, and the stage is accepted only when it fits its data no
worse than before and :func:`mftyre.fit.verify.verify_tir` finds no new problem (the vertical stage also
needs a positive deflection at the measured loads); otherwise it is rejected and the previous values kept.
"""
from __future__ import annotations

import datetime
import math
import textwrap
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import lmfit
import numpy as np
import pandas as pd
from scipy import stats

from ..data import UNCHECKED, TyreData, check_plausible, read_data
from ..formula import vertical
from ..inputs import warn_data_outside
from ..model import MFModel
from ..params import FIT_BOUNDS, SIGN_SYMMETRIC, TyreParameters
from .predict import BatchParameters, BatchPredictor, predict_stage
from ..programme import recognise
from ..timeseries import effective_samples, needs_reduction, reduce_sweeps
from ..tir import read_tir, write_tir
from .metrics import normalised_rms
from .stages import (STAGE_NAMES, STAGES, combined_fy, conditions, data_corners,
                     level_labels, shape_violations,
                     stage_parameters, stage_rows, supported_parameters)
from .start import estimate_stage, start_parameters
from .verify import check_speeds, physical_domain, verification, verify_tir

__all__ = ["fit_tir", "FitResult", "StageResult", "load_data", "COMPARED_STAGES", "BOUNDS", "bounded_parameters", "one_blas_thread",
           "forward_jacobian"]

#: Bounds (min, max) of fitted parameters, the schema's (:data:`mftyre.params.FIT_BOUNDS`); parameters not listed
#: are free.
BOUNDS: dict[str, tuple[float, float]] = FIT_BOUNDS
#: The characteristics of the paper's Table 2 (pure Fx, pure Fy, pure Mz).
COMPARED_STAGES = ("pure_fx", "pure_fy", "mz")


@dataclass
class StageResult:
    """One fitted stage: its passes' lmfit results, the final values and standard errors (scaled for the
    effective number of independent samples ``n_eff``), the fit error; ``reset``: {parameter: why it went back to
    its start value}; ``rejected``: reasons the stage was rejected (its values then not used; ``fitted`` empty);
    ``notes``: what the stage changed besides its parameters (e.g. the free radius derived from the data)."""

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
    reset: dict = field(default_factory=dict)
    rejected: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    n_eff: float = float("nan")

    @property
    def result(self):
        """The lmfit result of the last pass (all parameters, all data of the stage)."""
        return self.passes[-1][1] if self.passes else None


class FitResult:
    """The outcome of :func:`fit_tir`: ``model``, ``params``, ``stages`` (name -> :class:`StageResult`),
    ``comparison`` (Table-2 DataFrame or None), ``data`` (as fitted), ``raw_data``, ``programme``, ``reduction``,
    ``problems`` and ``warnings`` (:func:`mftyre.fit.verify.verification` of the result on the data's domain,
    relative to the start), ``start``; ``report`` (Markdown),
    ``save_report(path)`` (Markdown and PNG plots), ``write_tir(path)``."""

    def __init__(self, params, data, start, stages, comparison, notes, seconds):
        self.params = params
        self.model = MFModel(params)
        self.data, self.start, self.stages = data, start, stages
        self.comparison, self.notes, self.seconds = comparison, notes, seconds
        self.programme = self.reduction = None  # the recognised programme, the time-series reduction (or None)
        self.raw_data = data  # the data as given (``data``: what was fitted, reduced when a time series)
        self.problems = []  # what verification finds in the final parameters (and the start did not have)
        self.warnings = []  # what it finds beyond the data's domain, or shares with the start
        self.sources, self.generic = {}, True  # where the start values come from (mftyre.fit.provenance)
        self.raw_errors = {}  # stage -> (error on the samples as recorded, repeatability floor) [%]

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

    @property
    def undetermined(self) -> dict:
        """Reason -> the parameters held at their start values because the data do not determine them (the
        stages' ``skipped`` and ``reset``, e.g. the Fy shifts of a drive/brake run at alpha 0, -3, -6 deg)."""
        out = {}
        for st in self.stages.values():
            for n, why in list(st.skipped.items()) + list(st.reset.items()):
                if n not in st.fitted:   # the reset reasons by kind (their figures are in the stage results)
                    why = ("standard error larger than the value" if why.startswith("standard error") else
                           "over 0.99 correlated with another parameter" if why.startswith("correlated") else why)
                    out.setdefault(why, []).append(n)
        return out

    def write_tir(self, path, *, overwrite: bool = False) -> Path:
        """Write the fitted .tir; refused (:class:`mftyre.errors.TirError`) when no stage fitted anything, or when
        the parameters have a verification problem (:func:`mftyre.fit.verify.verification`) the start values did
        not have (which no accepted stage allows). Parameters the data do not determine keep their start values
        (:attr:`undetermined`); warnings of the verification are in ``warnings``."""
        from ..errors import TirError

        if not any(st.fitted for st in self.stages.values()):
            raise TirError(f"{path}: not written: nothing could be fitted: " + "; ".join(
                f"{st.title}: {'; '.join(st.rejected) or (next(iter(st.skipped.values())) if st.skipped else 'no parameter')}"
                for st in self.stages.values()))
        if self.problems:
            raise TirError(f"{path}: not written: the fitted parameters fail verification: "
                           + "; ".join(self.problems))
        from .provenance import closing_summary, provenance_of

        return write_tir(self.params, path, overwrite=overwrite, comments=self.provenance(),
                         notes=provenance_of(self), closing=closing_summary(self))

    def provenance(self) -> list[str]:
        """Header lines of the fitted .tir: mftyre version and date, the data (file name, SHA-256, rows), the
        recognised programme, the start, the fit error per stage and channel."""
        from .. import __version__

        raw = self.raw_data
        lines = [f"Fitted by mftyre {__version__} on {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC "
                 f"in {self.seconds:.1f} s",
                 f"Data: {Path(raw.source).name if raw.source else '(in memory)'}"
                 + (f" SHA-256 {raw.sha256}" if raw.sha256 else "") + f", {len(raw)} rows"]
        if self.programme is not None:
            lines += textwrap.wrap("Test programme: " + self.programme.summary(), 100)
        lines.append(f"Start: {self.start.source or 'generic values and estimates from the data'}"
                     if isinstance(self.start, TyreParameters) else "Start: generic values and estimates from the data")
        lines += textwrap.wrap("Fit error [%] (normalised RMS) per stage: " + "; ".join(
            f"{name} ({st.channel}) {st.fit_error:.3f}" + (" REJECTED" if st.rejected else "")
            for name, st in self.stages.items()), 100)
        return lines

    def __repr__(self):
        errs = ", ".join(f"{k} {v:.2f}%" for k, v in self.fit_errors.items())
        return f"FitResult({errs})"


def load_data(source) -> TyreData:
    """TyreData (checked for plausible values, :func:`mftyre.data.check_plausible`), or read from a path
    (TYDEX, TTC or CSV, recognised by content: :func:`mftyre.data.read_data`)."""
    if isinstance(source, TyreData):
        if UNCHECKED not in source.history:  # read with check=False (--no-check): the user has vouched for it
            check_plausible(source)
        return source
    return read_data(source)


def _start(data: TyreData, start, size=None, given=None, sources=None):
    """(start parameters, generic?): the generic start (:func:`mftyre.fit.start_parameters`, its provenance in
    ``sources``) or the given file, with the ``given`` parameters (and the ``size``'s geometry) set."""
    given = dict(given or {})
    if start is None:
        return start_parameters(data, size=size, sources=sources, **given), True
    prm = start.params if isinstance(start, MFModel) else start if isinstance(start, TyreParameters) else \
        read_tir(start)
    if size:
        from ..geometry import tyre_size

        given = {**tyre_size(size).parameters(), **given}
    if sources is not None:
        sources.update(dict.fromkeys(given, "given"))
    return (prm.replace(**given) if given else prm), False


def physical_bounds(prm, data: TyreData) -> dict:
    """Bounds that follow from physics and the data's range, tighter than :data:`BOUNDS` where they apply:
    free-radius growth with speed (Q_V1) at most 3 % and the speed stiffening (Q_V2) at most 40 % at the top
    speed checked by :func:`mftyre.fit.verify.verify_tir`; Q_RE0 within 5 % of 1; a positive vertical stiffness
    over the physical pressure range (:func:`mftyre.fit.verify.physical_domain`: 0.5-1.5 NOMPRES within
    PRESMIN..PRESMAX) and the data's pressures (PFZ1); shifts of a few percent (PHX1, PVX1, PHY1, PVY1)."""
    speed_ratio = float(check_speeds(prm, data)[-1]) / prm.LONGVL  # omega R0 / V0 at the top speed
    p = np.concatenate([data.array("P"), physical_domain(prm, data).pressures])
    dpi = np.abs(vertical.pressure_increment(prm, p[p > 0]))
    pfz1 = 0.9 / max(float(np.max(dpi)), 1e-3)
    return {"Q_V1": (0.0, 0.03 / speed_ratio**2), "Q_V2": (0.0, 0.4 / speed_ratio), "Q_RE0": (0.95, 1.05),
            "PFZ1": (-min(pfz1, 5.0), min(pfz1, 5.0)), "PHX1": (-0.05, 0.05), "PVX1": (-0.1, 0.1),
            "PHY1": (-0.05, 0.05), "PVY1": (-0.2, 0.2)}


def sign_in_bounds(prm, bounds: dict | None = None):
    """The same tyre with every sign-symmetric parameter (:data:`mftyre.params.SIGN_SYMMETRIC`) whose value lies
    outside its ``bounds`` (default :data:`BOUNDS`) but whose negative lies inside negated together with its
    partners: a fit started from it then starts from the file's own values instead of from a clipped, different
    curve."""
    bounds = BOUNDS if bounds is None else bounds
    flip = {}
    for name, partners in SIGN_SYMMETRIC.items():
        lo, hi = bounds.get(name, (-np.inf, np.inf))
        v = float(prm[name])
        if not lo <= v <= hi and lo <= -v <= hi:
            flip.update({n: -float(prm[n]) for n in (name, *partners)})
    return prm.replace(**flip) if flip else prm


def bounded_parameters(prm, names, bounds: dict | None = None) -> lmfit.Parameters:
    """lmfit parameters ``names`` started at their values in ``prm``, clipped into ``bounds`` (default
    :data:`BOUNDS`)."""
    bounds = BOUNDS if bounds is None else bounds
    params = lmfit.Parameters()
    for n in names:
        lo, hi = bounds.get(n, (-np.inf, np.inf))
        params.add(n, value=min(max(float(prm[n]), lo), hi), min=lo, max=hi)
    return params


#: Weight of the weak prior that holds each parameter of a pass near its start value: residual
#: PRIOR_WEIGHT x |dr/dx_j| (x_j - x_j,start), |dr/dx_j| the norm of the parameter's column of the data's Jacobian
#: at the start, so the prior is worth PRIOR_WEIGHT^2 (1e-4) of what the data would say of the parameter alone.
#: A direction the data determine moves by about that fraction less (benchmarks/bench_fit.py: the force and moment
#: errors of the point fit unchanged to 0.01 %); a direction they hardly see (parameters correlated beyond 1 - 1e-4,
#: PCY1/PDY1 of a sweep that does not reach the peak) no longer lets the optimiser wander along a flat valley
#: wherever its path, and the 9th digit of the data, take it (the same run from an ISO-W CSV and a TTC file gave
#: different resets). Stronger priors (0.03, 0.1) held a load-deflection fit back from a far start (fit error
#: +10 %).
PRIOR_WEIGHT = 0.01


class _Problem:
    """The least-squares problem of one pass: residuals of many parameter vectors at once (data rows, then the
    shape-condition penalties, then the weak prior towards the start values) and their forward-difference
    Jacobian from one batched evaluation."""

    def __init__(self, stage, prm, side, data, names, weighting, bounds):
        self.stage, self.prm, self.names = stage, prm, list(names)
        self.measured = data.array(stage.channel)
        self.scale = float(np.sqrt(np.mean(self.measured**2))) or 1.0
        self.weights = prm.FNOMIN / data.array("FZ") if weighting == "load" else np.ones(len(data))
        self.corners = data_corners(data, prm)
        self.penalty = 10.0 * math.sqrt(len(data))
        self.params = bounded_parameters(prm, names, bounds)
        self.predict = BatchPredictor(prm, data, (stage.channel,), names, side=side)
        self.hi = np.array([self.params[n].max for n in names])
        self.n_data = len(data)
        self.shaped = shape_violations(stage.name, prm, self.corners).size > 0
        self.start = np.array([self.params[n].value for n in names], float)
        self.prior = np.zeros(len(names))  # none while the data's Jacobian at the start is taken
        effect = np.linalg.norm(self.jacobian(self.start)[:self.n_data], axis=0)
        self.prior = PRIOR_WEIGHT * np.maximum(effect, 1e-6 * max(float(effect.max(initial=0.0)), 1e-12))

    def residuals(self, values):
        """Rows of residuals for the parameter vectors ``values`` (K, p): the data's, the shape-condition
        penalties (when the stage has shape conditions), the prior's (:data:`PRIOR_WEIGHT`)."""
        pred = self.predict(values)[self.stage.channel]
        r = self.weights * (pred - self.measured) / self.scale
        r = np.where(np.isfinite(r), r, 10.0)
        parts = [r]
        if self.shaped:
            parts.append(np.stack([self.penalty * shape_violations(self.stage.name, BatchParameters(self.prm, dict(
                zip(self.names, v))), self.corners) for v in values]))
        parts.append(self.prior * (np.asarray(values, float) - self.start))
        return np.concatenate(parts, axis=1)

    def jacobian(self, x):
        return forward_jacobian(self.residuals, x, self.hi)


def forward_jacobian(rows, x, upper) -> np.ndarray:
    """The forward-difference Jacobian (residuals x parameters) at the parameter vector ``x`` of ``rows`` ((K, p)
    parameter vectors -> (K, residuals)), every column from one call with x and x + h_j e_j: h_j = 1.5e-8
    max(|x_j|, 0.01), taken backwards where the step would pass the ``upper`` bound."""
    step = 1.5e-8 * np.maximum(np.abs(x), 1e-2)
    step = np.where(x + step > upper, -step, step)
    base = rows(np.vstack([x, x + np.diag(step)]))
    return ((base[1:] - base[0]) / step[:, None]).T


def _fit_pass(stage, prm, side, data, names, weighting, progress, label, max_nfev, bounds):
    """One least-squares pass over ``data`` varying ``names``; returns (new parameters, lmfit result, problem).

    The Jacobian is a forward difference computed in one batched evaluation (:class:`mftyre.fit.predict.BatchPredictor`); the
    optimiser stops when the cost changes by less than 1e-6 relative (ftol)."""
    problem = _Problem(stage, prm, side, data, names, weighting, bounds)

    def vector(p):
        return np.array([p[n].value for n in names], float)

    counter = {"n": 0}

    def iter_cb(p, it, resid, *a, **k):
        counter["n"] += 1
        if progress is not None and (counter["n"] % 25 == 0):
            progress(stage.name, label, counter["n"], float(np.sum(resid**2)))

    nfev = max_nfev or 30 * (len(names) + 1)
    minimizer = lmfit.Minimizer(lambda p: problem.residuals(vector(p)[None, :])[0], problem.params, iter_cb=iter_cb)
    with warnings.catch_warnings(), one_blas_thread():
        warnings.simplefilter("ignore", RuntimeWarning)  # a singular covariance: lmfit's errors undefined
        result = minimizer.minimize(method="least_squares", max_nfev=nfev, x_scale="jac", ftol=1e-6, xtol=1e-8,
                                    gtol=1e-8, Dfun=lambda p: problem.jacobian(vector(p)))
    new = prm.replace(**{n: float(result.params[n].value) for n in names})
    if progress is not None:
        progress(stage.name, label, counter["n"], float(result.chisqr))
    return new, result, problem


def one_blas_thread():
    """BLAS limited to one thread: the small dense factorisations of the optimiser run 10-100x slower when
    OpenBLAS spreads them over the cores of a busy machine."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency; without it the fit is only slower
        import contextlib

        return contextlib.nullcontext()
    return threadpool_limits(1, user_api="blas")


def _uncertainties(problem, prm, data):
    """(stderr, correlations, n_eff) at ``prm`` from the Jacobian of the data residuals: covariance
    s^2 (J^T J)^+ with s^2 = sum r^2 / (n_eff - p), n_eff the effective number of independent residuals (AR(1)
    rule within each sweep, :func:`mftyre.timeseries.effective_samples`). A parameter without effect on the data
    (a zero column of J) has an undefined error (None)."""
    names = problem.names
    x = np.array([float(prm[n]) for n in names])
    r = problem.residuals(x[None, :])[0][:problem.n_data]
    jac = problem.jacobian(x)[:problem.n_data]
    groups = data.frame["SWEEP"].to_numpy() if "SWEEP" in data else None
    n_eff = effective_samples(r, groups)
    s2 = float(r @ r) / max(n_eff - len(names), 1.0)
    col = np.linalg.norm(jac, axis=0)
    live = col > 1e-12 * max(float(col.max()), 1e-300)
    stderr, corr = {n: None for n in names}, {}
    if live.any():
        unit = jac[:, live] / col[live]  # columns of unit length: the covariance of parameters of any size
        with one_blas_thread():
            cov = s2 * np.linalg.pinv(unit.T @ unit) / np.outer(col[live], col[live])
        sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
        idx = np.flatnonzero(live)
        for i, j in enumerate(idx):
            stderr[names[j]] = float(sd[i])
            for k in range(i + 1, len(idx)):
                c = cov[i, k] / (sd[i] * sd[k]) if sd[i] > 0 and sd[k] > 0 else 0.0
                if abs(c) >= 0.95:
                    corr[tuple(sorted((names[j], names[idx[k]])))] = float(c)
    return stderr, corr, n_eff


def _undetermined(names, values, stderr, corr, needed=frozenset()):
    """{name: reason} of the parameters the data do not determine, in order: those without effect on the data;
    of each pair correlated beyond |r| = 0.99 the later one in the stage's order (the higher-order term: PKY2
    rather than PKY1); only when no such pair is left, those whose standard error exceeds their size (a
    collinear pair inflates the errors of both, so pairs are resolved first). ``needed``: parameters of pairs
    whose reset cost the fit significantly (:func:`_reset_costs`): the data determine what they do together, so
    neither their correlation nor their standard errors reset them."""
    out = {n: "no effect on the data" for n in names if stderr.get(n) is None}
    order = {n: i for i, n in enumerate(names)}
    for (a, b), c in sorted(corr.items(), key=lambda kv: -abs(kv[1])):
        if abs(c) > 0.99 and a not in out and b not in out and not {a, b} <= needed:
            later, earlier = (a, b) if order[a] > order[b] else (b, a)
            out[later] = f"correlated {c:+.4f} with {earlier}"
    if out:
        return out
    for n in names:
        if n not in needed and stderr[n] > abs(values[n]):
            out[n] = f"standard error {stderr[n]:.3g} exceeds its size {values[n]:.3g}"
    return out


def _bound_hit(param, value: float):
    """The bound of lmfit parameter ``param`` that ``value`` lies on (within 1e-6 relative), or None."""
    for b in (param.min, param.max):
        if np.isfinite(b) and abs(value - b) <= 1e-6 * max(abs(b), 1e-3):
            return float(b)
    return None


#: Significance level at which a reset that raises the stage's residual sum of squares is refused.
RESET_ALPHA = 1e-3


def _reset_costs(rss_before: float, rss_after: float, n: int, n_eff: float, k_free: int, k_reset: int) -> bool:
    """Whether resetting ``k_reset`` parameters raised the residual sum of squares significantly: F test of the
    increase against the residual variance of the fuller fit, counting n_eff of the n residuals as independent
    (as the gap finder's :func:`mftyre.gaps.core.f_test`)."""
    if rss_after <= rss_before:
        return False
    var = rss_before / max(n - k_free, 1)
    fstat = (rss_after - rss_before) * (n_eff / max(n, 1)) / k_reset / max(var, 1e-300)
    return float(stats.f.sf(fstat, k_reset, max(n_eff - k_free, 1))) < RESET_ALPHA


def _free_radius_from_rl(data: TyreData) -> float | None:
    """Free radius the loaded-radius data extrapolate to at zero load (quadratic in Fz over the lower half of the
    loads at the lowest speeds), or None."""
    rl, fz, vx = data.array("RL"), data.array("FZ"), data.array("VX")
    ok = np.isfinite(rl) & (fz > 0)
    if ok.sum() < 4:
        return None
    ok &= vx <= np.quantile(vx[ok], 0.5) + 1.0
    low = ok & (fz <= np.quantile(fz[ok], 0.5))
    if low.sum() < 4 or np.ptp(fz[low]) <= 0:
        return None
    deg = 2 if len(np.unique(np.round(fz[low]))) >= 6 else 1
    return float(np.polyval(np.polyfit(fz[low], rl[low], deg), 0.0))


def _vertical_consistency(prm, data: TyreData, radius_given: bool):
    """(parameters, note, rejection): the free radius the RL data imply against UNLOADED_RADIUS x Q_RE0. More
    than 5 % apart, or a measured loaded radius above the free radius (negative deflection): the radius is
    derived from the data when it was not given, otherwise the stage is rejected with the reason."""
    r_data = _free_radius_from_rl(data)
    r_free = prm.UNLOADED_RADIUS * prm.Q_RE0
    rl = data.array("RL")
    negative = float(np.nanmedian(rl[data.array("FZ") > 0.5 * prm.FNOMIN])) > r_free if np.any(
        data.array("FZ") > 0.5 * prm.FNOMIN) else False
    if r_data is None or (abs(r_data / r_free - 1.0) <= 0.05 and not negative):
        return prm, None, None
    what = (f"the RL data extrapolate to a free radius of {r_data:.4g} m at zero load, UNLOADED_RADIUS x Q_RE0 is "
            f"{r_free:.4g} m" + (" (the measured loaded radius exceeds it: negative deflection)" if negative else ""))
    if radius_given:
        return prm, None, f"inconsistent data: {what}; check the RL channel (loaded radius from the wheel centre " \
                          "to the ground) or the .tir's UNLOADED_RADIUS"
    return prm.replace(UNLOADED_RADIUS=r_data, Q_RE0=1.0), f"UNLOADED_RADIUS set to {r_data:.4g} m: {what}", None


def _fit_stage(stage, prm, side, data, fit_pressure, generic, weighting, progress, max_nfev, baseline,
               radius_given=False, held=frozenset(), fy_combined=True):
    rows = stage_rows(stage, data, fy_combined)
    sub = data.select(rows)
    cond = conditions(sub)
    groups, skipped = stage_parameters(stage, cond, fit_pressure)
    groups, capped = supported_parameters(stage, groups, sub)
    skipped.update(capped)
    skipped.update({n: "given by the user" for g in groups.values() for n in g if n in held})
    groups = {k: [n for n in g if n not in held] for k, g in groups.items()}
    names_all = groups["base"] + groups["pressure"] + groups["camber"]
    t0 = time.perf_counter()

    def not_fitted(reason_all=None, rejected=None, notes=()):
        if reason_all:
            skipped.update({n: reason_all for needs, names in stage.groups for n in names if n not in skipped})
        return prm, StageResult(stage.name, stage.title, stage.channel, len(sub), [], skipped, {}, {}, {}, {},
                                float("nan"), rejected=rejected or [], notes=list(notes))

    if len(sub) == 0:
        skipped.clear()
        return not_fitted(f"no data for this stage ({_ROWS_NEEDED[stage.rows]} with a measured {stage.channel})")
    if len(sub) < max(len(names_all) + 1, 5) or not names_all:
        return not_fitted(f"{len(sub)} points, too few for {len(names_all)} parameters" if names_all
                          else "no parameter to fit")
    before = prm
    notes = []
    if stage.name == "vertical" and sub.has("RL"):
        prm, note, rejection = _vertical_consistency(prm, sub, radius_given)
        if rejection:
            return not_fitted("stage rejected", [rejection])
        if note:
            notes.append(note)
    bounds = dict(BOUNDS, **physical_bounds(prm, data))
    prm = sign_in_bounds(prm, bounds)
    if generic:
        est = {k: v for k, v in estimate_stage(stage.name, prm, sub).items() if k in names_all}
        prm = prm.replace(**est)
    start = {n: float(prm[n]) for n in names_all}
    err_before = normalised_rms(predict_stage(stage, MFModel(before, side=side), sub, sub.inputs()),
                                sub.array(stage.channel))
    g, p = sub.array("IA"), sub.array("P")
    flat = np.abs(g) < math.radians(0.25)
    calm, what = flat, "zero camber"
    if stage.name == "vertical":
        # the load-deflection curve first from rows without slip: the side and longitudinal forces' effect on the
        # deflection (Q_FCX, Q_FCY; MF 6.2 also Q_FCY2, not fitted) would otherwise bend it (Q_FZ2 to 0)
        rolling = flat & (np.abs(sub.array("SA")) < math.radians(0.25)) & (np.abs(sub.array("SL")) < 0.005)
        if rolling.sum() > len(groups["base"] + groups["pressure"]) + 5:
            calm, what = rolling, "no slip, zero camber"
    nominal = calm & (np.abs(p - prm.NOMPRES) <= 0.02 * prm.NOMPRES)
    passes = []
    plan = []
    if (groups["pressure"] or groups["camber"]) and nominal.sum() > len(groups["base"]) + 5 and not nominal.all():
        plan.append((f"{what}, nominal pressure", groups["base"], nominal))
    # then the pressure terms, before the rest can bend the curve towards a missing pressure effect
    if groups["pressure"] and (groups["camber"] or not calm.all()) \
            and calm.sum() > len(groups["base"] + groups["pressure"]) + 5:
        plan.append((f"{what}, all pressures", groups["base"] + groups["pressure"], calm))
    plan.append(("all data", names_all, np.ones(len(sub), bool)))
    for label, names, mask in plan:
        part = sub if mask.all() else sub.select(mask)
        prm, res, problem = _fit_pass(stage, prm, side, part, names, weighting, progress, label, max_nfev, bounds)
        passes.append((label, res))
    # parameters the data do not determine go back to their default (the start parameter set) and the rest
    # is refitted, until every fitted parameter is determined
    # (except a correlated pair whose reset costs the fit significantly: amplitude and rate of one term, such as
    # QSX10 atan(QSX11 Fz/Fz0), are correlated by their form while the data determine the term)
    free = list(names_all)
    reset, needed = {}, set()
    for _ in range(6):
        values = {n: float(prm[n]) for n in free}
        stderr, corr, n_eff = _uncertainties(problem, prm, sub)
        drop = _undetermined(free, values, stderr, corr, needed)
        if not drop:  # a parameter ending on a bound of the fit: the data push it beyond what a tyre has
            drop = {n: f"at its bound {_bound_hit(problem.params[n], values[n]):g} of the fit" for n in free
                    if n not in needed and _bound_hit(problem.params[n], values[n]) is not None}
        if not drop:
            break
        rest = [n for n in free if n not in drop]
        trial = prm.replace(**{n: float(baseline[n]) for n in drop})
        if rest:
            trial, trial_res, trial_problem = _fit_pass(stage, trial, side, sub, rest, weighting, progress,
                                                        "after resetting undetermined", max_nfev, bounds)
        pairs = {n: w.split(" with ")[1] for n, w in drop.items() if w.startswith("correlated")}
        bound = [n for n, w in drop.items() if w.startswith("at its bound")]
        if bound and rest:
            rss = [float(np.sum(pr.residuals(np.array([[float(p_[n]) for n in pr.names]]))[0][:pr.n_data] ** 2))
                   for pr, p_ in ((problem, prm), (trial_problem, trial))]
            if _reset_costs(rss[0], rss[1], len(sub), n_eff, len(free), len(drop)):
                needed |= set(bound)
                notes.append(f"kept at a bound of the fit (resetting raised the residual sum of squares from "
                             f"{rss[0]:.4g} to {rss[1]:.4g}, significant; its value is not determined): "
                             + ", ".join(bound))
                continue
        if pairs and rest:
            rss = [float(np.sum(pr.residuals(np.array([[float(p_[n]) for n in pr.names]]))[0][:pr.n_data] ** 2))
                   for pr, p_ in ((problem, prm), (trial_problem, trial))]
            if _reset_costs(rss[0], rss[1], len(sub), n_eff, len(free), len(drop)):
                needed |= set(pairs) | set(pairs.values())
                notes.append("kept although correlated beyond 0.99 (resetting raised the residual sum of squares "
                             f"from {rss[0]:.4g} to {rss[1]:.4g}, significant): "
                             + ", ".join(f"{a} with {b}" for a, b in pairs.items()))
                continue
        reset.update(drop)
        free, prm = rest, trial
        if not free:
            break
        res, problem = trial_res, trial_problem
        passes.append(("after resetting undetermined", res))
    values = {n: float(prm[n]) for n in names_all}
    stderr, corr, n_eff = _uncertainties(problem, prm, sub) if free else ({}, {}, float(len(sub)))
    stderr.update({n: None for n in reset})
    pred = predict_stage(stage, MFModel(prm, side=side), sub, sub.inputs())
    err = normalised_rms(pred, sub.array(stage.channel))
    rejected = []
    if not np.isfinite(err):
        rejected.append("the fitted model is not finite on the stage data")
    elif np.isfinite(err_before) and err > err_before * 1.001 + 1e-9:
        rejected.append(f"the fit error {err:.3g} % is worse than before the stage ({err_before:.3g} %)")
    if stage.name == "vertical" and not rejected:
        measured_rho = (prm.UNLOADED_RADIUS * prm.Q_RE0 - sub.array("RL")) if sub.has("RL") else sub.array("RHO")
        if np.nanmin(measured_rho) < -0.02 * prm.UNLOADED_RADIUS or err > 25.0:
            rejected.append(f"the vertical relation does not describe the data (FZ error {err:.3g} %, measured "
                            f"deflection down to {np.nanmin(measured_rho):.3g} m)")
    if not rejected:
        rejected += verify_tir(MFModel(prm, side=side), data, baseline=MFModel(before, side=side))
    result = StageResult(stage.name, stage.title, stage.channel, len(sub), free, skipped, start, values, stderr,
                         corr, err, passes, time.perf_counter() - t0, reset=reset, rejected=rejected, notes=notes,
                         n_eff=n_eff)
    if rejected:
        result.fitted = []
        return before, result
    return prm, result


#: what rows a stage needs, in words (for the reason a stage is not fitted)
_ROWS_NEEDED = {"pure_lateral": "no rows with slip angle at zero longitudinal slip",
                "pure_longitudinal": "no rows with longitudinal slip at zero slip angle",
                "combined": "no rows with both slip angle and longitudinal slip",
                "with_kappa": "no rows with longitudinal slip", "slip": "no rows with slip",
                "free_rolling": "no free-rolling rows", "free_rolling_re": "no free-rolling rows",
                "all_rl": "no rows"}


def _fit_stages(data, prm, side, stages, fit_pressure, generic, weighting, progress, max_nfev, baseline,
                radius_given=False, held=frozenset()):
    results = {}
    for name in stages:
        if name not in STAGES:
            raise ValueError(f"unknown stage {name!r}; stages are {', '.join(STAGE_NAMES)}")
        prm, results[name] = _fit_stage(STAGES[name], prm, side, data, fit_pressure, generic, weighting, progress,
                                        max_nfev, baseline, radius_given, held, combined_fy(results))
        if name == "mz_combined" and results[name].fitted and "mz" in results and results["mz"].fitted:
            # the pure-Mz stage ran with the moment arm s = 0 and took the moment s Fx (paper A56) of the small
            # Fx at zero slip into the trail and residual torque; refit it now that s is known
            prm, results["mz"] = _fit_stage(STAGES["mz"], prm, side, data, fit_pressure, False, weighting, progress,
                                            max_nfev, baseline, radius_given, held)
    return prm, results


def fit_tir(data, start=None, stages=STAGE_NAMES, fit_pressure: bool = True, *, weighting: str = "uniform",
            compare: bool | None = None, progress=None, max_nfev: int | None = None, reduce: bool | None = None,
            bins: int = 40, size: str | None = None, given: dict | None = None) -> FitResult:
    """Fit MF 6.1 parameters to tyre measurements, stage by stage.

    ``data``: :class:`mftyre.data.TyreData` or a ``.tdx``/``.csv`` path. ``start``: None (neutral parameters
    sized to the tyre plus estimates from the data, :func:`mftyre.fit.start_parameters`), an
    :class:`mftyre.MFModel`, a :class:`mftyre.params.TyreParameters` or a ``.tir`` path (its values start every
    stage; parameters of stages not run are kept). ``stages``: names from :data:`mftyre.fit.STAGE_NAMES`, run in
    the order given. ``fit_pressure``: fit the inflation-pressure terms (needs two or more pressures).
    ``weighting``: "uniform" or "load". ``compare``: run the lower/upper-bound comparison of Schmeitz et al.
    (2005) for pure Fx, Fy, Mz (default: when pressure terms are fitted). ``progress``: callable
    (stage, pass, evaluations, cost) called every 25 residual evaluations and after each pass.
    ``max_nfev``: evaluations per pass (default 30 x (parameters + 1)). ``reduce``: reduce a time series to
    binned means per sweep first (:func:`mftyre.timeseries.reduce_sweeps`, ``bins`` per sweep; default: when
    the data are dense enough, :func:`mftyre.timeseries.needs_reduction`). ``size``: the tyre size designation
    (e.g. ``"16x7.5-10"``: R0, rim radius, width, aspect ratio); ``given``: parameters set by the user (e.g.
    ``{"RIM_RADIUS": 0.127}``), held, never fitted. Where each value of the result comes from is
    ``result.provenance_of`` (written beside each parameter of the .tir).

    The test programme is recognised first (:func:`mftyre.programme.recognise`, in ``result.programme``).
    In every stage: physical bounds (:func:`physical_bounds`), only the parameters the data's distinct
    conditions support (:func:`mftyre.fit.stages.supported_parameters`), parameters whose standard error (for the
    effective number of independent samples) exceeds their size or that are > 0.99 correlated go back to the
    start value (``StageResult.reset``), and the result must pass :func:`mftyre.fit.verify.verify_tir`, fit the
    stage data no worse than before and, for the vertical stage, describe the loaded radius with positive
    deflection; otherwise the stage is rejected (``StageResult.rejected``) and the previous values are kept.
    """
    t0 = time.perf_counter()
    data = load_data(data)
    if weighting not in ("uniform", "load"):
        raise ValueError(f"weighting must be 'uniform' or 'load', got {weighting!r}")
    if not (isinstance(bins, (int, np.integer)) and bins >= 3):
        raise ValueError(f"bins must be an integer >= 3, got {bins!r}")
    if max_nfev is not None and not (isinstance(max_nfev, (int, np.integer)) and max_nfev >= 1):
        raise ValueError(f"max_nfev must be None or an integer >= 1, got {max_nfev!r}")
    programme = recognise(data)
    notes = list(data.history) + ["test programme: " + programme.summary()]
    reduction = None
    if reduce or (reduce is None and needs_reduction(data, programme, bins)):
        reduction = reduce_sweeps(data, programme, bins=bins)
        notes.append(reduction.summary())
        fit_data = reduction.mean
    else:
        fit_data = programme.annotate(data)
    radius_given = start is not None or isinstance(data.constants.get("RFREE"), float) \
        or "UNLOADED_RADIUS" in (given or {})
    sources = {}
    prm, generic = _start(fit_data, start, size, given, sources)
    held = frozenset(given or ())
    warn_data_outside(MFModel(prm), fit_data.inputs(), f"{data.source or 'the data'} against the start values")
    side = None
    start_prm = prm
    prm, results = _fit_stages(fit_data, prm, side, stages, fit_pressure, generic, weighting, progress, max_nfev,
                               start_prm, radius_given, held)
    n_p = programme.levels["P"].size
    if compare is None:
        compare = fit_pressure and n_p >= 2
    comparison = None
    compared = [s for s in COMPARED_STAGES if s in results and results[s].fitted]
    if compare and n_p >= 2 and compared:
        comparison = _pressure_comparison(fit_data, start_prm, generic, side, compared, results, weighting, progress,
                                          max_nfev)
    elif compare:
        notes.append("pressure comparison not run: one pressure in the data")
    result = FitResult(prm.replace(INFLPRES=prm.NOMPRES), fit_data, start_prm, results, comparison, notes,
                       time.perf_counter() - t0)
    result.programme, result.reduction, result.raw_data = programme, reduction, data
    result.sources, result.generic = sources, generic
    if reduction is not None:
        result.raw_errors = _sample_errors(result.model, programme.annotate(data), programme, results, bins)
    checked = verification(result.model, data, baseline=MFModel(start_prm, side=side))
    result.problems, result.warnings = checked.problems, checked.warnings
    return result


def _sample_errors(model, data, programme, results, bins) -> dict:
    """Stage -> (fit error on the samples as recorded [%], the data's repeatability floor [%]) for the fitted
    stages of a reduced time series: the normalised RMS (:func:`normalised_rms`) of the model on every sample of the
    sweeps in the stage's rows, and the same measure of the samples' scatter about their bin mean at equal load,
    pressure, camber and slip (:func:`mftyre.timeseries.scatter_about_bins`, both branches): no model of the
    steady state fits the samples better than that."""
    from ..timeseries import scatter_about_bins

    out = {}
    in_sweep = programme.rows["SWEEP"].to_numpy() >= 0
    for name, st in results.items():
        if not st.fitted or STAGES[name].output == "fz_from_rl":
            continue
        stage = STAGES[name]
        rows = stage_rows(stage, data, combined_fy(results)) & in_sweep
        if rows.sum() < 10:
            continue
        sub = data.select(rows)
        measured = sub.array(stage.channel)
        err = normalised_rms(predict_stage(stage, model, sub, sub.inputs()), measured)
        dev = scatter_about_bins(data, programme, stage.channel, bins=bins)[rows]
        ok = np.isfinite(dev) & np.isfinite(measured)
        floor = 100.0 * float(np.sqrt(np.sum(dev[ok] ** 2) / np.sum(measured[ok] ** 2))) if ok.any() else float("nan")
        out[name] = (err, floor)
    return out


def _pressure_comparison(data, start_prm, generic, side, compared, extended, weighting, progress, max_nfev):
    """Table 2 of Schmeitz et al. (2005): lower bound = mean fit error of separate fits per pressure (no
    pressure terms), upper bound = one fit of all pressures without pressure terms, and the extended fit
    (with pressure terms); recovered = (upper - extended) / (upper - lower)."""
    _, upper = _fit_stages(data, start_prm, side, compared, False, generic, weighting, progress, max_nfev, start_prm)
    labels = level_labels(data, "P")
    centres = np.unique(labels[labels >= 0])
    lower = {s: [] for s in compared}
    for k in centres:
        part = data.select(labels == k)
        _, res = _fit_stages(part, start_prm, side, compared, False, generic, weighting, progress, max_nfev,
                             start_prm)
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
