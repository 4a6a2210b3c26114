"""Vertical tyre behaviour: radii, spin estimate, Fz(rho, p) both ways, contact patch.

Equations: Besselink, Schmeitz & Pacejka (2010), paper (1)-(10); Pacejka (2012) A3.1-A3.3; MF-Tyre/MF-Swift
6.2 vertical-force relation (as documented in its equation manual, 2013) with

* free spinning radius          R_omega = R0 (Q_RE0 + Q_V1 (omega R0 / V0)^2)                 paper (1)
* vertical stiffness            Cz = Cz0 (1 + PFZ1 dpi)                                         paper (5)
* effective rolling radius      Re = R_omega - Fz0/Cz (DREFF atan(BREFF Fz/Fz0) + FREFF Fz/Fz0)  paper (7)
* MF 6.1 load-deflection        Fz = (1 + Q_V2 |omega| R0/V0 - (Q_FCX Fx/Fz0)^2 - (Q_FCY Fy/Fz0)^2)
                                     (1 + PFZ1 dpi) (Q_FZ1 rho/R0 + Q_FZ2 (rho/R0)^2) Fz0         A3.3, paper (3)
  with Q_FZ1 = sqrt((Cz0 R0/Fz0)^2 - 4 Q_FZ2)                                                   paper (4)
* MF 6.2 adds the camber deflection rho_zgamma (Q_CAM1-3), the camber/side-force asymmetry S_Fygamma
  (Q_FYS1-3) and the deflection-dependent side-force term (rho/R0)^Q_FCY2.
* bottoming (both versions): when the loaded radius falls below RIM_RADIUS + BOTTOM_OFFST the rim
  pushes through the tyre with BOTTOM_STIFF: Fz_bottom = BOTTOM_STIFF (RIM_RADIUS + BOTTOM_OFFST - Rl).
* contact patch (paper (9), (10)): a = R0 (Q_RA2 Fz/(Cz R0) + Q_RA1 sqrt(Fz/(Cz R0))),
  b = w (Q_RB2 Fz/(Cz R0) + Q_RB1 (Fz/(Cz R0))^(1/3)), with the load capped at the bottoming load.

Loaded radius from the load. MF 6.1: the quadratic in rho/R0 is solved in the cancellation-free form
x = 2c / (B + sqrt(B^2 + 4 A c)), finite also for Q_FZ2 = 0 (linear tyre) where the textbook root formula
divides by zero. MF 6.2: the relation is not monotone near zero deflection (Q_FCY2 < 0 makes the side-force
term grow without bound as rho -> 0), so an unguarded iteration started near R0 can diverge. mftyre solves it by
Newton's method with the relation's analytic slope, kept inside a bracket (bisection where a step would leave it),
to 1e-15 m (a step, or the error left after the last step as the slope's change over the step before estimates
it) or 1e-12 relative in the load. In contact (the free tyre carries less than the load) it starts from the MF 6.1
deflection without the side-force term, corrected for the camber deflection and, where the relation has the
side-force term, by one step on its tangent in rho with S_Fygamma and the camber deflection held plus the rim's
bottoming kink (piecewise linear, solved exactly; from the deflection where the side-force term takes half the load
factor where it takes more at the start: a side force far above the load), inside [0, R_omega]. A Newton step that
crosses the bottoming onset stops there (the slope jumps by BOTTOM_STIFF; a root just beside the onset otherwise
takes many bisections). NumPy in the benchmark (measured with the start before the tangent and kink): one step of
the search after the start's evaluation on the sample file, one and for ~8 % of the points two on the TNO 205/60 R15
file (Q_FCY).
When even zero free deflection already gives more than the requested load (a cambered tyre at almost no load: the
camber deflection rho_zgamma alone carries more), the relation's root lies above R_omega, where the camber
asymmetry S_Fygamma, growing with Rl/R_omega, brings the load down. There the side-force term takes what the load
leaves, |Fy - S_Fygamma| = sqrt(correction - Fz/load) Fz0 / (|Q_FCY| x^Q_FCY2), which grows with Rl; taken at
R_omega + R0 it turns the quadratic S_Fygamma(Rl/R_omega) into an upper bound of every root (where Q_FCY2 <= 0,
Q_CAM1, Q_CAM2, Q_FZ2 >= 0 and S_Fygamma is monotone, as in the files at hand; else the bound is R_omega + R0). If
the load is gone at the bound, Newton from there inside [R_omega, bound] finds the root (the one the reference
evaluator reports, e.g. Rl = 0.4737 m for Fz = 0 at 31 m/s on its MF 6.2 sample file); its steps are those of
Newton on A - B, the side-force term A = |x^Q_FCY2 Q_FCY (Fy - S_Fygamma)/Fz0| against B = sqrt(correction -
Fz/load), nearly quadratic in Rl where Fz itself falls like a quartic. Where the relation has no root there (no
camber, no S_Fygamma, or a camber so small that the root lies more than R0 above the free radius: a wheel lifted by
more than its own radius is not in contact) the loaded radius is R_omega, where the camber deflection carries a
small load. CasADi (and so the compiled C) unrolls 7 steps, 9 relation evaluations in all; with ``early_stop``
(compiled models) a point stays put once the NumPy solver's stopping tests hold, and the compiled one-point C skips
the remaining steps (points in the .tir ranges converge after 1-2 steps: 1.25 -> 1.02 us per point on the TNO file).
On ~680,000 extreme and bottoming-onset points per file (of the kinds in tests/test_vertical_relation, three MF 6.2
files) the tyres in contact carry the load to 1e-9 after 5 steps, the lifted ones (root above R_omega, Newton from
the bound) after 7: with 6, 3 lifted points of the 2 million fall short; without the bound 8 steps (7 miss some).
"""
from __future__ import annotations


