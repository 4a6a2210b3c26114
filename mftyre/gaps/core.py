"""The gap-finder workflow: fair start, locate, name, add, show (see :mod:`mftyre.gaps`)."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy import stats

from ..data import TyreData
from ..files import write_atomically
from ..fit.core import load_data
from ..fit.metrics import normalised_rms
from ..fit.verify import verify_tir
from ..inputs import warn_data_outside
from ..fit.stages import SKIP_REASONS as _STAGE_REASONS  # the stages' own wording
from ..fit.stages import STAGES, conditions
from ..model import MFModel, load_tir
from ..programme import recognise
from ..timeseries import effective_samples, needs_reduction, reduce_sweeps
from ..tir import write_tir
from .catalogue import CATALOGUE, PARAM_STAGE, Effect, effect_state, parameter_needs
from .drift import FRICTION_DRIFT, tyre_of, with_progress
from .locate import locate
from .refit import FAIR_STAGES, SWEEP_REASONS, at_neutral, active_parameters, covariance, standard_errors, stage_data, data_conditions, needs_met, refit, refit_stages
from .residuals import Evaluator, sweep_labels, holdout_mask, noise_floor_of, noise_levels, noise_of_means
from .transient import sweep_hysteresis
from .search import Candidate, judge, search
from .small import SMALL_DATA, aicc, fit_all, loo_errors, weighted_rss

__all__ = ["find_gaps", "GapReport", "AddedEffect", "Candidate"]


@dataclass
class AddedEffect:
    name: str
    description: str
    parameters: dict          # name -> {"value", "stderr", "meaning"}
    held_out_gain: float
    held_out_gain_by_channel: dict
    p_value: float
    score: float
    round: int
    note: str = ""

    def to_dict(self) -> dict:
        return dict(name=self.name, description=self.description,
                    parameters=[dict(name=k, **v) for k, v in self.parameters.items()],
                    held_out_gain=self.held_out_gain, held_out_gain_by_channel=self.held_out_gain_by_channel,
                    p_value=self.p_value, score=self.score, round=self.round, note=self.note)


class GapReport:
    """The outcome of :func:`find_gaps`.

    ``model_given``, ``model_start`` (after the fair start), ``model`` (improved); ``effects_added``
    (:class:`AddedEffect` list, the tyre's); ``nuisances``: effects of the measurement named and fitted, not the
    tyre's and not in the .tir (:data:`mftyre.gaps.drift.FRICTION_DRIFT`); ``findings_before`` / ``findings_after`` (:class:`mftyre.gaps.Finding` lists, on the
    training data); ``error_given`` / ``error_before`` / ``error_after``: channel -> normalised RMS [%] on the held-out
    data (given model, fair start, improved); ``noise``: channel -> (sigma, method); ``rounds``: per round the
    candidates tried; ``untestable``: effect -> reason; ``message``: the verdict in one sentence.
    ``to_dict()``/``to_json(path)``, ``markdown()``, ``save(report_dir)`` (Markdown + PNG), ``write_tir(path)``.
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)

    @property
    def effect_names(self) -> list:
        return [e.name for e in self.effects_added]

    #: channels the model has no equations for (its output 0 everywhere): "not fitted", never an error of 100 %
    not_modelled: tuple = ()

    def shrink(self) -> dict:
        """Channel -> relative decrease of the held-out error, (before - after) / before."""
        return {c: (self.error_before[c] - self.error_after[c]) / self.error_before[c]
                for c in self.error_before if self.error_before[c] > 0}

    def held_out_error(self, model) -> dict:
        """Channel -> normalised RMS error [%] of any ``model`` (e.g. the true one) on the held-out points."""
        ev, mask = self.evaluator, self.test_mask
        pred = ev.predict(model)
        return {c: normalised_rms(pred[c][mask[ev.rows[c]]], ev.measured[c][mask[ev.rows[c]]]) for c in pred}

    def to_dict(self) -> dict:
        return dict(
            message=self.message,
            effects_added=[e.to_dict() for e in self.effects_added],
            nuisances=[e.to_dict() for e in self.nuisances],
            error_given=self.error_given, error_before=self.error_before, error_after=self.error_after,
            error_train_before=self.error_train_before, error_train_after=self.error_train_after,
            findings=[f.to_dict() for f in self.findings_before],
            findings_after=[f.to_dict() for f in self.findings_after],
            noise={c: dict(sigma=s, method=m) for c, (s, m) in self.noise.items()},
            rounds=[[c.to_dict() for c in r] for r in self.rounds],
            untestable=self.untestable, rejected=self.rejected, transient=self.transient, programme=self.programme,
            reduction=self.reduction, data=self.data_summary, seconds=self.seconds,
        )

    def to_json(self, path=None) -> str:
        import json

        text = json.dumps(_jsonable(self.to_dict()), indent=2)
        if path is not None:
            write_atomically(path, text)
        return text

    def markdown(self, plot_names: dict | None = None) -> str:
        from .report import markdown_report

        return markdown_report(self, plot_names)

    def save(self, directory) -> Path:
        from .report import save_report

        return save_report(self, directory)

    def write_tir(self, path, *, overwrite: bool = False) -> Path:
        """Write the improved .tir; when nothing was added, the parameters as given, unchanged (not the fair-start
        refit the search started from: it only served to judge candidates), with the given file's header comments
        (a fitted file's provenance) kept."""
        given = self.model_given.params
        if not self.effects_added and not self.nuisances:
            header = _header_comments(given.source)
            return write_tir(given, path, overwrite=overwrite, comments=[
                f"mftyre gaps: nothing added; the parameters of {Path(str(given.source)).name if given.source else 'the given model'}"
                " unchanged", *header])
        return write_tir(self.model.params, path, overwrite=overwrite, comments=[
            "mftyre gaps: effects added to " + (Path(str(given.source)).name if given.source else "the given model")
            + ": " + ", ".join(self.effect_names + [e.name for e in self.nuisances])])

    def __repr__(self):
        return f"GapReport(effects_added={self.effect_names}, error_before={_round(self.error_before)}, " \
               f"error_after={_round(self.error_after)})"


