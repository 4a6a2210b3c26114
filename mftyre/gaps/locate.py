"""Locate structure in the residuals: which condition variables explain the residual beyond measurement noise.

For every channel the residuals are standardised by the channel's noise level sigma (:func:`noise_levels`),
z = (model - measured) / sigma, so that under "no structure" every cell mean of n points has variance 1/n.
The points are put into cells:

* the sweep coordinate B: for forces and moments the signed slip-angle bin x the signed slip-ratio bin (seven
  bins each: zero, and |slip| / max|slip| up to 0.2, 0.5, 1 on either side), which separates free rolling, pure
  lateral, pure longitudinal and combined slip; for FZ the deflection (six quantile bins of RHO, or of R0 - RL);
* the condition variables: load, pressure, camber, speed, turn slip (levels as the modes of the values,
  :func:`mftyre.programme.cluster_levels`; values on no level, e.g. a speed sweep, in up to four quantile bins of
  their own; more than six levels pooled into quantile bins); for FZ also the slip cell (Fx and Fy act on the
  vertical stiffness).

With known sigma the explained sum of squares of a cell-mean model, ESS = sum over cells n_c mean_c^2 (of z), is
chi-square with (number of cells) degrees of freedom when the residual is pure noise. The tests:

* shape in the sweep coordinate, separately for the free-rolling, pure-lateral, pure-longitudinal and combined
  cells (variables ``free_rolling``, ``slip_angle``, ``slip_ratio``, ``combined``; ``deflection`` for FZ):
  ESS of those cells against chi2(cells);
* a condition variable v: the increase of ESS from the cells B to the cells (v level, B), against
  chi2(extra cells): the likelihood-ratio test of "the residual's dependence on slip changes with v";
* pairs (v, w): the increase from the better single variable to (v, w, B).

A test is significant at ``alpha`` after a Bonferroni correction over all tests of the call. Findings are ranked by
their excess over noise (statistic minus degrees of freedom, in units of sigma^2). Each reports the share of the
residual variance (sum z^2) the cell model explains, where the structure is largest (level of the variable
and slip region, from the cell means) and a 95 % confidence interval of the largest cell mean.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from ..programme import cluster_levels
from .residuals import UNITS, Evaluator

__all__ = ["Finding", "locate", "row_coordinates", "cell_table"]

_CONDITIONS = (("load", "FZ"), ("pressure", "P"), ("camber", "IA"), ("speed", "VX"), ("turn_slip", "PHIT"))
_FMT = {"load": (1.0, "{:.0f} N"), "pressure": (1e-5, "{:.2f} bar"), "camber": (180 / math.pi, "{:.1f} deg"),
        "speed": (1.0, "{:.1f} m/s"), "turn_slip": (1.0, "{:.3g} 1/m")}
_NAMES = {"load": "load", "pressure": "pressure", "camber": "camber", "speed": "speed", "turn_slip": "turn slip",
          "slip": "slip", "free_rolling": "free rolling", "slip_angle": "slip angle", "slip_ratio": "longitudinal slip",
          "combined": "combined slip", "deflection": "deflection"}

#: The kinds of dynamic run (:attr:`mftyre.gaps.dynamic_runs.DynamicRun.kind`): the variable of a dynamic finding.
RUN_KINDS = {"cleat": "an obstacle run", "steer": "a step steer", "brake": "a braking step", "flat": "a flat-road run"}


@dataclass
class Finding:
    """One significant structure in a channel's residual."""

    channel: str
    variables: tuple          # ("pressure",), ("pressure", "camber"), ("slip_angle",) ...
    statistic: float          # chi-square increase (in sigma^2)
    dof: int
    p_value: float
    explained: float          # share of the residual variance explained by the cell model of the test
    excess: float             # statistic - dof: structure beyond noise, in sigma^2
    where: str = ""
    trend: str = ""
    largest: dict = field(default_factory=dict)   # the cell with the largest mean: level, region, mean, ci
    rms: float = float("nan")                     # residual RMS of the channel (physical units)
    sigma: float = float("nan")

    @property
    def text(self) -> str:
        if self.variables[0] in RUN_KINDS:  # a dynamic run's residual beyond its noise (mftyre.gaps.dynamic)
            p = f"p = {self.p_value:.1e}" if self.p_value > 0 else "p < 1e-300"
            return (f"{self.channel}: residual beyond the noise in {RUN_KINDS[self.variables[0]]} {self.where} "
                    f"(chi2 {self.statistic:.0f} on {self.dof} independent samples, {p}; residual RMS "
                    f"{self.rms:.3g}, noise {self.sigma:.3g})")
        var = " x ".join(_NAMES[v] for v in self.variables)
        shape = self.variables[0] in ("free_rolling", "slip_angle", "slip_ratio", "combined", "deflection")
        base = "deflection" if self.channel == "FZ" else "slip"
        what = f"residual structured in {var}" if shape else f"error {self.trend or 'varies with ' + var}"
        model = var if shape else f"{var} x {base}"
        unit = UNITS[self.channel]
        p = f"p = {self.p_value:.1e}" if self.p_value > 0 else "p < 1e-300"
        return (f"{self.channel}: {what}{(' ' + self.where) if self.where else ''}; {100 * self.explained:.0f}% of "
                f"residual variance explained by {model} (chi2 {self.statistic:.0f} on {self.dof} dof, {p}; "
                f"residual RMS {self.rms:.3g} {unit}, noise {self.sigma:.3g} {unit})")

    def to_dict(self) -> dict:
        return dict(channel=self.channel, variables=list(self.variables), text=self.text,
                    explained=self.explained, statistic=self.statistic, dof=self.dof, p_value=self.p_value,
                    excess=self.excess, where=self.where, trend=self.trend, largest=self.largest, rms=self.rms,
                    noise=self.sigma)