__all__ = [
    "pressure_increment", "vertical_force", "loaded_radius",
    "free_radius", "vertical_stiffness", "rolling_radius_reduction", "spin_and_radius",
    "vertical_force_61", "vertical_force_62", "deflection_61", "deflection_62", "loaded_radius_62", "contact_patch",
    "MF62_SOLVER_FORM_PARAMETERS",
]

#: Parameters the MF 6.2 loaded-radius solver branches on in Python (side-force term present, its bounds of the
#: lifted roots): numbers, never symbols, in an MF 6.2 graph.
MF62_SOLVER_FORM_PARAMETERS = frozenset({"Q_FCY", "Q_FCY2", "Q_FYS2", "Q_FYS3", "Q_FZ2"})


def pressure_increment(prm, p=None):
    """dpi = (p - NOMPRES)/NOMPRES (4.E2b), the pressure increment every pressure term multiplies; ``p`` None: the
    file's INFLPRES (itself NOMPRES where the file does not give it, so dpi = 0)."""
    if p is None:
        p = prm.INFLPRES
    return (p - prm.NOMPRES) / prm.NOMPRES


def vertical_force(prm, rl, r_omega, omega, fx, fy, gamma, dpi, be):
    """Fz at loaded radius ``rl`` by the file's relation: MF 6.2 (:func:`vertical_force_62`, with camber) for
    FITTYP 62, else MF 6.1 (:func:`vertical_force_61`, rho = R_omega - Rl, no camber term)."""
    if prm.version == "62":
        return vertical_force_62(prm, rl, r_omega, omega, fx, fy, gamma, dpi, be)
    return vertical_force_61(prm, r_omega - rl, r_omega, omega, fx, fy, dpi, be)


def loaded_radius(prm, fz, r_omega, omega, fx, fy, gamma, dpi, be):
    """(Rl, rho) carrying the load ``fz`` by the file's relation, the inverse of :func:`vertical_force`: MF 6.2
    (:func:`loaded_radius_62`) for FITTYP 62, else the MF 6.1 deflection with Rl = max(R_omega - rho, 0)."""
    if prm.version == "62":
        return loaded_radius_62(prm, fz, r_omega, omega, fx, fy, gamma, dpi, be)
    rho = deflection_61(prm, fz, r_omega, omega, fx, fy, dpi, be)
    return be.fmax(r_omega - rho, 0.0), rho


def free_radius(prm, omega, be):
    """R_omega: centrifugal growth of the free radius, paper (1)."""
    return prm.UNLOADED_RADIUS * (prm.Q_RE0 + prm.Q_V1 * (omega * prm.UNLOADED_RADIUS / prm.LONGVL) ** 2)


def vertical_stiffness(prm, dpi):
    """Cz at pressure: Cz0 (1 + PFZ1 dpi), paper (5)."""
    return prm.VERTICAL_STIFFNESS * (1.0 + prm.PFZ1 * dpi)


