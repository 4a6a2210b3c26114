"""Verify a parameter set before it is written: finite and plausible over its whole declared range.

:func:`verify_tir` is the one check used by the fitting stages (:mod:`mftyre.fit.core`) and by the gap finder
(before an improved ``.tir`` is accepted): it evaluates the model on a grid spanning the ``.tir``'s own limits
(FZMIN..FZMAX, KPUMIN..KPUMAX, ALPMIN..ALPMAX, CAMMIN..CAMMAX, PRESMIN..PRESMAX) and speeds from 1 m/s to
beyond the data's top speed (``max(1.25 x data top speed, 40 m/s, 1.25 LONGVL)``), where there are data and
where there are none, and returns the problems found as sentences naming the quantity, where, the value and
what was expected. An empty list means the parameters pass.

Checks (each a physical property of a pneumatic tyre, not of the data):

* every output finite, and no exception from the model (e.g. the spin fixed point failing to converge);
* free radius growth with speed R_omega / (R0 Q_RE0) - 1 within [-1 %, +5 %] (Q_V1), vertical stiffness
  factor with speed 1 + Q_V2 |omega| R0 / V0 within [0.8, 1.5] at the top speed;
* loaded radius within the tyre: 0.5 R0 < Rl <= R_omega and deflection >= 0 at every load > 0; Fz(rho)
  increasing (the vertical stiffness positive) at every pressure;
* effective rolling radius within [0.7 R0, 1.05 R_omega];
* pure-slip signs (ISO-W): Fx > 0 for kappa >= 0.05 and < 0 for kappa <= -0.05, Fy < 0 for alpha >= 3 deg and
  > 0 for alpha <= -3 deg (camber 0), at every load and pressure and at the slip limits;
* no invented asymmetry: at camber 0, |Fx(+kappa)| / |Fx(-kappa)| and |Fy(+alpha)| / |Fy(-alpha)| within
  [1/1.5, 1.5] at kappa = 0.05, 0.1 and alpha = 3, 6 deg;
* friction plausible: |Fx|, |Fy| <= 4 Fz + 0.1 FNOMIN; moments: |Mz| <= 0.5 Fz R0 + 0.02 FNOMIN R0,
  |Mx| <= Fz R0, |My| <= 0.1 Fz R0 + 0.01 FNOMIN R0.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["verify_tir", "check_speeds"]

_ASYMMETRY = 1.5


def check_speeds(prm, data_ranges=None) -> np.ndarray:
    """The speeds [m/s] verified: 1 m/s to max(1.25 x the data's top speed, 40, 1.25 LONGVL)."""
    top = _data_top_speed(data_ranges)
    return np.linspace(1.0, max(1.25 * top, 40.0, 1.25 * prm.LONGVL), 9)


def _worst_asymmetry(up, down):
    """(ratio, i): |up| / |down| of a force under opposite pure slips at the two smaller slip levels (last axis),
    and the index of its worst point when some ratio lies outside 1/_ASYMMETRY.._ASYMMETRY (else None)."""
    ratio = np.abs(up[..., :2]) / np.maximum(np.abs(down[..., :2]), 1e-9)
    if np.any((ratio > _ASYMMETRY) | (ratio < 1 / _ASYMMETRY)):
        return ratio, np.unravel_index(np.argmax(np.abs(np.log(ratio))), ratio.shape)
    return ratio, None


def _data_top_speed(data_ranges) -> float:
    if data_ranges is None:
        return 0.0
    if hasattr(data_ranges, "array"):  # TyreData
        return float(np.nanmax(np.abs(data_ranges.array("VX"))))
    vx = data_ranges.get("VX", 0.0)
    return float(np.max(np.abs(vx))) if np.size(vx) else 0.0


def verify_tir(model, data_ranges=None) -> list[str]:
    """Problems of ``model`` (an :class:`mftyre.MFModel`, or parameters) over its declared range; [] when none.

    ``data_ranges``: the measured data (:class:`mftyre.data.TyreData`) or a dict with ``"VX"`` (speeds or the top
    speed, m/s), used to extend the speed range checked beyond the data's top speed. See the module text.
    """
    from ..model import MFModel

    if not isinstance(model, MFModel):
        model = MFModel(model)
    prm = model.params
    problems = []
    r0, fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    fz_lo = max(prm.FZMIN, 0.05 * fz0)
    fz_hi = prm.FZMAX if prm.FZMAX > fz_lo else 2.0 * fz0
    loads = np.linspace(fz_lo, fz_hi, 6)
    pressures = np.array([prm.PRESMIN, prm.NOMPRES, prm.PRESMAX]) if prm.PRESMAX > prm.PRESMIN > 0 \
        else np.array([prm.NOMPRES])
    speeds = check_speeds(prm, data_ranges)
    kappas = np.unique(np.concatenate([np.linspace(prm.KPUMIN, prm.KPUMAX, 9), [-0.1, -0.05, 0.0, 0.05, 0.1]]))
    alphas = np.unique(np.concatenate([np.linspace(prm.ALPMIN, prm.ALPMAX, 9), np.radians([-6, -3, 0, 3, 6])]))
    gammas = np.unique([prm.CAMMIN, 0.0, prm.CAMMAX])

    def run(fz, kappa, alpha, gamma, vx, p, what):
        try:
            out = model.evaluate(fz, kappa, alpha, gamma, 0.0, vx, p)
        except (ArithmeticError, ValueError, FloatingPointError) as exc:
            problems.append(f"{what}: the model fails ({type(exc).__name__}: {exc})")
            return None
        bad = [k for k in ("fx", "fy", "mx", "my", "mz", "rl", "re", "omega") if not np.all(np.isfinite(out[k]))]
        if bad:
            problems.append(f"{what}: non-finite {', '.join(bad)}")
            return None
        return out

    # combined slip, camber, pressure and load over the declared range at the reference speed
    F, K, A, G, P = np.meshgrid(loads, kappas, alphas, gammas, pressures, indexing="ij")
    out = run(F, K, A, G, prm.LONGVL, P, "declared slip/camber/load/pressure range")
    if out is not None:
        mu_lim = 4.0 * F + 0.1 * fz0
        for name, lim in (("fx", mu_lim), ("fy", mu_lim)):
            worst = np.max(np.abs(out[name]) - lim)
            if worst > 0:
                i = np.unravel_index(np.argmax(np.abs(out[name]) - lim), F.shape)
                problems.append(f"|{name.upper()}| = {abs(out[name][i]):.0f} N exceeds 4 Fz at Fz {F[i]:.0f} N, "
                                f"kappa {K[i]:.3g}, alpha {math.degrees(A[i]):.3g} deg, p {P[i]:.0f} Pa")
        for name, lim in (("mz", 0.5 * F * r0 + 0.02 * fz0 * r0), ("mx", F * r0 + 0.02 * fz0 * r0),
                          ("my", 0.1 * F * r0 + 0.01 * fz0 * r0)):
            excess = np.abs(out[name]) - lim
            if np.max(excess) > 0:
                i = np.unravel_index(np.argmax(excess), F.shape)
                problems.append(f"|{name.upper()}| = {abs(out[name][i]):.4g} N m implausibly large at Fz {F[i]:.0f} N, "
                                f"kappa {K[i]:.3g}, alpha {math.degrees(A[i]):.3g} deg, camber "
                                f"{math.degrees(G[i]):.3g} deg")
    # pure-slip signs and symmetry at camber 0
    Fl, Pl, Kl = np.meshgrid(loads, pressures, np.array([0.05, 0.1, prm.KPUMAX]), indexing="ij")
    up, down = run(Fl, Kl, 0.0, 0.0, prm.LONGVL, Pl, "pure kappa"), run(Fl, -Kl, 0.0, 0.0, prm.LONGVL, Pl,
                                                                         "pure kappa")
    if up is not None and down is not None:
        if np.any(up.fx <= 0) or np.any(down.fx >= 0):
            problems.append(f"Fx has the wrong sign under pure longitudinal slip (Fx {np.min(up.fx):.0f} N at "
                            f"kappa > 0, {np.max(down.fx):.0f} N at kappa < 0): expected Fx > 0 for kappa > 0")
        ratio, i = _worst_asymmetry(up.fx, down.fx)
        if i is not None:
            problems.append(f"Fx asymmetry: Fx = {down.fx[..., :2][i]:.0f} / {up.fx[..., :2][i]:.0f} N at kappa = "
                            f"-/+{Kl[..., :2][i]:.3g}, Fz {Fl[..., :2][i]:.0f} N (ratio {ratio[i]:.2f}, expected "
                            f"within 1/{_ASYMMETRY}..{_ASYMMETRY}; shifts PHX*/PVX*)")
    Fa, Pa, Aa = np.meshgrid(loads, pressures, np.array([math.radians(3), math.radians(6), prm.ALPMAX]), indexing="ij")
    up, down = run(Fa, 0.0, Aa, 0.0, prm.LONGVL, Pa, "pure alpha"), run(Fa, 0.0, -Aa, 0.0, prm.LONGVL, Pa, "pure alpha")
    if up is not None and down is not None:
        if np.any(up.fy >= 0) or np.any(down.fy <= 0):
            problems.append(f"Fy has the wrong sign under pure slip angle (Fy {np.max(up.fy):.0f} N at alpha > 0, "
                            f"{np.min(down.fy):.0f} N at alpha < 0): expected Fy < 0 for alpha > 0 (ISO-W)")
        ratio, i = _worst_asymmetry(up.fy, down.fy)
        if i is not None:
            problems.append(f"Fy asymmetry at camber 0: ratio {ratio[i]:.2f} at alpha = -/+"
                            f"{math.degrees(Aa[..., :2][i]):.3g} deg, Fz {Fa[..., :2][i]:.0f} N (expected within "
                            f"1/{_ASYMMETRY}..{_ASYMMETRY}; shifts PHY*/PVY*)")
    # speed: free rolling up to beyond the top speed
    Fs, Ps, Vs = np.meshgrid(loads, pressures, speeds, indexing="ij")
    out = run(Fs, 0.0, 0.0, 0.0, Vs, Ps, f"free rolling up to {speeds[-1]:.0f} m/s")
    if out is not None:
        from ..formula import vertical
        from ..backend import NUMPY

        r_omega = vertical.free_radius(prm, out.omega, NUMPY)
        growth = r_omega / (r0 * prm.Q_RE0) - 1.0
        if np.max(growth) > 0.05 or np.min(growth) < -0.01:
            problems.append(f"free radius grows by {100 * np.max(growth):.3g} % (min {100 * np.min(growth):.3g} %) "
                            f"up to {speeds[-1]:.0f} m/s: expected a few percent at most (Q_V1 = {prm.Q_V1:.4g})")
        speed_factor = 1.0 + prm.Q_V2 * r0 / prm.LONGVL * np.abs(out.omega)
        if np.max(speed_factor) > 1.5 or np.min(speed_factor) < 0.8:
            problems.append(f"vertical stiffness factor with speed 1 + Q_V2 |omega| R0/V0 reaches "
                            f"{np.max(speed_factor):.3g} (min {np.min(speed_factor):.3g}) up to {speeds[-1]:.0f} m/s: "
                            f"expected 0.8..1.5 (Q_V2 = {prm.Q_V2:.4g})")
        rl, re = out.rl, out.re
        if np.any(rl <= 0.5 * r0) or np.any(rl > r_omega * (1 + 1e-9)):
            problems.append(f"loaded radius {np.min(rl):.4g}..{np.max(rl):.4g} m outside the tyre (0.5 R0 = "
                            f"{0.5 * r0:.4g} m .. R_omega up to {np.max(r_omega):.4g} m)")
        if np.any(out.rho < 0):
            problems.append(f"negative deflection {np.min(out.rho):.3g} m at positive load")
        if np.any(re < 0.7 * r0) or np.any(re > 1.05 * r_omega):
            problems.append(f"effective rolling radius {np.min(re):.4g}..{np.max(re):.4g} m outside 0.7 R0 .. "
                            f"1.05 R_omega (BREFF, DREFF, FREFF)")
    # vertical stiffness: Fz increases with deflection at every pressure
    for p in pressures:
        dpi = (p - prm.NOMPRES) / prm.NOMPRES
        cz = prm.VERTICAL_STIFFNESS * (1.0 + prm.PFZ1 * dpi)
        if not cz > 0 or prm.Q_FZ2 < 0:
            problems.append(f"vertical stiffness not positive at p = {p:.0f} Pa (VERTICAL_STIFFNESS "
                            f"{prm.VERTICAL_STIFFNESS:.4g}, PFZ1 {prm.PFZ1:.4g}, Q_FZ2 {prm.Q_FZ2:.4g})")
    return problems