def _slip_bin(x, tol):
    xmax = float(np.max(np.abs(x))) if x.size else 0.0
    if xmax <= tol:
        return np.zeros(x.shape, int)
    a = np.abs(x) / xmax
    b = np.where(np.abs(x) <= tol, 0, np.where(a <= 0.2, 1, np.where(a <= 0.5, 2, 3)))
    return (np.sign(x) * b).astype(int)


def _level_codes(x):
    """Level index per value and the level centres: the modes of the values (:func:`mftyre.programme.cluster_levels`,
    so sweeps and points between the levels do not chain them); values on no level (a speed or load sweep) are
    pooled into up to four quantile bins of their own; more than six levels: quantile bins."""
    if x.size == 0:
        return np.zeros(0, int), np.zeros(0)
    lab, cen = cluster_levels(x)
    off = lab < 0
    if off.any():
        if off.mean() < 0.05 and len(cen):     # a few stragglers: the nearest level
            lab[off] = np.argmin(np.abs(x[off, None] - cen[None, :]), axis=1)
        else:
            edges = np.unique(np.quantile(x[off], np.linspace(0, 1, 5)))
            extra = np.clip(np.searchsorted(edges, x[off], side="right") - 1, 0, max(len(edges) - 2, 0))
            lab[off] = len(cen) + extra
            cen = np.concatenate([cen, [x[off][extra == k].mean() if np.any(extra == k) else np.nan
                                        for k in range(max(len(edges) - 1, 1))]])
    if len(cen) > 6:
        edges = np.unique(np.quantile(x, np.linspace(0, 1, 6)))
        lab = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
        cen = np.array([x[lab == k].mean() if np.any(lab == k) else np.nan for k in range(len(edges) - 1)])
    keep = np.isfinite(cen) & np.isin(np.arange(len(cen)), lab)
    remap = np.cumsum(keep) - 1
    return remap[lab], cen[keep]


def row_coordinates(ev: Evaluator, channel: str) -> dict:
    """Cell coordinates of the channel's rows: ``base`` (sweep coordinate code), ``region`` (names per row),
    ``bins`` (slip-angle bin, slip-ratio bin) and per condition variable (level code, centres)."""
    d, rows = ev.data, ev.rows[channel]
    out = {}
    sa_bin = _slip_bin(d.array("SA")[rows], math.radians(0.25))
    sl_bin = _slip_bin(d.array("SL")[rows], 0.005)
    slip_code = (sa_bin + 3) * 7 + (sl_bin + 3)
    region = np.where((sa_bin != 0) & (sl_bin != 0), "combined",
                      np.where(sa_bin != 0, "slip_angle", np.where(sl_bin != 0, "slip_ratio", "free_rolling")))
    if channel == "FZ":
        if d.has("RHO"):
            rho = d.array("RHO")[rows]
        else:
            rho = ev.data.constants.get("RFREE", np.nanmax(d.array("RL"))) - d.array("RL")[rows]
        rho = np.nan_to_num(rho)
        edges = np.unique(np.quantile(rho, np.linspace(0, 1, 7)))
        base = np.clip(np.searchsorted(edges, rho, side="right") - 1, 0, max(len(edges) - 2, 0))
        out.update(base=base, region=np.full(base.size, "deflection"), magnitude=base / max(base.max(), 1))
        slip_lab = np.unique(slip_code, return_inverse=True)[1].ravel()
        conds = {"slip": (slip_lab, None)} if slip_lab.max(initial=0) >= 1 else {}
    else:
        out.update(base=slip_code, region=region, magnitude=np.maximum(np.abs(sa_bin), np.abs(sl_bin)))
        conds = {}
    for name, ch in _CONDITIONS:
        if name == "load" and channel == "FZ":
            continue
        lab, cen = _level_codes(d.array(ch)[rows])
        if len(cen) >= 2:
            conds[name] = (lab, cen)
    out["conditions"] = conds
    return out