def rolling_radius_reduction(prm, fz, dpi, be):
    """R_omega - Re = Fz0/Cz (DREFF atan(BREFF Fz/Fz0) + FREFF Fz/Fz0), paper (7)."""
    Fz0 = prm.FNOMIN
    return (Fz0 / vertical_stiffness(prm, dpi)) * (prm.DREFF * be.atan(prm.BREFF * fz / Fz0) + prm.FREFF * fz / Fz0)


def spin_and_radius(prm, s, omega_in, omega_given, be):
    """Spin omega, free radius R_omega and effective rolling radius Re.

    Where the spin is not given it follows from the longitudinal slip: omega = (1 + kappa) Vx / Re (2.5).
    With (1) and (7), Re = c + d / Re^2 where c = R0 Q_RE0 - (R_omega - Re) and d = R0 Q_V1 (omega Re R0/V0)^2,
    i.e. the cubic f(Re) = Re^3 - c Re^2 - d = 0, which has exactly one positive root, above max(c, 0). Newton's
    method from the upper bound min(c + d/c^2, max(c, 0) + d^(1/3)) descends to it monotonically (f is convex
    there) and quadratically, at any speed and slip (a plain fixed-point iteration diverges once
    2 Q_V1 (omega R0/V0)^2 > 1, above about 840 m/s or kappa = 52).
    """
    reduction = rolling_radius_reduction(prm, s.uFz, s.dpi, be)  # at the load as given (not saturated at FZMAX)
    wheel_speed = (1.0 + s.ukappa) * s.vx  # omega Re (2.5)

    if omega_given is True:
        omega = omega_in
    else:
        R0 = prm.UNLOADED_RADIUS
        c = R0 * prm.Q_RE0 - reduction
        d = R0 * prm.Q_V1 * (wheel_speed * R0 / prm.LONGVL) ** 2
        c_pos = be.fmax(c, 0.0)
        spinning = d != 0  # (d^(1/3) not at d = 0: its infinite slope there would make NaN derivatives)
        cube_bound = c_pos + be.where(spinning, be.where(spinning, d, 1.0) ** (1.0 / 3.0), 0.0)
        re0 = be.where(c > 0, be.fmin(c + d / be.where(c > 0, c, 1.0) ** 2, cube_bound), cube_bound)
        re0 = be.where(d == 0, c, re0)  # no spin: Re = c

        def newton(re):
            slope = 3.0 * re**2 - 2.0 * c * re
            step = (re**3 - c * re**2 - d) / be.where(slope == 0, 1.0, slope)
            return be.where(slope == 0, re, re - step), None

        re, _ = be.fixed_point(newton, re0, tol=1e-15 + 1e-15 * be.abs(re0), max_iter=100, unrolled=6)
        omega_est = wheel_speed / re  # consistent with the converged radius
        omega = omega_est if omega_given is False else be.where(omega_given, omega_in, omega_est)
    r_omega = free_radius(prm, omega, be)
    return omega, r_omega, r_omega - reduction


def _q_fz1(prm, be):
    """Q_FZ1 from the nominal stiffness, paper (4)."""
    return be.sqrt((prm.VERTICAL_STIFFNESS * prm.UNLOADED_RADIUS / prm.FNOMIN) ** 2 - 4.0 * prm.Q_FZ2)


def _sqrt_positive(u, be):
    """sqrt(max(u, 0)) whose derivative stays finite (zero) where u <= 0: a derivative through the solver's
    unused branches must not turn 0 * inf into NaN (CasADi)."""
    positive = u > 0
    return be.where(positive, be.sqrt(be.where(positive, u, 1.0)), 0.0)


def _bottoming_force(prm, rl, be):
    return prm.BOTTOM_STIFF * be.fmax(prm.RIM_RADIUS + prm.BOTTOM_OFFST - rl, 0.0)


