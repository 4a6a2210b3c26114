"""Carcass stiffnesses and relaxation lengths.

MF 6.1/6.2 (paper (17)-(19)):
    Cx = LONGITUDINAL_STIFFNESS (1 + PCFX1 dfz + PCFX2 dfz^2)(1 + PCFX3 dpi)
    Cy = LATERAL_STIFFNESS (1 + PCFY1 dfz + PCFY2 dfz^2)(1 + PCFY3 dpi)
    sigma_x = |Kxk / Cx|,  sigma_y = |Kya / Cy|
MF 5.2 (MF-Tyre 5.2 equation manual):
    sigma_x = (PTX1 + PTX2 dfz) exp(-PTX3 dfz) LSGKP R0 Fz/Fz0
    sigma_y = PTY1 sin(2 atan(Fz/(PTY2 Fz0'))) (1 - PKY3 |gamma|) R0 LFZO LSGAL
"""
from __future__ import annotations

__all__ = ["carcass_stiffness_and_relaxation"]


def carcass_stiffness_and_relaxation(prm, s, kxk, kya, be):
    """(Cx, Cy, sigma_x, sigma_y) at the limited load and pressure."""
    dfz, dpi = s.dfz, s.dpi
    cx = prm.LONGITUDINAL_STIFFNESS * (1.0 + prm.PCFX1 * dfz + prm.PCFX2 * s.dfz2) * (1.0 + prm.PCFX3 * dpi)
    cy = prm.LATERAL_STIFFNESS * (1.0 + prm.PCFY1 * dfz + prm.PCFY2 * s.dfz2) * (1.0 + prm.PCFY3 * dpi)
    if prm.version == "52":
        R0 = prm.UNLOADED_RADIUS
        sigma_x = (prm.PTX1 + prm.PTX2 * dfz) * be.exp(-prm.PTX3 * dfz) * prm.LSGKP * R0 * s.Fz / prm.FNOMIN
        sigma_y = (prm.PTY1 * be.sin(2.0 * be.atan(s.Fz / (prm.PTY2 * s.Fz0p))) * (1.0 - prm.PKY3 * be.of("angle").abs(s.gamma))
                   * R0 * prm.LFZO * prm.LSGAL)
    else:
        sigma_x = be.abs(kxk / cx)
        sigma_y = be.abs(kya / cy)
    return cx, cy, sigma_x, sigma_y