def _header_comments(source) -> list:
    """The ``!`` comment lines of a .tir file's header (before its first section after [MDI_HEADER]): the provenance
    a fitted file carries; [] when there is no readable file."""
    try:
        lines = Path(str(source)).read_text(encoding="utf-8", errors="replace").splitlines()
    except (OSError, TypeError, ValueError):
        return []
    out = []
    for line in lines[:200]:
        if line.startswith("[") and "MDI_HEADER" not in line.upper():
            break
        if line.startswith("!") and line.strip("! ") and "Written by mftyre" not in line and \
                not line.startswith(("! Source:", "! Model:")):
            out.append(line[1:].strip())
    return out


def _round(d):
    return {k: round(v, 3) for k, v in d.items()}


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return None if not math.isfinite(float(x)) else float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def _errors(ev: Evaluator, prm) -> dict:
    pred = ev.predict(prm)
    return {c: normalised_rms(pred[c], ev.measured[c]) for c in pred}


def _chi2(ev: Evaluator, prm, sigma, channels) -> float:
    res = ev.residuals(prm, channels)
    return float(sum(np.sum(np.where(np.isfinite(r), r, 1e3 * sigma[c][0]) ** 2) / sigma[c][0] ** 2
                     for c, r in res.items()))


#: Candidates retried with their stages refitted when none is significant alone.
DEEP_RETRIES = 3
#: Bins per sweep when a time series is reduced (per branch; fewer points, faster refits, the same curves).
REDUCED_BINS = 15
#: Held-out sweeps (that the candidate changes by more than the noise, sum of (change/sigma)^2 >= 1) needed for
#: the test by whole sweeps.
MIN_HELD_OUT_SWEEPS = 8
#: One-sided level of the held-out test by whole sweeps (the training F test carries the family-wise alpha).
HELD_OUT_ALPHA = 0.05


def f_test(chi2_before: float, chi2_after: float, n: int, n_eff: float, k: int):
    """(F, p) of the chi-square decrease from freeing ``k`` parameters, with ``n`` residuals of which ``n_eff`` are
    independent: the decrease counts n_eff / n of its size (correlated residuals repeat the same information) and
    the residual variance per degree of freedom is at least the noise's (chi2 per dof >= 1)."""
    denom = max(chi2_after / max(n - k, 1), 1.0)
    fstat = max(chi2_before - chi2_after, 0.0) * (n_eff / max(n, 1)) / k / denom
    return fstat, float(stats.f.sf(fstat, k, max(n_eff - k, 1)))


def _sweep_ids(ev: Evaluator, c: str) -> np.ndarray:
    return sweep_labels(ev.data)[ev.rows[c]]


def _n_eff(ev: Evaluator, prm, channels, series: bool = True) -> float:
    """Effective number of independent residuals on ``channels``: point data (one row per condition, or binned
    means of a time series: ``series=False``) have independent noise, so every row counts; in a time series the
    AR(1) rule within sweeps on the residual of ``prm``, the candidate model (what is left when the effect is in:
    the noise), never on the residual the candidate is to explain."""
    res = ev.residuals(prm, channels)
    if not series:
        return float(sum(np.count_nonzero(np.isfinite(r)) for r in res.values()))
    return float(sum(effective_samples(res[c], _sweep_ids(ev, c)) for c in res))


def _n_eff_of_residual(ev: Evaluator, prm, channels) -> float:
    """The AR(1) count from the residual of ``prm`` itself (the model lacking the effect): shown beside the honest
    figure, since a missing effect makes that residual smooth and this count collapse."""
    res = ev.residuals(prm, channels)
    return float(sum(effective_samples(res[c], _sweep_ids(ev, c)) for c in res))


def _sweep_test(ev: Evaluator, before, after, sigma, channels):
    """(p value, sweeps) of the one-sided Wilcoxon signed-rank test that the chi-square decrease per held-out
    sweep is positive: whole sweeps are the independent units (samples within a sweep are not), and the rank test
    is not carried by a few sweeps with large decreases."""
    r0, r1 = ev.residuals(before, channels), ev.residuals(after, channels)
    dec, change = {}, {}
    for c in r0:
        s = sigma[c][0]
        a, b = np.nan_to_num(r0[c], nan=1e3 * s), np.nan_to_num(r1[c], nan=1e3 * s)
        for sw, v, w in zip(_sweep_ids(ev, c), (a**2 - b**2) / s**2, ((a - b) / s) ** 2):
            dec[sw] = dec.get(sw, 0.0) + v
            change[sw] = change.get(sw, 0.0) + w
    # only sweeps the candidate changes by more than the noise could show
    d = np.array([v for sw, v in dec.items() if change[sw] >= 1.0])
    if d.size < 3:
        return (0.0 if d.size and np.all(d > 0) else 1.0), int(d.size)
    return float(stats.wilcoxon(d, alternative="greater").pvalue), int(d.size)


