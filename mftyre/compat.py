"""Drop-in replacement for the MATLAB evaluator MFeval: ``mfeval(tir, inputs, use_mode) -> (N, 30)``.

Input columns ``[Fz kappa alpha gamma phit Vx P omega]`` (6 to 8 columns, ISO-W, SI); a missing or zero P
means INFLPRES, a missing or zero omega means "estimate it" (decided per row; MFeval decides per call) by MFeval's
own iteration: from Re = 0.965 R0, omega = (1 + kappa) Vx / Re and Re = R_omega(omega) - (R_omega - Re)(Fz) (book
(2.5), paper (1), (7)) until Re changes by at most 1e-9 m, omega from the step before the last Re (MFeval stops a
call once every row has converged; here each row stops by itself: the same for one-row calls).
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
    given = omega != 0
    if not given.all():  # MFeval's own spin estimate (its Re and omega differ from the converged ones by ~3e-9)
        p_used = model.used_input("p", arrays["p"]) if modes.limits else arrays["p"]
        arrays["omega"] = np.where(given, arrays["omega"],
                                   _mfeval_spin(prm, np.maximum(arrays["fz"], 0.0), arrays["kappa"], arrays["vx"],
                                                p_used))
    out = model._evaluate_arrays(arrays, True, modes)
    _reference_values(model, arrays, omega != 0, modes, out)

    result = np.empty((n, len(MFEVAL_COLUMNS)))
    for j, name in enumerate(MFEVAL_COLUMNS):
        if name in _FROM_OUTPUT:
            result[:, j] = out[_FROM_OUTPUT[name]]
    result[:, MFEVAL_COLUMNS.index("2a")] = 2.0 * out["a"]
    result[:, MFEVAL_COLUMNS.index("2b")] = 2.0 * out["b"]
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
    """MFeval's loaded radius, deflection and vertical stiffness in ``out`` (in place, :func:`_mfeval_vertical`),
    and a :class:`ReferenceValueWarning` where they, or the inputs, are beyond what the model itself gives or
    accepts."""
    prm = model.params
    notes = [message for _, message in limit_problems(prm, arrays, modes.limits, omega_given)]
    try:  # the model's own outputs: a deflection or radius no tyre has under load?
        check_tyre_outputs(out, arrays, prm)
    except ModelInputError as exc:
        notes.append(str(exc))
    own = {k: out[k].copy() for k in ("rl", "rho", "cz")}
    _mfeval_vertical(model, arrays, modes, out)
    loaded = out["fz"] > 0
    with np.errstate(all="ignore"):
        differs = loaded & ~(np.abs(out["rho"] - own["rho"]) <= 1e-6 * prm.UNLOADED_RADIUS)
    if differs.any():
        i = int(np.argmax(differs.reshape(-1)))
        notes.append(f"the deflection differs from the model's at {int(differs.sum())} row(s), first at Fz = "
                     f"{arrays['fz'].reshape(-1)[i]:.6g} N: MFeval rho = {out['rho'].reshape(-1)[i]:.6g} m, "
                     f"Rl = {out['rl'].reshape(-1)[i]:.6g} m, the model (MFModel.evaluate) "
                     f"{own['rho'].reshape(-1)[i]:.6g} m, {own['rl'].reshape(-1)[i]:.6g} m (MFeval: no bottoming; "
                     "the MF 6.1 deflection at FZMAX above it; its MF 6.2 secant iterate)")
    for note in notes:
        warnings.warn(f"compat.mfeval returns MFeval's values: {note}", ReferenceValueWarning, stacklevel=3)


def _mfeval_vertical(model, arrays: dict, modes, out: dict) -> None:
    """Rl, rho and Cz as MFeval 4.3.1 computes them (its calculateRhoRl61/62), in place. The model's vertical
    relations (mftyre.formula.vertical) are the same equations (paper (3), (4), A3.3 and the MF 6.2 relation) with
    the rim's bottoming added and solved to the root; MFeval has no bottoming and reports, for MF 6.1/5.2, the
    textbook root of the quadratic at the load saturated to FZMAX and raised to FZMIN (complex where it has no real
    root, of which it keeps the real part), for MF 6.2 the iterate of its secant method (20 calls at most,
    tolerance 1e-6 FNOMIN) at the load as given; Cz is the load (MF 6.2: saturated at FZMAX) over rho."""
    prm = model.params
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    fz = np.maximum(arrays["fz"], 0.0)
    fz_used = np.minimum(fz, prm.FZMAX) if modes.limits else fz
    omega, dpi = out["omega"], vertical.pressure_increment(prm, out["p"])
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    sign = -1.0 if model.mirrored else 1.0
    fx, fy = out["fx"], sign * out["fy"]
    q_fz1 = np.sqrt((prm.VERTICAL_STIFFNESS * R0 / Fz0) ** 2 - 4.0 * prm.Q_FZ2)  # paper (4)
    with np.errstate(all="ignore"):
        if prm.version != "62":
            load = np.maximum(fz_used, prm.FZMIN) if modes.limits else fz_used  # Fz_lowLimit
            effects = (1.0 + prm.Q_V2 * (R0 / prm.LONGVL) * np.abs(omega) - (prm.Q_FCX * fx / Fz0) ** 2
                       - (prm.Q_FCY * fy / Fz0) ** 2) * (1.0 + prm.PFZ1 * dpi) * Fz0  # A3.3
            c = -(load / effects)
            x = (-q_fz1 + np.sqrt((q_fz1**2 - 4.0 * prm.Q_FZ2 * c).astype(complex))) / (2.0 * prm.Q_FZ2)
            x = np.where(np.isnan(x), 0.0, x)  # (0/0 where Q_FZ2 = 0: MATLAB's max(NaN, 0) is 0)
            rho = np.where(np.isreal(x), np.maximum(x.real, 0.0), x) * R0  # max(x R0, 0) (by modulus if complex)
            rl = np.where(np.isreal(rho), np.maximum(r_omega - rho.real, 0.0), r_omega - rho)
            rho = np.where(load == 0, 1e-6, rho)
            cz = load / rho
        else:
            gamma = sign * arrays["gamma"]
            gamma = np.clip(gamma, prm.CAMMIN, prm.CAMMAX) if modes.limits else gamma

            def fz62(rl):  # MFeval's calculateFz62
                ratio = rl / r_omega
                sfyg = (prm.Q_FYS1 + prm.Q_FYS2 * ratio + prm.Q_FYS3 * ratio**2) * gamma
                rho_zfr = np.maximum(r_omega - rl, 0.0)
                rtw = (1.075 - 0.5 * prm.ASPECT_RATIO) * prm.WIDTH
                rho_zg = (((prm.Q_CAM1 * rl + prm.Q_CAM2 * rl**2) * gamma) ** 2 * (rtw / 8) * np.abs(np.tan(gamma))
                          / ((prm.Q_CAM1 * r_omega + prm.Q_CAM2 * r_omega**2) * gamma) ** 2
                          - prm.Q_CAM3 * rho_zfr * np.abs(gamma))
                rho_z = np.maximum(rho_zfr + np.where(np.isnan(rho_zg), 0.0, rho_zg), 1e-12)
                fcorr = (1 + prm.Q_V2 * (R0 / prm.LONGVL) * np.abs(omega) - (prm.Q_FCX * fx / Fz0) ** 2
                         - ((rho_z / R0) ** prm.Q_FCY2 * (prm.Q_FCY * (fy - sfyg) / Fz0)) ** 2) * (1 + prm.PFZ1 * dpi)
                return fcorr * (q_fz1 * (rho_z / R0) + prm.Q_FZ2 * (rho_z / R0) ** 2) * Fz0, rho_z

            rl = _secant(lambda r: fz62(r)[0] - fz, np.full(fz.shape, 0.95 * R0), np.full(fz.shape, R0),
                         1e-6 * Fz0)
            rho = np.where(fz_used == 0, 1e-6, fz62(rl)[1])
            cz = fz_used / rho
    out["rl"], out["rho"], out["cz"] = np.real(rl), np.real(rho), np.real(cz)


def _secant(fun, x0, x1, ytol):
    """MFeval's solve_secant: at most 20 calls; each element stops once |fun| <= ytol; the better of the last two
    points is kept as the second one."""
    y0, y1 = fun(x0), fun(x1)
    active = np.ones(x0.shape, dtype=bool)
    x = x1.copy()
    for _ in range(3, 21):
        step = x1 - (x1 - x0) / (y1 - y0) * y1
        x = np.where(active, step, x)
        y = fun(x)
        active &= np.abs(y) > ytol
        if not active.any():
            break
        better = np.abs(y1) < np.abs(y0)
        x0, y0 = np.where(better, x1, x0), np.where(better, y1, y0)
        x1, y1 = x, y
    return x


def _mfeval_spin(prm, fz, kappa, vx, p):
    """omega of MFeval's fixed-point spin estimate (module docstring) at the load, unsaturated slip, speed and
    pressure used; rows that do not converge in 10 000 steps (|Vx| far beyond any tyre's) keep their last step."""
    reduction = vertical.rolling_radius_reduction(prm, fz, vertical.pressure_increment(prm, p), NUMPY)
    shape = np.broadcast_shapes(np.shape(fz), np.shape(kappa), np.shape(vx), np.shape(p))
    r0 = prm.UNLOADED_RADIUS
    re, re_old = np.full(shape, 0.965 * r0), np.full(shape, r0)
    omega = np.zeros(shape)
    active = np.ones(shape, dtype=bool)
    with np.errstate(all="ignore"):
        for _ in range(10000):
            re_old = np.where(active, re, re_old)
            omega = np.where(active, (kappa * vx + vx) / re, omega)
            re = np.where(active, vertical.free_radius(prm, omega, NUMPY) - reduction, re)
            active &= np.abs(re_old - re) > 1e-9
            if not active.any():
                break
    return omega
