"""Drop-in replacement for the MATLAB evaluator MFeval: ``mfeval(tir, inputs, use_mode) -> (N, 30)``.

Input columns ``[Fz kappa alpha gamma phit Vx P omega]`` (6 to 8 columns, ISO-W, SI); a missing or zero P
means INFLPRES, a missing or zero omega means "estimate it" (decided per row; MFeval decides per call).
``use_mode`` has three digits: hundreds 1/2 = limit checks on/off, tens 1/2 = alpha* off/on, units 1/2 =
turn slip off/on.

Above FZMAX (limit checks on) the model and MFeval split the load alike: Fx, Fy, Mz, Mx and the relaxation outputs at
FZMAX, Re, the spin, the MF 6.2 loaded radius, the contact patch and My at the load given. MFeval's MF 6.1/5.2
deflection (and so Rl and Cz) stays at FZMAX's, and its MF 6.2 Cz divides the saturated load by the deflection at the
load given: :func:`mfeval` returns these values as MFeval does and warns (:class:`mftyre.ReferenceValueWarning`),
as it does where the inputs are beyond the limits at which the model refuses them (:func:`mftyre.inputs.check_limits`).

Output columns, in MFeval's order (half lengths doubled to 2a, 2b as MFeval reports them):
"""
from __future__ import annotations

import warnings

import numpy as np

from .backend import NUMPY
from .errors import ModelInputError, ReferenceValueWarning
from .formula import Modes, vertical
from .formula.normalisation import condition_inputs
from .inputs import check_tyre_outputs, limit_problems
from .model import MFModel, as_float_arrays, load_tir

__all__ = ["mfeval", "MFEVAL_COLUMNS"]

MFEVAL_COLUMNS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "Re", "rho",
                  "2a", "t", "mux", "muy", "omega", "Rl", "2b", "Mzr", "Cx", "Cy", "Cz", "Kya", "sigmax", "sigmay",
                  "iKya", "Kxk")
__doc__ += "    " + " ".join(MFEVAL_COLUMNS) + "\n"

_FROM_OUTPUT = {"Fx": "fx", "Fy": "fy", "Fz": "fz", "Mx": "mx", "My": "my", "Mz": "mz", "kappa": "kappa",
                "alpha": "alpha", "gamma": "gamma", "phit": "phit", "Vx": "vx", "P": "p", "Re": "re", "rho": "rho",
                "t": "t", "mux": "mux", "muy": "muy", "omega": "omega", "Rl": "rl", "Mzr": "mzr", "Cx": "cx",
                "Cy": "cy", "Cz": "cz", "Kya": "kya", "sigmax": "sigmax", "sigmay": "sigmay", "Kxk": "kxk"}


