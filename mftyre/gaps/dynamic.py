"""The gap finder for dynamic tyre tests (cleat runs, step steer): the SWIFT wheel driven by the measured inputs,
compared with the measured axle forces; locate, name, add, show.

    from mftyre.gaps.dynamic import find_dynamic_gaps
    rep = find_dynamic_gaps("runs.csv", "base.tir")         # or a list of DynamicRun, an MFModel
    rep.effect_names, rep.error_before, rep.error_after, rep.noise
    rep.save("report/"); rep.write_tir("improved.tir")

Command line: ``mftyre gaps --dynamic DATA.csv --model BASE.tir [-o improved.tir] [--report DIR]``. Data layout:
:mod:`mftyre.gaps.dynamic_runs`.

1. *Align*: the measurement chain, common to all runs (one rig): a time delay of the outputs relative to the
   inputs and a causal 4th-order Butterworth anti-alias filter (cutoff from a grid including "none": the data
   say which), both fitted by least squares to the given model's prediction.
   One delay for all runs on purpose: a delay per run would absorb the very lags (relaxation, enveloping) the
   finder must see. Refitted after every effect added (the given model's errors bend it).
2. *Noise* from the data: in the quiet lead-in of every run (before the model's response departs from its level)
   the measured signal minus its mean is noise: its standard deviation per channel and its integrated
   autocorrelation time tau (samples), so that a run of n samples counts n/tau independent ones. Every
   chi-square below is sum(r^2)/(sigma^2 tau): from the noise, never from the residual being explained.
3. *Locate* (:mod:`mftyre.gaps.dynamic_locate`): per run and channel the residual chi-square per independent
   sample against the noise variance (F test with the noise's own independent samples) and the engineers' features (peaks, peak-to-peak, response length, lag and build-up distance,
   decay frequency and damping) measured beside model.
4. *Name* (:mod:`mftyre.gaps.dynamic_catalogue`): the effects the runs can test (the rest listed with the
   reason) whose kinds and channels show a gap are screened by one Gauss-Newton step on the training runs
   (finite-difference sensitivity of the simulated histories); the most promising are refitted.
5. *Add*: whole runs are held out (stratified over kind and condition). A candidate is accepted when its
   training chi-square decrease is significant (chi2(k), Bonferroni over the candidates screened), its held-out
   decrease is significant too (chi2(k) at the same level) and material (at least :data:`MATERIAL` of the held-out
   chi-square above the noise), and the improved model is verified: it builds,
   :func:`mftyre.fit.verify.verify_tir` finds no new problem, every run simulates to finite values, and the
   linearised SWIFT wheel at the static state of every condition has no mode growing faster than a damping ratio
   of -1 % that the given model lacks (eigenvalues of :meth:`swift.SwiftTyre.jacobian`; the given model's own
   growing modes are reported). The best accepted candidate (held-out decrease) is added; repeat.
6. *Show*: RMS error per channel and condition before/after on the held-out runs beside the noise floor, features
   before/after, overlaid time histories (PNG), the improved .tir (never overwriting without ``overwrite``).
"""
from __future__ import annotations

import json
import math
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import stats

from ..errors import DataError, ModelInputError
from .dynamic_catalogue import DYNAMIC_CATALOGUE, testable_effects
from .dynamic_locate import compare, features
from .dynamic_runs import MODEL_KINDS, DynamicRun, SwiftTyres, measurement_chain, read_runs, simulate

__all__ = ["find_dynamic_gaps", "DynamicGapReport", "Chain", "align", "noise_from_data", "model_kind_for"]

#: Cutoffs [Hz] tried for the anti-alias filter (None: no filter).
CUTOFFS = (None, 400.0, 300.0, 250.0, 200.0, 150.0, 120.0, 100.0, 80.0, 60.0)
#: Share of the held-out chi-square above the noise (chi2 - n/tau) an effect must explain to be added.
MATERIAL = 0.1
#: Candidates refitted fully per round (after the linearised screening).
REFIT_TOP = 3


@dataclass
class Chain:
    """The measurement chain fitted in the alignment: ``delay`` [s], ``cutoff`` [Hz] or None."""

    delay: float = 0.0
    cutoff: float | None = None

    def __call__(self, y, dt):
        return measurement_chain(y, dt, self.cutoff, self.delay)


