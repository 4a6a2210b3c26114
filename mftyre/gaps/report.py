"""The gap report: Markdown (verdict, data, noise, held-out errors before/after, findings before and after, the
effects added with values and standard errors, the candidates of every round, effects that could not be tested)
and PNG plots: held-out errors per channel, and residual maps (cell means with 95 % confidence intervals over the
slip or deflection cells, one line per level of the finding's variable) before and after."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..files import make_output_folder, write_atomically, write_figure
from .locate import cell_table
from .residuals import UNITS

__all__ = ["markdown_report", "save_report", "plot_errors", "plot_residual_maps"]


def _f(v, fmt="{:.3g}"):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return fmt.format(v)


def markdown_report(rep, plot_names: dict | None = None) -> str:
    plot_names = plot_names or {}
    s = rep.data_summary
    lines = ["# Gap finder report", "", f"**{rep.message[0].upper() + rep.message[1:]}.**", "",
             f"Data: `{s['source']}` ({s['tyre'] or 'tyre'}), {s['points']} points; {s['loads']} loads, "
             f"{s['pressures']} pressures, {s['speeds']} speeds, camber {'yes' if s['camber'] else 'no'}, turn slip "
             f"{'yes' if s['turn_slip'] else 'no'}. " + (f"Small data: judged on all {s['points']} points (leave-one-out). "
             if getattr(rep, "small_data", False) else f"Held out: {int(rep.test_mask.sum())} points (whole sweeps). ") +
             f"Run time {rep.seconds:.1f} s.", "",
             *([f"Test programme: {rep.programme}.", ""] if rep.programme else []),
             *([f"Time series: {rep.reduction}.", ""] if rep.reduction else []),
             *_error_heading(rep),
             "| channel | given [%] | before [%] | after [%] | shrink | noise floor [%] | noise sigma |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    shrink = rep.shrink()
    floor = noise_floor(rep)
    for c in rep.error_before:
        if c in getattr(rep, "not_modelled", ()):
            lines.append(f"| {c} | not fitted (no model) | | | | | |")
            continue
        lines.append(f"| {c} | {_f(rep.error_given[c], '{:.3f}')} | {_f(rep.error_before[c], '{:.3f}')} | "
                     f"{_f(rep.error_after[c], '{:.3f}')} | {_f(100 * shrink.get(c, float('nan')), '{:.0f} %')} | "
                     f"{_f(floor.get(c), '{:.3f}')} | {rep.noise[c][0]:.3g} {UNITS[c]} ({rep.noise[c][1]}) |")
    lines.append("")
    if "errors" in plot_names:
        lines += [f"![held-out errors]({plot_names['errors']})", ""]
    if getattr(rep, "transient", None):
        lines += ["## Transient effects (named, not fitted)", ""]
        lines += [f"- {t['text']}." for t in rep.transient]
        lines.append("")
    lines += ["## Effects added", ""]
    if not rep.effects_added:
        lines += ["None." + (" The model explains the data: nothing to add." if not rep.findings_before else ""), ""]
    for a in rep.effects_added:
        gains = ", ".join(f"{c} {100 * g:.0f} %" for c, g in a.held_out_gain_by_channel.items())
        if getattr(rep, "small_data", False):
            how = f"leave-one-out error decrease {gains}"
        else:
            how = (f"held-out chi-square decrease {100 * a.held_out_gain:.0f} %; held-out error decrease {gains}; "
                   f"F-test p = {a.p_value:.2g}; score {a.score:.0f}")
        lines += [f"### {a.name}", "", f"{a.description}. Round {a.round}; {how}." + (f" {a.note}." if a.note else ""),
                  "",
                  "| parameter | value | standard error | meaning |", "| --- | ---: | ---: | --- |"]
        for k, v in a.parameters.items():
            lines.append(f"| {k} | {v['value']:.6g} | {_f(v['stderr'], '{:.3g}')} | {v['meaning']} |")
        lines.append("")
    if getattr(rep, "nuisances", None):
        lines += ["## Named in the measurement, not the tyre", "",
                  "Fitted as nuisances beside the tyre's parameters (held-out test as for the effects); not written "
                  "to the .tir.", ""]
        for a in rep.nuisances:
            vals = ", ".join(f"{k} = {v['value']:.4g}" for k, v in a.parameters.items())
            lines += [f"- {a.name}: {a.description}; {vals} (held-out chi-square decrease "
                      f"{100 * a.held_out_gain:.0f} %).", ""]
    for title, findings in (("Findings before (after the fair start)", rep.findings_before),
                            ("Findings after", rep.findings_after)):
        lines += [f"## {title}", ""]
        if not findings:
            lines += ["No residual structure beyond measurement noise (every test at the Bonferroni-corrected "
                      "level).", ""]
        for i, f in enumerate(findings[:12], 1):
            lines.append(f"{i}. {f.text}")
        if len(findings) > 12:
            lines.append(f"... and {len(findings) - 12} more.")
        lines.append("")
    if "maps" in plot_names:
        lines += ["Residual maps: mean residual per slip (or deflection) cell with its 95 % confidence interval, one "
                  "line per level of the finding's variable; before (left) and after (right).", "",
                  f"![residual maps before and after]({plot_names['maps']})", ""]
    lines += ["## Candidates tried", "",
              "Per round, each candidate's parameters refitted alone on the training sweeps; F = training chi-square "
              "decrease per parameter over the residual variance; score = held-out chi-square decrease - k ln(n). "
              "n: training residuals; n_eff: the independent ones the tests count (point data: every row; a time "
              "series: the AR(1) rule with the noise's correlation); n_eff (residual): the AR(1) count from the "
              "residual lacking the effect, shown for comparison (a missing effect makes it collapse).", ""]
    for i, rnd in enumerate(rep.rounds, 1):
        lines += [f"Round {i}:", "", "| effect | parameters | F | p | n | n_eff | n_eff (residual) | held-out gain | "
                  "score | accepted |", "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
        best = next((c.name for c in rnd if c.significant), None)
        for c in rnd:
            lines.append(f"| {c.name} | {' '.join(c.parameters)} | {c.f_statistic:.3g} | {c.p_value:.2g} | "
                         f"{c.n_train} | {c.n_eff:.0f} | {c.n_eff_residual:.0f} | "
                         f"{100 * c.held_out_gain:.1f} % | {c.score:.0f} | {'yes' if c.name == best else ''} |")
        lines.append("")
    if rep.rejected:
        lines += ["## Effects rejected", "", "Significant, but their parameters are not determined by the data or the "
                  "improved .tir fails verification over its declared range; the previous values are kept.", ""]
        for k, v in rep.rejected.items():
            lines.append(f"- {k}: {v}")
        lines.append("")
    if rep.untestable:
        lines += ["## Effects the data cannot test", ""]
        for k, v in rep.untestable.items():
            lines.append(f"- {k}: {v}")
        lines.append("")
    return "\n".join(lines)


def _error_heading(rep) -> list:
    if getattr(rep, "small_data", False):
        return ["## Fit error, leave-one-out", "",
                "Small data: every point predicted by the model refitted on the other points (leave-one-out), "
                "normalised RMS error %; effects were added when they lowered both AICc (the small-sample Akaike "
                "criterion over all points) and this error. Columns \"given\" and the noise floor refer to all "
                "points; the noise is the residual standard deviation of the selected model.", ""]
    return ["## Fit error on held-out sweeps", "",
            "Normalised RMS error, Schmeitz et al. (2005) eq. (4), 100 sqrt(sum (model - measured)^2 / sum "
            "measured^2) %, on the held-out sweeps: the model as given, after the fair start (its active parameters "
            "refitted) and with the effects added. The noise floor is the error pure measurement noise would give.",
            ""]


def noise_floor(rep) -> dict:
    """Channel -> the normalised RMS error [%] that the noise alone gives on the held-out data."""
    from .residuals import noise_floor_of

    return noise_floor_of(rep.evaluator, rep.test_mask, {c: rep.noise[c] for c in rep.error_before if c in rep.noise})


def _figure(**kw):
    """A figure drawn and saved without pyplot: no global backend or state is touched (notebooks keep theirs)."""
    from matplotlib.figure import Figure

    return Figure(**kw)


def plot_errors(rep, path) -> Path:
    chans = list(rep.error_before)
    x = np.arange(len(chans))
    fig = _figure(figsize=(5.5, 2.8), dpi=80)
    ax = fig.subplots()
    ax.bar(x - 0.2, [rep.error_before[c] for c in chans], 0.4, label="before")
    ax.bar(x + 0.2, [rep.error_after[c] for c in chans], 0.4, label="after")
    floor = noise_floor(rep)
    ax.plot(x, [floor.get(c, np.nan) for c in chans], "k_", ms=18, label="noise floor")
    ax.set_xticks(x, chans)
    ax.set_ylabel("held-out error [%]")
    ax.legend(fontsize=7)
    ax.set_title("normalised RMS error on held-out sweeps", fontsize=9)
    fig.tight_layout()
    return write_figure(fig, path)


def _map_targets(rep, limit=3):
    """(channel, variable) pairs to map: the strongest single-variable findings before, one per channel."""
    out = []
    for f in rep.findings_before:
        if len(f.variables) != 1 or any(c == f.channel for c, _ in out):
            continue
        out.append((f.channel, f.variables[0]))
        if len(out) == limit:
            break
    return out


def plot_residual_maps(rep, path) -> Path | None:
    """Residual cell means (95 % CI) before and after, for the strongest findings."""
    targets = _map_targets(rep)
    if not targets:
        return None
    ev = rep.evaluator
    res_before, res_after = ev.residuals(rep.model_start), ev.residuals(rep.model)
    fig = _figure(figsize=(11, 3.2 * len(targets)), dpi=100)
    axes = fig.subplots(len(targets), 2, squeeze=False)
    for i, (c, var) in enumerate(targets):
        lims = []
        for j, (res, title) in enumerate(((res_before, "before"), (res_after, "after"))):
            ax = axes[i, j]
            xs, labels, table = cell_table(ev, c, res[c], var)
            for level, (m, h) in table.items():
                ax.errorbar(xs, m, yerr=h, marker=".", ms=3, lw=0.8, capsize=1.5, label=str(level))
            ax.axhline(0.0, color="k", lw=0.6)
            every = max(1, math.ceil(len(xs) / 25))  # at most 25 labels: readable at 7 pt
            ax.set_xticks(xs[::every], labels[::every], rotation=60, fontsize=7)
            ax.set_xticks(xs, minor=True)
            ax.set_ylabel(f"{c} residual [{UNITS[c]}]", fontsize=8)
            ax.set_xlabel("deflection bin" if c == "FZ" else "slip cell: a = slip-angle bin, k = slip-ratio bin "
                          "(1 small, 2 medium, 3 large)", fontsize=8)
            ax.tick_params(axis="y", labelsize=7)
            ax.set_title(f"{c} by {var}, {title}", fontsize=9)
            lims.append(ax.get_ylim())
            if j == 0:
                ax.legend(fontsize=7)
        lo, hi = min(a for a, _ in lims), max(b for _, b in lims)
        for j in range(2):
            axes[i, j].set_ylim(lo, hi)
    fig.tight_layout()
    return write_figure(fig, path)


def save_report(rep, directory) -> Path:
    """Write ``report.md``, ``errors.png``, ``residual_maps_before_after.png`` and ``gaps.json`` into
    ``directory``; returns the Markdown path."""
    d = Path(directory)
    make_output_folder(d)
    names = {"errors": plot_errors(rep, d / "errors.png").name}
    maps = plot_residual_maps(rep, d / "residual_maps_before_after.png")
    if maps is not None:
        names["maps"] = maps.name
    md = d / "report.md"
    write_atomically(md, markdown_report(rep, names))
    rep.to_json(d / "gaps.json")
    return md
