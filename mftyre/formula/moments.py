"""Overturning moment Mx and rolling-resistance moment My.

Mx: the MF-Tyre 6.1 form (Pacejka 2012 4.E69 extended with QSX12-QSX14 and the pressure term PPMX1):
    Mx = R0 Fz LMX (QSX1 LVMX - QSX2 gamma (1 + PPMX1 dpi) + QSX3 Fy/Fz0
                    + QSX4 cos(QSX5 atan((QSX6 Fz/Fz0)^2)) sin(QSX7 gamma + QSX8 atan(QSX9 Fy/Fz0))
                    + QSX10 atan(QSX11 Fz/Fz0) gamma)
         + R0 LMX (Fy (QSX13 + QSX14 |gamma|) - Fz QSX12 gamma |gamma|)
The draft of Besselink et al. (eq. 49), which MF-Tyre uses when both QSX1-QSX11 and QSX12-QSX14 are non-zero, puts
QSX12 gamma|gamma| inside the Fz bracket and QSX13/QSX14 on Fy: the same expression, so one form serves both.

My: paper A48 (the rolling resistance is negative for forward rolling in ISO-W):
    My = -R0 Fz0 LMY (QSY1 + QSY2 Fx/Fz0 + QSY3 |Vx/V0| + QSY4 (Vx/V0)^4 + (QSY5 + QSY6 Fz/Fz0) gamma^2)
         (Fz/Fz0)^QSY7 (p/p0)^QSY8;    MF 5.2: -R0 Fz LMY (QSY1 + QSY2 Fx/Fz0 + QSY3 |Vx/V0| + QSY4 (Vx/V0)^4).
It reverses with the direction of travel, vanishes at standstill and, as MF-Tyre does, fades with a sine ramp
as the wheel approaches lock (kappa -> -1): for kappa in [-1 - VXLOW - h, h], h = VXLOW/|Vx| - 1, My is
multiplied by sin(pi/2 (kappa + 1)/(h + 1)), and reversed below that range.

Below FZMIN both moments scale the load down: Mx with Fz (Fz/FZMIN)^2, My with Fz (Fz/FZMIN).
"""
from __future__ import annotations

__all__ = ["overturning_moment", "rolling_resistance_moment"]


def overturning_moment(prm, s, fy, be):
    """Mx from the (limited) load, inclination and the combined lateral force."""
    Fz = s.Fz
    if prm.FZMIN > 0:
        Fz = be.where(Fz < prm.FZMIN, Fz * (Fz / prm.FZMIN) ** 2, Fz)
    R0, Fz0, g = prm.UNLOADED_RADIUS, prm.FNOMIN, s.gamma
    core = (prm.QSX1 * prm.LVMX - prm.QSX2 * g * (1.0 + prm.PPMX1 * s.dpi) + prm.QSX3 * fy / Fz0
            + prm.QSX4 * be.cos(prm.QSX5 * be.atan((prm.QSX6 * Fz / Fz0) ** 2))
            * be.sin(prm.QSX7 * g + prm.QSX8 * be.atan(prm.QSX9 * fy / Fz0))
            + prm.QSX10 * be.atan(prm.QSX11 * Fz / Fz0) * g)
    mx = R0 * Fz * prm.LMX * core
    if any(prm[f"QSX{i}"] != 0 for i in (12, 13, 14)):  # (zero in most files: no term in the graph)
        abs_g = be.of("angle").abs(g)
        mx = mx + R0 * prm.LMX * (fy * (prm.QSX13 + prm.QSX14 * abs_g) - Fz * prm.QSX12 * g * abs_g)
    return mx


def rolling_resistance_moment(prm, s, fx, be):
    """My from the load as given (not saturated at FZMAX: the rolling resistance keeps growing with the load, as in
    the reference evaluator), the speed, Fx, inclination and pressure."""
    Fz = s.uFz
    if prm.FZMIN > 0:
        Fz = be.where(Fz < prm.FZMIN, Fz * (Fz / prm.FZMIN), Fz)
    R0, Fz0, V0, vx = prm.UNLOADED_RADIUS, prm.FNOMIN, prm.LONGVL, s.vx
    speed_terms = prm.QSY1 + prm.QSY2 * fx / Fz0 + prm.QSY3 * be.of("speed").abs(vx) / V0 + prm.QSY4 * (vx / V0) ** 4
    if prm.version == "52":
        my = -R0 * Fz * prm.LMY * speed_terms
    else:
        my = (-R0 * Fz0 * prm.LMY * (speed_terms + (prm.QSY5 + prm.QSY6 * Fz / Fz0) * s.gamma2)
              * ((be.fmax(Fz, 1e-300) / Fz0) ** prm.QSY7 * (s.p / prm.NOMPRES) ** prm.QSY8))  # paper A48
        # (the floor keeps the derivative of Fz^QSY7 finite at zero load: 0 times a finite slope)
    my = be.where(vx < 0, -my, my)
    # fade towards wheel lock (MF-Tyre low-speed behaviour)
    kappa = s.ukappa
    high = prm.VXLOW / be.abs(vx) - 1.0
    low = -1.0 - prm.VXLOW - high
    ramp = be.logical_and(kappa >= low, kappa <= high)
    if be.any(ramp):  # (NumPy skips this when no wheel is near lock)
        my = be.where(ramp, my * be.sin(0.5 * be.pi * (kappa + 1.0) / (high + 1.0)), my)
    reversed_ = kappa < low
    if be.any(reversed_):
        my = be.where(reversed_, -my, my)
    return be.where(vx == 0, 0.0, my)
