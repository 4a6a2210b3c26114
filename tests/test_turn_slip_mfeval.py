"""turn_slip_form="mfeval" on a tyre whose turn-slip residual torque peak D_rphi is small.

MFeval computes Cr = zeta7 = (2/pi) acos(Mz_phi90 / |D_rphi|) (4.104) without limiting the ratio; MATLAB's acos
of a ratio above 1 is complex and MFeval reports the real part of Mzr = Dr cos(Cr atan(Br alpha_r)). On its
public MF 6.2 sample file the ratio stays below 1 (QDZ10 = 1.03 keeps its K_zgamma,r0 large); on the TNO 205/60 R15
file (QDZ10 = QDZ11 = 0, QDZ9 = 0.008, so K_zgamma,r0 = Fz R0 QDZ8 QDZ9 dfz ~ 0) it is far above 1, and the real
part is Dr cosh((2/pi) acosh(ratio) atan(Br alpha_r)): MFeval's 182 N m where the clipped ratio gave 2 N m.
The expected values here are computed with NumPy's complex arccos from the equations (4.93)-(4.104) as MFeval
writes them, independently of the model's code path.
"""
from __future__ import annotations

import numpy as np
import pytest

import mftyre
from mftyre.backend import NUMPY
from mftyre.formula import Modes, lateral, normalisation, turnslip, vertical

from conftest import MFEVAL_DIR, SHARED, require_shared

TNO = SHARED / "reference" / "tir" / "TNO_car205_60R15.tir"


def _expected_mzr(model, fz, alpha, gamma, phit):
    """Dr Re[cos(Cr x)] with MFeval's complex Cr, from the model's own Dr, Br, muy, Gyk (kappa = 0, Vx = LONGVL)."""
    from mftyre.formula import aligning

    prm = model.params
    modes = Modes(turn_slip=True, turn_slip_form="mfeval")
    n = np.size(alpha)
    z = np.zeros(n)
    s = normalisation.condition_inputs(prm, fz + z, z, alpha + z, gamma + z, phit + z, prm.LONGVL + z,
                                       prm.INFLPRES + z, modes, NUMPY)
    omega, _, _ = vertical.spin_and_radius(prm, s, z, False, NUMPY)
    s.phi, s.eps_gamma = turnslip.spin_slip(prm, s, omega, modes, NUMPY)
    turnslip.zeta_factors(prm, s, NUMPY)
    lat = lateral.pure_lateral(prm, s, s.gamma_star, modes, NUMPY)
    _, gyk, _ = lateral.combined_lateral(prm, s, lat.Fy0, lat.muy, modes, NUMPY)
    c = aligning.aligning_coefficients(prm, s, lat, gyk, modes, NUMPY)
    R0, Fz = prm.UNLOADED_RADIUS, s.Fz_low
    mz_inf = prm.QCRP1 * np.abs(lat.muy) * R0 * Fz * np.sqrt(Fz / s.Fz0p) * prm.LMP  # (4.95)
    d_drp = mz_inf / np.sin(0.5 * np.pi * prm.QDRP1)  # (4.94)
    k_zgr0 = Fz * R0 * (prm.QDZ8 * prm.QDZ9 * s.dfz + prm.QDZ10 + prm.QDZ11 * s.dfz * np.abs(s.gamma)) * prm.LKZC
    d_rp = d_drp * np.sin(prm.QDRP1 * np.arctan(k_zgr0 / (prm.QDRP1 * d_drp * (1 - s.eps_gamma)) * R0 * s.phit))
    mz90 = mz_inf * (2 / np.pi) * np.arctan(prm.QCRP2 * R0 * np.abs(s.phit)) * gyk  # (4.103)
    cr = (2 / np.pi) * np.arccos(mz90 / np.abs(d_rp) + 0j)  # (4.104), complex beyond [-1, 1]
    x = np.arctan(c.Br * c.alpha_r)  # kappa = 0: alpha_r,eq = alpha_r
    return np.real(c.Dr * np.cos(cr * x)), mz90 / np.abs(d_rp)


def test_mfeval_form_reproduces_matlab_complex_acos_on_the_tno_file():
    model = mftyre.load_tir(require_shared(TNO))
    alpha = np.linspace(-0.2, 0.2, 41)
    for fz, gamma, phit in ((4100.0, 0.099, 0.0011), (3000.0, -0.05, 0.02), (6000.0, 0.02, -0.005)):
        out = model.evaluate(fz, 0.0, alpha, gamma, phit, turn_slip=True, turn_slip_form="mfeval")
        expected, ratio = _expected_mzr(model, fz, alpha, gamma, phit)
        assert np.all(np.abs(ratio) > 1)  # the regime the public tables never reach
        np.testing.assert_allclose(out.mzr, expected, rtol=1e-12, atol=1e-9)
    # the point: hundreds of N m where the clipped acos gave a few
    out = model.evaluate(4100.0, 0.0, alpha, 0.099, 0.0011, turn_slip=True, turn_slip_form="mfeval")
    assert out.mzr.max() > 150.0
    published = model.evaluate(4100.0, 0.0, alpha, 0.099, 0.0011, turn_slip=True)
    assert np.abs(published.mzr).max() < 20.0


def test_public_file_ratio_stays_below_one():
    """Why the public tables could not show it: on MFeval's MF 6.2 sample the ratio is within [-1, 1]."""
    model = mftyre.load_tir(require_shared(MFEVAL_DIR / "MagicFormula62_Parameters.tir"))
    alpha = np.linspace(-0.2, 0.2, 41)
    for fz, gamma, phit in ((4100.0, 0.099, 0.0011), (3000.0, -0.05, 0.02)):
        out = model.evaluate(fz, 0.0, alpha, gamma, phit, turn_slip=True, turn_slip_form="mfeval")
        expected, ratio = _expected_mzr(model, fz, alpha, gamma, phit)
        assert np.all(np.abs(ratio) <= 1)
        np.testing.assert_allclose(out.mzr, expected, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("form", ["published", "mfeval"])
def test_casadi_agrees_in_the_complex_regime(form):
    model = mftyre.load_tir(require_shared(TNO))
    f = model.casadi_function(("alpha",), ("mzr",), fixed=dict(fz=4100.0, kappa=0.0, gamma=0.099, phit=0.0011),
                              turn_slip=True, turn_slip_form=form)
    alpha = np.linspace(-0.2, 0.2, 9)
    out = model.evaluate(4100.0, 0.0, alpha, 0.099, 0.0011, turn_slip=True, turn_slip_form=form)
    np.testing.assert_allclose([float(f(a)) for a in alpha], out.mzr, rtol=1e-12, atol=1e-9)
