"""Lateral force: pure slip Fy0 (4.E19-4.E30) and combined slip Fy = Gyk Fy0 + SVyk (4.E58-4.E67).

MF 6.1/6.2 use the camber stiffness Kyg0 (4.E30) in the horizontal shift (4.E27); MF 5.2 has the explicit
camber shift PHY3 instead (MF-Tyre 5.2 equation manual).
"""
from __future__ import annotations

from types import SimpleNamespace

from .normalisation import smooth_low_speed
from .turnslip import lateral_shift_turn_slip

__all__ = ["pure_lateral", "combined_lateral", "friction_y", "curvature_y", "cornering_pressure_factor",
           "cornering_peak_load", "combined_slope_y", "combined_curvature_y"]


def friction_y(prm, dfz, dpi, dpi2, gamma_star2):
    """muy before the friction scaling LMUY*: (PDY1 + PDY2 dfz)(1 + PPY3 dpi + PPY4 dpi^2)(1 - PDY3 gamma*^2)
    (4.E23)."""
    return (prm.PDY1 + prm.PDY2 * dfz) * (1.0 + prm.PPY3 * dpi + prm.PPY4 * dpi2) * (1.0 - prm.PDY3 * gamma_star2)


def curvature_y(prm, dfz, gamma_star, gamma_star2, sign):
    """Ey before LEY: (PEY1 + PEY2 dfz)(1 + PEY5 gamma*^2 - (PEY3 + PEY4 gamma*) sgn(alpha_y)) (4.E24)."""
    return (prm.PEY1 + prm.PEY2 * dfz) * (1.0 + prm.PEY5 * gamma_star2 - (prm.PEY3 + prm.PEY4 * gamma_star) * sign)


def cornering_pressure_factor(prm, dpi):
    """The pressure factor of Kya: 1 + PPY1 dpi (4.E25)."""
    return 1.0 + prm.PPY1 * dpi


def cornering_peak_load(prm, gamma_star2, dpi):
    """The load, over Fz0', at which Kya peaks: (PKY2 + PKY5 gamma*^2)(1 + PPY2 dpi) (4.E25)."""
    return (prm.PKY2 + prm.PKY5 * gamma_star2) * (1.0 + prm.PPY2 * dpi)


def combined_slope_y(prm, gamma_star2):
    """The load-free part of Byk: RBY1 + RBY4 gamma*^2 (4.E62)."""
    return prm.RBY1 + prm.RBY4 * gamma_star2


def combined_curvature_y(prm, dfz):
    """Eyk = REY1 + REY2 dfz (4.E64)."""
    return prm.REY1 + prm.REY2 * dfz


def _cornering_stiffness(prm, s, gamma_star, gamma_star2, zeta3, be):
    """Kya (4.E25) at inclination gamma_star (gamma_star2 = gamma_star^2)."""
    return (prm.PKY1 * s.Fz0p * cornering_pressure_factor(prm, s.dpi)
            * (1.0 - prm.PKY3 * be.of("angle").abs(gamma_star))
            * be.sin(prm.PKY4 * be.atan((s.Fz / s.Fz0p) / cornering_peak_load(prm, gamma_star2, s.dpi)))
            * zeta3 * prm.LKY)


