"""Rigid-ring tyre (SWIFT structure) with the Magic Formula as contact-patch slip model: the equations.

Bodies (Pacejka 2012 ch. 9; Zegelaar 1998; Maurice 2000; NOTES sec. 4): the rim (axle) with imposed or free
vertical motion and imposed or torque-driven spin; the belt, a rigid ring with mass m_b = BELT_MASS, diametral
inertia I_bx = BELT_IXX, polar inertia I_by = BELT_IYY, six degrees of freedom; a massless contact patch joined
to the belt by residual springs; the effective road from the tandem cams (:mod:`swift.enveloping`).
ISO-W axes (x forward, y left, z up), small angles, forward rolling = positive spin about +y.

State (``STATE_NAMES``): belt x_b, z_b, y_b [m], velocities; wind-up theta_w = theta_b - theta_a; belt and rim
spin Omega_b, Omega_a; axle z_a, its velocity, axle x_a and rim lateral position y_a (imposed at each step start
from the inputs x, y and moving with vx, vy within the step: a rim position held over a step while the belt moves
on stretched the sidewall by c_by vy h/2, steady cornering 9-119 % off at 1-5 ms); belt camber gamma_b and yaw psi_b with rates; residual
(patch) deflections u_x, u_y, residual yaw psi_r; transient slips kappa', alpha'; the patch's turn slip phi [1/m]
(constant without the turn-slip option); the filtered effective slope
betaf (for the rate at which the effective plane turns, below); the tandem base l_s of the last step (memory,
not integrated: the stepper starts its Newton pass there and stores the new solution after each step; the exact
right-hand side solves from scratch).

Sidewall (rim -> belt) [chosen from the parameter comments "undamped frequency / dimensionless damping of the
... mode", NOTES sec. 4.2], pressure-aware through this project's own parameters SWIFT_PSTIFF, SWIFT_PDAMP
(0 = no pressure effect; dpi = (p - NOMPRES)/NOMPRES). Where the file does not give them, SWIFT_PSTIFF = PFZ1
(the sidewall stiffens with pressure as the file's vertical stiffness does, paper (3); seed 002: the vertical
stiffness is the tyre property that carries the pressure effect on enveloping) and the damping factor is
f_d = 1/sqrt(f_c): the sidewall damping coefficients k_b stay the same, as for a damper
whose hysteresis does not depend on pressure, so the damping ratios fall as the stiffness rises (seed 001, FE tyre
over a bump at 160/200/242 kPa, decays fastest at the lowest pressure) [chosen]; to first order this is
SWIFT_PDAMP = -PFZ1/2, but positive wherever f_c is (the linear form made f_d < 0, negative damping, above
dpi = 2/PFZ1: 3.5 bar over nominal on the TNO file, whose range reaches 10 bar). With both 0 the damping ratio of
the vertical belt mode rose with pressure (0.102 -> 0.114 from 1.6 to 2.4 bar, sample file). A pressure at which
f_c or f_d <= 0 (:func:`pressure_limits`) is refused with a ModelInputError (:func:`check_pressure`):
    c_bx = c_bz = m_b (2 pi FREQ_LONG)^2 f_c,  c_by = m_b (2 pi FREQ_LAT)^2 f_c,
    c_bg = c_bpsi = I_bx (2 pi FREQ_YAW)^2 f_c,  c_bth = I_by (2 pi FREQ_WINDUP)^2 f_c,   f_c = 1 + SWIFT_PSTIFF dpi
    k_b = 2 DAMP_* f_d sqrt(c_b M),  residual time constant (DAMP_RESIDUAL + low-speed part) f_d,
    f_d = 1 + SWIFT_PDAMP dpi  (given),  f_d = 1/sqrt(f_c)  (SWIFT_PDAMP absent)
Residual springs in series so that the static stiffness of ring + residual is the steady-state model's:
    vertical  rho_MF(F) = rho_r + F / c_bz with F(rho) = A rho + B rho^2 the MF 6.1 load-deflection relation
              without bottoming (A3.3 with its speed and pressure factors; = MF 6.2 at zero camber and side
              force): the total deflection t = rho_r + F/c_bz solves B t^2 + (A - c_bz) t + c_bz rho_r = 0, taken
              in closed form at its smaller root, t = 2 c_bz rho_r / ((c_bz - A) + sqrt((c_bz - A)^2 - 4 B c_bz
              rho_r)): exact, monotone while the tyre is softer than the sidewall [chosen]
    bottoming (vertical.py): the rim pushes on the road directly, BOTTOM_STIFF (RIM_RADIUS + BOTTOM_OFFST - d_a)
              with d_a the rim-centre distance to the effective plane; it acts on the rim, not through the
              sidewall (so the static Fz(rho) is the MF relation including bottoming) [chosen]
    1/C_x = 1/c_bx + r_c^2/c_bth + 1/c_rx + sigma_c/K_xk,  1/C_y = 1/c_by + r_c^2/c_bg + 1/c_ry + sigma_c/K_ya
              (C_x, C_y of paper (17), (18) at the current load and pressure; K_xk, K_ya the MF slip stiffnesses:
              sigma_c/K is the contact patch's static compliance, the transient slip being the patch deflection over
              sigma_c at standstill; ring + residual + patch = the measured static stiffness, so that the overall
              relaxation lengths are the MF's K/C, NOTES 4.4. Old: the patch term was left out, static C_x 277 kN/m
              for 358, relaxation lengths 0.31/0.57 m for 0.25/0.53 m) [chosen]; lever terms dropped, with a warning,
              where they would make a residual stiffness non-positive; the residual compliance floored at
              RESIDUAL_FLOOR of 1/C where the patch alone is softer (light or very heavy loads; a warning where it
              acts within 0.5-1.5 FNOMIN) [chosen guards]
    1/C_psi = 1/c_bpsi + 1/c_rpsi,  C_psi = YAW_STIFFNESS (1 + PCMZ1 dpi)   (NOTES sec. 2.6, 4.2)
    residual damping k_r = (DAMP_RESIDUAL + DAMP_VLOW max(0, 1 - |V|/VXLOW)) f_d c_r [chosen: stiffness
    proportional, DAMP_VLOW faded in linearly below VXLOW]
Effective road, five inputs (Pacejka 2012 sec. 10.1.4; NOTES sec. 3): from the tandem cam heights h_f, h_r at
x_b +- l_s/2 the height w = (h_f + h_r)/2, forward slope beta_y = atan((h_f - h_r)/l_s), road camber beta_x
(ELLIPS_NWIDTH tracks over the contact width at nominal load: atan of the least-squares slope of the track
heights, :class:`swift.enveloping.CamTable`, plus the input ``road_camber``), effective curvature
kappa_e = d beta_y/dx = cos^2(beta_y) (h_f' - h_r')/l_s, and
    * the cams move only vertically, the tandem centred under the belt centre (seed 002, Schmeitz et al. 2005
      sec. 3.1: "each cam ... is allowed to move vertically"; Schmeitz 2004) [published]; the plane passes through
      (x_b, w) with slope beta_y, r_c = (z_b - w) cos(beta_y) is the normal distance of the belt centre from it and
      the contact point is the foot of that normal, x_c = x_b + r_c sin(beta_y) (output ``x_c``; NOTES sec. 3.5).
      (Old [chosen]: the tandem moved with the foot of the normal, x_c = x_b + r_c sin(beta_y) solved together
      with l_s; where a cam met an edge the forward shift and the load's l_s pushed it further on, the solution
      folded and jumped: Fz +364 N within 0.5 mm at the first touch of a 20 mm step or 20 x 20 mm cleat, creep
      10 % off the quasi-static model at the fold; tests/test_swift_contact.py);
    * the effective rolling radius variation [derived here; chosen: the published relation (Pacejka 2012 sec.
      10.1.4, Schmeitz 2004) could not be read (searched: public docs, pages, code and issues corpora; no .tir
      names a coefficient)]. Kinematics of the rigid ring with an inextensible belt band: on the flat the band
      runs at Omega_b R_e relative to the contact (that is what R_e of paper (7) measures). Where the effective
      plane turns at beta_dot, the band's shape turns with it: the band runs at (Omega_b + beta_dot) R_e
      relative to that shape, whose contact point (the foot of the normal) moves along the road at V_cx + r_c
      beta_dot. The tread's speed over the fixed road, the difference, is the slip velocity
          V_sx = V_cx - Omega_b R_e - SWIFT_REVAR beta_dot (R_e - r_c),
      zero for a rigid wheel (R_e = r_c rolls without slip on any curve). On a road of constant curvature
      kappa_s = d beta_y/ds (> 0 concave) the tandem under the belt centre turns at beta_dot = kappa_s V_cx (a
      rigid wheel's contact tangent turns at kappa_s V_cx/(1 - r_c kappa_s), its foot of the normal moving
      faster than the centre; the tandem model turns the plane about the point under the centre: a difference
      of order r_c kappa_s, 3 % of Delta r_e on an 11 m hump), and free rolling (V_sx = 0) gives
          r_e = V_cx/Omega_b = R_e/(1 - t),  Delta r_e = R_e t/(1 - t),  t = kappa_s (R_e - r_c),
      i.e. V_sx = (1 - t)(V_cx - Omega_b (R_e + Delta r_e)): the slip of a tyre of rolling radius
      R_e + Delta r_e. Over a convex crest r_e drops (the belt must spin
      faster), in a concave dip (entry and exit of a cleat) it grows; at -6/+12 mm over a 10 x 20 mm cleat
      (4 kN). Output ``dre`` = Delta r_e from the current effective curvature (kappa_s = cos(beta_y) kappa_e; the
      steady value; 1 - t floored at 0.2 where a concave corner is tighter than 1/(R_e - r_c) [chosen guard]). In
      the slip, beta_dot is the actual rate of the effective slope (with the tandem base moving): the slope
      filtered over the contact half-length a of travel, state ``betaf``, beta_dot = |V_cx| (beta_y - betaf) /
      sigma_f, sigma_f = max(a, |V_cx| h/2) (the rolling radius is a property of the belt along the whole contact
      patch, the same length over which the patch slip relaxes), which is exact on a constant curvature and keeps
      the right-hand side continuous where a cam first touches an edge (the slope has a kink there) [chosen]. (Old:
      a numerical
      4 mm filter, or half a step's travel above 57 km/h at 1 ms; the term's Fx at 60 km/h was +238 / +151 /
      -74 N with a 4 / 8 / 16 mm filter; now independent of the step, test_swift_revar.) The filter runs at a
      pace of at least 0.1 VXLOW (betaf_dot = max(|V_cx|, 0.1 VXLOW) (beta_y - betaf)/sigma_f), so that the
      static equilibrium (betaf = beta_y) is defined at standstill and beta_dot fades out linearly below
      0.1 VXLOW. SWIFT_REVAR (this project's own, [CONTACT_PATCH]) scales the term: 1 (default) = the
      kinematics above, 0 = off. The default is not neutral on uneven roads (Fx over a 10 x 20 mm cleat, fixed
      axle, free rim: peak-to-peak 1119 -> 1254 N at 30 km/h, 963 -> 648 N at 60 km/h); on a flat road
      Delta r_e = 0 exactly, on a constant grade to round-off (1e-14 m);
    * the tandem base l_s = ELLIPS_SHIFT 2a(F_r) at the current (static part of the) contact load F_r, solved by
      Newton passes (``CONTACT_PASSES`` from an estimate, one per stage in the stepper from the previous solution)
      [published l_s = p_ls 2a, Zegelaar eq. 4.15]. A longer base puts a cam further onto an edge, which raises the
      load and the base again; with the cams under the belt centre that feedback stays well below 1 (no fold), the
      slope of the l_s equation is floored (``_SLOPE_FLOOR``) as a guard [chosen].
Contact (normal to the effective plane):
    rho_r = R_Omega - r_c,  F'_z = max(0, F_r(rho_r) + k_rz d(rho_r)/dt)   (no pull)
    V_cx = xdot_b cos(beta_y) + zdot_b sin(beta_y),  V_sx = V_cx - Omega_b R_e - SWIFT_REVAR beta_dot (R_e - r_c)
    (R_e of paper (7); the last term: the effective rolling radius variation, above)
    massless patch:  c_rx u_x + k_rx udot_x = F'_x,  c_ry u_y + k_ry udot_y = F'_y,  c_rpsi psi_r + k_rpsi
    psidot_r = M'_z
    sigma_c dkappa'/dt + |V_cx| kappa' = -(V_sx + udot_x)
    sigma_c dalpha'/dt + |V_cx| alpha' = ydot_b + r_c gammadot_b + udot_y - V_cx (psi_b + psi_r)
                                         + |V_cx| s_v c_rpsi psi_r / C_psi   (static twist, below)
    sigma_c = max(a, |V_cx| h) with a the half contact length [chosen, NOTES sec. 4.4] and h the integration
    step (``h`` argument, 0 for the exact model): |V_cx|/sigma_c never exceeds 1/h, so contact loss (a -> 0)
    cannot make the explicit stepper unstable. Off the road (rho_r <= 0) the slips relax to zero with
    ``AIR_TIME``.
    Slip model: the Magic Formula (MF 6.1/6.2, the .tir's own) at F'_z, kappa', alpha' and the rim camber
    gamma_a - road camber [chosen]: the MF's camber is the wheel-plane inclination it was measured at, and the
    measured forces contain the belt's static camber deflection (r_c F_y + M'_x)/c_bg; the belt camber would
    count it twice (car_205_60R15_mf62_swift.tir, 4 kN, 20 m/s: the belt settles 1.4 mrad below a 30 mrad rim
    camber and the MF at the belt camber gives Fy 13 % lower than at the rim camber,
    test_camber_slip_is_the_rim_camber). So the belt camber acts on the slip only through the geometry
    (r_c gammadot_b in alpha'). Evaluated at speed max(|V_cx|, VXLOW): the low-speed reduction is not
    applied again on top of the transient slips (they already vanish properly at standstill, so the tyre keeps
    its static grip), and the forces keep the sign of the slips in both directions of travel (reversing);
    M'_z follows the direction of travel and M'_y the spin direction (signs linear through standstill).
    Static twist: the slip comes from the belt and patch heading; the twist Mz/C_psi, which the steady-state
    Magic Formula already contains (it was measured against the rim heading), is added back as the yaw
    deflection of the moment the residual spring carries, s_v M_r/C_psi with M_r = c_rpsi psi_r, in the input
    of the slip-angle relaxation (alpha' below) [chosen], so that the steady state equals the Magic Formula while
    belt yaw dynamics and YAW_STIFFNESS act on the transient forces. (Earlier form: alpha_MF = alpha' + s_v
    (psi_b - psi_a + psi_r), the twist from the headings: equal in the steady state, but it passed a rim-yaw
    change straight into the slip (67-87 % of the Fy change within 7 mm at 60 km/h) and self-excited the
    belt-yaw mode at 13-34 km/h on the book's DAMP_YAW 0.007; added to alpha' unrelaxed, the lag of psi_r made
    the 94 Hz camber mode grow at 1-4 m/s, 8 kN on the TNO file; tests/test_swift_modes.py.)
    Forces on the belt (global): F_x = F'_x cos(beta_y) - F'_z sin(beta_y) cos(beta_x), F_z = (F'_x sin(beta_y) +
    F'_z cos(beta_y)) cos(beta_x) + F'_y sin(beta_x), F_y = F'_y cos(beta_x) - F'_z sin(beta_x); moments
    -r_c F'_x + M'_y about y, r_c F'_y + M'_x about x, M'_z about z.
Equations of motion (NOTES sec. 4.3, gyroscopic terms from dH/dt = M with H = I_by Omega (-psi, 1, gamma)):
    m_b xddot_b = -c_bx (x_b - x_a) - k_bx (xdot_b - xdot_a) + F_x
    m_b zddot_b = -c_bz (z_b - z_a) - k_bz (zdot_b - zdot_a) + F_z + m_b GRAVITY
    I_by Omegadot_b = -c_bth theta_w - k_bth (Omega_b - Omega_a) - r_c F'_x + M'_y
    m_b yddot_b = -c_by (y_b - y_a) - k_by (ydot_b - ydot_a) + F_y
    I_bx gammaddot_b = -c_bg (gamma_b - gamma_a) - k_bg gammadot_b + r_c F_y + M'_x + I_by Omega_b psidot_b
    I_bx psiddot_b = -c_bpsi (psi_b - psi_a) - k_bpsi psidot_b + M'_z - I_by Omega_b gammadot_b
    axle "load":   m_a zddot_a = -F_load + F_wz + F_bottom cos(beta_y)  (F_wz = c_bz (z_b - z_a) + k_bz (zdot_b -
                   zdot_a); gravity acts on the belt only, F_load is everything else pushing the rim down)
    rim "torque":  I_a Omegadot_a = T + c_bth theta_w + k_bth (Omega_b - Omega_a)
Not modelled (open in the literature, NOTES sec. 9): Q_BVX/Q_BVT (load and speed influence on the sidewall
stiffness: no published formula could be read; a non-zero value gives a warning. Searched for issue 19: the docs,
pages, code and issues corpora (the MF-Tyre/MF-Swift 6.2 help and equation manuals and the Simcenter 2020.2 user
manual appear only as title pages; public code has the names in .tir parsers and parameter structs only, described
"load and speed influence on in-plane translation / rotation stiffness"), NOTES sec. 4.2 and 9.7), rotating-damper
coupling terms, ENV_C1/ENV_C2.
Turn slip of the contact patch (``turn_slip=True``; off by default, below) [chosen, from the MF's turn-slip
equations, Pacejka 2012 (4.75)-(4.106), mftyre.formula.turnslip]: the patch yaws at psi_dot_c = psidot_b +
psidot_r (belt and residual yaw, the heading the slip angle uses) and its spin relaxes over sigma_c like the slips,
    sigma_c dphi/dt + V' phi = s_v psi_dot_c,   V' = max(|V_cx|, VXLOW)   (air: phi relaxes to 0 with AIR_TIME)
so that phi = psi_dot_c / V with V signed by the direction of travel. The forces get the MF's turn-slip increment
    F'_x, F'_y, M'_z  +=  MF_ts(phit = phi min(1, |V_cx|/VXLOW)) - MF_ts(phit = 0)
(below VXLOW the turn slip fades as in the MF's low-speed model, phit |Vx|/VXLOW: phi itself, relaxed at V' >=
VXLOW, does not vanish at standstill as the transient slips do; without the fade the TNO file's 93 Hz belt
camber/lateral mode (DAMP_LAT 0.005) grew at 0.5 m/s, 8 kN, +1.1 1/s, fed by the turn-slip side force)
(the zeta reduction factors of the peaks and stiffness, the lateral shift S_Hyphi, the moment D_rphi) at the same
load, slips, rim camber and speed as the slip model, with the camber spin (1 - eps_gamma) s_v Omega_b sin(gamma) of
rolling forward (reversing as for the other forces: the MF rolls forward, M'_z turns with s_v, so the spin moment
resists the yaw in both directions): at zero yaw rate the outputs are exactly those without turn slip and the
steady state stays the MF's. The increment is taken about R0 phi = TURN_SLIP_REFERENCE: (4.104)'s C_r is 0/0 at
zero turn slip and camber (its value there, 1, is not its limit).
    Sign: phit = +psi_dot/V in ISO-W (z up). The MF adds phit to the camber spin (1 - eps_gamma) Omega sin(gamma)/V
(4.76), and an ISO camber gamma > 0 (leaning right: the files' camber thrust Fy < 0) tilts the spin axis to +z; so a
wheel rolling freely along its cone (leaning right, turning right at psi_dot = -(1 - eps_gamma) Omega sin(gamma))
has no spin and no camber thrust, and a left-turning patch at zero slip angle is pushed outwards (brush model).
Pacejka's phit = -psi_dot/V (4.75) has z down. Issue 19's first attempt took -psi_dot/V: the cone's camber thrust
doubles (tests/test_swift_turn_slip.py); with that sign (and the reference spin) the MFeval 6.2 file, whose moment
resists the yaw most, grows at +635 1/s (1 m/s, 4 kN), while the sample and TNO files stay damped at 2-8 kN: the
two cases swap. Its +2310 1/s came with C_r at 0/0 (the Jacobian there has entries of 1e13).
    Why off by default: on a file whose camber moment changes sign with the load (K_zgamma,r0 = Fz R0 (QDZ8 +
QDZ9 dfz) LKZC, (4.99): MFeval's MF 6.1/6.2 files above 1.66 FNOMIN) the MF's turn-slip moment at zero slip,
dMz/dphit = K_zgamma,r0 R0/(1 - eps_gamma), pushes the yaw, and the ring grows (MFeval 6.2 +176 1/s at -70 m/s,
13.5 kN); :class:`mftyre.errors.TurnSlipWarning` names the file, the loads and the parameters there
(:func:`turn_slip_warning`). And at FZMAX (2.5 FNOMIN) the turn-slip side force still feeds the TNO file's 89 Hz
belt camber/lateral mode at 1-2 m/s (+5.9 1/s at 1 m/s, 10 kN). Elsewhere, 0.5-70 m/s both ways, PRESMIN..PRESMAX
(TNO: up to 2.2 bar; above 5.7 bar its own cornering stiffness reverses), every mode of every bundled and shared
SWIFT file stays damped with turn slip from 0.5 FNOMIN (or 2 kN) to FZMAX, or to 1.66 FNOMIN on the MFeval files,
including the sample file's belt-yaw mode at 10 kN, 2.55 bar that grows without it (+0.18 1/s, 7 m/s)
(benchmarks/swift_turn_slip_modes.py; FSAE_Defaults's LoadFactorWarning case aside). (Until the MF's pneumatic trail multiplied F'y at gamma = phi = 0 (4.E32,
4.E74), it took the camber spin's side force S_Hyphi through the trail, and dMz/dphit turned positive above ~6 kN
on the sample and TNO files: +2.7 1/s at 8 kN, 15 m/s.)
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from mftyre.errors import InputClippedWarning, LoadFactorWarning, ModelInputError
from mftyre.formula import vertical
from mftyre.inputs import load_factor_problems

__all__ = ["RingConstants", "STATE_NAMES", "INPUT_NAMES", "OUTPUT_NAMES", "CONTACT_PASSES", "AIR_TIME",
           "TURN_SLIP_REFERENCE", "RESIDUAL_FLOOR", "pressure_coefficients", "pressure_limits", "check_pressure",
           "residual_vertical", "residual_compliance", "contact_start", "contact_geometry", "ring_equations",
           "turn_slip_moment_slopes", "turn_slip_warning"]

STATE_NAMES = ("xb", "vxb", "zb", "vzb", "thw", "omb", "oma", "za", "vza", "xa", "ya",
               "ux", "kappa", "yb", "vyb", "gb", "wgb", "psb", "wpsb", "uy", "alpha", "psr", "phi", "betaf", "lsm")
#: Inputs of one step. x/z/omega of the axle enter through the state (imposed parts are set by the stepper).
INPUT_NAMES = ("vx", "load", "torque", "p", "y", "vy", "gamma", "psi", "road_camber")
OUTPUT_NAMES = ("fx", "fy", "fz", "mx", "my", "mz",            # forces and moments of the tyre on the rim
                "fx_c", "fy_c", "fz_c", "mz_c",                # contact forces in the effective plane
                "rho", "rl", "re", "a", "ls", "w", "beta",     # deflection, radii, patch, effective road
                "kappa", "alpha", "vcx", "curvature", "dre", "x_c", "beta_x")
_S = {n: i for i, n in enumerate(STATE_NAMES)}
#: Newton passes of the tandem-base solution from the start estimate (quadratic convergence).
CONTACT_PASSES = 3
#: Floor of the slope 1 - dl_s(F)/dl_s of the tandem-base equation (:func:`contact_geometry`) [chosen guard].
_SLOPE_FLOOR = 0.1
#: Time constant [s] with which the transient slips relax to zero while the tyre is off the road.
AIR_TIME = 5e-3
#: Load floor [N] of the slip model and contact length: keeps derivatives finite off the road (sqrt(Fz) at 0).
_FZ_FLOOR = 1e-3
#: Least residual compliance as a fraction of the overall 1/C_x, 1/C_y (:func:`residual_compliance`).
RESIDUAL_FLOOR = 0.02
#: Floor of 1 - t, t = kappa_s (R_e - r_c), in the reported rolling radius variation ``dre`` (a concave corner
#: tighter than 1/(R_e - r_c)) [chosen guard].
_TURN_FLOOR = 0.2
#: Reference spin R0 phi about which the turn-slip increment is taken (:func:`ring_equations`) [chosen guard]: the
#: published C_r = (2/pi) acos(M_zphi90 / |D_rphi|) (Pacejka 2012 (4.104)) is 0/0 at zero turn slip and camber, held
#: at C_r = 1 exactly there and at its limit (another value) around it: a removable jump of M_z (0.07 N m of 15 N m,
#: sample file, 4 kN, 0.1 rad) and a derivative of order 1e-16/phi next to it.
TURN_SLIP_REFERENCE = 1e-6


@dataclass(frozen=True)
class RingConstants:
    """Sidewall constants from [INERTIA]/[STRUCTURAL] (at nominal pressure) and the options of the rim and axle
    bodies."""

    mb: float
    ibx: float
    iby: float
    cbx: float
    cby: float
    cbg: float
    cbth: float
    kbx: float
    kby: float
    kbg: float
    kbth: float
    lever_x: bool  # r_c^2/c_bth term in the C_x series relation
    lever_y: bool  # r_c^2/c_bg term in the C_y series relation
    axle_mass: float
    rim_inertia: float

    @classmethod
    def from_model(cls, model, axle_mass: float = 30.0, rim_extra_inertia: float = 0.3) -> "RingConstants":
        """Constants of ``model``; ``axle_mass`` [kg] (axle "load" mode), rim inertia = IYY - BELT_IYY +
        ``rim_extra_inertia`` [kg m^2] (rim, hub, brake; the TNO cleat rig example uses 0.253 + 0.049)."""
        prm = model.params
        need = ["BELT_MASS", "BELT_IXX", "BELT_IYY", "FREQ_LONG", "FREQ_LAT", "FREQ_YAW", "FREQ_WINDUP"]
        bad = [n for n in need if not (n in prm and prm[n] > 0)]
        if bad:
            raise ModelInputError(f"the rigid ring needs positive {', '.join(bad)} ([INERTIA]/[STRUCTURAL] of "
                                  f"the .tir file)")
        for name in ("Q_BVX", "Q_BVT"):
            if name in prm and prm[name] != 0:
                warnings.warn(f"{name} = {prm[name]} (load and speed influence on the in-plane sidewall stiffness) "
                              f"is not modelled: no published formula; the sidewall stiffness follows FREQ_* only",
                              stacklevel=2)
        for _, message in load_factor_problems(prm):  # the MF's own data, which no ring can damp
            warnings.warn(f"{getattr(prm, 'source', None) or 'this .tir file'}: {message}", LoadFactorWarning,
                          stacklevel=2)
        mb, ibx, iby = prm.BELT_MASS, prm.BELT_IXX, prm.BELT_IYY
        w = {k: 2 * np.pi * prm[f"FREQ_{k}"] for k in ("LONG", "LAT", "YAW", "WINDUP")}
        cbx, cby, cbg, cbth = mb * w["LONG"] ** 2, mb * w["LAT"] ** 2, ibx * w["YAW"] ** 2, iby * w["WINDUP"] ** 2
        damp = lambda c, m, name: 2 * prm[f"DAMP_{name}"] * np.sqrt(c * m)  # noqa: E731
        # guard: residual series stiffness must stay positive over 0.25..2 Fz0 at nominal pressure
        out = model.evaluate(np.linspace(0.25, 2.0, 8) * prm.FNOMIN, 0.0, 0.0)
        r2 = out.rl**2
        lever_x = bool(np.all(1 / out.cx - 1 / cbx - r2 / cbth > 0))
        lever_y = bool(np.all(1 / out.cy - 1 / cby - r2 / cbg > 0))
        for ok, name in ((lever_x, "x"), (lever_y, "y")):
            if not ok:
                warnings.warn(f"residual stiffness c_r{name} with the rotation lever term would be non-positive; "
                              f"using the translation-only series relation", stacklevel=2)
        sub = (out.fz >= 0.49 * prm.FNOMIN) & (out.fz <= 1.51 * prm.FNOMIN)
        floored = [name for name, c, ring, k, ok in (("x", out.cx, 1 / cbx + r2 / cbth * lever_x, out.kxk, lever_x),
                                                     ("y", out.cy, 1 / cby + r2 / cbg * lever_y, out.kya, lever_y))
                   if np.any((1 / c - ring - out.a / np.maximum(np.abs(k), 1.0) < RESIDUAL_FLOOR / c)[sub])]
        if floored:
            warnings.warn(f"residual stiffness c_r{'/c_r'.join(floored)}: the ring and contact patch alone are "
                          f"softer than LONGITUDINAL/LATERAL_STIFFNESS between 0.5 and 1.5 FNOMIN; the residual "
                          f"compliance is held at {RESIDUAL_FLOOR} of the overall one there (the static stiffness "
                          f"comes out lower than the file's)", stacklevel=2)
        if not (1 / out.cx - 1 / cbx > 0).all() or not (1 / out.cy - 1 / cby > 0).all():
            raise ModelInputError("LONGITUDINAL/LATERAL_STIFFNESS exceed the sidewall stiffness from FREQ_*: "
                                  "no positive residual stiffness exists")
        if not 1 / prm.YAW_STIFFNESS - 1 / cbg > 0:
            raise ModelInputError(f"YAW_STIFFNESS = {prm.YAW_STIFFNESS} exceeds the sidewall yaw stiffness "
                                  f"{cbg:.0f} N m/rad from FREQ_YAW and BELT_IXX: no positive residual yaw stiffness")
        if not prm.DAMP_RESIDUAL > 0:
            raise ModelInputError("DAMP_RESIDUAL must be positive: the massless contact patch needs residual "
                                  "damping")
        return cls(mb, ibx, iby, cbx, cby, cbg, cbth, damp(cbx, mb, "LONG"), damp(cby, mb, "LAT"),
                   damp(cbg, ibx, "YAW"), damp(cbth, iby, "WINDUP"), lever_x, lever_y, float(axle_mass),
                   float(prm.IYY - prm.BELT_IYY + rim_extra_inertia))


def residual_compliance(c_total, c_ring, sigma_c, k_slip, be):
    """1/c_r: the compliance of the residual spring that makes the static series compliance ring (``c_ring``:
    1/c_b plus the rotation lever) + residual + contact patch (sigma_c / K, the slip model's static stiffness:
    at standstill the transient slip is the patch deflection over sigma_c) equal the file's 1/``c_total``
    (LONGITUDINAL/LATERAL_STIFFNESS at the load and pressure); at least RESIDUAL_FLOOR / c_total, where the
    patch alone is softer (light loads: K ~ Fz, sigma_c ~ sqrt(Fz)) [chosen]."""
    patch = sigma_c / be.fmax(be.abs(k_slip), 1.0)
    return be.fmax(1.0 / c_total - c_ring - patch, RESIDUAL_FLOOR / c_total)


def turn_slip_moment_slopes(model, loads=None, h: float = 1e-3):
    """[(Fz, dMz/dphit, dMzr/dphit)]: the slopes [N m per 1/m] of the MF's aligning moment and of its residual part
    in the turn slip phit about the reference spin (:data:`TURN_SLIP_REFERENCE`), by central differences of
    ``h``/R0 with MFModel.evaluate(turn_slip=True) at zero slip and camber, LONGVL, INFLPRES, at ``loads``
    (default 0.5, 0.55, ... 2 FNOMIN). With phit = psi_dot/V (ISO-W, module notes) a positive slope pushes the patch
    along its yaw rate: the MF's own (camber) data drive the yaw instead of damping it."""
    prm = model.params
    loads = np.linspace(0.5, 2.0, 31) * prm.FNOMIN if loads is None else np.asarray(loads, dtype=float)
    r0 = prm.UNLOADED_RADIUS
    ref, dp = TURN_SLIP_REFERENCE / r0, h / r0
    with warnings.catch_warnings():  # loads above FZMAX: saturated, as in the ring's slip model
        warnings.simplefilter("ignore", InputClippedWarning)
        plus = model.evaluate(loads, 0.0, 0.0, 0.0, ref + dp, turn_slip=True)
        minus = model.evaluate(loads, 0.0, 0.0, 0.0, ref - dp, turn_slip=True)
    return [(float(f), float(a), float(b)) for f, a, b in zip(loads, (plus.mz - minus.mz) / (2 * dp),
                                                              (plus.mzr - minus.mzr) / (2 * dp))]