def _prune(new, current, e: Effect, names, ev: Evaluator, sigma, alpha: float, series: bool = True):
    """(parameters, kept names, note): a candidate parameter whose standard error (from the effective number of
    samples) exceeds its size goes back to its value before the effect (switches: neutral), the rest refitted; one
    more than 0.99 correlated with another goes back too unless that raises the training chi-square significantly
    (F test on n_eff at ``alpha``: the data do tell them apart). One at a time, shape factors before switches; no
    switch left: kept = []."""
    names, notes, needed = list(names), [], set()
    ch = [c for c in e.channels if c in ev.channels]
    while names:
        n_eff = _n_eff(ev, new, ch, series)
        se, corr = covariance(new, ev, names, ch, sigma, n_eff)
        ref = {k: e.neutral[k] if k in e.neutral else float(current[k]) for k in names}
        # a switch's size is its distance from the neutral value, a shape factor's its value
        size = {k: abs(float(new[k]) - e.neutral[k]) if k in e.neutral else abs(float(new[k])) for k in names}
        ratio = {k: (math.inf if se[k] is None else se[k] / max(size[k], 1e-300)) for k in names}
        correlated = {}
        for i, j in zip(*np.triu_indices(len(names), 1)):
            a, b = names[i], names[j]
            if abs(corr[i, j]) > 0.99 and not {a, b} <= needed:   # the shape factor first, else the less certain
                worse = (b if b not in e.neutral else a) if (a in e.neutral) != (b in e.neutral) \
                    else (a if ratio[a] >= ratio[b] else b)
                if worse not in needed:
                    correlated[worse] = (b if worse == a else a, float(corr[i, j]))
        uncertain = [k for k in names if ratio[k] > 1.0]
        pick = uncertain or list(correlated)
        if not pick:
            break
        worst = max(pick, key=lambda k: (k not in e.neutral, ratio[k]))
        trial = new.replace(**{worst: ref[worst]})
        rest = [k for k in names if k != worst]
        if rest:
            trial, _ = refit(trial, ev, rest, ch, sigma)
        if worst not in uncertain:
            c0, c1 = _chi2(ev, new, sigma, ch), _chi2(ev, trial, sigma, ch)
            n = sum(ev.measured[c].size for c in ch)
            f = max(c1 - c0, 0.0) * n_eff / max(n, 1) / max(c0 / max(n - len(names), 1), 1.0)
            if float(stats.f.sf(f, 1, max(n_eff - len(names), 1))) < alpha:
                other, r = correlated[worst]
                needed |= {worst, other}
                notes.append(f"{worst} kept although {r:+.3f} correlated with {other}: resetting it raises the "
                             f"training chi-square from {c0:.0f} to {c1:.0f}")
                continue
            why = f"{correlated[worst][1]:+.3f} correlated with {correlated[worst][0]}"
        else:
            why = "standard error larger than its size" if se[worst] is not None else "undetermined"
        notes.append(f"{worst} reset to {ref[worst]:.4g} ({why})")
        names, new = rest, trial
        if not any(k in e.neutral for k in names):
            return new, [], "no switch of the effect is determined: " + "; ".join(notes)
    return new, names, "; ".join(notes)


def _identifiable(effect: Effect, prm, data: TyreData, turn_slip: bool):
    """(parameters the data determine, {parameter: reason})."""
    keep, why = [], {}
    for n in effect.parameters:
        stage = PARAM_STAGE.get(n)
        sub = stage_data(stage, data) if stage in STAGES else data
        cond = data_conditions(sub)
        ts = turn_slip and bool(np.any(sub.array("PHIT") != 0))
        needs = tuple(parameter_needs(n)) + tuple(effect.needs)
        if len(sub) == 0:
            why[n] = f"no data for the {stage} stage"
        elif needs_met(needs, cond, ts):
            keep.append(n)
        else:
            missing = [x for x in needs if not needs_met((x,), cond, ts)]
            why[n] = "; ".join(SKIP_REASONS.get(x, "needs " + x) for x in missing)
    # the switches must be determinable, or the effect cannot be switched on
    if not any(n in keep for n in effect.neutral):
        return [], why
    return keep, why


SKIP_REASONS = dict(_STAGE_REASONS, **SWEEP_REASONS, turn_slip="no turn slip in the data")


def _numbered(reduced: TyreData) -> TyreData:
    """Reduced data with every steady point (SWEEP -1: one mean per steady segment) a sweep of its own, so that
    held-out sweeps and repeats are counted per test."""
    frame = reduced.frame.copy()
    sweep = frame["SWEEP"].to_numpy().copy()
    steady = sweep < 0
    sweep[steady] = sweep.max(initial=-1) + 1 + np.arange(int(steady.sum()))
    frame["SWEEP"] = sweep
    return reduced.with_frame(frame, "steady points numbered as sweeps")


def _summary(data: TyreData) -> dict:
    c = conditions(data)
    return dict(points=len(data), source=data.source, tyre=data.tyre, loads=c["loads"], pressures=c["pressures"],
                speeds=c["speeds"], camber=c["camber"], turn_slip=bool(np.any(data.array("PHIT") != 0)))


def _candidates(pool, given, train: TyreData, ts: bool):
    """({name: (effect, parameters the data determine, {parameter: why not})}, {untestable name: reason}) of the
    absent (or partly absent) effects of ``pool``."""
    untestable, candidates = {}, {}
    for e in pool:
        state = effect_state(e, given)
        if state == "unavailable":
            continue
        if state == "active":
            # partly switched on: the switches still at their neutral values are the candidate
            off = [n for n in e.neutral if at_neutral(given[n], e.neutral[n])]
            if not off:
                continue
            e = replace(e, parameters=tuple(off), neutral={n: e.neutral[n] for n in off})
        keep, why = _identifiable(e, given, train, ts)
        if not keep:
            untestable[e.name] = "; ".join(f"{k}: {v}" for k, v in why.items()) or "not determinable"
            continue
        candidates[e.name] = (e, keep, why)
    return candidates, untestable


