"""Rigid-ring tyre (SWIFT structure) with the Magic Formula as contact-patch slip model: the equations.

Bodies (Pacejka 2012 ch. 9; Zegelaar 1998; Maurice 2000; NOTES sec. 4): the rim (axle) with imposed or free
vertical motion and imposed or torque-driven spin; the belt, a rigid ring with mass m_b = BELT_MASS, diametral
inertia I_bx = BELT_IXX, polar inertia I_by = BELT_IYY, six degrees of freedom; a massless contact patch joined
to the belt by residual springs; the effective road from the tandem cams (:mod:`swift.enveloping`).
ISO-W axes (x forward, y left, z up), small angles, forward rolling = positive spin about +y.

State (``STATE_NAMES``): belt x_b, z_b, y_b [m], velocities; wind-up theta_w = theta_b - theta_a; belt and rim
spin Omega_b, Omega_a; axle z_a, its velocity, axle x_a; belt camber gamma_b and yaw psi_b with rates; residual
(patch) deflections u_x, u_y; transient slips kappa', alpha'.

Sidewall (rim -> belt) [chosen from the parameter comments "undamped frequency / dimensionless damping of the
... mode", NOTES sec. 4.2]:
    c_bx = c_bz = m_b (2 pi FREQ_LONG)^2,  c_by = m_b (2 pi FREQ_LAT)^2,  c_bg = c_bpsi = I_bx (2 pi FREQ_YAW)^2,
    c_bth = I_by (2 pi FREQ_WINDUP)^2,     k_b = 2 DAMP_* sqrt(c_b M)
Residual springs in series so that the static stiffness of ring + residual is the steady-state model's:
    vertical  rho_MF(F) = rho_r(F) + F / c_bz: the residual characteristic F_r(rho_r) is the inverse of
              rho_MF(F) - F/c_bz, with rho_MF the MF 6.1 load-deflection relation (A3.3, pressure and speed
              terms; = MF 6.2 at zero camber and side force) [chosen], solved by 6 Newton steps from F = 0
              (monotone from below: rho_MF is concave in F)
    1/C_x = 1/c_bx + r_c^2/c_bth + 1/c_rx,  1/C_y = 1/c_by + r_c^2/c_bg + 1/c_ry   (C_x, C_y of paper (17),
              (18) at the current load and pressure; lever terms dropped, with a warning, where they would make
              a residual stiffness non-positive [chosen guard])
    residual damping k_r = (DAMP_RESIDUAL + DAMP_VLOW max(0, 1 - |V|/VXLOW)) c_r [chosen: stiffness
    proportional, DAMP_VLOW faded in linearly below VXLOW]
Contact (effective plane through the tandem midpoint, slope beta_y; road camber beta_x an input):
    rho_r = R_Omega - (z_b - w) cos(beta_y)   (normal distance from the belt centre, contact below the belt
              centre [chosen]); r_c = R_Omega - rho_r lever arm of the contact forces [chosen]
    F'_z = max(0, F_r(rho_r) + k_rz d(rho_r)/dt)   (no pull)
    V_cx = xdot_b cos(beta_y) + zdot_b sin(beta_y),  V_sx = V_cx - Omega_b R_e   (R_e of paper (7))
    massless patch:  c_rx u_x + k_rx udot_x = F'_x = MF_x(kappa', alpha', ...), likewise y
    sigma_c dkappa'/dt + |V_cx| kappa' = -(V_sx + udot_x)
    sigma_c dalpha'/dt + |V_cx| alpha' = ydot_b + r_c gammadot_b + udot_y - V_cx psi_a   (mftyre's alpha sign)
    with sigma_c = a (half contact length) [chosen, NOTES sec. 4.4].
    The slip model gets the rim camber and heading, not the belt's: the steady-state Magic Formula was measured
    against the rim angles, so feeding back the static yaw/camber deflection would count that compliance twice
    [chosen]. Hence YAW_STIFFNESS (yaw residual) has no effect and is not used; Mz acts on the belt directly.
    Forces on the belt (global): F_x = F'_x cos(beta_y) - F'_z sin(beta_y), F_z = F'_x sin(beta_y) +
    F'_z cos(beta_y); moments -r_c F'_x + My about y, r_c F_y + Mx about x, Mz about z.
Equations of motion (NOTES sec. 4.3, gyroscopic terms from dH/dt = M with H = I_by Omega (-psi, 1, gamma)):
    m_b xddot_b = -c_bx (x_b - x_a) - k_bx (xdot_b - xdot_a) + F_x
    m_b zddot_b = -c_bz (z_b - z_a) - k_bz (zdot_b - zdot_a) + F_z + m_b GRAVITY
    I_by Omegadot_b = -c_bth theta_w - k_bth (Omega_b - Omega_a) - r_c F'_x + My
    m_b yddot_b = -c_by (y_b - y_a) - k_by (ydot_b - ydot_a) + F_y
    I_bx gammaddot_b = -c_bg (gamma_b - gamma_a) - k_bg gammadot_b + r_c F_y + Mx + I_by Omega_b psidot_b
    I_bx psiddot_b = -c_bpsi (psi_b - psi_a) - k_bpsi psidot_b + Mz - I_by Omega_b gammadot_b
    axle "load":   m_a zddot_a = -F_load + F_wz  (F_wz = c_bz (z_b - z_a) + k_bz (zdot_b - zdot_a); gravity acts
                   on the belt only, F_load is everything else pushing the rim down)
    rim "torque":  I_a Omegadot_a = T + c_bth theta_w + k_bth (Omega_b - Omega_a)
Not modelled (open in the literature, NOTES sec. 9): Q_BVX/Q_BVT (load and speed influence on the sidewall
stiffness), rotating-damper coupling terms, the effective-rolling-radius change with road curvature, turn slip
from the belt yaw rate, ENV_C1/ENV_C2.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from mftyre.errors import ModelInputError
from mftyre.formula import vertical

__all__ = ["RingConstants", "STATE_NAMES", "INPUT_NAMES", "OUTPUT_NAMES", "ring_equations", "tandem_base_now"]

STATE_NAMES = ("xb", "vxb", "zb", "vzb", "thw", "omb", "oma", "za", "vza", "xa",
               "ux", "kappa", "yb", "vyb", "gb", "wgb", "psb", "wpsb", "uy", "alpha")
#: Inputs of one step. x/z/omega of the axle enter through the state (imposed parts are set by the stepper).
INPUT_NAMES = ("vx", "load", "torque", "p", "y", "vy", "gamma", "psi", "road_camber")
OUTPUT_NAMES = ("fx", "fy", "fz", "mx", "my", "mz",            # forces and moments of the tyre on the rim
                "fx_c", "fy_c", "fz_c", "mz_c",                # contact forces in the effective plane
                "rho", "rl", "re", "a", "ls", "w", "beta",     # deflection, radii, patch, effective road
                "kappa", "alpha", "vcx")
_S = {n: i for i, n in enumerate(STATE_NAMES)}
_NEWTON_STEPS = 6
#: Load floor [N] of the slip model and contact length: keeps derivatives finite off the road (sqrt(Fz) at 0).
_FZ_FLOOR = 1e-3


@dataclass(frozen=True)
class RingConstants:
    """Sidewall constants from [INERTIA]/[STRUCTURAL] and the options of the rim and axle bodies."""

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
        if not (1 / out.cx - 1 / cbx > 0).all() or not (1 / out.cy - 1 / cby > 0).all():
            raise ModelInputError("LONGITUDINAL/LATERAL_STIFFNESS exceed the sidewall stiffness from FREQ_*: "
                                  "no positive residual stiffness exists")
        if not prm.DAMP_RESIDUAL > 0:
            raise ModelInputError("DAMP_RESIDUAL must be positive: the massless contact patch needs residual "
                                  "damping")
        return cls(mb, ibx, iby, cbx, cby, cbg, cbth, damp(cbx, mb, "LONG"), damp(cby, mb, "LAT"),
                   damp(cbg, ibx, "YAW"), damp(cbth, iby, "WINDUP"), lever_x, lever_y, float(axle_mass),
                   float(prm.IYY - prm.BELT_IYY + rim_extra_inertia))


def _residual_vertical(prm, rc: RingConstants, rho_r, r_omega, omega, dpi, be):
    """(F_r, dF_r/drho_r): inverse of rho_MF(F) - F/c_bz = rho_r by Newton from F = 0 (module notes)."""
    import casadi as ca

    F, ro, om, dp = (ca.SX.sym(n) for n in ("F", "r_omega", "omega", "dpi"))
    g = vertical.deflection_61(prm, F, ro, om, 0.0, 0.0, dp, be) - F / rc.cbx
    fun = ca.Function("residual", [F, ro, om, dp], [g, ca.jacobian(g, F)])
    target = be.fmax(rho_r, 0.0)
    f = 0.0 * rho_r
    for _ in range(_NEWTON_STEPS):
        gv, dgv = fun(f, r_omega, omega, dpi)
        f = f - (gv - target) / dgv
    _, dgv = fun(f, r_omega, omega, dpi)
    inside = rho_r > 0
    return be.where(inside, f, 0.0), be.where(inside, 1.0 / dgv, 0.0)


def tandem_base_now(model, state, u, h_c):
    """l_s for the current state: ELLIPS_SHIFT 2a at the load of the static tyre whose deflection is the rim-to-cam
    distance at the contact centre (cam height ``h_c``) [chosen: one explicit pass of the l_s-load loop]."""
    from mftyre.backend import casadi_backend

    be = casadi_backend()
    prm = model.params
    s = {n: state[i] for i, n in enumerate(STATE_NAMES)}
    dpi = (u[INPUT_NAMES.index("p")] - prm.NOMPRES) / prm.NOMPRES
    r_omega = vertical.free_radius(prm, s["omb"], be)
    fz_est = be.fmax(vertical.vertical_force_61(prm, be.fmax(r_omega - (s["za"] - h_c), 0.0), r_omega, s["omb"],
                                                0.0, 0.0, dpi, be), 0.0)
    a_est, _ = vertical.contact_patch(prm, be.fmax(fz_est, _FZ_FLOOR), dpi, be)
    return be.fmax(prm.ELLIPS_SHIFT * 2.0 * a_est, 1e-6)


def ring_equations(model, rc: RingConstants, state, u, hf, dhf, hr, dhr, ls, *, axle: str, rim: str):
    """State derivative and outputs (CasADi vectors) of the ring at ``state`` (STATE_NAMES) and inputs ``u``
    (INPUT_NAMES), with the front/rear cam heights ``hf``, ``hr`` and their slopes along x at the cam positions
    x_b +- ``ls``/2. ``axle``: "height" (imposed, z_a and its rate from the state, held by the stepper) or
    "load"; ``rim``: "speed" (imposed spin) or "torque"."""
    import casadi as ca
    from mftyre.backend import casadi_backend

    be = casadi_backend()
    prm = model.params
    s = {n: state[i] for i, n in enumerate(STATE_NAMES)}
    v = {n: u[i] for i, n in enumerate(INPUT_NAMES)}
    dpi = (v["p"] - prm.NOMPRES) / prm.NOMPRES
    r_omega = vertical.free_radius(prm, s["omb"], be)
    w, dw = (hf + hr) / 2, (dhf + dhr) / 2
    beta = be.atan((hf - hr) / ls)
    cb, sb = be.cos(beta), be.sin(beta)

    # vertical residual element, normal to the effective plane
    rho_r = r_omega - (s["zb"] - w) * cb
    rc_lever = r_omega - rho_r
    vcx = s["vxb"] * cb + s["vzb"] * sb
    damp = prm.DAMP_RESIDUAL + prm.DAMP_VLOW * be.fmax(0.0, 1.0 - be.abs(vcx) / prm.VXLOW)
    f_r, c_rz = _residual_vertical(prm, rc, rho_r, r_omega, s["omb"], dpi, be)
    rho_r_dot = -(s["vzb"] - dw * s["vxb"]) * cb
    fzc = be.where(rho_r > 0, be.fmax(f_r + damp * c_rz * rho_r_dot, 0.0), 0.0)

    mf = model.casadi_function(inputs=("fz", "kappa", "alpha", "gamma", "vx", "p", "omega"),
                               outputs=("fx", "fy", "mz", "mx", "my", "re", "a", "cx", "cy"))
    gamma = v["gamma"] - v["road_camber"]
    fxc, fyc, mzc, mxc, myc, re, a, cx, cy = mf(be.fmax(fzc, _FZ_FLOOR), s["kappa"], s["alpha"], gamma, vcx, v["p"], s["omb"])

    # residual springs in series with sidewall (+ rotation lever): 1/C = 1/c_b (+ r^2/c_rot) + 1/c_r
    crx = 1.0 / (1.0 / cx - 1.0 / rc.cbx - (rc_lever**2 / rc.cbth if rc.lever_x else 0.0))
    cry = 1.0 / (1.0 / cy - 1.0 / rc.cby - (rc_lever**2 / rc.cbg if rc.lever_y else 0.0))
    uxdot = (fxc - crx * s["ux"]) / (damp * crx)
    uydot = (fyc - cry * s["uy"]) / (damp * cry)
    sigma_c = be.fmax(a, 1e-3)
    vsx = vcx - s["omb"] * re
    kappa_dot = (-(vsx + uxdot) - be.abs(vcx) * s["kappa"]) / sigma_c
    vcy = s["vyb"] + rc_lever * s["wgb"] + uydot - vcx * v["psi"]
    alpha_dot = (vcy - be.abs(vcx) * s["alpha"]) / sigma_c

    # forces on the belt, global axes
    fx_b, fz_b = fxc * cb - fzc * sb, fxc * sb + fzc * cb
    fwx = rc.cbx * (s["xb"] - s["xa"]) + rc.kbx * (s["vxb"] - v["vx"])
    fwz = rc.cbx * (s["zb"] - s["za"]) + rc.kbx * (s["vzb"] - s["vza"])
    fwy = rc.cby * (s["yb"] - v["y"]) + rc.kby * (s["vyb"] - v["vy"])
    mwy = rc.cbth * s["thw"] + rc.kbth * (s["omb"] - s["oma"])
    mwx = rc.cbg * (s["gb"] - v["gamma"]) + rc.kbg * s["wgb"]
    mwz = rc.cbg * (s["psb"] - v["psi"]) + rc.kbg * s["wpsb"]

    d = {
        "xb": s["vxb"], "vxb": (-fwx + fx_b) / rc.mb,
        "zb": s["vzb"], "vzb": (-fwz + fz_b) / rc.mb + prm.GRAVITY,
        "thw": s["omb"] - s["oma"], "omb": (-mwy - rc_lever * fxc + myc) / rc.iby,
        "oma": (v["torque"] + mwy) / rc.rim_inertia if rim == "torque" else 0.0 * s["oma"],
        "za": s["vza"], "vza": (-v["load"] + fwz) / rc.axle_mass if axle == "load" else 0.0 * s["vza"],
        "xa": v["vx"], "ux": uxdot, "kappa": kappa_dot,
        "yb": s["vyb"], "vyb": (-fwy + fyc) / rc.mb,
        "gb": s["wgb"], "wgb": (-mwx + rc_lever * fyc + mxc + rc.iby * s["omb"] * s["wpsb"]) / rc.ibx,
        "psb": s["wpsb"], "wpsb": (-mwz + mzc - rc.iby * s["omb"] * s["wgb"]) / rc.ibx,
        "uy": uydot, "alpha": alpha_dot,
    }
    rho = r_omega - (s["za"] - w) * cb
    out = dict(fx=fwx, fy=fwy, fz=fwz, mx=mwx, my=mwy, mz=mwz, fx_c=fxc, fy_c=fyc, fz_c=fzc, mz_c=mzc,
               rho=rho, rl=rc_lever, re=re, a=a, ls=ls, w=w, beta=beta, kappa=s["kappa"], alpha=s["alpha"],
               vcx=vcx)
    return ca.vertcat(*(d[n] for n in STATE_NAMES)), ca.vertcat(*(out[n] for n in OUTPUT_NAMES))