def _sse_delay(meas, pred, dt, cutoff, delays, weights):
    total = np.zeros(len(delays))
    for r, ch in meas:
        for c, y in ch.items():
            f = measurement_chain(pred[r][c], dt[r], cutoff, 0.0)
            k = np.arange(y.size)
            for j, d in enumerate(delays):
                total[j] += np.nansum((np.interp(k - d / dt[r], k, f) - y) ** 2) / weights[c]
    return total


def align(runs, pred) -> tuple:
    """(Chain, {cutoff: chi-square}) fitted to the model prediction ``pred`` (run -> channel -> array)."""
    meas = [(r.name, r.measured) for r in runs]
    dt = {r.name: r.dt for r in runs}
    weights = {c: max(np.var(np.concatenate([r.measured[c] for r in runs if c in r.measured])), 1e-12)
               for r in runs for c in r.measured}
    delays = np.arange(-0.005, 0.0301, 0.001)
    best, table = None, {}
    for cutoff in CUTOFFS:
        sse = _sse_delay(meas, pred, dt, cutoff, delays, weights)
        j = int(np.argmin(sse))
        d = delays[j]
        if 0 < j < len(delays) - 1:  # parabola through the three best
            a, b, c = sse[j - 1], sse[j], sse[j + 1]
            den = a - 2 * b + c
            if den > 0:
                d = d + 0.5 * (a - c) / den * (delays[1] - delays[0])
        fine = _sse_delay(meas, pred, dt, cutoff, [d], weights)[0]
        table[cutoff] = fine
        if best is None or fine < best[0]:
            best = (fine, Chain(float(d), cutoff))
    return best[1], table


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
            model_y = chain(pred[r.name][c], r.dt)
            q = _quiet(model_y, r.dt)
            if q >= 30:  # measured less the model (any slow settling), less the mean (a static model error)
                e = np.asarray(y[:q], float) - model_y[:q]
                parts.setdefault(c, []).append(e - np.mean(e))
    out = {}
    for c in {c for r in runs for c in r.measured}:
        segs = parts.get(c)
        if not segs:
            raise DataError(f"channel {c}: no run has a quiet lead-in of 30 samples before the event, so the "
                            f"measurement noise cannot be estimated; start the runs earlier")
        e = np.concatenate(segs)
        out[c] = dict(sigma=float(np.sqrt(np.mean(e**2))), tau=float(np.median([_tau(s) for s in segs])),
                      samples=int(e.size), runs=len(segs))
    return out


def _holdout(runs, fraction, seed):
    """Names of the held-out runs: per kind, runs ordered by condition, every 1/fraction-th from an offset set
    by ``seed``; each kind keeps at least one training run."""
    out = set()
    for kind in sorted({r.kind for r in runs}):
        group = sorted([r for r in runs if r.kind == kind],
                       key=lambda r: (r.condition["speed"], r.condition["pressure"], r.condition["load"]))
        if len(group) < 2:
            continue
        step = max(2, int(round(1 / fraction)))
        start = seed % step
        picks = group[start::step] or group[-1:]
        out |= {r.name for r in picks[:len(group) - 1]}
    return out


class _Problem:
    """Residuals of a model on a set of runs, weighted by the noise (chi-square = sum of squares)."""

    def __init__(self, runs, chain, noise):
        self.runs, self.chain, self.noise = runs, chain, noise

    def weighted(self, run, channel, pred):
        n = self.noise[channel]
        return (self.chain(pred, run.dt) - run.measured[channel]) / (n["sigma"] * math.sqrt(n["tau"]))

    def residuals(self, pred, names=None) -> dict:
        """(run, channel) -> weighted residual array."""
        return {(r.name, c): self.weighted(r, c, pred[r.name][c]) for r in self.runs
                if names is None or r.name in names for c in r.measured}

    def n_eff(self, names) -> float:
        return sum(r.t.size / self.noise[c]["tau"] for r in self.runs if r.name in names for c in r.measured)


def _chi2(res: dict, keys=None) -> float:
    return float(sum(np.nansum(v**2) for k, v in res.items() if keys is None or k in keys))


@dataclass
class DynamicCandidate:
    name: str
    parameters: tuple
    screened_decrease: float = math.nan  # linearised training chi-square decrease
    chi2_train_before: float = math.nan
    chi2_train_after: float = math.nan
    chi2_test_before: float = math.nan
    chi2_test_after: float = math.nan
    p_train: float = math.nan
    p_test: float = math.nan
    values: dict = field(default_factory=dict)
    stderr: dict = field(default_factory=dict)
    accepted: bool = False
    note: str = ""

    def to_dict(self):
        return dict(self.__dict__)


