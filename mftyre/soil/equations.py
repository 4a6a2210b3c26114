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
  [L]  M. Lyasko, "Slip sinkage effect in soil-vehicle mechanics", J. Terramechanics 47 (2010) 21-31: total
       sinkage z = z_0 (1 + i) / (1 - 0.5 i) for a driven wheel (the form as recalled here; the paper was not
       re-read in this session).
  [T]  bearing capacity factors: N_q = exp(pi tan phi) tan^2(pi/4 + phi/2) (Prandtl-Reissner),
       N_c = (N_q - 1) cot phi (N_c = pi + 2 at phi = 0), N_gamma = (N_q - 1) tan(1.4 phi) (Meyerhof's closed
       form of Terzaghi's tabulated factor).

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
  smooth switch                    Wong's switch is a case distinction and a step: at p_g = p_cr the rigid
                                   wheel has no flat part and width WIDTH, the flexible tyre a flat part 2 a_h
                                   and deflection rho_h (its sinkage differs only through k(b)). Over the band
                                   |p_g / p_cr - 1| < SWITCH_BAND the geometry is blended with the flexible
                                   fraction w = s(t), t = (1 + SWITCH_BAND - p_g / p_cr) / (2 SWITCH_BAND)
                                   clipped to [0, 1], s(t) = t^2 (3 - 2 t) (C1): b = WIDTH + w (2 b_h - WIDTH),
                                   z_0 = z_r + w (z_f - z_r), delta = w^2 rho_h, a = w a_h, r_f = r - w (r - Re)
                                   (delta goes with w^2 so that the front of the flat part, r sin theta_f =
                                   sqrt(delta (2 r - delta)), moves with finite slope; linear in w it would grow
                                   like sqrt(w)); outside the band the modes are exactly Wong's
  slip sinkage (option)            z = z_0 [(1 + i+) / (1 - 0.5 i+)]^s_j, i+ = max(i, 0): s_j = 0 none (the
                                   default), s_j = 1 Lyasko's driven-wheel form [L]; the extra rut is dug, not
                                   compressed: the normal stresses keep the static pressure-sinkage relation
                                   (sigma = k (d z_0 / z)^n at depth d), the rut geometry, R_c and R_b use z
  compaction resistance            R_c = b k z^(n+1) / (n + 1)  (work of pressing a rut of depth z)    [B]
  bulldozing (option)              R_b = b (0.67 c z_b K_pc + 0.5 gamma z_b^2 K_pgamma), z_b = max(z - z_bd, 0)
                                   the rut depth beyond the threshold z_bd (z_bd = inf: none, the default);
                                   K_pc = (N_c - tan phi) cos^2 phi, K_pgamma = (2 N_gamma / tan phi + 1)
                                   cos^2 phi (K_pgamma = 1 at phi = 0)                            [B] via [W], [T]
  contact                          the tyre circle (free radius r, centre r - delta above the footprint)
                                   enters the soil at cos(theta_e) = (r - delta - z) / r; the front arc down to
                                   cos(theta_f) = (r - delta) / r is followed by the flat part of length 2 a;
                                   contact length L = r (sin theta_e - sin theta_f) + 2 a
  normal stress                    arc: sigma = k (r (cos theta - cos theta_e))^n; flat: sigma = k z^n
  tread speeds                     arc: omega r (the undeformed circle); flat: omega r_f, r_f = Re in the
                                   flexible mode (the belt moves as on hard ground, where Re is the radius of
                                   free rolling): tread slips i_a = 1 - (1 - i) Re / r, i_f = 1 - (1 - i) Re / r_f
                                   (i_f = i when flexible)
  shear displacement               j_x = i_a x on the arc (x from its front), i_a X + i_f (x - X) on the flat part
                                   (X its front, the arc's horizontal extent); j_y likewise with the rates
                                   (1 - i_a) tan(alpha), (1 - i_f) tan(alpha)
  shear stress (M-C, JH)           tau = (c + sigma tan phi)(1 - exp(-j / K)), j = |(j_x, j_y)|, along (j_x, j_y)
  gross traction, lateral force    H = H_a + H_f = b int_0^L tau_x dx,   F_y = -b int_0^L tau_y dx         [W]
  torque about the axle            T = r H_a + (r - delta) H_f: the shear on the arc acts at radius r, on the
                                   flat part at the loaded radius; the normal stresses give no moment (on the
                                   arc they are radial, through the axle; on the flat part the pressure is
                                   uniform and centred under the axle, as on hard ground; the tyre's hysteresis
                                   shift, the .tir's My, is not carried over); R_c and R_b are the horizontal
                                   parts of the radial arc stresses and act through the axle too
  drawbar pull                     DP = H - R_c - R_b
  spin, power, efficiency          omega = V / ((1 - i) Re),  P = T omega,  eta = DP V / P

With uniform normal stress and one tread slip the thrust is Wong's closed form
H = (c A + W tan phi)[1 - K/(i L)(1 - exp(-i L/K))].

Towed wheel (T = 0, solved by :meth:`mftyre.soil.SoftSoilTyre.towed`): in the rigid mode the arc's tread slip is
zero, the wheel turns at V / r, slower than V / Re on hard ground (slip 1 - r / Re < 0). In the flexible mode the
arc, running at omega r > omega Re, would drive the wheel if the flat part did not skid: zero torque needs
r H_a = -(r - delta) H_f, so the flat part skids (i < 0) and the towed wheel turns slower than on hard ground,
the more so the longer the front arc (deeper sinkage, higher pressure) against the flat part. A consequence to
know: measured against the hard-ground Re the self-propelled point (DP = 0) lies at a small negative slip too
(about -0.6 % for the 460/85 R34 at 25 kN, 1.2 bar on sandy loam), because the arc's shear displacement carries
over to the flat part; and the size of the skid scales with r - Re, i.e. with the .tir's BREFF, DREFF, FREFF.
Seed 001's towed FE wheel slows down until it stops turning (soil piled ahead of it); this steady model has no
soil flow ahead of the wheel and gives a steady skid of a few per cent instead.

Simplifications (each a documented choice, not a hidden one): the load is carried by the flat part in the
flexible mode (Wong) and by the rigid-wheel formula in the rigid mode (the arc's vertical reaction in the flexible
mode is not added); the flat part has the .tir's length 2 a and follows the front arc in the shear integral, but
for the moments it is taken centred under the axle (the undeformed circle reaches the flat's level at
r sin theta_f > a: the bulge between is not modelled); shear acts along the horizontal projection of the contact; the soil does not rebound behind
the bottom; no sidewall (lateral soil wedge) reaction: the lateral force is shear only; speed enters through
omega and the power only (the soil is rate-independent). The integrals are Gauss-Legendre sums (8 nodes on the
arc, 16 on the flat part).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..formula import vertical

__all__ = ["SoilEffects", "SWITCH_BAND", "rigid_wheel_sinkage", "critical_pressure", "compaction_resistance",
           "bulldozing_coefficients", "flexible_fraction", "hard_ground_footprint", "soft_soil", "OUTPUTS"]

_ARC_NODES, _ARC_WEIGHTS = np.polynomial.legendre.leggauss(8)
_FLAT_NODES, _FLAT_WEIGHTS = np.polynomial.legendre.leggauss(16)

#: half-width of the rigid/flexible blend in p_g / p_cr (see the module notes)
SWITCH_BAND = 0.05

#: name -> (SI unit, meaning) of every output of :func:`soft_soil`
OUTPUTS = {
    "sinkage": ("m", "depth of the rut below the soil surface"),
    "contact_length": ("m", "projected length of the soil contact (front arc + flat part)"),
    "contact_width": ("m", "width b of the soil contact"),
    "ground_pressure": ("Pa", "normal stress under the bottom of the tyre, k z_0^n"),
    "critical_pressure": ("Pa", "critical ground pressure p_cr (rigid-wheel pressure at this load)"),
    "carcass_pressure": ("Pa", "carcass stiffness pressure p_c = p_g - p_i on hard ground"),
    "flexible": ("-", "flexible fraction w: 1 where the tyre flattens (p_i + p_c < p_cr), 0 where it acts as a "
                      "rigid wheel, in between over the switch band"),
    "deflection": ("m", "tyre deflection on the soil (0 in the rigid mode)"),
    "rolling_radius": ("m", "radius r_f of the tread speed omega r_f on the flat part: hard-ground Re (flexible), "
                            "free radius r (rigid: no flat part; the arc runs at omega r)"),
    "motion_resistance": ("N", "motion resistance R_c + R_b"),
    "bulldozing_resistance": ("N", "bulldozing resistance R_b (0 unless the bulldozing option is on)"),
    "gross_traction": ("N", "gross traction (thrust) H"),
    "drawbar_pull": ("N", "drawbar pull DP = H - R_c - R_b (net longitudinal force)"),
    "torque": ("N m", "driving torque on the wheel, r H_arc + (r - delta) H_flat"),
    "fy": ("N", "lateral force (ISO-W, shear only)"),
    "omega": ("rad/s", "wheel spin V / ((1 - i) Re)"),
    "power": ("W", "wheel input power T omega"),
    "efficiency": ("-", "tractive efficiency DP V / (T omega); NaN where T <= 0"),
    "slip": ("-", "slip i = 1 - V / (omega Re), Re the hard-ground rolling radius (input)"),
}


@dataclass(frozen=True)
class SoilEffects:
    """Optional effects, each switched by a parameter whose neutral value means absent.

    slip_sinkage      s_j [-] >= 0, exponent of Lyasko's slip-sinkage factor (0: none, 1: Lyasko's form)
    bulldozing_depth  z_bd [m] >= 0, rut depth beyond which the wheel pushes a soil wedge (inf: no bulldozing;
                      needs the soil's unit weight gamma)
    """

    slip_sinkage: float = 0.0
    bulldozing_depth: float = math.inf


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


def bulldozing_coefficients(phi):
    """(K_pc, K_pgamma) of Bekker's bulldozing resistance R_b = b (0.67 c z K_pc + 0.5 gamma z^2 K_pgamma):
    K_pc = (N_c - tan phi) cos^2 phi, K_pgamma = (2 N_gamma / tan phi + 1) cos^2 phi [B via W], with the bearing
    capacity factors N_c (Prandtl-Reissner) and N_gamma (Meyerhof) of the module notes [T]; at phi = 0 their
    limits N_c = pi + 2 and N_gamma / tan phi = 0."""
    if phi == 0.0:
        return math.pi + 2.0, 1.0
    tan_phi, cos2 = math.tan(phi), math.cos(phi) ** 2
    n_q = math.exp(math.pi * tan_phi) * math.tan(math.pi / 4 + phi / 2) ** 2
    n_c, n_gamma = (n_q - 1.0) / tan_phi, (n_q - 1.0) * math.tan(1.4 * phi)
    return (n_c - tan_phi) * cos2, (2.0 * n_gamma / tan_phi + 1.0) * cos2


def flexible_fraction(p_g, p_cr, be):
    """w = s(t), t = (1 + SWITCH_BAND - p_g/p_cr) / (2 SWITCH_BAND) in [0, 1], s(t) = t^2 (3 - 2t): 1 flexible
    (p_g <= (1 - band) p_cr), 0 rigid (p_g >= (1 + band) p_cr), continuously differentiable in between."""
    t = be.clip((1.0 + SWITCH_BAND - p_g / p_cr) / (2.0 * SWITCH_BAND), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


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


def soft_soil(prm, soil, fz, slip, alpha, p, vx, be, effects=SoilEffects()):
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
    w = flexible_fraction(p_g, p_cr, be)                                  # 1 flexible, 0 rigid
    width = prm.WIDTH + w * (2.0 * b_h - prm.WIDTH)
    k = soil.modulus(width)
    z_f = (p_g / soil.modulus(2.0 * b_h)) ** (1.0 / n)
    z_0 = z_r + w * (z_f - z_r)                                           # static sinkage
    delta, a = w * w * rho_h, w * a_h
    r_f = r - w * (r - r_e)                                               # tread speed on the flat part: omega r_f
    drive_slip = be.fmax(slip, 0.0)
    z = z_0 * ((1.0 + drive_slip) / (1.0 - 0.5 * drive_slip)) ** effects.slip_sinkage   # [L]
    cos_f = (r - delta) / r
    cos_e = cos_f - z / r
    sin_f = w * be.sqrt(rho_h * (2.0 * r - delta)) / r                  # sqrt(1 - cos_f^2), smooth at w = 0
    sin_e = be.sqrt(be.fmax(1.0 - cos_e * cos_e, 0.0))
    arc = r * (sin_e - sin_f)                                             # horizontal extent of the front arc
    slip_arc = 1.0 - (1.0 - slip) * r_e / r                               # 1 - V / (omega r)
    slip_flat = 1.0 - (1.0 - slip) * r_e / r_f                            # 1 - V / (omega r_f)
    tan_alpha = be.tan(alpha)

    def shear(jx, jy, sigma):
        """(tau_x, tau_y): Janosi-Hanamoto along the resultant displacement (jx, jy), Mohr-Coulomb strength."""
        j = be.sqrt(jx * jx + jy * jy + (1e-9 * soil.K) ** 2)
        per_unit = (soil.c + sigma * tan_phi) * (1.0 - be.exp(-j / soil.K)) / j
        return per_unit * jx, per_unit * jy

    stress_scale = (z_0 / z) ** n                                         # the dug part of the rut carries no load
    h_arc = lateral = 0.0 * fz
    for node, weight in zip(_ARC_NODES, _ARC_WEIGHTS):                  # front arc, x = 0 .. arc
        x = 0.5 * arc * (node + 1.0)
        sin_theta = sin_e - x / r
        sigma = k * stress_scale * be.fmax(r * (be.sqrt(1.0 - sin_theta * sin_theta) - cos_e), 0.0) ** n
        tau_x, tau_y = shear(slip_arc * x, (1.0 - slip_arc) * tan_alpha * x, sigma)
        h_arc, lateral = h_arc + tau_x * weight * 0.5 * arc, lateral + tau_y * weight * 0.5 * arc
    sigma_flat = k * z_0 ** n
    h_flat = 0.0 * fz
    jx_front, jy_front = slip_arc * arc, (1.0 - slip_arc) * tan_alpha * arc
    for node, weight in zip(_FLAT_NODES, _FLAT_WEIGHTS):                # flat part, x = arc .. arc + 2a
        s = a * (node + 1.0)
        tau_x, tau_y = shear(jx_front + slip_flat * s, jy_front + (1.0 - slip_flat) * tan_alpha * s, sigma_flat)
        h_flat, lateral = h_flat + tau_x * weight * a, lateral + tau_y * weight * a
    h_arc, h_flat, fy = width * h_arc, width * h_flat, -width * lateral
    traction = h_arc + h_flat
    compaction = compaction_resistance(soil, z, width, be)
    k_pc, k_pgamma = bulldozing_coefficients(soil.phi)
    wedge = be.fmax(z - effects.bulldozing_depth, 0.0)                  # rut depth beyond the threshold
    gamma_term = 0.5 * soil.gamma * k_pgamma if math.isfinite(effects.bulldozing_depth) else 0.0
    bulldozing = width * (0.67 * soil.c * k_pc * wedge + gamma_term * wedge * wedge)
    resistance = compaction + bulldozing
    drawbar = traction - resistance
    omega = vx / ((1.0 - slip) * r_e)
    torque = r * h_arc + (r - delta) * h_flat
    power = torque * omega
    return {
        "sinkage": z,
        "contact_length": arc + 2.0 * a,
        "contact_width": width,
        "ground_pressure": sigma_flat,
        "critical_pressure": p_cr,
        "carcass_pressure": p_g - p,
        "flexible": w,
        "deflection": delta,
        "rolling_radius": r_f,
        "motion_resistance": resistance,
        "bulldozing_resistance": bulldozing,
        "gross_traction": traction,
        "drawbar_pull": drawbar,
        "torque": torque,
        "fy": fy,
        "omega": omega,
        "power": power,
        "efficiency": be.where(power > 0, drawbar * vx / be.where(power > 0, power, 1.0), np.nan),
        "slip": slip + 0.0 * fz,
    }
