"""The gap finder: where do model and measurement disagree, which named effect is missing, add it, show the gap
shrink.

    from mftyre.gaps import find_gaps
    report = find_gaps(data, model)            # TyreData / .tdx / .csv; MFModel / .tir
    report.effects_added, report.error_before, report.error_after, report.findings_before
    report.save("gap_report/"); report.to_json("gaps.json"); report.write_tir("improved.tir")

Command line: ``mftyre gaps DATA --model BASE.tir [-o improved.tir] [--report DIR] [--json report.json]``.

The workflow (:func:`find_gaps`):

0. *Programme* (:func:`mftyre.programme.recognise`): levels, sweeps with their direction, steady and transient
   segments; a time series (100 Hz rig data) is reduced per sweep (:func:`mftyre.timeseries.reduce_sweeps`), the
   up and down branches apart: the search works on the branch means, and the up/down difference is named as the
   transient effect it is (:mod:`mftyre.gaps.transient`: relaxation length, PTY*/PTX*), never bought with
   steady-state parameters.
1. *Fair start* (:func:`mftyre.gaps.refit.refit_stages`): the parameters already active in the model are refitted
   stage by stage, so the remaining gap is what the model cannot express; a stage whose values would fail
   verification (:func:`mftyre.fit.verify.verify_tir`) keeps the previous ones.
2. *Locate* (:func:`mftyre.gaps.locate.locate`): per channel, the residual standardised by the measurement noise
   (from repeated points, :func:`mftyre.gaps.residuals.noise_levels`; for reduced time series from the raw AR(1)
   noise, :func:`mftyre.gaps.residuals.noise_of_means`) is tested for structure in the slip and deflection
   coordinates and in every condition variable (chi-square tests of cell means, Bonferroni corrected); findings
   are ranked by their excess over noise.
3. *Name* (:data:`mftyre.gaps.CATALOGUE`): effects as data over the parameter schema; the absent effects whose
   channels and variables match a finding are the candidates, if the data can test them: the input their
   parameters act along is swept (Fx terms need a slip-ratio sweep, Fy and Mz terms a slip-angle sweep, ...) and
   the conditions they need vary (two pressures, camber, ...); the others are reported untestable with the reason.
4. *Add*: each candidate's parameters alone are refitted on the training sweeps; it is tested on the training data
   (F test of the chi-square decrease on the effective number of independent residuals, Bonferroni over the
   round's candidates) and scored on held-out sweeps (chi-square decrease x n_eff/n minus k ln n_eff; with enough
   changed held-out sweeps also a signed-rank test over whole sweeps). The best significant candidate has its
   stages refitted, its undetermined parameters reset (standard error above the size, or > 0.99 correlated
   unless needed), and the improved model verified over its declared range; a candidate failing either is
   rejected with the reason. The search repeats until nothing significant remains.
   With a handful of points (:data:`mftyre.gaps.small.SMALL_DATA`) AICc and leave-one-out over all points
   replace held-out sweeps, and the noise comes from the selected model's residual.
5. *Show* (:mod:`mftyre.gaps.report`): held-out normalised RMS errors per channel before/after, residual maps,
   the effects with values and standard errors, transient effects, rejected and untestable effects, the improved
   .tir; Markdown + PNG and JSON.
"""

from ..lazy import export_lazily

__all__ = ["find_gaps", "GapReport", "AddedEffect", "Candidate", "CATALOGUE", "Effect", "BASE", "coverage",
           "effect_state", "neutralise", "Finding", "locate", "refit", "refit_stages", "CHANNELS", "Evaluator",
           "holdout_mask", "noise_levels"]
#: the names above, each imported from its submodule when first used: `mftyre --help` imports no scipy or lmfit
export_lazily(__name__, {
    "BASE": "catalogue", "CATALOGUE": "catalogue", "Effect": "catalogue", "coverage": "catalogue",
    "effect_state": "catalogue", "neutralise": "catalogue",
    "AddedEffect": "core", "Candidate": "search", "GapReport": "core", "find_gaps": "core",
    "Finding": "locate", "locate": "locate",
    "refit": "refit", "refit_stages": "refit",
    "CHANNELS": "residuals", "Evaluator": "residuals", "holdout_mask": "residuals", "noise_levels": "residuals"})
