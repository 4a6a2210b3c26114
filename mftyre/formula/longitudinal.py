"""Longitudinal force: pure slip Fx0 (4.E9-4.E18) and combined slip Fx = Gxa Fx0 (4.E50-4.E57)."""
from __future__ import annotations

from types import SimpleNamespace

from .normalisation import smooth_low_speed

__all__ = ["pure_longitudinal", "combined_longitudinal", "friction_x", "slip_stiffness_x", "curvature_x",
           "combined_slope_x", "combined_curvature_x"]


def friction_x(prm, dfz, dpi, dpi2, gamma2):
    """mux before the friction scaling LMUX*: (PDX1 + PDX2 dfz)(1 + PPX3 dpi + PPX4 dpi^2)(1 - PDX3 gamma^2) (4.E13)."""
    return (prm.PDX1 + prm.PDX2 * dfz) * (1.0 + prm.PPX3 * dpi + prm.PPX4 * dpi2) * (1.0 - prm.PDX3 * gamma2)


def slip_stiffness_x(prm, fz, dfz, dpi, dpi2, be):
    """Kxk before LKX: Fz (PKX1 + PKX2 dfz) exp(PKX3 dfz) (1 + PPX1 dpi + PPX2 dpi^2) (4.E15)."""
    return fz * (prm.PKX1 + prm.PKX2 * dfz) * be.exp(prm.PKX3 * dfz) * (1.0 + prm.PPX1 * dpi + prm.PPX2 * dpi2)


def curvature_x(prm, dfz, dfz2, sign):
    """Ex before LEX: (PEX1 + PEX2 dfz + PEX3 dfz^2)(1 - PEX4 sgn(kappa_x)) (4.E14)."""
    return (prm.PEX1 + prm.PEX2 * dfz + prm.PEX3 * dfz2) * (1.0 - prm.PEX4 * sign)


def combined_slope_x(prm, gamma_star2):
    """The load-free part of Bxa: RBX1 + RBX3 gamma*^2 (4.E54)."""
    return prm.RBX1 + prm.RBX3 * gamma_star2


def combined_curvature_x(prm, dfz):
    """Exa = REX1 + REX2 dfz (4.E56)."""
    return prm.REX1 + prm.REX2 * dfz


def pure_longitudinal(prm, s, modes, be) -> SimpleNamespace:
    """Fx0, the friction coefficient mux and the slip stiffness Kxk."""
    dfz, dfz2, dpi, dpi2, Fz = s.dfz, s.dfz2, s.dpi, s.dpi2, s.Fz  # dfz2 = dfz^2, dpi2 = dpi^2
    zeta1 = s.zeta1 if modes.turn_slip else 1.0
    Cx = prm.PCX1 * prm.LCX  # (4.E11)
    mux = friction_x(prm, dfz, dpi, dpi2, s.gamma2) * s.LMUX_star  # (4.E13)
    mux = be.where(Fz == 0, 0.0, mux)
    Dx = mux * Fz * zeta1  # (4.E12)
    Kxk = slip_stiffness_x(prm, Fz, dfz, dpi, dpi2, be) * prm.LKX  # (4.E15)
    Bx = Kxk / (Cx * Dx + 1e-6 * be.sign_nz(Dx))  # (4.E16)
    SHx = smooth_low_speed(s, (prm.PHX1 + prm.PHX2 * dfz) * prm.LHX, be)  # (4.E17)
    SVx = smooth_low_speed(s, Fz * (prm.PVX1 + prm.PVX2 * dfz) * prm.LVX * s.LMUX_prime * zeta1, be)  # (4.E18)
    kappa_x = s.kappa + SHx  # (4.E10)
    Ex = curvature_x(prm, dfz, dfz2, be.of("slip").sign(kappa_x)) * prm.LEX  # (4.E14)
    if modes.limits:
        Ex = be.fmin(Ex, 1.0)
    bk = Bx * kappa_x
    Fx0 = Dx * be.sin(Cx * be.atan(bk - Ex * (bk - be.atan(bk)))) + SVx  # (4.E9)
    Fx0 = be.where(s.vx < 0, -Fx0, Fx0)  # rolling backwards
    return SimpleNamespace(Fx0=Fx0, mux=mux, Kxk=Kxk)


def combined_longitudinal(prm, s, fx0, modes, be):
    """Fx = Gxa Fx0 with the weighting function of alpha (4.E50-4.E57)."""
    Cxa = prm.RCX1  # (4.E55)
    Exa = combined_curvature_x(prm, s.dfz)  # (4.E56)
    if modes.limits:
        Exa = be.fmin(Exa, 1.0)
    SHxa = prm.RHX1  # (4.E57)
    Bxa = combined_slope_x(prm, s.gamma_star2) * be.cos_atan(prm.RBX2 * s.kappa) * prm.LXAL  # (4.E54)
    alpha_s = s.alpha_star + SHxa  # (4.E53)

    def weight(x):
        bx = Bxa * x
        return be.cos(Cxa * be.atan(bx - Exa * (bx - be.atan(bx))))

    Gxa = weight(alpha_s) / weight(SHxa)  # (4.E51), (4.E52)
    return Gxa * fx0  # (4.E50)
