"""The gap finder for dynamic tyre tests (cleat runs, step steer): the SWIFT wheel driven by the measured inputs,
compared with the measured axle forces; locate, name, add, show.

    from mftyre.gaps.dynamic import find_dynamic_gaps
    rep = find_dynamic_gaps("runs.csv", "base.tir")         # or a list of DynamicRun, an MFModel
    rep.effect_names, rep.error_before, rep.error_after, rep.noise
    rep.save("report/"); rep.write_tir("improved.tir")

Command line: ``mftyre gaps --dynamic DATA.csv --model BASE.tir [-o improved.tir] [--report DIR]``. Data layout:
:mod:`mftyre.gaps.dynamic_runs`.

1. *Align*: the measurement chain, common to all runs (one rig): a time delay of the outputs relative to the
   inputs, a causal Butterworth anti-alias filter (order 2 or 4, cutoff from a grid below Nyquist including
   "none": the data say which) and per channel the load cell's gain and offset drift (linear, :class:`Chain`),
   fitted by least squares to the given model's prediction, each channel weighted by its noise as the chi-square
   weighs it. They are nuisances: refitted with every candidate (from the best cell of each filter order, the
   delay and a continuous cutoff jointly with its parameters, the calibration projected out of every trial), so
   a candidate is credited only with what the chain cannot explain.
   One delay for all runs on purpose: a delay per run would absorb the very lags (relaxation, enveloping) the
   finder must see. Refitted after every effect added (the given model's errors bend it).
2. *Noise* from the data: in the quiet lead-in of every run (before the model's response departs from its level)
   the measured signal minus its mean is noise: its standard deviation per channel and its integrated
   autocorrelation time tau (samples), so that a run of n samples counts n/tau independent ones. Every
   chi-square below is sum(r^2)/(sigma^2 tau): from the noise, never from the residual being explained.
3. *Locate*: per run and channel the residual chi-square per independent sample against the noise variance (F test
   with the noise's own independent samples): a :class:`mftyre.gaps.locate.Finding` whose variable is the run's
   kind; the report also shows the engineers' features (:mod:`mftyre.gaps.dynamic_locate`: peaks, peak-to-peak,
   response length, lag and build-up distance, decay frequency and damping) measured beside model.
4. *Name and add*: the one search of the gap finder (:func:`mftyre.gaps.search.search`, the steady finder's loop)
   on the evidence of the runs (:class:`_Runs`). Candidates are the catalogue effects the runs can test
   (:mod:`mftyre.gaps.dynamic_catalogue`, the rest listed with the reason) whose run kinds and channels match a
   finding; they are screened by one Gauss-Newton step on the training runs (finite-difference sensitivity of the
   simulated histories), the most promising refitted with the chain. Whole runs are held out by the steady finder's
   rule (:func:`mftyre.gaps.residuals.stratified_holdout`: every manoeuvre, speed, load, pressure and road held out
   somewhere, none lost from the training runs). The acceptance rule is the steady finder's
   (:func:`mftyre.gaps.search.judge`): the training chi-square decrease significant (chi2(k), Bonferroni over the
   candidates screened), the held-out decrease significant too (chi2(k) at the same level) and material (at least
   :data:`MATERIAL` of the held-out chi-square above the noise). The best accepted candidate (held-out decrease) is
   verified: it builds, :func:`mftyre.fit.verify.verify_tir` finds no new problem, every run simulates to finite
   values, and the linearised SWIFT wheel at the static state of every condition has no mode growing faster than a
   damping ratio of -1 % that the given model lacks (eigenvalues of :meth:`swift.SwiftTyre.jacobian`; the given
   model's own growing modes are reported); failing, the next. Once added, the parameters of every effect added
   so far are refitted together (a later candidate is credited only with what they cannot explain). Repeat; then
   the steady finder's backward check: an effect added before others is taken out when, with them refitted
   without it, it no longer passes the rule (:meth:`_Runs.recheck`).
5. *Show*: RMS error per channel and condition before/after on the held-out runs beside the noise floor, features
   before/after, overlaid time histories (PNG), the improved .tir (never overwriting without ``overwrite``).
"""
from __future__ import annotations

import json
import math
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType

import lmfit
import numpy as np
from scipy import stats

from ..errors import DataError, ModelInputError
from .dynamic_catalogue import DYNAMIC_CATALOGUE, testable_effects
from .dynamic_locate import compare, features
from .dynamic_runs import (MODEL_KINDS, RUN_LEVELS, DynamicRun, RelaxedWheels, SwiftTyres, measurement_chain,
                           read_runs, road_layout, run_levels, simulate)
from .locate import Finding
from .search import Candidate, judge, matches, search

__all__ = ["find_dynamic_gaps", "DynamicGapReport", "Chain", "align", "align_task", "noise_from_data",
           "model_kind_for", "precision", "calibration", "values_text"]

#: Cutoffs [Hz] tried for the anti-alias filter (None: no filter).
CUTOFFS = (None, 400.0, 300.0, 250.0, 200.0, 150.0, 120.0, 100.0, 80.0, 60.0)
#: Highest cutoff of the anti-alias filter, as a share of the Nyquist frequency (a Butterworth design needs it below 1).
NYQUIST_SHARE = 0.95
#: Share of the held-out chi-square above the noise (chi2 - n/tau) an effect must explain to be added.
MATERIAL = 0.1
#: Candidates refitted fully per round (after the linearised screening).
REFIT_TOP = 3


#: Filter orders the alignment tries (causal Butterworth), and the largest calibration error of a load cell's gain
#: the chain may correct (1 +- GAIN_RANGE): beyond it a "gain" would be the tyre's, not the rig's.
ORDERS = (2, 4)
GAIN_RANGE = 0.05


@dataclass
class Chain:
    """The measurement chain, the nuisances fitted with every candidate: ``delay`` [s], ``cutoff`` [Hz] or None and
    ``order`` of the causal anti-alias filter (common to all runs: one rig), and per channel the calibration: the
    recorded signal is ``gain`` x (filtered, delayed true signal) + ``drift`` x (time since the run's start) (a
    load cell zeroed before the run whose offset drifts slowly; a constant offset would take the static load
    that sets the gain)."""

    delay: float = 0.0
    cutoff: float | None = None
    order: int = 4
    gain: dict = field(default_factory=dict)
    drift: dict = field(default_factory=dict)
    #: channel -> the least-squares gain where it lay beyond 1 +- :data:`GAIN_RANGE` and the gain was held at the
    #: bound (said in the report: the rest of the difference is left to the model)
    held: dict = field(default_factory=dict)

    def dynamics(self, y, dt):
        """The filter and the delay (no calibration)."""
        return measurement_chain(y, dt, self.cutoff, self.delay, self.order)

    def __call__(self, y, run, channel):
        """What the chain records of the true signal ``y`` of ``channel`` in ``run``."""
        return self.calibrate(self.dynamics(y, run.dt), run, channel)

    def calibrate(self, f, run, channel):
        return self.gain.get(channel, 1.0) * f + self.drift.get(channel, 0.0) * (run.t - run.t[0])

    def calibrated(self, runs, pred) -> "Chain":
        """This chain with each channel's gain and drift fitted to ``runs`` against the prediction
        ``pred`` (run -> channel -> array) by linear least squares (the gain kept within :data:`GAIN_RANGE`)."""
        return replace(self, **calibration([(r, c, self.dynamics(pred[r.name][c], r.dt)) for r in runs
                                            for c in r.measured]))


def calibration(filtered: list) -> dict:
    """dict(gain=, drift=) per channel from ``filtered`` ((run, channel, filtered and delayed model)):
    measured = gain f + drift (t - t0) in least squares; a gain beyond 1 +- :data:`GAIN_RANGE` is held at the bound
    and the drift refitted (``held``: channel -> the gain least squares gave there)."""
    out = dict(gain={}, drift={}, held={})
    for c in sorted({c for _, c, _ in filtered}):
        keys = [k for k in filtered if k[1] == c]
        f = np.concatenate([k[2] for k in keys])
        y = np.concatenate([k[0].measured[c] for k in keys])
        t = np.concatenate([k[0].t - k[0].t[0] for k in keys])
        ok = np.isfinite(y) & np.isfinite(f)
        if not ok.all():  # (masking only where needed: it costs 4x the least squares)
            f, y, t = f[ok], y[ok], t[ok]
        a = np.column_stack([f, t])
        coef = np.linalg.lstsq(a, y, rcond=None)[0]
        if not abs(coef[0] - 1.0) <= GAIN_RANGE:
            out["held"][c] = float(coef[0])
            g = float(np.clip(coef[0], 1.0 - GAIN_RANGE, 1.0 + GAIN_RANGE)) if np.isfinite(coef[0]) else 1.0
            coef = np.r_[g, np.linalg.lstsq(a[:, 1:], y - g * f, rcond=None)[0]]
        out["gain"][c], out["drift"][c] = (float(v) for v in coef)
    return out


#: Gains of a channel against the model beyond which it is no load cell's calibration but a wrong unit, axis,
#: channel or tyre file (:func:`check_scales`): an error, not a search.
PLAUSIBLE_GAIN = (0.5, 2.0)