def vertical_force_61(prm, rho, r_omega, omega, fx, fy, dpi, be):
    """MF 6.1 Fz(rho, p): A3.3 / paper (3) with the speed, Fx and Fy factors, plus bottoming; zero where the tyre
    is lifted (rho <= 0) or the force factor is negative (the road cannot pull the tyre down)."""
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    x = be.fmax(rho, 0.0) / R0
    correction = (1.0 + prm.Q_V2 * (R0 / prm.LONGVL) * be.abs(omega) - (prm.Q_FCX * fx / Fz0) ** 2
                  - (prm.Q_FCY * fy / Fz0) ** 2) * (1.0 + prm.PFZ1 * dpi)
    fz = correction * (_q_fz1(prm, be) * x + prm.Q_FZ2 * x**2) * Fz0 + _bottoming_force(prm, r_omega - rho, be)
    return be.fmax(fz, 0.0)


def deflection_61(prm, fz, r_omega, omega, fx, fy, dpi, be):
    """Inverse of :func:`vertical_force_61`: deflection rho >= 0 carrying the load ``fz``.

    Where the force factor is not positive (|Fx| or |Fy| beyond about Fz0/Q_FCX, Fz0/Q_FCY: far outside any
    measured range) the relation carries no load at any deflection; the factor is then held at 1e-3 so that the
    deflection stays finite (the tyre deflects down to the rim, where bottoming carries the load).
    """
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    correction = (1.0 + prm.Q_V2 * (R0 / prm.LONGVL) * be.abs(omega) - (prm.Q_FCX * fx / Fz0) ** 2
                  - (prm.Q_FCY * fy / Fz0) ** 2) * (1.0 + prm.PFZ1 * dpi)
    return _deflection_61(prm, fz, r_omega, correction, be)


def _deflection_61(prm, fz, r_omega, correction, be):
    """:func:`deflection_61` from its force factor ``correction`` (speed, Fx, Fy and pressure)."""
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    correction = be.fmax(correction, 1e-3)
    A, B = prm.Q_FZ2 * correction * Fz0, _q_fz1(prm, be) * correction * Fz0

    def root(a, b, c):  # positive root of a x^2 + b x = c, cancellation free
        return 2.0 * c / (b + be.sqrt(b**2 + 4.0 * a * c))

    x = be.fmax(root(A, B, fz), 0.0)
    # past the bottoming deflection the rim adds BOTTOM_STIFF (R0 x - rho_b)
    rho_b = r_omega - prm.RIM_RADIUS - prm.BOTTOM_OFFST
    bottoming = x * R0 > rho_b
    if be.any(bottoming):  # NumPy skips the root where no element bottoms
        x = be.where(bottoming, root(A, B + prm.BOTTOM_STIFF * R0, fz + prm.BOTTOM_STIFF * rho_b), x)
    return x * R0


_RHO_FLOOR = 1e-12  # m, the smallest MF 6.2 deflection
_NEWTON_STEPS = 7  # unrolled (CasADi) Newton steps of the MF 6.2 loaded radius, see the module notes
_NEWTON_STEPS_FROM_TOP = 8  # the same where the lifted roots have no bound below R_omega + R0


def deflection_62(prm, rl, r_omega, gamma, be):
    """MF 6.2 vertical deflection at loaded radius ``rl``: free-rolling deflection plus the camber deflection
    rho_zgamma (Q_CAM1-3, reference tread width (1.075 - 0.5 ASPECT_RATIO) WIDTH), at least 1e-12 m."""
    return _deflection_62(prm, rl, r_omega, *_camber_terms_62(prm, r_omega, gamma, be), be)


def _camber_terms_62(prm, r_omega, gamma, be):
    """(free share 1 - Q_CAM3 |gamma|, camber factor (W/8) |tan gamma| / (Q_CAM1 R_omega + Q_CAM2 R_omega^2)^2):
    the parts of the MF 6.2 deflection that do not depend on Rl."""
    free_share = 1.0 - prm.Q_CAM3 * be.abs(gamma)
    camber = 0.0
    if prm.Q_CAM1 != 0.0 or prm.Q_CAM2 != 0.0:
        tread_width = (1.075 - 0.5 * prm.ASPECT_RATIO) * prm.WIDTH
        camber = (tread_width / 8.0) * be.abs(be.tan(gamma)) / (prm.Q_CAM1 * r_omega + prm.Q_CAM2 * r_omega**2) ** 2
    return free_share, camber


