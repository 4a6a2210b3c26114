"""Transient effects the gap finder names but does not fit: the up/down hysteresis of slip sweeps.

On a rig the tyre's contact deflection relaxes over a travelled distance, the relaxation length (MF: sigma_alpha
from PTY1, PTY2; sigma_kappa from PTX1-PTX3): swept up, the force lags the recorded slip; swept down, it lags the
other way. The up and down branches of a sweep (:func:`mftyre.timeseries.reduce_sweeps`) differ by about
2 |dF/dslip| sigma |dslip/dt| / V. It is the largest structure in real-rig residuals (+-150 N in Fy), and no
steady-state parameter can explain it: the fit uses the mean of the branches, and the gap finder names it here.

:func:`sweep_hysteresis`: per channel and kind of sweep, the half difference up - down of the branch means (RMS
and peak), its significance against the noise of a reduced point (chi-square over every bin measured both ways),
and, where the data carry TIME, the relaxation length it implies: the least-squares sigma of
h = -(dF/dslip) sigma (dslip/dt) / V over the bins (slope of the branch-mean curve, sweep rate from the samples),
the median over the sweeps, beside the relaxation length of the model (``sigmay`` / ``sigmax`` at the sweeps'
conditions).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from ..inputs import saturate_inputs
from ..timeseries import both_ways

__all__ = ["sweep_hysteresis"]

#: (kind of sweep, channel, swept column, model output of the relaxation length, .tir parameters)
_PAIRS = (("slip_angle", "FY", "SA", "sigmay", "PTY1, PTY2"), ("slip_angle", "MZ", "SA", "sigmay", "PTY1, PTY2"),
          ("slip_ratio", "FX", "SL", "sigmax", "PTX1, PTX2, PTX3"))
_UNIT = {"FX": "N", "FY": "N", "MZ": "N m"}
_WHAT = {"slip_angle": "slip-angle", "slip_ratio": "slip-ratio"}


def _rate(raw, rows, sweep, column) -> float:
    """Median |d slip / dt| of a sweep's moving samples (over 10-sample steps, above the sensor noise)."""
    idx = np.flatnonzero((rows["SWEEP"].to_numpy() == sweep) & (rows["BRANCH"].to_numpy() != 0))
    if idx.size < 20 or "TIME" not in raw:
        return math.nan
    x, t = raw.array(column)[idx], raw.array("TIME")[idx]
    step = 10
    dx, dt = np.abs(x[step:] - x[:-step]), t[step:] - t[:-step]
    ok = (dt > 0) & (dt < 1.0)
    return float(np.median(dx[ok] / dt[ok])) if ok.any() else math.nan


def sweep_hysteresis(reduction, raw, model, sigma: dict, alpha: float = 1e-3) -> list:
    """Named hysteresis per (kind, channel) with significant up/down differences: list of dicts with ``channel``,
    ``kind``, ``sweeps``, ``rms``, ``peak``, ``chi2``, ``dof``, ``p_value``, ``relaxation_length`` (measured, m, or
    nan), ``model_relaxation_length`` (m), ``parameters`` and ``text``."""
    if reduction is None:
        return []
    br = reduction.branches.frame
    rows = reduction.programme.rows
    out = []
    for kind, ch, col, out_name, params in _PAIRS:
        if ch not in br or ch not in sigma:
            continue
        s_mean = sigma[ch][0] if isinstance(sigma[ch], tuple) else sigma[ch]
        sub = br[br["KIND"] == kind]
        h_all, chi2, dof, lengths, model_lengths, peaks = [], 0.0, 0, [], [], []
        for sw, grp in sub.groupby("SWEEP"):
            up, down = both_ways(grp)
            if len(up) < 5:
                continue
            h = 0.5 * (up[ch].to_numpy(float) - down[ch].to_numpy(float))
            x = 0.5 * (up[col].to_numpy(float) + down[col].to_numpy(float))
            f = 0.5 * (up[ch].to_numpy(float) + down[ch].to_numpy(float))
            ok = np.isfinite(h) & np.isfinite(x) & np.isfinite(f)
            h, x, f = h[ok], x[ok], f[ok]
            if h.size < 5:
                continue
            # a bin mean of one branch holds about half the samples of a reduced point: var(h) = s_mean^2
            chi2 += float(np.sum(h**2)) / s_mean**2
            dof += h.size
            h_all.append(h)
            peaks.append(float(np.max(np.abs(h))))
            order = np.argsort(x)
            slope = np.gradient(f[order], x[order])
            rate = _rate(raw, rows, sw, col)
            vx = float(np.mean(grp["VX"]))
            if math.isfinite(rate) and rate > 0 and vx > 0:
                g = slope * rate / vx
                if float(g @ g) > 0:
                    lengths.append(-float(h[order] @ g) / float(g @ g))
            cond = grp.iloc[len(grp) // 2]
            res = model.evaluate(**saturate_inputs(model, dict(
                fz=float(np.mean(grp["FZ"])), kappa=0.0, alpha=0.0, gamma=float(cond["IA"]), phit=0.0, vx=vx,
                p=float(np.mean(grp["P"])))))
            model_lengths.append(float(res[out_name]))
        if not dof:
            continue
        p = float(stats.chi2.sf(chi2, dof))
        if p >= alpha:
            continue
        h = np.concatenate(h_all)
        sig = float(np.median(lengths)) if lengths else math.nan
        sig_model = float(np.median(model_lengths))
        rms = float(np.sqrt(np.mean(h**2)))
        text = (f"{ch}: up/down hysteresis of the {_WHAT[kind]} sweeps, +-{rms:.3g} {_UNIT[ch]} RMS (peak "
                f"{max(peaks):.3g} {_UNIT[ch]}) over {len(h_all)} sweeps (chi2 {chi2:.0f} on {dof} dof against the "
                f"noise): a transient effect, the relaxation length ({params} in the .tir), not a steady-state "
                f"one; the fit and the gap search use the mean of the up and down branches")
        if math.isfinite(sig):
            text += (f". Relaxation length implied: {sig:.3g} m (median over the sweeps); the model's: "
                     f"{sig_model:.3g} m")
        out.append(dict(channel=ch, kind=kind, sweeps=len(h_all), rms=rms, peak=max(peaks), chi2=chi2, dof=dof,
                        p_value=p, relaxation_length=sig, model_relaxation_length=sig_model, parameters=params,
                        text=text))
    out.sort(key=lambda d: -d["chi2"] / max(d["dof"], 1))
    return out
