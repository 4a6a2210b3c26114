"""A flexible tyre on soft soil: the classical semi-empirical model (Bekker, Janosi-Hanamoto, Wong).

Backend-neutral (NumPy or CasADi through ``be``), pure functions of the tyre parameters ``prm`` (a
:class:`mftyre.params.TyreParameters`), a :class:`~mftyre.soil.soils.Soil` and the operating point. SI units;
x forward, z up. Slip i = 1 - V / (omega Re) with Re the tyre's effective rolling radius on hard ground at this
load and pressure (the .tir's Re; the usual convention of tractive-performance tests, slip measured against the
self-propelled wheel on a hard surface): 0 free rolling on hard ground, > 0 driving, < 0 braked; it equals
kappa / (1 + kappa) of the Magic Formula. Slip angle alpha as in ISO-W (Fy < 0 for alpha > 0).

References
  [B]  M.G. Bekker, Off-the-Road Locomotion (1960) and Introduction to Terrain-Vehicle Systems (1969).
  [W]  J.Y. Wong, Theory of Ground Vehicles, 3rd ed. (2001), ch. 2: pressure-sinkage, shear, the rigid wheel and
       the flexible tyre with the critical-pressure switch, thrust from the Janosi-Hanamoto shear along the
       contact (equation numbers differ between editions, so none are quoted).
  [JH] Z. Janosi, B. Hanamoto (1961), the exponential shear stress-displacement relation.

The model, one line per equation:
  pressure-sinkage                 p = k z^n,  k = k_c / b + k_phi                                    [B]
  rigid-wheel sinkage              z_r = [3 W / ((3 - n) b k sqrt(D))]^(2 / (2n + 1))                [B]
  critical ground pressure         p_cr = k z_r^n  (the pressure under the bottom of the rigid wheel)   [W]
  tyre on hard ground              rho_h, a_h, b_h, Re from the .tir's Fz(rho, p), contact patch and rolling
                                   radius (MF 6.1/6.2); mean pressure p_g = W / (4 a_h b_h) = p_i + p_c
                                   (this defines the carcass stiffness pressure p_c)
  switch                           p_g >= p_cr: rigid wheel (deflection 0, width b = WIDTH, no flat part);  [W]
                                   p_g <  p_cr: flexible: the flat footprint 2 a_h x 2 b_h of the hard-ground
                                   tyre presses the soil with p_g, sinkage z_f = (p_g / k(2 b_h))^(1/n)
  compaction resistance            R_c = b k z^(n+1) / (n + 1)  (work of pressing a rut of depth z)    [B]
  contact                          the tyre circle (free radius r, centre r - delta above the footprint)
                                   enters the soil at cos(theta_e) = (r - delta - z) / r; the front arc down to
                                   cos(theta_f) = (r - delta) / r is followed by the flat part of length 2 a;
                                   contact length L = r (sin theta_e - sin theta_f) + 2 a
  normal stress                    arc: sigma = k (r (cos theta - cos theta_e))^n; flat: sigma = k z^n
  tread speed                      omega r_t, r_t = r (rigid) or Re (flexible: the belt moves as on hard
                                   ground); tread slip i_t = 1 - V / (omega r_t) = 1 - (1 - i) Re / r_t
  shear displacement               j_x = i_t x, j_y = (1 - i_t) tan(alpha) x, x from the front of the contact
  shear stress (M-C, JH)           tau = (c + sigma tan phi)(1 - exp(-j / K)), j = |(j_x, j_y)|, along (j_x, j_y)
  gross traction, lateral force    H = b int_0^L tau_x dx,   F_y = -b int_0^L tau_y dx                   [W]
  drawbar pull, torque             DP = H - R_c,   T = H r_t
  spin, power, efficiency          omega = V / ((1 - i) Re),  P = T omega,  eta = DP V / P = (DP / H)(1 - i_t)

With uniform normal stress the thrust is Wong's closed form H = (c A + W tan phi)[1 - K/(i L)(1 - exp(-i L/K))].
A towed wheel (T = 0) has i_t = 0: it turns at V / r_t. In the rigid mode that is V / r, slower than V / Re on
hard ground (slip 1 - r / Re < 0); in the flexible mode it turns as on hard ground.

Simplifications (each a documented choice, not a hidden one): the load is carried by the flat part in the
flexible mode (Wong) and by the rigid-wheel formula in the rigid mode (the arc's vertical reaction in the flexible
mode is not added); shear acts along the horizontal projection of the contact; the soil does not rebound behind
the bottom; no bulldozing and no sidewall (lateral soil wedge) reaction: the lateral force is shear only; speed
enters through omega and the power only (the soil is rate-independent); the switch between the modes is a case
distinction (a step in contact length and traction; sinkage and ground pressure change only through the different
widths b). The integrals are Gauss-Legendre sums (8 nodes on the arc, 16 on the flat part).
"""
from __future__ import annotations