def _deflection_62(prm, rl, r_omega, free_share, camber, be, slope=False):
    """rho = (R_omega - Rl)+ (1 - Q_CAM3 |gamma|) + growth^2 (W/8) |tan gamma|, growth = (Q_CAM1 Rl + Q_CAM2 Rl^2)
    / (Q_CAM1 R_omega + Q_CAM2 R_omega^2); with ``slope``: (rho, d rho/d Rl)."""
    rho = be.fmax(r_omega - rl, 0.0) * free_share
    growth_camber = 0.0
    if prm.Q_CAM1 != 0.0 or prm.Q_CAM2 != 0.0:
        growth = (prm.Q_CAM1 + prm.Q_CAM2 * rl) * rl
        growth_camber = growth * camber
        rho = rho + growth * growth_camber
    if not slope:
        return be.fmax(rho, _RHO_FLOOR)
    drho = be.where(rl < r_omega, -free_share, 0.0)
    if prm.Q_CAM1 != 0.0 or prm.Q_CAM2 != 0.0:
        drho = drho + 2.0 * growth_camber * (prm.Q_CAM1 + 2.0 * prm.Q_CAM2 * rl)
    return be.fmax(rho, _RHO_FLOOR), be.where(rho > _RHO_FLOOR, drho, 0.0)


def vertical_force_62(prm, rl, r_omega, omega, fx, fy, gamma, dpi, be):
    """MF 6.2 Fz(Rl) at loaded radius ``rl``: the relation below, or zero where it is negative (lifted tyre)."""
    terms = _relation_terms_62(prm, r_omega, omega, fx, fy, gamma, dpi, be)
    return be.fmax(_relation_62(prm, rl, terms, be), 0.0)


def _relation_terms_62(prm, r_omega, omega, fx, fy, gamma, dpi, be) -> tuple:
    """The parts of the MF 6.2 relation that do not depend on Rl (computed once per root search)."""
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    free_share, camber = _camber_terms_62(prm, r_omega, gamma, be)
    correction = 1.0 + prm.Q_V2 * (R0 / prm.LONGVL) * be.abs(omega) - (prm.Q_FCX * fx / Fz0) ** 2
    stiffness = (1.0 + prm.PFZ1 * dpi) * Fz0
    return r_omega, free_share, camber, correction, stiffness, fy, gamma


def _relation_62(prm, rl, terms, be, target=None, lift=True):
    """The MF 6.2 load-radius relation, negative where the side-force term exceeds the rest (terms whose
    parameters are zero are skipped). Its sign change above R_omega is a lifted tyre's loaded radius.

    With a ``target`` load: (Fz - target, dFz/dRl, lift slope or, without ``lift``, dFz/dRl again), the derivative
    written out term by term (the relation is explicit in rho). The lift slope serves the root above R_omega,
    where Fz - target = -(A + B) load (A - B) with A = |side-force term|, B = sqrt(correction - target/load): the
    slope of that with (A + B) load held fixed, i.e. a Newton step on A - B, whose shape is nearly that of
    S_Fygamma, quadratic in Rl (Fz itself falls there like a quartic, and Newton on it creeps)."""
    r_omega, free_share, camber, correction, stiffness, fy, gamma = terms
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    rho, drho = _deflection_62(prm, rl, r_omega, free_share, camber, be, slope=True)
    x, dx = rho / R0, drho / R0
    x_load = be.where(rho > _RHO_FLOOR, x, 0.0)  # no deflection, no load (the floor only keeps x^Q_FCY2 finite)
    q_fz1 = _q_fz1(prm, be)
    load = stiffness * x_load * (q_fz1 + prm.Q_FZ2 * x_load)
    net = correction
    if prm.Q_FCY != 0.0:  # side force, with the camber asymmetry S_Fygamma and the deflection dependency
        ratio = rl / r_omega
        s_fygamma = (prm.Q_FYS1 + (prm.Q_FYS2 + prm.Q_FYS3 * ratio) * ratio) * gamma
        power = x ** prm.Q_FCY2
        side = power * (fy - s_fygamma) * (prm.Q_FCY / Fz0)
        net = correction - side**2
    fz = net * load
    bottoming = rl < prm.RIM_RADIUS + prm.BOTTOM_OFFST
    bottoming_any = be.any(bottoming)  # NumPy skips the rim's terms where no element bottoms
    if bottoming_any:
        fz = fz + _bottoming_force(prm, rl, be)
    if target is None:
        return fz
    dload = stiffness * (q_fz1 + 2.0 * prm.Q_FZ2 * x_load) * dx
    slope = net * dload
    if bottoming_any:
        slope = slope + be.where(bottoming, -prm.BOTTOM_STIFF, 0.0)
    if prm.Q_FCY == 0.0:
        return fz - target, slope, slope
    # d side/d Rl: through x^Q_FCY2 and through S_Fygamma(Rl/R_omega)
    ds_fygamma = (prm.Q_FYS2 + 2.0 * prm.Q_FYS3 * ratio) * gamma / r_omega
    dside = side * (dx / x) * prm.Q_FCY2 - power * ds_fygamma * (prm.Q_FCY / Fz0)
    slope = slope - 2.0 * side * dside * load
    if not lift:
        return fz - target, slope, slope
    safe_load = be.where(load > 0, load, 1.0)
    b = _sqrt_positive(correction - target / safe_load, be)
    db = target * dload / (2.0 * safe_load**2 * be.where(b > 0, b, 1.0))
    lift_slope = -(be.abs(side) + b) * load * (be.sign_nz(side) * dside - db)
    return fz - target, slope, lift_slope


