"""The catalogue of dynamic effects: which .tir parameters of the SWIFT wheel an effect acts on, the runs that can
test it and the signature it leaves in the time histories (channels and engineers' features of
:mod:`mftyre.gaps.dynamic_locate`).

Every parameter named here is checked against the schema (:data:`mftyre.params.PARAMETERS`) at import, and the
meaning shown in reports is the schema's. ``scale``: the size of a change the refit starts from (relative to the
value, or absolute where the neutral value is 0). ``needs``: run kinds (``cleat``: an obstacle; ``steer``: a yaw
step; ``brake``: a step of the rim's slip), and ``pressures``/``loads``/``speeds``: at least two levels of that
condition in those runs. ``models``: the dynamic models the effect is a parameter of (``swift``: the rigid ring;
``relaxed``: the MF behind relaxation lengths, :mod:`mftyre.transient`); ``versions``: the MF versions whose
equations use the parameters (empty: all).

The relaxed wheel's relaxation lengths: MF 6.1/6.2 sigma_x = K_xk/C_x and sigma_y = K_ya/C_y with the carcass
stiffnesses C_x = LONGITUDINAL_STIFFNESS (1 + PCFX1 dfz + PCFX2 dfz^2)(1 + PCFX3 dpi) (C_y likewise with
LATERAL_STIFFNESS, PCFY1-3); MF 5.2 the PTX1-PTX3, PTY1-PTY2 formulas (:mod:`mftyre.formula.derived`).
"""
from __future__ import annotations

from dataclasses import replace

from ..params import PARAMETERS
from .catalogue import Effect
from .dynamic_runs import run_levels

__all__ = ["DYNAMIC_CATALOGUE", "NOT_TRIED", "NOT_TRIED_RELAXED", "testable_effects"]


def _d(name, parameters, kinds, channels, features, description, *, needs=(), absolute=(), models=("swift",),
       versions=()) -> Effect:
    """A dynamic effect: the one effect record (:class:`mftyre.gaps.catalogue.Effect`) with the run ``kinds`` as
    its condition variables (a dynamic finding names the kind of run it is in), no switch (``neutral``: the
    parameters refine values the wheel always uses), its signature's ``features``, the parameters refitted by
    absolute steps, the dynamic ``models`` and the MF ``versions`` whose equations use the parameters."""
    return Effect(name, description, tuple(parameters), {}, tuple(channels), tuple(kinds), needs=tuple(needs),
                  features=tuple(features), absolute=tuple(absolute), models=tuple(models), equations=tuple(versions))


