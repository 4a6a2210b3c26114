"""The fit report: Markdown text (data, fit errors, the Table-2 pressure comparison of Schmeitz et al. 2005,
per-stage parameter tables with standard errors and strong correlations, parameters not fitted and why)
and PNG plots per stage (measured vs fitted per sweep at zero camber and nominal pressure, residuals of all
points) written next to it."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..files import make_output_folder, write_atomically, write_figure
from ..programme import cluster_levels
from ..model import MFModel
from .predict import predict_stage
from .provenance import unidentified
from .stages import STAGES, combined_fy, stage_rows

__all__ = ["markdown_report", "save_report", "plot_stage", "stage_figure"]

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
    for name, ch, fac, unit in (("loads", "FZ", 1.0, "N"), ("pressures", "P", 1e-5, "bar"),
                                ("cambers", "IA", 180 / math.pi, "deg"), ("speeds", "VX", 1.0, "m/s")):
        centres = result.programme.levels[ch] if result.programme is not None else cluster_levels(data.array(ch))[1]
        summ[name] = (", ".join(f"{round(c * fac, 3) + 0.0:.4g}" for c in centres) or "none on a level") + f" {unit}"
    start = "neutral schema values sized to the tyre, leading coefficients estimated from the data" \
        if result.start.source is None else f"`{result.start.source}`"
    lines += [f"Data: `{data.source}`, {len(result.raw_data)} rows, {len(data)} points fitted. Loads: "
              f"{summ['loads']}; pressures: {summ['pressures']}; cambers: {summ['cambers']}; speeds: "
              f"{summ['speeds']}.", "",
              f"Start values: {start}. FNOMIN {result.params.FNOMIN:g} N, NOMPRES {result.params.NOMPRES:g} Pa, "
              f"UNLOADED_RADIUS {result.params.UNLOADED_RADIUS:g} m. Fit time {result.seconds:.1f} s.", ""]
    if result.notes:
        lines += ["Data preparation: " + "; ".join(result.notes), ""]
    if result.programme is not None and result.programme.notes:
        lines += ["Not determinable from these data: " + "; ".join(result.programme.notes) + ".", ""]
    rejected = {n: st.rejected for n, st in result.stages.items() if st.rejected}
    if rejected:
        lines += ["## Rejected stages", "", "Their previous parameter values are kept.", ""]
        lines += [f"- {result.stages[n].title}: " + "; ".join(why) for n, why in rejected.items()]
        lines.append("")
    if result.problems:
        lines += ["## Verification problems", ""] + [f"- {p}" for p in result.problems] + [""]
    if result.warnings:
        lines += ["## Verification warnings", "", "Not a reason to reject the file: beyond the data, or the start "
                  "values have them too.", ""] + [f"- {p}" for p in result.warnings] + [""]
    lines += ["## Fit errors", "",
              "Normalised RMS error, Schmeitz et al. (2005) eq. (4): "
              "100 sqrt(sum (A_MF - A_meas)^2 / sum A_meas^2) %, over the data of each stage.", "",
              "| stage | channel | points | parameters | fit error [%] |", "| --- | --- | ---: | ---: | ---: |"]
    for st in result.stages.values():
        lines.append(f"| {st.title} | {st.channel} | {st.n_points} | {len(st.fitted)} | {_fmt(st.fit_error)} |")
    lines.append("")
    if result.raw_errors:
        lines += ["## Errors on the samples as recorded", "",
                  "The same measure on every sample of the sweeps (not the binned means), beside the samples' own "
                  "scatter at equal load, pressure, camber and slip (the repeatability floor: about each bin's line in "
                  "the slip, the force scaled to the bin's mean load; no steady-state model fits the samples better).",
                  "", "| stage | binned points [%] | samples [%] | repeatability floor [%] | samples / floor |",
                  "| --- | ---: | ---: | ---: | ---: |"]
        for name, (err, floor) in result.raw_errors.items():
            ratio = err / floor if floor > 0 else float("nan")
            lines.append(f"| {name} | {_fmt(result.stages[name].fit_error)} | {_fmt(err)} | {_fmt(floor)} | "
                         f"{_fmt(ratio)} |")
        lines.append("")
    unknown = unidentified(result)
    if unknown:
        lines += ["## Not determined by the data", "",
                  "At a bound of the fit, or with a standard error above the value (held at the start value unless "
                  "the data need them), and the measurement that would pin each.", "",
                  "| parameter | why | measurement that would pin it |", "| --- | --- | --- |"]
        lines += [f"| {n} | {why} | {need} |" for n, why, need in unknown]
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
        if st.rejected:
            lines += [f"Rejected ({st.n_points} points): " + "; ".join(st.rejected) + ". Previous values kept.", ""]
        elif not st.fitted:
            lines += [f"Not fitted ({st.n_points} points).", ""]
        else:
            passes = "; ".join(f"{label}: {res.nfev} evaluations, {'converged' if res.success else 'stopped'}"
                               for label, res in st.passes)
            lines += [f"{st.n_points} points ({st.n_eff:.0f} effective independent samples), fit error "
                      f"{_fmt(st.fit_error)} % on {st.channel}. Passes: {passes}.", "",
                      "| parameter | start | fitted | standard error |", "| --- | ---: | ---: | ---: |"]
            for n in st.fitted:
                lines.append(f"| {n} | {_fmt(st.start[n])} | {_fmt(st.values[n])} | {_fmt(st.stderr[n])} |")
            lines.append("")
            if st.correlations:
                pairs = ", ".join(f"{a}/{b} {c:+.3f}" for (a, b), c in sorted(st.correlations.items()))
                lines += [f"Strongly correlated (|r| >= 0.95): {pairs}.", ""]
        if st.reset:
            lines += ["Not determined by the data, back to their start values: " + "; ".join(
                f"{n} ({why})" for n, why in st.reset.items()) + ".", ""]
        for note in st.notes:
            lines += [note + ".", ""]
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
    """Save :func:`stage_figure` to ``path`` (None when the stage was not fitted)."""
    fig = stage_figure(result, name)
    if fig is None:
        return None
    return write_figure(fig, path)


def stage_figure(result, name: str):
    """Measured (dots) and fitted (lines) per sweep at zero camber and nominal pressure, one colour per load
    level (no line joins two sweeps), and the residuals of all points: a matplotlib Figure (no pyplot)."""
    from matplotlib.figure import Figure  # no pyplot: the caller's backend and figures are left alone

    st, stage = result.stages[name], STAGES[name]
    if not st.fitted:
        return None
    data = result.data.select(stage_rows(stage, result.data, combined_fy(result.stages)))
    model = MFModel(result.params)
    fitted = predict_stage(stage, model, data, data.inputs())
    measured = data.array(stage.channel)
    xch, xlabel, fac = _X[name]
    x = data.array(xch) * fac
    # the levels of the whole programme (recognised on the raw data), each point on its nearest level
    levels = {ch: (result.programme.levels[ch] if result.programme is not None else cluster_levels(data.array(ch))[1])
              for ch in ("FZ", "P", "IA")}
    nearest = {ch: (np.argmin(np.abs(data.array(ch)[:, None] - c[None, :]), axis=1) if len(c) else
                    np.zeros(len(data), int)) for ch, c in levels.items()}
    ref = np.ones(len(data), bool)
    for ch, target in (("P", result.params.NOMPRES), ("IA", 0.0)):  # the level nearest nominal p, camber 0
        if len(levels[ch]):
            ref &= nearest[ch] == int(np.argmin(np.abs(levels[ch] - target)))
    if ref.sum() == 0:
        ref = np.ones(len(data), bool)
    fig = Figure(figsize=(9, 3.4), dpi=80)
    ax1, ax2 = fig.subplots(1, 2)
    cen = levels["FZ"] if len(levels["FZ"]) else np.array([float(np.mean(data.array("FZ")))])
    lab = nearest["FZ"][ref]
    sweep = data.frame["SWEEP"].to_numpy() if "SWEEP" in data else np.zeros(len(data), int)
    colours = [f"C{k % 10}" for k in range(max(len(cen), 1))]
    idx = np.flatnonzero(ref)
    for k, c in enumerate(cen):
        sel = idx[lab == k]
        ax1.plot(x[sel], measured[sel], ".", ms=3, color=colours[k], label=f"Fz {c:.0f} N")
        for s in np.unique(sweep[sel]):
            one = sel[sweep[sel] == s]
            if s < 0 or one.size < 3:  # a line needs a sweep, not two points of one
                continue
            order = np.argsort(x[one], kind="stable")
            ax1.plot(x[one][order], fitted[one][order], "-", lw=1.0, color=colours[k])
    ax1.set_xlabel(xlabel)
    ax1.set_ylabel(f"{stage.channel} [{_UNIT.get(stage.channel, '')}]")
    ax1.set_title("measured (dots), fitted per sweep (lines); camber 0, nominal p", fontsize=9)
    if len(cen):
        ax1.legend(fontsize=7)
    ax2.plot(x, fitted - measured, ".", ms=2)
    ax2.axhline(0.0, color="k", lw=0.8)
    ax2.set_xlabel(xlabel)
    ax2.set_ylabel("fitted - measured")
    ax2.set_title(f"residuals, all {len(data)} points ({st.fit_error:.2f} %)", fontsize=9)
    fig.suptitle(st.title, fontsize=10)
    fig.tight_layout()
    return fig


def save_report(result, path) -> Path:
    """Write the Markdown report to ``path`` and one PNG per fitted stage beside it (``<stem>_<stage>.png``)."""
    path = Path(path)
    make_output_folder(path.parent)
    names = {}
    for name in result.stages:
        png = path.with_name(f"{path.stem}_{name}.png")
        if plot_stage(result, name, png) is not None:
            names[name] = png.name
    write_atomically(path, markdown_report(result, names))
    return path
