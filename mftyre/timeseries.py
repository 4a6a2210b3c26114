"""Time series of a rig (100 Hz and more): reduce each sweep to binned means, measure the hysteresis, count the
independent samples.

* :func:`reduce_sweeps`: per recognised sweep (:func:`mftyre.programme.recognise`) and branch (up / down), the
  samples (with the programme's level of load, pressure and camber: FZ_LEVEL, P_LEVEL, IA_LEVEL) are averaged
  in ``bins`` equal bins of the swept channel (same edges for both branches). The branches stay apart in
  ``Reduction.branches``; ``Reduction.mean`` averages the up and down branch of each bin (so what is left of a
  first-order lag cancels to first order) and is what a fit uses. Steady segments give one mean row each;
  transitions are left out (counted in the history).
* relaxation: a slip sweep's force follows the slip the contact has relaxed to, not the recorded one (first-order
  lag over the travelled distance, :func:`relaxed_slip`). Where the data carry TIME, the relaxation length of
  each slip-angle (slip-ratio) sweep is the one that collapses the sweep's FY (FX) against the relaxed slip onto
  one curve (:func:`relaxation_length`: least within-bin variance); ``Reduction.mean`` is binned in the relaxed
  slip. At a car tyre's 0.2 deg of lag this changes little; at a large tyre's 3-4 m relaxation length swept at
  6 deg/s and 3 m/s (6-8 deg of lag in a 12 deg sweep) the up/down mean alone is far from the steady-state
  curve (Fy 44 %, Mz 178 % normalised RMS off the tyre's own), the relaxed slip's mean is close to it.
* :func:`hysteresis`: half the difference up - down of the branch means (in the recorded slip), per sweep and
  channel: its RMS over the bins (``amplitude``) and the largest (``peak``), the transient effect of the
  relaxation length that a steady-state model must not be asked to explain.
* :func:`effective_samples`: n_eff = sum over sweeps of n (1 - r) / (1 + r), r the lag-one autocorrelation of
  the residuals within the sweep (the AR(1) rule); use it for every significance test and uncertainty
  instead of the number of rows.
* :func:`measurement_noise`: the standard deviation and lag-one correlation of a channel's AR(1) measurement noise
  from its residual about a local trend within each branch of each sweep (blocks of 0.2 s: a cubic in time and
  the measured load as regressors), the residual's expected sum of squares and lag-one sum for AR(1) noise
  counted exactly for the fitted regressors (so right for white and coloured noise at 100 Hz and at kHz rates;
  second differences of the samples see the sweep's own curvature once the noise is correlated over several
  samples). The one noise estimate of sampled data: the gap finder's noise of binned means derives from it.
* :func:`needs_reduction`: whether the data are dense enough (a time series) for the reduction to pay.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import minimize_scalar
from scipy.signal import lfilter

from .data import TyreData
from .programme import Programme, recognise

__all__ = ["reduce_sweeps", "Reduction", "relaxed_slip", "relaxation_length", "hysteresis", "both_ways",
           "effective_samples", "needs_reduction", "lag_one_correlation", "scatter_about_bins",
           "measurement_noise", "mean_variance_factor"]

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
    relaxation: pd.DataFrame | None = None

    def summary(self) -> str:
        text = (f"{self.rows_in} samples reduced to {len(self.mean)} points (binned means per sweep, up and down "
                f"branches averaged); {self.rows_dropped} transition samples left out")
        hyst = self.hysteresis
        hyst = hyst[hyst["kind"].isin(["slip_angle", "slip_ratio"]) & hyst["channel"].isin(["FX", "FY", "MZ"])]
        if len(hyst):
            h = hyst.groupby(["kind", "channel"])["amplitude"].median()
            text += "; hysteresis (half up-down difference, RMS, median over sweeps): " + ", ".join(
                f"{ch} {v:.3g} ({kind})" for (kind, ch), v in h.items())
        if self.relaxation is not None and len(self.relaxation):
            text += "; slip relaxation undone (means binned in the relaxed slip): " + _relaxation_summary(
                self.relaxation)
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
    """Binned means per sweep and branch (see the module text); ``min_per_bin`` samples or the bin is dropped.
    ``branches`` are binned in the recorded slip (their difference is the hysteresis), ``mean`` in the relaxed
    slip of slip sweeps with TIME (``relaxation``: the relaxation length per sweep, :func:`relaxation_length`)."""
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
    sweeps = np.unique(sweep_id[sweep_id >= 0])
    members = {s: np.flatnonzero(sweep_id == s) for s in sweeps}
    found = {s: _sweep_relaxation(frame, idx, kind[idx[0]], bins) for s, idx in members.items()}
    relaxation = pd.DataFrame([dict(sweep=int(s), kind=kind[members[s][0]], length=f[0], spread_ratio=f[1],
                                    condition=tuple(values[members[s][0], [numeric.index(c) for c in _CONDITION]]))
                               for s, f in found.items() if f is not None],
                              columns=["sweep", "kind", "length", "spread_ratio", "condition"])
    branch_parts, mean_parts = [], []
    for s in sweeps:
        idx = members[s]
        k = kind[idx[0]]
        col = numeric.index(_SWEPT[k])
        per = _branch_means(values[idx], col, branch[idx], numeric, bins, min_per_bin)
        branch_parts += [part.assign(BRANCH=direction, SWEEP=s, KIND=k) for direction, part in per.items()]
        if found[s] is not None:
            # both slips relaxed: the swept one with the sweep's length, the held one (the slip angle of a
            # combined sweep, still relaxing from the ramp before it) with that of its sweeps at the condition
            sigma, _, step, window = found[s]
            relaxed = values[idx].copy()
            for other in _RELAXED_FORCE:
                length = sigma if other == k else _condition_length(relaxation, other, values[idx[0]], numeric)
                if length is not None:
                    c = numeric.index(_SWEPT[other])
                    relaxed[:, c] = relaxed_slip(values[window, c], step, length)[window.size - idx.size:]
            per = _branch_means(relaxed, col, branch[idx], numeric, bins, min_per_bin)
        if len(per) == 2:
            # bins measured one way only are left out unless the lag was undone (then nothing is left to cancel)
            up, down = (per[d].set_index("BIN") for d in (1, -1))
            common = up.index.intersection(down.index)
            both = (up.loc[common, numeric] + down.loc[common, numeric]) / 2.0
            both["N"] = up.loc[common, "N"] + down.loc[common, "N"]
            if found[s] is not None:
                both = pd.concat([both, up.drop(common), down.drop(common)]).sort_index()
            both = both.reset_index()
        elif per:
            both = next(iter(per.values()))
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
    relaxation = relaxation.drop(columns=["condition"])
    if len(relaxation):
        note += "; slip relaxation undone: " + _relaxation_summary(relaxation)
    mean_data = data.with_frame(mean, note)
    branch_data = data.with_frame(branches, note.replace("averaged", "kept apart"))
    return Reduction(mean_data, branch_data, hysteresis(branches), prog, len(frame), dropped, relaxation)


def _branch_means(values, col, branch, numeric, bins, min_per_bin) -> dict:
    """{direction: DataFrame of the bin means of that branch (columns ``numeric``, N, BIN)} of one sweep's
    samples ``values`` binned in column ``col`` (the same edges for both branches)."""
    x = values[:, col]
    edges = np.linspace(np.min(x), np.max(x), bins + 1)
    b = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
    per = {}
    for direction in (1, -1):
        sel = branch == direction
        if not sel.any():
            continue
        keys = b[sel]
        cnt = np.bincount(keys, minlength=bins)
        sums = np.zeros((bins, values.shape[1]))
        np.add.at(sums, keys, values[sel])
        ok = cnt >= min_per_bin
        part = pd.DataFrame(sums[ok] / cnt[ok, None], columns=numeric)
        part["N"], part["BIN"] = cnt[ok], np.flatnonzero(ok)
        per[direction] = part
    return per


#: the force whose curve over the relaxed slip a sweep's relaxation length straightens, per kind of sweep
_RELAXED_FORCE = {"slip_angle": "FY", "slip_ratio": "FX"}
#: the levels that make a sweep's condition (the relaxation length of its held slip is its kind's there)
_CONDITION = ("FZ_LEVEL", "P_LEVEL", "IA_LEVEL")


def _condition_length(relaxation: pd.DataFrame, kind: str, row, numeric) -> float | None:
    """The median relaxation length of the sweeps of ``kind`` at the condition (load, pressure and camber level)
    of ``row``; over all of that kind's sweeps when none is at the condition; None when there is none."""
    own = relaxation[relaxation["kind"] == kind]
    if not len(own):
        return None
    key = tuple(row[[numeric.index(c) for c in _CONDITION]])
    here = own["length"][[c == key for c in own["condition"]]]
    return float(np.median(here if len(here) else own["length"]))