_IN_PLANE = ("FX", "FZ")
_LAT = ("FY", "MZ")
_MF6 = ("61", "62")
DYNAMIC_CATALOGUE = (
    _d("longitudinal carcass stiffness (relaxation length K_xk/C_x)", ("LONGITUDINAL_STIFFNESS",),
                  ("cleat",), ("FX",), ("peak_to_peak", "peak"),
                  "the carcass compliance behind the patch sets the longitudinal relaxation length sigma_x = "
                  "K_xk/C_x of the SWIFT wheel: Fx over an obstacle builds up and decays with it"),
    _d("lateral carcass stiffness (relaxation length K_ya/C_y)", ("LATERAL_STIFFNESS",),
                  ("steer",), _LAT, ("lag", "build_up", "peak"),
                  "sigma_y = K_ya/C_y of the SWIFT wheel: the build-up distance and phase lag of Fy after a steer "
                  "step"),
    _d("yaw stiffness of the carcass", ("YAW_STIFFNESS",), ("steer",), ("MZ", "FY"),
                  ("lag", "peak"), "the residual yaw compliance: the lag of Mz after a steer step"),
    _d("contact length (Q_RA1)", ("Q_RA1",), ("cleat",), _IN_PLANE,
                  ("response_length", "peak", "peak_to_peak"),
                  "the half contact length a sets the tandem base l_s = ELLIPS_SHIFT 2a: the length of the cleat "
                  "response and the height of its peaks"),
    _d("contact length over load (Q_RA2)", ("Q_RA2",), ("cleat",), _IN_PLANE,
                  ("response_length", "peak"), "the growth of the contact length with the deflection: response "
                  "lengths and peaks differ between loads", needs=("loads",), absolute=("Q_RA2",)),
    _d("vertical stiffness over pressure (PFZ1)", ("PFZ1",), ("cleat",), _IN_PLANE,
                  ("level", "peak", "response_length"),
                  "the pressure dependence of the vertical stiffness (and of the contact length through F_z/C_z): "
                  "static load, peaks and response length change with pressure", needs=("pressures",),
                  absolute=("PFZ1",)),
    _d("tandem base (ELLIPS_SHIFT)", ("ELLIPS_SHIFT",), ("cleat",), _IN_PLANE,
                  ("response_length", "peak_to_peak"),
                  "the distance between the front and rear cams: the length of the enveloped response"),
    _d("cam shape (ELLIPS_LENGTH, ELLIPS_HEIGHT)", ("ELLIPS_LENGTH", "ELLIPS_HEIGHT"), ("cleat",),
                  _IN_PLANE, ("response_length", "peak"),
                  "the elliptical cam's semi-axes: how early the tyre feels the obstacle and how its edges are "
                  "rounded"),
    _d("cam order (ELLIPS_ORDER)", ("ELLIPS_ORDER",), ("cleat",), _IN_PLANE,
                  ("response_length", "peak"), "the cam's exponent: how square the enveloped edge is"),
    _d("in-plane sidewall stiffness (FREQ_LONG)", ("FREQ_LONG",), ("cleat",), _IN_PLANE,
                  ("frequency", "peak"), "the belt's longitudinal and vertical mode: frequency of the free decay "
                  "after the obstacle"),
    _d("in-plane sidewall damping (DAMP_LONG)", ("DAMP_LONG",), ("cleat",), _IN_PLANE,
                  ("damping", "peak"), "the damping ratio of the belt's in-plane mode: the decay after the "
                  "obstacle"),
    _d("wind-up mode (FREQ_WINDUP, DAMP_WINDUP)", ("FREQ_WINDUP", "DAMP_WINDUP"), ("cleat",), ("FX",),
                  ("frequency", "damping", "peak_to_peak"),
                  "the belt's rotation against the rim: the second frequency of the Fx decay"),
    _d("sidewall stiffness over pressure (SWIFT_PSTIFF)", ("SWIFT_PSTIFF",), ("cleat",), _IN_PLANE,
                  ("frequency", "peak"), "the belt mode frequencies change with pressure",
                  needs=("pressures",), absolute=("SWIFT_PSTIFF",)),
    _d("sidewall damping over pressure (SWIFT_PDAMP)", ("SWIFT_PDAMP",), ("cleat",), _IN_PLANE,
                  ("damping",), "the belt mode damping changes with pressure", needs=("pressures",),
                  absolute=("SWIFT_PDAMP",)),
    _d("belt mass (BELT_MASS)", ("BELT_MASS",), ("cleat",), _IN_PLANE, ("frequency", "peak"),
                  "the ring's mass at fixed sidewall stiffness: lower frequency of the decay and higher force "
                  "peaks at speed", needs=("speeds",)),
    _d("belt polar inertia (BELT_IYY)", ("BELT_IYY",), ("cleat",), ("FX",), ("frequency", "peak"),
                  "the ring's rotational inertia: the wind-up frequency and the Fx peaks"),
    _d("rolling radius variation (SWIFT_REVAR)", ("SWIFT_REVAR",), ("cleat",), ("FX",),
                  ("peak_to_peak", "peak"),
                  "the effective rolling radius follows the effective road curvature: the belt spins up and down "
                  "over the obstacle, Fx grows at low speed", absolute=("SWIFT_REVAR",)),
    _d("residual (patch) damping (DAMP_RESIDUAL)", ("DAMP_RESIDUAL",), ("cleat", "steer"),
                  ("FX", "FY"), ("peak", "damping"), "the damping of the contact patch's residual springs"),
    _d("lateral belt mode (FREQ_LAT, DAMP_LAT)", ("FREQ_LAT", "DAMP_LAT"), ("steer",), _LAT,
                  ("frequency", "peak", "lag"), "the belt's lateral mode: the overshoot of Fy after a steer step"),
    _d("yaw and camber belt mode (FREQ_YAW, DAMP_YAW)", ("FREQ_YAW", "DAMP_YAW"), ("steer",), _LAT,
                  ("peak", "lag"), "the belt's yaw mode: the overshoot of Mz after a steer step"),
    # the relaxed wheel: MF 6.1/6.2 relaxation lengths K/C (carcass stiffness, its load and pressure terms)
    _d("longitudinal relaxation length (LONGITUDINAL_STIFFNESS)", ("LONGITUDINAL_STIFFNESS",),
                  ("brake",), ("FX",), ("lag", "build_up"),
                  "sigma_x = K_xk/C_x: the lag and build-up distance of Fx after a braking step",
                  models=("relaxed",), versions=_MF6),
    _d("longitudinal relaxation length over load (PCFX1, PCFX2)", ("PCFX1", "PCFX2"), ("brake",),
                  ("FX",), ("lag", "build_up"), "C_x over load: the Fx lag differs between loads",
                  needs=("loads",), absolute=("PCFX1", "PCFX2"), models=("relaxed",), versions=_MF6),
    _d("longitudinal relaxation length over pressure (PCFX3)", ("PCFX3",), ("brake",), ("FX",),
                  ("lag", "build_up"), "C_x over pressure: the Fx lag differs between pressures",
                  needs=("pressures",), absolute=("PCFX3",), models=("relaxed",), versions=_MF6),
    _d("lateral relaxation length (LATERAL_STIFFNESS)", ("LATERAL_STIFFNESS",), ("steer",), _LAT,
                  ("lag", "build_up"), "sigma_y = K_ya/C_y: the lag and build-up distance of Fy and Mz after a "
                  "steer step", models=("relaxed",), versions=_MF6),
    _d("lateral relaxation length over load (PCFY1, PCFY2)", ("PCFY1", "PCFY2"), ("steer",), _LAT,
                  ("lag", "build_up"), "C_y over load: the Fy lag differs between loads", needs=("loads",),
                  absolute=("PCFY1", "PCFY2"), models=("relaxed",), versions=_MF6),
    _d("lateral relaxation length over pressure (PCFY3)", ("PCFY3",), ("steer",), _LAT,
                  ("lag", "build_up"), "C_y over pressure: the Fy lag differs between pressures",
                  needs=("pressures",), absolute=("PCFY3",), models=("relaxed",), versions=_MF6),
    # MF 5.2: the relaxation lengths' own formulas
    _d("longitudinal relaxation length (PTX1)", ("PTX1",), ("brake",), ("FX",), ("lag", "build_up"),
                  "sigma_x at the nominal load: the lag and build-up distance of Fx after a braking step",
                  models=("relaxed",), versions=("52",)),
    _d("longitudinal relaxation length over load (PTX2, PTX3)", ("PTX2", "PTX3"), ("brake",), ("FX",),
                  ("lag", "build_up"), "sigma_x over load: the Fx lag differs between loads", needs=("loads",),
                  absolute=("PTX2", "PTX3"), models=("relaxed",), versions=("52",)),
    _d("lateral relaxation length (PTY1)", ("PTY1",), ("steer",), _LAT, ("lag", "build_up"),
                  "the peak of sigma_y/R0 over load: the lag and build-up distance of Fy after a steer step",
                  models=("relaxed",), versions=("52",)),
    _d("lateral relaxation length over load (PTY2)", ("PTY2",), ("steer",), _LAT, ("lag", "build_up"),
                  "the load (Fz/Fz0) of the largest sigma_y: the Fy lag differs between loads", needs=("loads",),
                  models=("relaxed",), versions=("52",)),
)

