"""Ground: one interface for a vehicle model to run a tyre on hard ground, on soft soil, or on a blend of both.

    >>> ground = Ground(model, soil="sandy_loam", blend=0.7)    # 0: hard ground (MF), 1: soft soil
    >>> f = ground.forces(fz=25e3, kappa=0.1, alpha=0.02, vx=3.0)
    >>> f.fx, f.fy, f.torque, f.sinkage

The inputs are those of the Magic Formula (kappa = (omega Re - Vx) / Vx with the hard-ground effective rolling
radius Re, ISO-W). The soil model's slip is measured against the same Re: i = kappa / (1 + kappa). The outputs are blended linearly,
X = (1 - w) X_hard + w X_soil, for the longitudinal force (drawbar pull on soil), the lateral force and the
driving torque (hard ground: Fx Rl - My, the torque that holds the wheel at this slip); sinkage is w z_soil. The
blend factor w may be an array (e.g. a map of the field under each wheel).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelInputError
from ..model import MFModel, load_tir
from .cone_index import ConeIndexTyre
from .model import SoftSoilTyre

__all__ = ["Ground", "GroundForces"]


@dataclass(frozen=True)
class GroundForces:
    """Forces on the wheel [N, N m] (ISO-W) and the rut depth [m], blended; ``slip`` is the soil slip i."""

    fx: np.ndarray
    fy: np.ndarray
    torque: np.ndarray
    sinkage: np.ndarray
    slip: np.ndarray


class Ground:
    """A tyre on hard ground (``soil=None`` or ``blend=0``), soft soil (``blend=1``) or a blend in between.

    ``soil``: a soil name or :class:`Soil` (the Bekker-Wong model, :class:`SoftSoilTyre` of this tyre), or a soil
    model of this tyre already built (a :class:`SoftSoilTyre` with its options, or a :class:`ConeIndexTyre`)."""

    def __init__(self, tyre, soil=None, blend=None):
        self.tyre = tyre if isinstance(tyre, MFModel) else load_tir(tyre)
        if isinstance(soil, (SoftSoilTyre, ConeIndexTyre)):
            if soil.tyre is not self.tyre:
                raise ModelInputError("Ground: the soil model must be built on the same tyre (MFModel) as Ground")
            self.soft = soil
        else:
            self.soft = None if soil is None else SoftSoilTyre(self.tyre, soil)
        blend = (0.0 if soil is None else 1.0) if blend is None else blend
        blend = np.asarray(blend, dtype=float)
        if not np.all((blend >= 0) & (blend <= 1)):
            raise ModelInputError(f"blend must be in [0, 1] (0 hard ground, 1 soft soil); got {blend!r}")
        if soil is None and np.any(blend > 0):
            raise ModelInputError("blend > 0 needs a soil (soil=NAME or a Soil)")
        self.blend = blend

    def forces(self, fz, kappa, alpha=0.0, vx=None, p=None) -> GroundForces:
        """Blended forces at the operating points (inputs broadcast; kappa > -1: the wheel turns forwards)."""
        prm = self.tyre.params
        vx = prm.LONGVL if vx is None else vx
        hard = self.tyre.evaluate(fz=fz, kappa=kappa, alpha=alpha, vx=vx, p=p)
        w = self.blend
        hard_torque = hard.fx * hard.rl - hard.my
        if self.soft is None:
            zero = 0.0 * hard.fx
            return GroundForces(hard.fx, hard.fy, hard_torque, zero, zero)
        kappa = np.asarray(kappa, dtype=float)
        if np.any(kappa <= -1):
            raise ModelInputError(f"kappa must be > -1 on soft soil (the wheel turns forwards); got {kappa.min()!r}")
        slip = kappa / (1.0 + kappa)
        soft = self.soft.evaluate(fz=fz, slip=slip, alpha=alpha, p=p, vx=vx)
        return GroundForces((1 - w) * hard.fx + w * soft.drawbar_pull, (1 - w) * hard.fy + w * soft.fy,
                            (1 - w) * hard_torque + w * soft.torque, w * soft.sinkage, soft.slip)
