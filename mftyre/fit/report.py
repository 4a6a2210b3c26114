"""The fit report: Markdown text (data, fit errors, the Table-2 pressure comparison of Schmeitz et al. 2005,
per-stage parameter tables with standard errors and strong correlations, parameters not fitted and why)
and PNG plots per stage (measured vs fitted per sweep at zero camber and nominal pressure, residuals of all
points) written next to it."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..data import levels
from ..model import MFModel
from .core import _predict
from .stages import STAGES, stage_rows

__all__ = ["markdown_report", "save_report", "plot_stage"]

# x axis of each stage's plot: (channel, label, factor)
_X = {"pure_fx": ("SL", "kappa [-]", 1.0), "combined_fx": ("SL", "kappa [-]", 1.0),
      "mz_combined": ("SL", "kappa [-]", 1.0), "pure_fy": ("SA", "alpha [deg]", 180 / math.pi),
      "mz": ("SA", "alpha [deg]", 180 / math.pi), "combined_fy": ("SL", "kappa [-]", 1.0),
      "mx": ("SA", "alpha [deg]", 180 / math.pi), "my": ("VX", "Vx [m/s]", 1.0),
      "vertical": ("RL", "loaded radius [m]", 1.0), "rolling_radius": ("FZ", "Fz [N]", 1.0)}
_UNIT = {"FX": "N", "FY": "N", "FZ": "N", "MX": "N m", "MY": "N m", "MZ": "N m", "RE": "m"}


def _fmt(v):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.6g}"


def markdown_report(result, plot_names: dict | None = None) -> str:
    data = result.data
    lines = [f"# Magic Formula fit: {data.tyre or 'tyre'}", ""]
    summ = {}
    for name, ch, tol, fac, unit in (("loads", "FZ", 0.05, 1.0, "N"), ("pressures", "P", 0.02, 1e-5, "bar"),
                                     ("cambers", "IA", None, 180 / math.pi, "deg"), ("speeds", "VX", None, 1.0, "m/s")):
        x = data.array(ch)
        t = tol * float(np.max(np.abs(x))) if tol else (math.radians(0.25) if ch == "IA" else 0.5)
        summ[name] = ", ".join(f"{c * fac:.4g}" for c in levels(x, t)[1]) + f" {unit}"
    start = "neutral schema values sized to the tyre, leading coefficients estimated from the data" \
        if result.start.source is None else f"`{result.start.source}`"
    lines += [f"Data: `{data.source}`, {len(data)} points. Loads: {summ['loads']}; pressures: {summ['pressures']}; "
              f"cambers: {summ['cambers']}; speeds: {summ['speeds']}.", "",
              f"Start values: {start}. FNOMIN {result.params.FNOMIN:g} N, NOMPRES {result.params.NOMPRES:g} Pa, "
              f"UNLOADED_RADIUS {result.params.UNLOADED_RADIUS:g} m. Fit time {result.seconds:.1f} s.", ""]
    if result.notes:
        lines += ["Data preparation: " + "; ".join(result.notes), ""]
    lines += ["## Fit errors", "",
              "Normalised RMS error, Schmeitz et al. (2005) eq. (4): "
              "100 sqrt(sum (A_MF - A_meas)^2 / sum A_meas^2) %, over the data of each stage.", "",
              "| stage | channel | points | parameters | fit error [%] |", "| --- | --- | ---: | ---: | ---: |"]
    for st in result.stages.values():
        lines.append(f"| {st.title} | {st.channel} | {st.n_points} | {len(st.fitted)} | {_fmt(st.fit_error)} |")
    lines.append("")
    if result.comparison is not None:
        lines += ["## Inflation pressure: lower bound, upper bound, extended fit", "",
                  "As Table 2 of Schmeitz et al. (2005): lower bound = mean fit error of separate fits at each "
                  "pressure (no pressure terms), upper bound = one fit of all pressures without pressure terms, "
                  "extended = the fit with the pressure terms; recovered = (upper - extended) / (upper - lower), the "
                  "share of the room for improvement the pressure terms recover.", "",
                  "| characteristic | lower bound [%] | upper bound [%] | extended [%] | recovered |",
                  "| --- | ---: | ---: | ---: | ---: |"]
        for _, row in result.comparison.iterrows():
            rec = "-" if not math.isfinite(row.recovered) else f"{100 * row.recovered:.0f} %"
            lines.append(f"| {row.characteristic} | {row.lower:.3f} | {row.upper:.3f} | {row.extended:.3f} | {rec} |")
        lines.append("")
    lines += ["## Stages", ""]
    for name, st in result.stages.items():
        lines += [f"### {st.title}", ""]
        if not st.fitted:
            lines += [f"Not fitted ({st.n_points} points).", ""]
        else:
            passes = "; ".join(f"{label}: {res.nfev} evaluations, {'converged' if res.success else 'stopped'}"
                               for label, res in st.passes)
            lines += [f"{st.n_points} points, fit error {_fmt(st.fit_error)} % on {st.channel}. Passes: {passes}.", "",
                      "| parameter | start | fitted | standard error |", "| --- | ---: | ---: | ---: |"]
            for n in st.fitted:
                lines.append(f"| {n} | {_fmt(st.start[n])} | {_fmt(st.values[n])} | {_fmt(st.stderr[n])} |")
            lines.append("")
            if st.correlations:
                pairs = ", ".join(f"{a}/{b} {c:+.3f}" for (a, b), c in sorted(st.correlations.items()))
                lines += [f"Strongly correlated (|r| >= 0.95): {pairs}.", ""]
        if st.skipped:
            by_reason = {}
            for n, why in st.skipped.items():
                by_reason.setdefault(why, []).append(n)
            lines += ["Not fitted, kept at their start values: " + "; ".join(
                f"{', '.join(ns)} ({why})" for why, ns in by_reason.items()) + ".", ""]
        if plot_names and name in plot_names:
            lines += [f"![{st.title}]({plot_names[name]})", ""]
    return "\n".join(lines)


def plot_stage(result, name: str, path) -> Path | None:
    """Measured vs fitted (zero camber, nominal pressure, one colour per load) and residuals of all points."""
    from matplotlib.figure import Figure  # no pyplot: the caller's backend and figures are left alone

    st, stage = result.stages[name], STAGES[name]
    if not st.fitted:
        return None
    data = result.data.select(stage_rows(stage, result.data))
    model = MFModel(result.params)
    fitted = _predict(stage, model, data, data.inputs())
    measured = data.array(stage.channel)
    xch, xlabel, fac = _X[name]
    x = data.array(xch) * fac
    p0 = result.params.NOMPRES
    ref = (np.abs(data.array("IA")) < math.radians(0.25)) & (np.abs(data.array("P") - p0) <= 0.02 * p0)
    if ref.sum() == 0:
        ref = np.ones(len(data), bool)
    fig = Figure(figsize=(9, 3.4), dpi=80)
    ax1, ax2 = fig.subplots(1, 2)
    fz = data.array("FZ")
    lab, cen = levels(fz[ref], 0.05 * float(np.max(fz)))
    for k, c in enumerate(cen):
        sel = np.flatnonzero(ref)[lab == k]
        order = np.argsort(x[sel], kind="stable")
        line = ax1.plot(x[sel][order], fitted[sel][order], "-", lw=1.2, label=f"Fz {c:.0f} N")[0]
        ax1.plot(x[sel], measured[sel], ".", ms=3, color=line.get_color())
    ax1.set_xlabel(xlabel)
    ax1.set_ylabel(f"{stage.channel} [{_UNIT.get(stage.channel, '')}]")
    ax1.set_title("measured (dots) vs fitted, camber 0, nominal p", fontsize=9)
    ax1.legend(fontsize=7)
    ax2.plot(x, fitted - measured, ".", ms=2)
    ax2.axhline(0.0, color="k", lw=0.8)
    ax2.set_xlabel(xlabel)
    ax2.set_ylabel("fitted - measured")
    ax2.set_title(f"residuals, all {len(data)} points ({st.fit_error:.2f} %)", fontsize=9)
    fig.suptitle(st.title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return Path(path)


def save_report(result, path) -> Path:
    """Write the Markdown report to ``path`` and one PNG per fitted stage beside it (``<stem>_<stage>.png``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    names = {}
    for name in result.stages:
        png = path.with_name(f"{path.stem}_{name}.png")
        if plot_stage(result, name, png) is not None:
            names[name] = png.name
    path.write_text(markdown_report(result, names), encoding="utf-8")
    return path
