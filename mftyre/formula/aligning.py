"""Aligning torque: pneumatic trail t, residual torque Mzr and Mz = -t Fy' + Mzr + s Fx (4.E31-4.E78).

Where the MF 6.1 book equations and the MF-Tyre implementation differ, the forms of Besselink, Schmeitz &
Pacejka (2010) are used, as in the reference evaluator (they reproduce MF-Tyre):

* Dt (paper A60) with gamma (not |gamma*|) and the pressure factor (1 - PPZ1 dpi), no sign(Vx);
* Bt (paper A58) with QBZ4 gamma + QBZ5 |gamma| (the book's QBZ6 does not exist in .tir files);
* alpha_r,eq, alpha_t,eq (paper A54, A55) with tan/atan, and s (paper A56) normalised by Fz0, not Fz0';
* the trail is multiplied by LFZO (as MF-Tyre does);
* Fy' = Gyk(gamma) Fy0(gamma = 0) (4.E74); MF 5.2 uses -t (Fy - SVyk) instead.
With limits on, the load in t and Mzr is at least FZMIN.
"""
from __future__ import annotations

from types import SimpleNamespace

from .normalisation import smooth_low_speed

__all__ = ["aligning_coefficients", "aligning_torque", "peak_trail", "trail_slope", "trail_curvature"]


def peak_trail(prm, dfz, dpi, gamma, gamma2):
    """Dt over Fz R0/Fz0' LTR: (QDZ1 + QDZ2 dfz)(1 - PPZ1 dpi)(1 + QDZ3 gamma + QDZ4 gamma^2) (paper A60)."""
    return (prm.QDZ1 + prm.QDZ2 * dfz) * (1.0 - prm.PPZ1 * dpi) * (1.0 + prm.QDZ3 * gamma + prm.QDZ4 * gamma2)


def trail_slope(prm, dfz, dfz2, gamma, abs_gamma):
    """Bt over LKY/LMUY*: (QBZ1 + QBZ2 dfz + QBZ3 dfz^2)(1 + QBZ4 gamma + QBZ5 |gamma|) (paper A58)."""
    return (prm.QBZ1 + prm.QBZ2 * dfz + prm.QBZ3 * dfz2) * (1.0 + prm.QBZ4 * gamma + prm.QBZ5 * abs_gamma)


def trail_curvature(prm, dfz, dfz2, gamma_star, bend, be):
    """Et = (QEZ1 + QEZ2 dfz + QEZ3 dfz^2)(1 + (QEZ4 + QEZ5 gamma*) (2/pi) bend), bend = atan(Bt Ct alpha_t)
    (4.E44)."""
    return ((prm.QEZ1 + prm.QEZ2 * dfz + prm.QEZ3 * dfz2)
            * (1.0 + (prm.QEZ4 + prm.QEZ5 * gamma_star) * (2.0 / be.pi) * bend))


def _load_for_moments(s, modes, be):
    if modes.limits:
        return be.where(s.Fz <= 0, 0.0, s.Fz_low)
    return s.Fz


