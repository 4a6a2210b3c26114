"""Residuals of a model on measured data, per channel; the measurement-noise estimate; held-out sweeps.

Channels: FX FY MZ MX MY and FZ (the vertical force from the measured loaded radius or deflection), predicted
by the fit's one rule (:func:`mftyre.fit.predict.predict`). A channel is used where it is measured (finite).

Noise (:func:`noise_levels`): the standard deviation of the measurement noise per channel, from the residual
differences between *repeated* points (same sweep, same nominal slip, camber, speed, pressure and turn slip, load
within 1 % of the largest, e.g. the out-and-back halves of a trailer sweep): the pooled within-group variance, which the model and any
smooth missing effect cancel from. Channels without enough repeats use neighbouring points instead: the
second difference d_i = r_i - (r_{i-1} + r_{i+1})/2 along each sweep, var(d) = 1.5 sigma^2 for white noise.

Reduced time series (:func:`noise_of_means`): the noise of a binned mean of N raw samples follows from the raw
AR(1) noise (:func:`mftyre.timeseries.measurement_noise`: the residual about a local trend within each branch of
each sweep, degrees of freedom counted for correlated noise), never from the reduced curve's neighbours.

Held-out data (:func:`holdout_mask`): whole sweeps, a quarter of the sweeps of each kind of test (``TEST`` when
present, else pure lateral / pure longitudinal / combined / free rolling / other from the slip values), stratified
over the levels of load, pressure, camber, speed and held slip, so every kind of test and the whole operating range
are represented in both parts.
"""
from __future__ import annotations

import math

import numpy as np

from ..data import TyreData, split_sweeps
from ..fit.predict import BatchPredictor, predict
from ..model import MFModel
from .drift import FORCE_CHANNELS, Drifting, friction_nodes, predict_drifting

__all__ = ["CHANNELS", "UNITS", "Evaluator", "noise_levels", "noise_of_means", "noise_floor_of", "holdout_mask",
           "stratified_holdout", "condition_levels", "test_kind"]

#: Channels the gap finder maps, in report order.
CHANNELS = ("FX", "FY", "MZ", "MX", "MY", "FZ")
UNITS = {"FX": "N", "FY": "N", "FZ": "N", "MX": "N m", "MY": "N m", "MZ": "N m"}
_KAPPA_TOL, _ALPHA_TOL = 0.005, math.radians(0.25)