def _sweep_relaxation(frame, idx, kind, bins):
    """(relaxation length [m], spread ratio, distance step [m], rows) of one slip sweep: ``rows`` the sweep's
    rows ``idx`` preceded by the samples before it, evenly in time, up to as many as the sweep has (the contact
    is still relaxing from what came before when the sweep starts); None when the sweep is no slip sweep, has no
    TIME, force or forward speed, or is sampled unevenly."""
    force = _RELAXED_FORCE.get(kind)
    if force is None or "TIME" not in frame or force not in frame:
        return None
    time, vx = frame["TIME"].to_numpy(float), frame["VX"].to_numpy(float)[idx]
    f, x = frame[force].to_numpy(float)[idx], frame[_SWEPT[kind]].to_numpy(float)
    dt = np.diff(time[idx])
    finite = np.all(np.isfinite(dt)) and np.all(np.isfinite(f + x[idx] + vx))
    if idx.size < 4 * bins or not (finite and np.all(dt > 0)):
        return None
    typical = float(np.median(dt))
    step = typical * float(np.median(vx))
    if not (step > 0 and np.all(np.abs(dt / typical - 1.0) < 0.5)):
        return None
    # the samples before the sweep, back to a time gap or a slip that is not finite
    first = max(int(idx[0]) - idx.size, 0)
    before = np.arange(first, int(idx[0]))
    gaps = np.flatnonzero(~(np.abs(np.diff(time[np.r_[before, idx[0]]]) / typical - 1.0) < 0.5)
                          | ~np.isfinite(x[before]))
    if gaps.size:
        before = before[gaps[-1] + 1:]
    rows = np.r_[before, idx]
    length, ratio = relaxation_length(x[rows], f, step, bins)
    return length, ratio, step, rows