def _growing_load_62(prm) -> bool:
    """Whether the camber deflection and the load grow with Rl above R_omega (Q_CAM1, Q_CAM2, Q_FZ2 >= 0)."""
    return prm.Q_CAM1 >= 0.0 and prm.Q_CAM2 >= 0.0 and prm.Q_FZ2 >= 0.0


def _lift_bound_applies(prm) -> bool:
    """Whether :func:`_lift_bound_62` bounds the lifted roots: a growing load, a side-force term that weakens as
    the deflection grows (Q_FCY2 <= 0) and S_Fygamma monotone in Rl/R_omega over [1, 3] (R_omega above R0/2)."""
    monotone = all(prm.Q_FYS2 + 2.0 * prm.Q_FYS3 * r > 0 for r in (1.0, 3.0))
    return prm.Q_FCY != 0.0 and prm.Q_FCY2 <= 0.0 and _growing_load_62(prm) and monotone


def _lift_bound_62(prm, fz, terms, top, be):
    """An upper bound of a lifted tyre's root, below ``top`` = R_omega + R0 (else ``top``), see
    :func:`_lift_bound_applies`. At a root above R_omega the side-force term takes what the load leaves:
    |Fy - S_Fygamma| = M = sqrt(correction - fz/load) Fz0 / (|Q_FCY| x^Q_FCY2), and S_Fygamma moves away from Fy
    in the direction of gamma: S_Fygamma = Fy + sign(gamma) M. M grows with Rl (so does x), so with M taken at
    ``top`` the quadratic S_Fygamma(Rl/R_omega) = Fy + sign(gamma) M(top) has its root at or beyond every root."""
    r_omega, free_share, camber, correction, stiffness, fy, gamma = terms
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    x = _deflection_62(prm, top, r_omega, free_share, camber, be) / R0
    load = stiffness * (_q_fz1(prm, be) * x + prm.Q_FZ2 * x**2)
    usable = be.logical_and(load > 0, gamma != 0)
    side = _sqrt_positive(correction - fz / be.where(usable, load, 1.0), be) * Fz0 / abs(prm.Q_FCY) * x ** (-prm.Q_FCY2)
    # Q_FYS3 r^2 + Q_FYS2 r + c = 0, the root where S_Fygamma grows with r (cancellation-free either sign of Q_FYS2)
    a, b = prm.Q_FYS3, prm.Q_FYS2
    c = prm.Q_FYS1 - (fy + be.sign_nz(gamma) * side) / be.where(usable, gamma, 1.0)
    root_d = _sqrt_positive(b * b - 4.0 * a * c, be)
    ratio = -2.0 * c / (b + root_d) if b >= 0 else (-b + root_d) / (2.0 * a)
    bound = ratio * r_omega
    inside = be.logical_and(usable, be.logical_and(b * b - 4.0 * a * c >= 0, be.logical_and(bound > r_omega,
                                                                                           bound < top)))
    return be.where(inside, bound, top)


