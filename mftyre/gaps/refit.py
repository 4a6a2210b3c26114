"""Refit a given parameter subset on given channels and data, with the fitting machinery of :mod:`mftyre.fit`.

:func:`refit` is the one least-squares step of the gap finder: lmfit's trust-region reflective method
(``scipy.optimize.least_squares``) as in :mod:`mftyre.fit.core`, the parameter bounds :data:`mftyre.fit.BOUNDS`,
and the Magic Formula shape conditions of :func:`mftyre.fit.stages.shape_violations` as penalty residuals at the
corners of the data's load, pressure and camber range. Unlike a fitting stage it may span several channels at
once (an effect on Fy also moves Mz and Mx) and weighs each channel's residual by its measurement-noise level
(sigma), so that the cost is a chi-square and differences of costs are likelihood-ratio statistics; without
sigma each channel is normalised by its RMS as in the fit. As in the fit, the Jacobian is a forward difference of
all its columns in one batched evaluation (:meth:`mftyre.gaps.residuals.Evaluator.batch`, the fit's
:class:`mftyre.fit.predict.BatchPredictor`), the search stops on a relative cost change of 1e-6 (a chi-square
cost: far below a difference the tests could see) and BLAS runs on one thread.

Bounds are the fit's (:data:`mftyre.fit.core.BOUNDS` tightened by :func:`mftyre.fit.core.physical_bounds`).

:func:`refit_stages` is the "fair start": stage by stage (rows and channel of :data:`mftyre.fit.STAGES`), the
parameters that are active in the model (base parameters, and those of every effect that is switched on) and
that the stage's data can determine (the stage groups' ``needs``, and a sweep of the input the stage's curve runs
along, :func:`data_conditions`) are refitted; a stage whose values have a problem
(:func:`mftyre.fit.verify.verify_tir` in the data's domain) that the given file does not have keeps the previous
ones.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import lmfit
import numpy as np

from ..data import TyreData, levels
from ..fit.core import (BOUNDS, bounded_parameters, forward_jacobian, one_blas_thread, physical_bounds,
                        sign_in_bounds)
from ..fit.predict import BatchParameters
from ..fit.verify import verify_tir
from ..fit.stages import STAGES, data_corners, need_met, conditions, shape_violations, stage_rows  # need_met: the stages' own rule
from ..model import MFModel
from ..params import PARAMETERS
from .catalogue import BASE, CATALOGUE, PARAM_STAGE, TURN_SLIP_BASE, effect_state, parameter_needs
from .drift import BOUNDS as DRIFT_BOUNDS
from .residuals import Evaluator

__all__ = ["refit", "RefitResult", "refit_stages", "stage_names", "needs_met", "data_conditions", "SWEEP_REASONS", "active_parameters", "standard_errors", "covariance", "FAIR_STAGES"]

#: Stages the fair start refits, in order (the effective rolling radius is not mapped).
FAIR_STAGES = ("pure_fx", "pure_fy", "mz", "combined_fx", "combined_fy", "mz_combined", "mx", "my", "vertical")


@dataclass
class RefitResult:
    names: list
    values: dict
    stderr: dict
    chi2_before: float
    chi2_after: float
    n: int
    nfev: int
    success: bool
    problems: tuple = ()


def refit(params, ev: Evaluator, names, channels=None, sigma: dict | None = None, *, start: dict | None = None,
          max_nfev: int | None = None):
    """Least-squares refit of ``names`` (others fixed) on the channels of ``ev``; returns (parameters, result).

    ``sigma``: channel -> noise standard deviation (residuals weighted by 1/sigma; chi-square costs), default the
    RMS of the measured channel. ``start``: start values for some of the names (default: their current values).
    """
    prm = params.params if isinstance(params, MFModel) else params
    names = list(names)
    channels = [c for c in (channels or ev.channels) if c in ev.channels]
    scale = {c: (sigma[c][0] if isinstance(sigma[c], tuple) else sigma[c]) if sigma and c in sigma
             else (float(np.sqrt(np.mean(ev.measured[c] ** 2))) or 1.0) for c in channels}
    if start:
        prm = prm.replace(**{k: v for k, v in start.items() if k in names})
    bounds = {**BOUNDS, **physical_bounds(prm, ev.data), **DRIFT_BOUNDS}   # the fit's physics
    prm = sign_in_bounds(prm, bounds)
    n = int(sum(ev.measured[c].size for c in channels))

    def resid_vec(trial):
        res = ev.residuals(trial, channels)
        r = np.concatenate([res[c] / scale[c] for c in channels]) if channels else np.zeros(0)
        return np.where(np.isfinite(r), r, 1e3)

    r0 = resid_vec(prm)
    chi2_before = float(np.sum(r0**2))
    if not names or n == 0:
        return prm, RefitResult(names, {}, {}, chi2_before, chi2_before, n, 0, True)
    stage_set = sorted({PARAM_STAGE.get(k) for k in names} & set(STAGES))
    corners = data_corners(ev.data, prm)
    penalty = 10.0 * math.sqrt(max(n, 1)) * max(1.0, float(np.sqrt(np.mean(r0**2))))
    lp = bounded_parameters(prm, names, bounds)
    batch = ev.batch(prm, names, channels)
    hi = np.array([lp[k].max for k in names])

    def residual_rows(values):
        """(K, residuals) of the parameter vectors ``values``: the data's, then the shape-condition penalties."""
        pred = batch(values)
        r = np.concatenate([(pred[c] - ev.measured[c]) / scale[c] for c in channels], axis=1)
        r = np.where(np.isfinite(r), r, 1e3)
        if not stage_set:
            return r
        pen = np.stack([np.concatenate([penalty * shape_violations(s, BatchParameters(prm, dict(zip(names, v))),
                                                                   corners) for s in stage_set]) for v in values])
        return np.concatenate([r, pen], axis=1)

    def vector(p):
        return np.array([p[k].value for k in names], float)

    nfev = max_nfev or 40 * (len(names) + 1)
    with warnings.catch_warnings(), one_blas_thread():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = lmfit.Minimizer(lambda p: residual_rows(vector(p)[None, :])[0], lp).minimize(
            method="least_squares", max_nfev=nfev, x_scale="jac", ftol=1e-6, xtol=1e-8,
            Dfun=lambda p: forward_jacobian(residual_rows, vector(p), hi))  # every column in one batch
    values = {k: float(out.params[k].value) for k in names}
    new = prm.replace(**values)
    chi2_after = float(np.sum(resid_vec(new) ** 2))
    if chi2_after > chi2_before:  # never worse than the start (a failed or stopped search)
        new, chi2_after = prm, chi2_before
        values = {k: float(prm[k]) for k in names}
    stderr = {k: (float(out.params[k].stderr) if out.params[k].stderr is not None
                  and np.isfinite(out.params[k].stderr) else None) for k in names}
    return new, RefitResult(names, values, stderr, chi2_before, chi2_after, n, int(out.nfev), bool(out.success))