def _offer_drift(candidates, untestable, train: TyreData):
    """Offer :data:`mftyre.gaps.drift.FRICTION_DRIFT` where the friction shows: a slip sweep and Fx or Fy measured."""
    cond = data_conditions(train)
    if not (cond["slip_angle"] or cond["slip_ratio"]):
        untestable[FRICTION_DRIFT.name] = "no slip sweep in the data: the friction does not show"
    elif not any(train.has(c) for c in ("FX", "FY")):
        untestable[FRICTION_DRIFT.name] = "neither FX nor FY measured"
    else:
        candidates[FRICTION_DRIFT.name] = (FRICTION_DRIFT, list(FRICTION_DRIFT.parameters), {})


def _find_small(data, given, start, fair, candidates, untestable, ev, ts, max_effects, t0, say) -> GapReport:
    """The small-data search (:mod:`mftyre.gaps.small`): forward selection by AICc and leave-one-out over all
    points; the report's "held-out" errors are the leave-one-out errors."""
    chans = list(ev.channels)
    names = sorted({k for r in fair.values() for k in r.names})
    n = int(sum(ev.measured[c].size for c in chans))
    scale = {c: float(np.sqrt(np.mean(ev.measured[c] ** 2))) or 1.0 for c in chans}
    prm = start
    crit = aicc(weighted_rss(ev, prm, chans, scale), n, len(names))
    loo = loo_errors(prm, data, names, chans)
    loo_start = dict(loo)
    rounds, added, rejected = [], [], {}
    while candidates and len(added) < max_effects:
        trials = []
        for e, keep, why in candidates.values():
            if not any(c in chans for c in e.channels):
                continue
            startv = {k: e.start.get(k, e.neutral.get(k, float(prm[k]))) for k in keep}
            new, _ = fit_all(prm, ev, names + list(keep), chans, start=startv)
            c_new = aicc(weighted_rss(ev, new, chans, scale), n, len(names) + len(keep))
            trials.append([e, keep, why, new, c_new, None])
        if not trials:
            break
        trials.sort(key=lambda t: t[4])
        for t in trials[:3]:   # leave-one-out for the best few by AICc
            t[5] = loo_errors(t[3], data, names + list(t[1]), chans)
        rnd = []
        for e, keep, why, new, c_new, loo_new in trials:
            before, after = (float(np.mean(list(loo.values()))), float(np.mean(list(loo_new.values())))) \
                if loo_new else (math.nan, math.nan)
            ok = loo_new is not None and c_new < crit - 2.0 and after < before
            rnd.append(Candidate(e.name, list(keep), crit, c_new, before, after, n, n, math.nan, math.nan,
                                 crit - c_new, (before - after) / before if before > 0 else 0.0, ok,
                                 {k: float(new[k]) for k in keep}, {},
                                 "AICc before/after in the chi2 columns, leave-one-out error [%] in the held-out "
                                 "columns"))
        rounds.append(rnd)
        best = None
        for t, c in zip(trials, rnd):
            if not c.significant:
                continue
            problems = verify_tir(t[3], data, baseline=given)
            if problems:
                c.significant = False
                rejected[c.name] = "the improved .tir fails verification: " + "; ".join(problems)
                say(f"rejected {c.name}: {rejected[c.name]}")
                continue
            best = t
            break
        if best is None:
            say("no effect lowers both AICc and the leave-one-out error")
            break
        e, keep, why, new, c_new, loo_new = best
        by_ch = {c: (loo[c] - loo_new[c]) / loo[c] for c in loo_new if loo[c] > 0}
        added.append(AddedEffect(e.name, e.description, {k: dict(value=float(new[k]), stderr=None,
                                                                 meaning=e.parameter_descriptions()[k])
                                                        for k in keep},
                                 rnd[trials.index(best)].held_out_gain, by_ch, math.nan,
                                 crit - c_new, len(rounds), f"AICc {crit:.1f} -> {c_new:.1f}"))
        say(f"added {e.name}: AICc {crit:.1f} -> {c_new:.1f}; leave-one-out error "
            + ", ".join(f"{c} {loo[c]:.2f} -> {loo_new[c]:.2f} %" for c in loo_new))
        prm, crit, loo = new, c_new, loo_new
        names += list(keep)
        del candidates[e.name]
    # noise: the residual standard deviation of the selected model; standard errors of all fitted parameters
    k = len(names)
    res = ev.residuals(prm, chans)
    sigma = {c: (float(math.sqrt(np.sum(res[c] ** 2) / max(res[c].size - k, 1))),
                 f"residual of the selected model ({res[c].size} points, {k} parameters)") for c in chans}
    se = standard_errors(prm, ev, names, chans, sigma)
    for a in added:
        for p in a.parameters:
            a.parameters[p].update(value=float(prm[p]), stderr=se.get(p))
    message = ("small data: " + (f"added {len(added)} effect(s): {', '.join(a.name for a in added)}" if added
                                 else "no effect lowers both AICc and the leave-one-out error; nothing added"))
    say(message)
    err_all = _errors(ev, prm)
    return GapReport(
        model_given=MFModel(given), model_start=MFModel(start), model=MFModel(prm), effects_added=added,
        findings_before=[], findings_after=[], error_given=_errors(ev, given), error_before=loo_start,
        error_after=loo, error_train_before=_errors(ev, start), error_train_after=err_all, noise=sigma,
        rounds=rounds, untestable=untestable, rejected=rejected, message=message, data=data,
        test_mask=np.ones(len(data), bool), transient=[], nuisances=[], programme=None, reduction=None,
        evaluator=ev, data_summary=_summary(data), seconds=time.perf_counter() - t0, turn_slip=ts,
        small_data=True, parameter_stderr=se)


