"""The cone-index route: Brixius's traction equations for a tyre on a soil described by one cone index, behind the
same interface as :class:`~mftyre.soil.SoftSoilTyre` (``evaluate``, ``towed``, :class:`SoilOutputs`).

    >>> from mftyre.soil import ConeIndexTyre
    >>> tyre = ConeIndexTyre("tir_files/agri_460_85R34_mf61.tir", cone_index=1.0e6)   # CI in Pa
    >>> out = tyre.evaluate(fz=25e3, slip=np.linspace(0, 0.4, 21), p=1.2e5)
    >>> out.drawbar_pull, out.efficiency

Source: W.W. Brixius, "Traction prediction equations for bias ply tires", ASAE Paper 87-1622 (1987); the form
and coefficients as adopted in ASAE/ASABE D497 (Agricultural Machinery Management Data):
  mobility number        B_n = (CI b d / W) (1 + 5 delta / h) / (1 + 3 b / d)
  gross traction ratio   GT / W = 0.88 (1 - exp(-0.1 B_n)) (1 - exp(-7.5 s)) + 0.04
  motion resistance      MR / W = 1 / B_n + 0.04 + 0.5 s / sqrt(B_n)
  net traction ratio     NT / W = GT / W - MR / W            (drawbar pull DP = NT)
with CI the cone index, b the section width (WIDTH), d the overall diameter (2 UNLOADED_RADIUS), W the load, h the
section height (UNLOADED_RADIUS - RIM_RADIUS) and delta the tyre's deflection on hard ground at this load and
pressure (the .tir's Fz(rho, p)). The slip s = 1 - V / (omega Re) with the hard-ground rolling radius Re, as in
:mod:`mftyre.soil.equations`; the torque is GT Re (Brixius's torque ratio GT/W = T / (r W) with the rolling
radius r = Re). Fitted for bias-ply tyres on agricultural soils at driving slips; below s = 0 the exponential is
extrapolated. No lateral force, no sinkage, no contact geometry: those outputs are NaN.

Power: T omega = DP V + MR V + GT (omega Re - V), the last term the slip loss, exactly.
"""
from __future__ import annotations

import math

import numpy as np

from ..backend import NUMPY
from ..errors import ModelInputError
from ..formula import vertical
from ..model import MFModel, load_tir
from .equations import OUTPUTS, carcass_pressure, hard_ground_footprint
from .model import SoilOutputs, check_soil_inputs

__all__ = ["ConeIndexTyre", "mobility_number", "SOURCE"]

SOURCE = ("W.W. Brixius, Traction prediction equations for bias ply tires, ASAE Paper 87-1622 (1987); "
          "ASAE/ASABE D497")


def mobility_number(cone_index, width, diameter, load, deflection, section_height):
    """Brixius's B_n = (CI b d / W) (1 + 5 delta/h) / (1 + 3 b/d)."""
    shape = (1.0 + 5.0 * deflection / section_height) / (1.0 + 3.0 * width / diameter)
    return cone_index * width * diameter / load * shape