def standard_errors(params, ev: Evaluator, names, channels, sigma: dict, n_eff: float | None = None) -> dict:
    """Standard errors of ``names`` at their current values (see :func:`covariance`)."""
    return covariance(params, ev, names, channels, sigma, n_eff)[0]


def covariance(params, ev: Evaluator, names, channels, sigma: dict, n_eff: float | None = None):
    """({name: standard error or None}, correlation matrix) of ``names`` at their current values:
    cov = (J^T J)^-1 chi2/(n - k) from the central-difference Jacobian J of the noise-weighted residuals (as lmfit
    scales its covariance), times n / n_eff when only ``n_eff`` of the n residuals are independent
    (autocorrelated samples carry less information than their number says)."""
    prm = params.params if isinstance(params, MFModel) else params
    channels = [c for c in channels if c in ev.channels]
    scale = {c: sigma[c][0] if isinstance(sigma[c], tuple) else sigma[c] for c in channels}
    none = ({k: None for k in names}, np.full((len(names), len(names)), np.nan))
    if not channels or not names:
        return none

    values = np.array([float(prm[k]) for k in names])
    steps = 1e-5 * np.maximum(np.abs(values), 1e-2)
    sets = np.vstack([values, values + np.diag(steps), values - np.diag(steps)])
    pred = ev.batch(prm, names, channels)(sets)
    rows = np.concatenate([(pred[c] - ev.measured[c]) / scale[c] for c in channels], axis=1)
    r0 = rows[0]
    k = len(names)
    cols = [(rows[1 + i] - rows[1 + k + i]) / (2 * steps[i]) for i in range(k)]
    jac = np.stack(cols, axis=1)
    ok = np.all(np.isfinite(jac), axis=1) & np.isfinite(r0)
    jac, r0 = jac[ok], r0[ok]
    dof = max(r0.size - len(names), 1)
    inflation = max(r0.size / n_eff, 1.0) if n_eff else 1.0
    try:
        cov = np.linalg.inv(jac.T @ jac) * float(np.sum(r0**2)) / dof * inflation
    except np.linalg.LinAlgError:
        return none
    d = np.sqrt(np.where(np.diag(cov) > 0, np.diag(cov), np.nan))
    corr = cov / np.outer(d, d)
    return {k: (float(d[i]) if np.isfinite(d[i]) else None) for i, k in enumerate(names)}, corr


