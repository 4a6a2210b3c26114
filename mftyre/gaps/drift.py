"""Friction drift over the run: a nuisance of the measurement the gap finder can name, never a property of the tyre.

A test day drifts: the tread warms up and wears, the belt or track surface changes, so the friction the tyre
shows changes slowly while the programme runs its blocks one after another (a pressure, then the next; within it
load after load). Run in that order, a friction change over time reads as a change with whatever the blocks
vary: a pressure effect on a pressure-blind tyre, say. :data:`FRICTION_DRIFT` is the candidate that says so: the
friction scale factors LMUX and LMUY times a smooth function of the run's progress u (0 at the first sample, 1 at
the last: TIME, or without it the row order),

    mu(u) = 1 + sum_k DRIFTk P_k(2 u - 1),   k = 1 .. DEGREE   (P_k: Legendre polynomials)

zero mean over the run, so the mean friction stays with the tyre's own parameters. Its coefficients are fitted as
nuisance parameters, offered and judged like every catalogue effect (held-out sweeps, F test, pruning of
undetermined coefficients), reported apart from the tyre's effects and never written to the .tir. When it
passes alone (training F test, a held-out gain), it is scored again with the stages of its channels refitted
around it, against the same stages refitted without it (as the deep retries of :mod:`mftyre.gaps.core`): the
fair start has bent the friction and load parameters towards the drift in the order the blocks were run, and
the drift alone, on that bent tyre, would be judged on a strawman.

:class:`Drifting` is a parameter set with drift coefficients: the tyre's :class:`mftyre.params.TyreParameters`
(an :class:`mftyre.MFModel` built from it, verification and the .tir writer see the tyre alone) plus the
coefficients, which :func:`predict_drifting` applies row by row from the data's :data:`PROGRESS` column.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from ..data import TyreData
from ..params import TyreParameters
from .catalogue import Effect

__all__ = ["PROGRESS", "DEGREE", "NAMES", "FRICTION_DRIFT", "Drifting", "with_progress", "drift_factor",
           "predict_drifting", "friction_nodes", "FORCE_CHANNELS", "tyre_of", "BOUNDS"]

#: Column of the run's progress u in [0, 1] that the gap finder adds to the data it reads (mean per bin when a
#: time series is reduced).
PROGRESS = "RUN_PROGRESS"
#: Degree of the drift polynomial: a warm-up and a slow decline over the day (the coefficients the data do not
#: determine are reset by the candidate's pruning).
DEGREE = 3
NAMES = tuple(f"DRIFT{k}" for k in range(1, DEGREE + 1))
#: a friction change of more than +-25 % over a run is no drift
BOUNDS = {n: (-0.25, 0.25) for n in NAMES}
#: the channels the friction drift scales (FZ, from the loaded radius, has no friction in it)
FORCE_CHANNELS = ("FX", "FY", "MZ", "MX", "MY")


@dataclass(frozen=True)
class DriftEffect(Effect):
    """An effect whose parameters are the drift's nuisance coefficients (not schema parameters)."""

    @property
    def versions(self) -> frozenset:
        return frozenset({"52", "61", "62"})

    def parameter_descriptions(self) -> dict:
        return {n: f"coefficient of the Legendre polynomial P{n[5:]} of the run's progress in the friction "
                   "scaling (LMUX, LMUY) over the run" for n in self.parameters}

    @staticmethod
    def admit(prm):
        """The parameter set able to carry the drift coefficients."""
        return prm if isinstance(prm, Drifting) else Drifting.of(prm, {n: 0.0 for n in NAMES})


#: The drift candidate. Its variables: every condition the programme's blocks can vary in the order they are run.
FRICTION_DRIFT = DriftEffect(
    "friction_drift", "friction drift over the run (tread temperature, wear, surface): LMUX and LMUY scaled by a "
    "smooth function of the time (or row order) the data were recorded in; a nuisance of the test, not written to "
    "the .tir", NAMES, {n: 0.0 for n in NAMES}, ("FY", "FX", "MZ", "MX", "MY"),
    ("load", "pressure", "camber", "speed", "slip_angle", "slip_ratio", "combined", "free_rolling"),
    {"DRIFT1": 0.0}, with_stages=True)