@dataclass
class _Run:
    """What every phase of one gap-finder run reads: the data (reduced when a time series), the split into
    training and held-out sweeps, their evaluators and the settings."""

    data: TyreData
    raw: TyreData
    reduction: object
    programme: object
    given: object
    ts: bool
    series: bool               # a time series (correlated noise), not point data
    small: bool
    test_mask: np.ndarray
    train: TyreData
    ev_train: Evaluator
    ev_test: Evaluator
    ev_all: Evaluator
    alpha: float
    max_nfev: int | None
    say: object
    t0: float


def _prepare(data, model, holdout, seed, channels, turn_slip, alpha, max_nfev, say, t0) -> _Run:
    """Read the data and the model, reduce a time series to binned means, hold out whole sweeps."""
    data = load_data(data)
    programme = recognise(data)
    say("test programme: " + programme.summary())
    data = with_progress(data)   # the run's progress (TIME or row order), for the friction drift
    raw, reduction = data, None
    if needs_reduction(data, programme):
        reduction = reduce_sweeps(data, programme, bins=REDUCED_BINS)
        say(reduction.summary())
        data = _numbered(reduction.mean)
    if isinstance(model, (str, Path)):
        model = load_tir(model)
    if not isinstance(model, MFModel):
        model = MFModel(model)
    warn_data_outside(model, data.inputs(), f"{data.source or 'the data'} against the given model")
    ts = bool(np.any(data.array("PHIT") != 0)) if turn_slip is None else bool(turn_slip)
    # point data (one row per condition, or binned means) have independent noise; a time series has not
    series = reduction is None and programme.sample_rate is not None
    small = len(data) < SMALL_DATA
    test_mask = np.zeros(len(data), bool) if small else holdout_mask(data, holdout, seed)
    train, test = data.select(~test_mask), data.select(test_mask)
    if len(test) == 0:
        test = train
    ev_train = Evaluator(train, channels, ts)
    ev_test = Evaluator(test, ev_train.channels, ts)
    ev_all = Evaluator(data, ev_train.channels, ts)
    say(f"{len(train)} training points, {len(test)} held-out points (whole sweeps); channels "
        f"{' '.join(ev_train.channels)}")
    return _Run(data, raw, reduction, programme, model.params, ts, series, small, test_mask, train, ev_train,
                ev_test, ev_all, alpha, max_nfev, say, t0)


def _fair_start(run: _Run):
    """(start, {stage: result}, active parameters): the stages refitted to the training data, never worse on the
    held-out data than the values as given; ``active``: what the given model has switched on."""
    active = active_parameters(run.given, run.ts)

    def held_out_worse(old, new):
        before, after = _errors(run.ev_test, old), _errors(run.ev_test, new)
        worse = [f"{c} {before[c]:.3g} -> {after[c]:.3g} %" for c in before if after[c] > before[c] * (1 + 1e-9)]
        return "worse on the held-out data (" + ", ".join(worse) + ")" if worse else None

    start, fair = refit_stages(run.given, run.train, turn_slip=run.ts, channels=run.ev_train.channels,
                               max_nfev=run.max_nfev, progress=run.say, active=active,
                               min_points=2 if run.small else 10, judge=None if run.small else held_out_worse)
    return start, fair, active


def _noise(run: _Run, start) -> dict:
    """Channel -> (sigma, method): the measurement noise (of the binned means for a reduced time series)."""
    sigma = noise_levels(run.ev_train, run.ev_train.residuals(start))
    if run.reduction is not None:
        sigma.update(noise_of_means(run.raw, run.programme, run.data, run.ev_train.channels,
                                    float(run.given.VERTICAL_STIFFNESS)))
    run.say("noise: " + ", ".join(f"{c} {s:.3g}" for c, (s, _) in sigma.items()))
    return sigma