def turn_slip_warning(model) -> str | None:
    """The message of :class:`mftyre.errors.TurnSlipWarning` where the MF turn-slip moment of ``model`` is
    anti-damping at some load of 0.5-2 FNOMIN (:func:`turn_slip_moment_slopes`), else None. At zero slip the slope
    is the residual moment's, K_zgamma,r0 R0 / (1 - eps_gamma) (4.97)-(4.99): the file's camber moment (QDZ8 +
    QDZ9 dfz, QDZ10, QDZ11) changing sign with the load."""
    bad = [row for row in turn_slip_moment_slopes(model) if row[1] > 0]
    if not bad:
        return None
    prm = model.params
    fz, slope, _ = max(bad, key=lambda row: row[1])
    names = ", ".join(f"{n} = {prm[n]:g}" for n in ("QDZ8", "QDZ9", "QDZ10", "QDZ11", "PECP1", "PECP2") if n in prm)
    return (f"{getattr(prm, 'source', None) or 'this .tir file'}: with turn slip the Magic Formula's aligning moment "
            f"pushes the contact patch along its yaw rate at {bad[0][0]:.0f}-{bad[-1][0]:.0f} N "
            f"(dMz/dphit = {slope:+.3g} N m per 1/m at {fz:.0f} N, from the camber moment K_zgamma,r0 of the file; "
            f"{names}): the SWIFT belt yaw or camber modes can grow (swift.modes.scan shows where)")


