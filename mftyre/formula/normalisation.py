"""Input conditioning, normalised load and pressure increments, alpha*, gamma* and friction scalings.

Limits and the low-speed model (``modes.limits``), following the TNO/MF-Tyre practice that the reference
evaluator encodes:

* Fz < 0 is set to 0 (the tyre has left the road). Fz is saturated at FZMAX in the fitted force and moment
  equations (Fx, Fy, Mz, Mx) and the relaxation outputs; the vertical relations (Re and the spin, the loaded radius
  and deflection, the vertical stiffness, the contact patch) and My use the load as given (``uFz``), as the
  reference evaluator does. FZMIN raises the load used in the aligning-torque coefficients and the MF 6.1
  deflection only.
* alpha, gamma, kappa and p are saturated to [ALPMIN, ALPMAX], [CAMMIN, CAMMAX], [KPUMIN, KPUMAX] and
  [PRESMIN, PRESMAX].
* Below VXLOW: kappa and phit scale linearly with |Vx|/VXLOW, alpha with (|Vx| + |Vsy|)/VXLOW when that sum
  is below VXLOW; the shifts SHx, SVx, SHy, SVy, SVyk, the trail t and the residual torque Mzr are scaled by
  the smooth factor 0.5 (1 - cos(pi Vx / VXLOW)).
* With limits on, the turn slip is projected, phit cos(alpha), and its sign follows the direction of travel.
"""
from __future__ import annotations

from types import SimpleNamespace

from .options import SMOOTH_LIMITS_MARGIN, SMOOTH_LIMITS_SLOPE
from .vertical import pressure_increment

__all__ = ["condition_inputs", "smooth_low_speed"]


def condition_inputs(prm, fz, kappa, alpha, gamma, phit, vx, p, modes, be) -> SimpleNamespace:
    """The conditioned inputs and the basic quantities of Section 4.3.2 (4.E1-4.E8)."""
    s = SimpleNamespace(vx=vx, ukappa=kappa, ugamma=gamma, uphit=phit)
    uFz = be.of("force").fmax(fz, 0.0)  # a negative load means no contact
    s.uFz = uFz
    s.alpha_out = be.where(vx == 0, 0.0, alpha)

    if modes.limits:
        VXLOW = prm.VXLOW
        s.low_speed = be.abs(vx) <= VXLOW
        if be.any(phit != 0):  # (NumPy skips this without turn slip)
            phit = phit * be.cos(alpha)
        if modes.low_speed and be.any(s.low_speed):  # (NumPy skips this when no point is that slow: factors 1)
            speed_kink = be.of("speed")  # (the switch at VXLOW rounded with the speed width when smooth)
            reduction_linear = speed_kink.fmin(speed_kink.abs(vx), VXLOW) / VXLOW
            s.reduction_smooth = be.where(s.low_speed, 1.0 - 0.5 * (1.0 + be.cos(be.pi * vx / VXLOW)), 1.0)
            kappa = kappa * reduction_linear
            phit = phit * reduction_linear
            speed_sum = speed_kink.abs(vx) + speed_kink.abs(be.tan(alpha) * vx)  # below VXLOW only where |Vx| is
            alpha = alpha * (speed_kink.fmin(speed_sum, VXLOW) / VXLOW)
        else:
            s.reduction_smooth = None
        s.kappa_out = kappa
        phit = be.where(vx < 0, -phit, phit)

        def saturate(x, lo, hi):
            if modes.limits == "smooth":  # a soft saturation beyond the ranges (see Modes.limits)
                return _soft_saturate(x, lo, hi, be)
            return be.saturate(x, lo, hi)

        kappa = saturate(kappa, prm.KPUMIN, prm.KPUMAX)
        alpha = saturate(alpha, prm.ALPMIN, prm.ALPMAX)
        gamma = saturate(gamma, prm.CAMMIN, prm.CAMMAX)
        Fz = saturate(uFz, None, prm.FZMAX)
        s.Fz_low = be.of("force").fmax(Fz, prm.FZMIN)
        s.uFz_low = be.of("force").fmax(uFz, prm.FZMIN)
        p = saturate(p, prm.PRESMIN, prm.PRESMAX)
    else:
        s.low_speed = None
        s.reduction_smooth = None
        s.kappa_out = kappa
        Fz = uFz
        s.Fz_low = s.uFz_low = Fz

    s.Fz, s.kappa, s.alpha, s.gamma, s.phit, s.p = Fz, kappa, alpha, gamma, phit, p
    s.tan_alpha = be.tan(alpha)

    s.Fz0p = prm.LFZO * prm.FNOMIN  # Fz0' (4.E1)
    s.dfz = (Fz - s.Fz0p) / s.Fz0p  # (4.E2a)
    s.dpi = pressure_increment(prm, p)  # (4.E2b)
    s.dfz2, s.dpi2 = s.dfz**2, s.dpi**2  # (their squares, shared by the equations)

    if modes.alpha_star:
        s.alpha_star = s.tan_alpha * be.of("speed").sign(vx)  # (4.E3)
        s.gamma_star = be.sin(gamma)  # (4.E4)
    else:
        s.alpha_star, s.gamma_star = alpha, gamma
    s.gamma2 = gamma**2
    s.gamma_star2 = s.gamma2 if s.gamma_star is gamma else s.gamma_star**2

    # slip and contact-centre velocities, ISO-W signs: Vsy = tan(alpha) |Vx| (2.12, 4.E5)
    speed = be.of("speed").abs(vx)
    vsx = -kappa * speed
    vsy = s.tan_alpha * speed
    vs = be.sqrt0(vsx**2 + vsy**2)
    vc = be.sqrt0(vx**2 + vsy**2)
    vc_prime = vc + 1e-6  # (4.E6a), Vc >= 0 so sign(Vc) = +1
    s.cos_alpha_prime = vx / vc_prime  # cos(alpha') (4.E6)

    # friction decaying with slip speed (4.E7) and the digressive factor (4.E8) with A_mu = 1: the
    # reference evaluator found A_mu = 1 matches MF-Tyre; lambda'_mu = lambda*_mu then.
    friction_decay = 1.0 + prm.LMUV * vs / prm.LONGVL
    s.LMUX_star = prm.LMUX / friction_decay
    s.LMUY_star = prm.LMUY / friction_decay
    s.LMUX_prime, s.LMUY_prime = s.LMUX_star, s.LMUY_star
    return s


def _soft_saturate(x, lo, hi, be):
    """x inside [lo, hi] (``lo`` None: below ``hi``); beyond a bound by d: the bound + (1 - s) m tanh(d/m) + s d,
    with the slope 1 and no curvature at the bound (see Modes.limits)."""
    s = SMOOTH_LIMITS_SLOPE
    m = SMOOTH_LIMITS_MARGIN * (hi if lo is None else hi - lo)

    def beyond(d):
        return (1.0 - s) * m * be.tanh(d / m) + s * d

    above = x > hi
    used = be.where(above, hi + beyond(be.where(above, x - hi, 0.0)), x)
    if lo is None:
        return used
    below = x < lo
    return be.where(below, lo - beyond(be.where(below, lo - x, 0.0)), used)


def smooth_low_speed(s, value, be):
    """Scale a shift or moment term by the low-speed factor (identity above VXLOW or without limits)."""
    if s.reduction_smooth is None:
        return value
    return value * s.reduction_smooth