def _ess(z, codes):
    """(ESS, number of cells, cell codes, cell means, counts) of the cell-mean model."""
    uniq, inv = np.unique(codes, return_inverse=True)
    inv = np.ravel(inv)
    n = np.bincount(inv)
    s = np.bincount(inv, weights=z)
    mean = s / n
    return float(np.sum(n * mean**2)), len(uniq), inv, mean, n


def _combine(*codes):
    out = np.zeros(codes[0].shape, np.int64)
    for c in codes:
        c = np.asarray(c, np.int64)
        out = out * (int(c.max()) + 1 if c.size else 1) + c
    return out


def _describe_level(var, cen, k):
    if var in _FMT:
        f, fmt = _FMT[var]
        return fmt.format(cen[k] * f)
    return f"level {k}"


def _trend(var, cen, rms_by_level):
    order = np.argsort(cen)
    r = np.asarray(rms_by_level)[order]
    c = np.asarray(cen)[order]
    name = _NAMES[var]
    if len(r) < 2 or not np.all(np.isfinite(r)):
        return f"varies with {name}"
    k = int(np.argmax(r))
    if len(r) >= 3 and 0 < int(np.argmin(r)) < len(r) - 1:
        return f"grows away from {name} {_describe_level(var, c, int(np.argmin(r)))}"
    if k == len(r) - 1:
        return f"grows with {name}"
    if k == 0:
        return f"grows as {name} falls"
    return f"is largest at {name} {_describe_level(var, c, k)}"


def _region_text(channel, magnitude, region, dev, n):
    """Where the deviations are largest: slip magnitude class or region."""
    if channel == "FZ":
        groups = {"at small deflection": magnitude <= 0.34, "at medium deflection": (magnitude > 0.34) &
                  (magnitude <= 0.67), "at large deflection": magnitude > 0.67}
    else:
        groups = {"in free rolling": region == "free_rolling", "under combined slip": region == "combined",
                  "at small slip": (region != "combined") & (magnitude == 1),
                  "at medium slip": (region != "combined") & (magnitude == 2),
                  "at large slip": (region != "combined") & (magnitude == 3)}
    best, val = "", 0.0
    for text, sel in groups.items():
        if np.sum(n[sel]) == 0:
            continue
        ms = float(np.sum(n[sel] * dev[sel] ** 2) / np.sum(n[sel]))
        if ms > val:
            best, val = text, ms
    return best