#: Effects the SWIFT wheel of this project cannot express, or no run here can show: never tried, with the reason.
NOT_TRIED = {
    "relaxation lengths PTX1-PTX3, PTY1-PTY2": "the SWIFT wheel does not use them: its relaxation follows from the "
                                               "carcass stiffnesses (LONGITUDINAL_STIFFNESS, LATERAL_STIFFNESS: "
                                               "sigma = K/C); the relaxed wheel does (model kind relaxed)",
    "load and speed influence on the sidewall (Q_BVX, Q_BVT)": "not modelled in SWIFT (no published formula)",
    "turn slip from the belt yaw rate": "not modelled in SWIFT (no parameter acts on it)",
    "enveloping smoothing (ENV_C1, ENV_C2)": "not modelled in SWIFT (formula unpublished)",
    "cam series length (ELLIPS_NLENGTH)": "not used: each cam's height is the exact maximum over the profile",
    "vertical damping (VERTICAL_DAMPING)": "not used by the SWIFT wheel (damping comes from DAMP_LONG and "
                                           "DAMP_RESIDUAL)",
    "low-speed residual damping (DAMP_VLOW)": "acts below VXLOW only; dynamic runs are above it",
}

#: ... and the relaxed wheel.
NOT_TRIED_RELAXED = {
    "relaxation length scaling (LSGKP, LSGAL)": "user scaling factors (1 in a fitted file); PTX1/PTY1 set the same "
                                                "lengths",
    "turn slip from the yaw rate": "the relaxed wheel of the dynamic gap finder runs without turn slip",
    "low-speed damping of the deflections (tau_vlow)": "acts below VXLOW only; dynamic runs are above it",
    "everything of the ring, the enveloping and the vertical dynamics": "not in the relaxed wheel: use the SWIFT "
                                                                        "model (model kind swift)",
}

