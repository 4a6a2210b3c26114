"""The gap finder: where do model and measurement disagree, which named effect is missing, add it, show the gap
shrink.

    from mftyre.gaps import find_gaps
    report = find_gaps(data, model)            # TyreData / .tdx / .csv; MFModel / .tir
    report.effects_added, report.error_before, report.error_after, report.findings_before
    report.save("gap_report/"); report.to_json("gaps.json"); report.write_tir("improved.tir")

Command line: ``mftyre gaps DATA --model BASE.tir [-o improved.tir] [--report DIR] [--json report.json]``.

The workflow (:func:`find_gaps`):

1. *Fair start* (:func:`mftyre.gaps.refit.refit_stages`): the parameters already active in the model are refitted
   stage by stage, so the remaining gap is what the model cannot express.
2. *Locate* (:func:`mftyre.gaps.locate.locate`): per channel, the residual standardised by the measurement noise
   (estimated from repeated points, :func:`mftyre.gaps.residuals.noise_levels`) is tested for structure in the
   slip and deflection coordinates and in every condition variable (chi-square tests of cell means, Bonferroni
   corrected); findings are ranked by their excess over noise.
3. *Name* (:data:`mftyre.gaps.CATALOGUE`): effects as data over the parameter schema; the absent effects whose
   channels and variables match a finding and whose parameters the data determine are the candidates.
4. *Add*: each candidate's parameters alone are refitted on the training sweeps; it is scored on held-out sweeps
   (decrease of the noise-weighted chi-square minus k ln n, a BIC-type penalty) and tested on the training data
   (F test of the chi-square decrease, Bonferroni over the round's candidates). The best significant candidate is
   accepted, its stage refitted from the current model, and the search repeats until nothing significant remains.
5. *Show* (:mod:`mftyre.gaps.report`): held-out normalised RMS errors per channel before/after, residual maps,
   the effects with values and standard errors, the improved .tir; Markdown + PNG and JSON.
"""
from .catalogue import BASE, CATALOGUE, Effect, coverage, effect_state, neutralise
from .core import AddedEffect, Candidate, GapReport, find_gaps
from .locate import Finding, locate
from .refit import refit, refit_stages
from .residuals import CHANNELS, Evaluator, holdout_mask, noise_levels

__all__ = ["find_gaps", "GapReport", "AddedEffect", "Candidate", "CATALOGUE", "Effect", "BASE", "coverage",
           "effect_state", "neutralise", "Finding", "locate", "refit", "refit_stages", "CHANNELS", "Evaluator",
           "holdout_mask", "noise_levels"]