def _with_side_force_62(prm, fz, rho, free_deflection, terms, be):
    """The start ``free_deflection`` (R_omega - Rl) of the loaded-radius search, whose deflection ``rho`` carries
    ``fz`` without the side-force term, moved by one Newton step on the relation with the side-force term
    (S_Fygamma and the camber deflection held at the start) and the rim's bottoming force: the relation taken
    as its tangent plus the bottoming kink (piecewise linear in the deflection, solved exactly), an analytic
    step much cheaper than one of the search. Where the side-force term takes more than half the load factor
    there (a side force far above the load; Q_FCY2 < 0), the step starts from the deflection where it takes half:
    the root lies beyond the one where it takes all."""
    r_omega, free_share, _, correction, stiffness, fy, gamma = terms
    R0 = prm.UNLOADED_RADIUS
    deflected = rho > 0
    x = be.where(deflected, rho, R0) / R0  # no deflection: no step (and finite derivatives through it, CasADi)
    start = free_deflection
    ratio = (r_omega - free_deflection) / r_omega
    s_fygamma = (prm.Q_FYS1 + (prm.Q_FYS2 + prm.Q_FYS3 * ratio) * ratio) * gamma
    side2 = (x ** prm.Q_FCY2 * (fy - s_fygamma) * (prm.Q_FCY / prm.FNOMIN)) ** 2
    if prm.Q_FCY2 < 0.0:  # side^2 ~ x^(2 Q_FCY2): x where it is half the load factor, if above x
        heavy = be.logical_and(2.0 * side2 > correction, correction > 0)
        x_half = x * (correction / be.where(heavy, 2.0 * side2, correction)) ** (0.5 / prm.Q_FCY2)
        free_deflection = be.where(heavy, free_deflection + (x_half - x) * R0 / free_share, free_deflection)
        x, side2 = be.where(heavy, x_half, x), be.where(heavy, 0.5 * correction, side2)
    q_fz1 = _q_fz1(prm, be)
    load = stiffness * x * (q_fz1 + prm.Q_FZ2 * x)
    net = correction - side2
    # d/dx of net load: net dload/dx - 2 Q_FCY2 side^2 load / x; per unit free deflection: times free_share / R0
    slope = (net * stiffness * (q_fz1 + 2.0 * prm.Q_FZ2 * x) - 2.0 * prm.Q_FCY2 * side2 * load / x) * (
        free_share / R0)
    rising = be.logical_and(slope > 0, deflected)
    # tangent plus bottoming: g(d) = base + slope d + K max(d - d_b, 0), d_b the free deflection at the onset
    d_b = r_omega - prm.RIM_RADIUS - prm.BOTTOM_OFFST
    K = prm.BOTTOM_STIFF
    base = net * load - slope * free_deflection
    safe = be.where(rising, slope, 1.0)
    above = (fz - base) / safe  # root where it lies above the onset (no bottoming)
    below = (fz - base + K * d_b) / (safe + K)  # root in bottoming
    moved = be.where(above <= d_b, above, below)
    # kept where the relation rises and the step stays inside (0, R_omega)
    return be.where(be.logical_and(rising, be.logical_and(moved > 0, moved < r_omega)), moved, start)


