"""What the model predicts for a measured channel: one rule for the fit, its report and the gap finder.

Channels FX FY MZ MX MY: the model outputs of :meth:`MFModel.evaluate` at the measured Fz, kappa, alpha, gamma,
phit, Vx and p, saturated to the .tir ranges (the caller warns once, :func:`mftyre.inputs.warn_data_outside`),
the spin estimated by the model from kappa and Vx. RE: the effective rolling radius at the measured spin OMEGA.
FZ: the vertical force of the load-deflection relation at the measured loaded radius RL (or, without RL, at
RL = R_omega - RHO, the measured deflection), the measured Fx, Fy, camber and pressure, and the wheel spin
(:func:`wheel_spin`: OMEGA, or without it the model's own estimate from kappa and Vx, as for the forces).
"""
from __future__ import annotations

import numpy as np

from ..backend import NUMPY
from ..data import TyreData
from ..formula import vertical
from ..inputs import saturate_inputs
from ..model import MFModel

__all__ = ["predict", "predict_stage", "wheel_spin", "OUTPUT_OF_CHANNEL"]

#: measured channel -> the model output it is compared with ("fz_from_rl": the vertical-force relation)
OUTPUT_OF_CHANNEL = {"FX": "fx", "FY": "fy", "MZ": "mz", "MX": "mx", "MY": "my", "RE": "re", "FZ": "fz_from_rl"}


def _channel(data: TyreData, name: str) -> np.ndarray:
    return np.nan_to_num(data.array(name)) if name in data else np.zeros(len(data))


def wheel_spin(model: MFModel, data: TyreData, inputs: dict | None = None) -> np.ndarray:
    """The wheel spin [rad/s] of every row for the vertical relation: the measured OMEGA where it is finite, else
    the spin the model itself estimates at the measured inputs, (1 + kappa) Vx / Re (:meth:`MFModel.evaluate`):
    a rolling wheel, never a standing one."""
    inputs = data.inputs() if inputs is None else inputs
    omega = data.array("OMEGA") if data.has("OMEGA") else np.full(len(data), np.nan)
    missing = ~np.isfinite(omega)
    if missing.any():
        estimate = model.evaluate(**saturate_inputs(model, inputs)).omega
        omega = np.where(missing, estimate, omega)
    return omega


def vertical_prediction(model: MFModel, data: TyreData, inputs: dict) -> np.ndarray:
    """Fz [N] of every row from the measured loaded radius (or deflection), Fx, Fy, camber, pressure and spin;
    NaN where neither is measured."""
    omega = wheel_spin(model, data, inputs)
    if data.has("RL"):
        rl = data.array("RL")
    else:  # measured deflection: the loaded radius it means for the model
        rl = vertical.free_radius(model.params, omega, NUMPY) - data.array("RHO")
    out = np.full(len(data), np.nan)
    ok = np.isfinite(rl)
    if ok.any():
        out[ok] = model.vertical_force(rl[ok], p=inputs["p"][ok], omega=omega[ok], fx=_channel(data, "FX")[ok],
                                       fy=_channel(data, "FY")[ok], gamma=inputs["gamma"][ok])
    return out


def predict(model: MFModel, data: TyreData, channels, inputs: dict | None = None, *,
            turn_slip: bool = False) -> dict:
    """Channel -> what ``model`` predicts for that measured channel at every row of ``data`` (``inputs``: the
    model inputs of the rows, :meth:`TyreData.inputs`, when already at hand). The force and moment channels share
    one evaluation."""
    inputs = data.inputs() if inputs is None else inputs
    out = {}
    forces = [c for c in channels if c not in ("FZ", "RE")]
    if forces:
        res = model.evaluate(**saturate_inputs(model, inputs), turn_slip=turn_slip)
        out.update({c: np.asarray(res[OUTPUT_OF_CHANNEL[c]], float) for c in forces})
    if "RE" in channels:
        omega = data.array("OMEGA") if data.has("OMEGA") else None
        out["RE"] = np.asarray(model.evaluate(**saturate_inputs(model, inputs), omega=omega, turn_slip=turn_slip)
                               ["re"], float)
    if "FZ" in channels:
        out["FZ"] = np.asarray(vertical_prediction(model, data, inputs), float)
    return out


def predict_stage(stage, model: MFModel, data: TyreData, inputs: dict) -> np.ndarray:
    """What ``model`` predicts for the measured channel of a fitting ``stage`` (:func:`predict`)."""
    return predict(model, data, (stage.channel,), inputs)[stage.channel]
