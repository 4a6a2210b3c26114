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


#: What each part of the evaluation is needed for: an output is computed only when asked for (``outputs``) or
#: needed by one that is.
_NEEDS_FX = frozenset({"fx", "mz", "t", "mzr", "my", "rl", "rho", "cz", "mux", "kxk", "cx", "cy", "sigmax",
                       "sigmay"})
_NEEDS_FY = frozenset({"fy", "mz", "t", "mzr", "mx", "rl", "rho", "cz", "muy", "kya", "cx", "cy", "sigmax",
                       "sigmay"})
_NEEDS_MZ = frozenset({"mz", "t", "mzr"})
_NEEDS_DEFLECTION = frozenset({"rl", "rho", "cz"})
_NEEDS_PATCH = frozenset({"a", "b"})
_NEEDS_CARCASS = frozenset({"cx", "cy", "sigmax", "sigmay"})


def steady_state(prm, fz, kappa, alpha, gamma, phit, vx, p, omega, omega_given, modes, be, outputs=None) -> dict:
    """All outputs at the given inputs (ISO-W, SI), or only ``outputs`` (names of :data:`OUTPUT_NAMES`; the parts
    of the evaluation no asked output needs are skipped, the values of the others are the same).

    ``omega_given`` is True (use ``omega``), False (estimate it from kappa and Vx) or a boolean array
    choosing per element. With limits the fitted force and moment equations (Fx, Fy, Mz, Mx) and the relaxation
    outputs use the load saturated at FZMAX; Re and the spin estimated from it, the loaded radius, deflection and
    vertical stiffness, the contact patch and My use the load as given (the reference evaluator's split); the
    output fz is the load as given.
    """
    want = frozenset(OUTPUT_NAMES if outputs is None else outputs)
    s = normalisation.condition_inputs(prm, fz, kappa, alpha, gamma, phit, vx, p, modes, be)
    omega, r_omega, re = vertical.spin_and_radius(prm, s, omega, omega_given, be)
    if modes.turn_slip:
        s.phi, s.eps_gamma = turnslip.spin_slip(prm, s, omega, modes, be)
        turnslip.zeta_factors(prm, s, be)
    out = dict(fz=s.uFz, kappa=s.kappa_out, alpha=s.alpha_out, gamma=s.ugamma, phit=s.phit, vx=s.vx, p=s.p,
               omega=omega, re=re)

    if want & _NEEDS_FX:
        lon = longitudinal.pure_longitudinal(prm, s, modes, be)
        fx = longitudinal.combined_longitudinal(prm, s, lon.Fx0, modes, be)
        out.update(fx=fx, mux=lon.mux, kxk=lon.Kxk)
    if want & _NEEDS_FY:
        lat = lateral.pure_lateral(prm, s, s.gamma_star, modes, be)
        fy, gyk, svyk = lateral.combined_lateral(prm, s, lat.Fy0, lat.muy, modes, be)
        out.update(fy=fy, muy=be.abs(lat.muy) if modes.limits else lat.muy, kya=lat.Kya)
    if want & _NEEDS_MZ:
        coeffs = aligning.aligning_coefficients(prm, s, lat, gyk, modes, be)
        # F'y of the pneumatic-trail moment at gamma = phi = 0 (4.E32, 4.E74): with turn slip, the published form
        # leaves the spin's side force out of it (the camber moment is then D_rphi's, as without turn slip it is
        # D_r's); the reference evaluator keeps S_Hyphi there (mfeval form)
        published = modes.turn_slip and modes.turn_slip_form == "published"
        trail_modes = replace(modes, turn_slip=False) if published else modes
        fy0_gamma0 = None if prm.version == "52" else lateral.pure_lateral(prm, s, be.exact(0.0), trail_modes,
                                                                            be).Fy0
        mz, t, mzr = aligning.aligning_torque(prm, s, coeffs, lon.Kxk, fx, fy, svyk, fy0_gamma0, gyk, modes, be)
        out.update(mz=mz, t=t, mzr=mzr)
    if "mx" in want:
        out["mx"] = moments.overturning_moment(prm, s, fy, be)
    if "my" in want:
        out["my"] = moments.rolling_resistance_moment(prm, s, fx, be)
    if want & _NEEDS_DEFLECTION:
        fz_cz = s.uFz if prm.version == "62" else s.uFz_low  # FZMIN raises the load of the MF 6.1 deflection only
        rl, rho = vertical.loaded_radius(prm, fz_cz, r_omega, omega, fx, fy, s.gamma, s.dpi, be)
        out.update(rl=rl, rho=rho, cz=fz_cz / be.where(fz_cz == 0, 1e-6, rho))
    if want & _NEEDS_PATCH:
        out["a"], out["b"] = vertical.contact_patch(prm, s.uFz, s.dpi, be)
    if want & _NEEDS_CARCASS:
        out["cx"], out["cy"], out["sigmax"], out["sigmay"] = derived.carcass_stiffness_and_relaxation(
            prm, s, lon.Kxk, lat.Kya, be)
    return {name: out[name] for name in OUTPUT_NAMES if name in want}
