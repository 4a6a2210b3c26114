"""The prediction rule of the fit: what the model says for a stage's measured channel (one home for the fit and
its report)."""
from __future__ import annotations

import numpy as np

from ..backend import NUMPY
from ..data import TyreData
from ..formula import vertical
from ..inputs import saturate_inputs
from ..model import MFModel
from .stages import Stage

__all__ = ["predict_stage"]


def predict_stage(stage: Stage, model: MFModel, data: TyreData, inputs: dict) -> np.ndarray:
    """What ``model`` predicts for the measured channel of ``stage`` at ``data``'s rows (``inputs``: the model
    inputs of the rows): the vertical force at the measured loaded radius (or deflection) for the vertical
    stage, else the stage's output of :meth:`MFModel.evaluate` at the inputs saturated to the .tir ranges (the
    caller warns once, :func:`mftyre.inputs.warn_data_outside`), with the measured spin for the rolling radius."""
    if stage.output == "fz_from_rl":
        def chan(name):
            return np.nan_to_num(data.array(name)) if name in data else 0.0
        if data.has("RL"):
            rl = data.array("RL")
        else:  # measured deflection: the loaded radius it means for the model
            rl = vertical.free_radius(model.params, chan("OMEGA"), NUMPY) - data.array("RHO")
        return model.vertical_force(rl, p=inputs["p"], omega=chan("OMEGA"), fx=chan("FX"), fy=chan("FY"),
                                    gamma=inputs["gamma"])
    omega = data.array("OMEGA") if stage.output == "re" and data.has("OMEGA") else None
    return model.evaluate(**saturate_inputs(model, inputs), omega=omega)[stage.output]