def pressure_coefficients(prm) -> tuple[float, float | None]:
    """(SWIFT_PSTIFF, SWIFT_PDAMP) as used: the file's values; where the file has none SWIFT_PSTIFF = PFZ1 and
    SWIFT_PDAMP None (the damping factor f_d = 1/sqrt(f_c): damping coefficients independent of pressure, module
    notes)."""
    pstiff = prm.PFZ1 if "SWIFT_PSTIFF" in prm.missing else prm.SWIFT_PSTIFF
    pdamp = None if "SWIFT_PDAMP" in prm.missing else prm.SWIFT_PDAMP
    return pstiff, pdamp  # (numbers, or symbols where the compiled step takes the parameters at run time)


def _pressure_factors(prm, dpi, be):
    """(f_c, f_d): sidewall stiffness and damping factors at pressure (module notes; 1 at NOMPRES)."""
    pstiff, pdamp = pressure_coefficients(prm)
    f_c = 1.0 + pstiff * dpi
    return f_c, (1.0 / be.sqrt(f_c) if pdamp is None else 1.0 + pdamp * dpi)


def pressure_limits(prm) -> tuple[tuple[float, str], tuple[float, str]]:
    """((p_low, parameter), (p_high, parameter)): the open range of inflation pressures [Pa] over which the
    sidewall factors f_c and f_d (module notes) are positive, each bound with the parameter that sets it
    ("" where none does: 0 and inf). Outside it the ring has a negative stiffness or damping: no tyre."""
    pstiff, pdamp = pressure_coefficients(prm)
    low, high = (0.0, ""), (math.inf, "")
    for name, coef in (("SWIFT_PSTIFF", pstiff), ("SWIFT_PDAMP", pdamp)):
        if not coef:  # None (f_d = 1/sqrt(f_c): positive wherever f_c is) or 0
            continue
        edge = prm.NOMPRES * (1.0 - 1.0 / coef)  # 1 + coef (p - NOMPRES)/NOMPRES = 0
        if coef > 0 and edge > low[0]:
            low = (edge, name)
        elif coef < 0 and edge < high[0]:
            high = (edge, name)
    return low, high