def aligning_coefficients(prm, s, lat, gyk, modes, be) -> SimpleNamespace:
    """Trail and residual-torque coefficients (4.E33-4.E47), turn-slip factors zeta5-zeta8 included."""
    dfz, dpi, gs = s.dfz, s.dpi, s.gamma_star
    R0 = prm.UNLOADED_RADIUS
    Fz = _load_for_moments(s, modes, be)
    c = SimpleNamespace()
    SHt = prm.QHZ1 + prm.QHZ2 * dfz + (prm.QHZ3 + prm.QHZ4 * dfz) * gs  # (4.E35)
    c.Kya_prime = lat.Kya + 1e-6 * be.sign_nz(lat.Kya)  # (4.E39)
    SHf = lat.SHy + lat.SVy / c.Kya_prime  # (4.E38)
    c.alpha_r = s.alpha_star + SHf  # (4.E37)
    c.alpha_t = s.alpha_star + SHt  # (4.E34)
    zeta5 = s.zeta5 if modes.turn_slip else 1.0
    c.Dt = peak_trail(prm, dfz, dpi, s.gamma, s.gamma2) * Fz * (R0 / s.Fz0p) * prm.LTR * zeta5  # paper A60
    c.Bt = trail_slope(prm, dfz, s.dfz2, s.gamma, be.of("angle").abs(s.gamma)) * prm.LKY / s.LMUY_star  # paper A58
    c.Ct = prm.QCZ1  # (4.E41)
    c.Et = trail_curvature(prm, dfz, s.dfz2, gs, be.atan(c.Bt * c.Ct * c.alpha_t), be)  # (4.E44)
    if modes.limits:
        c.Et = be.fmin(c.Et, 1.0)

    if modes.turn_slip:
        zeta0, zeta2, zeta6 = 0.0, s.zeta2, s.zeta6
        published = modes.turn_slip_form == "published"
        mz_inf = prm.QCRP1 * be.abs(lat.muy) * R0 * Fz * be.sqrt0(Fz / s.Fz0p) * prm.LMP  # (4.95)
        mz_inf = be.where(mz_inf <= 0, 1e-6, mz_inf)  # kept positive (also at zero load)
        c_drp = prm.QDRP1  # (4.96)
        d_drp = mz_inf / be.sin(0.5 * be.pi * c_drp)  # (4.94)
        if published:  # (4.99)
            k_zgr0 = Fz * R0 * (prm.QDZ8 + prm.QDZ9 * dfz + (prm.QDZ10 + prm.QDZ11 * dfz) * be.of("angle").abs(s.gamma)) * prm.LKZC
        else:  # the reference evaluator's form
            k_zgr0 = Fz * R0 * (prm.QDZ8 * prm.QDZ9 * dfz + prm.QDZ10 + prm.QDZ11 * dfz * be.of("angle").abs(s.gamma)) * prm.LKZC
        b_drp = k_zgr0 / (c_drp * d_drp * (1.0 - s.eps_gamma))  # (4.98)
        spin = s.phi if published else s.phit
        d_rp = d_drp * be.sin(c_drp * be.atan(b_drp * R0 * spin))  # (4.93)
        mz90 = mz_inf * (2.0 / be.pi) * be.atan(prm.QCRP2 * R0 * be.abs(s.phit)) * gyk  # (4.103)
        # (4.104): Cr = zeta7 = (2/pi) acos(Mz90 / |D_rphi|), real for ratios in [-1, 1]; without turn slip
        # (Mz90 = 0) the ratio is 0 and Cr = 1 as in the model without turn slip. Beyond [-1, 1] (|D_rphi| small:
        # a file with QDZ8 QDZ9 dfz + QDZ10 ~ 0 in the mfeval K_zgamma,r0, or small turn slip):
        # published: Cr = (2/pi) acos of the ratio held in [-1, 1] (0 or 2), a real shape factor as (4.46) needs;
        # mfeval: MATLAB's complex acos, Cr = a + i b with b = (2/pi) acosh|ratio|, of which MFeval reports the
        # real part of Mzr: Dr cos(a x) cosh(b x), x = atan(Br alpha_r) (unbounded in alpha_r)
        held = be.abs(d_rp)
        finite = held * 1e12 > be.abs(mz90)  # else the ratio is held at +-1e12 (D_rphi = 0 at zero load)
        ratio = be.where(mz90 == 0, 0.0, be.where(finite, mz90 / be.where(finite, held, 1.0),
                                                  be.where(mz90 > 0, 1e12, -1e12)))
        # (acos and acosh only inside their open domains: their infinite slopes at +-1 times the held ratio's zero
        # slope would make NaN derivatives)
        inside = be.abs(ratio) < 1.0
        zeta7 = be.where(inside, (2.0 / be.pi) * be.acos(be.where(inside, ratio, 0.0)), be.where(ratio > 0, 0.0, 2.0))
        # (where D_rphi = 0 MFeval divides by zero; the ratio is held at 1e12 to keep Mzr finite)
        if not published:
            beyond = be.abs(ratio) > 1.0
            zeta7_imag = (2.0 / be.pi) * be.where(beyond, be.acosh(be.where(beyond, be.fmin(be.abs(ratio), 1e12), 2.0)),
                                                   0.0)
        else:
            zeta7_imag = None
        zeta8 = 1.0 + d_rp  # (4.97)
    else:
        zeta0 = zeta2 = zeta6 = zeta7 = zeta8 = 1.0
        zeta7_imag = None

    c.Dr = (Fz * R0 * ((prm.QDZ6 + prm.QDZ7 * dfz) * prm.LRES * zeta2
                       + ((prm.QDZ8 + prm.QDZ9 * dfz) * (1.0 + prm.PPZ2 * dpi)
                          + (prm.QDZ10 + prm.QDZ11 * dfz) * be.of("angle").abs(gs)) * gs * prm.LKZC * zeta0)
            * s.LMUY_star * be.of("speed").sign(s.vx) * be.cos(s.alpha_star) + zeta8 - 1.0)  # (4.E47)
    c.Br = (prm.QBZ9 * prm.LKY / s.LMUY_star + prm.QBZ10 * lat.By * lat.Cy) * zeta6  # (4.E45)
    c.Cr = zeta7  # (4.E46)
    c.Cr_imag = zeta7_imag  # mfeval form only (None: Cr is real)
    return c


def aligning_torque(prm, s, c, kxk, fx, fy, svyk, fy0_gamma0, gyk, modes, be):
    """(Mz, t, Mzr) under combined slip (4.E71-4.E78, paper A54-A56)."""
    R0 = prm.UNLOADED_RADIUS
    k_ratio2 = (kxk / c.Kya_prime) ** 2 * s.kappa**2
    alpha_r_eq = be.atan(be.sqrt0(be.tan(c.alpha_r) ** 2 + k_ratio2)) * be.of("angle").sign(c.alpha_r)  # paper A54
    alpha_t_eq = be.atan(be.sqrt0(be.tan(c.alpha_t) ** 2 + k_ratio2)) * be.of("angle").sign(c.alpha_t)  # paper A55
    arm = R0 * (prm.SSZ1 + prm.SSZ2 * (fy / prm.FNOMIN) + (prm.SSZ3 + prm.SSZ4 * s.dfz) * s.gamma) * prm.LS  # paper A56
    shape_arg = be.atan(c.Br * alpha_r_eq)
    mzr = c.Dr * be.cos(c.Cr * shape_arg)  # (4.E75)
    if c.Cr_imag is not None:  # mfeval form: the real part of cos((Cr + i Cr_imag) x)
        mzr = mzr * be.cosh(c.Cr_imag * shape_arg)
    bt = c.Bt * alpha_t_eq
    t = c.Dt * be.cos(c.Ct * be.atan(bt - c.Et * (bt - be.atan(bt)))) * s.cos_alpha_prime  # (4.E73)
    t = t * prm.LFZO
    t, mzr = smooth_low_speed(s, t, be), smooth_low_speed(s, mzr, be)
    if prm.version == "52":
        mz = -t * (fy - svyk) + mzr + arm * fx
    else:
        fy_prime = gyk * fy0_gamma0  # (4.E74)
        mz = -t * fy_prime + mzr + arm * fx  # (4.E71), (4.E72)
    return mz, t, mzr