def relaxed_slip(slip, distance_step, length):
    """The slip the contact has relaxed to (first-order lag over the travelled distance, Pacejka 2012, eq. 7.8:
    d(x_t)/ds = (x - x_t) / sigma): x_t[k] = a_k x_t[k-1] + (1 - a_k) x[k], a_k = exp(-ds_k / sigma_k), from
    x_t[0] = x[0] (exact for a slip held over each step). ``distance_step`` ds and ``length`` sigma [m]: scalars or
    arrays of the slip's size; a length of 0 returns the slip."""
    slip = np.asarray(slip, dtype=float)
    a = np.exp(-np.asarray(distance_step, float) / np.maximum(length, 1e-12))
    if np.ndim(a) == 0:
        if slip.size == 0 or a == 0.0:
            return slip.copy()
        return lfilter([1.0 - a], [1.0, -a], slip, zi=[a * slip[0]])[0]
    a = np.broadcast_to(a, slip.shape)
    out = np.empty_like(slip)
    x_t = slip[0] if slip.size else 0.0
    for k in range(slip.size):
        x_t = a[k] * x_t + (1.0 - a[k]) * slip[k]
        out[k] = x_t
    return out


def relaxation_length(slip, force, distance_step: float, bins: int = 40) -> tuple[float, float]:
    """(sigma [m], spread ratio): the relaxation length that lays a sweep's force samples (in time order, swept up
    and down) onto one curve over the relaxed slip (:func:`relaxed_slip`): the least within-bin variance of the
    force in ``bins`` bins of the relaxed slip, over sigma = 0 and a log grid from one distance step to the
    distance the sweep travels (a sweep to 4 deg at 3 m/s travels 2-3 relaxation lengths of a tractor tyre),
    refined between the best point's neighbours (bounded Brent search in log sigma). ``slip`` may start with samples
    before the sweep (the contact relaxes from them): its last ``force.size`` samples are the sweep's. The spread
    ratio is that variance at sigma over the one at sigma = 0 (1: no lag seen)."""
    slip, force = np.asarray(slip, float), np.asarray(force, float)
    lead = slip.size - force.size

    def spread(sigma):
        x = relaxed_slip(slip, distance_step, sigma)[lead:]
        edges = np.linspace(np.min(x), np.max(x), bins + 1)
        b = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
        cnt = np.bincount(b, minlength=bins)
        s1, s2 = np.bincount(b, force, bins), np.bincount(b, force * force, bins)
        ok = cnt > 1
        return float(np.sum(s2[ok] - s1[ok] ** 2 / cnt[ok]) / max(int(np.sum(cnt[ok])), 1))

    far = distance_step * force.size
    if far <= 2.0 * distance_step:
        return 0.0, 1.0
    grid = np.concatenate([[0.0], np.geomspace(distance_step, far, 48)])
    cost = np.array([spread(g) for g in grid])
    best = int(np.argmin(cost))
    sigma, value = float(grid[best]), float(cost[best])
    if best > 0:  # refined in log sigma between the neighbours
        lo, hi = math.log(grid[max(best - 1, 1)]), math.log(grid[min(best + 1, grid.size - 1)])
        found = minimize_scalar(lambda t: spread(math.exp(t)), bounds=(lo, hi), method="bounded",
                                options={"xatol": 1e-3})
        if found.fun < value:
            sigma, value = math.exp(float(found.x)), float(found.fun)
    return float(sigma), float(value / cost[0]) if cost[0] > 0 else 1.0