def check_pressure(prm, p: float) -> None:
    """ModelInputError naming the parameter and the pressure where the sidewall stiffness or damping factor
    (module notes) is not positive at ``p`` [Pa]; the valid range from :func:`pressure_limits`."""
    pstiff, pdamp = pressure_coefficients(prm)
    dpi = vertical.pressure_increment(prm, p)
    for name, coef, factor, what in (("SWIFT_PSTIFF", pstiff, "stiffness factor f_c", "stiffness"),
                                     ("SWIFT_PDAMP", pdamp, "damping factor f_d", "damping")):
        if coef is None or 1.0 + coef * dpi > 0:
            continue
        (p_low, _), (p_high, _) = pressure_limits(prm)
        given = " (absent from the file: PFZ1)" if name in prm.missing else ""
        raise ModelInputError(
            f"inflation pressure p = {p:g} Pa gives the SWIFT sidewall {factor} = 1 + {name} dpi = "
            f"{1.0 + coef * dpi:.3g} <= 0 ({name} = {coef!r}{given}, dpi = (p - NOMPRES)/NOMPRES = {dpi:.3g}): a ring "
            f"with negative {what} is no tyre; with these parameters the ring is valid for {p_low:g} < p < {p_high:g} Pa")


def residual_vertical(prm, rho_r, omega, dpi, cbz, be):
    """(F_r, dF_r/drho_r): the vertical residual spring, the series complement of the sidewall c_bz in the MF 6.1
    load-deflection relation without bottoming (closed form, module notes); negative for rho_r < 0."""
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    q_fz1 = np.sqrt((prm.VERTICAL_STIFFNESS * R0 / Fz0) ** 2 - 4.0 * prm.Q_FZ2)  # paper (4)
    factor = (1.0 + prm.Q_V2 * (R0 / prm.LONGVL) * be.abs(omega)) * (1.0 + prm.PFZ1 * dpi) * Fz0  # A3.3
    A, B = factor * q_fz1 / R0, factor * prm.Q_FZ2 / R0**2
    soft = cbz - A
    disc = be.fmax(soft**2 - 4.0 * B * cbz * rho_r, 1e-6 * soft**2)
    t = 2.0 * cbz * rho_r / (soft + be.sqrt(disc))  # total deflection rho_r + F/c_bz
    k_t = A + 2.0 * B * t  # tangent stiffness of the MF relation
    return cbz * (t - rho_r), cbz * k_t / (cbz - k_t)