class Evaluator:
    """Predictions and residuals of parameter sets on one data set (inputs converted once).

    ``channels``: the channels to use (default: every one of :data:`CHANNELS` measured); ``turn_slip``: evaluate
    with turn slip (default: when the data have turn slip)."""

    def __init__(self, data: TyreData, channels=None, turn_slip: bool | None = None):
        self.data = data
        self.inputs = data.inputs()
        self.turn_slip = bool(np.any(self.inputs["phit"] != 0)) if turn_slip is None else bool(turn_slip)
        avail = [c for c in CHANNELS if self._measured(c) is not None]
        self.channels = tuple(c for c in (channels or CHANNELS) if c in avail)
        self.measured, self.rows = {}, {}
        for c in self.channels:
            m = self._measured(c)
            ok = np.isfinite(m)
            if c == "FZ":
                ok &= self._rl_or_rho_finite()
            self.rows[c] = ok
            self.measured[c] = m[ok]

    def _measured(self, c):
        d = self.data
        if c == "FZ":
            return d.array("FZ") if (d.has("RL") or d.has("RHO")) else None
        return d.array(c) if d.has(c) else None

    def _rl_or_rho_finite(self):
        d = self.data
        if d.has("RL"):
            return np.isfinite(d.array("RL"))
        return np.isfinite(d.array("RHO"))

    def predict(self, params, channels=None) -> dict:
        """Channel -> model values at the channel's rows (the fit's rule, :func:`mftyre.fit.predict.predict`; with
        the friction drift of :class:`mftyre.gaps.drift.Drifting` parameters)."""
        channels = self.channels if channels is None else [c for c in channels if c in self.channels]
        prm = params.params if isinstance(params, MFModel) else params

        def plain(p, chans):
            return predict(p if isinstance(p, MFModel) else MFModel(p), self.data, chans, self.inputs,
                           turn_slip=self.turn_slip)

        pred = predict_drifting(plain, prm, self.data, channels) if isinstance(prm, Drifting) else \
            plain(params, channels)
        return {c: pred[c][self.rows[c]] for c in channels}

    def batch(self, params, names, channels=None):
        """A function of (K, len(names)) values: channel -> (K, rows of the channel) predictions of ``params`` with
        ``names`` set to each row's values, the K sets in one vectorised evaluation
        (:class:`mftyre.fit.predict.BatchPredictor`; :meth:`predict`'s values). With :class:`Drifting`
        parameters (``names`` may hold drift coefficients) the force channels are evaluated at each set's friction
        nodes (:func:`mftyre.gaps.drift.friction_nodes`), all sets' nodes in the same evaluation."""
        channels = self.channels if channels is None else [c for c in channels if c in self.channels]
        prm = params.params if isinstance(params, MFModel) else params
        names = list(names)
        if not isinstance(prm, Drifting):
            plain = BatchPredictor(prm, self.data, channels, names, self.inputs, turn_slip=self.turn_slip)
            return lambda values: {c: v[:, self.rows[c]] for c, v in plain(values).items()}
        tyre = prm.tyre
        tyre_names = [n for n in names if n not in prm.drift]
        forces = [c for c in channels if c in FORCE_CHANNELS]
        others = [c for c in channels if c not in forces]
        scaled = tyre_names + [n for n in ("LMUX", "LMUY") if n not in tyre_names]
        at_nodes = BatchPredictor(tyre, self.data, forces, scaled, self.inputs, turn_slip=self.turn_slip) \
            if forces else None
        plain = BatchPredictor(tyre, self.data, others, tyre_names, self.inputs, turn_slip=self.turn_slip) \
            if others else None
        tyre_col = [names.index(n) for n in tyre_names]
        friction = [scaled.index(n) for n in ("LMUX", "LMUY")]
        fixed = np.array([float(tyre[n]) for n in scaled])

        drift_col = [i for i, n in enumerate(names) if n in prm.drift]
        nodes_of = {}   # drift coefficients -> their friction nodes (the same for every set of a tyre refit)

        def run(values):
            values = np.atleast_2d(np.asarray(values, float))
            out = plain(values[:, tyre_col]) if plain is not None else {}
            if at_nodes is not None:
                sets, rows = [], []
                for v in values:
                    key = tuple(v[drift_col])
                    if key not in nodes_of:
                        nodes_of[key] = friction_nodes({**prm.drift, **{names[i]: v[i] for i in drift_col}},
                                                       self.data)
                    nodes, weights = nodes_of[key]
                    base = fixed.copy()
                    base[:len(tyre_names)] = v[tyre_col]
                    for m in nodes:
                        row = base.copy()
                        row[friction] *= m
                        rows.append(row)
                    sets.append(weights)
                pred = at_nodes(np.array(rows))
                start = np.cumsum([0] + [len(w) for w in sets])
                for c in forces:
                    out[c] = np.stack([sum(w * pred[c][i0 + j] for j, w in enumerate(ws))
                                       for i0, ws in zip(start, sets)])
            return {c: out[c][:, self.rows[c]] for c in channels}

        return run

    def residuals(self, params, channels=None) -> dict:
        """Channel -> model - measured at the channel's rows."""
        pred = self.predict(params, channels)
        return {c: pred[c] - self.measured[c] for c in pred}

    def frame_rows(self, c):
        """Row indices (into ``data``) of channel ``c``."""
        return np.flatnonzero(self.rows[c])


def sweep_labels(data: TyreData) -> np.ndarray:
    if "SWEEP" in data:
        return data.frame["SWEEP"].to_numpy()
    return split_sweeps(data).frame["SWEEP"].to_numpy()


