"""Where each value of a fitted parameter set comes from, what the data did not determine, and what that means.

:func:`provenance_of` gives every parameter of a :class:`mftyre.fit.FitResult` one of four origins, written beside
it in the .tir (:meth:`mftyre.fit.FitResult.write_tir`):

* ``fitted +- s.e. (stage)``: fitted in an accepted stage, with its standard error (effective samples);
* ``estimated from the data`` / ``from the tyre size`` / ``given``: set before the fit from the data or the user
  (:func:`mftyre.fit.start_parameters` records which);
* ``held at its start value``: a parameter a stage could fit that the data did not determine (with why), or a
  parameter of a stage not run, taken from the start file;
* ``default placeholder``: a schema default (a neutral value, or a car tyre's value where the schema has no
  neutral one) that nothing in the data touched.

:func:`unidentified` names the parameters presented as fitted whose value the data do not pin down (at a bound of
the fit, or with a standard error above their size) and those held because of it, each with the measurement that
would pin it (:data:`MEASUREMENTS`). :func:`closing_summary` says which groups a vehicle model uses were not fitted
(vertical, relaxation, carcass, mass and inertia, ...) and what follows for a simulation.
"""
from __future__ import annotations

from ..params import PARAMETERS

__all__ = ["provenance_of", "unidentified", "closing_summary", "MEASUREMENTS", "GROUPS", "PLACEHOLDER"]

PLACEHOLDER = "default placeholder"

#: Parameter families (name prefixes, tried longest first) -> the measurement that determines them.
MEASUREMENTS = {
    "PKY": "slip-angle sweeps at three or more loads (the cornering-stiffness law), beyond the peak of the "
           "cornering stiffness over load",
    "PKY5": "slip-angle sweeps at two or more non-zero camber angles",
    "PPY": "pure slip-angle sweeps at three pressures",
    "PCY": "slip-angle sweeps beyond the peak of Fy", "PDY": "slip-angle sweeps beyond the peak of Fy",
    "PEY": "slip-angle sweeps beyond the peak of Fy, both signs",
    "PHY": "slip-angle sweeps of both signs", "PVY": "slip-angle sweeps of both signs",
    "PKX": "slip-ratio sweeps at three or more loads", "PPX": "slip-ratio sweeps at three pressures",
    "PCX": "slip-ratio sweeps beyond the peak of Fx", "PDX": "slip-ratio sweeps beyond the peak of Fx",
    "PEX": "slip-ratio sweeps beyond the peak, braking and driving",
    "PHX": "slip-ratio sweeps of both signs", "PVX": "slip-ratio sweeps of both signs",
    "QBZ": "Mz of slip-angle sweeps at three or more loads, beyond the Mz peak",
    "QCZ": "Mz of slip-angle sweeps beyond the Mz peak", "QEZ": "Mz of slip-angle sweeps beyond the Mz peak",
    "QDZ": "Mz of slip-angle sweeps at several loads and cambers", "QHZ": "Mz of slip-angle sweeps of both signs",
    "PPZ": "Mz of slip-angle sweeps at three pressures",
    "SSZ": "Mz of combined sweeps (slip ratio at several slip angles of both signs)",
    "QSX": "Mx of slip-angle sweeps at several loads, cambers and pressures",
    "PPMX": "Mx of slip-angle sweeps at three pressures",
    "QSY": "rolling resistance at several speeds and loads (free rolling)",
    "RBX": "combined sweeps: slip ratio at three or more slip angles", "RCX": "combined sweeps",
    "REX": "combined sweeps", "RHX": "combined sweeps",
    "RBY": "combined sweeps: slip ratio at slip angles of both signs", "RCY": "combined sweeps",
    "REY": "combined sweeps", "RHY": "combined sweeps", "RVY": "combined sweeps at slip angles of both signs",
    "VERTICAL_STIFFNESS": "loaded radius against load (a vertical load sweep)",
    "Q_FZ": "loaded radius against load up to high loads", "PFZ": "vertical load sweeps at three pressures",
    "Q_FC": "loaded radius under side and longitudinal force",
    "Q_V": "loaded and rolling radius at several speeds", "Q_RE0": "rolling radius at low speed",
    "BREFF": "effective rolling radius at several loads (free rolling)", "DREFF": "effective rolling radius",
    "FREFF": "effective rolling radius",
}