def _plane(hf, hr, ls, zb, be):
    """(w, beta_y, r_c): effective height and slope of the tandem, and the normal distance to that plane from a
    centre at height zb above the tandem's midpoint (the cams sit under the belt centre, module notes)."""
    w = (hf + hr) / 2
    beta = be.atan((hf - hr) / ls)
    return w, beta, (zb - w) * be.cos(beta)


def _tandem_base(prm, fz, dpi, be):
    a, _ = vertical.contact_patch(prm, be.fmax(fz, _FZ_FLOOR), dpi, be)
    return be.fmax(prm.ELLIPS_SHIFT * 2.0 * a, 1e-6)


def contact_start(model, rc: RingConstants, state, u, h_c):
    """l_s to start the contact passes: at the load of the residual spring with the cam height ``h_c`` under the
    belt centre."""
    from mftyre.backend import casadi_backend

    be = casadi_backend()
    prm = model.params
    s = {n: state[i] for i, n in enumerate(STATE_NAMES)}
    dpi = vertical.pressure_increment(prm, u[INPUT_NAMES.index("p")])
    f_c, _ = _pressure_factors(prm, dpi, be)
    rho_r = vertical.free_radius(prm, s["omb"], be) - (s["zb"] - h_c)
    f_r, _ = residual_vertical(prm, rho_r, s["omb"], dpi, rc.cbx * f_c, be)
    return _tandem_base(prm, f_r, dpi, be)