for _e in DYNAMIC_CATALOGUE:
    for _p in _e.parameters:
        if _p not in PARAMETERS:  # pragma: no cover - guards the table
            raise RuntimeError(f"dynamic effect {_e.name!r} names {_p}, which the schema does not know")


def _levels(runs, kinds, key):
    """How many levels of the condition ``key`` the runs of ``kinds`` hold (:func:`run_levels`)."""
    known = [r for r in runs if r.kind in kinds and r.condition[key] == r.condition[key]]
    return len(set(run_levels(known, key).tolist())) if known else 0


def testable_effects(runs, model, catalogue=DYNAMIC_CATALOGUE, model_kind: str = "swift"):
    """(testable effects, {effect name: reason untestable}) for these runs, this model and the dynamic model
    ``model_kind`` (effects of the other model are left out silently)."""
    ok, why = [], dict(NOT_TRIED_RELAXED if model_kind == "relaxed" else NOT_TRIED)
    kinds_present = {r.kind for r in runs}
    channels = {c for r in runs for c in r.measured}
    version = model.params.version
    for e in catalogue:
        if model_kind not in e.models:
            continue
        if e.equations and version not in e.equations:
            why[e.name] = (f"MF {'/'.join(v[0] + '.' + v[1] for v in e.equations)} only; the file is MF "
                           f"{version[0]}.{version[1]}")
            continue
        kinds = [k for k in e.kinds if k in kinds_present]
        if not kinds:
            why[e.name] = f"needs {' or '.join(e.kinds)} runs; the data hold {', '.join(sorted(kinds_present))}"
            continue
        if not set(e.channels) & channels:
            why[e.name] = f"needs a measured {' or '.join(e.channels)}"
            continue
        lacking = [n for n in e.needs if _levels(runs, kinds, {"pressures": "pressure", "loads": "load",
                                                                 "speeds": "speed"}[n]) < 2]
        if lacking:
            why[e.name] = f"needs at least two {' and '.join(lacking)} in the {'/'.join(kinds)} runs"
            continue
        missing = [p for p in e.parameters if p not in model.params]
        if missing:
            why[e.name] = f"the model has no {', '.join(missing)}"
            continue
        ok.append(_separable(e, runs, kinds, why))
    return ok, why


def _separable(e: Effect, runs, kinds, why: dict) -> Effect:
    """``e`` with only the parameters the runs can separate: parameters acting along a condition (``needs``: a
    slope, a curvature...) need one level more than there are of them (two loads give a load slope, not its
    curvature as well); the others are left at the file's values, named in ``why``."""
    for need in e.needs:
        key = {"pressures": "pressure", "loads": "load", "speeds": "speed"}[need]
        n = _levels(runs, kinds, key)
        if len(e.parameters) > n - 1:
            kept, dropped = e.parameters[:n - 1], e.parameters[n - 1:]
            why[f"{e.name}: {', '.join(dropped)}"] = (
                f"{len(e.parameters)} parameters along the {key} need {len(e.parameters) + 1} {need} in the "
                f"{'/'.join(kinds)} runs to be separated; the runs have {n}: {', '.join(kept)} refitted alone")
            e = replace(e, parameters=kept, absolute=tuple(p for p in e.absolute if p in kept))
    return e
