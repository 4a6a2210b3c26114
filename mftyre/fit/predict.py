"""What the model predicts for a measured channel: one rule for the fit, its report and the gap finder.

Channels FX FY MZ MX MY: the model outputs of :meth:`MFModel.evaluate` at the measured Fz, kappa, alpha, gamma,
phit, Vx and p, saturated to the .tir ranges (the caller warns once, :func:`mftyre.inputs.warn_data_outside`),
the spin estimated by the model from kappa and Vx. RE: the effective rolling radius at the measured spin OMEGA.
FZ: the vertical force of the load-deflection relation at the measured loaded radius RL (or, without RL, at
RL = R_omega - RHO, the measured deflection), the measured Fx, Fy, camber and pressure, and the wheel spin
(:func:`wheel_spin`: OMEGA, or without it the model's own estimate from kappa and Vx, as for the forces).

:class:`BatchPredictor` applies the same rule to many parameter sets at once (a finite-difference Jacobian, the
refits of the fit and the gap finder): the equations evaluated once with the varied parameters as column vectors
(shape (K, 1)) against the data as a row (shape (1, N)).
"""
from __future__ import annotations

import numpy as np

from ..backend import NUMPY
from ..data import TyreData
from ..formula import Modes, steady_state, vertical
from ..inputs import RANGE_PARAMETERS, saturate_inputs
from ..model import MFModel
from ..params import SELECTS_FORM

__all__ = ["predict", "predict_stage", "wheel_spin", "OUTPUT_OF_CHANNEL", "BatchPredictor", "BatchParameters"]

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


class BatchParameters:
    """Parameters of which some are column vectors (one row per parameter set); ``prm[name]`` of a structural
    parameter (a choice of equation form) gives the first row's value (the rows of a batch differ by small
    steps that, as :class:`BatchPredictor` ensures, do not switch the form). Every parameter is a plain attribute
    (the equations read hundreds per evaluation); other attributes are those of ``params``."""

    def __init__(self, params, columns: dict):
        self.__dict__.update(params.to_dict())
        self.__dict__.update(columns)
        self._params, self._columns = params, columns
        self.version, self.fittyp = params.version, params.fittyp

    def __getattr__(self, name):   # not a parameter: an attribute of the parameter set
        return getattr(self.__dict__["_params"], name)

    def __getitem__(self, name):
        if name in self._columns:
            value = self._columns[name]
            return float(np.ravel(value)[0]) if name in SELECTS_FORM else value
        return self._params[name]

    def __contains__(self, name):
        return name in self._params


class BatchPredictor:
    """:func:`predict` of the measured ``channels`` for many parameter sets at once: ``prm`` with ``names`` set to
    the values of each row of a (K, len(names)) array; channel -> (K, N) predictions of every row of ``data``.

    The force and moment channels share one evaluation of the equations with the varied parameters as column
    vectors against the (saturated, as :func:`predict`) inputs as a row, so a finite-difference Jacobian of K
    parameters costs one vectorised evaluation instead of K. A channel falls back to one :func:`predict` per set
    where a batch could switch the form of the equations (a varied parameter of :data:`mftyre.params.SELECTS_FORM`
    with the QSX12-14 moment on, a varied .tir range, the MF 6.2 vertical relation's branches on Q_FCY, a spin
    measured on some rows only) or where the model is mirrored (``side``)."""

    def __init__(self, prm, data: TyreData, channels, names, inputs: dict | None = None, *, side=None,
                 turn_slip: bool = False):
        self.prm, self.data, self.names, self.side, self.turn_slip = prm, data, list(names), side, bool(turn_slip)
        self.channels = tuple(channels)
        self.inputs = data.inputs() if inputs is None else inputs
        model = MFModel(prm, side=side)
        self.row = {k: np.asarray(v, float)[None, :] for k, v in saturate_inputs(model, self.inputs).items()}
        self.measured_row = {k: np.asarray(v, float)[None, :] for k, v in self.inputs.items()}  # FZ's: as measured
        self.modes = Modes(turn_slip=self.turn_slip)
        ranges = {n for lo, hi, _ in RANGE_PARAMETERS.values() for n in (lo, hi) if n}
        structural = set(names) & SELECTS_FORM
        loop_all = (side is not None or bool(set(names) & ranges)
                    or bool(structural and any(prm[f"QSX{i}"] != 0 for i in (12, 13, 14))))
        self.loop = {c: loop_all for c in self.channels}
        if "FZ" in self.channels:
            def chan(name):
                return np.nan_to_num(data.array(name))[None, :] if name in data else np.zeros((1, len(data)))
            # the spin: OMEGA, else the model's estimate (wheel_spin), per parameter set in __call__
            self.spin_measured = data.has("OMEGA") and bool(np.all(np.isfinite(data.array("OMEGA"))))
            self.vertical = dict(omega=chan("OMEGA"), fx=chan("FX"), fy=chan("FY"))
            self.loop["FZ"] = (loop_all or prm.version == "62"          # 6.2: branches on Q_FCY
                               or (data.has("OMEGA") and not self.spin_measured))   # partly measured: row by row
            if data.has("RL"):
                self.vertical["rl"] = data.array("RL")[None, :]
            else:
                self.vertical["rho"] = data.array("RHO")[None, :]
        self.omega_measured = data.array("OMEGA")[None, :] if data.has("OMEGA") else None
        self.no_omega = np.zeros((1, len(data)))

    def __call__(self, values: np.ndarray) -> dict:
        """Channel -> (K, N) predictions for the (K, P) parameter values (P = len(names))."""
        values = np.atleast_2d(np.asarray(values, float))
        k, n = values.shape[0], len(self.data)
        out = {}
        looped = [c for c in self.channels if self.loop[c]]
        if looped:
            each = [predict(MFModel(self.prm.replace(**dict(zip(self.names, v))), side=self.side), self.data, looped,
                            self.inputs, turn_slip=self.turn_slip) for v in values]
            out.update({c: np.stack([e[c] for e in each]) for c in looped})
        batched = [c for c in self.channels if not self.loop[c]]
        if not batched:
            return out
        prm = BatchParameters(self.prm, {nm: values[:, j:j + 1] for j, nm in enumerate(self.names)})
        r = self.row

        def evaluate(outputs, omega=None):   # the equations at the saturated inputs (the spin estimated, or given)
            given = omega is not None
            return steady_state(prm, r["fz"], r["kappa"], r["alpha"], r["gamma"], r["phit"], r["vx"], r["p"],
                                omega if given else self.no_omega, given, self.modes, NUMPY, outputs=outputs)

        forces = [c for c in batched if c not in ("FZ", "RE")]
        with np.errstate(all="ignore"):
            if forces:
                res = evaluate([OUTPUT_OF_CHANNEL[c] for c in forces])
                out.update({c: np.broadcast_to(res[OUTPUT_OF_CHANNEL[c]], (k, n)) for c in forces})
            if "RE" in batched:
                out["RE"] = np.broadcast_to(evaluate(("re",), self.omega_measured)["re"], (k, n))
            if "FZ" in batched:
                v = self.vertical
                omega = v["omega"] if self.spin_measured else evaluate(("omega",))["omega"]
                m = self.measured_row
                dpi = vertical.pressure_increment(prm, m["p"])
                r_omega = vertical.free_radius(prm, omega, NUMPY)
                rl = v["rl"] if "rl" in v else r_omega - v["rho"]
                fz = vertical.vertical_force(prm, rl, r_omega, omega, v["fx"], v["fy"], m["gamma"], dpi, NUMPY)
                out["FZ"] = np.broadcast_to(fz, (k, n))
        return out