def needs_met(needs, cond: dict, turn_slip: bool) -> bool:
    """Whether data with the conditions ``cond`` (:func:`data_conditions`) determine a parameter with ``needs``."""
    return all(turn_slip if n == "turn_slip" else cond[n] if n in _SWEEPS else need_met(n, cond, True) for n in needs)


_SWEEPS = ("slip_ratio", "slip_angle", "combined", "deflection", "slip_speeds")
#: Why a parameter whose stage sweeps an input cannot be determined without that sweep.
SWEEP_REASONS = {
    "slip_ratio": "no longitudinal-slip sweep in the data (SL = 0 throughout): the Fx curve's shape and shifts "
                  "act along kappa",
    "slip_angle": "no slip-angle sweep in the data (SA = 0 throughout): the Fy and Mz curves' shape and shifts "
                  "act along alpha",
    "combined": "no combined-slip sweep (kappa swept at a slip angle) in the data",
    "deflection": "no load-deflection sweep (loaded radius or deflection at three or more loads) in the data",
    "slip_speeds": "slip swept at one speed only (the speed sweeps free rolling): a friction decay with slip "
                   "speed cannot be told from the slip curve's shape",
}


def _swept(x, tol) -> bool:
    """A sweep: three or more distinct levels, one of them away from zero."""
    x = x[np.isfinite(x)]
    return bool(x.size) and len(levels(x, tol)[1]) >= 3 and bool(np.any(np.abs(x) > tol))


def data_conditions(data: TyreData) -> dict:
    """:func:`mftyre.fit.stages.conditions` plus the swept inputs (``slip_ratio``, ``slip_angle``,
    ``combined``, ``deflection``: True where the data sweep them) and ``slip_speeds``: slip at two or more
    speeds (a speed sweep of the free-rolling wheel does not count)."""
    cond = dict(conditions(data))
    if len(data) == 0:
        return dict(cond, **{k: False for k in _SWEEPS})
    sl, sa = data.array("SL"), data.array("SA")
    both = (np.abs(sl) > _KAPPA_TOL) & (np.abs(sa) > _ALPHA_TOL)
    rl = data.array("RL") if data.has("RL") else (data.array("RHO") if data.has("RHO") else None)
    fz = data.array("FZ")
    deflect = rl is not None and _swept(fz[np.isfinite(rl)], 0.02 * float(np.max(np.abs(fz))))
    slipping = (np.abs(sl) > _KAPPA_TOL) | (np.abs(sa) > _ALPHA_TOL)
    return dict(cond, slip_ratio=_swept(sl, _KAPPA_TOL), slip_angle=_swept(sa, _ALPHA_TOL),
                combined=_swept(sl[both], _KAPPA_TOL), deflection=bool(deflect),
                slip_speeds=_spread(data.array("VX")[slipping]))


_KAPPA_TOL, _ALPHA_TOL = 0.005, math.radians(0.25)


def _spread(vx) -> bool:
    """Speeds that differ: the 5-95 % range beyond 1 m/s and 10 % of the median (a rig holds its speed to a few
    cm/s, which a level count would split into levels)."""
    vx = np.abs(vx[np.isfinite(vx)])
    if vx.size < 2:
        return False
    lo, hi = np.percentile(vx, [5, 95])
    return bool(hi - lo > max(1.0, 0.1 * float(np.median(vx))))


def stage_data(stage_name: str, data: TyreData) -> TyreData:
    """The rows the gap finder refits a stage on: wider than the fitting stage's (:func:`stage_rows`), since the
    gap finder starts from a complete model: every row whose channel the stage's functions shape."""
    stage = STAGES[stage_name]
    if stage_name == "vertical":
        rows = np.isfinite(data.array("FZ"))
        rl = data.array("RL") if data.has("RL") else (data.array("RHO") if data.has("RHO") else None)
        rows = rows & np.isfinite(rl) if rl is not None else np.zeros(len(data), bool)
    elif stage_name in _OTHER_PURE:
        # the combined-slip functions also shape the pure-slip sweeps of the other direction: Fy at alpha = 0
        # under kappa (kappa-induced side force, RVY*), Fx at kappa = 0 under alpha, Mz via s Fx
        other = np.abs(data.array(_OTHER_PURE[stage_name][0])) > _OTHER_PURE[stage_name][1]
        rows = (stage_rows(stage, data) | other) & np.isfinite(data.array(stage.channel)) \
            if stage.channel in data else np.zeros(len(data), bool)
    elif stage_name in _ZERO_OTHER:
        # the pure-slip stage on every row without the other slip: free rolling included (camber thrust,
        # residual torque, shifts at zero slip)
        ch, tol = _ZERO_OTHER[stage_name]
        rows = (np.abs(data.array(ch)) <= tol) & np.isfinite(data.array(stage.channel)) \
            if stage.channel in data else np.zeros(len(data), bool)
    elif stage_name in ("mx", "my"):
        rows = np.isfinite(data.array(stage.channel)) if stage.channel in data else np.zeros(len(data), bool)
    else:
        rows = stage_rows(stage, data)
    return data.select(rows)