def locate(ev: Evaluator, residuals: dict, sigma: dict, alpha: float = 1e-3, pairs: bool = True) -> list:
    """Significant findings, strongest first (see the module docstring for the statistics)."""
    tests = []
    for c, r in residuals.items():
        if c not in sigma or r.size < 10:
            continue
        s = sigma[c][0] if isinstance(sigma[c], tuple) else sigma[c]
        z = r / s
        tss = float(np.sum(z**2))
        coords = row_coordinates(ev, c)
        base, region, mag = coords["base"], coords["region"], coords["magnitude"]
        ess_b, ncell_b, _, _, _ = _ess(z, base)
        rms = float(np.sqrt(np.mean(r**2)))
        # shape in the sweep coordinate, per region
        for reg in np.unique(region):
            sel = region == reg
            e, k, inv, mean, n = _ess(z[sel], base[sel])
            if k < 1 or sel.sum() < 5:
                continue
            j = int(np.argmax(np.abs(mean)))
            half = 1.96 / math.sqrt(n[j])
            largest = dict(mean=float(mean[j] * s), ci95=[float((mean[j] - half) * s), float((mean[j] + half) * s)],
                           points=int(n[j]))
            tests.append(Finding(c, (str(reg),), e, k, 0.0, e / tss, e - k, "", "", largest, rms, s))
        # condition variables x sweep coordinate
        singles = {}
        for var, (lab, cen) in coords["conditions"].items():
            code = _combine(lab, base)
            e, k, inv, mean, n = _ess(z, code)
            singles[var] = (e, k, code)
            dof = k - ncell_b
            if dof <= 0:
                continue
            # deviations of the (level, B) cell means from the B cell means: where the variable matters
            _, _, inv_b, mean_b, _ = _ess(z, base)
            cell_base = np.zeros(k, int)
            cell_level = np.zeros(k, int)
            cell_base[inv] = inv_b
            cell_level[inv] = lab
            dev = mean - mean_b[cell_base]
            cell_mag = np.zeros(k)
            cell_mag[inv] = mag
            cell_reg = np.empty(k, object)
            cell_reg[inv] = region
            rms_lvl = [math.sqrt(float(np.sum(n[cell_level == q] * dev[cell_level == q] ** 2)
                                       / max(np.sum(n[cell_level == q]), 1))) for q in range(len(cen))] \
                if cen is not None else []
            trend = _trend(var, cen, rms_lvl) if cen is not None else f"varies with {_NAMES[var]}"
            where = _region_text(c, cell_mag, cell_reg, dev, n)
            j = int(np.argmax(np.abs(dev) * np.sqrt(n)))
            half = 1.96 / math.sqrt(n[j])
            largest = dict(level=_describe_level(var, cen, cell_level[j]) if cen is not None else "",
                           mean=float(mean[j] * s), ci95=[float((mean[j] - half) * s), float((mean[j] + half) * s)],
                           points=int(n[j]))
            tests.append(Finding(c, (var,), e - ess_b, dof, 0.0, e / tss, e - ess_b - dof, where, trend, largest,
                                 rms, s))
        if pairs:
            names = list(singles)
            for i in range(len(names)):
                for j2 in range(i + 1, len(names)):
                    v, w = names[i], names[j2]
                    lab_v, lab_w = coords["conditions"][v][0], coords["conditions"][w][0]
                    e, k, *_ = _ess(z, _combine(lab_v, lab_w, base))
                    best = max((singles[v], singles[w]), key=lambda t: t[0])
                    dof = k - best[1]
                    if dof <= 0:
                        continue
                    tests.append(Finding(c, (v, w), e - best[0], dof, 0.0, e / tss, e - best[0] - dof,
                                         "", f"depends on {_NAMES[v]} and {_NAMES[w]} together", {}, rms, s))
    m = max(len(tests), 1)
    out = []
    for f in tests:
        f.p_value = float(stats.chi2.sf(f.statistic, f.dof))
        if f.p_value < alpha / m and f.excess > 0:
            out.append(f)
    out.sort(key=lambda f: -f.excess)
    return out


def cell_table(ev: Evaluator, channel: str, residual: np.ndarray, variable: str):
    """For plots: (x positions of the slip/deflection cells, labels, {level text: (means, half-widths 95 %)})."""
    coords = row_coordinates(ev, channel)
    base = coords["base"]
    ub = np.unique(base)
    if channel == "FZ":
        labels = [f"d{b}" for b in ub]
    else:
        labels = []
        for b in ub:
            sa, sl = b // 7 - 3, b % 7 - 3
            labels.append(("a%+d" % sa if sa else "") + ("k%+d" % sl if sl else "") or "0")
    out = {}
    if variable in coords["conditions"]:
        lab, cen = coords["conditions"][variable]
        keys = range(len(cen)) if cen is not None else np.unique(lab)
    else:
        lab, cen, keys = np.zeros(base.size, int), None, [0]
    for q in keys:
        means, half = np.full(len(ub), np.nan), np.full(len(ub), np.nan)
        for i, b in enumerate(ub):
            sel = (base == b) & (lab == q)
            if sel.any():
                means[i] = residual[sel].mean()
                half[i] = 1.96 * residual[sel].std(ddof=1) / math.sqrt(sel.sum()) if sel.sum() > 1 else np.nan
        name = _describe_level(variable, cen, q) if cen is not None else "all"
        out[name] = (means, half)
    return np.arange(len(ub)), labels, out
