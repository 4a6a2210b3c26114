"""The catalogue of named effects: each is a set of schema parameters that switches a physical effect on.

An :class:`Effect` is data: a name, a one-line physical description, the ``.tir`` parameters that are freed when
the effect is added (``parameters``), the subset that switches it (``neutral``: parameter -> the value meaning
"effect absent", the schema's ``neutral``; the other parameters are inert shape factors while the switches are
neutral), typical values
to start a fit from where the neutral value leaves the fit without a gradient (``start``), the measured channels
it acts on (the first is its primary channel) and the condition variables whose residual structure it explains.

Everything else is derived from the parameter schema (:data:`mftyre.params.PARAMETERS`) and the fitting stages
(:data:`mftyre.fit.STAGES`): the one-line meaning of each parameter, the model versions it exists in, its neutral
value, the stage (rows and channel) on which it is refitted and the data conditions needed to determine it (the stage group's
``needs``: two or three load levels, two or three pressures, camber, two or three speeds...).

:data:`BASE` are the stage parameters that belong to no effect (shape, peak, stiffness and shifts at the
nominal condition): always active, refitted by the fair start. :func:`coverage` tells for every schema parameter
which effect(s) reach it, or that it is a base parameter, or why steady-state measurements cannot see it.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..fit.stages import STAGES
from ..params import PARAMETERS, STAGE_MEMBERS

__all__ = ["Effect", "CATALOGUE", "BASE", "VARIABLES", "PARAM_STAGE", "parameter_needs", "SWEPT_INPUT", "coverage",
           "effect_state", "neutralise", "EXCLUDED"]

#: Condition variables findings and effects speak of: name -> text used in findings.
VARIABLES = {
    "load": "load", "pressure": "pressure", "camber": "camber", "speed": "speed", "turn_slip": "turn slip",
    "slip_angle": "slip angle", "slip_ratio": "longitudinal slip", "combined": "combined slip",
    "free_rolling": "free rolling", "deflection": "deflection", "slip": "slip (Fx, Fy)",
}


@dataclass(frozen=True)
class Effect:
    name: str
    description: str
    parameters: tuple          # every parameter freed when the effect is added
    neutral: dict              # switch parameter -> neutral value (effect absent when all are neutral)
    channels: tuple            # measured channels it acts on; first = primary
    variables: tuple           # condition variables whose residual structure it explains
    start: dict = field(default_factory=dict)   # start values when switching on (default: the neutral value)
    needs: tuple = ()          # extra data conditions (beyond the stage groups'): e.g. ("turn_slip",)
    with_stages: bool = False  # scored with its stages refitted around it when it passes alone (a nuisance)
    # a dynamic effect (:mod:`mftyre.gaps.dynamic_catalogue`): ``variables`` are the run kinds it shows in, and
    features: tuple = ()       # ... the features of its signature in the time histories
    absolute: tuple = ()       # parameters refitted by absolute steps (neutral value 0)
    models: tuple = ()         # the dynamic models it is a parameter of (() : a steady effect)
    equations: tuple = ()      # MF versions whose equations use its parameters (() : where they all exist)

    def parameter_descriptions(self) -> dict:
        """Parameter -> its one-line meaning from the schema."""
        return {n: PARAMETERS[n].description for n in self.parameters}

    @staticmethod
    def admit(prm):
        """The parameter set able to carry the effect's parameters: the tyre's own for a catalogue effect (a
        nuisance such as :data:`mftyre.gaps.drift.FRICTION_DRIFT` adds its coefficients)."""
        return prm

    @property
    def kinds(self) -> tuple:
        """The run kinds a dynamic effect shows in (its condition variables: a finding of a dynamic run names its
        kind)."""
        return self.variables

    @property
    def versions(self) -> frozenset:
        """Model versions in which every parameter of the effect exists (a dynamic effect's: those whose
        equations use them)."""
        if self.equations:
            return frozenset(self.equations)
        out = frozenset({"61", "62"})
        for n in self.parameters:
            out &= PARAMETERS[n].versions
        return out


def _e(name, description, params, channels, variables, switches=None, start=None, needs=()):
    """An effect; ``switches``: the parameters that switch it (default all), at their schema neutral values."""
    params = tuple(params.split())
    neutral = {n: PARAMETERS[n].neutral for n in (params if switches is None else switches.split())}
    return Effect(name, description, params, neutral, tuple(channels.split()), tuple(variables.split()),
                  dict(start or {}), tuple(needs))


_FY = "FY MZ MX"   # a change of Fy moves Mz (trail x Fy) and Mx (QSX3 Fy) with it
_FX = "FX MZ MY"   # Fx enters Mz (moment arm s Fx) and My (QSY2 Fx)

#: The catalogue, in the order effects are listed in reports.
CATALOGUE: dict[str, Effect] = {e.name: e for e in (
    # ---------------------------------------------------------------------------- inflation pressure
    _e("pressure_cornering_stiffness", "inflation pressure changes the cornering stiffness and the load at which "
       "it peaks (Besselink et al. 2010)", "PPY1 PPY2", _FY, "pressure"),
    _e("pressure_slip_stiffness", "inflation pressure changes the longitudinal slip stiffness", "PPX1 PPX2", _FX,
       "pressure"),
    _e("pressure_friction_x", "inflation pressure changes the peak longitudinal friction", "PPX3 PPX4", _FX,
       "pressure"),
    _e("pressure_friction_y", "inflation pressure changes the peak lateral friction", "PPY3 PPY4", _FY, "pressure"),
    _e("pressure_camber_stiffness", "inflation pressure changes the camber stiffness of Fy", "PPY5", _FY,
       "pressure camber"),
    _e("pressure_trail", "inflation pressure changes the length of the pneumatic trail (higher pressure, shorter "
       "contact patch, smaller Mz)", "PPZ1", "MZ", "pressure"),
    _e("pressure_residual_torque", "inflation pressure changes the camber-induced residual aligning torque", "PPZ2",
       "MZ", "pressure camber"),
    _e("pressure_vertical_stiffness", "inflation pressure changes the vertical stiffness (load at given "
       "deflection)", "PFZ1", "FZ", "pressure"),
    _e("pressure_overturning", "inflation pressure changes the camber-induced overturning moment", "PPMX1", "MX",
       "pressure camber"),
    _e("pressure_rolling_resistance", "inflation pressure changes the rolling resistance (softer tyre, more "
       "hysteresis loss)", "QSY8", "MY", "pressure"),
    # ---------------------------------------------------------------------------------------- camber
    _e("camber_cornering_stiffness", "camber changes the cornering stiffness", "PKY3 PKY5", _FY, "camber"),
    _e("camber_thrust", "camber produces a side force (camber stiffness and the camber-induced shift of Fy)",
       "PKY6 PKY7 PVY3 PVY4", _FY, "camber", start={"PKY6": -0.5}),
    _e("camber_fy_peak", "camber changes the lateral friction and the curvature of the Fy curve",
       "PDY3 PEY4 PEY5", _FY, "camber"),
    _e("camber_friction_x", "camber reduces the peak longitudinal friction", "PDX3", _FX, "camber"),
    _e("camber_trail", "camber changes the pneumatic trail (its slope, peak, curvature and shift)",
       "QBZ4 QBZ5 QDZ3 QDZ4 QEZ5 QHZ3 QHZ4", "MZ", "camber"),
    _e("camber_aligning_moment", "camber produces a residual aligning moment (camber moment of Mz)",
       "QDZ8 QDZ9 QDZ10 QDZ11", "MZ", "camber"),
    _e("camber_overturning", "camber produces an overturning moment Mx", "QSX2 QSX10 QSX11",
       "MX", "camber", switches="QSX2 QSX10", start={"QSX11": 5.0}),
    _e("camber_squared_overturning", "an overturning moment growing with camber squared (MF-Tyre 6.1 term)",
       "QSX12", "MX", "camber"),
    _e("camber_rolling_resistance", "camber increases the rolling resistance", "QSY5 QSY6", "MY", "camber"),
    _e("camber_combined_fx", "camber changes the combined-slip weighting of Fx", "RBX3", _FX, "camber combined"),
    _e("camber_combined_fy", "camber changes the combined-slip weighting and the kappa-induced side force",
       "RBY4 RVY3", _FY, "camber combined"),
    _e("camber_fx_moment_arm", "camber changes the moment arm of Fx in Mz", "SSZ3 SSZ4", "MZ", "camber combined"),
    _e("camber_vertical", "camber changes the vertical stiffness and deflection (MF 6.2)",
       "Q_CAM1 Q_CAM2 Q_CAM3", "FZ", "camber"),
    _e("camber_side_force_vertical", "camber with side force changes the vertical stiffness (MF 6.2)",
       "Q_FYS1 Q_FYS2 Q_FYS3", "FZ", "camber slip"),
    # ------------------------------------------------------------------------------- load dependence
    _e("load_friction_x", "the longitudinal friction coefficient falls with load", "PDX2", _FX, "load"),
    _e("load_friction_y", "the lateral friction coefficient falls with load", "PDY2", _FY, "load"),
    _e("load_curvature_x", "the curvature of the Fx curve changes with load", "PEX2 PEX3", _FX, "load"),
    _e("load_curvature_y", "the curvature of the Fy curve changes with load", "PEY2", _FY, "load"),
    _e("load_slip_stiffness", "the longitudinal slip stiffness per unit load changes with load", "PKX2 PKX3", _FX,
       "load"),
    _e("load_trail", "the pneumatic trail (slope, peak, curvature, shift) changes with load",
       "QBZ2 QBZ3 QDZ2 QEZ2 QEZ3 QHZ2", "MZ", "load"),
    _e("load_residual_torque", "the residual aligning torque changes with load", "QDZ7", "MZ", "load"),
    _e("load_shift_x", "the Fx shifts (offsets at zero slip) change with load", "PHX2 PVX2", _FX, "load"),
    _e("load_shift_y", "ply steer and conicity (Fy shifts) change with load", "PHY2 PVY2", _FY, "load"),
    _e("load_rolling_resistance", "rolling resistance not proportional to load (exponent QSY7; neutral 1)",
       "QSY7", "MY", "load"),
    _e("load_combined_fx", "the combined-slip curvature of Fx changes with load", "REX2", _FX, "load combined"),
    _e("load_combined_fy", "the combined-slip curvature, shift and kappa-induced Fy change with load",
       "REY2 RHY2 RVY2", _FY, "load combined"),
    # ------------------------------------------------------------------------------------------ speed
    _e("speed_friction", "friction falls with sliding speed (LMUV: the friction decay with slip speed)", "LMUV",
       "FX FY MZ MX MY", "speed slip_ratio slip_angle", start={"LMUV": 0.05}, needs=("slip_speeds",)),
    _e("speed_rolling_resistance", "rolling resistance grows with speed", "QSY3 QSY4", "MY", "speed"),
    _e("speed_vertical", "the free radius and the vertical stiffness grow with speed", "Q_V1 Q_V2", "FZ", "speed"),
    # ---------------------------------------------------------------------------------- combined slip
    _e("combined_fx", "side slip reduces Fx (combined-slip weighting function G_xalpha)",
       "RBX1 RBX2 RCX1 REX1 RHX1", _FX, "combined", switches="RBX1",
       start={"RBX1": 15.0, "RBX2": 10.0, "RCX1": 1.0}),
    _e("combined_fy", "longitudinal slip reduces Fy (combined-slip weighting function G_ykappa)",
       "RBY1 RBY2 RBY3 RCY1 REY1 RHY1", _FY, "combined", switches="RBY1",
       start={"RBY1": 10.0, "RBY2": 8.0, "RCY1": 1.0}),
    _e("kappa_induced_fy", "longitudinal slip induces a side force at a slip angle (S_Vykappa, ply steer of the "
       "carcass under Fx)", "RVY1 RVY4 RVY5 RVY6", _FY, "combined", switches="RVY1",
       start={"RVY4": 20.0, "RVY5": 2.0, "RVY6": 10.0}),
    _e("fx_moment_arm", "Fx acts on Mz through a lateral moment arm of the contact force", "SSZ1 SSZ2", "MZ",
       "combined"),
    _e("fx_rolling_resistance", "rolling resistance changes with the longitudinal force", "QSY2", "MY",
       "slip_ratio"),
    # ------------------------------------------------------------------------------------ asymmetries
    _e("fx_shift", "offsets of the Fx curve at zero slip (horizontal and vertical shift)", "PHX1 PVX1", _FX,
       "slip_ratio free_rolling"),
    _e("fy_shift", "ply steer and conicity: offsets of the Fy curve at zero slip angle", "PHY1 PVY1", _FY,
       "slip_angle free_rolling"),
    _e("trail_shift", "offset of the pneumatic trail curve in slip angle", "QHZ1", "MZ", "slip_angle"),
    _e("fx_curvature_asymmetry", "the Fx curve's curvature differs between driving and braking", "PEX4", _FX,
       "slip_ratio"),
    _e("fy_curvature_asymmetry", "the Fy curve's curvature differs for positive and negative slip angle", "PEY3",
       _FY, "slip_angle"),
    _e("trail_curvature_asymmetry", "the trail curvature differs for positive and negative slip angle", "QEZ4",
       "MZ", "slip_angle"),
    _e("residual_torque", "a residual aligning torque at zero camber (peak of M_zr)", "QDZ6", "MZ",
       "slip_angle free_rolling"),
    _e("residual_torque_stiffness", "the slope of the residual torque follows the Fy stiffness (QBZ10)", "QBZ10",
       "MZ", "slip_angle"),
    _e("overturning_offset", "an overturning moment at zero side force and camber (offset of Mx)", "QSX1", "MX",
       "slip_angle free_rolling"),
    _e("lateral_force_overturning", "the lateral force produces an overturning moment (lateral shift of the "
       "contact force)", "QSX3", "MX", "slip_angle"),
    _e("combined_overturning", "load, lateral force and camber interact in Mx (MF-Tyre 6.1 sine term)",
       "QSX4 QSX5 QSX6 QSX7 QSX8 QSX9", "MX", "camber slip_angle load", switches="QSX4",
       start={"QSX4": 1.0, "QSX5": 1.0, "QSX6": 10.0, "QSX9": 0.4}),
    _e("lateral_force_overturning_camber", "lateral force induced Mx growing with camber (MF-Tyre 6.1 terms)",
       "QSX13 QSX14", "MX", "slip_angle camber"),
    # --------------------------------------------------------------------------------------- vertical
    _e("vertical_hardening", "the tyre stiffens with deflection (quadratic term of the load-deflection curve; "
       "neutral = linear spring)", "Q_FZ2", "FZ", "deflection"),
    _e("force_vertical_stiffness", "longitudinal and lateral force reduce the vertical stiffness",
       "Q_FCX Q_FCY", "FZ", "slip"),
    _e("side_force_deflection_vertical", "deflection dependence of the side-force effect on vertical stiffness "
       "(MF 6.2)", "Q_FCY2", "FZ", "slip"),
    # -------------------------------------------------------------------------------------- turn slip
    _e("turn_slip_fx", "turn slip (spin) reduces the peak longitudinal force", "PDXP1 PDXP2 PDXP3", _FX,
       "turn_slip", switches="PDXP1", start={"PDXP1": 0.4}, needs=("turn_slip",)),
    _e("turn_slip_fy_peak", "turn slip (spin) reduces the peak lateral force", "PDYP1 PDYP2 PDYP3 PDYP4", _FY,
       "turn_slip", switches="PDYP1", start={"PDYP1": 0.4}, needs=("turn_slip",)),
    _e("turn_slip_cornering_stiffness", "turn slip (spin) reduces the cornering stiffness", "PKYP1", _FY,
       "turn_slip", start={"PKYP1": 1.0}, needs=("turn_slip",)),
    _e("turn_slip_trail", "turn slip (spin) reduces the pneumatic trail", "QDTP1", "MZ", "turn_slip",
       start={"QDTP1": 10.0}, needs=("turn_slip",)),
    _e("turn_slip_residual_torque", "turn slip (spin) changes the slope of the residual torque", "QBRP1", "MZ",
       "turn_slip", start={"QBRP1": 0.1}, needs=("turn_slip",)),
    _e("turn_slip_moment", "the turning (spin) moment at turn slip, up to the parking torque",
       "QCRP1 QCRP2 QDRP1 QDRP2", "MZ", "turn_slip", switches="QCRP1",
       start={"QCRP1": 0.2, "QCRP2": 0.1, "QDRP1": 1.0}, needs=("turn_slip",)),
)}

#: Parameter -> the stage that fits or refits it (the schema's ``stage``, :data:`mftyre.params.STAGE_MEMBERS`): the
#: stage groups' parameters first, then those refitted with a stage although no group lists them.
PARAM_STAGE: dict[str, str] = {n: stage.name for stage in STAGES.values() for _, names in stage.groups for n in names}
PARAM_STAGE.update({n: stage for stage, names in STAGE_MEMBERS.items() for n in names if n not in PARAM_STAGE})
# turn-slip parameters without a neutral value: active whenever turn slip is evaluated
_TURN_SLIP_BASE = ("PHYP1", "PHYP2", "PHYP3", "PHYP4", "PECP1", "PECP2")

_IN_EFFECT = {n for e in CATALOGUE.values() for n in e.parameters}

#: Base parameters: fitted by a stage, in no effect (always active). Turn-slip base parameters are refitted only
#: when the data have turn slip.
BASE: tuple = tuple(n for n in PARAM_STAGE if n not in _IN_EFFECT and STAGES.get(PARAM_STAGE[n]) is not None
                    and n not in ("BREFF", "DREFF", "FREFF"))
TURN_SLIP_BASE: tuple = _TURN_SLIP_BASE

#: Parameters no effect reaches, with the reason (steady-state force/moment/deflection data cannot see them, or
#: they are not model coefficients).
EXCLUDED = {
    "scaling": "scale factors (L...) are the user's scaling of a fitted model, not an effect of the tyre "
               "(LMUV, the friction decay with slip speed, is the exception: effect speed_friction)",
    "effective rolling radius": "BREFF, DREFF, FREFF describe the effective rolling radius (channel RE), which the "
                                "gap finder does not map",
    "dynamics": "structural, inertia, contact-patch and enveloping parameters (MF-Swift) act on dynamics, "
                "relaxation and short-wavelength response, not on steady-state measurements",
    "settings": "header, model settings, dimensions, operating conditions and validity ranges",
    "mf52": "MF 5.2-only coefficients (the catalogue is for MF 6.1/6.2)",
    "unused": "not used by mftyre's steady-state equations (Q_CAM: MF 6.1 camber on vertical stiffness)",
}


#: The input a stage's parameters shape the output along: without a sweep of it the data cannot tell them apart
#: (e.g. the Fx shifts PHX1 and PVX1 both give a constant Fx at kappa = 0: from free rolling alone any
#: horizontal shift is cancelled by a vertical one, and the fitted curve's shape away from kappa = 0 is invented).
SWEPT_INPUT = {"pure_fx": "slip_ratio", "pure_fy": "slip_angle", "mz": "slip_angle", "combined_fx": "combined",
               "combined_fy": "combined", "mz_combined": "slip_ratio", "vertical": "deflection"}
#: Exceptions: the kappa-induced side force (S_Vykappa) is largest at alpha = 0, a slip-ratio sweep shows it.
_SWEPT_EXCEPTIONS = {"RVY1": "slip_ratio", "RVY2": "slip_ratio", "RVY3": "slip_ratio", "RVY5": "slip_ratio",
                     "RVY6": "slip_ratio"}


def parameter_needs(name: str) -> tuple:
    """Data conditions needed to determine a parameter: the input its stage sweeps (:data:`SWEPT_INPUT`:
    ``slip_ratio``, ``slip_angle``, ``combined``, ``deflection``) and the ``needs`` of its stage group;
    ``turn_slip`` for the turn-slip coefficients, ``camber`` / ``fy`` for the Mx and MF 6.2 vertical terms no
    stage lists. (LMUV needs a slip sweep: the slip speed varies within it.)"""
    swept = _SWEPT_EXCEPTIONS.get(name) or SWEPT_INPUT.get(PARAM_STAGE.get(name, ""))
    return ((swept,) if swept else ()) + _condition_needs(name)


def _condition_needs(name: str) -> tuple:
    for stage in STAGES.values():
        for needs, names in stage.groups:
            if name in names:
                return tuple(needs)
    if PARAMETERS[name].section == "TURNSLIP_COEFFICIENTS":
        return ("turn_slip",)
    if name in ("QSX12", "QSX14", "Q_CAM1", "Q_CAM2", "Q_CAM3", "Q_FYS1", "Q_FYS2", "Q_FYS3"):
        return ("camber",)
    if name in ("QSX4", "QSX5", "QSX6", "QSX7", "QSX8", "QSX9", "QSX13", "Q_FCY2"):
        return ("fy",)
    return ()


def effect_state(effect: Effect, params) -> str:
    """"absent" (every switch at its neutral value), "active" or "unavailable" (not in this model version)."""
    if params.version not in effect.versions:
        return "unavailable"
    absent = all(abs(float(params[n]) - v) <= 1e-12 * max(1.0, abs(v)) for n, v in effect.neutral.items())
    return "absent" if absent else "active"


def neutralise(model, *names):
    """The model with the named effects switched off (their switch parameters at the neutral values)."""
    changes = {}
    for name in names:
        changes.update(CATALOGUE[name].neutral)
    return model.with_params(**changes)


def coverage() -> dict:
    """Schema parameter -> ("effect", [effect names]) | ("base", stage) | ("excluded", reason)."""
    out = {}
    for name, spec in PARAMETERS.items():
        effects = [e.name for e in CATALOGUE.values() if name in e.parameters]
        if effects:
            out[name] = ("effect", effects)
        elif name in BASE or name in TURN_SLIP_BASE:
            out[name] = ("base", PARAM_STAGE[name])
        elif name in ("BREFF", "DREFF", "FREFF"):
            out[name] = ("excluded", EXCLUDED["effective rolling radius"])
        elif spec.section == "SCALING_COEFFICIENTS":
            out[name] = ("excluded", EXCLUDED["scaling"])
        elif spec.versions == frozenset({"52"}):
            out[name] = ("excluded", EXCLUDED["mf52"])
        elif name == "Q_CAM":
            out[name] = ("excluded", EXCLUDED["unused"])
        elif name == "Q_FZ1":
            out[name] = ("excluded", "linear load-deflection term, derived from VERTICAL_STIFFNESS (a base "
                                     "parameter) when 0")
        elif spec.section in ("STRUCTURAL", "CONTACT_PATCH", "INERTIA") or name in (
                "VERTICAL_DAMPING", "MC_CONTOUR_A", "MC_CONTOUR_B", "BOTTOM_OFFST", "BOTTOM_STIFF"):
            out[name] = ("excluded", EXCLUDED["dynamics"])
        else:
            out[name] = ("excluded", EXCLUDED["settings"])
    return out