class _Search:
    """The naming and adding phase: rounds of candidate effects against the current model ``prm``."""

    def __init__(self, run: _Run, start, sigma: dict, candidates: dict, active: set):
        self.run, self.prm, self.sigma, self.candidates, self.active = run, start, sigma, candidates, active
        self.start = start
        self.rounds, self.added, self.added_effects, self.rejected = [], [], {}, {}
        self.n_test_rows = {c: run.ev_test.measured[c].size for c in run.ev_test.channels}

    def polish(self, new, e: Effect, names, free: bool = True, active=None):
        """Refit from ``new``: the stages of the effect's parameters ``names`` and of its channels, with those
        parameters active (``free=False``: held, the same stages refitted without them; ``active``: the active
        set, default the current one); a nuisance's own coefficients (no stage's) are refitted after the stages;
        kept when it lowers the training chi-square."""
        run = self.run
        stages = [st for st in FAIR_STAGES if st in {PARAM_STAGE.get(k) for k in names}
                  or STAGES[st].channel in e.channels]
        polished, _ = refit_stages(new, run.train, stages, turn_slip=run.ts, channels=run.ev_train.channels,
                                   max_nfev=run.max_nfev, extra=tuple(names) if free else (),
                                   active=self.active if active is None else active,
                                   baseline=run.given)
        own = [k for k in names if k not in PARAM_STAGE] if free else []
        if own:   # a nuisance's coefficients belong to no stage: refitted around the refitted stages
            polished, _ = refit(polished, run.ev_train, own, [c for c in e.channels if c in run.ev_train.channels],
                                self.sigma, max_nfev=run.max_nfev)
        chans = run.ev_train.channels
        if _chi2(run.ev_train, polished, self.sigma, chans) <= _chi2(run.ev_train, new, self.sigma, chans):
            return polished
        return new

    def score(self, e: Effect, keep, why, new, stderr, m, extra_note="", ref=None, ref_test=None):
        """Training F test and held-out score of a candidate model ``new`` against the current ``prm``.

        The training F test counts the effective number of independent residuals (n_eff, from the noise) rather
        than rows, and so does the held-out score (chi-square decrease x n_eff / n - k ln n_eff, a BIC-type
        penalty); with enough held-out sweeps the held-out test is also by whole sweeps: the chi-square decrease
        of each held-out sweep, a one-sided signed-rank test (so a gain a few sweeps carry, or 7.120 -> 7.119 %,
        is not significant). ``ref``: the model it is compared with (default the current one); ``ref_test``: on the
        held-out data (default ``ref``)."""
        run, sigma, prm = self.run, self.sigma, self.prm if ref is None else ref
        prm_test = prm if ref_test is None else ref_test
        ev_train, ev_test = run.ev_train, run.ev_test
        ch = [c for c in e.channels if c in ev_train.channels]
        k = len(keep)
        c_tr0, c_tr1 = _chi2(ev_train, prm, sigma, ch), _chi2(ev_train, new, sigma, ch)
        c_te0, c_te1 = _chi2(ev_test, prm_test, sigma, ch), _chi2(ev_test, new, sigma, ch)
        n_tr = int(sum(ev_train.measured[c].size for c in ch))
        n_te = int(sum(self.n_test_rows[c] for c in ch))
        n_eff = _n_eff(ev_train, new, ch, run.series)
        fstat, p = f_test(c_tr0, c_tr1, n_tr, n_eff, k)
        n_eff_te = _n_eff(ev_test, new, ch, run.series)
        sc = (c_te0 - c_te1) * n_eff_te / max(n_te, 1) - k * math.log(max(n_eff_te, 2.0))
        gain = (c_te0 - c_te1) / c_te0 if c_te0 > 0 else 0.0
        p_sweeps, n_sweeps = _sweep_test(ev_test, prm_test, new, sigma, ch)
        # the test by whole sweeps where there are enough changed held-out sweeps (a rank test without a p: failed)
        p_held = (p_sweeps if p_sweeps == p_sweeps else 1.0) if n_sweeps >= MIN_HELD_OUT_SWEEPS else math.nan
        sig = not judge(p, run.alpha / m, p_held, HELD_OUT_ALPHA, sc)
        note = "; ".join([f"{k2} not freed ({v})" for k2, v in why.items()] + ([extra_note] if extra_note else []))
        return (Candidate(e.name, list(keep), c_tr0, c_tr1, c_te0, c_te1, n_tr, n_te, fstat, p, sc, gain, sig,
                          {k: float(new[k]) for k in keep}, stderr, note, n_eff, p_sweeps, n_sweeps,
                          _n_eff_of_residual(ev_train, prm, ch)), new)

    def trials(self, tried, round_no: int) -> list:
        """(candidate, model) of every effect in ``tried`` refitted alone, best score first; when
        none is significant, the strongest few again with their stages refitted around them (the fair start may
        have bent other parameters towards the missing effect), scored against the same stages refitted without
        them (what refitting alone gains is not the effect's)."""
        run, results = self.run, []
        ev_train = run.ev_train
        for i, (e, keep, why) in enumerate(tried):
            if not any(c in ev_train.channels for c in e.channels):
                continue
            run.say(f"round {round_no}: candidate {i + 1}/{len(tried)} {e.name} ({' '.join(keep)})")
            base = e.admit(self.prm)
            startv = {k: e.start.get(k, e.neutral.get(k, float(base[k]))) for k in keep}
            new, rr = refit(base, ev_train, keep, [c for c in e.channels if c in ev_train.channels],
                            self.sigma, start=startv, max_nfev=run.max_nfev)
            result = self.score(e, keep, why, new, rr.stderr, len(tried))
            if e.with_stages and result[0].p_value < run.alpha / len(tried) and result[0].score > 0:
                # worth the stages refitted around it: it explains the training data alone and gains held out
                result = self._score_with_stages(e, keep, why, new, rr.stderr, len(tried))
            results.append(result)
        if results and not any(r[0].significant for r in results):
            results.sort(key=lambda t: -t[0].score)
            deep = []
            for cand, new in results[:DEEP_RETRIES]:
                e = self.candidates[cand.name][0]
                if e.with_stages:
                    deep.append((cand, new))
                    continue
                run.say(f"round {round_no}: {e.name} with its stages refitted")
                deep.append(self._score_with_stages(e, cand.parameters, self.candidates[cand.name][2], new,
                                                    cand.stderr, len(tried)))
            results = deep + results[DEEP_RETRIES:]
        results.sort(key=lambda t: -t[0].score)
        return results

    def _score_with_stages(self, e: Effect, keep, why, new, stderr, m):
        """:meth:`score` of ``new`` with the stages of the effect refitted around it, against the same stages
        refitted without it (the gain of refitting alone is not the effect's); on the held-out data against the
        better of those and the current model (stages refitted freely can lose there what they gain in training:
        that loss is no gain of the effect either)."""
        new = self.polish(new, e, keep)
        base = self.polish(self.prm, e, keep, free=False)
        ch = [c for c in e.channels if c in self.run.ev_test.channels]
        ev_test = self.run.ev_test
        better = base if _chi2(ev_test, base, self.sigma, ch) <= _chi2(ev_test, self.prm, self.sigma, ch) else self.prm
        return self.score(e, keep, why, new, stderr, m, "scored with its stages refitted, against them refitted "
                          "without it", ref=base, ref_test=better)

    def verify(self, cand, new, m: int):
        """(model, '') when the significant candidate's determined parameters (:func:`_prune`) still explain the data
        and its .tir passes verification against the given one, else (model, the reason)."""
        run = self.run
        e = self.candidates[cand.name][0]
        if "stages refitted" not in cand.note:
            new = self.polish(new, e, cand.parameters)
        new, kept, why_not = _prune(new, self.prm, e, cand.parameters, run.ev_train, self.sigma, run.alpha,
                                    run.series)
        if kept and len(kept) < len(cand.parameters):
            # a partial effect: the parameters the data determine are added when they still pass the rule on what
            # is left (the effect as a whole passed the held-out test by sweeps; the rest stay at their values,
            # the note says which)
            again = self.score(e, kept, self.candidates[cand.name][2], new, cand.stderr, m, why_not)[0]
            if not judge(again.p_value, run.alpha / m, math.nan, HELD_OUT_ALPHA, again.score):
                why_not = f"partly added ({' '.join(kept)}): " + why_not
            else:
                kept, why_not = [], why_not + "; what is left is not significant"
        if not kept:
            return new, why_not
        problems = verify_tir(new, run.data, baseline=run.given)
        if problems:
            return new, "the improved .tir fails verification: " + "; ".join(problems)
        cand.parameters, cand.note = kept, "; ".join(x for x in (cand.note, why_not) if x)
        return new, ""

    def locate(self):
        return locate(self.run.ev_train, self.run.ev_train.residuals(self.prm), self.sigma, self.run.alpha)

    def say(self, text):
        self.run.say(text)

    def add(self, cand, new):
        """Make ``new`` the current model and record the effect with its held-out gain per channel."""
        run = self.run
        e = self.candidates[cand.name][0]
        before_err = _errors(run.ev_test, self.prm)
        se = standard_errors(new, run.ev_train, cand.parameters, e.channels, self.sigma)
        self.prm = new
        after_err = _errors(run.ev_test, new)
        by_ch = {c: (before_err[c] - after_err[c]) / before_err[c] for c in e.channels
                 if c in before_err and before_err[c] > 0}
        self.added.append(AddedEffect(e.name, e.description,
                                      {k: dict(value=float(new[k]), stderr=se.get(k),
                                               meaning=e.parameter_descriptions()[k]) for k in cand.parameters},
                                      cand.held_out_gain, by_ch, cand.p_value, cand.score, len(self.rounds),
                                      cand.note))
        run.say(f"added {e.name}: held-out chi2 {cand.chi2_test_before:.0f} -> {cand.chi2_test_after:.0f}")
        self.added_effects[e.name] = e
        self.active |= set(cand.parameters)

    def recheck(self):
        """Backward check of forward selection: an effect added before others is taken out again when, with the
        later ones in, it no longer passes the test it passed (its parameters back to their values before it, the
        stages of its channels refitted without it, compared with the final model). Early in the search a small
        effect can win while the fair start has bent other parameters towards a missing one."""
        run = self.run
        for a in list(self.added[:-1]):
            e = self.added_effects[a.name]
            names = list(a.parameters)
            without = self.prm.replace(**{k: e.neutral[k] if k in e.neutral else float(self.start[k]) for k in names})
            without = self.polish(without, e, names, free=False, active=self.active - set(names))
            cand = self.score(e, names, {}, self.prm, {}, 1, ref=without)[0]
            if cand.significant:
                continue
            self.prm = without
            self.added.remove(a)
            self.active -= set(names)
            self.rejected[e.name] = (f"added in round {a.round}, then taken out: with "
                                     f"{', '.join(x.name for x in self.added)} it is no longer significant "
                                     f"(held-out gain {cand.held_out_gain:.3g}, p {cand.p_value:.2g})")
            run.say(f"taken out {e.name}: {self.rejected[e.name]}")

    def search(self, findings, max_effects: int):
        """The one search (:func:`mftyre.gaps.search.search`) on this evidence, then the backward check and the
        final values and standard errors."""
        run = self.run
        search(self, self.candidates, findings, max_effects)
        self.recheck()
        if self.added:
            # final values and standard errors of every added parameter, jointly at the final model
            names = [k for a in self.added for k in a.parameters]
            chans = sorted({c for a in self.added for c in self.added_effects[a.name].channels
                            if c in run.ev_train.channels})
            se = standard_errors(self.prm, run.ev_train, names, chans, self.sigma)
            for a in self.added:
                for k in a.parameters:
                    a.parameters[k].update(value=float(self.prm[k]), stderr=se.get(k))