_ZERO_OTHER = {"pure_fx": ("SA", math.radians(0.25)), "pure_fy": ("SL", 0.005), "mz": ("SL", 0.005)}


_OTHER_PURE = {"combined_fx": ("SA", math.radians(0.25)), "combined_fy": ("SL", 0.005),
               "mz_combined": ("SL", 0.005)}


def _is_active(name: str, prm, turn_slip: bool) -> bool:
    if name in BASE:
        return True
    if name in TURN_SLIP_BASE:
        return turn_slip
    for e in CATALOGUE.values():
        if name not in e.parameters:
            continue
        if name in e.neutral:          # a switch: active when away from its neutral value
            if not at_neutral(prm[name], e.neutral[name]):
                return True
        elif effect_state(e, prm) == "active":   # a shape factor of an effect that is switched on
            return True
    return False


def at_neutral(value, neutral) -> bool:
    return abs(float(value) - neutral) <= 1e-12 * max(1.0, abs(neutral))


def active_parameters(prm, turn_slip: bool = False) -> set:
    """The parameters active in a parameter set: base parameters, switches away from their neutral values and the
    shape factors of effects that are switched on."""
    return {n for n in PARAM_STAGE if n in PARAMETERS and prm.version in PARAMETERS[n].versions
            and _is_active(n, prm, turn_slip)}


def stage_names(stage_name: str, prm, sub: TyreData, turn_slip: bool, extra=(), active=None) -> list:
    """Active parameters of a stage that its data determine (``active``: the active set, default that of
    ``prm``; ``extra``: parameters to add to it)."""
    cond = data_conditions(sub)
    ts = turn_slip and bool(np.any(sub.array("PHIT") != 0))
    out = []
    for n, st in PARAM_STAGE.items():
        if st != stage_name or prm.version not in _versions(n):
            continue
        needs = parameter_needs(n)
        act = _is_active(n, prm, turn_slip) if active is None else (n in active or n in BASE)
        if (act or n in extra) and needs_met(needs, cond, ts):
            out.append(n)
    return out


def _versions(n):
    return PARAMETERS[n].versions


def refit_stages(params, data: TyreData, stages=FAIR_STAGES, *, turn_slip: bool = False, channels=None,
                 max_nfev: int | None = None, progress=None, extra=(), active=None, min_points: int = 10, baseline=None, judge=None):
    """Fair start: refit the active parameters stage by stage (stages with at least ``min_points`` rows, more
    than their parameters); returns (parameters, {stage: RefitResult}). A stage is kept only when
    :func:`mftyre.fit.verify.verify_tir` finds no problem in the data's domain that ``baseline`` (default
    ``params``) does not have, and when ``judge(old, new)`` (e.g. the held-out errors, never worse) returns no
    reason against it."""
    prm = params.params if isinstance(params, MFModel) else params
    given = prm if baseline is None else baseline
    results = {}
    for name in stages:
        stage = STAGES[name]
        if channels is not None and stage.channel not in channels:
            continue
        sub = stage_data(name, data)
        if len(sub) < min_points:
            continue
        names = stage_names(name, prm, sub, turn_slip, extra, active)
        if not names or len(sub) <= len(names):
            continue
        ev = Evaluator(sub, channels=[stage.channel], turn_slip=turn_slip)
        if stage.channel not in ev.channels:
            continue
        if progress:
            progress(f"fair start: {name}: {len(names)} parameters on {len(sub)} points")
        new, results[name] = refit(prm, ev, names, max_nfev=max_nfev)
        problems = verify_tir(new, data, baseline=given)
        if problems:   # the stage's values would make the .tir implausible where there are no data: keep the previous
            results[name].success, results[name].values = False, {k: float(prm[k]) for k in names}
            results[name].problems = problems
            if progress:
                progress(f"fair start: {name} rejected, the previous values kept: " + "; ".join(problems))
            continue
        worse = judge(prm, new) if judge is not None else None
        if worse:      # e.g. worse on held-out data than the values as given: keep those
            results[name].success, results[name].values = False, {k: float(prm[k]) for k in names}
            results[name].problems = (worse,)
            if progress:
                progress(f"fair start: {name}: the previous values kept: {worse}")
            continue
        prm = new
    return prm, results