def noise_levels(ev: Evaluator, residuals: dict, min_dof: int = 20) -> dict:
    """Channel -> (sigma, method): measurement-noise standard deviation from repeats or neighbours."""
    d = ev.data
    sweep = sweep_labels(d)
    fz_step = 0.01 * float(np.max(np.abs(d.array("FZ")))) or 1.0   # the load is recorded with noise
    key_cols = [np.round(d.array(c) / s).astype(np.int64) for c, s in
                (("SA", 1e-5), ("SL", 1e-5), ("IA", 1e-5), ("VX", 1e-3), ("P", 1.0), ("PHIT", 1e-6), ("FZ", fz_step))]
    out = {}
    for c, r in residuals.items():
        idx = ev.frame_rows(c)
        keys = np.stack([sweep[idx]] + [k[idx] for k in key_cols], axis=1)
        _, group = np.unique(keys, axis=0, return_inverse=True)
        group = np.ravel(group)
        counts = np.bincount(group)
        means = np.bincount(group, weights=r) / counts
        dev = r - means[group]
        dof = int(np.sum(counts[counts > 1] - 1))
        if dof >= min_dof:
            sq = dev[counts[group] > 1] ** 2
            var = float(np.sum(sq)) / dof
            # one pass of 5-sigma clipping (a spike in one half of a pair would dominate)
            keep = sq <= 25.0 * var
            var = float(np.sum(sq[keep])) / max(dof - int(np.sum(~keep)), 1)
            out[c] = (math.sqrt(max(var, 0.0)), f"repeated points ({dof} dof)")
            continue
        sw = sweep[idx]
        same = (sw[1:-1] == sw[:-2]) & (sw[1:-1] == sw[2:])
        d2 = r[1:-1] - 0.5 * (r[:-2] + r[2:])
        d2 = d2[same]
        if d2.size >= 5:
            var = float(np.mean(d2**2)) / 1.5
            keep = d2**2 <= 25 * 1.5 * var
            var = float(np.mean(d2[keep] ** 2)) / 1.5
            out[c] = (math.sqrt(var), f"neighbouring points ({d2.size} second differences)")
        else:
            out[c] = (float(np.std(r)) or 1.0, "residual spread (no repeats or neighbours)")
        if out[c][0] <= 0:
            out[c] = (1e-9, out[c][1])
    return out


def test_kind(data: TyreData) -> np.ndarray:
    """The kind of test of every row: the TEST column, else from the slip values."""
    if "TEST" in data:
        return data.frame["TEST"].astype(str).to_numpy()
    if "KIND" in data:   # recognised by :func:`mftyre.programme.recognise`
        return data.frame["KIND"].astype(str).to_numpy()
    sa, sl = np.abs(data.array("SA")) > _ALPHA_TOL, np.abs(data.array("SL")) > _KAPPA_TOL
    kind = np.where(sa & sl, "combined", np.where(sa, "pure_lateral", np.where(sl, "pure_longitudinal",
                                                                                "free_rolling")))
    return kind


#: Factors the held-out sweeps are spread over, with the step that separates two levels (absolute, and relative to
#: the largest magnitude): load, pressure, camber, speed and the slip held fixed during a sweep.
_LEVEL_STEPS = {"FZ": (0.0, 0.08), "P": (0.0, 0.05), "IA": (math.radians(0.5), 0.0), "VX": (0.5, 0.05),
                "HELD_SLIP": (0.01, 0.05)}


def _levels(values: np.ndarray, absolute: float, relative: float) -> np.ndarray:
    """Level index of each value: sorted values split where neighbours differ by more than the step."""
    step = absolute + relative * float(np.max(np.abs(values), initial=0.0))
    order = np.argsort(values, kind="stable")
    jumps = np.concatenate([[0], np.cumsum(np.diff(values[order]) > step)])
    out = np.empty(values.size, int)
    out[order] = jumps
    return out