def loaded_radius_62(prm, fz, r_omega, omega, fx, fy, gamma, dpi, be):
    """Inverse of :func:`vertical_force_62`: (Rl, rho_z) carrying ``fz``, see the module notes."""
    # the residual below evaluates subsets of the elements: the load and the terms as arrays of one shape
    fz, *terms = be.broadcast(fz, *_relation_terms_62(prm, r_omega, omega, fx, fy, gamma, dpi, be))
    r_omega, free_share, camber, correction, stiffness = terms[:5]
    # in contact where the free tyre (Rl = R_omega) carries less than fz; what it carries without the side-force
    # term (which only takes load away) bounds that from above: NumPy evaluates the relation at R_omega only where
    # some load is not above the bound, and skips the lifted tyre's work where no element is lifted
    x_free = _deflection_62(prm, r_omega, r_omega, free_share, camber, be) / prm.UNLOADED_RADIUS
    free_load = stiffness * (_q_fz1(prm, be) * x_free + prm.Q_FZ2 * x_free**2)
    free_bound = correction * free_load + _bottoming_force(prm, r_omega, be)
    contact = be.logical_and(free_load >= 0, fz > free_bound)
    lifting = False
    if be.any(be.logical_or(free_load < 0, fz <= free_bound)):
        f_top = _relation_62(prm, r_omega, terms, be) - fz
        contact, lifted = f_top < 0, f_top > 0
        lifting = be.any(lifted)

    def residual(rl, idx):  # (Fz(Rl) - fz, the slope for the Newton step: in contact dFz/dRl, else the lift slope)
        sub = terms if idx is None else [v[idx] for v in terms]
        value, slope, lift_slope = _relation_62(prm, rl, sub, be, fz if idx is None else fz[idx], lifting)
        return value, be.where(contact if idx is None else contact[idx], slope, lift_slope)

    # in contact: Newton from the deflection of the MF 6.1 relation without the side-force term, less the camber
    # deflection, corrected for the side-force term, inside [0, R_omega] (Fz is taken to exceed any load at Rl = 0,
    # deep in bottoming).
    # Lifted (the free tyre already carries more than fz: camber deflection at a low load): the root lies above
    # R_omega, where the camber asymmetry S_Fygamma grows with Rl/R_omega; Newton from an upper bound of the
    # roots (at most R_omega + R0) inside [R_omega, bound] when the load is gone there, else no root: Rl = R_omega.
    rho_61 = _deflection_61(prm, fz, r_omega, correction * (stiffness / prm.FNOMIN), be)
    camber_share = rho_61 - _deflection_62(prm, r_omega - rho_61, r_omega, free_share, camber, be)
    rho_1 = be.fmax(rho_61 + camber_share / free_share, 0.1 * rho_61)
    if prm.Q_FCY != 0.0:
        rho_1 = _with_side_force_62(prm, fz, rho_61, rho_1, terms, be)
    top = r_omega + prm.UNLOADED_RADIUS
    steps = _NEWTON_STEPS
    if not _lift_bound_applies(prm):
        if prm.Q_FCY != 0.0 or not _growing_load_62(prm):  # lifted roots possible: Newton from R_omega + R0
            steps = _NEWTON_STEPS_FROM_TOP
    elif lifting:
        top = _lift_bound_62(prm, fz, terms, top, be)
    x = be.where(contact, r_omega - rho_1, top)
    f, df = residual(x, None)
    found = be.logical_or(contact, be.logical_and(lifted, f <= 0)) if lifting else contact
    f = be.where(found, f, 0.0)  # no root: stay (Rl = R_omega below)
    lo, hi = be.where(contact, 0.0 * fz, r_omega), be.where(contact, r_omega, top)
    # stop at steps below 1e-15 m (or an error estimated that small after the step) or once the load is matched to
    # 1e-12 relative (floor 1e-12 N); CasADi unrolls a fixed number of steps (see solve_newton)
    rl = be.solve_newton(residual, x, f, df, lo, hi, xtol=1e-15, ftol=1e-12 * be.fmax(fz, 1.0), max_iter=200,
                         unrolled=steps, kink=prm.RIM_RADIUS + prm.BOTTOM_OFFST)
    rl = be.where(found, rl, r_omega)
    return rl, _deflection_62(prm, rl, r_omega, free_share, camber, be)


def contact_patch(prm, fz, dpi, be):
    """Half length a and half width b of the contact patch, paper (9), (10) (MF 5.2: Q_A1, Q_A2)."""
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    cz = vertical_stiffness(prm, dpi)
    fz_bottoming = (R0 - prm.RIM_RADIUS - prm.BOTTOM_OFFST) * cz
    fz = be.where(R0 - fz / cz < prm.RIM_RADIUS + prm.BOTTOM_OFFST, fz_bottoming, fz)
    if prm.version == "52":
        q_a1, q_a2 = prm.Q_A1, prm.Q_A2
        if q_a1 == 0.0 and q_a2 == 0.0:  # MF-Tyre 5.2 default from the stiffness ratio
            y = be.log10(R0 * prm.VERTICAL_STIFFNESS / Fz0)
            q_a1 = -0.0388 * y**3 + 0.2509 * y**2 - 0.6283 * y + 0.6279
            q_a2 = 1.693 * q_a1**2
        a = R0 * (q_a2 * fz / Fz0 + q_a1 * be.sqrt(fz / Fz0))
        return a, prm.WIDTH / 2.0 + 0.0 * a
    load = fz / (cz * R0)
    a = R0 * (prm.Q_RA2 * load + prm.Q_RA1 * be.sqrt(load))
    b = prm.WIDTH * (prm.Q_RB2 * load + prm.Q_RB1 * load ** (1.0 / 3.0))
    return a, b