class DynamicGapReport:
    """The outcome of :func:`find_dynamic_gaps`: ``model_given``, ``model`` (improved), ``effects_added``
    (candidate list), ``rounds`` (per round the candidates), ``untestable`` (effect -> reason), ``chain``,
    ``noise``, ``held_out`` (run names), ``error_before``/``error_after`` (channel -> held-out RMS in the
    channel's unit), ``noise_floor`` (channel -> RMS of the noise), ``by_condition`` (rows per held-out run and
    channel), ``findings`` (located feature differences of the given model), ``message``."""

    def __init__(self, **kw):
        self.__dict__.update(kw)

    @property
    def effect_names(self) -> list:
        return [c.name for c in self.effects_added]

    def to_dict(self) -> dict:
        return _jsonable(dict(message=self.message, model_kind=self.model_kind, effects_added=[c.to_dict() for c in self.effects_added],
                              rounds=[[c.to_dict() for c in r] for r in self.rounds], untestable=self.untestable,
                              chain=dict(delay=self.chain.delay, cutoff=self.chain.cutoff), noise=self.noise,
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
             f"Measurement chain fitted to the given model: delay {1e3 * self.chain.delay:.2f} ms, anti-alias "
             f"filter {'none' if self.chain.cutoff is None else f'{self.chain.cutoff:g} Hz (4th-order Butterworth)'}.",
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
            vals = ", ".join(f"{k} = {v:.5g} +- {c.stderr.get(k, math.nan):.2g}" for k, v in c.values.items())
            L.append(f"* **{c.name}**: {vals}; training chi2 {c.chi2_train_before:.0f} -> {c.chi2_train_after:.0f} "
                     f"(p {c.p_train:.2g}), held-out chi2 {c.chi2_test_before:.0f} -> {c.chi2_test_after:.0f} "
                     f"(p {c.p_test:.2g})")
        if not self.effects_added:
            L.append("none")
        L += ["", "## Candidates per round", ""]
        for i, rnd in enumerate(self.rounds, 1):
            for c in rnd:
                L.append(f"* round {i}: {c.name}: screened decrease {c.screened_decrease:.1f}"
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
        rows = [(r, c) for r in runs for c in r.measured]
        fig, axes = plt.subplots(len(rows), 1, figsize=(7, 1.8 * len(rows)), squeeze=False)
        for ax, (r, c) in zip(axes[:, 0], rows):
            ax.plot(r.t, r.measured[c], color="0.6", lw=0.8, label="measured")
            ax.plot(r.t, self.chain(self.pred_before[r.name][c], r.dt), lw=1.0, label="given model")
            ax.plot(r.t, self.chain(self.pred_after[r.name][c], r.dt), lw=1.0, ls="--", label="improved")
            ax.set_ylabel(c)
            ax.set_title(r.label(), fontsize=8)
        axes[0, 0].legend(fontsize=7)
        axes[-1, 0].set_xlabel("time [s]")
        fig.tight_layout()
        fig.savefig(path, dpi=70)
        plt.close(fig)
        return path

    def save(self, folder, *, overwrite: bool = False) -> Path:
        from ..files import write_atomically

        folder = Path(folder)
        if folder.exists() and any(folder.iterdir()) and not overwrite:
            raise DataError(f"{folder} exists and is not empty: pass overwrite=True")
        folder.mkdir(parents=True, exist_ok=True)
        write_atomically(folder / "report.md", self.markdown() + "\n![held-out runs](histories.png)\n")
        write_atomically(folder / "gaps.json", json.dumps(self.to_dict(), indent=1))
        self.plot(folder / "histories.png")
        return folder


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
    """Simulate a model on runs (``kind``: :data:`MODEL_KINDS`), building its SWIFT tyres once per parameter set;
    counts evaluations."""

    def __init__(self, runs, kind="swift"):
        self.runs, self.kind, self.evaluations = runs, kind, 0

    def __call__(self, model, runs=None):
        runs = runs or self.runs
        self.evaluations += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if self.kind == "relaxed":
                return simulate(model, runs, model_kind="relaxed")
            return simulate(model, runs, SwiftTyres(model, runs))


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


def _growth(model, runs, model_kind="swift") -> dict:
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
        tyres = SwiftTyres(model, list(seen.values()))
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
                      model_kind: str = "auto", progress=None) -> DynamicGapReport:
    """Locate, name and add the dynamic effects ``model`` misses in the runs ``data`` (module text);
    ``refit_top``: candidates refitted per round after the screening; ``model_kind``: "swift", "relaxed" or
    "auto" (:func:`model_kind_for`)."""
    from ..fit.verify import verify_tir

    t_start = time.perf_counter()
    say = progress or (lambda text: None)
    runs, model_given = _load(data, model)
    model_kind = model_kind_for(model_given, runs, model_kind)
    sim = _Sim(runs, model_kind)
    say(f"{len(runs)} runs; simulating the given model ({model_kind} wheel)")
    pred0 = sim(model_given)
    held = _holdout(runs, holdout, seed)
    train = {r.name for r in runs} - held
    train_runs = [r for r in runs if r.name in train]
    chain, chain_table = align(train_runs, pred0)
    noise = noise_from_data(runs, pred0, chain)
    say(f"aligned: delay {1e3 * chain.delay:.2f} ms, filter {chain.cutoff} Hz; noise "
        + ", ".join(f"{c} {n['sigma']:.3g} (tau {n['tau']:.1f})" for c, n in noise.items()))
    prob = _Problem(runs, chain, noise)
    testable, untestable = testable_effects(runs, model_given, catalogue, model_kind)

    # locate: features of the given model against the measurement
    findings = _findings(runs, pred0, chain, noise)
    gap_kinds = _gaps(runs, prob, pred0, alpha)

    model, pred, rounds, added = model_given, pred0, [], []
    candidates = [e for e in testable if any((k, c) in gap_kinds for k in e.kinds for c in e.channels)]
    for e in testable:
        if e not in candidates:
            untestable.setdefault(e.name, "testable, but no run of its kinds shows a gap in its channels")
    jac_cache, growth_given = {}, None
    while candidates and len(added) < max_effects:
        if added:  # only effects whose kinds and channels still show a gap beyond the noise
            gap_kinds = _gaps(runs, prob, pred, alpha)
            candidates = [e for e in candidates if any((k, c) in gap_kinds for k in e.kinds for c in e.channels)]
            if not candidates:
                break
        res = prob.residuals(pred)
        keys_train = [k for k in res if k[0] in train]
        r_train = np.concatenate([res[k] for k in keys_train])
        chi_train, chi_test = _chi2(res, set(keys_train)), _chi2(res, set(res) - set(keys_train))
        rnd = []
        say(f"round {len(rounds) + 1}: screening {len(candidates)} effects")
        # ranked by what each explains beyond the measurement chain's own freedom (its delay and cutoff take up
        # part of a lag or a frequency gap, differently for each effect: screened with the chain held, in the TNO
        # case FREQ_LONG x 0.88 the three refitted were DAMP_RESIDUAL, the wind-up mode and BELT_IYY, not FREQ_LONG)
        chain_cols = _chain_columns(prob, pred, train, keys_train, r_train)
        step, *_ = np.linalg.lstsq(chain_cols, -r_train, rcond=None)
        chain_only = float(r_train @ r_train - np.sum((r_train + chain_cols @ step) ** 2))
        for e in candidates:
            if e.name not in jac_cache:
                base = given_values(model, e.parameters)
                cols = []
                for j in range(len(e.parameters)):
                    d = np.zeros(len(e.parameters))
                    d[j] = 0.25
                    try:
                        pj = sim(_with(model, e, base, d),
                                 [r for r in runs if r.name in train and r.kind in e.kinds])
                        rj = prob.residuals({**pred, **pj}, train)
                        cols.append((np.concatenate([rj[k] for k in keys_train]) - r_train) / 0.25)
                    except ModelInputError:
                        cols.append(np.zeros_like(r_train))
                jac_cache[e.name] = np.column_stack(cols)
            J = np.column_stack([jac_cache[e.name], chain_cols])
            step, *_ = np.linalg.lstsq(J, -r_train, rcond=None)
            dec = float(r_train @ r_train - np.sum((r_train + J @ step) ** 2)) - chain_only
            rnd.append(DynamicCandidate(e.name, e.parameters, screened_decrease=dec))
        rnd.sort(key=lambda c: -c.screened_decrease)
        m_tests = len(rnd)
        best, growth = None, None
        for cand in rnd[:refit_top]:
            e = next(x for x in candidates if x.name == cand.name)
            say(f"  refitting {e.name}")
            out = _refit(e, model, pred, prob, sim, runs, train, keys_train, jac_cache[e.name])
            if out is None:
                cand.note = "refit failed (the model could not be built or simulated)"
                continue
            new_model, new_pred, delta, cov, prob_new = out
            res_new = prob_new.residuals(new_pred)
            k = len(e.parameters)
            cand.chi2_train_before, cand.chi2_test_before = chi_train, chi_test
            cand.chi2_train_after = _chi2(res_new, set(keys_train))
            cand.chi2_test_after = _chi2(res_new, set(res_new) - set(keys_train))
            cand.p_train = float(stats.chi2.sf(max(chi_train - cand.chi2_train_after, 0.0), k))
            cand.p_test = float(stats.chi2.sf(max(chi_test - cand.chi2_test_after, 0.0), k)) if held else math.nan
            cand.values = {p: float(new_model.params[p]) for p in e.parameters}
            cand.stderr = {p: float(math.sqrt(max(cov[j, j], 0.0)) * _slope(e, p, cand.values[p], model.params[p]))
                           for j, p in enumerate(e.parameters)}
            level = alpha / m_tests
            if not cand.p_train < level:
                cand.note = f"training decrease not significant (p {cand.p_train:.2g} >= {level:.2g})"
                continue
            if held and not cand.p_test < level:
                cand.note = f"held-out decrease not significant (p {cand.p_test:.2g} >= {level:.2g})"
                continue
            # and material: beside a large unexplained gap a tiny improvement is significant but names nothing
            excess = (chi_test - prob.n_eff(held)) if held else (chi_train - prob.n_eff(train))
            done = (chi_test - cand.chi2_test_after) if held else (chi_train - cand.chi2_train_after)
            if done < MATERIAL * excess:
                cand.note = (f"explains {100 * done / max(excess, 1e-300):.1f} % of the held-out chi-square above "
                             f"the noise (needs {100 * MATERIAL:g} %)")
                continue
            problems = [p for p in verify_tir(new_model) if p not in verify_tir(model)]
            if problems:
                cand.note = "verification: " + "; ".join(problems[:2])
                continue
            if not all(np.all(np.isfinite(v)) for ch in new_pred.values() for v in ch.values()):
                cand.note = "the improved model gives non-finite outputs"
                continue
            if growth is None:
                growth = _growth(model, runs, model_kind)
                growth_given = growth_given or growth
            unstable = _less_stable(_growth(new_model, runs, model_kind), growth)
            if unstable:
                cand.note = "unstable: " + unstable
                continue
            cand.accepted = True
            gain = chi_test - cand.chi2_test_after if held else chi_train - cand.chi2_train_after
            if best is None or gain > best[0]:
                best = (gain, cand, new_model, new_pred)
        rounds.append(rnd)
        if best is None:
            break
        _, cand, model, pred = best
        added.append(cand)
        # the measurement chain again, now fitted to the improved model (the given model's errors bent it)
        chain, chain_table = align(train_runs, pred)
        noise = noise_from_data(runs, pred, chain)
        prob = _Problem(runs, chain, noise)
        jac_cache.clear()
        say(f"  added {cand.name}; realigned: delay {1e3 * chain.delay:.2f} ms, filter {chain.cutoff} Hz")
        candidates = [e for e in candidates if e.name != cand.name]

    # show
    def rms(p, names):
        out = {}
        for c in noise:
            e = [p[r.name][c] for r in runs if r.name in names and c in r.measured]
            m = [r for r in runs if r.name in names and c in r.measured]
            if m:
                out[c] = float(np.sqrt(np.mean(np.concatenate([(chain(x, r.dt) - r.measured[c]) ** 2
                                                               for x, r in zip(e, m)]))))
        return out

    names_eval = held or train
    by_condition = []
    for r in runs:
        for c in r.measured:
            b = float(np.sqrt(np.mean((chain(pred0[r.name][c], r.dt) - r.measured[c]) ** 2)))
            a = float(np.sqrt(np.mean((chain(pred[r.name][c], r.dt) - r.measured[c]) ** 2)))
            by_condition.append(dict(run=r.name, kind=r.kind, held_out=r.name in held, **r.condition, channel=c,
                                     rms_before=b, rms_after=a))
    err_b, err_a = rms(pred0, names_eval), rms(pred, names_eval)
    floor = {c: n["sigma"] for c, n in noise.items()}
    if added:
        msg = (f"added {len(added)} effect(s): " + "; ".join(c.name for c in added) + ". Held-out RMS "
               + ", ".join(f"{c} {err_b[c]:.3g} -> {err_a[c]:.3g} (noise {floor[c]:.3g})" for c in err_b))
    else:
        msg = ("nothing added: no effect lowered the held-out error significantly. Held-out RMS "
               + ", ".join(f"{c} {err_b[c]:.3g} (noise {floor[c]:.3g})" for c in err_b))
    return DynamicGapReport(model_given=model_given, model=model, effects_added=added, rounds=rounds,
                            untestable=untestable, chain=chain, chain_table=chain_table, noise=noise, held_out=held,
                            error_before=err_b, error_after=err_a, noise_floor=floor, by_condition=by_condition,
                            findings=findings, message=msg, runs=runs, pred_before=pred0, pred_after=pred,
                            evaluations=sim.evaluations, growth_given=growth_given, model_kind=model_kind,
                            seconds=time.perf_counter() - t_start)


def _gaps(runs, prob, pred, alpha) -> set:
    """(run kind, channel) pairs with a run whose residual exceeds the noise at ``alpha``: an F test of its
    chi-square per independent sample against the noise variance, which is itself estimated from the quiet
    lead-ins (samples/tau independent samples), so a noise level known from few samples claims no gap."""
    res = prob.residuals(pred)
    out = set()
    for r in runs:
        for c in r.measured:
            noise = prob.noise[c]
            n_eff = r.t.size / noise["tau"]
            ratio = _chi2(res, {(r.name, c)}) / n_eff
            if stats.f.sf(ratio, n_eff, max(noise["samples"] / noise["tau"], 1.0)) < alpha:
                out.add((r.kind, c))
    return out


#: Refit coordinates of the measurement chain (nuisance parameters fitted with every candidate): delay in ms, the
#: filter's cutoff as cutoff0 exp(0.1 d); and the range they may take.
_CHAIN_STEP = (1e-3, 0.1)
_DELAY_RANGE, _CUTOFF_RANGE = (-0.005, 0.03), (20.0, 500.0)


def _chain_at(chain0, dc) -> Chain:
    """``chain0`` moved by ``dc`` (delay in ms, the cutoff by exp(0.1 dc[1])), in :data:`_CHAIN_STEP` units."""
    cutoff = None if chain0.cutoff is None else chain0.cutoff * math.exp(_CHAIN_STEP[1] * dc[1])
    return Chain(chain0.delay + _CHAIN_STEP[0] * dc[0], cutoff)


def _chain_columns(prob, pred, train, keys_train, r0):
    """Sensitivity of the weighted training residuals ``r0`` to the chain's delay and cutoff (no simulation)."""
    cols = []
    for j in range(1 if prob.chain.cutoff is None else 2):
        dc = np.zeros(2)
        dc[j] = 0.1
        rr = _Problem(prob.runs, _chain_at(prob.chain, dc), prob.noise).residuals(pred, train)
        cols.append((np.concatenate([rr[k] for k in keys_train]) - r0) / 0.1)
    return np.column_stack(cols)


def _refit(effect, model, pred, prob, sim, runs, train, keys_train, J):
    """The effect's parameters refitted on the training runs of its kinds, in three stages: Gauss-Newton from the
    screening sensitivity ``J`` with the measurement chain held; the chain aligned afresh to that candidate (the
    grid of :func:`align`: the filter's presence and a start for the cutoff); then the parameters together with
    the chain's delay and cutoff (nuisance parameters) by Levenberg-Marquardt with Broyden updates. Jointly because
    a lag the model adds (a relaxation length, a softer sidewall) and the chain's lag trade off: fitted in turn,
    the chain kept part of the gap and the parameter stopped short (PTY1 of the MF 5.2 file: 1.31 +- 0.012 for a
    truth of 1.22). The parameters' covariance is the marginal one (chain included, :func:`_covariance`: model
    error and the correlation within runs counted). (model, prediction on all runs, delta, covariance of delta,
    the candidate's _Problem) or None."""
    k = len(effect.parameters)
    base = given_values(model, effect.parameters)
    sub = [r for r in runs if r.kind in effect.kinds]
    sub_train = [r for r in sub if r.name in train]
    simulated = {}
    damping = [1e-3]

    def predict(dp):  # the candidate's training prediction, one simulation per parameter vector
        key = tuple(np.round(dp, 12))
        if key not in simulated:
            if len(simulated) > 2 * k + 4:
                simulated.clear()
            p = None
            if _bounds_ok(effect, dp):
                try:
                    p = {**pred, **sim(_with(model, effect, base, dp), sub_train)}
                except ModelInputError:
                    p = None
            simulated[key] = p
        return simulated[key]

    def resid(delta, chain0):
        chain = _chain_at(chain0, delta[k:])
        if not (_DELAY_RANGE[0] <= chain.delay <= _DELAY_RANGE[1]
                and (chain.cutoff is None or _CUTOFF_RANGE[0] <= chain.cutoff <= _CUTOFF_RANGE[1])):
            return None
        p = predict(delta[:k])
        if p is None:
            return None
        rr = _Problem(runs, chain, prob.noise).residuals(p, train)
        v = np.concatenate([rr[key] for key in keys_train])
        return v if np.all(np.isfinite(v)) else None

    def jacobian(delta, r, chain0, free):  # finite differences (a parameter column: one simulation; chain: none)
        cols = []
        for j in free:
            d = delta.copy()
            d[j] += 0.1
            rj = resid(d, chain0)
            cols.append(np.zeros_like(r) if rj is None else (rj - r) / 0.1)
        return np.column_stack(cols)

    def fit(delta, r, J, chain0, free, iterations):  # Levenberg-Marquardt on the coordinates ``free``
        fresh = False  # J from finite differences at delta (else the screening's or Broyden's)
        damping[0] = 1e-3
        for _ in range(iterations):
            normal, gradient = J.T @ J, J.T @ r
            scale = np.diag(normal).copy()
            scale[scale <= 0] = 1.0
            for _try in range(6):
                step = np.zeros_like(delta)
                step[free] = -np.linalg.lstsq(normal + damping[0] * np.diag(scale), gradient, rcond=None)[0]
                r_new = resid(delta + step, chain0)
                if r_new is not None and r_new @ r_new < r @ r:
                    damping[0] = max(damping[0] / 10, 1e-6)
                    break
                damping[0] *= 10
            else:
                r_new = None
            gain = 0.0 if r_new is None else (r @ r - r_new @ r_new) / max(r @ r, 1e-300)
            if r_new is not None:
                s = step[free]
                J = J + np.outer(r_new - r - J @ s, s) / float(s @ s)  # Broyden
                delta, r = delta + step, r_new
            if gain < 1e-3:  # stalled: a stale Jacobian gets one refresh, a fresh one ends the search
                if fresh:
                    break
                J, fresh = jacobian(delta, r, chain0, free), True
                damping[0] = 1e-3
            else:
                fresh = False
        return delta, r, J

    params = list(range(k))
    delta = np.zeros(k + 2)  # parameters, then the chain's delay and cutoff moves
    r = resid(delta, prob.chain)
    if r is None:
        return None
    delta, r, _ = fit(delta, r, J.copy(), prob.chain, params, 8)
    if not np.any(delta[:k]):
        return None
    try:  # the chain aligned afresh to this candidate
        chain0, _ = align([x for x in runs if x.name in train],
                          {**pred, **sim(_with(model, effect, base, delta[:k]), sub_train)})
    except ModelInputError:
        return None
    free = params + [k] + ([k + 1] if chain0.cutoff is not None else [])
    r = resid(delta, chain0)
    if r is None:
        return None
    delta, r, _ = fit(delta, r, jacobian(delta, r, chain0, free), chain0, free, 10)
    J = jacobian(delta, r, chain0, free)  # the covariance from a fresh Jacobian at the optimum
    new_model = _with(model, effect, base, delta[:k])
    try:
        full = {**pred, **sim(new_model, sub)}
    except ModelInputError:
        return None
    return new_model, full, delta[:k], _covariance(J, r, runs, keys_train, prob.n_eff(train))[:k, :k], \
        _Problem(runs, _chain_at(chain0, delta[k:]), prob.noise)


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
            model_y = chain(pred[r.name][c], r.dt)
            q = _quiet(model_y, r.dt)
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