#: The held-out error a model may have, as a multiple of the error the measurement noise alone gives (the noise
#: floor), for the verdict "the model explains the data".
NOISE_MULTIPLE = 2.0


def _beyond_noise(errors: dict, floor: dict) -> dict:
    """Channel -> (held-out error, floor) [%] where the error exceeds :data:`NOISE_MULTIPLE` x the noise floor."""
    return {c: (e, floor[c]) for c, e in errors.items()
            if c in floor and np.isfinite(e) and e > NOISE_MULTIPLE * floor[c]}


def _verdict(findings_before, added, findings_after, transient, nuisances=(), beyond=None) -> str:
    """The outcome in one sentence. ``beyond``: channel -> (held-out error, noise floor) [%] where the error is
    more than :data:`NOISE_MULTIPLE` x the floor: then the data are not explained, whatever the residual tests say
    (their noise may be misjudged, or the structure too smooth for them)."""
    beyond = beyond or {}
    gap = ", ".join(f"{c} {e:.3g} % against a noise floor of {f:.3g} %" for c, (e, f) in beyond.items())
    if not findings_before and beyond:
        message = (f"no residual structure found by the tests, but the held-out error is more than "
                   f"{NOISE_MULTIPLE:g}x what the noise explains ({gap}): the model does NOT explain the data; "
                   "nothing added")
    elif not findings_before:
        message = ("the model already explains the data: no residual structure beyond measurement noise, the "
                   f"held-out error within {NOISE_MULTIPLE:g}x the noise floor in every channel; nothing added")
    elif not added:
        message = "residual structure found, but no catalogue effect explains it significantly on held-out data; " \
                  "nothing added" + ("" if not nuisances else " to the tyre")
    else:
        message = f"added {len(added)} effect(s): {', '.join(a.name for a in added)}" + (
            "; remaining structure: " + findings_after[0].text if findings_after else
            "; no significant residual structure remains")
    if nuisances:
        message += "; named in the measurement, not the tyre: " + ", ".join(a.description.split(":")[0]
                                                                           for a in nuisances)
    if transient:
        message += "; transient (named, not fitted): " + ", ".join(
            f"{t['channel']} up/down hysteresis +-{t['rms']:.3g} (relaxation length, {t['parameters']})"
            for t in transient)
    return message


