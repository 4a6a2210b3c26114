"""A tyre on soft soil: one energy-consistent, vertically balanced stress distribution (Bekker, Janosi-Hanamoto,
Wong) on a tyre that deflects as its .tir says.

Backend-neutral (NumPy or CasADi through ``be``), pure functions of the tyre parameters ``prm`` (a
:class:`mftyre.params.TyreParameters`), a :class:`~mftyre.soil.soils.Soil` and the operating point. SI units;
x forward, z up. Slip i = 1 - V / (omega Re) with Re the tyre's effective rolling radius on hard ground at this
load and pressure (the .tir's Re; the usual convention of tractive-performance tests): 0 free rolling on hard
ground, > 0 driving, < 0 braked; it equals kappa / (1 + kappa) of the Magic Formula. Slip angle alpha as in ISO-W
(Fy < 0 for alpha > 0).

References
  [B]  M.G. Bekker, Off-the-Road Locomotion (1960) and Introduction to Terrain-Vehicle Systems (1969).
  [W]  J.Y. Wong, Theory of Ground Vehicles, 3rd ed. (2001), ch. 2: pressure-sinkage, repetitive loading, shear,
       the rigid wheel (stresses along the rim, shear displacement j = r[(theta_e - theta) - (1 - i)(sin theta_e
       - sin theta)]) and the flexible tyre (equation numbers differ between editions, so none are quoted).
  [JH] Z. Janosi, B. Hanamoto (1961), the exponential shear stress-displacement relation.
  [L]  M. Lyasko, "Slip sinkage effect in soil-vehicle mechanics", J. Terramechanics 47 (2010) 21-31: total
       sinkage z = z_0 (1 + i) / (1 - 0.5 i) for a driven wheel (the form as recalled here).
  [T]  bearing capacity factors: N_q = exp(pi tan phi) tan^2(pi/4 + phi/2) (Prandtl-Reissner),
       N_c = (N_q - 1) cot phi (N_c = pi + 2 at phi = 0), N_gamma = (N_q - 1) tan(1.4 phi) (Meyerhof's closed
       form of Terzaghi's tabulated factor).

The tyre against the soil (one shape for every tyre, soil and pressure; no rigid/flexible switch):
  shape            the free circle of radius r about the axle, cut by a flat part of half-length a_t centred under
                   the axle (the .tir's contact half-length at the load F_t the flat carries): the flat lies
                   c = sqrt(r^2 - a_t^2) below the axle, at the bottom of the rut, sinkage z below the surface.
                   The front arc runs from the surface (theta_e, cos theta_e = (c - z) / r) down to the flat
                   (theta_f, sin theta_f = a_t / r); theta from the downward vertical, forward positive.
  width            B = WIDTH, the section width, for the rut, the arc and the flat part alike (one width: a flat
                   narrower than the arc it replaces would carry less than the circle there, and a stiffer tyre
                   would then sink less); k = k_c / B + k_phi.
  flat part        the tyre presses the soil with the load it carries there spread over its contact length on
                   hard ground at that load, sigma_f = F_t / (2 a_t B) (a_t the .tir's contact half-length at F_t),
                   and the soil answers with its pressure-sinkage relation: sigma_f = k z_0^n               [B]
  front arc        sigma(theta) = k (d / f)^n at the depth d = r cos theta - (c - z) below the surface (f = 1
                   without slip sinkage; continuous with sigma_f at the flat)                               [W]
  vertical balance Fz = F_t + B int_arc sigma cos theta r dtheta: the normal stress over the whole contact
                   carries the load. One equation for F_t in (0, Fz], solved by Newton's method in ln F_t
                   (see :func:`flat_load`). A soft tyre on firm soil carries nearly all on the flat (F_t -> Fz:
                   the hard-ground footprint), a stiff tyre on soft soil nearly all on the arc (F_t -> 0: Bekker's
                   rigid wheel): the pressure acts on every tyre and soil, continuously.
  tyre deflection  rho_t: the .tir's Fz(rho, p) at the load F_t (what the carcass deflects under its flat load)
  slip sinkage     z = f z_0, f = [(1 + i+) / (1 - 0.5 i+)]^s_j, i+ = max(i, 0): s_j = 0 none (default), 1 [L];
                   the dug part of the rut carries no extra load (sigma = k (d / f)^n)

Kinematics (the tread's speed relative to the axle is the one that does work):
  spin             omega = V / ((1 - i) Re)
  arc              the tread runs on the circle at omega r: slip velocity v_x = omega r - V cos theta, normal
                   velocity V sin theta into the soil; shear displacement (time integral of v_x)
                   j_x = r [(theta_e - theta) - (V / (omega r)) (sin theta_e - sin theta)]                   [W]
  flat part        the tread runs at omega r_f, r_f = the .tir's rolling radius at the load F_t (r_f -> Re as
                   F_t -> Fz, -> r as F_t -> 0): v_x = omega r_f - V; j_x = j_x(theta_f) + (1 - V/(omega r_f)) s
                   at the distance s behind the flat's front
  lateral          the wheel moves sideways at V tan alpha: v_y = V tan alpha, j_y = V tan alpha t (t the time
                   since the tread entered the soil)
  shear stress     tau = (c + sigma tan phi)(1 - exp(-j / K)) along (j_x, j_y), j = |(j_x, j_y)|        [JH]

Forces and torque from the same stresses:
  gross traction   H = B [int_arc tau_x cos theta r dtheta + int_flat tau_x ds]
  compaction       R_c = B int_arc sigma sin theta r dtheta = B k f^-n z^(n+1) / (n + 1)  (the rut work) [B]
  bulldozing       R_b = B (0.67 c z_b K_pc + 0.5 gamma z_b^2 K_pgamma), z_b = max(z - z_bd, 0) (option:
                   z_bd = inf none, the default); K_pc = (N_c - tan phi) cos^2 phi, K_pgamma = (2 N_gamma / tan phi
                   + 1) cos^2 phi, a drag through the axle                                          [B via W, T]
  drawbar pull     DP = H - R_c - R_b
  lateral force    Fy = -B [int_arc tau_y r dtheta + int_flat tau_y ds]
  hysteresis       M_h = -My(F_t, V, p): the .tir's rolling-resistance moment (MF A48) at the load the carcass
                   carries on its flat (0 for a rigid wheel, the hard-ground value when F_t = Fz)
  torque           T = B [r^2 int_arc tau_x dtheta + r_f int_flat tau_x ds] + M_h: each shear at the speed of its
                   tread (the normal stresses give none: radial on the arc, centred and uniform on the flat)
  power balance    T omega - Fy V tan alpha = DP V + (R_c + R_b) V + P_slip + M_h omega, exactly, with the
                   shear-slip loss P_slip = B int tau . v dA (so the efficiency DP V / (T omega) <= 1 - i where
                   the shear drives; see tests/test_soil.py)

Simplifications (documented choices): the vertical component of the shear on the arc is left out of the balance
(the normal stress carries the load); the arc is the undeformed circle and the flat the .tir's footprint length
(the carcass shape between them is not modelled); no soil rebound behind the bottom; no sidewall (lateral soil
wedge) reaction; the soil is rate-independent. Integrals: Gauss-Legendre, 10 nodes on the arc in s with
theta = theta_e - (theta_e - theta_f) s^m, m = 2 / (n + 1) (removes the d^n edge at the surface), 12 on the flat.

Multi-pass (option ``rut``: the front tyre's rut depth z_1): the soil the rear tyre meets was loaded to
sigma_1 = k z_1^n and rebounded along Wong's unloading line of slope k_u = k_0 + A_u z_1 (repetitive loading [W];
k_0, A_u soil constants): it carries nothing above z_1 - sigma_1 / k_u, reloads along that line down to z_1 and
follows the virgin curve below:  sigma(d) = k_u (d - z_1 + sigma_1 / k_u)  for d in [z_1 - sigma_1 / k_u, z_1],
k d^n below. The soil springs back to its surface at most: where sigma_1 / k_u > z_1 the reloading line runs from
zero stress at the surface to sigma_1 at z_1 (slope sigma_1 / z_1; see _reloading_slope), never a stress step at
the surface. The rear tyre's front arc starts at that rebounded rut bottom; R_c is the integral of this stress over
the depth (closed form), the rest as above; no slip sinkage in a rut. Wong gives k_0 and A_u for a few terrains
(for a sandy terrain k_0 = 0, A_u = 503 MN/m^4, as recalled here: check the book before relying on it); they are
inputs, not built-in soil constants. The rear tyre sinks further than the front at the same load (repetitive
loading), by less than the front's rut, with less compaction resistance; the soil's strength (c, phi) is not
raised by the first pass.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from ..errors import ModelInputError
from ..formula import moments, vertical
from ..variables import SOIL_OUTPUTS, unit_table

__all__ = ["SoilEffects", "rigid_wheel_sinkage", "critical_pressure", "compaction_resistance",
           "bulldozing_coefficients", "hard_ground_footprint", "carcass_pressure", "flat_load", "soft_soil",
           "OUTPUTS", "ARC_NODES", "FLAT_NODES"]

#: Gauss-Legendre nodes on the front arc (in s, theta = theta_e - (theta_e - theta_f) s^m) and on the flat part
ARC_NODES, FLAT_NODES = 10, 12
_ARC_X, _ARC_WX = np.polynomial.legendre.leggauss(ARC_NODES)
_FLAT_X, _FLAT_WX = np.polynomial.legendre.leggauss(FLAT_NODES)
_ARC_S, _ARC_W = 0.5 * (_ARC_X + 1.0), 0.5 * _ARC_WX                  # on [0, 1]
_FLAT_S, _FLAT_W = 0.5 * (_FLAT_X + 1.0), 0.5 * _FLAT_WX
#: Newton steps CasADi unrolls for the vertical balance (NumPy iterates to convergence; see flat_load)
_BALANCE_STEPS = 14
_LOG_STEP = 1e-6  # step in ln F_t of the difference slope of the balance

#: name -> (SI unit, meaning) of every output of :func:`soft_soil`
#: Unit and meaning of every output (the table :data:`mftyre.variables.SOIL_OUTPUTS`).
OUTPUTS = unit_table(SOIL_OUTPUTS)


@dataclass(frozen=True)
class SoilEffects:
    """Optional effects, each switched by a parameter whose neutral value means absent.

    slip_sinkage      s_j [-] >= 0, exponent of Lyasko's slip-sinkage factor (0: none, 1: Lyasko's form)
    bulldozing_depth  z_bd [m] >= 0, rut depth beyond which the wheel pushes a soil wedge (inf: no bulldozing;
                      needs the soil's unit weight gamma)
    rut               z_1 [m] >= 0, depth of the rut left by the tyre ahead (0: virgin soil); with it
    unloading         (k_0 [N/m^3], A_u [N/m^4]) of Wong's unloading/reloading slope k_u = k_0 + A_u z_1
    """

    slip_sinkage: float = 0.0
    bulldozing_depth: float = math.inf
    rut: float = 0.0
    unloading: tuple = (0.0, 0.0)


def rigid_wheel_sinkage(soil, fz, diameter, width, be):
    """z_r = [3 W / ((3 - n) b (k_c/b + k_phi) sqrt(D))]^(2/(2n+1)), Bekker (1960); Wong (2.43)."""
    n = soil.n
    return (3.0 * fz / ((3.0 - n) * width * soil.modulus(width) * be.sqrt(diameter))) ** (2.0 / (2.0 * n + 1.0))


def critical_pressure(soil, fz, diameter, width, be):
    """p_cr = (k_c/b + k_phi) z_r^n: the ground pressure under a rigid wheel of the same size and load (Wong)."""
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


def hard_ground_footprint(prm, fz, p, be):
    """(rho, a, b) of the tyre on a flat rigid surface at load ``fz`` and pressure ``p`` (no slip, no spin):
    the .tir's Fz(rho, p) inverted and its contact patch (half length a, half width b)."""
    dpi = vertical.pressure_increment(prm, p)
    zero = 0.0 * fz
    r_omega = vertical.free_radius(prm, zero, be)
    _, rho = vertical.loaded_radius(prm, fz, r_omega, zero, zero, zero, zero, dpi, be)
    a, b = vertical.contact_patch(prm, fz, dpi, be)
    return rho, a, b


def carcass_pressure(fz, a, b, p, be):
    """Wong's carcass stiffness pressure p_c: what the mean pressure over the hard-ground patch (half length a, half
    width b: the .tir's) adds to the inflation pressure p, max(Fz / (4 a b) - p, 0). The carcass only adds
    pressure; where the gross rectangle 4ab carries less than p (a car tyre's patch: grooves, rounded ends), the
    rectangle is larger than the area that carries the load and p_c is 0, not negative."""
    return be.fmax(fz / (4.0 * a * b) - p, 0.0)


class _Contact(SimpleNamespace):
    """Geometry and normal stresses of the contact at one flat load (see :func:`_contact`)."""


def _stress(soil, k, depth, factor, effects, be):
    """sigma(d): Bekker's k (d / f)^n on virgin soil; in a rut of depth z_1 Wong's reloading line
    k_u (d - z_1 + sigma_1 / k_u) down to z_1, then the virgin curve (see the module notes)."""
    n = soil.n
    virgin = k * be.fmax(depth if factor is None else depth / factor, 1e-300) ** n   # (finite slope at 0)
    if effects.rut == 0.0:
        return virgin
    z_1 = effects.rut
    sigma_1 = k * z_1 ** n
    k_u = _reloading_slope(soil, k, effects)
    reload = be.fmax(k_u * (depth - z_1) + sigma_1, 0.0)                # (no slip sinkage in a rut)
    return be.where(depth < z_1, reload, virgin)


def _contact(prm, soil, k, flat_load_, dpi, factor, effects, be):
    """Geometry and arc stresses with the flat part carrying ``flat_load_`` (module notes: shape, flat part,
    front arc). Returns a namespace with a (half flat length), sigma_f, z, c, theta_e, theta_f,
    the arc nodes (theta, sigma, dtheta weights) and the arc's vertical normal force."""
    r = vertical.free_radius(prm, 0.0 * flat_load_, be)
    a, _ = vertical.contact_patch(prm, flat_load_, dpi, be)
    sigma_f = flat_load_ / (2.0 * a * prm.WIDTH)
    z_virgin = (sigma_f / k) ** (1.0 / soil.n)
    if effects.rut == 0.0:
        z_0 = z_virgin
    else:  # in the rut: the reloading line carries sigma_f where it is below sigma_1
        z_1 = effects.rut
        sigma_1 = k * z_1 ** soil.n
        k_u = _reloading_slope(soil, k, effects)
        z_0 = be.where(sigma_f < sigma_1, z_1 - (sigma_1 - sigma_f) / k_u, z_virgin)
    z = z_0 if factor is None else factor * z_0
    c = be.sqrt(r * r - a * a)                                      # axle height above the flat
    theta_f = be.atan(a / c)
    top = 0.0 if effects.rut == 0.0 else _rebounded_rut(soil, k, effects, be)   # where the soil begins
    # (the soil surface is held at the axle's height at most: only iterates above the root, or a tyre buried to
    # its axle, which :class:`SoftSoilTyre` reports, get there; the clip keeps acos and its slope finite)
    theta_e = be.acos(be.clip((c - be.fmin(z, c) + top) / r, 1e-15, 1.0 - 1e-15))
    m = 2.0 / (soil.n + 1.0)
    span = theta_e - theta_f
    nodes = []
    vertical_force = 0.0 * flat_load_
    for s, w in zip(_ARC_S, _ARC_W):
        theta = theta_e - span * s ** m
        weight = w * span * m * s ** (m - 1.0)                      # dtheta = span m s^(m-1) ds
        depth = r * be.cos(theta) - (c - z)
        sigma = _stress(soil, k, depth, factor, effects, be)
        nodes.append((theta, sigma, weight))
        vertical_force = vertical_force + sigma * be.cos(theta) * weight
    vertical_force = prm.WIDTH * r * vertical_force
    return _Contact(r=r, a=a, sigma_f=sigma_f, z=z, z_0=z_0, c=c, theta_e=theta_e, theta_f=theta_f, nodes=nodes,
                    arc_load=vertical_force)


def flat_load(prm, soil, fz, k, dpi, factor, effects, be):
    """F_t: the load the flat part carries, from the vertical balance Fz = F_t + (the arc's normal force).

    Newton's method on g(u) = ln(F_t + A(F_t)) - ln Fz, u = ln F_t, from u = ln Fz (the hard-ground footprint),
    the first slope by a difference of 1e-6 in u, then secants, every step kept in a bracket that starts as
    [ln(1e-30 Fz), ln Fz] (a stiff tyre on soft soil carries almost nothing on its flat; bisection where a step
    would leave the bracket). In u both terms are nearly exponentials (F_t = e^u, A ~ e^(m u)), so g is nearly
    linear and convex: Newton from the top comes down to the root monotonically, in 3-11 steps (the most over
    loads 0.05-2 FNOMIN x PRESMIN-PRESMAX, five .tir files, every built-in soil not burying the tyre; CasADi
    unrolls 14). NumPy iterates until every step is below 1e-13 (raising if 80 steps do not get there); CasADi
    unrolls its fixed number of steps and a last Newton step with the difference slope, whose derivatives are
    those of the implicit function."""
    top = be.log10(fz) * math.log(10.0)
    bottom = top + math.log(1e-30)

    def residual(u):
        load = be.exp(u)
        return be.log10(load + _contact(prm, soil, k, load, dpi, factor, effects, be).arc_load) * math.log(10.0) - top

    def newton(u, lo, hi, g, slope):
        """One safeguarded Newton step from u (residual g, its slope): (new u, narrowed bracket [lo, hi], step)."""
        above = g > 0
        lo, hi = be.where(above, lo, u), be.where(above, u, hi)
        candidate = u - g / be.fmax(slope, 1e-3)
        inside = be.logical_and(candidate >= lo, candidate <= hi)
        return be.where(inside, candidate, 0.5 * (lo + hi)), lo, hi, be.where(inside, be.abs(candidate - u), hi - lo)

    u, lo, hi = top, bottom + 0.0 * top, top + _LOG_STEP
    g = residual(u)
    slope = (residual(u + _LOG_STEP) - g) / _LOG_STEP
    casadi = be.name == "casadi"
    for _ in range(_BALANCE_STEPS if casadi else 80):
        new, lo, hi, size = newton(u, lo, hi, g, slope)
        if not casadi and not np.any(size > 1e-13):
            if np.any(new <= bottom + 1e-9):        # the root lies below the bracket: not a silent clip
                raise ModelInputError("soft soil: the vertical balance needs a flat load below 1e-30 Fz (a tyre "
                                      "stiffer than any the model is meant for, e.g. VERTICAL_STIFFNESS far too large)")
            return be.exp(new)
        g_new = residual(new)
        # secant slopes after the first step (one evaluation a step); where the step was tiny, the slope is kept
        secant = be.abs(new - u) > 1e-9
        slope = be.where(secant, (g_new - g) / be.where(secant, new - u, 1.0), slope)
        u, g = new, g_new
    if not casadi:
        raise ModelInputError("soft soil: the vertical balance (flat load) did not converge in 80 steps")
    # CasADi: a last Newton step with the difference slope, so that the derivatives are the implicit function's
    return be.exp(newton(u, lo, hi, g, (residual(u + _LOG_STEP) - g) / _LOG_STEP)[0])


def soft_soil(prm, soil, fz, slip, alpha, p, vx, be, effects=SoilEffects()):
    """Every output of :data:`OUTPUTS` at the operating points (see the module notes for the equations)."""
    n = soil.n
    tan_phi = float(np.tan(soil.phi))
    zero = 0.0 * fz
    dpi = vertical.pressure_increment(prm, p)
    r = vertical.free_radius(prm, zero, be)                               # free radius at rest
    r_e = r - vertical.rolling_radius_reduction(prm, fz, dpi, be)         # hard-ground rolling radius
    _, a_h, b_h = hard_ground_footprint(prm, fz, p, be)
    width = prm.WIDTH                                                     # the rut: the section width
    k = soil.modulus(width)
    if effects.slip_sinkage:
        drive_slip = be.fmax(slip, 0.0)
        factor = ((1.0 + drive_slip) / (1.0 - 0.5 * drive_slip)) ** effects.slip_sinkage    # [L]
    else:
        factor = None
    load_t = flat_load(prm, soil, fz, k, dpi, factor, effects, be)
    g = _contact(prm, soil, k, load_t, dpi, factor, effects, be)
    z, a = g.z, g.a
    rho_t, _, _ = hard_ground_footprint(prm, load_t, p, be)
    r_f = r - vertical.rolling_radius_reduction(prm, load_t, dpi, be)    # tread radius on the flat part

    omega = vx / ((1.0 - slip) * r_e)
    ratio = (1.0 - slip) * r_e                                            # V / omega
    tan_alpha = be.tan(alpha)
    lateral_rate = ratio * tan_alpha                                      # dj_y / dtheta = V tan(alpha) / omega

    def shear(jx, jy, sigma):
        """(tau_x, tau_y): Janosi-Hanamoto along the resultant displacement (jx, jy), Mohr-Coulomb strength."""
        j = be.sqrt(jx * jx + jy * jy + (1e-9 * soil.K) ** 2)
        per_unit = (soil.c + sigma * tan_phi) * (1.0 - be.exp(-j / soil.K)) / j
        return per_unit * jx, per_unit * jy

    sin_e = be.sin(g.theta_e)
    h_arc = t_arc = fy_arc = loss = zero                                # per unit width
    for theta, sigma, weight in g.nodes:
        jx = r * (g.theta_e - theta) - ratio * (sin_e - be.sin(theta))     # [W]
        jy = lateral_rate * (g.theta_e - theta)
        tau_x, tau_y = shear(jx, jy, sigma)
        cos_t = be.cos(theta)
        h_arc = h_arc + tau_x * cos_t * weight
        t_arc = t_arc + tau_x * weight
        fy_arc = fy_arc + tau_y * weight
        loss = loss + (tau_x * (r - ratio * cos_t) + tau_y * lateral_rate) * weight   # x omega below
    h_arc, t_arc, fy_arc, loss = r * h_arc, r * r * t_arc, r * fy_arc, r * loss
    jx_f = r * (g.theta_e - g.theta_f) - ratio * (sin_e - be.sin(g.theta_f))
    jy_f = lateral_rate * (g.theta_e - g.theta_f)
    flat_slip = 1.0 - ratio / r_f                                         # 1 - V / (omega r_f)
    h_flat = fy_flat = zero
    for s, w in zip(_FLAT_S, _FLAT_W):                                    # s: 0 front .. 1 rear of the flat part
        dist = 2.0 * a * s
        tau_x, tau_y = shear(jx_f + flat_slip * dist, jy_f + lateral_rate / r_f * dist, g.sigma_f)
        h_flat, fy_flat = h_flat + tau_x * w, fy_flat + tau_y * w
    h_arc, t_arc, fy_arc, loss = width * h_arc, width * t_arc, width * fy_arc, width * loss
    h_flat, fy_flat = 2.0 * a * width * h_flat, 2.0 * a * width * fy_flat
    slip_power = omega * (loss + h_flat * (r_f - ratio) + fy_flat * lateral_rate)
    traction = h_arc + h_flat
    fy = -(fy_arc + fy_flat)
    dug = 1.0 if factor is None else factor ** (-n)                       # the dug part carries nothing
    compaction = width * k * dug * _compaction_integral(soil, k, z, effects, be)
    k_pc, k_pgamma = bulldozing_coefficients(soil.phi)
    wedge = be.fmax(z - effects.bulldozing_depth, 0.0)                  # rut depth beyond the threshold
    gamma_term = 0.5 * soil.gamma * k_pgamma if math.isfinite(effects.bulldozing_depth) else 0.0
    bulldozing = width * (0.67 * soil.c * k_pc * wedge + gamma_term * wedge * wedge)
    resistance = compaction + bulldozing
    drawbar = traction - resistance
    state = SimpleNamespace(Fz=load_t, uFz=load_t, vx=vx, gamma2=zero, p=p, ukappa=zero)  # My at the load as given
    hysteresis = -moments.rolling_resistance_moment(prm, state, zero, be)
    torque = t_arc + r_f * h_flat + hysteresis
    power = torque * omega
    positive = power > 1e-9 * fz * vx                                    # (not a towed wheel's round-off)
    return {
        "sinkage": z,
        "contact_length": r * sin_e + a,
        "flat_length": 2.0 * a,
        "contact_width": width + zero,
        "ground_pressure": g.sigma_f,
        "flat_load": load_t,
        "carcass_pressure": carcass_pressure(fz, a_h, b_h, p, be),
        "deflection": rho_t,
        "rolling_radius": r_f,
        "compaction_resistance": compaction,
        "bulldozing_resistance": bulldozing,
        "motion_resistance": resistance,
        "gross_traction": traction,
        "drawbar_pull": drawbar,
        "hysteresis_moment": hysteresis,
        "torque": torque,
        "fy": fy,
        "omega": omega,
        "power": power,
        "slip_power": slip_power,
        "efficiency": be.where(positive, drawbar * vx / be.where(positive, power, 1.0), np.nan),
        "slip": slip + zero,
    }


def _compaction_integral(soil, k, z, effects, be):
    """int_0^z sigma(d) dd / k f^-n (closed forms): z^(n+1) / (n+1) on virgin soil (Bekker's rut work); in a rut
    the reloading line's triangle above z_1 plus the virgin curve below (module notes)."""
    n = soil.n
    virgin = z ** (n + 1.0) / (n + 1.0)
    if effects.rut == 0.0:
        return virgin
    z_1 = effects.rut
    sigma_1 = k * z_1 ** n
    k_u = _reloading_slope(soil, k, effects)
    top = _rebounded_rut(soil, k, effects, be)
    end = be.fmax(be.fmin(z, z_1), top)                                  # the reloading line from top to end
    reload = sigma_1 * (end - top) + 0.5 * k_u * ((end - z_1) ** 2 - (top - z_1) ** 2)
    deeper = be.fmax(z, z_1)
    return reload / k + (deeper ** (n + 1.0) - z_1 ** (n + 1.0)) / (n + 1.0)


def _reloading_slope(soil, k, effects):
    """Slope of the unloading/reloading line in the rut of depth z_1: Wong's k_u = k_0 + A_u z_1 [W], at least
    sigma_1 / z_1, so that the line reaches zero stress at or below the soil surface (the soil does not spring back
    above the surface it had)."""
    z_1 = effects.rut
    return max(effects.unloading[0] + effects.unloading[1] * z_1, k * z_1 ** soil.n / z_1)


def _rebounded_rut(soil, k, effects, be):
    """z_1 - sigma_1 / k_u (>= 0): the bottom of the front tyre's rut after the soil's elastic rebound [W]."""
    z_1 = effects.rut
    return be.fmax(z_1 - k * z_1 ** soil.n / _reloading_slope(soil, k, effects), 0.0)