import numpy as np

from ..formula import vertical

__all__ = ["rigid_wheel_sinkage", "critical_pressure", "compaction_resistance", "hard_ground_footprint",
           "soft_soil", "OUTPUTS"]

_ARC_NODES, _ARC_WEIGHTS = np.polynomial.legendre.leggauss(8)
_FLAT_NODES, _FLAT_WEIGHTS = np.polynomial.legendre.leggauss(16)

#: name -> (SI unit, meaning) of every output of :func:`soft_soil`
OUTPUTS = {
    "sinkage": ("m", "depth of the rut below the soil surface"),
    "contact_length": ("m", "projected length of the soil contact (front arc + flat part)"),
    "contact_width": ("m", "width b of the soil contact"),
    "ground_pressure": ("Pa", "normal stress under the bottom of the tyre, k z^n"),
    "critical_pressure": ("Pa", "critical ground pressure p_cr (rigid-wheel pressure at this load)"),
    "carcass_pressure": ("Pa", "carcass stiffness pressure p_c = p_g - p_i on hard ground"),
    "flexible": ("-", "1 where the tyre flattens (p_i + p_c < p_cr), 0 where it acts as a rigid wheel"),
    "deflection": ("m", "tyre deflection on the soil (0 in the rigid mode)"),
    "rolling_radius": ("m", "radius r_t of the tread speed omega r_t: free radius (rigid), hard-ground Re (flexible)"),
    "motion_resistance": ("N", "compaction resistance R_c"),
    "gross_traction": ("N", "gross traction (thrust) H"),
    "drawbar_pull": ("N", "drawbar pull DP = H - R_c (net longitudinal force)"),
    "torque": ("N m", "driving torque on the wheel, H r_t"),
    "fy": ("N", "lateral force (ISO-W, shear only)"),
    "omega": ("rad/s", "wheel spin V / ((1 - i) Re)"),
    "power": ("W", "wheel input power T omega"),
    "efficiency": ("-", "tractive efficiency DP V / (T omega) = (DP / H)(1 - i_t); NaN where H <= 0"),
    "slip": ("-", "slip i = 1 - V / (omega Re), Re the hard-ground rolling radius (input)"),
}


def rigid_wheel_sinkage(soil, fz, diameter, width, be):
    """z_r = [3 W / ((3 - n) b (k_c/b + k_phi) sqrt(D))]^(2/(2n+1)), Bekker (1960); Wong (2.43)."""
    n = soil.n
    return (3.0 * fz / ((3.0 - n) * width * soil.modulus(width) * be.sqrt(diameter))) ** (2.0 / (2.0 * n + 1.0))


def critical_pressure(soil, fz, diameter, width, be):
    """p_cr = (k_c/b + k_phi) z_r^n: the ground pressure under a rigid wheel of the same size and load."""
    return soil.modulus(width) * rigid_wheel_sinkage(soil, fz, diameter, width, be) ** soil.n


def compaction_resistance(soil, sinkage, width, be):
    """R_c = b (k_c/b + k_phi) z^(n+1) / (n+1), Bekker."""
    return width * soil.modulus(width) * sinkage ** (soil.n + 1.0) / (soil.n + 1.0)


def hard_ground_footprint(prm, fz, p, be):
    """(rho, a, b) of the tyre on a flat rigid surface at load ``fz`` and pressure ``p`` (no slip, no spin):
    the .tir's Fz(rho, p) inverted and its contact patch (half length a, half width b)."""
    dpi = (p - prm.NOMPRES) / prm.NOMPRES
    zero = 0.0 * fz
    r_omega = vertical.free_radius(prm, zero, be)
    if prm.version == "62":
        _, rho = vertical.loaded_radius_62(prm, fz, r_omega, zero, zero, zero, zero, dpi, be)
    else:
        rho = vertical.deflection_61(prm, fz, r_omega, zero, zero, zero, dpi, be)
    a, b = vertical.contact_patch(prm, fz, dpi, be)
    return rho, a, b