def _relaxation_summary(relaxation: pd.DataFrame) -> str:
    h = relaxation.groupby("kind")
    return ", ".join(f"{kind.replace('_', '-')} sweeps: relaxation length {grp['length'].median():.3g} m (median), "
                     f"force spread about the curve {100 * grp['spread_ratio'].median():.3g} % of that over the "
                     "recorded slip" for kind, grp in h)


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


def scatter_about_bins(data: TyreData, programme: Programme, channel: str, *, bins: int = 40,
                       by_branch: bool = False) -> np.ndarray:
    """Per sample of the sweeps (NaN elsewhere): ``channel``, scaled to the bin's mean load (a force about
    proportional to the load: the load control's scatter is no scatter of the measurement), minus the line fitted
    to it over the swept slip in its bin (a line, not a mean: the characteristic's slope within a bin is no scatter
    either); the bins are ``bins`` equal parts of the swept slip's range within each sweep, both branches together
    (``by_branch=False``: the scatter at equal load, pressure, camber and slip, the data's repeatability) or each
    branch apart (``True``: the residual about the sweep's smooth trend, the measurement noise, hysteresis left
    out). Scaled by sqrt(n / (n - 2)) for the two coefficients fitted to the bin's n samples; bins of fewer than 6
    samples give NaN."""
    rows = programme.rows
    sweep, branch, kind = (rows[c].to_numpy() for c in ("SWEEP", "BRANCH", "KIND"))
    y, fz = data.array(channel), data.array("FZ")
    out = np.full(len(data), np.nan)
    for s in np.unique(sweep[sweep >= 0]):
        idx = np.flatnonzero(sweep == s)
        swept = _SWEPT.get(kind[idx[0]], "SA")
        slip = data.array(swept)[idx]
        lo, hi = float(np.min(slip)), float(np.max(slip))
        b = np.clip(((slip - lo) / max(hi - lo, 1e-300) * bins).astype(int), 0, bins - 1)
        key = b * 3 + (np.sign(branch[idx]).astype(int) + 1 if by_branch else 0)
        ys, load = y[idx], fz[idx]
        ok = np.isfinite(ys) & np.isfinite(slip) & np.isfinite(load)
        k, x, v = key[ok], slip[ok], ys[ok]
        n = np.bincount(k, minlength=3 * bins)

        def bin_mean(c):
            return (np.bincount(k, c, minlength=3 * bins) / np.maximum(n, 1))[k]

        if swept != "FZ":  # at equal load: the force scaled to the bin's mean load (about proportional to it)
            v = v * bin_mean(load[ok]) / np.where(load[ok] != 0, load[ok], np.nan)
        xc, yc = x - bin_mean(x), v - bin_mean(v)
        sxx = np.bincount(k, xc * xc, minlength=3 * bins)
        slope = np.bincount(k, xc * yc, minlength=3 * bins) / np.where(sxx > 0, sxx, 1.0)
        resid = yc - slope[k] * xc
        dev = np.full(idx.size, np.nan)
        dev[ok] = np.where(n[k] >= 6, resid * np.sqrt(n[k] / np.maximum(n[k] - 2, 1)), np.nan)
        out[idx] = dev
    return out


