"""Small data: a handful of points (e.g. a measured load-deflection table, 2 pressures x 4 loads).

With so few points neither held-out sweeps nor a noise estimate from the data's own sweeps can be trusted: the
second differences of a four-point sweep are the curvature under test, not noise. So every candidate is judged on
*all* points by two criteria that need no noise estimate:

* AICc, the small-sample Akaike criterion (Hurvich & Tsai 1989) of the least-squares fit,
  ``n ln(RSS/n) + 2k + 2k(k+1)/(n-k-1)``, with k every parameter fitted (the model's active ones and the effect's);
* leave-one-out cross-validation: each point predicted by the model refitted (all k parameters) without it.

An effect is added when it lowers AICc by more than 2 and lowers the leave-one-out error; the best such effect is
added and the search repeats. The noise level reported is the residual standard deviation of the selected model,
RSS/(n-k), and each added parameter carries its standard error at that level.
"""
from __future__ import annotations

import math

import numpy as np

from ..fit.metrics import normalised_rms
from .refit import refit
from .residuals import Evaluator

__all__ = ["SMALL_DATA", "aicc", "loo_errors", "fit_all", "weighted_rss"]

#: Fewer rows than this: the small-data criteria (AICc and leave-one-out over all points) replace held-out sweeps.
SMALL_DATA = 60


def aicc(rss: float, n: int, k: int) -> float:
    """Small-sample Akaike criterion of a least-squares fit (Gaussian errors, unknown variance)."""
    if n - k - 1 <= 0:
        return math.inf
    return n * math.log(max(rss, 1e-300) / n) + 2 * k + 2 * k * (k + 1) / (n - k - 1)


def _scales(ev: Evaluator, channels) -> dict:
    return {c: float(np.sqrt(np.mean(ev.measured[c] ** 2))) or 1.0 for c in channels}


def weighted_rss(ev: Evaluator, prm, channels, scale) -> float:
    """Sum of squared residuals, each channel in units of its RMS measured value (channels comparable)."""
    res = ev.residuals(prm, channels)
    return float(sum(np.sum(np.where(np.isfinite(r), r, 1e3 * scale[c]) ** 2) / scale[c] ** 2
                     for c, r in res.items()))


def fit_all(prm, ev: Evaluator, names, channels, start=None):
    """Refit ``names`` on every point (channels weighed by their RMS)."""
    return refit(prm, ev, names, channels, sigma={c: (s,) for c, s in _scales(ev, channels).items()},
                 start=start)


def loo_errors(prm, data, names, channels) -> dict:
    """Channel -> normalised RMS error [%] of leave-one-out predictions: every row predicted by the model with
    ``names`` refitted on the other rows (from ``prm``, the fit on all rows)."""
    n = len(data)
    pred = {c: [] for c in channels}
    meas = {c: [] for c in channels}
    for i in range(n):
        keep = np.ones(n, bool)
        keep[i] = False
        ev_i = Evaluator(data.select(keep), channels)
        fitted, _ = fit_all(prm, ev_i, names, ev_i.channels)
        ev_one = Evaluator(data.select(~keep), channels)
        p1 = ev_one.predict(fitted)
        for c in ev_one.channels:
            pred[c].extend(np.ravel(p1[c]))
            meas[c].extend(np.ravel(ev_one.measured[c]))
    return {c: normalised_rms(np.asarray(pred[c]), np.asarray(meas[c])) for c in channels if meas[c]}