#: Groups a vehicle model uses -> (parameters, what a simulation gets when they are placeholders).
GROUPS = {
    "vertical": (("VERTICAL_STIFFNESS", "Q_FZ2", "PFZ1", "Q_V2", "BOTTOM_OFFST", "BOTTOM_STIFF", "VERTICAL_DAMPING"),
                 "ride, wheel load fluctuation and bottoming follow the placeholder stiffness, not this tyre"),
    "relaxation": (("PTX1", "PTX2", "PTX3", "PTY1", "PTY2"),
                   "transient slip (lane change, ABS, low speed) lags by placeholder relaxation lengths"),
    "carcass": (("LONGITUDINAL_STIFFNESS", "LATERAL_STIFFNESS", "YAW_STIFFNESS", "PCFX1", "PCFY1"),
                "the SWIFT ring and relaxation from carcass compliance use car-tyre values"),
    "mass and inertia": (("MASS", "IYY", "IXX", "BELT_MASS", "BELT_IYY", "BELT_IXX"),
                         "wheel spin dynamics (traction control, ABS) use placeholder inertias: give the tyre's "
                         "measured mass and inertia"),
    "damping": (("DAMP_LONG", "DAMP_LAT", "DAMP_YAW", "DAMP_WINDUP", "FREQ_LONG", "FREQ_LAT"),
                "belt modes of the SWIFT ring are placeholders"),
    "longitudinal force": (("PKX1", "PDX1", "PCX1", "PEX1"),
                           "pure Fx (traction and braking) is a placeholder shape"),
    "combined slip": (("RBX1", "RBX2", "RBY1", "RBY2"),
                      "friction-circle interaction under combined slip is the placeholder's"),
    "rolling resistance": (("QSY1", "QSY2"), "rolling resistance is a placeholder"),
}


def _measurement(name: str) -> str:
    for prefix in sorted(MEASUREMENTS, key=len, reverse=True):
        if name.startswith(prefix):
            return MEASUREMENTS[prefix]
    return "data that vary what this parameter acts on"


def provenance_of(result) -> dict:
    """Parameter -> origin of its value (see the module text) for every parameter of ``result.params``."""
    out = {}
    generic = getattr(result, "generic", True)
    start_label = "held at its start value" + ("" if generic else f" (from {result.start.source or 'the start'})")
    for name in PARAMETERS:
        out[name] = PLACEHOLDER if generic else start_label
    for name, text in getattr(result, "sources", {}).items():
        out[name] = text
    for st in result.stages.values():
        for name, why in list(st.skipped.items()) + list(st.reset.items()):
            if name in st.fitted:
                continue
            prefix = PLACEHOLDER if generic and why != "given by the user" else start_label
            out[name] = f"{prefix}: not fitted ({why})" if why != "given by the user" else "given"
        for name in st.fitted:
            se = st.stderr.get(name)
            spread = f" +- {se:.3g}" if se is not None else " (s.e. undefined)"
            out[name] = f"fitted{spread} ({st.name})"
    return out


def unidentified(result) -> list[tuple[str, str, str]]:
    """[(parameter, why, the measurement that would pin it)]: fitted parameters at a bound of the fit or with a
    standard error above their size (kept because the data need them), then those held at their start values
    because the data do not determine them (standard error, correlation, no effect)."""
    out, seen = [], set()
    for st in result.stages.values():
        bounds = {}
        if st.result is not None:
            bounds = {n: (p.min, p.max) for n, p in st.result.params.items()}
        for name in st.fitted:
            v, se = st.values[name], st.stderr.get(name)
            lo, hi = bounds.get(name, (None, None))
            tol = 1e-6 * max(abs(v), 1e-3)
            if lo is not None and (abs(v - lo) <= tol or abs(v - hi) <= tol):
                why = f"ends on its bound {lo if abs(v - lo) <= tol else hi:g} of the fit ({st.name})"
            elif se is not None and se > abs(v):
                why = f"standard error {se:.3g} exceeds its value {v:.3g} ({st.name}); kept: the data need it"
            else:
                continue
            out.append((name, why, _measurement(name)))
            seen.add(name)
        for name, why in st.reset.items():
            if name not in seen and name not in st.fitted:
                out.append((name, f"held at its start value: {why} ({st.name})", _measurement(name)))
                seen.add(name)
    return out


def closing_summary(result) -> list[str]:
    """Lines closing the .tir: the groups of parameters a vehicle model uses that were not fitted (placeholders or
    start values), with what that means for a simulation; the one-sided ranges."""
    origin = provenance_of(result)
    lines = ["NOT FITTED (what a vehicle model gets from this file as a placeholder or start value):"]
    for group, (names, meaning) in GROUPS.items():
        open_ = [n for n in names if n in origin and not origin[n].startswith(("fitted", "estimated", "given",
                                                                                "from ", "the data"))]
        if open_:
            lines.append(f"  {group}: {' '.join(open_)} not fitted: {meaning}")
    if len(lines) == 1:
        lines.append("  nothing of the groups a vehicle model uses")
    sided = [n for n in ("ALPMIN", "KPUMIN") if "ONE-SIDED" in origin.get(n, "")]
    for n in sided:
        lines.append(f"  range: {origin[n]} ({n}..{n.replace('MIN', 'MAX')})")
    unknown = unidentified(result)
    if unknown:
        lines.append("NOT DETERMINED by the data (held at their start values, or fitted at a bound or with a "
                     "standard error above the value; the comment of each says which): "
                     + " ".join(n for n, _, _ in unknown))
    return lines