def pure_lateral(prm, s, gamma_star, modes, be) -> SimpleNamespace:
    """Fy0 and its coefficients at inclination ``gamma_star`` (the evaluation also needs gamma = 0)."""
    dfz, dpi, Fz = s.dfz, s.dpi, s.Fz
    gamma_star2 = gamma_star**2
    mf52 = prm.version == "52"
    if modes.turn_slip:
        zeta2, zeta3 = s.zeta2, s.zeta3
    else:
        zeta2 = zeta3 = 1.0
    Kya = _cornering_stiffness(prm, s, gamma_star, gamma_star2, zeta3, be)
    SVyg = Fz * (prm.PVY3 + prm.PVY4 * dfz) * gamma_star * prm.LKYC * s.LMUY_prime * zeta2  # (4.E28)
    if mf52:
        kya0_52 = prm.PKY1 * s.Fz0p * be.sin(prm.PKY4 * be.atan(Fz / (prm.PKY2 * s.Fz0p))) * prm.LKYC
        Kyg0 = (prm.PHY3 * kya0_52 + Fz * (prm.PVY3 + prm.PVY4 * dfz)) * prm.LKYC
    else:
        Kyg0 = Fz * (prm.PKY6 + prm.PKY7 * dfz) * (1.0 + prm.PPY5 * dpi) * prm.LKYC  # (4.E30)

    if modes.turn_slip:
        kya0 = _cornering_stiffness(prm, s, 0.0, 0.0, zeta3, be)
        zeta4 = lateral_shift_turn_slip(prm, s, Kya, kya0, Kyg0, SVyg, modes.limits, be)
        zeta0 = 0.0
    else:
        zeta4, zeta0 = 1.0, 1.0

    if mf52:
        SHy = (prm.PHY1 + prm.PHY2 * dfz) * prm.LHY + prm.PHY3 * gamma_star * prm.LKYC
    else:
        SHy = ((prm.PHY1 + prm.PHY2 * dfz) * prm.LHY
               + (Kyg0 * gamma_star - SVyg) / (Kya + 1e-6 * be.sign_nz(Kya)) * zeta0 + zeta4 - 1.0)  # (4.E27)
    SVy = Fz * (prm.PVY1 + prm.PVY2 * dfz) * prm.LVY * s.LMUY_prime * zeta2 + SVyg  # (4.E29)
    SHy, SVy = smooth_low_speed(s, SHy, be), smooth_low_speed(s, SVy, be)

    alpha_y = s.alpha_star + SHy  # (4.E20)
    Cy = prm.PCY1 * prm.LCY  # (4.E21)
    muy = friction_y(prm, dfz, dpi, s.dpi2, gamma_star2) * s.LMUY_star  # (4.E23)
    Dy = muy * Fz * zeta2  # (4.E22)
    Ey = curvature_y(prm, dfz, gamma_star, gamma_star2, be.sign_nz(alpha_y)) * prm.LEY  # (4.E24)
    if modes.limits:
        Ey = be.fmin(Ey, 1.0)
    By = Kya / (Cy * Dy + 1e-6 * be.sign_nz(Dy))  # (4.E26)
    ba = By * alpha_y
    Fy0 = Dy * be.sin(Cy * be.atan(ba - Ey * (ba - be.atan(ba)))) + SVy  # (4.E19)
    if modes.alpha_star:
        Fy0 = be.where(s.vx < 0, -Fy0, Fy0)
    muy = be.where(Fz == 0, 0.0, muy)
    return SimpleNamespace(Fy0=Fy0, muy=muy, Kya=Kya, Kyg0=Kyg0, SHy=SHy, SVy=SVy, By=By, Cy=Cy)


def combined_lateral(prm, s, fy0, muy, modes, be):
    """(Fy, Gyk, SVyk): Fy = Gyk Fy0 + SVyk (4.E58)."""
    dfz = s.dfz
    zeta2 = s.zeta2 if modes.turn_slip else 1.0
    DVyk = (muy * s.Fz * (prm.RVY1 + prm.RVY2 * dfz + prm.RVY3 * s.gamma_star)
            * be.cos_atan(prm.RVY4 * s.alpha_star) * zeta2)  # (4.E67)
    SVyk = DVyk * be.sin(prm.RVY5 * be.atan(prm.RVY6 * s.kappa)) * prm.LVYKA  # (4.E66)
    SHyk = prm.RHY1 + prm.RHY2 * dfz  # (4.E65)
    Eyk = combined_curvature_y(prm, dfz)  # (4.E64)
    if modes.limits:
        Eyk = be.fmin(Eyk, 1.0)
    Cyk = prm.RCY1  # (4.E63)
    Byk = combined_slope_y(prm, s.gamma_star2) * be.cos_atan(prm.RBY2 * (s.alpha_star - prm.RBY3)) * prm.LYKA  # (4.E62)
    kappa_s = s.kappa + SHyk  # (4.E61)

    def weight(x):
        bx = Byk * x
        return be.cos(Cyk * be.atan(bx - Eyk * (bx - be.atan(bx))))

    Gyk = weight(kappa_s) / weight(SHyk)  # (4.E59), (4.E60)
    SVyk = smooth_low_speed(s, SVyk, be)
    return Gyk * fy0 + SVyk, Gyk, SVyk