def _sweep_conditions(data: TyreData, sweep: np.ndarray, ids: list) -> np.ndarray:
    """(sweeps x factors) level indices of each sweep's median load, pressure, camber, speed and held slip (the
    slip angle of a slip-ratio sweep, the slip ratio of a slip-angle sweep: whichever varies less)."""
    cols = {c: data.array(c) for c in ("FZ", "P", "IA", "VX", "SA", "SL")}
    med = {c: np.zeros(len(ids)) for c in _LEVEL_STEPS}
    for i, s in enumerate(ids):
        rows = sweep == s
        for c in ("FZ", "P", "IA", "VX"):
            med[c][i] = np.nanmedian(cols[c][rows]) if np.isfinite(cols[c][rows]).any() else 0.0
        sa, sl = np.nan_to_num(cols["SA"][rows]), np.nan_to_num(cols["SL"][rows])
        held = sa if np.ptp(sa) / math.radians(1.0) < np.ptp(sl) / 0.01 else sl
        med["HELD_SLIP"][i] = np.median(held)
    return np.stack([_levels(med[c], *_LEVEL_STEPS[c]) for c in _LEVEL_STEPS], axis=1)


def holdout_mask(data: TyreData, fraction: float = 0.25, seed: int = 0) -> np.ndarray:
    """Boolean mask of the held-out rows: whole sweeps, a ``fraction`` of the sweeps of each kind of test (kinds
    with fewer than three sweeps are not held out), stratified, sweep by sweep (kinds in turn): never the last
    training sweep of a level if another choice keeps every level in the training data; then the one whose load,
    pressure, camber, speed and held-slip levels are least held out so far within its kind, then over all kinds;
    then the one farthest from the middle levels (a condition's effect is nil at its nominal level, so sweeps
    held out at nominal conditions cannot show it); ties broken in an order drawn with
    ``seed``. Every level of every condition is held out somewhere when the sweeps allow it, and none vanishes
    from the training data."""
    sweep = sweep_labels(data)
    kind = test_kind(data)
    if fraction <= 0:
        return np.zeros(len(data), bool)
    ids = list(dict.fromkeys(sweep))
    level = _sweep_conditions(data, sweep, ids)
    kind_of = np.array([kind[np.argmax(sweep == s)] for s in ids])
    held = stratified_holdout(level, kind_of, fraction, seed)
    return np.isin(sweep, np.asarray(ids)[held])


def condition_levels(values: np.ndarray, absolute: float, relative: float) -> np.ndarray:
    """Level index of each value (:func:`stratified_holdout`'s levels): sorted values split where neighbours
    differ by more than ``absolute`` + ``relative`` x the largest magnitude."""
    return _levels(np.asarray(values, float), absolute, relative)


def stratified_holdout(level: np.ndarray, kind_of: np.ndarray, fraction: float, seed: int = 0,
                       count=lambda n, fraction: round(n * fraction), min_units: int = 3) -> np.ndarray:
    """The one rule of held-out evidence, for steady sweeps (:func:`holdout_mask`) and dynamic runs
    (:mod:`mftyre.gaps.dynamic`): ``level`` (units x factors) level indices of each unit's conditions, ``kind_of``
    each unit's kind of test; boolean per unit, held out. Per kind with at least ``min_units`` units a ``fraction`` of
    them (``count(units of the kind, fraction)``: how many; at least one), unit by unit by the priorities of
    :func:`holdout_mask`."""
    level = np.asarray(level)
    kind_of = np.asarray(kind_of)
    held = np.zeros(len(kind_of), bool)
    if fraction <= 0 or len(kind_of) == 0:
        return held
    rank = np.random.default_rng(seed).permutation(len(kind_of))
    n_factors = level.shape[1]
    # distance of each sweep's levels from the middle level of each condition (in levels)
    off_centre = np.sum(np.abs(level - 0.5 * level.max(axis=0)), axis=1)
    held_count = [dict() for _ in range(n_factors)]             # factor -> level -> held-out sweeps
    train_count = [dict(zip(*np.unique(level[:, f], return_counts=True))) for f in range(n_factors)]
    for k in sorted(set(kind_of)):
        pool = list(np.flatnonzero(kind_of == k))
        if len(pool) < min_units:
            continue
        for _ in range(max(1, int(count(len(pool), fraction)))):
            def priority(i):
                vanish = sum(train_count[f][level[i, f]] <= 1 for f in range(n_factors))
                in_kind = sum(np.count_nonzero(held & (kind_of == k) & (level[:, f] == level[i, f]))
                              for f in range(n_factors))
                spread = sum(held_count[f].get(level[i, f], 0) for f in range(n_factors))
                return vanish, in_kind, spread, -off_centre[i], rank[i]
            best = min(pool, key=priority)
            pool.remove(best)
            held[best] = True
            for f in range(n_factors):
                held_count[f][level[best, f]] = held_count[f].get(level[best, f], 0) + 1
                train_count[f][level[best, f]] -= 1
    return held