def check_scales(chain) -> None:
    """:class:`DataError` where a channel's calibration in the aligned ``chain`` (its least-squares gain over the
    runs, :func:`calibration`, before it is held at 1 +- :data:`GAIN_RANGE`) lies outside :data:`PLAUSIBLE_GAIN`:
    a negative gain (the other axis system: ``--axes``), about 0.22, 0.10 or 0.001 (lbf, kgf or kN read as N:
    ``--units``), about 0 (a dead or unconnected channel: ``--drop``) are no tyre's dynamics, and the search would fit
    them as such. Pooled over the runs as the
    calibration is (one run's gain against the given model, its drift free, came out 0.2-0.3 on good runs of the
    benchmark's controls), so one bad run among many good ones is not caught here."""
    bad = {c: g for c, g in chain.held.items() if not PLAUSIBLE_GAIN[0] <= g <= PLAUSIBLE_GAIN[1]}
    if bad:
        raise DataError("measured channels are not the model's outputs at any load cell's calibration (gain "
                        f"{PLAUSIBLE_GAIN[0]:g}-{PLAUSIBLE_GAIN[1]:g} expected): "
                        + "; ".join(f"{c} is {g:.3g} x the model's" for c, g in bad.items())
                        + ". A negative gain: the file's axes (--axes SAE for SAE axes); about 0.22, 0.10 or 0.001: "
                          "forces in lbf, kgf or kN read as N (e.g. --units FX=lbf); about 0: a dead or unconnected "
                          "channel (--drop FX); else another tyre's file or a channel read from the wrong column "
                          "(--columns)")


def cutoffs_below_nyquist(runs, grid=CUTOFFS) -> tuple:
    """The cutoffs of ``grid`` a causal filter can have at the runs' slowest sample rate: below
    :data:`NYQUIST_SHARE` of its Nyquist frequency (None, no filter, always)."""
    top = NYQUIST_SHARE * 0.5 / max(r.dt for r in runs)
    return tuple(c for c in grid if c is None or c < top)


def _sse(filtered, delay, weights) -> float:
    """Channel-weighted sum of squares of measured less the calibrated (afresh), ``delay``-ed ``filtered`` model
    ((run, channel, filtered prediction))."""
    delayed = [(r, c, measurement_chain(f, r.dt, None, delay)) for r, c, f in filtered]
    chain = Chain(delay, **calibration(delayed))
    return float(sum(np.nansum((chain.calibrate(f, r, c) - r.measured[c]) ** 2) / weights[c] for r, c, f in delayed))


#: Delays [s] of the alignment's grid (refined by a parabola through the three best).
DELAYS = np.arange(-0.004, 0.0301, 0.002)


def align(runs, pred, runner=None) -> tuple:
    """(Chain, {(order, cutoff): weighted sum of squares}) fitted to the model prediction ``pred`` (run -> channel
    -> array): per filter order (:data:`ORDERS`) and cutoff (:data:`CUTOFFS` below Nyquist,
    :func:`cutoffs_below_nyquist`) the delay on a 2 ms grid refined by a parabola, each with the channels'
    calibration (:meth:`Chain.calibrated`) fitted; the cutoff is refined further with every candidate
    (:func:`_refit`). Each prediction is filtered once per order and cutoff, the delays applied to that.
    ``runner`` (:class:`mftyre.runner.Runner`, not serial): the (order, cutoff) cells in as many tasks as it has
    slots (:func:`align_task`), the same numbers as here."""
    cells = _aligned(runs, pred, runner)
    return _best(cells).calibrated(runs, pred), {(c.order, c.cutoff): fine for fine, c in cells}


def _aligned(runs, pred, runner=None) -> list:
    """[(weighted sum of squares, Chain uncalibrated)] of every (order, cutoff) cell of :func:`align`, in the
    order of the cells."""
    cells = [(order, cutoff) for order in ORDERS for cutoff in cutoffs_below_nyquist(runs)
             if cutoff is not None or order == ORDERS[-1]]
    if runner is None or runner.serial:
        found = _aligned_cells(runs, pred, cells)
    else:
        found = _aligned_cells_on(runner, runs, pred, cells)
    return [(found[cell][1], Chain(found[cell][0], cell[1], cell[0])) for cell in cells]


def _best(cells):
    """The chain of the lowest sum of ``cells`` ([(sum, Chain)]; the first of equal sums wins)."""
    best = None
    for fine, chain in cells:
        if best is None or fine < best[0]:
            best = (fine, chain)
    return best[1]


def _aligned_cells(runs, pred, cells) -> dict:
    """(order, cutoff) -> (delay, weighted sum of squares at it) for each of ``cells`` (:func:`align`)."""
    # each channel weighted by its noise as the chi-square weighs it (sigma^2 tau, from the quiet lead-ins, which
    # the chain hardly changes): weighted by the signal's variance instead, an aligned chain could trade a
    # channel's misfit against another's and bend the refits (a 200 Hz 2nd-order filter for 150 Hz, 4th order)
    noise = noise_from_data(runs, pred, Chain(0.0, None, ORDERS[-1]))
    weights = {c: max(n["sigma"] ** 2 * n["tau"], 1e-300) for c, n in noise.items()}
    out = {}
    for order, cutoff in cells:
        filtered = [(r, c, measurement_chain(pred[r.name][c], r.dt, cutoff, 0.0, order)) for r in runs
                    for c in r.measured]
        sse = np.array([_sse(filtered, d, weights) for d in DELAYS])
        j = int(np.argmin(sse))
        d = DELAYS[j]
        if 0 < j < len(DELAYS) - 1:  # parabola through the three best
            a, b, c = sse[j - 1], sse[j], sse[j + 1]
            den = a - 2 * b + c
            if den > 0:
                d = d + 0.5 * (a - c) / den * (DELAYS[1] - DELAYS[0])
        out[order, cutoff] = (float(d), _sse(filtered, float(d), weights))
    return out