def find_gaps(data, model, *, holdout: float = 0.25, seed: int = 0, alpha: float = 1e-3,
              max_effects: int = 5, channels=None, effects=None, turn_slip: bool | None = None,
              max_nfev: int | None = None, progress=None) -> GapReport:
    """Find where ``model`` and the measurements ``data`` disagree, name the missing effects, add them.

    ``data``: :class:`mftyre.data.TyreData` or a ``.tdx``/``.csv`` path; ``model``: :class:`mftyre.MFModel`,
    parameters or a ``.tir`` path. ``holdout``: fraction of the sweeps held out (whole sweeps); ``seed``: which;
    ``alpha``: family-wise significance level of the residual tests and of the candidate tests; ``max_effects``:
    at most this many effects are added; ``channels``: restrict to these channels (default all measured);
    ``effects``: restrict the candidates to these catalogue names (and ``"friction_drift"``, the nuisance of
    :mod:`mftyre.gaps.drift`, offered by default); ``turn_slip``: evaluate with turn slip
    (default: when the data have turn slip); ``max_nfev``: evaluations per refit; ``progress``: callable(text).

    Phases: prepare (split), fair start, noise, locate, name and add (:class:`_Search`), report.
    """
    say = progress or (lambda text: None)
    run = _prepare(data, model, holdout, seed, channels, turn_slip, alpha, max_nfev, say, time.perf_counter())
    start, fair, active = _fair_start(run)
    pool = [CATALOGUE[n] for n in (effects or CATALOGUE) if n != FRICTION_DRIFT.name]
    candidates, untestable = _candidates(pool, run.given, run.train, run.ts)
    if effects is None or FRICTION_DRIFT.name in effects:
        _offer_drift(candidates, untestable, run.train)
    if run.small:
        say(f"small data ({len(run.data)} rows): effects judged by AICc and leave-one-out over all points")
        return _find_small(run.data, run.given, start, fair, candidates, untestable, run.ev_all, run.ts,
                           max_effects, run.t0, say)
    sigma = _noise(run, start)
    transient = sweep_hysteresis(run.reduction, run.raw, MFModel(start), sigma, alpha)
    for t in transient:
        say("transient: " + t["text"])
    findings = locate(run.ev_train, run.ev_train.residuals(start), sigma, alpha)
    say(f"{len(findings)} significant findings" + (f"; strongest: {findings[0].text}" if findings else ""))
    search = _Search(run, start, sigma, candidates, active)
    search.search(findings, max_effects)
    return _report(run, start, search, findings, transient, untestable)


def _report(run: _Run, start, search: _Search, findings_before, transient, untestable) -> GapReport:
    prm, ev_train, ev_test = search.prm, run.ev_train, run.ev_test
    findings_after = locate(ev_train, ev_train.residuals(prm), search.sigma, run.alpha)
    added = [a for a in search.added if a.name != FRICTION_DRIFT.name]
    nuisances = [a for a in search.added if a.name == FRICTION_DRIFT.name]
    pred = ev_test.predict(prm)
    not_modelled = [c for c in pred if pred[c].size and not np.any(pred[c])]  # the model gives 0: no model of it
    errors = {c: e for c, e in _errors(ev_test, prm).items() if c not in not_modelled}
    beyond = _beyond_noise(errors, noise_floor_of(run.ev_all, run.test_mask, search.sigma))
    message = _verdict(findings_before, added, findings_after, transient, nuisances, beyond)
    run.say(message)
    return GapReport(
        model_given=MFModel(run.given), model_start=MFModel(start), model=MFModel(tyre_of(prm)),
        effects_added=added, nuisances=nuisances, findings_before=findings_before, findings_after=findings_after,
        error_given=_errors(ev_test, run.given), error_before=_errors(ev_test, start),
        error_after=_errors(ev_test, prm), error_train_before=_errors(ev_train, start),
        error_train_after=_errors(ev_train, prm), noise=search.sigma, rounds=search.rounds, untestable=untestable,
        rejected=search.rejected, message=message, data=run.data, test_mask=run.test_mask, transient=transient,
        programme=run.programme.summary(), reduction=run.reduction.summary() if run.reduction else None,
        evaluator=run.ev_all, data_summary=_summary(run.data), seconds=time.perf_counter() - run.t0,
        turn_slip=run.ts, small_data=False, not_modelled=not_modelled)