def contact_geometry(model, rc: RingConstants, state, u, hf, dhf, hr, dhr, ls):
    """One Newton pass of the tandem base from the cam heights ``hf``, ``hr`` (slopes ``dhf``, ``dhr``) at
    x_b +- ``ls``/2: the new l_s solving l_s = ELLIPS_SHIFT 2a(F_r(R_Omega - r_c)) (module notes)."""
    import casadi as ca
    from mftyre.backend import casadi_backend

    be = casadi_backend()
    prm = model.params
    s = {n: state[i] for i, n in enumerate(STATE_NAMES)}
    dpi = vertical.pressure_increment(prm, u[INPUT_NAMES.index("p")])
    f_c, _ = _pressure_factors(prm, dpi, be)
    r_omega = vertical.free_radius(prm, s["omb"], be)
    ls_, hf_, hr_ = (ca.SX.sym(n) for n in ("ls", "hf", "hr"))
    _, _, r_c = _plane(hf_, hr_, ls_, s["zb"], be)
    f_r, _ = residual_vertical(prm, r_omega - r_c, s["omb"], dpi, rc.cbx * f_c, be)
    res = ls_ - _tandem_base(prm, f_r, dpi, be)
    # chain rule through the cam heights at x_b +- l_s/2: d(hf)/dl_s = dhf/2, d(hr)/dl_s = -dhr/2
    slope = ca.jacobian(res, ls_) + ca.jacobian(res, hf_) * dhf / 2 - ca.jacobian(res, hr_) * dhr / 2
    res, slope = ca.substitute([res, slope], [ls_, hf_, hr_], [ls, hf, hr])
    # Newton with the slope 1 - dl_s(F)/dl_s floored: the load's feedback on the tandem base (a longer base puts a
    # cam further onto an edge) stays well below 1 with the cams under the belt centre, the floor only guards
    return be.fmax(ls - res / be.fmax(slope, _SLOPE_FLOOR), 1e-6)


