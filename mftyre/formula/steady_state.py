"""Steady-state evaluation: conditioned inputs -> every output of the model, for any backend."""
from __future__ import annotations

from dataclasses import replace

from . import aligning, derived, lateral, longitudinal, moments, normalisation, turnslip, vertical

__all__ = ["steady_state", "OUTPUT_NAMES"]

#: Every output, in the order of :class:`mftyre.model.MFOutputs`.
OUTPUT_NAMES = (
    "fx", "fy", "fz", "mx", "my", "mz",
    "kappa", "alpha", "gamma", "phit", "vx", "p", "omega",
    "re", "rho", "rl", "a", "b", "t", "mzr", "mux", "muy",
    "cx", "cy", "cz", "kya", "kxk", "sigmax", "sigmay",
)


def steady_state(prm, fz, kappa, alpha, gamma, phit, vx, p, omega, omega_given, modes, be) -> dict:
    """All outputs at the given inputs (ISO-W, SI).

    ``omega_given`` is True (use ``omega``), False (estimate it from kappa and Vx) or a boolean array
    choosing per element. With limits the fitted force and moment equations (Fx, Fy, Mz, Mx) and the relaxation
    outputs use the load saturated at FZMAX; Re and the spin estimated from it, the loaded radius, deflection and
    vertical stiffness, the contact patch and My use the load as given (the reference evaluator's split); the
    output fz is the load as given.
    """
    s = normalisation.condition_inputs(prm, fz, kappa, alpha, gamma, phit, vx, p, modes, be)
    omega, r_omega, re = vertical.spin_and_radius(prm, s, omega, omega_given, be)
    if modes.turn_slip:
        s.phi, s.eps_gamma = turnslip.spin_slip(prm, s, omega, modes, be)
        turnslip.zeta_factors(prm, s, be)

    lon = longitudinal.pure_longitudinal(prm, s, modes, be)
    lat = lateral.pure_lateral(prm, s, s.gamma_star, modes, be)
    fx = longitudinal.combined_longitudinal(prm, s, lon.Fx0, modes, be)
    fy, gyk, svyk = lateral.combined_lateral(prm, s, lat.Fy0, lat.muy, modes, be)

    coeffs = aligning.aligning_coefficients(prm, s, lat, gyk, modes, be)
    # F'y of the pneumatic-trail moment at gamma = phi = 0 (4.E32, 4.E74): with turn slip, the published form
    # leaves the spin's side force out of it (the camber moment is then D_rphi's, as without turn slip it is D_r's);
    # the reference evaluator keeps S_Hyphi there (mfeval form)
    published = modes.turn_slip and modes.turn_slip_form == "published"
    trail_modes = replace(modes, turn_slip=False) if published else modes
    fy0_gamma0 = None if prm.version == "52" else lateral.pure_lateral(prm, s, be.exact(0.0), trail_modes, be).Fy0
    mz, t, mzr = aligning.aligning_torque(prm, s, coeffs, lon.Kxk, fx, fy, svyk, fy0_gamma0, gyk, modes, be)
    mx = moments.overturning_moment(prm, s, fy, be)
    my = moments.rolling_resistance_moment(prm, s, fx, be)

    fz_cz = s.uFz if prm.version == "62" else s.uFz_low  # FZMIN raises the load of the MF 6.1 deflection only
    rl, rho = vertical.loaded_radius(prm, fz_cz, r_omega, omega, fx, fy, s.gamma, s.dpi, be)
    cz = fz_cz / be.where(fz_cz == 0, 1e-6, rho)
    a, b = vertical.contact_patch(prm, s.uFz, s.dpi, be)
    cx, cy, sigmax, sigmay = derived.carcass_stiffness_and_relaxation(prm, s, lon.Kxk, lat.Kya, be)

    muy = be.abs(lat.muy) if modes.limits else lat.muy
    return dict(
        fx=fx, fy=fy, fz=s.uFz, mx=mx, my=my, mz=mz,
        kappa=s.kappa_out, alpha=s.alpha_out, gamma=s.ugamma, phit=s.phit, vx=s.vx, p=s.p, omega=omega,
        re=re, rho=rho, rl=rl, a=a, b=b, t=t, mzr=mzr, mux=lon.mux, muy=muy,
        cx=cx, cy=cy, cz=cz, kya=lat.Kya, kxk=lon.Kxk, sigmax=sigmax, sigmay=sigmay,
    )
