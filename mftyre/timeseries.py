"""Time series of a rig (100 Hz and more): reduce each sweep to binned means, measure the hysteresis, count the
independent samples.

* :func:`reduce_sweeps`: per recognised sweep (:func:`mftyre.programme.recognise`) and branch (up / down), the
  samples (with the programme's level of load, pressure and camber: FZ_LEVEL, P_LEVEL, IA_LEVEL) are averaged
  in ``bins`` equal bins of the swept channel (same edges for both branches). The branches stay apart in
  ``Reduction.branches``; ``Reduction.mean`` averages the up and down branch of each bin (so a first-order lag
  cancels) and is what a fit uses. Steady segments give one mean row each; transitions are left out (counted
  in the history).
* :func:`hysteresis`: half the difference up - down of the branch means, per sweep and channel: its RMS over
  the bins (``amplitude``) and the largest (``peak``), the transient effect of the relaxation length that a
  steady-state model must not be asked to explain.
* :func:`effective_samples`: n_eff = sum over sweeps of n (1 - r) / (1 + r), r the lag-one autocorrelation of
  the residuals within the sweep (the AR(1) rule); use it for every significance test and uncertainty
  instead of the number of rows.
* :func:`needs_reduction`: whether the data are dense enough (a time series) for the reduction to pay.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .data import TyreData
from .programme import Programme, recognise

__all__ = ["reduce_sweeps", "Reduction", "hysteresis", "both_ways", "effective_samples", "needs_reduction",
           "lag_one_correlation"]

_SWEPT = {"slip_angle": "SA", "slip_ratio": "SL", "speed": "VX", "load": "FZ"}
_RESPONSE = ("FX", "FY", "MX", "MY", "MZ", "RL", "RHO", "RE")


@dataclass
class Reduction:
    """Result of :func:`reduce_sweeps`: ``mean`` (TyreData, branch-averaged bin means plus steady points; columns
    SWEEP, KIND, N = samples averaged), ``branches`` (TyreData, per sweep, branch (BRANCH +1/-1) and bin),
    ``hysteresis`` (DataFrame, see :func:`hysteresis`), ``programme`` and ``rows_in`` / ``rows_dropped``."""

    mean: TyreData
    branches: TyreData
    hysteresis: pd.DataFrame
    programme: Programme
    rows_in: int
    rows_dropped: int

    def summary(self) -> str:
        text = (f"{self.rows_in} samples reduced to {len(self.mean)} points (binned means per sweep, up and down "
                f"branches averaged); {self.rows_dropped} transition samples left out")
        hyst = self.hysteresis
        hyst = hyst[hyst["kind"].isin(["slip_angle", "slip_ratio"]) & hyst["channel"].isin(["FX", "FY", "MZ"])]
        if len(hyst):
            h = hyst.groupby(["kind", "channel"])["amplitude"].median()
            text += "; hysteresis (half up-down difference, RMS, median over sweeps): " + ", ".join(
                f"{ch} {v:.3g} ({kind})" for (kind, ch), v in h.items())
        return text


def needs_reduction(data: TyreData, programme: Programme | None = None, bins: int = 40) -> bool:
    """True when the median sweep branch holds at least 2 samples per bin (a sampled time series)."""
    prog = programme or recognise(data)
    sweeps = prog.sweeps
    if not len(sweeps):
        return False
    swept = sweeps[sweeps["kind"].isin(list(_SWEPT))]
    if not len(swept):
        return False
    per_branch = swept["n"] / np.maximum(1, (swept["reversals"] + 1))
    return bool(np.median(per_branch) >= 2 * bins)


def reduce_sweeps(data: TyreData, programme: Programme | None = None, *, bins: int = 40,
                  min_per_bin: int = 2) -> Reduction:
    """Binned means per sweep and branch (see the module text); ``min_per_bin`` samples or the bin is dropped."""
    prog = programme or recognise(data)
    rows = prog.rows
    frame = data.frame.assign(**{c: rows[c].to_numpy() for c in ("FZ_LEVEL", "P_LEVEL", "IA_LEVEL")})
    numeric = [c for c in frame.columns if pd.api.types.is_numeric_dtype(frame[c])
               and c not in ("SWEEP", "BRANCH", "SEGMENT")]
    values = frame[numeric].to_numpy(float)
    sweep_id = rows["SWEEP"].to_numpy()
    branch = rows["BRANCH"].to_numpy()
    kind = rows["KIND"].to_numpy()
    seg = rows["SEGMENT"].to_numpy()
    branch_parts, mean_parts = [], []
    for s in np.unique(sweep_id[sweep_id >= 0]):
        idx = np.flatnonzero(sweep_id == s)
        k = kind[idx[0]]
        ch = _SWEPT[k]
        x = frame[ch].to_numpy(float)[idx]
        edges = np.linspace(np.min(x), np.max(x), bins + 1)
        b = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
        per = {}
        for direction in (1, -1):
            sel = branch[idx] == direction
            if not sel.any():
                continue
            keys = b[sel]
            cnt = np.bincount(keys, minlength=bins)
            sums = np.zeros((bins, len(numeric)))
            np.add.at(sums, keys, values[idx[sel]])
            ok = cnt >= min_per_bin
            means = sums[ok] / cnt[ok, None]
            part = pd.DataFrame(means, columns=numeric)
            part["N"], part["BIN"], part["BRANCH"], part["SWEEP"], part["KIND"] = cnt[ok], np.flatnonzero(ok), \
                direction, s, k
            per[direction] = part
            branch_parts.append(part)
        if len(per) == 2:
            up, down = (per[d].set_index("BIN") for d in (1, -1))
            common = up.index.intersection(down.index)
            both = (up.loc[common, numeric] + down.loc[common, numeric]) / 2.0
            both["N"] = up.loc[common, "N"] + down.loc[common, "N"]
            both = both.reset_index()
        elif per:
            both = next(iter(per.values())).drop(columns=["BRANCH"])
        else:
            continue
        both["SWEEP"], both["KIND"] = s, k
        mean_parts.append(both.drop(columns=["BIN"]))
    # steady segments: one mean each
    for g in np.unique(seg[(kind == "steady")]):
        idx = np.flatnonzero(seg == g)
        part = pd.DataFrame(values[idx].mean(axis=0)[None, :], columns=numeric)
        part["N"], part["SWEEP"], part["KIND"] = idx.size, -1, "steady"
        mean_parts.append(part)
    mean = pd.concat(mean_parts, ignore_index=True) if mean_parts else frame.iloc[:0].copy()
    branches = pd.concat(branch_parts, ignore_index=True) if branch_parts else frame.iloc[:0].copy()
    dropped = int(np.sum(kind == "transition"))
    note = (f"reduced per sweep: {len(frame)} samples -> {len(mean)} binned means ({bins} bins per sweep, up and "
            f"down branches averaged); {dropped} transition samples left out")
    mean_data = data.with_frame(mean, note)
    branch_data = data.with_frame(branches, note.replace("averaged", "kept apart"))
    return Reduction(mean_data, branch_data, hysteresis(branches), prog, len(frame), dropped)


def hysteresis(branches) -> pd.DataFrame:
    """Half the up - down difference of the branch means per sweep and response channel: one row per (sweep,
    channel) with kind, amplitude (RMS over the bins measured both ways), peak (largest magnitude), bins."""
    frame = branches.frame if isinstance(branches, TyreData) else branches
    out = []
    if not len(frame) or "BRANCH" not in frame:
        return pd.DataFrame(columns=["sweep", "kind", "channel", "amplitude", "peak", "bins"])
    for s, grp in frame.groupby("SWEEP"):
        up, down = both_ways(grp)
        if len(up) < 3:
            continue
        for ch in _RESPONSE:
            if ch not in grp or not np.isfinite(grp[ch]).any():
                continue
            d = 0.5 * (up[ch].to_numpy(float) - down[ch].to_numpy(float))
            d = d[np.isfinite(d)]
            if d.size:
                out.append(dict(sweep=int(s), kind=grp["KIND"].iloc[0], channel=ch,
                                amplitude=float(np.sqrt(np.mean(d**2))), peak=float(np.max(np.abs(d))),
                                bins=int(d.size)))
    return pd.DataFrame(out, columns=["sweep", "kind", "channel", "amplitude", "peak", "bins"])


def both_ways(sweep: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The bins of one sweep's branch means (rows of ``Reduction.branches`` with one SWEEP) measured both ways:
    (up, down), the BRANCH +1 and -1 rows indexed by BIN, each restricted to the bins the other has too."""
    up = sweep[sweep["BRANCH"] == 1].set_index("BIN")
    down = sweep[sweep["BRANCH"] == -1].set_index("BIN")
    common = up.index.intersection(down.index)
    return up.loc[common], down.loc[common]


def lag_one_correlation(x) -> float:
    """Lag-one autocorrelation of a series (about its mean); 0 for fewer than 3 finite values."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if x.size < 3:
        return 0.0
    x = x - x.mean()
    den = float(x @ x)
    return float(x[1:] @ x[:-1] / den) if den > 0 else 0.0


def effective_samples(residuals, groups=None) -> float:
    """Effective number of independent samples of ``residuals`` (in measurement order): the sum over ``groups``
    (e.g. the SWEEP column; None: one group) of n (1 - r) / (1 + r), r the lag-one autocorrelation within the
    group clipped to [0, 0.999]; each group counts at least 1."""
    res = np.asarray(residuals, float)
    if groups is None:
        groups = np.zeros(res.size, int)
    groups = np.asarray(groups)
    total = 0.0
    for g in pd.unique(groups):
        r = res[groups == g]
        r = r[np.isfinite(r)]
        if r.size == 0:
            continue
        rho = min(max(lag_one_correlation(r), 0.0), 0.999)
        total += max(1.0, r.size * (1.0 - rho) / (1.0 + rho))
    return total