def noise_of_means(raw: TyreData, programme, reduced: TyreData, channels, vertical_stiffness: float):
    """Channel -> (sigma, method): the measurement noise of a *reduced* point (the mean of N raw samples) from
    the raw time series: sigma and rho of its AR(1) noise about the sweeps' local trend
    (:func:`mftyre.timeseries.measurement_noise`) and the median N of the reduced points,
    sigma_mean^2 = sigma^2 (1 + 2 sum_k (1 - k/N) rho^k) / N (:func:`mftyre.timeseries.mean_variance_factor`).
    FZ (from the loaded radius): the noise of FZ + the vertical stiffness x RL (FZ - cz RHO), which holds the
    noise of both and not the load control's scatter (a real load change the loaded radius follows)."""
    from ..timeseries import mean_variance_factor, measurement_noise

    n_med = float(np.median(reduced.array("N"))) if "N" in reduced else 1.0
    out = {}

    def of(ch):
        if not raw.has(ch):
            return None
        est = measurement_noise(raw, programme, ch)
        if est is None:
            return None
        s, rho = est
        return s * math.sqrt(mean_variance_factor(rho, n_med)), rho

    for c in channels:
        if c == "FZ":  # FZ from the loaded radius: the noise of FZ + cz RL (or FZ - cz RHO), the load's own scatter out
            deflection = "RL" if raw.has("RL") else "RHO" if raw.has("RHO") else None
            if deflection is None or not raw.has("FZ"):
                continue
            sign = 1.0 if deflection == "RL" else -1.0
            est = measurement_noise(raw, programme, "FZ",
                                    values=raw.array("FZ") + sign * vertical_stiffness * raw.array(deflection))
            if est is not None:
                out[c] = (max(est[0] * math.sqrt(mean_variance_factor(est[1], n_med)), 1e-9),
                          f"noise of FZ {'+' if sign > 0 else '-'} cz {deflection} about the sweeps' local trend "
                          f"(AR(1), lag-one correlation {est[1]:.2f}) over the median {n_med:.0f} samples per point")
        else:
            e = of(c)
            if e is not None:
                out[c] = (max(e[0], 1e-9), f"noise about the sweeps' local trend (AR(1), lag-one correlation "
                                           f"{e[1]:.2f}) over the median {n_med:.0f} samples per point")
    return out


def noise_floor_of(ev, test_mask, sigma: dict) -> dict:
    """Channel -> the normalised RMS error [%] the noise ``sigma`` alone gives on the held-out rows of ``ev``."""
    out = {}
    for c in sigma:
        if c not in ev.rows:
            continue
        rows = ev.rows[c] & test_mask
        meas = ev.data.array(c)[rows]
        if meas.size and np.any(meas):
            out[c] = 100.0 * sigma[c][0] / math.sqrt(float(np.mean(meas**2)))
    return out
