"""Fit-error measures."""
from __future__ import annotations

import numpy as np

__all__ = ["normalised_rms"]


def normalised_rms(fitted, measured) -> float:
    """Normalised RMS fit error in percent, eq. (4) of Schmeitz, Besselink, de Hoogh & Nijmeijer (2005),
    "Extending the Magic Formula and SWIFT tyre models for inflation pressure changes":

        epsilon = 100 sqrt( sum_i (A_MF,i - A_Meas,i)^2 / sum_i A_Meas,i^2 )  [%]

    with A one characteristic (e.g. pure-slip Fy), A_MF the model and A_Meas the measured values over the
    n measurement points. Points where either value is not finite are left out.
    """
    fitted = np.asarray(fitted, dtype=float)
    measured = np.asarray(measured, dtype=float)
    fitted, measured = np.broadcast_arrays(fitted, measured)
    ok = np.isfinite(fitted) & np.isfinite(measured)
    denominator = float(np.sum(measured[ok] ** 2))
    if denominator == 0.0:
        return float("nan")
    return 100.0 * float(np.sqrt(np.sum((fitted[ok] - measured[ok]) ** 2) / denominator))
