"""Checks of the model inputs shared by every evaluator (NumPy :meth:`mftyre.MFModel.evaluate`, the compiled C of
:mod:`mftyre.compiled` and the tables of ``mftyre eval``), so that all reject, saturate and warn alike:

* every input must be finite (NaN and +-inf raise :class:`ModelInputError` naming the input);
* the inflation pressure must be positive;
* with ``limits=True`` the equations saturate fz, kappa, alpha, gamma and p to the ranges of the .tir file
  (:data:`RANGE_PARAMETERS`): values outside them are evaluated at the bound, and one
  :class:`InputClippedWarning` per call names each such input, its range (parameter names and values) and how
  many points lay outside it. ``limits=False`` evaluates the values as given.

Fz has an upper bound only. FZMAX saturates the load everywhere. FZMIN is not a bound of the input: loads in
(0, FZMIN) are evaluated as given, except that the aligning-torque coefficients and the MF 6.1 deflection use
max(Fz, FZMIN) and Mx, My scale down below FZMIN (the TNO practice the reference evaluator encodes), so they give
no warning; Fz <= 0 is no contact, not a range violation either. The compiled C counts one interval per input,
the same as :func:`saturate` here.
"""
from __future__ import annotations

import warnings

import numpy as np

from .errors import InputClippedWarning, ModelInputError, spelled

__all__ = ["RANGE_PARAMETERS", "input_ranges", "saturate", "check_finite", "check_pressure", "warn_outside"]

#: input -> (.tir parameter of the lower bound or None, of the upper bound, unit): the ranges ``limits=True``
#: saturates the inputs to (see the module docstring for Fz and FZMIN).
RANGE_PARAMETERS = {
    "fz": (None, "FZMAX", "N"),
    "kappa": ("KPUMIN", "KPUMAX", "-"),
    "alpha": ("ALPMIN", "ALPMAX", "rad"),
    "gamma": ("CAMMIN", "CAMMAX", "rad"),
    "p": ("PRESMIN", "PRESMAX", "Pa"),
}
_MIRRORED = ("alpha", "gamma")  # ranges of the measured side, negated for a tyre mounted on the other side


def input_ranges(params, mirrored: bool = False) -> dict:
    """{input: (lower, upper, description)} in the axes of the caller (a mirrored tyre sees -ALPMAX..-ALPMIN);
    the description names the parameters, their values and the unit, e.g. 'PRESMIN..PRESMAX = [186000, 255000]
    Pa'."""
    ranges = {}
    for name, (lo_name, hi_name, unit) in RANGE_PARAMETERS.items():
        lo = -np.inf if lo_name is None else float(params[lo_name])
        hi = float(params[hi_name])
        if mirrored and name in _MIRRORED:
            lo, hi = -hi, -lo
        bounds = f"{lo_name}..{hi_name}" if lo_name else hi_name
        ranges[name] = (lo, hi, f"{bounds} = [{lo:.6g}, {hi:.6g}] {unit}")
    return ranges


def saturate(values, bounds) -> tuple[np.ndarray, int]:
    """(values used by ``limits=True``, number of values outside) for ``bounds`` = (lower, upper, ...) of
    :func:`input_ranges`."""
    lo, hi = bounds[0], bounds[1]
    values = np.asarray(values, dtype=float)
    outside = int(np.count_nonzero((values < lo) | (values > hi)))
    return (np.clip(values, lo, hi) if outside else values), outside


def check_finite(name: str, values) -> None:
    """Raise :class:`ModelInputError` if ``values`` holds NaN or +-inf, naming the input and the first places."""
    values = np.asarray(values)
    bad = ~np.isfinite(values)
    if bad.any():
        where = np.argwhere(bad)[:5].tolist() if values.ndim else "scalar"
        raise ModelInputError(f"input {name!r} must be finite; got {values[bad][:3].tolist()} at {where}")


def check_pressure(p, name: str = "p") -> None:
    """Raise :class:`ModelInputError` unless every inflation pressure is positive (in Pa)."""
    p = np.asarray(p)
    if np.any(~(p > 0)):
        raise ModelInputError(f"inflation pressure {name!r} must be positive (in Pa); got minimum {float(np.min(p))!r}")


def warn_outside(counts: dict, total: int, ranges: dict, stacklevel: int = 3) -> None:
    """One :class:`InputClippedWarning` naming every input with points outside its range (none if no such)."""
    parts = [f"{name} outside {ranges[name][2]} at {n} of {total} point(s)" for name, n in counts.items() if n]
    if parts:
        given = spelled("limits=False", "mftyre eval --no-limits")
        warnings.warn(f"inputs outside the .tir ranges, saturated to them ({given} evaluates them as given): "
                      + "; ".join(parts), InputClippedWarning, stacklevel=stacklevel)