def soft_soil(prm, soil, fz, slip, alpha, p, vx, be):
    """Every output of :data:`OUTPUTS` at the operating points (see the module notes for the equations)."""
    n = soil.n
    tan_phi = float(np.tan(soil.phi))
    dpi = (p - prm.NOMPRES) / prm.NOMPRES
    r = vertical.free_radius(prm, 0.0 * fz, be)                          # free radius at rest
    r_e = r - vertical.rolling_radius_reduction(prm, fz, dpi, be)        # hard-ground rolling radius
    rho_h, a_h, b_h = hard_ground_footprint(prm, fz, p, be)
    p_g = fz / (4.0 * a_h * b_h)                                          # p_i + p_c
    z_r = rigid_wheel_sinkage(soil, fz, 2.0 * r, prm.WIDTH, be)
    p_cr = soil.modulus(prm.WIDTH) * z_r ** n
    flexible = p_g < p_cr
    width = be.where(flexible, 2.0 * b_h, prm.WIDTH + 0.0 * fz)
    k = soil.modulus(width)
    z = be.where(flexible, (p_g / k) ** (1.0 / n), z_r)
    delta = be.where(flexible, rho_h, 0.0 * fz)
    a = be.where(flexible, a_h, 0.0 * fz)
    r_t = be.where(flexible, r_e, r)                                      # tread speed = omega r_t
    cos_f = (r - delta) / r
    cos_e = cos_f - z / r
    sin_f, sin_e = be.sqrt(1.0 - cos_f * cos_f), be.sqrt(be.fmax(1.0 - cos_e * cos_e, 0.0))
    arc = r * (sin_e - sin_f)                                             # horizontal extent of the front arc
    tread_slip = 1.0 - (1.0 - slip) * r_e / r_t                           # 1 - V / (omega r_t)
    lateral_rate = (1.0 - tread_slip) * be.tan(alpha)

    def shear(x, sigma):
        """(tau_x, tau_y) at x from the front: Janosi-Hanamoto along the resultant displacement, Mohr-Coulomb."""
        jx, jy = tread_slip * x, lateral_rate * x
        j = be.sqrt(jx * jx + jy * jy + (1e-9 * soil.K) ** 2)
        per_unit = (soil.c + sigma * tan_phi) * (1.0 - be.exp(-j / soil.K)) / j
        return per_unit * jx, per_unit * jy

    traction = lateral = 0.0 * fz
    for node, weight in zip(_ARC_NODES, _ARC_WEIGHTS):                  # front arc, x = 0 .. arc
        x = 0.5 * arc * (node + 1.0)
        sin_theta = sin_e - x / r
        sigma = k * be.fmax(r * (be.sqrt(1.0 - sin_theta * sin_theta) - cos_e), 0.0) ** n
        tau_x, tau_y = shear(x, sigma)
        traction, lateral = traction + tau_x * weight * 0.5 * arc, lateral + tau_y * weight * 0.5 * arc
    sigma_flat = k * z ** n
    for node, weight in zip(_FLAT_NODES, _FLAT_WEIGHTS):                # flat part, x = arc .. arc + 2a
        tau_x, tau_y = shear(arc + a * (node + 1.0), sigma_flat)
        traction, lateral = traction + tau_x * weight * a, lateral + tau_y * weight * a
    traction, fy = width * traction, -width * lateral
    resistance = compaction_resistance(soil, z, width, be)
    drawbar = traction - resistance
    omega = vx / ((1.0 - slip) * r_e)
    torque = traction * r_t
    return {
        "sinkage": z,
        "contact_length": arc + 2.0 * a,
        "contact_width": width,
        "ground_pressure": sigma_flat,
        "critical_pressure": p_cr,
        "carcass_pressure": p_g - p,
        "flexible": be.where(flexible, 1.0, 0.0),
        "deflection": delta,
        "rolling_radius": r_t,
        "motion_resistance": resistance,
        "gross_traction": traction,
        "drawbar_pull": drawbar,
        "torque": torque,
        "fy": fy,
        "omega": omega,
        "power": torque * omega,
        "efficiency": be.where(traction > 0, drawbar * (1.0 - tread_slip) / be.where(traction > 0, traction, 1.0),
                               np.nan),
        "slip": slip + 0.0 * fz,
    }