class Drifting(TyreParameters):
    """Tyre parameters plus drift coefficients (``drift``: DRIFTk -> value). Indexing and :meth:`replace` reach
    both; everything else (an :class:`mftyre.MFModel`, verification, writing) sees the tyre alone."""

    __slots__ = ("drift",)

    @classmethod
    def of(cls, tyre: TyreParameters, drift: dict) -> "Drifting":
        obj = cls.__new__(cls)
        for key in TyreParameters.__slots__:
            object.__setattr__(obj, key, getattr(tyre, key))
        object.__setattr__(obj, "drift", {n: float(v) for n, v in drift.items()})
        return obj

    @property
    def tyre(self) -> TyreParameters:
        return TyreParameters.replace(self)

    def __getitem__(self, name: str):
        if name in self.drift:
            return self.drift[name]
        return super().__getitem__(name)

    def replace(self, **changes) -> "Drifting":
        drift = dict(self.drift)
        tyre_changes = {}
        for key, val in changes.items():
            if key.upper() in drift:
                drift[key.upper()] = float(val)
            else:
                tyre_changes[key] = val
        return Drifting.of(TyreParameters.replace(self, **tyre_changes), drift)

    def __reduce__(self):
        return (Drifting.of, (self.tyre, self.drift))

    def __repr__(self) -> str:
        return f"Drifting({super().__repr__()}, {self.drift})"


def tyre_of(prm) -> TyreParameters:
    """The tyre's own parameters (drift coefficients dropped)."""
    return prm.tyre if isinstance(prm, Drifting) else prm


def with_progress(data: TyreData) -> TyreData:
    """``data`` with the :data:`PROGRESS` column: TIME scaled to 0..1 over the run where TIME is recorded
    (finite throughout), else the row order."""
    n = len(data)
    t = data.array("TIME") if "TIME" in data else np.full(n, np.nan)
    if n and np.all(np.isfinite(t)) and np.ptp(t) > 0:
        u, how = (t - np.min(t)) / np.ptp(t), "TIME"
    else:
        u, how = np.arange(n) / max(n - 1, 1), "row order"
    return data.with_frame(data.frame.assign(**{PROGRESS: u}), f"{PROGRESS}: the run's progress from the {how}")


def drift_factor(drift: dict, u) -> np.ndarray:
    """mu(u) = 1 + sum_k DRIFTk P_k(2u - 1) at the progress ``u``."""
    coef = np.zeros(DEGREE + 1)
    for k in range(1, DEGREE + 1):
        coef[k] = drift.get(f"DRIFT{k}", 0.0)
    return 1.0 + legendre.legval(2.0 * np.asarray(u, float) - 1.0, coef)


def friction_nodes(drift: dict, data: TyreData):
    """(nodes, weights): the least, middle and greatest drift factor of the rows of ``data`` (one node where the
    factor is constant) and each row's Lagrange weights of the nodes, so that a prediction quadratic in the
    factor is sum_i weights[i] x prediction(nodes[i]) (:func:`predict_drifting`)."""
    mu = drift_factor(drift, data.array(PROGRESS)) if PROGRESS in data else np.ones(len(data))
    lo, hi = float(np.min(mu, initial=1.0)), float(np.max(mu, initial=1.0))
    if hi - lo < 1e-12:
        return (lo,), [np.ones(len(data))]
    nodes = (lo, 0.5 * (lo + hi), hi)
    weights = [np.prod([(mu - nodes[j]) / (nodes[i] - nodes[j]) for j in range(3) if j != i], axis=0)
               for i in range(3)]
    return nodes, weights


def predict_drifting(predict, prm: Drifting, data: TyreData, channels) -> dict:
    """Channel -> prediction of every row of ``data`` with the friction scaled row by row by the drift factor:
    ``predict(params, channels)`` is the plain prediction; the force channels are evaluated at the least, middle and
    greatest factor and interpolated quadratically in it (:func:`friction_nodes`: exact at those three; the drift
    is a few percent, the third-order remainder far below the noise), FZ (no friction in it) once."""
    tyre = prm.tyre
    forces = [c for c in channels if c in FORCE_CHANNELS]
    out = predict(tyre, [c for c in channels if c not in forces]) if len(forces) < len(channels) else {}
    if not forces:
        return out
    nodes, weights = friction_nodes(prm.drift, data)
    values = [predict(tyre.replace(LMUX=tyre.LMUX * m, LMUY=tyre.LMUY * m), forces) for m in nodes]
    for c in forces:
        out[c] = sum(w * v[c] for w, v in zip(weights, values))
    return out