def _stretch(runner, n: int) -> int:
    """How many of ``n`` items go into one task so that the tasks fill ``runner``'s slots once."""
    return -(-n // max(1, min(runner.slots(), n)))


def _results(runner, function, tasks: dict, what: str) -> dict:
    """``runner.run(function, tasks)``'s results (task key -> result); the first failure raised as a
    :class:`mftyre.runner.RunnerError` naming ``what`` failed, with its inputs and traceback."""
    from ..runner import RunnerError

    outcome = runner.run(function, tasks)
    if outcome.failures:
        raise RunnerError(f"{what} failed: {outcome.failures[0].summary()}\n{outcome.failures[0].error}")
    return outcome.results


def _aligned_cells_on(runner, runs, pred, cells) -> dict:
    """:func:`_aligned_cells` with ``cells`` cut into as many tasks as ``runner`` has slots (:func:`align_task`)."""
    from .dynamic_runs import run_data

    data = [run_data(r) for r in runs]
    seen = {r.name: {c: np.asarray(pred[r.name][c], float) for c in r.measured} for r in runs}
    size = _stretch(runner, len(cells))
    tasks = {f"a{i}": dict(runs=data, pred=seen, cells=[list(c) for c in cells[i:i + size]])
             for i in range(0, len(cells), size)}
    results = _results(runner, align_task, tasks, "an alignment task")
    return {(order, cutoff): (delay, fine) for result in results.values()
            for order, cutoff, delay, fine in result["cells"]}


def align_task(runs: list, pred: dict, cells: list) -> dict:
    """:func:`align`'s ``cells`` ([order, cutoff] pairs) where a task lands (:mod:`mftyre.runner`): ``runs`` as
    :func:`~mftyre.gaps.dynamic_runs.run_data`, ``pred`` run -> channel -> array. ``{"cells": [[order, cutoff,
    delay, weighted sum of squares], ...]}``."""
    found = _aligned_cells([DynamicRun(**r) for r in runs], pred, [(int(o), c) for o, c in cells])
    return {"cells": [[order, cutoff, delay, fine] for (order, cutoff), (delay, fine) in found.items()]}


def _quiet(y, dt):
    """Samples before ``y`` (the model) departs from its first value by 2 % of its range, less 20 ms."""
    dev = np.abs(y - y[0])
    rng = np.ptp(y)
    if rng <= 1e-9 * max(float(np.max(np.abs(y))), 1.0):  # constant but for the filter's round-off
        return y.size
    k = np.flatnonzero(dev > 0.02 * rng)
    return max(0, int(k[0]) - int(0.02 / dt)) if k.size else y.size


def _tau(e):
    """Integrated autocorrelation time (samples) of ``e``: 1 + 2 sum of the autocorrelations up to the first
    below 0.05."""
    e = e - e.mean()
    v = float(e @ e)
    if v <= 0 or e.size < 10:
        return 1.0
    tau = 1.0
    for k in range(1, min(60, e.size // 3)):
        rho = float(e[:-k] @ e[k:]) / v
        if rho < 0.05:
            break
        tau += 2 * rho
    return tau


def noise_from_data(runs, pred, chain) -> dict:
    """channel -> dict(sigma, tau, samples, runs): the noise in the quiet lead-ins (pooled per channel): the
    measured signal less the aligned model, less its mean."""
    parts = {}
    for r in runs:
        for c, y in r.measured.items():
            model_y = chain(pred[r.name][c], r, c)
            q = _quiet(chain.dynamics(pred[r.name][c], r.dt), r.dt)  # the tyre's event, not the cell's drift
            e = np.asarray(y[:q], float) - model_y[:q]
            e = e[~np.isnan(y[:q])]  # (a sample missing: left out)
            if e.size >= 30:  # measured less the model (any slow settling), less the mean (a static model error)
                parts.setdefault(c, []).append(e - np.mean(e))
    out = {}
    for c in {c for r in runs for c in r.measured}:
        segs = parts.get(c)
        if not segs:
            raise DataError(f"channel {c}: no run has a quiet lead-in of 30 samples before the event, so the "
                            f"measurement noise cannot be estimated; start the runs earlier")
        e = np.concatenate(segs)
        sigma = float(np.sqrt(np.mean(e**2)))
        if not sigma > 1e-12 * max(float(np.nanmax(np.abs(np.concatenate([r.measured[c] for r in runs
                                                                           if c in r.measured])))), 1e-300):
            raise DataError(f"channel {c}: no noise in the quiet lead-ins (the measured value follows the model to "
                            f"the last digit or holds still): no sensor measures so; a held, dead or computed "
                            f"channel? Drop the column or give the raw measurement")
        out[c] = dict(sigma=sigma, tau=float(np.median([_tau(s) for s in segs])), samples=int(e.size),
                      runs=len(segs))
    return out


def _holdout(runs, fraction, seed):
    """Names of the held-out runs: the steady finder's rule (:func:`mftyre.gaps.residuals.stratified_holdout`) over
    the runs as units, their kind (cleat, steer, brake, flat) as the kind of test and as conditions the levels
    of speed, load and pressure and the road (which obstacle): every condition and manoeuvre present is held out
    somewhere when the runs allow it, and none vanishes from the training runs."""
    from .residuals import stratified_holdout

    level = [run_levels(runs, key) for key in RUN_LEVELS]
    roads = sorted({r.road for r in runs})
    level.append(np.array([roads.index(r.road) for r in runs]))
    # whole runs are few and long: the fraction rounded up (4 runs at 0.34: 2 held out), two kept for training
    # where there are three or more, and one of two held out (a manoeuvre run twice is tested on one)
    held = stratified_holdout(np.stack(level, axis=1), np.array([r.kind for r in runs]), fraction, seed,
                              lambda n, f: min(math.ceil(n * f), n - 2), min_units=2)
    return {r.name for r, h in zip(runs, held) if h}


class _Problem:
    """Residuals of a model on a set of runs, weighted by the noise (chi-square = sum of squares)."""

    def __init__(self, runs, chain, noise):
        self.runs, self.chain, self.noise = runs, chain, noise

    def weighted(self, run, channel, pred):
        """The noise-weighted residual of ``channel`` of ``run``; 0 at the samples the run lacks (a measured value
        missing: up to 10 % of a channel, :func:`mftyre.gaps.dynamic_runs.read_runs`), so that every sum, fit and
        finite difference leaves them out (a model's non-finite output stays non-finite)."""
        n, measured = self.noise[channel], run.measured[channel]
        r = (self.chain(pred, run, channel) - measured) / (n["sigma"] * math.sqrt(n["tau"]))
        return np.where(np.isnan(measured), 0.0, r)

    def residuals(self, pred, names=None) -> dict:
        """(run, channel) -> weighted residual array."""
        return {(r.name, c): self.weighted(r, c, pred[r.name][c]) for r in self.runs
                if names is None or r.name in names for c in r.measured}

    def n_eff(self, names) -> float:
        """The independent samples of the runs ``names``: the measured samples over each channel's noise
        correlation time."""
        return sum(np.count_nonzero(~np.isnan(v)) / self.noise[c]["tau"] for r in self.runs if r.name in names
                   for c, v in r.measured.items())


@dataclass(frozen=True)
class _Scored:
    """A change of model judged by the search's rule (:meth:`_Runs._scored`): training and held-out chi-square
    (before, after), their chi2(k) p-values, the chi-square the materiality is measured against (``before``), the
    decrease there (``score``) and :func:`judge`'s reason ('' when it passes)."""
    train: tuple
    held: tuple
    p_train: float
    p_held: float
    before: float
    score: float
    note: str


def _chi2(res: dict, keys=None) -> float:
    return float(sum(np.nansum(v**2) for k, v in res.items() if keys is None or k in keys))


class DynamicGapReport:
    """The outcome of :func:`find_dynamic_gaps`: ``model_given``, ``model`` (improved), ``effects_added``
    (candidate list), ``rounds`` (per round the candidates), ``untestable`` (effect -> reason), ``chain``,
    ``noise``, ``held_out`` (run names), ``error_before``/``error_after`` (channel -> held-out RMS in the
    channel's unit), ``noise_floor`` (channel -> RMS of the noise), ``by_condition`` (rows per held-out run and
    channel), ``findings`` (located feature differences of the given model), ``message``."""

    def __init__(self, **kw):
        self.__dict__.update(kw)

    def evaluate(self, model) -> dict:
        """channel -> RMS error of ``model`` (e.g. the written file read back) on the runs the errors were reported
        for (held out, else training), through the fitted measurement chain: :attr:`error_after` for
        :attr:`model`."""
        return _rms(self.runs, _Sim(self.runs, self.model_kind)(model), self.chain, self.held_out or self.trained)

    @property
    def effect_names(self) -> list:
        return [c.name for c in self.effects_added]

    def to_dict(self) -> dict:
        return _jsonable(dict(message=self.message, model_kind=self.model_kind, effects_added=[c.to_dict() for c in self.effects_added],
                              rounds=[[c.to_dict() for c in r] for r in self.rounds], untestable=self.untestable,
                              chain=self.chain.__dict__, noise=self.noise,
                              held_out=sorted(self.held_out), error_before=self.error_before,
                              error_after=self.error_after, noise_floor=self.noise_floor,
                              by_condition=self.by_condition, findings=self.findings, seconds=self.seconds))

    def to_json(self, path, *, overwrite: bool = False):
        from ..files import write_atomically

        path = Path(path)
        if path.exists() and not overwrite:
            raise DataError(f"{path} exists: pass overwrite=True to replace it")
        return write_atomically(path, json.dumps(self.to_dict(), indent=1))

    def write_tir(self, path, *, overwrite: bool = False) -> Path:
        """Write the improved model (:func:`mftyre.tir.write_tir`: atomic, never over an existing file without
        ``overwrite``, never over the file the model was read from)."""
        from ..tir import write_tir

        return write_tir(self.model.params, path, overwrite=overwrite)

    def markdown(self) -> str:
        L = ["# Dynamic gap report", "", self.message, "",
             f"Dynamic model: the {self.model_kind} wheel. "
             f"Measurement chain fitted with the final model: delay {1e3 * self.chain.delay:.2f} ms, anti-alias "
             f"filter {'none' if self.chain.cutoff is None else f'{self.chain.cutoff:.4g} Hz ({self.chain.order}-pole Butterworth)'}; "
             "calibration " + ", ".join(f"{c} gain {g:.4f} drift {self.chain.drift[c]:.3g}/s"
                                        for c, g in self.chain.gain.items()) + "."
             + "".join(f" The {c} gain is held at its bound (1 +- {GAIN_RANGE:g}): least squares gave {g:.4g}, more "
                       f"than a load cell's calibration error, so the rest is left to the model."
                       for c, g in self.chain.held.items()),
             "", "## Noise (quiet lead-ins)", "", "| channel | sigma | tau [samples] | samples |", "|---|---|---|---|"]
        L += [f"| {c} | {n['sigma']:.3g} | {n['tau']:.2f} | {n['samples']} |" for c, n in self.noise.items()]
        L += ["", "## Held-out error (RMS) before -> after, noise floor", "", "| channel | before | after | noise |",
              "|---|---|---|---|"]
        L += [f"| {c} | {self.error_before[c]:.4g} | {self.error_after[c]:.4g} | {self.noise_floor[c]:.3g} |"
              for c in self.error_before]
        L += ["", "## Per run and channel (held-out runs marked *)", "",
              "| run | speed km/h | load N | pressure bar | channel | RMS before | RMS after |", "|---|---|---|---|---|---|---|"]
        L += [f"| {r['run']}{'*' if r['held_out'] else ''} | {r['speed']:g} | {r['load']:.0f} | {r['pressure']:g} | "
              f"{r['channel']} | {r['rms_before']:.4g} | {r['rms_after']:.4g} |" for r in self.by_condition]
        L += ["", "## Located differences of the given model (|z| > 3)", "",
              "| run | channel | feature | measured | model | z |", "|---|---|---|---|---|---|"]
        L += [f"| {f['run']} | {f['channel']} | {f['feature']} | {f['measured']:.4g} | {f['model']:.4g} | "
              f"{f['z']:.1f} |" for f in self.findings[:40]]
        L += ["", "## Effects added", ""]
        for c in self.effects_added:
            vals = values_text(c)
            L.append(f"* **{c.name}**: {vals}; training chi2 {c.chi2_train_before:.0f} -> {c.chi2_train_after:.0f} "
                     f"(p {c.p_value:.2g}), held-out chi2 {c.chi2_test_before:.0f} -> {c.chi2_test_after:.0f} "
                     f"(p {c.held_out_p:.2g})")
        if not self.effects_added:
            L.append("none")
        L += ["", "## Candidates per round", ""]
        for i, rnd in enumerate(self.rounds, 1):
            for c in rnd:
                L.append(f"* round {i}: {c.name}: screened decrease {c.screened:.1f}"
                         + (f", held-out chi2 {c.chi2_test_before:.0f} -> {c.chi2_test_after:.0f}"
                            if math.isfinite(c.chi2_test_after) else "") + (f"; {c.note}" if c.note else ""))
        unstable = {k: g for k, (g, _) in (self.growth_given or {}).items() if g > 1e-6}
        if unstable:
            L += ["", "## Stability of the given model", "", "Linearised at the static state, the given model grows "
                  "at " + "; ".join(f"{k}: {g:.3g} 1/s" for k, g in unstable.items())
                  + f" (an improved model may not add a mode with a damping ratio below -{GROWTH_MARGIN:g})."]
        L += ["", "## Effects not tried", ""] + [f"* {k}: {v}" for k, v in self.untestable.items()]
        return "\n".join(L) + "\n"

    def plot(self, path, runs=None):
        """Overlaid time histories (measured, given model, improved) of the held-out runs to ``path`` (PNG)."""
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        runs = runs or [r for r in self.runs if r.name in self.held_out] or self.runs
        from ..files import write_figure

        rows = [(r, c) for r in runs for c in r.measured]
        fig, axes = plt.subplots(len(rows), 1, figsize=(7, 1.8 * len(rows)), squeeze=False, dpi=70)
        for ax, (r, c) in zip(axes[:, 0], rows):
            ax.plot(r.t, r.measured[c], color="0.6", lw=0.8, label="measured")
            ax.plot(r.t, self.chain(self.pred_before[r.name][c], r, c), lw=1.0, label="given model")
            ax.plot(r.t, self.chain(self.pred_after[r.name][c], r, c), lw=1.0, ls="--", label="improved")
            ax.set_ylabel(c)
            ax.set_title(r.label(), fontsize=8)
        axes[0, 0].legend(fontsize=7)
        axes[-1, 0].set_xlabel("time [s]")
        fig.tight_layout()
        try:
            return write_figure(fig, path)  # the one safe writer: never through a planted link
        finally:
            plt.close(fig)

    def save(self, folder, *, overwrite: bool = False) -> Path:
        from ..files import check_outputs, make_output_folder, write_atomically

        folder = Path(folder)
        check_outputs({}, folders={"report folder": folder}, overwrite=overwrite, option="overwrite=True")
        make_output_folder(folder, "report folder")
        write_atomically(folder / "report.md", self.markdown() + "\n![held-out runs](histories.png)\n")
        write_atomically(folder / "gaps.json", json.dumps(self.to_dict(), indent=1))
        self.plot(folder / "histories.png")
        return folder


def values_text(c) -> str:
    """``A = 1.2 +- 0.03``, or without +- for a parameter the data do not separate from another (its correlation
    said instead)."""
    vals = ", ".join(f"{k} = {v:.5g}" + (f" +- {c.stderr[k]:.2g}" if math.isfinite(c.stderr.get(k, math.nan)) else
                                          " (no +-)") for k, v in c.values.items())
    return vals + "".join(f"; {pair.replace('~', ' and ')} not separated by these runs (correlation {rho:.3f})"
                          for pair, rho in c.correlation.items())


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, set)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


# ------------------------------------------------------------------------------------------------ the workflow
def _load(data, model):
    from ..model import MFModel, load_tir

    runs = read_runs(data) if isinstance(data, (str, Path)) else list(data)
    if not runs or not all(isinstance(r, DynamicRun) for r in runs):
        raise DataError("dynamic data must be a CSV file, a folder of CSV files or a list of DynamicRun")
    if len({r.name for r in runs}) != len(runs):
        raise DataError("run names must be unique")
    model = load_tir(model) if isinstance(model, (str, Path)) else model
    if not isinstance(model, MFModel):
        raise ModelInputError("model must be an MFModel or a .tir path")
    return runs, model


class _Sim:
    """Simulate a model on runs (``kind``: :data:`MODEL_KINDS`); counts evaluations. What the last few parameter
    sets gave on each run is kept (a refit simulates its result on the training runs, then on all: only the
    held-out runs are simulated again; the outputs are read-only, channel -> array per run), and so are their SWIFT
    tyres, built for every run, their cam tables kept across parameter sets with the same cams (:class:`SwiftTyres`).

    ``runner`` (:class:`mftyre.runner.Runner`, not serial; the SWIFT wheel: the relaxed one is a few vectorised
    CasADi calls): the runs of every model asked for at once (:meth:`many`) go out as tasks (:func:`simulate_task`:
    the model's .tir text, the road layout of all the runs, some of its runs), so the runs of one simulation and
    the models of one Jacobian run in parallel; each worker keeps the tyres it built. The outputs are those of the
    serial simulation, bit for bit. The relaxed wheel's graphs are built for models near ``reference`` (the given
    model: :class:`RelaxedWheels`, one graph per refit, not per trial)."""

    KEPT = 6

    def __init__(self, runs, kind="swift", runner=None, reference=None):
        self.runs, self.kind, self.evaluations = runs, kind, 0
        self._wheels = RelaxedWheels(reference) if kind == "relaxed" and reference is not None else None
        self.runner = None if runner is None or runner.serial or kind != "swift" else runner
        self._tables, self._tyres, self._outputs = {}, {}, {}
        self._roads = road_layout(runs) if kind == "swift" else {}  # the tyres' roads, here and on the workers

    @staticmethod
    def _key(model):
        prm = model.params
        return tuple(repr(prm[k]) for k in prm), tuple(sorted(prm.missing)), model.side

    @classmethod
    def _kept(cls, cache: dict, key, make):
        if key not in cache:
            if len(cache) >= cls.KEPT:
                del cache[next(iter(cache))]
            cache[key] = make()
        return cache[key]

    def tyres(self, model) -> SwiftTyres:
        return self._kept(self._tyres, self._key(model),
                          lambda: SwiftTyres(model, tables=self._tables, layout=self._roads))

    def __call__(self, model, runs=None):
        out, = self.many([model], runs)
        if isinstance(out, ModelInputError):
            raise out
        return out

    def many(self, models, runs=None) -> list:
        """Each of ``models`` simulated on ``runs`` (default: all): per model, run name -> channel -> output, or the
        :class:`ModelInputError` that model raised."""
        runs = runs or self.runs
        self.evaluations += len(models)
        keys = [self._key(m) for m in models]
        found = {}  # model key -> run name -> outputs, or the error
        for key in keys:
            if key not in found:
                found[key] = dict(self._outputs.get(key, {}))
        todo = {key: (m, [r for r in runs if r.name not in found[key]]) for key, m in zip(keys, models)}
        todo = {key: job for key, job in todo.items() if job[1]}
        if self.runner is None:
            for key, (model, missing) in todo.items():
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        found[key].update(simulate(model, missing, self._wheels, model_kind="relaxed")
                                          if self.kind == "relaxed" else simulate(model, missing, self.tyres(model)))
                except ModelInputError as exc:
                    found[key] = exc
        elif todo:
            self._on_runner(todo, found)
        answers = []
        for key in keys:
            done = found[key]
            if isinstance(done, ModelInputError):
                answers.append(done)
                continue
            kept = self._kept(self._outputs, key, dict)
            for name, channels in done.items():
                if name not in kept:
                    for values in channels.values():
                        values.setflags(write=False)
                    kept[name] = MappingProxyType(channels)
            answers.append({r.name: kept[r.name] for r in runs})
        return answers

    def _on_runner(self, todo: dict, found: dict) -> None:
        """The (model, run) pairs of ``todo`` cut into as many equal stretches as the runner has workers, one task
        per model of each stretch (:func:`simulate_task`): a model's tyres are built once per task, a batch of
        models spreads over the workers by model, the runs of one model by run."""
        from ..runner import unpack
        from ..tir import tir_text
        from .dynamic_runs import run_data, simulate_task

        pairs = [(key, r) for key, (_, missing) in todo.items() for r in missing]
        size = _stretch(self.runner, len(pairs))
        layout = [[*key, *xr] for key, xr in self._roads.items()]
        texts, tasks, owner = {}, {}, {}
        for start in range(0, len(pairs), size):
            pieces = {}
            for key, r in pairs[start:start + size]:
                pieces.setdefault(key, []).append(r)
            for key, piece in pieces.items():
                model = todo[key][0]
                if key not in texts:
                    texts[key] = tir_text(model.params)
                name = f"s{len(tasks)}"
                tasks[name] = dict(tir=texts[key], side=model.side, model_kind=self.kind, layout=layout,
                                   runs=[run_data(r) for r in piece])
                owner[name] = key
        for name, result in _results(self.runner, simulate_task, tasks, "a simulation task").items():
            key = owner[name]
            if isinstance(found[key], ModelInputError):
                continue
            if "error" in result:
                found[key] = ModelInputError(result["error"])
                continue
            for run, channels in result["outputs"].items():
                found[key][run] = {c: unpack(v) for c, v in channels.items()}


#: The parameters of the SWIFT wheel a file must have for model kind "auto" to choose it.
SWIFT_SECTIONS = ("BELT_MASS", "BELT_IXX", "BELT_IYY", "FREQ_LONG", "FREQ_LAT", "FREQ_YAW", "FREQ_WINDUP")


def model_kind_for(model, runs, kind: str = "auto") -> str:
    """The dynamic model the finder drives: ``kind`` as given, or for "auto" the SWIFT wheel when the file has its
    sections (:data:`SWIFT_SECTIONS`; the relaxed wheel lacks the ring: on the TNO 205/60 R15 file its static
    Fz at the same axle height is 1.7 % above the ring's, a gap that is no effect), else the relaxed wheel."""
    if kind not in (*MODEL_KINDS, "auto"):
        raise ModelInputError(f"model kind must be one of auto, {', '.join(MODEL_KINDS)}; got {kind!r}")
    if kind != "auto":
        return kind
    prm = model.params
    return "swift" if all(n in prm and n not in prm.missing for n in SWIFT_SECTIONS) else "relaxed"


#: Refit coordinates: a positive parameter moves as value = base exp(0.2 delta) (scale-free, stays positive; a
#: relaxation length ~ 1/stiffness is near linear in it); a parameter whose neutral value is 0 (``absolute``) as
#: base + 0.5 delta.
_LOG_STEP, _ABS_STEP = 0.2, 0.5


def _value(effect, p, base, d):
    if p in effect.absolute or base == 0:
        return base + _ABS_STEP * d
    return base * math.exp(_LOG_STEP * d)


def given_values(model, parameters) -> dict:
    """The values the SWIFT equations use for ``parameters``: the file's, or for SWIFT_PSTIFF / SWIFT_PDAMP absent
    from the file the defaults derived from PFZ1 (:func:`swift.ring.pressure_coefficients`; for SWIFT_PDAMP the
    slope -SWIFT_PSTIFF/2 of its default f_d = 1/sqrt(f_c) at NOMPRES), so that a refit starts from the tyre as
    simulated, not from the schema's 0."""
    from swift.ring import pressure_coefficients

    prm = model.params
    pstiff, pdamp = pressure_coefficients(prm)
    used = {"SWIFT_PSTIFF": pstiff, "SWIFT_PDAMP": -0.5 * pstiff if pdamp is None else pdamp}
    return {p: used[p] if p in used and p in prm.missing else float(prm[p]) for p in parameters}


def _with(model, effect, base, delta):
    return model.with_params(**{p: _value(effect, p, base[p], d) for p, d in zip(effect.parameters, delta)})


def _slope(effect, p, value, base):
    """d value / d delta at ``value`` (standard errors from the delta covariance)."""
    return _ABS_STEP if p in effect.absolute or base == 0 else _LOG_STEP * abs(value)


def _bounds_ok(effect, delta):
    return bool(np.all(np.abs(delta) < 12.0))  # at most a factor e^2.4 = 11 either way, or +-6 absolute


def _growth(model, runs, model_kind="swift", tyres=None) -> dict:
    """Condition label -> largest real part [1/s] of the eigenvalues of the linearised SWIFT wheel at its static
    state, for every distinct (speed, pressure, axle height or load) of the runs. The relaxed wheel: {} (first-order
    relaxation at the rate |vx|/sigma, sigma floored positive: stable whatever the parameters)."""
    from swift import StepInputs

    if model_kind == "relaxed":
        return {}
    seen = {}
    for r in runs:
        i = r.inputs
        key = tuple(round(float(np.mean(i[k])), 4) if k in i else None for k in ("VX", "P", "Z", "LOAD")) + (
            r.axle, r.rim)
        seen.setdefault(key, r)
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tyres = tyres or SwiftTyres(model, list(seen.values()))
        for r in seen.values():
            i = r.inputs
            first = {k.lower(): float(i[k][0]) for k in ("X", "VX", "Z", "LOAD", "OMEGA", "TORQUE", "P") if k in i}
            u = StepInputs(**first)
            tyre = tyres.tyre(r)
            lam = np.linalg.eigvals(tyre.jacobian(tyre.initial_state(u), u))
            c = r.condition
            ok = np.all(np.isfinite(lam))
            out[f"{c['speed']:g} km/h, {c['pressure']:g} bar, {c['load']:.0f} N"] = (
                float(lam.real.max()) if ok else math.inf,
                float(np.max(lam.real - GROWTH_MARGIN * np.abs(lam))) if ok else math.inf)
    return out


#: A mode counts as unstable when it grows faster than a damping ratio of -GROWTH_MARGIN (Re > margin |lambda|):
#: a marginal mode (the given files' own belt modes reach damping ratios of -0.0014 at low speed) is the model's
#: property, not the candidate's.
GROWTH_MARGIN = 0.01


def _less_stable(new: dict, given: dict) -> str:
    """'' or the condition where the improved model has a mode growing beyond :data:`GROWTH_MARGIN` that the
    given one does not have (or has weaker)."""
    for k, (g, m) in new.items():
        ref = given.get(k, (0.0, 0.0))[1]
        if m > 0 and m > max(ref, 0.0) + 0.05:
            return (f"{k}: an eigenvalue with real part {g:.3g} 1/s at the static state, a damping ratio below "
                    f"-{GROWTH_MARGIN:g} (given model: {given.get(k, (math.nan,))[0]:.3g} 1/s)")
    return ""


def find_dynamic_gaps(data, model, *, holdout: float = 0.34, seed: int = 0, alpha: float = 1e-3,
                      max_effects: int = 3, catalogue=DYNAMIC_CATALOGUE, refit_top: int = REFIT_TOP,
                      model_kind: str = "auto", progress=None, runner=None) -> DynamicGapReport:
    """Locate, name and add the dynamic effects ``model`` misses in the runs ``data`` (module text): the one
    search of the gap finder (:func:`mftyre.gaps.search.search`) on the evidence of the runs (:class:`_Runs`);
    ``refit_top``: candidates refitted per round after the screening; ``model_kind``: "swift", "relaxed" or
    "auto" (:func:`model_kind_for`); ``runner``: a :class:`mftyre.runner.Runner` to simulate the SWIFT wheel's runs
    in parallel on (:class:`_Sim`; the same report as without)."""
    t_start = time.perf_counter()
    say = progress or (lambda text: None)
    runs, model_given = _load(data, model)
    model_kind = model_kind_for(model_given, runs, model_kind)
    sim = _Sim(runs, model_kind, runner, model_given)
    say(f"{len(runs)} runs; simulating the given model ({model_kind} wheel)")
    pred0 = sim(model_given)
    held = _holdout(runs, holdout, seed)
    train = {r.name for r in runs} - held
    ev = _Runs(runs, train, held, sim, model_given, pred0, alpha, refit_top, model_kind, say)
    check_scales(ev.chain)
    say(f"aligned: delay {1e3 * ev.chain.delay:.2f} ms, filter {_cutoff_text(ev.chain)}; noise "
        + ", ".join(f"{c} {n['sigma']:.3g} (tau {n['tau']:.1f})" for c, n in ev.noise.items()))
    testable, untestable = testable_effects(runs, model_given, catalogue, model_kind)
    # locate: features of the given model against the measurement (shown), runs beyond their noise (searched)
    findings = _findings(runs, pred0, ev.chain, ev.noise)
    gaps = ev.locate()
    for e in testable:
        if not matches(e, gaps):
            untestable.setdefault(e.name, "testable, but no run of its kinds shows a gap in its channels")
    search(ev, {e.name: (e, e.parameters, {}) for e in testable}, gaps, max_effects)
    ev.recheck()

    model, pred, chain, noise, added = ev.model, ev.pred, ev.chain, ev.noise, ev.added
    # show: the improved model simulated afresh on every run (what is written is what is scored)
    if added:
        pred = sim(model)
    names_eval = held or train
    by_condition = []
    for r in runs:
        for c in r.measured:
            b = float(np.sqrt(np.mean((chain(pred0[r.name][c], r, c) - r.measured[c]) ** 2)))
            a = float(np.sqrt(np.mean((chain(pred[r.name][c], r, c) - r.measured[c]) ** 2)))
            by_condition.append(dict(run=r.name, kind=r.kind, held_out=r.name in held, **r.condition, channel=c,
                                     rms_before=b, rms_after=a))
    err_b, err_a = _rms(runs, pred0, chain, names_eval), _rms(runs, pred, chain, names_eval)
    floor = {c: n["sigma"] for c, n in noise.items()}
    if added:
        msg = (f"added {len(added)} effect(s): " + "; ".join(c.name for c in added) + ". Held-out RMS "
               + ", ".join(f"{c} {err_b[c]:.3g} -> {err_a[c]:.3g} (noise {floor[c]:.3g})" for c in err_b))
    else:
        msg = ("nothing added: no effect lowered the held-out error significantly. Held-out RMS "
               + ", ".join(f"{c} {err_b[c]:.3g} (noise {floor[c]:.3g})" for c in err_b))
    return DynamicGapReport(model_given=model_given, model=model, effects_added=added, rounds=ev.rounds,
                            untestable=untestable, rejected=ev.rejected, chain=chain, chain_table=ev.chain_table,
                            noise=noise, held_out=held, trained=train, error_before=err_b, error_after=err_a,
                            noise_floor=floor, by_condition=by_condition, findings=findings, gaps=gaps,
                            message=msg, runs=runs, pred_before=pred0, pred_after=pred, evaluations=sim.evaluations,
                            growth_given=ev.growth_given, model_kind=model_kind,
                            seconds=time.perf_counter() - t_start)


class _Runs:
    """The evidence of dynamic runs for the one search (:func:`mftyre.gaps.search.search`): the wheel simulated
    on the runs (``sim``), the measurement chain aligned to the current model on the training runs, the noise of the
    quiet lead-ins; the current ``model`` and its prediction ``pred``."""

    def __init__(self, runs, train, held, sim, model, pred, alpha, refit_top, model_kind, say):
        self.runs, self.train, self.held, self.sim = runs, train, held, sim
        self.train_runs = [r for r in runs if r.name in train]
        self.alpha, self.refit_top, self.model_kind, self.say = alpha, refit_top, model_kind, say
        self.rounds, self.rejected, self.added = [], {}, []
        self.growth_given, self._verified, self._effects = None, {}, {}
        self.given = model
        self._align(model, pred)

    def _align(self, model, pred):
        """The current model: the measurement chain and the noise fitted to it (the given model's errors bent
        them), the linearised screening's Jacobians dropped."""
        self.model, self.pred = model, pred
        self.chain, self.chain_table = align(self.train_runs, pred, self.sim.runner)
        self.noise = noise_from_data(self.runs, pred, self.chain)
        self.chain = refined(self.chain, self.runs, pred, self.noise, self.train)
        self.noise = noise_from_data(self.runs, pred, self.chain)
        self.prob = _Problem(self.runs, self.chain, self.noise)
        self._jac = {}

    def _problem(self, pred) -> _Problem:
        """The residuals of ``pred`` through a chain fitted to it as the current model's is (aligned, refined), with
        the current noise."""
        chain = refined(align(self.train_runs, pred, self.sim.runner)[0], self.runs, pred, self.noise, self.train)
        return _Problem(self.runs, chain, self.noise)

    def locate(self) -> list:
        return _gaps(self.runs, self.prob, self.pred, self.alpha)

    def trials(self, tried, round_no: int) -> list:
        """The candidates ranked by a linearised step on the training runs (finite-difference sensitivity of the
        simulated histories, beyond what the chain's own freedom explains); the best :attr:`refit_top` refitted
        with the chain (:func:`_refit`) and judged (:func:`mftyre.gaps.search.judge`); (candidate, (model,
        prediction)) pairs, the refitted by held-out decrease first."""
        prob, pred, train, runs = self.prob, self.pred, self.train, self.runs
        res = prob.residuals(pred)
        keys_train = [k for k in res if k[0] in train]
        r_train = np.concatenate([res[k] for k in keys_train])
        self.say(f"round {round_no}: screening {len(tried)} effects")
        # ranked by what each explains beyond the measurement chain's own freedom (its delay and cutoff take up
        # part of a lag or a frequency gap, differently for each effect: screened with the chain held, in the TNO
        # case FREQ_LONG x 0.88 the three refitted were DAMP_RESIDUAL, the wind-up mode and BELT_IYY, not FREQ_LONG)
        chain_cols = _chain_columns(prob, pred, train, keys_train, r_train)
        step, *_ = np.linalg.lstsq(chain_cols, -r_train, rcond=None)
        chain_only = float(r_train @ r_train - np.sum((r_train + chain_cols @ step) ** 2))
        screened = []
        self._sensitivity([e for e, *_ in tried], keys_train, r_train)
        for e, keep, _ in tried:
            J = np.column_stack([self._jac[e.name], chain_cols])
            step, *_ = np.linalg.lstsq(J, -r_train, rcond=None)
            dec = float(r_train @ r_train - np.sum((r_train + J @ step) ** 2)) - chain_only
            screened.append((Candidate(e.name, e.parameters, screened=dec), e))
            self._effects[e.name] = e
        screened.sort(key=lambda t: -t[0].screened)
        level = self.alpha / len(screened)
        refitted, rest = [], []
        for cand, e in screened:
            if len(refitted) + len(rest) >= self.refit_top:
                rest.append((cand, None))
                continue
            self.say(f"  refitting {e.name}")
            out = _refit(e, self.model, pred, prob, self.sim, runs, train, keys_train)
            if out is None:
                cand.note = "refit failed (the model could not be built or simulated)"
                rest.append((cand, None))
                continue
            new_model, new_pred, delta, cov, prob_new = out
            sc = self._scored(res, prob_new.residuals(new_pred), prob, len(e.parameters), level)
            (cand.chi2_train_before, cand.chi2_train_after), (cand.chi2_test_before, cand.chi2_test_after) = \
                sc.train, sc.held
            cand.n_eff, cand.p_value, cand.held_out_p = prob.n_eff(train), sc.p_train, sc.p_held
            cand.values = {p: float(new_model.params[p]) for p in e.parameters}
            cand.stderr, cand.correlation = precision(
                cov, [_slope(e, p, cand.values[p], self.model.params[p]) for p in e.parameters], e.parameters)
            cand.score, cand.held_out_gain = sc.score, sc.score / sc.before if sc.before > 0 else 0.0
            cand.note = sc.note
            cand.significant = not cand.note
            refitted.append((cand, (new_model, new_pred)))
        refitted.sort(key=lambda t: -t[0].score)
        return refitted + rest

    def _scored(self, before: dict, after: dict, prob, k: int, level: float) -> _Scored:
        """The search's rule (:func:`mftyre.gaps.search.judge`) for a change of model of ``k`` parameters, from
        weighted residuals ``before`` (problem ``prob``) to ``after``: the training and held-out chi2(k) p-values
        at ``level``, and the decrease material against what the noise does not explain, held-out where there is a
        hold-out (else training). One rule for adding a candidate (:meth:`trials`) and for keeping one
        (:meth:`recheck`)."""
        train = {key for key in after if key[0] in self.train}
        chi = {part: (_chi2(before, keys), _chi2(after, keys)) for part, keys in (("train", train),
                                                                                   ("held", set(after) - train))}
        p_train = float(stats.chi2.sf(max(chi["train"][0] - chi["train"][1], 0.0), k))
        p_held = float(stats.chi2.sf(max(chi["held"][0] - chi["held"][1], 0.0), k)) if self.held else math.nan
        b, a = chi["held"] if self.held else chi["train"]
        note = judge(p_train, level, p_held, level, b - a, material=MATERIAL,
                     excess=b - prob.n_eff(self.held or self.train))
        return _Scored(chi["train"], chi["held"], p_train, p_held, b, b - a, note)

    def _sensitivity(self, effects, keys_train, r_train) -> None:
        """d (weighted training residuals) / d (refit coordinates) of each of ``effects`` by finite differences
        (one simulation of its training runs per parameter, all of them at once: :meth:`_Sim.many`), kept in
        ``_jac`` until the model changes."""
        todo = [e for e in effects if e.name not in self._jac]
        by_runs, cols = {}, {}  # the effects' training runs -> [(effect, column, model)]; (effect, column) -> column
        for e in todo:
            base = given_values(self.model, e.parameters)
            sub = tuple(r.name for r in self.train_runs if r.kind in e.kinds)
            for j in range(len(e.parameters)):
                d = np.zeros(len(e.parameters))
                d[j] = 0.25
                try:
                    by_runs.setdefault(sub, []).append((e, j, _with(self.model, e, base, d)))
                except ModelInputError:
                    cols[e.name, j] = np.zeros_like(r_train)  # no model there: no sensitivity
        for sub, jobs in by_runs.items():
            sub_runs = [r for r in self.train_runs if r.name in sub]
            for (e, j, _), out in zip(jobs, self.sim.many([m for *_, m in jobs], sub_runs)):
                if isinstance(out, ModelInputError):
                    cols[e.name, j] = np.zeros_like(r_train)
                    continue
                rj = self.prob.residuals({**self.pred, **out}, self.train)
                cols[e.name, j] = (np.concatenate([rj[k] for k in keys_train]) - r_train) / 0.25
        for e in todo:
            self._jac[e.name] = np.column_stack([cols[e.name, j] for j in range(len(e.parameters))])

    def verify(self, cand, new, m: int):
        """(new, '') when the improved model builds, :func:`mftyre.fit.verify.verify_tir` finds no problem the
        current one lacks, every run simulates to finite values and the linearised wheel grows no faster mode than
        the current one (:func:`_less_stable`); else (new, the reason)."""
        from ..fit.verify import verify_tir

        new_model, new_pred = new
        if id(self.model) not in self._verified:  # (the model kept beside its problems: its id is not reused)
            self._verified[id(self.model)] = (self.model, verify_tir(self.model))
        problems = [p for p in verify_tir(new_model) if p not in self._verified[id(self.model)][1]]
        if problems:
            return new, "verification: " + "; ".join(problems[:2])
        if not all(np.all(np.isfinite(v)) for ch in new_pred.values() for v in ch.values()):
            return new, "the improved model gives non-finite outputs"
        kind = self.model_kind
        growth = _growth(self.model, self.runs, kind, self.sim.tyres(self.model) if kind == "swift" else None)
        self.growth_given = self.growth_given or growth
        unstable = _less_stable(_growth(new_model, self.runs, kind, self.sim.tyres(new_model) if kind == "swift"
                                        else None), growth)
        return new, ("unstable: " + unstable) if unstable else ""

    def add(self, cand, new):
        """Make the candidate's model the current one, realign the chain to it and refit every parameter added so
        far together (:meth:`_polish`)."""
        self.added.append(cand)
        self._align(*new)
        self._polish()
        self.say(f"  added {cand.name}; realigned: delay {1e3 * self.chain.delay:.2f} ms, filter "
                 f"{_cutoff_text(self.chain)}")

    def _polish(self) -> None:
        """The parameters of every effect added so far refitted together, with the chain, against the chain
        realigned to the current model (:meth:`_together`). A refit alone stops where the chain it started from
        holds it (SWIFT_PSTIFF 1.38 for a truth of 1.40 in the benchmark's "sidewall over pressure"): left there, a
        later candidate is credited with the rest of that effect (DAMP_LONG -2 % took 9 % of the held-out
        chi-square)."""
        out = self._together(self.added, self.model, self.pred, self.prob)
        if out is not None:
            self._align(*out)

    def _together(self, cands, model, pred, prob):
        """(model, prediction) with the parameters of ``cands`` refitted together from ``model`` (:func:`_refit`
        of their union, the chain of ``prob`` its start), or None where that does not lower the training
        chi-square; their values, standard errors and correlations become the joint ones."""
        effects = [self._effects[c.name] for c in cands]
        joint = replace(effects[0], name="the effects added", parameters=tuple(p for c in cands
                                                                                 for p in c.parameters),
                        variables=tuple(dict.fromkeys(k for e in effects for k in e.kinds)),
                        absolute=tuple(p for e in effects for p in e.absolute))
        res = prob.residuals(pred)
        keys_train = [k for k in res if k[0] in self.train]
        self.say("  refitting " + ", ".join(joint.parameters) + " together")
        out = _refit(joint, model, pred, prob, self.sim, self.runs, self.train, keys_train)
        if out is None:
            return None
        new_model, new_pred, _, cov, new_prob = out
        if not _chi2(new_prob.residuals(new_pred), set(keys_train)) < _chi2(res, set(keys_train)):
            return None
        values = {p: float(new_model.params[p]) for p in joint.parameters}
        base = given_values(model, joint.parameters)
        stderr, correlation = precision(cov, [_slope(joint, p, values[p], base[p]) for p in joint.parameters],
                                        joint.parameters)
        for c in cands:
            c.values = {p: values[p] for p in c.parameters}
            c.stderr = {p: stderr[p] for p in c.parameters}
            c.correlation = {pair: rho for pair, rho in correlation.items()
                             if any(name in c.parameters for name in pair.split("~"))}
        return new_model, new_pred

    def recheck(self) -> None:
        """Backward check of forward selection, as the steady finder's: an effect added before others is taken
        out again when, with the later ones in, it no longer passes the rule it passed (:func:`judge` at the
        search's alpha): its parameters back to the given model's, the chain realigned and the others refitted
        together without it (:meth:`_together`), against the current model. Early in the search an effect can
        win that a later one explains better (the wind-up mode before FREQ_LONG in the benchmark's "in-plane
        stiffness")."""
        for cand in list(self.added[:-1]):
            rest = [c for c in self.added if c is not cand]
            model = self.given.with_params(**{p: float(self.model.params[p]) for c in rest for p in c.parameters})
            pred = self.sim(model)
            prob = self._problem(pred)
            saved = [(c.values, c.stderr, c.correlation) for c in rest]
            out = self._together(rest, model, pred, prob)
            if out is not None:
                model, pred = out
                prob = self._problem(pred)
            why = self._scored(prob.residuals(pred), self.prob.residuals(self.pred), prob, len(cand.parameters),
                               self.alpha).note
            if not why:
                for c, (values, stderr, correlation) in zip(rest, saved):
                    c.values, c.stderr, c.correlation = values, stderr, correlation
                continue
            self.added.remove(cand)
            self.rejected[cand.name] = (f"added, then taken out: with {', '.join(c.name for c in rest)} refitted "
                                        f"without it, {why}")
            self.say(f"taken out {cand.name}: {self.rejected[cand.name]}")
            self._align(model, pred)


def _cutoff_text(chain) -> str:
    return "none" if chain.cutoff is None else f"{chain.cutoff:.4g} Hz ({chain.order}-pole)"


def _rms(runs, pred, chain, names) -> dict:
    """channel -> RMS of measured less the chain's image of the prediction ``pred`` over the runs ``names`` (the
    samples measured)."""
    out = {}
    for c in sorted({c for r in runs for c in r.measured}):
        m = [r for r in runs if r.name in names and c in r.measured]
        if m:
            e = np.concatenate([chain(pred[r.name][c], r, c) - r.measured[c] for r in m])
            out[c] = float(np.sqrt(np.mean(e[~np.isnan(np.concatenate([r.measured[c] for r in m]))] ** 2)))
    return out


def _gaps(runs, prob, pred, alpha) -> list:
    """The findings (:class:`mftyre.gaps.locate.Finding`, variable: the run's kind) of a run and channel whose
    residual exceeds the noise at ``alpha``: an F test of its chi-square per independent sample against the noise
    variance, which is itself estimated from the quiet lead-ins (samples/tau independent samples), so a noise level
    known from few samples claims no gap. Largest excess first."""
    res = prob.residuals(pred)
    out = []
    for r in runs:
        for c in r.measured:
            noise = prob.noise[c]
            n_eff = np.count_nonzero(~np.isnan(r.measured[c])) / noise["tau"]
            chi2 = _chi2(res, {(r.name, c)})
            p = float(stats.f.sf(chi2 / n_eff, n_eff, max(noise["samples"] / noise["tau"], 1.0)))
            if p < alpha:
                rms = _rms([r], pred, prob.chain, {r.name})[c]
                out.append(Finding(c, (r.kind,), chi2, int(round(n_eff)), p, 1.0 - n_eff / chi2, chi2 - n_eff,
                                   where=f"run {r.name}", rms=rms, sigma=noise["sigma"]))
    out.sort(key=lambda f: -f.excess)
    return out


#: Refit coordinates of the measurement chain (nuisance parameters fitted with every candidate): delay in ms, the
#: filter's cutoff as cutoff0 exp(0.1 d); and the range they may take.
_CHAIN_STEP = (1e-3, 0.1)
_DELAY_RANGE, _CUTOFF_RANGE = (-0.005, 0.03), (20.0, 500.0)


def _chain_limits(chain0, top) -> list:
    """Bounds of the moves of ``chain0`` (:func:`_chain_at` units) that keep its delay in :data:`_DELAY_RANGE` and its
    cutoff in :data:`_CUTOFF_RANGE` below ``top``: [delay bounds] and, with a filter, [cutoff bounds]."""
    d0, c0 = chain0.delay, chain0.cutoff
    out = [((_DELAY_RANGE[0] - d0) / _CHAIN_STEP[0], (_DELAY_RANGE[1] - d0) / _CHAIN_STEP[0])]
    if c0 is not None:
        out.append((math.log(_CUTOFF_RANGE[0] / c0) / _CHAIN_STEP[1],
                    math.log(min(_CUTOFF_RANGE[1], top) / c0) / _CHAIN_STEP[1]))
    return out


def refined(chain, runs, pred, noise, names) -> Chain:
    """``chain`` with its delay and cutoff refined continuously on the runs ``names`` against the prediction
    ``pred`` (lmfit's least squares of the noise-weighted residuals, the calibration fitted with every trial): the
    freedom every candidate's refit has (:func:`_refit`), given to the current model too, so that no candidate is
    credited with the chain's own refinement. The alignment's grid is 10-25 % coarse in the cutoff: a rig at 93 Hz
    aligned at 100 Hz left a misfit (and a load-cell gain 1 % off) that a contact-length change took in a
    control."""
    sub = [r for r in runs if r.name in names]
    limits = _chain_limits(chain, NYQUIST_SHARE * 0.5 / max(r.dt for r in runs))
    lp = lmfit.Parameters()
    for j, (lo, hi) in enumerate(limits):
        lp.add(f"c{j}", value=0.0, min=lo, max=hi)

    def at(p):
        return _chain_at(chain, [p[f"c{j}"].value for j in range(len(limits))] + [0.0] * (2 - len(limits))
                         ).calibrated(sub, pred)

    def residual(p):
        return np.concatenate(list(_Problem(runs, at(p), noise).residuals(pred, names).values()))

    out = lmfit.minimize(residual, lp, method="least_squares", diff_step=1e-3, x_scale="jac")
    return at(out.params)


def _chain_at(chain0, dc) -> Chain:
    """``chain0`` moved by ``dc`` (delay in ms, the cutoff by exp(0.1 dc[1])), in :data:`_CHAIN_STEP` units."""
    cutoff = None if chain0.cutoff is None else chain0.cutoff * math.exp(_CHAIN_STEP[1] * dc[1])
    return replace(chain0, delay=chain0.delay + _CHAIN_STEP[0] * dc[0], cutoff=cutoff)


def _chain_columns(prob, pred, train, keys_train, r0):
    """Sensitivity of the weighted training residuals ``r0`` to the chain's nuisances (no simulation): its delay and
    cutoff (finite differences), and per channel its gain and drift (exact: linear)."""
    cols = []
    for j in range(1 if prob.chain.cutoff is None else 2):
        dc = np.zeros(2)
        dc[j] = 0.1
        rr = _Problem(prob.runs, _chain_at(prob.chain, dc), prob.noise).residuals(pred, train)
        cols.append((np.concatenate([rr[k] for k in keys_train]) - r0) / 0.1)
    run = {r.name: r for r in prob.runs}
    blocks = {k: prob.weighted(run[k[0]], k[1], pred[k[0]][k[1]]) for k in keys_train}
    for c in sorted({k[1] for k in keys_train}):
        n = prob.noise[c]
        w = n["sigma"] * math.sqrt(n["tau"])
        for part in ("gain", "drift"):
            col = []
            for k in keys_train:
                r = run[k[0]]
                if k[1] != c:
                    col.append(np.zeros_like(blocks[k]))
                elif part == "gain":
                    col.append(prob.chain.dynamics(pred[k[0]][c], r.dt) / w)
                else:
                    col.append((r.t - r.t[0]) / w)
            cols.append(np.concatenate(col))
    return np.column_stack(cols)


def _refit(effect, model, pred, prob, sim, runs, train, keys_train):
    """The effect's parameters refitted on the training runs of its kinds, in three stages: the parameters alone
    with the measurement chain held; the chain aligned afresh to that candidate (the grid of :func:`align`: the
    filter's presence and a start for the cutoff); then the parameters together with the chain's delay and cutoff
    (nuisance parameters). Each stage by lmfit's least squares (trust-region reflective) with the Jacobian of
    finite differences (a parameter column: one simulation; a chain column: none). Jointly because
    a lag the model adds (a relaxation length, a softer sidewall) and the chain's lag trade off: fitted in turn,
    the chain kept part of the gap and the parameter stopped short (PTY1 of the MF 5.2 file: 1.31 +- 0.012 for a
    truth of 1.22). The parameters' covariance is the marginal one (chain included, :func:`_covariance`: model
    error and the correlation within runs counted). (model, prediction on all runs, delta, covariance of delta,
    the candidate's _Problem) or None."""
    k = len(effect.parameters)
    base = given_values(model, effect.parameters)
    sub = [r for r in runs if r.kind in effect.kinds]
    sub_train = [r for r in sub if r.name in train]
    train_runs = [r for r in runs if r.name in train]
    simulated = {}

    def prefetch(dps):  # the candidate's training predictions, one simulation per parameter vector, at once
        keys = {tuple(np.round(dp, 12)): dp for dp in dps}
        new = {key: dp for key, dp in keys.items() if key not in simulated}
        if len(simulated) + len(new) > 2 * k + 4:
            kept = {key: simulated[key] for key in keys if key in simulated}
            simulated.clear()
            simulated.update(kept)
        models = {}
        for key, dp in new.items():
            simulated[key] = None  # out of bounds, or the model cannot be built or simulated
            if _bounds_ok(effect, dp):
                try:
                    models[key] = _with(model, effect, base, dp)
                except ModelInputError:
                    pass
        for key, out in zip(models, sim.many(list(models.values()), sub_train) if models else []):
            simulated[key] = None if isinstance(out, ModelInputError) else {**pred, **out}
        return [simulated[key] for key in keys]

    def predict(dp):
        return prefetch([dp])[0]

    top = NYQUIST_SHARE * 0.5 / max(r.dt for r in runs)  # the filter's cutoff stays below Nyquist

    def resid(delta, chain0):
        chain = _chain_at(chain0, delta[k:])
        if not (_DELAY_RANGE[0] <= chain.delay <= _DELAY_RANGE[1]
                and (chain.cutoff is None or _CUTOFF_RANGE[0] <= chain.cutoff <= min(_CUTOFF_RANGE[1], top))):
            return None
        p = predict(delta[:k])
        if p is None:
            return None
        chain = chain.calibrated(train_runs, p)  # the calibration fitted with every trial (linear: projected out)
        rr = _Problem(runs, chain, prob.noise).residuals(p, train)
        v = np.concatenate([rr[key] for key in keys_train])
        return v if np.all(np.isfinite(v)) else None

    def jacobian(delta, r, chain0, free):  # finite differences (a parameter column: one simulation; chain: none)
        prefetch([delta[:k] + 0.1 * (np.arange(k) == j) for j in free if j < k])
        cols = []
        for j in free:
            d = delta.copy()
            d[j] += 0.1
            rj = resid(d, chain0)
            cols.append(np.zeros_like(r) if rj is None else (rj - r) / 0.1)
        return np.column_stack(cols)

    def fit(delta, chain0, free, evaluations):  # lmfit's least squares on the coordinates ``free``, our Jacobian
        lp = lmfit.Parameters()
        limits = {k + j: lim for j, lim in enumerate(_chain_limits(chain0, top))}
        for j in free:
            lo, hi = limits.get(j, (-11.9, 11.9))
            lp.add(f"d{j}", value=float(np.clip(delta[j], lo, hi)), min=lo, max=hi)

        def full(p):
            d = delta.copy()
            d[free] = [p[f"d{j}"].value for j in free]
            return d

        def residual(p):
            v = resid(full(p), chain0)
            return np.full(size, 1e3) if v is None else v  # a tyre that cannot be built: far from any optimum

        def jac(p):
            d = full(p)
            v = resid(d, chain0)
            return np.zeros((size, len(free))) if v is None else jacobian(d, v, chain0, free)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            out = lmfit.Minimizer(residual, lp).minimize(method="least_squares", jac=jac, max_nfev=evaluations,
                                                         x_scale="jac", ftol=1e-3, xtol=1e-4)
        d = full(out.params)
        r = resid(d, chain0)
        return (delta, resid(delta, chain0)) if r is None else (d, r)

    params = list(range(k))
    delta = np.zeros(k + 2)  # parameters, then the chain's delay and cutoff moves
    r = resid(delta, prob.chain)
    if r is None:
        return None
    size = r.size
    delta, r = fit(delta, prob.chain, params, 8)
    if not np.any(delta[:k]):
        return None
    try:  # the chain aligned afresh to this candidate
        aligned_to = {**pred, **sim(_with(model, effect, base, delta[:k]), sub_train)}
        cells = _aligned(train_runs, aligned_to, sim.runner)
    except ModelInputError:
        return None
    best = None
    for order in ORDERS:  # from the best cell of each filter order: a filter's order and a damping trade off
        chain0 = _best([(fine, c) for fine, c in cells if c.order == order]).calibrated(train_runs, aligned_to)
        free = params + [k] + ([k + 1] if chain0.cutoff is not None else [])
        if resid(delta, chain0) is None:
            continue
        d, r = fit(delta, chain0, free, 10)
        if best is None or r @ r < best[2] @ best[2]:
            best = d, chain0, r, free
    if best is None:
        return None
    delta, chain0, r, free = best
    J = jacobian(delta, r, chain0, free)  # the covariance from a fresh Jacobian at the optimum
    new_model = _with(model, effect, base, delta[:k])
    try:
        full = {**pred, **sim(new_model, sub)}
    except ModelInputError:
        return None
    return new_model, full, delta[:k], _covariance(J, r, runs, keys_train, prob.n_eff(train))[:k, :k], \
        _Problem(runs, _chain_at(chain0, delta[k:]).calibrated(train_runs, full), prob.noise)


#: Correlation beyond which two refitted parameters are not separated by the data: their values are reported with
#: the correlation and without standard errors.
SINGULAR = 0.98


def precision(cov, slopes, names) -> tuple:
    """(standard errors, near-singular pairs) of parameters ``names`` from the covariance ``cov`` of their refit
    coordinates and ``slopes`` (d value / d coordinate): a parameter in a pair correlated beyond :data:`SINGULAR`
    (or with no finite variance) gets NaN, "no +-", and the pair its correlation ("A~B" -> rho): identifiability
    before precision, the data fix only a combination of the two."""
    cov = np.asarray(cov, float)
    var = np.diag(cov)
    stderr = {p: float(math.sqrt(v) * abs(s)) if np.isfinite(v) and v > 0 else math.nan
              for p, v, s in zip(names, var, slopes)}
    pairs = {}
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            rho = cov[i, j] / math.sqrt(var[i] * var[j]) if var[i] > 0 and var[j] > 0 else math.nan
            if not abs(rho) <= SINGULAR:
                pairs[f"{names[i]}~{names[j]}"] = float(rho)
                stderr[names[i]] = stderr[names[j]] = math.nan
    return stderr, pairs


def _covariance(J, r, runs, keys, n_eff):
    """Covariance of the refitted coordinates at the optimum (Jacobian ``J`` of the weighted residuals ``r``, the
    concatenation over ``keys`` = (run, channel)): the larger, per coordinate, of (a) (J'J)^-1 scaled by the
    chi-square per independent sample where above 1 (model error the noise does not explain) and (b) the
    run-clustered sandwich (J'J)^-1 (sum over runs of g g') (J'J)^-1 G/(G-1), g = J_run' r_run: the runs as
    independent blocks, whatever the correlation and the model error within a run (with a handful of runs a rough
    estimate, hence the larger of the two). Off-diagonal terms: (a)'s."""
    bread = np.linalg.pinv(J.T @ J)
    model_based = bread * max(1.0, float(r @ r) / n_eff)
    length = {run.name: run.t.size for run in runs}
    blocks, start = {}, 0
    for run_name, _ in keys:
        blocks.setdefault(run_name, []).append(slice(start, start + length[run_name]))
        start += length[run_name]
    scores = [sum(J[sl].T @ r[sl] for sl in parts) for parts in blocks.values()]
    g = len(scores)
    if g < 2:
        return model_based
    meat = sum(np.outer(x, x) for x in scores) * g / (g - 1)
    clustered = bread @ meat @ bread
    cov = model_based.copy()
    np.fill_diagonal(cov, np.maximum(np.diag(model_based), np.diag(clustered)))
    return cov


def _findings(runs, pred, chain, noise) -> list:
    """Feature differences beyond 3 uncertainties of the given model, per run and channel, largest first."""
    out = []
    for r in runs:
        for c, y in r.measured.items():
            model_y = chain(pred[r.name][c], r, c)
            q = _quiet(chain.dynamics(pred[r.name][c], r.dt), r.dt)
            decay = None
            if r.kind == "cleat":
                dev = np.abs(model_y - model_y[0])
                big = np.flatnonzero(dev > 0.1 * dev.max()) if dev.max() > 0 else []
                decay = int(big[-1]) if len(big) and big[-1] < y.size - 40 else None
            x = r.inputs["X"]
            s = noise[c]["sigma"]
            fm = features(y, r.t, x, r.kind, q, decay_from=decay, sigma=s)
            fs = features(model_y, r.t, x, r.kind, q, decay_from=decay, sigma=s)
            for row in compare(fm, fs, s, r.dt, float(np.mean(r.inputs["VX"]))):
                if abs(row["z"]) > 3:
                    out.append(dict(run=r.name, kind=r.kind, channel=c, **r.condition, **row))
    out.sort(key=lambda f: -abs(f["z"]))
    return out