def _lag_sums(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """sum over blocks and columns of x . (T_d y) for d = 0..m-1, where T_0 = I and T_d = S^d + S^-d (S the shift
    along axis 1, m = x.shape[1]): the coefficients of the AR(1) correlation matrix R(rho) = sum_d rho^d T_d
    (R_ij = rho^|i-j|) in sum x . (R y)."""
    m = x.shape[1]
    out = np.empty(m)
    out[0] = np.einsum("bmk,bmk->", x, y)
    for d in range(1, m):
        out[d] = np.einsum("bmk,bmk->", x[:, d:], y[:, :-d]) + np.einsum("bmk,bmk->", x[:, :-d], y[:, d:])
    return out


def _ar1_traces(q: np.ndarray):
    """traces(rho) -> (sum over blocks of tr(M R), of tr(U M R M)) for blocks of regressors ``q`` (blocks, m, k;
    orthonormal columns or zero ones), M = I - Q Q^T, U the shift (U x)_i = x_(i+1), R = R(rho) the AR(1)
    correlation matrix. tr(M R) = m - tr(Q^T R Q) and tr(U M R M) = (m - 1) rho - sum (U + U^T) Q . R Q
    + tr(Q^T U Q Q^T R Q), each linear in R = sum_d rho^d T_d: polynomials in rho whose coefficients are lag sums."""
    nb, m, _ = q.shape
    uq, utq = np.zeros_like(q), np.zeros_like(q)
    uq[:, :-1], utq[:, 1:] = q[:, 1:], q[:, :-1]
    qtuq = np.einsum("bmk,bml->bkl", q, uq)
    trace_qrq = _lag_sums(q, q)
    trace_umrm = _lag_sums(np.einsum("bml,bkl->bmk", q, qtuq) - uq - utq, q)
    powers = np.arange(m)

    def traces(rho):
        rho_d = rho ** powers
        return nb * m - float(rho_d @ trace_qrq), nb * (m - 1) * rho + float(rho_d @ trace_umrm)

    return traces


def measurement_noise(data: TyreData, programme: Programme, channel: str, *, window: float = 0.2, degree: int = 3,
                      values=None):
    """(sigma, rho) of the AR(1) measurement noise of ``channel`` in the swept rows of a time series, or None with
    fewer than 3 blocks. ``values``: a series of the rows to take instead of the channel (no load regressor; e.g.
    FZ + VERTICAL_STIFFNESS x RL, whose noise is the vertical force's from the loaded radius, the load control's
    scatter cancelled).

    Each branch of each sweep (``programme.rows`` SWEEP and BRANCH, contiguous runs) is cut into blocks of
    ``window`` seconds (TIME; 20 samples without it), longer where the noise is correlated over more than a sixth
    of that (6 (1 + rho) / (1 - rho) samples, from a first pass): in each block the samples are fitted by least
    squares with a polynomial of ``degree`` in time and, for a channel other than FZ, the measured load FZ (the
    load control's scatter is a real force change the model sees, not noise). For residuals r = M e,
    M = I - Q Q^T (Q an orthonormal basis of the block's regressors) and noise e of variance sigma^2 and
    correlation R(rho) (R_ij = rho^|i-j|): E[r.r] = sigma^2 tr(M R), E[sum r_t r_(t+1)] = sigma^2 tr(U M R M) (U the
    shift). rho solves the measured ratio of the two sums (bisection), sigma^2 = sum r.r / sum tr(M R): the
    regressors' degrees of freedom counted for white and for correlated noise alike."""
    rows = programme.rows
    sweep, branch = rows["SWEEP"].to_numpy(), rows["BRANCH"].to_numpy()
    y = data.array(channel) if values is None else np.asarray(values, float)
    cov = data.array("FZ") if values is None and channel != "FZ" and data.has("FZ") else None
    ok = (sweep >= 0) & np.isfinite(y) & (np.isfinite(cov) if cov is not None else True)
    dt = np.diff(data.array("TIME")) if data.has("TIME") else np.array([])
    dt = dt[np.isfinite(dt) & (dt > 0)]
    m = max(int(round(window / float(np.median(dt)))) if dt.size else 20, 2 * (degree + 3))
    key = np.where(ok, sweep * 3 + branch + 1, -1)
    runs = [r for r in np.split(np.arange(y.size), np.flatnonzero(key[1:] != key[:-1]) + 1) if key[r[0]] >= 0]
    est = _noise_in_blocks(y, cov, runs, m, degree)
    if est is not None:
        longer = int(math.ceil(6.0 * (1.0 + est[1]) / (1.0 - est[1])))
        if longer > m:
            est = _noise_in_blocks(y, cov, runs, longer, degree) or est
    return est


def _noise_in_blocks(y, cov, runs, m, degree):
    """(sigma, rho) of :func:`measurement_noise` with blocks of ``m`` samples, None with fewer than 3 blocks."""
    starts = []
    for run in runs:
        if run.size >= m:
            k = run.size // m
            starts.extend(run[0] + (run.size - k * m) // 2 + m * np.arange(k))
    if len(starts) < 3:
        return None
    idx = np.asarray(starts)[:, None] + np.arange(m)[None, :]
    x = np.repeat(np.vander(np.linspace(-1.0, 1.0, m), degree + 1)[None], idx.shape[0], axis=0)
    if cov is not None:
        c = cov[idx] - cov[idx].mean(axis=1, keepdims=True)
        x = np.concatenate([x, c[:, :, None]], axis=2)
    q, tri = np.linalg.qr(x)
    diag = np.abs(np.diagonal(tri, axis1=1, axis2=2))
    q = q * (diag > 1e-9 * diag.max(axis=1, keepdims=True))[:, None, :]  # a load constant in the block: no column
    v = y[idx]
    res = v - np.einsum("bmk,bk->bm", q, np.einsum("bmk,bm->bk", q, v))
    rss, lag = float(np.sum(res * res)), float(np.sum(res[:, 1:] * res[:, :-1]))
    if rss <= 0:
        return 0.0, 0.0
    traces = _ar1_traces(q)

    target = lag / rss
    lo, hi = 0.0, 0.999
    for rho in (lo, hi):
        a, b = traces(rho)
        if (rho == lo and target <= b / a) or (rho == hi and target >= b / a):
            return math.sqrt(rss / a), rho
    for _ in range(16):
        mid = 0.5 * (lo + hi)
        a, b = traces(mid)
        lo, hi = (mid, hi) if b / a < target else (lo, mid)
    rho = 0.5 * (lo + hi)
    return math.sqrt(rss / traces(rho)[0]), rho


def mean_variance_factor(rho: float, n: float) -> float:
    """Var(mean of n AR(1) samples) / sigma^2 = (1 + 2 sum_k (1 - k/n) rho^k) / n, k = 1 ... n - 1."""
    n = max(int(round(n)), 1)
    k = np.arange(1, n)
    return float((1.0 + 2.0 * np.sum((1.0 - k / n) * rho**k)) / n)
