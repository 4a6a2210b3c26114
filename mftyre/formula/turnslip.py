"""Turn slip and camber spin: the spin slip phi and the reduction factors zeta (Pacejka 2012, Section 4.3.3).

With turn slip switched off every zeta is 1 (zeta0 = 1 as well): the pure/combined-slip model for small camber.

Two forms (``Modes.turn_slip_form``):

* "published" (default): the spin as printed, phi = -(1/Vc') (psi_dot - (1 - eps_gamma) omega sin(gamma)) (4.76)
  with psi_dot = -phit Vc' (4.75), i.e. phi = phit + (1 - eps_gamma) omega sin(gamma) / Vc'. This is the form in
  which the model is consistent with itself: at zero turn slip the camber spin reproduces, to first order, the
  camber thrust and camber moment of the model without turn slip (S_Hyphi -> Kyg0 gamma / Kya, D_rphi -> the
  camber part of D_r, Cr -> 1), provided the pneumatic trail multiplies F'y at gamma = phi = 0 (4.E32, 4.E74);
  ``tests/test_turn_slip.py`` checks both. Below VXLOW the speed is held at
  Vc' = max(Vc, VXLOW) (continuous, positive in both directions of travel).
* "mfeval": the reference evaluator's choices, reproduced for comparison: (4.76) without the minus sign (its
  authors' reading of the axis systems), Vc' = VXLOW sign(Vx) below VXLOW, D_rphi from phit instead of phi,
  K_zgamma,r0 = Fz R0 (QDZ8 QDZ9 dfz + QDZ10 + QDZ11 dfz |gamma|) LKZC instead of (4.99), F'y of the trail
  moment with the spin's S_Hyphi in it (the camber thrust counted again through the trail), and Cr (4.104) taken
  through MATLAB's complex acos where Mz90/|D_rphi| > 1 (Mzr = Dr cos(a x) cosh(b x), the real part MFeval
  reports). The last matters on files with QDZ10 = QDZ11 = 0 and a small QDZ9 (TNO's 205/60 R15 MF 6.2 example):
  there K_zgamma,r0 ~ 0, D_rphi ~ 0, the ratio is far above 1 and Mzr grows with the slip angle (182 N m at
  Fz = 4.1 kN, gamma = 0.099 rad, phit = 0.0011 1/m), while on MFeval's public sample files (QDZ10 = 1.03) the
  ratio stays below 1, which is why its tables could not show it.

The published form follows Pacejka (2012) (4.76)-(4.106) and Besselink et al. (2010); where (4.104)'s ratio leaves
[-1, 1] it holds it there, so that Cr stays a real shape factor (0..2) and |Mzr| <= |Dr|.
"""
from __future__ import annotations

__all__ = ["spin_slip", "zeta_factors", "lateral_shift_turn_slip"]


def spin_slip(prm, s, omega, modes, be):
    """phi (4.76) and the camber reduction factor eps_gamma (4.90)."""
    eps_gamma = prm.PECP1 * (1.0 + prm.PECP2 * s.dfz)  # (4.90)
    vsy = -s.tan_alpha * be.of("speed").abs(s.vx)
    vc = be.sqrt0(s.vx**2 + vsy**2)
    camber_spin = (1.0 - eps_gamma) * omega * be.sin(s.gamma)
    if modes.turn_slip_form == "published":
        vc_prime = be.fmax(vc, prm.VXLOW)  # singularity protection, continuous
        psi_dot = -s.phit * vc_prime  # (4.75)
        phi = -(psi_dot - camber_spin) / vc_prime  # (4.76)
    else:
        vc_prime = be.where(be.abs(s.vx) < prm.VXLOW, prm.VXLOW * be.sign_nz(s.vx), vc)
        psi_dot = -s.phit * vc_prime
        phi = (psi_dot - camber_spin) / vc_prime
    return phi, eps_gamma


def zeta_factors(prm, s, be):
    """zeta1, zeta2, zeta3, zeta5, zeta6 from the spin phi (stored in ``s``)."""
    R0, phi = prm.UNLOADED_RADIUS, s.phi
    bxp = prm.PDXP1 * (1.0 + prm.PDXP2 * s.dfz) * be.cos_atan(prm.PDXP3 * s.kappa)  # (4.106)
    s.zeta1 = be.cos_atan(bxp * R0 * phi)  # (4.105)
    byp = prm.PDYP1 * (1.0 + prm.PDYP2 * s.dfz) * be.cos_atan(prm.PDYP3 * s.tan_alpha)  # (4.78)
    s.zeta2 = be.cos_atan(byp * (R0 * be.abs(phi) + prm.PDYP4 * be.sqrt(R0 * be.abs(phi))))  # (4.77)
    s.zeta3 = be.cos_atan(prm.PKYP1 * R0**2 * phi**2)  # (4.79)
    s.zeta5 = be.cos_atan(prm.QDTP1 * R0 * phi)  # (4.91)
    s.zeta6 = be.cos_atan(prm.QBRP1 * R0 * phi)  # (4.102)


def lateral_shift_turn_slip(prm, s, kya, kya0, kyg0, svyg, limits, be):
    """zeta4 = 1 + S_Hyphi - S_Vygamma / K'_ya (4.84) with S_Hyphi from (4.80)-(4.89)."""
    R0, phi = prm.UNLOADED_RADIUS, s.phi
    kya_prime = kya + 1e-6 * be.sign_nz(kya)  # (4.E39)
    kya0_prime = kya0 + 1e-6 * be.sign_nz(kya0)
    c_hyp = prm.PHYP1  # (4.85)
    d_hyp = (prm.PHYP2 + prm.PHYP3 * s.dfz) * be.of("speed").sign_nz(s.vx)  # (4.86); +1 at standstill keeps B_Hyphi finite
    e_hyp = min(prm.PHYP4, 1.0) if limits else prm.PHYP4  # (4.87)
    k_yrp0 = kyg0 / (1.0 - s.eps_gamma)  # (4.89)
    b_hyp = k_yrp0 / (c_hyp * d_hyp * kya0_prime)  # (4.88)
    x = b_hyp * R0 * phi
    s_hyp = d_hyp * be.sin(c_hyp * be.atan(x - e_hyp * (x - be.atan(x)))) * be.of("speed").sign(s.vx)  # (4.80)
    return 1.0 + s_hyp - svyg / kya_prime  # (4.84)