def mfeval(tir, inputs, use_mode: int, *, turn_slip_form: str = "published") -> np.ndarray:
    """Evaluate like MFeval. ``tir``: a path or an :class:`MFModel`; ``turn_slip_form='mfeval'`` reproduces
    MFeval's turn-slip equations (see :data:`mftyre.formula.options.TURN_SLIP_FORMS`); the default is the
    published form."""
    model = tir if isinstance(tir, MFModel) else load_tir(tir)
    modes = Modes.from_use_mode(use_mode, turn_slip_form=turn_slip_form)
    table = np.atleast_2d(np.asarray(inputs, dtype=float))
    if table.ndim != 2 or not 6 <= table.shape[1] <= 8:
        raise ModelInputError(f"inputs must be an (N, 6..8) array [Fz kappa alpha gamma phit Vx P omega], "
                              f"got shape {np.shape(inputs)}")
    prm = model.params
    n = table.shape[0]
    pressure = table[:, 6] if table.shape[1] > 6 else np.zeros(n)
    omega = table[:, 7] if table.shape[1] > 7 else np.zeros(n)
    arrays = as_float_arrays(dict(fz=table[:, 0], kappa=table[:, 1], alpha=table[:, 2], gamma=table[:, 3],
                                   phit=table[:, 4], vx=table[:, 5],
                                   p=np.where(pressure == 0, prm.INFLPRES, pressure), omega=omega))
    if np.any(arrays["p"] < 0):
        raise ModelInputError("pressure column P must be positive (or 0 for INFLPRES)")
    out = model._evaluate_arrays(arrays, omega != 0, modes)
    _reference_values(model, arrays, omega != 0, modes, out)

    result = np.empty((n, len(MFEVAL_COLUMNS)))
    for j, name in enumerate(MFEVAL_COLUMNS):
        if name in _FROM_OUTPUT:
            result[:, j] = out[_FROM_OUTPUT[name]]
    result[:, MFEVAL_COLUMNS.index("2a")] = 2.0 * out["a"]
    result[:, MFEVAL_COLUMNS.index("2b")] = 2.0 * out["b"]
    # MFeval's MF 6.1/6.2 branch reports a placeholder deflection of 1e-6 m where the tyre carries no load; its
    # MF 5.2 branch reports the deflection it computes (at FZMIN with limit checks, FZMIN/Cz ~ 2.16e-4 m for
    # its MF 5.2 sample file)
    if prm.version != "52":
        rho_col = MFEVAL_COLUMNS.index("rho")
        result[:, rho_col] = np.where(out["fz"] == 0, 1e-6, result[:, rho_col])
    # "instantaneous" cornering stiffness: forward difference over consecutive rows of the call
    with np.errstate(all="ignore"):
        sign = -1.0 if model.mirrored else 1.0
        alpha_used = sign * condition_inputs(prm, arrays["fz"], arrays["kappa"], sign * arrays["alpha"],
                                             arrays["gamma"], arrays["phit"], arrays["vx"], arrays["p"], modes,
                                             NUMPY).alpha
        if n > 1:
            diff = np.diff(out["fy"]) / np.diff(alpha_used)
            result[:, MFEVAL_COLUMNS.index("iKya")] = np.append(diff, diff[-1])
        else:
            result[:, MFEVAL_COLUMNS.index("iKya")] = 0.0
    return result


def _reference_values(model, arrays: dict, omega_given, modes, out: dict) -> None:
    """MFeval's vertical outputs above FZMAX in ``out`` (in place), and a :class:`ReferenceValueWarning` for them
    and for inputs beyond the model's limits."""
    prm = model.params
    notes = [message for _, message in limit_problems(prm, arrays, modes.limits, omega_given)]
    above = arrays["fz"] > prm.FZMAX if modes.limits else np.zeros(arrays["fz"].shape, dtype=bool)
    if above.any():
        fz_used = max(prm.FZMAX, prm.FZMIN)  # MFeval's Fz_lowLimit above FZMAX
        if prm.version == "62":  # Cz = Fz (saturated) / rho (at the load given)
            out["cz"] = np.where(above, prm.FZMAX / out["rho"], out["cz"])
            what = "Cz as FZMAX divided by the deflection at the load"
        else:  # the MF 6.1 deflection at FZMAX, Rl = R_omega - rho, Cz = FZMAX / rho
            dpi = vertical.pressure_increment(prm, out["p"])
            r_omega = vertical.free_radius(prm, out["omega"], NUMPY)
            with np.errstate(all="ignore"):
                rl, rho = vertical.loaded_radius(prm, fz_used, r_omega, out["omega"], out["fx"], out["fy"], 0.0, dpi,
                                                 NUMPY)
            out["rl"], out["rho"] = np.where(above, rl, out["rl"]), np.where(above, rho, out["rho"])
            out["cz"] = np.where(above, fz_used / rho, out["cz"])
            what = "the deflection, Rl and Cz of the load FZMAX"
        notes.append(f"Fz above FZMAX = {prm.FZMAX:g} N at {int(above.sum())} row(s) (up to {arrays['fz'].max():.6g} "
                     f"N): MFeval returns {what}, which no tyre carrying more load has; the model's own "
                     "(MFModel.evaluate) are those of the load")
    try:
        check_tyre_outputs(out, arrays)
    except ModelInputError as exc:
        notes.append(str(exc))
    for note in notes:
        warnings.warn(f"compat.mfeval returns MFeval's values: {note}", ReferenceValueWarning, stacklevel=3)