class ConeIndexTyre:
    """A tyre (an :class:`~mftyre.model.MFModel` or a .tir path) on a soil of cone index ``cone_index`` [Pa]."""

    def __init__(self, tyre, cone_index):
        self.tyre = tyre if isinstance(tyre, MFModel) else load_tir(tyre)
        if not (isinstance(cone_index, (int, float)) and math.isfinite(cone_index) and cone_index > 0):
            raise ModelInputError(f"cone_index must be a positive number in Pa (e.g. 1.0e6 for 1 MPa), "
                                  f"got {cone_index!r}")
        self.cone_index = float(cone_index)
        prm = self.params
        if not prm.RIM_RADIUS < prm.UNLOADED_RADIUS:
            raise ModelInputError(f"the cone-index model needs the section height UNLOADED_RADIUS - RIM_RADIUS > 0; "
                                  f"got RIM_RADIUS {prm.RIM_RADIUS!r} m, UNLOADED_RADIUS {prm.UNLOADED_RADIUS!r} m")

    @property
    def params(self):
        return self.tyre.params

    def evaluate(self, fz, slip, alpha=0.0, p=None, vx=None) -> SoilOutputs:
        """All outputs (:data:`mftyre.soil.OUTPUTS`; NaN where Brixius's model has none) at the operating points."""
        prm = self.params
        values = dict(fz=fz, slip=slip, alpha=alpha, p=prm.INFLPRES if p is None else p,
                      vx=prm.LONGVL if vx is None else vx)
        try:
            args = dict(zip(values, np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in values.values()))))
        except (TypeError, ValueError):
            raise ModelInputError(f"inputs must be numeric and broadcast to one shape, got {values!r}") from None
        check_soil_inputs(args)
        fz, s, p, vx = args["fz"], args["slip"], args["p"], args["vx"]
        dpi = vertical.pressure_increment(prm, p)
        r = vertical.free_radius(prm, 0.0, NUMPY)
        r_e = r - vertical.rolling_radius_reduction(prm, fz, dpi, NUMPY)
        rho, a_h, b_h = hard_ground_footprint(prm, fz, p, NUMPY)
        bn = mobility_number(self.cone_index, prm.WIDTH, 2.0 * prm.UNLOADED_RADIUS, fz, rho,
                             prm.UNLOADED_RADIUS - prm.RIM_RADIUS)
        gtr = 0.88 * (1.0 - np.exp(-0.1 * bn)) * (1.0 - np.exp(-7.5 * s)) + 0.04
        mrr = 1.0 / bn + 0.04 + 0.5 * s / np.sqrt(bn)
        gross, resistance = gtr * fz, mrr * fz
        omega = vx / ((1.0 - s) * r_e)
        torque = gross * r_e
        power = torque * omega
        drawbar = gross - resistance
        with np.errstate(all="ignore"):
            driven = power > 1e-9 * fz * vx
            efficiency = np.where(driven, drawbar * vx / np.where(driven, power, 1.0), np.nan)
        nan = np.full(fz.shape, np.nan)
        zero = np.zeros(fz.shape)
        out = dict(sinkage=nan, contact_length=nan, flat_length=nan, contact_width=zero + prm.WIDTH,
                   ground_pressure=nan, flat_load=nan, carcass_pressure=carcass_pressure(fz, a_h, b_h, p, NUMPY),
                   deflection=rho, rolling_radius=r_e,
                   compaction_resistance=resistance, bulldozing_resistance=zero, motion_resistance=resistance,
                   gross_traction=gross, drawbar_pull=drawbar, hysteresis_moment=zero, torque=torque, fy=nan,
                   omega=omega, power=power, slip_power=gross * (omega * r_e - vx), efficiency=efficiency, slip=s)
        assert set(out) == set(OUTPUTS)
        return SoilOutputs(**out)

    def towed(self, fz, alpha=0.0, p=None, vx=None) -> SoilOutputs:
        """The towed wheel (zero torque: GT = 0), in closed form: s = -ln(1 + 0.04 / (0.88 (1 - exp(-0.1 B_n))))
        / 7.5."""
        prm = self.params
        fz_a, p_a = np.broadcast_arrays(np.asarray(fz, dtype=float), np.asarray(prm.INFLPRES if p is None else p,
                                                                             dtype=float))
        check_soil_inputs(dict(fz=fz_a, slip=np.zeros(fz_a.shape), alpha=np.asarray(alpha, dtype=float), p=p_a,
                    vx=np.asarray(prm.LONGVL if vx is None else vx, dtype=float)))
        rho, _, _ = hard_ground_footprint(prm, fz_a, p_a, NUMPY)
        bn = mobility_number(self.cone_index, prm.WIDTH, 2.0 * prm.UNLOADED_RADIUS, fz_a, rho,
                             prm.UNLOADED_RADIUS - prm.RIM_RADIUS)
        slip = -np.log(1.0 + 0.04 / (0.88 * (1.0 - np.exp(-0.1 * bn)))) / 7.5
        return self.evaluate(fz_a, slip, alpha, p_a, vx)

    def __repr__(self):
        return f"ConeIndexTyre({self.tyre!r}, cone_index={self.cone_index:g} Pa)"