def ring_equations(model, rc: RingConstants, state, u, hf, dhf, hr, dhr, ls, *, axle: str, rim: str, h=0.0,
                   road_camber=0.0, turn_slip: bool = False):
    """State derivative and outputs (CasADi vectors) of the ring at ``state`` (STATE_NAMES) and inputs ``u``
    (INPUT_NAMES), with the front/rear cam heights ``hf``, ``hr`` and their slopes along x at the cam positions
    x_b +- ``ls``/2 (under the belt centre). ``axle``: "height" (imposed, z_a and its rate
    from the state, held by the stepper) or "load"; ``rim``: "speed" (imposed spin) or "torque"; ``h``: the
    integration step (limits the relaxation rate, module notes; 0 = the exact model); ``road_camber``: the
    multi-track road camber beta_x of a 3D road [rad] (added to the input ``road_camber``); ``turn_slip``: the
    contact patch's turn slip from its yaw rate (module notes; off: the state ``phi`` stays constant)."""
    import casadi as ca
    from mftyre.backend import casadi_backend

    be = casadi_backend()
    prm = model.params
    s = {n: state[i] for i, n in enumerate(STATE_NAMES)}
    v = {n: u[i] for i, n in enumerate(INPUT_NAMES)}
    dpi = vertical.pressure_increment(prm, v["p"])
    f_c, f_d = _pressure_factors(prm, dpi, be)
    cbx, cby, cbg, cbth = rc.cbx * f_c, rc.cby * f_c, rc.cbg * f_c, rc.cbth * f_c
    g = be.sqrt(f_c) * f_d
    kbx, kby, kbg, kbth = rc.kbx * g, rc.kby * g, rc.kbg * g, rc.kbth * g
    r_omega = vertical.free_radius(prm, s["omb"], be)

    # effective road: height, slope, curvature of the tandem under the belt centre; contact at the foot of the normal
    w, beta, r_c = _plane(hf, hr, ls, s["zb"], be)
    dw = (dhf + dhr) / 2
    cb, sb = be.cos(beta), be.sin(beta)
    curvature = cb**2 * (dhf - dhr) / ls

    # vertical residual element, normal to the effective plane
    rho_r = r_omega - r_c
    contact = rho_r > 0
    vcx = s["vxb"] * cb + s["vzb"] * sb
    damp = (prm.DAMP_RESIDUAL + prm.DAMP_VLOW * be.fmax(0.0, 1.0 - be.abs(vcx) / prm.VXLOW)) * f_d
    f_r, c_rz = residual_vertical(prm, rho_r, s["omb"], dpi, cbx, be)
    rho_r_dot = -(s["vzb"] - dw * s["vxb"]) / cb
    fzc = be.where(contact, be.fmax(f_r + damp * c_rz * rho_r_dot, 0.0), 0.0)

    # slip model: MF at the transient slips, rim camber (module notes), no second low-speed reduction
    # direction of travel and of spin: +-1, linear through standstill (below 0.1 VXLOW)
    s_v = be.fmin(be.fmax(vcx / (0.1 * prm.VXLOW), -1.0), 1.0)
    s_o = be.fmin(be.fmax(s["omb"] * prm.UNLOADED_RADIUS / (0.1 * prm.VXLOW), -1.0), 1.0)
    # static twist (module notes): the yaw deflection M_r / C_psi of the moment the residual spring carries
    c_psi = prm.YAW_STIFFNESS * (1.0 + prm.PCMZ1 * dpi)
    crpsi = 1.0 / (1.0 / c_psi - 1.0 / cbg)
    twist = s_v * crpsi * s["psr"] / c_psi
    alpha_mf = s["alpha"]
    beta_x = road_camber + v["road_camber"]
    mf = model.casadi_function(inputs=("fz", "kappa", "alpha", "gamma", "vx", "p", "omega"),
                               outputs=("fx", "fy", "mz", "mx", "my", "re", "a", "cx", "cy", "kxk", "kya"),
                               low_speed=False)  # (its speed is at least VXLOW: the low-speed factors are 1)
    fxc, fyc, mzc, mxc, myc, re, a, cx, cy, kxk, kya = mf(be.fmax(fzc, _FZ_FLOOR), s["kappa"], alpha_mf,
                                                 v["gamma"] - beta_x, be.fmax(be.abs(vcx), prm.VXLOW),
                                                 v["p"], s["omb"])
    if turn_slip:  # the MF's turn-slip increment at the patch's relaxed turn slip phi (module notes)
        mf_ts = model.casadi_function(inputs=("fz", "kappa", "alpha", "gamma", "phit", "vx", "p", "omega"),
                                      outputs=("fx", "fy", "mz"), turn_slip=True, low_speed=False)
        slip = (be.fmax(fzc, _FZ_FLOOR), s["kappa"], alpha_mf, v["gamma"] - beta_x)
        rest = (be.fmax(be.abs(vcx), prm.VXLOW), v["p"], s["omb"] * s_v)  # camber spin as rolling forward
        ref = TURN_SLIP_REFERENCE / prm.UNLOADED_RADIUS
        fade = be.fmin(be.abs(vcx) / prm.VXLOW, 1.0)  # the MF's low-speed turn slip, phit |Vx| / VXLOW
        on, off = mf_ts(*slip, s["phi"] * fade + ref, *rest), mf_ts(*slip, ref, *rest)
        fxc, fyc, mzc = fxc + (on[0] - off[0]), fyc + (on[1] - off[1]), mzc + (on[2] - off[2])
    mzc, myc = mzc * s_v, myc * s_o

    # residual springs in series with sidewall (+ rotation lever) and the contact patch (the slip model's static
    # stiffness K / sigma_c): 1/C = 1/c_b (+ r^2/c_rot) + 1/c_r + sigma_c/K, floored (module notes)
    sigma_c = be.fmax(a, be.abs(vcx) * h + 1e-4)
    crx = 1.0 / residual_compliance(cx, 1.0 / cbx + (r_c**2 / cbth if rc.lever_x else 0.0), sigma_c, kxk, be)
    cry = 1.0 / residual_compliance(cy, 1.0 / cby + (r_c**2 / cbg if rc.lever_y else 0.0), sigma_c, kya, be)
    uxdot = (fxc - crx * s["ux"]) / (damp * crx)
    uydot = (fyc - cry * s["uy"]) / (damp * cry)
    psrdot = (mzc - crpsi * s["psr"]) / (damp * crpsi)
    # turn slip: the contact patch's yaw rate (belt + residual yaw) over the speed, relaxed over sigma_c; in the
    # direction of travel (s_v), the speed held at VXLOW below it as in the MF (module notes)
    phi_dot = (be.where(contact, (s_v * (s["wpsb"] + psrdot) - be.fmax(be.abs(vcx), prm.VXLOW) * s["phi"]) / sigma_c,
                        -s["phi"] / AIR_TIME) if turn_slip else 0.0 * s["phi"])
    # effective rolling radius variation (module notes): the belt band runs at (Omega_b + beta_dot) R_e relative to
    # the turning plane, whose contact point moves along the road at V_cx + r_c beta_dot; beta_dot from the slope
    # filtered over the contact half-length a of travel (at least half a step's travel: stable RK4), paced by at least
    # 0.1 VXLOW (defined at standstill)
    sigma_f = be.fmax(a, be.abs(vcx) * h / 2 + 1e-4)
    lag = beta - s["betaf"]
    betaf_dot = be.where(contact, be.fmax(be.abs(vcx), 0.1 * prm.VXLOW) * lag / sigma_f, lag / AIR_TIME)
    beta_rate = be.where(contact, be.abs(vcx) * lag / sigma_f, 0.0)
    vsx = vcx - s["omb"] * re - prm.SWIFT_REVAR * beta_rate * (re - r_c)
    # reported: the free-rolling radius change on a road of the current effective curvature (steady value)
    kappa_s = curvature * cb  # d beta_y / ds along the effective road
    turn = prm.SWIFT_REVAR * kappa_s * (re - r_c)  # beta_dot (R_e - r_c) / V_cx on a constant curvature
    dre = re * turn / be.fmax(1.0 - turn, _TURN_FLOOR)  # V_cx / Omega_b = R_e + dre at zero slip
    vcy = s["vyb"] + r_c * s["wgb"] + uydot - vcx * (s["psb"] + s["psr"])
    kappa_dot = be.where(contact, (-(vsx + uxdot) - be.abs(vcx) * s["kappa"]) / sigma_c, -s["kappa"] / AIR_TIME)
    alpha_dot = be.where(contact, (vcy + be.abs(vcx) * (twist - s["alpha"])) / sigma_c, -s["alpha"] / AIR_TIME)

    # forces on the belt, global axes (plane tilted by beta_y forward, beta_x sideways); bottoming on the rim
    cx_, sx_ = be.cos(beta_x), be.sin(beta_x)
    fx_b, fz_b, fy_b = fxc * cb - fzc * sb * cx_, (fxc * sb + fzc * cb) * cx_ + fyc * sx_, fyc * cx_ - fzc * sx_
    fwx = cbx * (s["xb"] - s["xa"]) + kbx * (s["vxb"] - v["vx"])
    fwz = cbx * (s["zb"] - s["za"]) + kbx * (s["vzb"] - s["vza"])
    fwy = cby * (s["yb"] - s["ya"]) + kby * (s["vyb"] - v["vy"])
    mwy = cbth * s["thw"] + kbth * (s["omb"] - s["oma"])
    mwx = cbg * (s["gb"] - v["gamma"]) + kbg * s["wgb"]
    mwz = cbg * (s["psb"] - v["psi"]) + kbg * s["wpsb"]
    r_a = (s["za"] - w) / cb  # rim centre to the effective plane
    f_bottom = prm.BOTTOM_STIFF * be.fmax(prm.RIM_RADIUS + prm.BOTTOM_OFFST - r_a, 0.0)

    d = {
        "xb": s["vxb"], "vxb": (-fwx + fx_b) / rc.mb,
        "zb": s["vzb"], "vzb": (-fwz + fz_b) / rc.mb + prm.GRAVITY,
        "thw": s["omb"] - s["oma"], "omb": (-mwy - r_c * fxc + myc) / rc.iby,
        "oma": (v["torque"] + mwy) / rc.rim_inertia if rim == "torque" else 0.0 * s["oma"],
        "za": s["vza"],
        "vza": (-v["load"] + fwz + f_bottom * cb) / rc.axle_mass if axle == "load" else 0.0 * s["vza"],
        "xa": v["vx"], "ya": v["vy"], "ux": uxdot, "kappa": kappa_dot,
        "yb": s["vyb"], "vyb": (-fwy + fy_b) / rc.mb,
        "gb": s["wgb"], "wgb": (-mwx + r_c * fyc + mxc + rc.iby * s["omb"] * s["wpsb"]) / rc.ibx,
        "psb": s["wpsb"], "wpsb": (-mwz + mzc - rc.iby * s["omb"] * s["wgb"]) / rc.ibx,
        "uy": uydot, "alpha": alpha_dot, "psr": psrdot, "phi": phi_dot, "betaf": betaf_dot,
        "lsm": 0.0 * s["lsm"],
    }
    out = dict(fx=fwx - f_bottom * sb, fy=fwy, fz=fwz + f_bottom * cb, mx=mwx, my=mwy, mz=mwz, fx_c=fxc,
               fy_c=fyc, fz_c=fzc, mz_c=mzc, rho=r_omega - r_a, rl=r_c, re=re, a=a, ls=ls, w=w, beta=beta,
               kappa=s["kappa"], alpha=alpha_mf, vcx=vcx, curvature=curvature, dre=dre, beta_x=beta_x,
               x_c=s["xb"] + r_c * sb)
    return ca.vertcat(*(d[n] for n in STATE_NAMES)), ca.vertcat(*(out[n] for n in OUTPUT_NAMES))
