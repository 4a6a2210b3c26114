"""The parameter schema of mftyre: every ``.tir`` parameter exactly once.

Each entry of :data:`PARAMETERS` is a :class:`ParamSpec` giving the name (as in the ``.tir`` file, upper
case), the canonical section, the default used when a file lacks it, the *unit kind* that drives the
``[UNITS]`` conversion, a one-line meaning, the model versions ("52", "61", "62") whose equations use it,
and whether its default is a neutral "effect absent" value (``optional``). The reader, the writer, the
checker, the documentation and the fitting groups all derive from this one table.

Defaults
--------
For a parameter absent from a file mftyre uses the value that MFeval 4.3.1's ``readTIR`` uses (the
independent reference evaluator; its defaults are constants set before the file is parsed, and the
``<prefix>_parameters.csv`` reference tables show them for the MF 5.2 sample file, which lacks ~150
parameters). The exceptions, all deliberate and listed here:

* ``INFLPRES`` (derived): when absent it is set to the file's ``NOMPRES`` (evaluate at nominal pressure).
  MFeval uses the constant 220000 Pa; the two agree for every reference file (both pressures are absent
  or both are 220000 Pa).
* ``FILE_TYPE`` / ``FILE_FORMAT`` / ``PROPERTY_FILE_FORMAT``: 'tir' / 'ASCII' / 'USER' instead of
  MFeval's placeholder 'default' (strings without effect on any equation; present in every sample file).
* ``FITTYP`` has no default: a file without it is an error (MFeval's 0 is not a valid model).
* Parameters MFeval does not know (``LMUV``, ``Q_FZ1``, ``LGAX``, ``LGAY``, ``LGAZ``, ``LGYR``, ``QTZ1``,
  ``MBELT``, ``QDRP2``) default to their neutral value: scale factors 1, ``LMUV`` 0 (no speed decay of
  friction), ``Q_FZ1`` 0 (= derive it from ``VERTICAL_STIFFNESS``), ``QTZ1``/``MBELT`` 0 (no gyroscopic
  torque), ``QDRP2`` 0.

Unit kinds (the rule)
---------------------
* Magic Formula coefficients are dimensionless and are never converted: everything in the
  ``*_COEFFICIENTS`` sections (including the turn-slip ones), the scale factors, ``BREFF``, ``DREFF``,
  ``FREFF``, ``Q_RE0``, ``Q_V1``, ``Q_V2``, ``Q_FZ1``, ``Q_FZ2``, ``Q_FCX``, ``Q_FCY``, ``Q_FCY2``,
  ``Q_CAM``, ``Q_CAM3``, ``PFZ1``, ``Q_A1``/``Q_A2``, ``Q_RA*``, ``Q_RB*``, ``PCF*``, ``PCMZ1``, ``Q_BVX``,
  ``Q_BVT``, ``ELLIPS_SHIFT/LENGTH/HEIGHT/ORDER``, ``ENV_C1/C2``, the modal damping ratios ``DAMP_LONG``,
  ``DAMP_LAT``, ``DAMP_YAW``, ``DAMP_WINDUP``, ``ASPECT_RATIO``, ``MC_CONTOUR_A/B``, slip limits
  ``KPUMIN/KPUMAX`` and other ratios: kind ``"-"``. Their values are defined for SI inputs whatever the
  file's ``[UNITS]`` say (TNO convention).
* Physical parameters carry their kind wherever they sit: radii, widths and offsets (``length``), loads
  (``force``), stiffnesses (``force/length``; ``YAW_STIFFNESS`` ``force*length/angle``), dampings
  (``force*time/length``; ``DAMP_RESIDUAL``/``DAMP_VLOW`` are stiffness-proportional, ``time``), masses
  (``mass``, including the MF 5.2 ``MBELT`` in the aligning section), inertias (``mass*length^2``), speeds
  (``length/time``), pressures (``pressure``), the ``*_RANGE`` limits including the angles ``ALPMIN``,
  ``ALPMAX``, ``CAMMIN``, ``CAMMAX`` (``angle``), ``BOTTOM_OFFST``, ``BOTTOM_STIFF``, ``ELLIPS_MAX_STEP``,
  ``Q_CAM1`` (``1/length``), ``Q_CAM2`` (``1/length^2``), ``Q_FYS1-3`` (``force``), ``GRAVITY``
  (``length/time^2``), ``FREQ_*`` (``1/time``, Hz), the ADAMS time steps (``time``).
* ``"string"`` and ``"integer"`` parameters are never converted.

A compound kind is a product/quotient of the base kinds ``length force mass time angle pressure`` with
optional integer powers, e.g. ``"force*time/length"`` or ``"1/length^2"``; the conversion factor combines
the factors of the base units.

Fitting facts
-------------
The fit and the gap finder read four more facts off the schema (tables ``_FIT_BOUNDS``, ``_SELECTS_FORM``,
``_NEUTRAL``, ``_STAGE`` below): ``bounds``, the range a fit keeps the parameter within (the data's physics may
narrow it, :func:`mftyre.fit.core.physical_bounds`); ``selects_form``, the value picks the form of the
equations (a branch, the side, the load floor), so a batch of parameter sets must share it; ``neutral``, the
value that switches the parameter's effect off (the gap finder's "effect absent"); ``stage``, the fitting stage
(:data:`mftyre.fit.stages.STAGES`) that fits it, or refits it although no stage group lists it
(:data:`STAGE_MEMBERS` keeps each stage's members in the order the refits free them).

Versions
--------
``versions`` lists the model versions whose equations (MF steady state or MF-Swift dynamics) use the
parameter; a file of such a version is expected to define it unless ``optional``. ADAMS-only settings and
the file header have an empty set: they are kept and written, but their absence is never reported.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from .errors import ModelInputError

__all__ = [
    "ParamSpec",
    "PARAMETERS",
    "SECTIONS",
    "UNIT_KINDS",
    "MissingParameterWarning",
    "TyreParameters",
    "parameters_by_section",
    "describe",
    "version_of_fittyp",
    "VALID_FITTYP",
    "CORE_PARAMETERS",
    "invalid_values",
    "implausible_values",
    "PLAUSIBLE_RANGES",
    "STAGE_MEMBERS",
    "FIT_BOUNDS",
    "SELECTS_FORM",
    "SIGN_SYMMETRIC",
]


class MissingParameterWarning(UserWarning):
    """A property file lacks parameters its model version uses; defaults were filled in."""


@dataclass(frozen=True)
class ParamSpec:
    """One .tir parameter."""

    name: str  # as in the .tir file, upper case
    section: str  # canonical section, e.g. "LATERAL_COEFFICIENTS"
    default: float | int | str | None  # value used when absent; None = required (error when absent)
    unit: str  # unit kind used for [UNITS] conversion
    description: str  # one line, the physical meaning
    versions: frozenset[str]  # model versions whose equations use it
    optional: bool = False  # True: neutral default meaning "effect absent"; absence not reported
    # facts the fit and the gap finder read (see "Fitting facts" in the module notes)
    bounds: tuple[float, float] | None = None  # (min, max) a fit keeps it within; None: free
    selects_form: bool = False  # its value selects the form of the equations (a branch, not a smooth factor)
    neutral: float | None = None  # the value that switches its effect off; None: no effect of its own to switch
    stage: str | None = None  # the fitting stage that fits (or refits) it; None: no stage

    @property
    def is_string(self) -> bool:
        return self.unit == "string"

    @property
    def is_integer(self) -> bool:
        return self.unit == "integer"

    @property
    def is_dimensional(self) -> bool:
        """True when the value is converted according to the file's [UNITS]."""
        return self.unit not in ("-", "string", "integer")


SECTIONS: tuple[str, ...] = (
    "MDI_HEADER",
    "UNITS",
    "MODEL",
    "DIMENSION",
    "OPERATING_CONDITIONS",
    "INERTIA",
    "VERTICAL",
    "STRUCTURAL",
    "CONTACT_PATCH",
    "INFLATION_PRESSURE_RANGE",
    "VERTICAL_FORCE_RANGE",
    "LONG_SLIP_RANGE",
    "SLIP_ANGLE_RANGE",
    "INCLINATION_ANGLE_RANGE",
    "SCALING_COEFFICIENTS",
    "LONGITUDINAL_COEFFICIENTS",
    "OVERTURNING_COEFFICIENTS",
    "LATERAL_COEFFICIENTS",
    "ROLLING_COEFFICIENTS",
    "ALIGNING_COEFFICIENTS",
    "TURNSLIP_COEFFICIENTS",
)

#: Base kinds a compound unit kind is built from.
UNIT_KINDS: tuple[str, ...] = ("length", "force", "mass", "time", "angle", "pressure")

#: FITTYP codes accepted and the model version they select.
VALID_FITTYP: dict[int, str] = {6: "52", 21: "52", **{k: "52" for k in range(50, 60)}, 61: "61", 62: "62"}

_V = {
    "A": frozenset({"52", "61", "62"}),
    "6": frozenset({"61", "62"}),
    "5": frozenset({"52"}),
    "2": frozenset({"62"}),
    "": frozenset(),
}

# (name, default, unit kind, versions code, description[, optional])
_TABLE: dict[str, list[tuple]] = {
    "MDI_HEADER": [
        ("FILE_TYPE", "tir", "string", "", "File type, 'tir' for a tyre property file"),
        ("FILE_VERSION", 3.0, "-", "", "Version of the property file format"),
        ("FILE_FORMAT", "ASCII", "string", "", "File format, 'ASCII'"),
    ],
    "MODEL": [
        ("FITTYP", None, "integer", "A", "Magic Formula version: 61 (MF 6.1), 62 (MF 6.2), 6/21/52 (MF 5.2)"),
        ("TYRESIDE", "LEFT", "string", "A", "Side the tyre was measured on: LEFT or RIGHT"),
        ("LONGVL", 16.7, "length/time", "A", "Reference (measurement) speed V0"),
        ("VXLOW", 1.0, "length/time", "A", "Speed below which the low-speed slip model is used"),
        ("ROAD_INCREMENT", 0.01, "length", "", "Increment in road sampling (ADAMS)"),
        ("ROAD_DIRECTION", 1, "integer", "", "Direction of travelled distance (ADAMS)"),
        ("PROPERTY_FILE_FORMAT", "USER", "string", "", "Property file format (ADAMS)"),
        ("USER_SUB_ID", 815, "integer", "", "User subroutine id (ADAMS)"),
        ("N_TIRE_STATES", 4, "integer", "", "Number of tyre states (ADAMS)"),
        ("USE_MODE", 124, "integer", "", "Tyre use mode switch (ADAMS)"),
        ("HMAX_LOCAL", 2.5e-4, "time", "", "Local integration time step (ADAMS)"),
        ("TIME_SWITCH_INTEG", 0.1, "time", "", "Time when the local integrator is activated (ADAMS)"),
        ("FUNCTION_NAME", "default", "string", "", "Tyre interface function name (ADAMS)"),
        ("SWITCH_INTEG", 0.0, "time", "", "Time to switch the local integrator; 0 = overrule it (ADAMS)"),
    ],
    "DIMENSION": [
        ("UNLOADED_RADIUS", 0.3135, "length", "A", "Free tyre radius R0"),
        ("WIDTH", 0.205, "length", "A", "Nominal section width of the tyre"),
        ("ASPECT_RATIO", 0.6, "-", "A", "Nominal aspect ratio"),
        ("RIM_RADIUS", 0.1905, "length", "A", "Nominal rim radius"),
        ("RIM_WIDTH", 0.152, "length", "A", "Rim width"),
    ],
    "OPERATING_CONDITIONS": [
        ("INFLPRES", 220000.0, "pressure", "6", "Tyre inflation pressure (default: NOMPRES)"),
        ("NOMPRES", 220000.0, "pressure", "6", "Nominal tyre inflation pressure p0"),
    ],
    "INERTIA": [
        ("MASS", 9.3, "mass", "6", "Tyre mass"),
        ("IXX", 0.391, "mass*length^2", "6", "Tyre diametral moment of inertia"),
        ("IYY", 0.736, "mass*length^2", "6", "Tyre polar moment of inertia"),
        ("BELT_MASS", 7.0, "mass", "6", "Belt mass"),
        ("BELT_IXX", 0.34, "mass*length^2", "6", "Belt diametral moment of inertia"),
        ("BELT_IYY", 0.6, "mass*length^2", "6", "Belt polar moment of inertia"),
        ("GRAVITY", -9.81, "length/time^2", "6", "Gravity acting on the belt in Z direction"),
    ],
    "VERTICAL": [
        ("FNOMIN", 4000.0, "force", "A", "Nominal wheel load Fz0"),
        ("VERTICAL_STIFFNESS", 200000.0, "force/length", "A", "Tyre vertical stiffness Cz0 at nominal load"),
        ("VERTICAL_DAMPING", 50.0, "force*time/length", "A", "Tyre vertical damping"),
        ("MC_CONTOUR_A", 0.5, "-", "6", "Motorcycle contour ellipse A"),
        ("MC_CONTOUR_B", 0.5, "-", "6", "Motorcycle contour ellipse B"),
        ("BREFF", 8.4, "-", "A", "Low load stiffness of the effective rolling radius"),
        ("DREFF", 0.27, "-", "A", "Peak value of the effective rolling radius"),
        ("FREFF", 0.07, "-", "A", "High load stiffness of the effective rolling radius"),
        ("Q_RE0", 1.0, "-", "A", "Ratio of free tyre radius to nominal tyre radius"),
        ("Q_V1", 0.0, "-", "A", "Tyre radius increase with speed"),
        ("Q_V2", 0.0, "-", "A", "Vertical stiffness increase with speed"),
        ("Q_FZ1", 0.0, "-", "A",
         "Linear load-deflection term; 0 = derive it from VERTICAL_STIFFNESS", True),
        ("Q_FZ2", 1.0e-4, "-", "A", "Quadratic term in load vs. deflection"),
        ("Q_FCX", 0.0, "-", "6", "Longitudinal force influence on vertical stiffness"),
        ("Q_FCY", 0.0, "-", "6", "Lateral force influence on vertical stiffness"),
        ("Q_CAM", 0.0, "-", "6", "Stiffness reduction due to camber"),
        ("PFZ1", 0.0, "-", "6", "Pressure effect on vertical stiffness"),
        ("Q_FCY2", 0.0, "-", "2", "Explicit load dependency of the lateral force influence on vertical stiffness"),
        ("Q_CAM1", 0.0, "1/length", "2", "Linear load dependent camber influence on vertical stiffness"),
        ("Q_CAM2", 0.0, "1/length^2", "2", "Quadratic load dependent camber influence on vertical stiffness"),
        ("Q_CAM3", 0.0, "-", "2", "Linear load and camber dependent reduction of vertical stiffness"),
        ("Q_FYS1", 0.0, "force", "2", "Combined camber and side slip effect on vertical stiffness (constant)"),
        ("Q_FYS2", 0.0, "force", "2", "Combined camber and side slip effect on vertical stiffness (linear)"),
        ("Q_FYS3", 0.0, "force", "2", "Combined camber and side slip effect on vertical stiffness (quadratic)"),
        ("BOTTOM_OFFST", 0.01, "length", "6", "Distance to rim when bottoming starts"),
        ("BOTTOM_STIFF", 2000000.0, "force/length", "6", "Vertical stiffness of the bottomed tyre"),
        ("Q_A1", 0.0, "-", "5", "Square root term in contact length equation (MF 5.2)"),
        ("Q_A2", 0.0, "-", "5", "Linear term in contact length equation (MF 5.2)"),
    ],
    "STRUCTURAL": [
        ("LONGITUDINAL_STIFFNESS", 300000.0, "force/length", "6", "Tyre overall longitudinal stiffness"),
        ("LATERAL_STIFFNESS", 100000.0, "force/length", "6", "Tyre overall lateral stiffness"),
        ("YAW_STIFFNESS", 5000.0, "force*length/angle", "6", "Tyre overall yaw stiffness"),
        ("FREQ_LONG", 80.0, "1/time", "6", "Undamped frequency of the fore/aft and vertical mode"),
        ("FREQ_LAT", 40.0, "1/time", "6", "Undamped frequency of the lateral mode"),
        ("FREQ_YAW", 50.0, "1/time", "6", "Undamped frequency of the yaw and camber mode"),
        ("FREQ_WINDUP", 70.0, "1/time", "6", "Undamped frequency of the wind-up mode"),
        ("DAMP_LONG", 0.04, "-", "6", "Dimensionless damping of the fore/aft and vertical mode"),
        ("DAMP_LAT", 0.04, "-", "6", "Dimensionless damping of the lateral mode"),
        ("DAMP_YAW", 0.04, "-", "6", "Dimensionless damping of the yaw and camber mode"),
        ("DAMP_WINDUP", 0.04, "-", "6", "Dimensionless damping of the wind-up mode"),
        ("DAMP_RESIDUAL", 0.002, "time", "6", "Residual damping (proportional to stiffness)"),
        ("DAMP_VLOW", 0.001, "time", "6", "Additional low speed damping (proportional to stiffness)"),
        ("Q_BVX", 0.0, "-", "6", "Load and speed influence on in-plane translation stiffness"),
        ("Q_BVT", 0.0, "-", "6", "Load and speed influence on in-plane rotation stiffness"),
        ("SWIFT_PSTIFF", 0.0, "-", "6", "SWIFT ring (mftyre): sidewall stiffness pressure dependency (absent: "
         "PFZ1)", True),
        ("SWIFT_PDAMP", 0.0, "-", "6", "SWIFT ring (mftyre): sidewall and residual damping pressure dependency "
         "(absent: damping coefficients independent of pressure, f_d = 1/sqrt(f_c))", True),
        ("PCFX1", 0.0, "-", "6", "Longitudinal stiffness: linear vertical deflection dependency"),
        ("PCFX2", 0.0, "-", "6", "Longitudinal stiffness: quadratic vertical deflection dependency"),
        ("PCFX3", 0.0, "-", "6", "Longitudinal stiffness: pressure dependency"),
        ("PCFY1", 0.0, "-", "6", "Lateral stiffness: linear vertical deflection dependency"),
        ("PCFY2", 0.0, "-", "6", "Lateral stiffness: quadratic vertical deflection dependency"),
        ("PCFY3", 0.0, "-", "6", "Lateral stiffness: pressure dependency"),
        ("PCMZ1", 0.0, "-", "6", "Yaw stiffness: pressure dependency"),
    ],
    "CONTACT_PATCH": [
        ("Q_RA1", 0.5, "-", "6", "Square root term in contact length equation"),
        ("Q_RA2", 1.0, "-", "6", "Linear term in contact length equation"),
        ("Q_RB1", 1.0, "-", "6", "Root term in contact width equation"),
        ("Q_RB2", -1.0, "-", "6", "Linear term in contact width equation"),
        ("ELLIPS_SHIFT", 0.8, "-", "6", "Scaling of distance between front and rear ellipsoid"),
        ("ELLIPS_LENGTH", 1.0, "-", "6", "Semi major axis of ellipsoid"),
        ("ELLIPS_HEIGHT", 1.0, "-", "6", "Semi minor axis of ellipsoid"),
        ("ELLIPS_ORDER", 1.8, "-", "6", "Order of ellipsoid"),
        ("ELLIPS_MAX_STEP", 0.025, "length", "6", "Maximum height of road step"),
        ("ELLIPS_NWIDTH", 10, "integer", "6", "Number of parallel ellipsoids"),
        ("ELLIPS_NLENGTH", 10, "integer", "6", "Number of ellipsoids at sides of contact patch"),
        ("ENV_C1", 0.0, "-", "6", "Effective height attenuation (enveloping)", True),
        ("ENV_C2", 0.0, "-", "6", "Effective plane angle attenuation (enveloping)", True),
        ("SWIFT_REVAR", 1.0, "-", "6", "SWIFT ring (mftyre): scale factor of the effective rolling radius variation "
         "over the curved effective road (1 = the belt-band kinematics of swift.ring, 0 = no variation)", True),
    ],
    "INFLATION_PRESSURE_RANGE": [
        ("PRESMIN", 10000.0, "pressure", "6", "Minimum valid tyre inflation pressure"),
        ("PRESMAX", 1000000.0, "pressure", "6", "Maximum valid tyre inflation pressure"),
    ],
    "VERTICAL_FORCE_RANGE": [
        ("FZMIN", 100.0, "force", "A", "Minimum allowed wheel load"),
        ("FZMAX", 10000.0, "force", "A", "Maximum allowed wheel load"),
    ],
    "LONG_SLIP_RANGE": [
        ("KPUMIN", -1.5, "-", "A", "Minimum valid wheel slip"),
        ("KPUMAX", 1.5, "-", "A", "Maximum valid wheel slip"),
    ],
    "SLIP_ANGLE_RANGE": [
        ("ALPMIN", -1.5, "angle", "A", "Minimum valid slip angle"),
        ("ALPMAX", 1.5, "angle", "A", "Maximum valid slip angle"),
    ],
    "INCLINATION_ANGLE_RANGE": [
        ("CAMMIN", -0.175, "angle", "A", "Minimum valid inclination (camber) angle"),
        ("CAMMAX", 0.175, "angle", "A", "Maximum valid inclination (camber) angle"),
    ],
    "SCALING_COEFFICIENTS": [
        ("LFZO", 1.0, "-", "A", "Scale factor of nominal (rated) load"),
        ("LCX", 1.0, "-", "A", "Scale factor of Fx shape factor"),
        ("LMUX", 1.0, "-", "A", "Scale factor of Fx peak friction coefficient"),
        ("LEX", 1.0, "-", "A", "Scale factor of Fx curvature factor"),
        ("LKX", 1.0, "-", "A", "Scale factor of Fx slip stiffness"),
        ("LHX", 1.0, "-", "A", "Scale factor of Fx horizontal shift"),
        ("LVX", 1.0, "-", "A", "Scale factor of Fx vertical shift"),
        ("LGAX", 1.0, "-", "5", "Scale factor of camber for Fx (MF 5.2)"),
        ("LCY", 1.0, "-", "A", "Scale factor of Fy shape factor"),
        ("LMUY", 1.0, "-", "A", "Scale factor of Fy peak friction coefficient"),
        ("LEY", 1.0, "-", "A", "Scale factor of Fy curvature factor"),
        ("LKY", 1.0, "-", "A", "Scale factor of Fy cornering stiffness"),
        ("LKYC", 1.0, "-", "6", "Scale factor of Fy camber stiffness"),
        ("LKZC", 1.0, "-", "6", "Scale factor of Mz camber stiffness"),
        ("LHY", 1.0, "-", "A", "Scale factor of Fy horizontal shift"),
        ("LVY", 1.0, "-", "A", "Scale factor of Fy vertical shift"),
        ("LGAY", 1.0, "-", "5", "Scale factor of camber for Fy (MF 5.2)"),
        ("LTR", 1.0, "-", "A", "Scale factor of peak of pneumatic trail"),
        ("LRES", 1.0, "-", "A", "Scale factor of offset of residual torque"),
        ("LGAZ", 1.0, "-", "5", "Scale factor of camber for Mz (MF 5.2)"),
        ("LXAL", 1.0, "-", "A", "Scale factor of alpha influence on Fx"),
        ("LYKA", 1.0, "-", "A", "Scale factor of kappa influence on Fy"),
        ("LVYKA", 1.0, "-", "A", "Scale factor of kappa induced Fy"),
        ("LS", 1.0, "-", "A", "Scale factor of moment arm of Fx"),
        ("LSGKP", 1.0, "-", "5", "Scale factor of relaxation length of Fx (MF 5.2)"),
        ("LSGAL", 1.0, "-", "5", "Scale factor of relaxation length of Fy (MF 5.2)"),
        ("LGYR", 1.0, "-", "5", "Scale factor of gyroscopic torque (MF 5.2)"),
        ("LMX", 1.0, "-", "A", "Scale factor of overturning couple"),
        ("LVMX", 1.0, "-", "A", "Scale factor of Mx vertical shift"),
        ("LMY", 1.0, "-", "A", "Scale factor of rolling resistance torque"),
        ("LMP", 1.0, "-", "6", "Scale factor of parking torque"),
        ("LMUV", 0.0, "-", "6", "Friction decay with slip speed (0 = no speed effect on friction)", True),
    ],
    "LONGITUDINAL_COEFFICIENTS": [
        ("PCX1", 1.65, "-", "A", "Shape factor Cfx for longitudinal force"),
        ("PDX1", 1.3, "-", "A", "Longitudinal friction Mux at Fznom"),
        ("PDX2", -0.15, "-", "A", "Variation of friction Mux with load"),
        ("PDX3", 0.0, "-", "A", "Variation of friction Mux with camber squared"),
        ("PEX1", 0.0, "-", "A", "Longitudinal curvature Efx at Fznom"),
        ("PEX2", 0.0, "-", "A", "Variation of curvature Efx with load"),
        ("PEX3", 0.0, "-", "A", "Variation of curvature Efx with load squared"),
        ("PEX4", 0.0, "-", "A", "Factor in curvature Efx while driving"),
        ("PKX1", 20.0, "-", "A", "Longitudinal slip stiffness Kfx/Fz at Fznom"),
        ("PKX2", 0.0, "-", "A", "Variation of slip stiffness Kfx/Fz with load"),
        ("PKX3", 0.0, "-", "A", "Exponent in slip stiffness Kfx/Fz with load"),
        ("PHX1", 0.0, "-", "A", "Horizontal shift Shx at Fznom"),
        ("PHX2", 0.0, "-", "A", "Variation of shift Shx with load"),
        ("PVX1", 0.0, "-", "A", "Vertical shift Svx/Fz at Fznom"),
        ("PVX2", 0.0, "-", "A", "Variation of shift Svx/Fz with load"),
        ("PPX1", 0.0, "-", "6", "Linear influence of inflation pressure on longitudinal slip stiffness"),
        ("PPX2", 0.0, "-", "6", "Quadratic influence of inflation pressure on longitudinal slip stiffness"),
        ("PPX3", 0.0, "-", "6", "Linear influence of inflation pressure on peak longitudinal friction"),
        ("PPX4", 0.0, "-", "6", "Quadratic influence of inflation pressure on peak longitudinal friction"),
        ("RBX1", 20.0, "-", "A", "Slope factor for combined slip Fx reduction"),
        ("RBX2", 15.0, "-", "A", "Variation of slope Fx reduction with kappa"),
        ("RBX3", 0.0, "-", "6", "Influence of camber on stiffness for Fx combined"),
        ("RCX1", 1.0, "-", "A", "Shape factor for combined slip Fx reduction"),
        ("REX1", 0.0, "-", "A", "Curvature factor of combined Fx"),
        ("REX2", 0.0, "-", "A", "Curvature factor of combined Fx with load"),
        ("RHX1", 0.0, "-", "A", "Shift factor for combined slip Fx reduction"),
        ("PTX1", 0.0, "-", "5", "Relaxation length SigKap0/Fz at Fznom (MF 5.2)"),
        ("PTX2", 0.0, "-", "5", "Variation of SigKap0/Fz with load (MF 5.2)"),
        ("PTX3", 0.0, "-", "5", "Variation of SigKap0/Fz with exponent of load (MF 5.2)"),
    ],
    "OVERTURNING_COEFFICIENTS": [
        ("QSX1", 0.0, "-", "A", "Vertical shift of overturning moment"),
        ("QSX2", 0.0, "-", "A", "Camber induced overturning couple"),
        ("QSX3", 0.0, "-", "A", "Fy induced overturning couple"),
        ("QSX4", 5.0, "-", "6", "Mixed load, lateral force and camber on Mx"),
        ("QSX5", 1.0, "-", "6", "Load effect on Mx with lateral force and camber"),
        ("QSX6", 10.0, "-", "6", "B-factor of load with Mx"),
        ("QSX7", 0.0, "-", "6", "Camber with load on Mx"),
        ("QSX8", 0.0, "-", "6", "Lateral force with load on Mx"),
        ("QSX9", 0.4, "-", "6", "B-factor of lateral force with load on Mx"),
        ("QSX10", 0.0, "-", "6", "Vertical force with camber on Mx"),
        ("QSX11", 5.0, "-", "6", "B-factor of vertical force with camber on Mx"),
        ("QSX12", 0.0, "-", "6", "Camber squared induced overturning moment"),
        ("QSX13", 0.0, "-", "6", "Lateral force induced overturning moment"),
        ("QSX14", 0.0, "-", "6", "Lateral force induced overturning moment with camber"),
        ("PPMX1", 0.0, "-", "6", "Influence of inflation pressure on overturning moment"),
    ],
    "LATERAL_COEFFICIENTS": [
        ("PCY1", 1.3, "-", "A", "Shape factor Cfy for lateral forces"),
        ("PDY1", 1.1, "-", "A", "Lateral friction Muy"),
        ("PDY2", -0.15, "-", "A", "Variation of friction Muy with load"),
        ("PDY3", 0.0, "-", "A", "Variation of friction Muy with squared camber"),
        ("PEY1", 0.0, "-", "A", "Lateral curvature Efy at Fznom"),
        ("PEY2", 0.0, "-", "A", "Variation of curvature Efy with load"),
        ("PEY3", 0.0, "-", "A", "Zero order camber dependency of curvature Efy"),
        ("PEY4", 0.0, "-", "A", "Variation of curvature Efy with camber"),
        ("PEY5", 0.0, "-", "6", "Variation of curvature Efy with camber squared"),
        ("PKY1", -20.0, "-", "A", "Maximum value of stiffness Kfy/Fznom"),
        ("PKY2", 1.0, "-", "A", "Load at which Kfy reaches maximum value"),
        ("PKY3", 0.0, "-", "A", "Variation of Kfy/Fznom with camber"),
        ("PKY4", 2.0, "-", "6", "Curvature of stiffness Kfy"),
        ("PKY5", 0.0, "-", "6", "Peak stiffness variation with camber squared"),
        ("PKY6", -1.0, "-", "6", "Fy camber stiffness factor"),
        ("PKY7", 0.0, "-", "6", "Vertical load dependency of camber stiffness"),
        ("PHY1", 0.0, "-", "A", "Horizontal shift Shy at Fznom"),
        ("PHY2", 0.0, "-", "A", "Variation of shift Shy with load"),
        ("PHY3", 0.0, "-", "5", "Variation of shift Shy with camber (MF 5.2)"),
        ("PVY1", 0.0, "-", "A", "Vertical shift in Svy/Fz at Fznom"),
        ("PVY2", 0.0, "-", "A", "Variation of shift Svy/Fz with load"),
        ("PVY3", 0.0, "-", "A", "Variation of shift Svy/Fz with camber"),
        ("PVY4", 0.0, "-", "A", "Variation of shift Svy/Fz with camber and load"),
        ("PPY1", 0.0, "-", "6", "Influence of inflation pressure on cornering stiffness"),
        ("PPY2", 0.0, "-", "6", "Influence of inflation pressure on load dependency of cornering stiffness"),
        ("PPY3", 0.0, "-", "6", "Linear influence of inflation pressure on lateral peak friction"),
        ("PPY4", 0.0, "-", "6", "Quadratic influence of inflation pressure on lateral peak friction"),
        ("PPY5", 0.0, "-", "6", "Influence of inflation pressure on camber stiffness"),
        ("RBY1", 10.0, "-", "A", "Slope factor for combined Fy reduction"),
        ("RBY2", 10.0, "-", "A", "Variation of slope Fy reduction with alpha"),
        ("RBY3", 0.0, "-", "A", "Shift term for alpha in slope Fy reduction"),
        ("RBY4", 0.0, "-", "6", "Influence of camber on stiffness of Fy combined"),
        ("RCY1", 1.0, "-", "A", "Shape factor for combined Fy reduction"),
        ("REY1", 0.0, "-", "A", "Curvature factor of combined Fy"),
        ("REY2", 0.0, "-", "A", "Curvature factor of combined Fy with load"),
        ("RHY1", 0.0, "-", "A", "Shift factor for combined Fy reduction"),
        ("RHY2", 0.0, "-", "A", "Shift factor for combined Fy reduction with load"),
        ("RVY1", 0.0, "-", "A", "Kappa induced side force Svyk/Muy*Fz at Fznom"),
        ("RVY2", 0.0, "-", "A", "Variation of Svyk/Muy*Fz with load"),
        ("RVY3", 0.0, "-", "A", "Variation of Svyk/Muy*Fz with camber"),
        ("RVY4", 20.0, "-", "A", "Variation of Svyk/Muy*Fz with alpha"),
        ("RVY5", 2.0, "-", "A", "Variation of Svyk/Muy*Fz with kappa"),
        ("RVY6", 10.0, "-", "A", "Variation of Svyk/Muy*Fz with atan(kappa)"),
        ("PTY1", 0.0, "-", "5", "Peak value of relaxation length SigAlp0/R0 (MF 5.2)"),
        ("PTY2", 0.0, "-", "5", "Value of Fz/Fznom where SigAlp0 is extreme (MF 5.2)"),
    ],
    "ROLLING_COEFFICIENTS": [
        ("QSY1", 0.01, "-", "A", "Rolling resistance torque coefficient"),
        ("QSY2", 0.0, "-", "A", "Rolling resistance torque depending on Fx"),
        ("QSY3", 4.0e-4, "-", "A", "Rolling resistance torque depending on speed"),
        ("QSY4", 4.0e-5, "-", "A", "Rolling resistance torque depending on speed ^4"),
        ("QSY5", 0.0, "-", "6", "Rolling resistance torque depending on camber squared"),
        ("QSY6", 0.0, "-", "6", "Rolling resistance torque depending on load and camber squared"),
        ("QSY7", 0.85, "-", "6", "Rolling resistance torque coefficient load dependency"),
        ("QSY8", -0.4, "-", "6", "Rolling resistance torque coefficient pressure dependency"),
    ],
    "ALIGNING_COEFFICIENTS": [
        ("QBZ1", 10.0, "-", "A", "Trail slope factor for trail Bpt at Fznom"),
        ("QBZ2", 0.0, "-", "A", "Variation of slope Bpt with load"),
        ("QBZ3", 0.0, "-", "A", "Variation of slope Bpt with load squared"),
        ("QBZ4", 0.0, "-", "A", "Variation of slope Bpt with camber"),
        ("QBZ5", 0.0, "-", "A", "Variation of slope Bpt with absolute camber"),
        ("QBZ9", 10.0, "-", "A", "Factor for scaling factors of slope factor Br of Mzr"),
        ("QBZ10", 0.0, "-", "A", "Factor for dimensionless cornering stiffness of Br of Mzr"),
        ("QCZ1", 1.1, "-", "A", "Shape factor Cpt for pneumatic trail"),
        ("QDZ1", 0.12, "-", "A", "Peak trail Dpt = Dpt*(Fz/Fznom*R0)"),
        ("QDZ2", 0.0, "-", "A", "Variation of peak Dpt with load"),
        ("QDZ3", 0.0, "-", "A", "Variation of peak Dpt with camber"),
        ("QDZ4", 0.0, "-", "A", "Variation of peak Dpt with camber squared"),
        ("QDZ6", 0.0, "-", "A", "Peak residual torque Dmr = Dmr/(Fz*R0)"),
        ("QDZ7", 0.0, "-", "A", "Variation of peak factor Dmr with load"),
        ("QDZ8", -0.05, "-", "A", "Variation of peak factor Dmr with camber"),
        ("QDZ9", 0.0, "-", "A", "Variation of peak factor Dmr with camber and load"),
        ("QDZ10", 0.0, "-", "6", "Variation of peak factor Dmr with camber squared"),
        ("QDZ11", 0.0, "-", "6", "Variation of Dmr with camber squared and load"),
        ("QEZ1", 0.0, "-", "A", "Trail curvature Ept at Fznom"),
        ("QEZ2", 0.0, "-", "A", "Variation of curvature Ept with load"),
        ("QEZ3", 0.0, "-", "A", "Variation of curvature Ept with load squared"),
        ("QEZ4", 0.0, "-", "A", "Variation of curvature Ept with sign of Alpha-t"),
        ("QEZ5", 0.0, "-", "A", "Variation of Ept with camber and sign Alpha-t"),
        ("QHZ1", 0.0, "-", "A", "Trail horizontal shift Sht at Fznom"),
        ("QHZ2", 0.0, "-", "A", "Variation of shift Sht with load"),
        ("QHZ3", 0.0, "-", "A", "Variation of shift Sht with camber"),
        ("QHZ4", 0.0, "-", "A", "Variation of shift Sht with camber and load"),
        ("PPZ1", 0.0, "-", "6", "Effect of inflation pressure on length of pneumatic trail"),
        ("PPZ2", 0.0, "-", "6", "Influence of inflation pressure on residual aligning torque"),
        ("SSZ1", 0.0, "-", "A", "Nominal value of s/R0: effect of Fx on Mz"),
        ("SSZ2", 0.0, "-", "A", "Variation of distance s/R0 with Fy/Fznom"),
        ("SSZ3", 0.0, "-", "A", "Variation of distance s/R0 with camber"),
        ("SSZ4", 0.0, "-", "A", "Variation of distance s/R0 with load and camber"),
        ("QTZ1", 0.0, "-", "5", "Gyration torque constant (MF 5.2)"),
        ("MBELT", 0.0, "mass", "5", "Belt mass of the wheel for the gyroscopic torque (MF 5.2)"),
    ],
    "TURNSLIP_COEFFICIENTS": [
        ("PDXP1", 0.4, "-", "6", "Peak Fx reduction due to spin"),
        ("PDXP2", 0.0, "-", "6", "Peak Fx reduction due to spin with varying load"),
        ("PDXP3", 0.0, "-", "6", "Peak Fx reduction due to spin with kappa"),
        ("PKYP1", 1.0, "-", "6", "Cornering stiffness reduction due to spin"),
        ("PDYP1", 0.4, "-", "6", "Peak Fy reduction due to spin"),
        ("PDYP2", 0.0, "-", "6", "Peak Fy reduction due to spin with varying load"),
        ("PDYP3", 0.0, "-", "6", "Peak Fy reduction due to spin with alpha"),
        ("PDYP4", 0.0, "-", "6", "Peak Fy reduction due to square root of spin"),
        ("PHYP1", 1.0, "-", "6", "Fy-alpha curve lateral shift limitation"),
        ("PHYP2", 0.15, "-", "6", "Fy-alpha curve maximum lateral shift"),
        ("PHYP3", 0.0, "-", "6", "Fy-alpha curve maximum lateral shift varying with load"),
        ("PHYP4", -4.0, "-", "6", "Fy-alpha curve maximum lateral shift parameter"),
        ("PECP1", 0.5, "-", "6", "Camber w.r.t. spin reduction factor in camber stiffness"),
        ("PECP2", 0.0, "-", "6", "Camber w.r.t. spin reduction factor varying with load"),
        ("QDTP1", 10.0, "-", "6", "Pneumatic trail reduction factor due to turn slip"),
        ("QCRP1", 0.2, "-", "6", "Turning moment at constant turning and zero forward speed"),
        ("QCRP2", 0.1, "-", "6", "Turn slip moment (at alpha = 90 deg) increase with spin"),
        ("QBRP1", 0.1, "-", "6", "Residual (spin) torque reduction factor due to side slip"),
        ("QDRP1", 1.0, "-", "6", "Turn slip moment peak magnitude"),
        ("QDRP2", 0.0, "-", "6", "Turn slip moment peak position (not used by the reference evaluator)", True),
    ],
}


#: Fit bounds (min, max); parameters not listed are free.
_FIT_BOUNDS: dict[str, tuple[float, float]] = {
    "PCX1": (0.3, 3.0), "PCY1": (0.3, 3.0), "QCZ1": (0.3, 3.0), "RCX1": (0.3, 3.0), "RCY1": (0.3, 3.0),
    "PDX1": (0.05, 5.0), "PDY1": (0.05, 5.0), "PKX1": (0.5, 300.0), "PKY1": (-300.0, -0.5), "PKY2": (0.1, 20.0),
    "PKY4": (0.5, 3.0), "PEX1": (-30.0, 1.0), "PEY1": (-30.0, 1.0), "QEZ1": (-30.0, 1.0), "REX1": (-30.0, 1.0),
    "REY1": (-30.0, 1.0), "QDZ1": (0.0, 1.0), "QBZ1": (0.3, 200.0), "QBZ9": (0.0, 200.0), "RBX1": (0.1, 300.0),
    "RBY1": (0.1, 300.0), "RVY4": (0.0, 500.0), "RVY5": (-3.0, 3.0), "RVY6": (0.0, 200.0), "RBX2": (-300.0, 300.0),
    "VERTICAL_STIFFNESS": (1.0e4, 1.0e7), "Q_FZ2": (0.0, 60.0), "Q_RE0": (0.8, 1.2), "BREFF": (0.0, 100.0),
    "DREFF": (0.0, 5.0), "FREFF": (-2.0, 2.0), "QSY1": (-0.1, 0.1), "QSY7": (0.0, 3.0), "PFZ1": (-5.0, 5.0),
    "QSX11": (0.0, 100.0),
}

#: Sign symmetries of the equations: negating the parameter together with its partners leaves every output
#: unchanged (QSX10 atan(QSX11 Fz/Fz0): atan is odd; cos(atan(RVY4 alpha)): even; sin(RVY5 atan(RVY6 kappa)):
#: odd). The fit bounds keep one sign (the pair's scale and sign are then one parameter each); a file with the
#: other sign (the MFeval samples: QSX11 = -1.76, RVY4 = -97, RVY6 = -27.5) is the same tyre in the other form.
SIGN_SYMMETRIC: dict[str, tuple[str, ...]] = {"QSX11": ("QSX10",), "RVY4": (), "RVY6": ("RVY5",)}

#: Parameters whose value selects the form of the equations: the model version and side, the load floor, the MF
#: 6.2 camber deflection (skipped when both Q_CAM1, Q_CAM2 are 0), the MF 5.2 patch default (Q_A1 = Q_A2 = 0),
#: the sign branch of PHYP4 and the overturning moment's parameters (QSX1-QSX14: its QSX12-QSX14 term is left out
#: of the graph when all three are 0; QSX1-QSX11 select nothing since the draft's eq. 49 was found to be the same
#: expression, kept here so that the fit's batches and the CasADi guard behave as before).
_SELECTS_FORM = frozenset(["FITTYP", "TYRESIDE", "FZMIN", "Q_CAM1", "Q_CAM2", "Q_A1", "Q_A2", "PHYP4",
                           *(f"QSX{i}" for i in range(1, 15))])

#: The value that switches a parameter's effect off: 0, except the load exponent of the rolling resistance.
_NEUTRAL: dict[str, float] = {**dict.fromkeys("""
    PPY1 PPY2 PPX1 PPX2 PPX3 PPX4 PPY3 PPY4 PPY5 PPZ1 PPZ2 PFZ1 PPMX1 QSY8 PKY3 PKY5 PKY6 PKY7 PVY3 PVY4 PDY3
    PEY4 PEY5 PDX3 QBZ4 QBZ5 QDZ3 QDZ4 QEZ5 QHZ3 QHZ4 QDZ8 QDZ9 QDZ10 QDZ11 QSX2 QSX10 QSX12 QSY5 QSY6 RBX3 RBY4
    RVY3 SSZ3 SSZ4 Q_CAM1 Q_CAM2 Q_CAM3 Q_FYS1 Q_FYS2 Q_FYS3 PDX2 PDY2 PEX2 PEX3 PEY2 PKX2 PKX3 QBZ2 QBZ3 QDZ2
    QEZ2 QEZ3 QHZ2 QDZ7 PHX2 PVX2 PHY2 PVY2 REX2 REY2 RHY2 RVY2 LMUV QSY3 QSY4 Q_V1 Q_V2 RBX1 RBY1 RVY1 SSZ1
    SSZ2 QSY2 PHX1 PVX1 PHY1 PVY1 QHZ1 PEX4 PEY3 QEZ4 QDZ6 QBZ10 QSX1 QSX3 QSX4 QSX13 QSX14 Q_FZ2 Q_FCX Q_FCY
    Q_FCY2 PDXP1 PDYP1 PKYP1 QDTP1 QBRP1 QCRP1""".split(), 0.0), "QSY7": 1.0}

#: The fitting stage of each parameter it fits or refits, in the order the refits free them (the stage's groups
#: first, :data:`mftyre.fit.stages.STAGES`; then the parameters no group lists, refitted with the stage).
_STAGE: dict[str, str] = {
    "pure_fx": "PCX1 PDX1 PEX1 PKX1 PEX4 PHX1 PVX1 PDX2 PEX2 PKX2 PHX2 PVX2 PEX3 PKX3 PDX3 PPX1 PPX3 PPX2 PPX4 "
               "PDXP1 PDXP2 PDXP3",
    "pure_fy": "PCY1 PDY1 PEY1 PKY1 PEY3 PHY1 PVY1 PDY2 PEY2 PKY2 PHY2 PVY2 PKY4 PDY3 PEY4 PEY5 PKY3 PKY6 PVY3 PKY5 "
               "PKY7 PVY4 PPY1 PPY3 PPY2 PPY4 PPY5 LMUV PDYP1 PDYP2 PDYP3 PDYP4 PKYP1 PHYP1 PHYP2 PHYP3 PHYP4 PECP1 "
               "PECP2",
    "mz": "QBZ1 QCZ1 QDZ1 QEZ1 QDZ6 QBZ9 QEZ4 QHZ1 QBZ2 QDZ2 QEZ2 QDZ7 QHZ2 QBZ3 QEZ3 QBZ4 QBZ5 QDZ3 QDZ4 QEZ5 QHZ3 "
          "QDZ8 QDZ10 QHZ4 QDZ9 QDZ11 PPZ1 PPZ2 QBZ10 QDTP1 QCRP1 QCRP2 QBRP1 QDRP1 QDRP2",
    "combined_fx": "RBX1 RBX2 RCX1 REX1 RHX1 REX2 RBX3",
    "combined_fy": "RBY1 RBY2 RBY3 RCY1 REY1 RHY1 RVY1 RVY4 RVY5 RVY6 REY2 RHY2 RVY2 RBY4 RVY3",
    "mz_combined": "SSZ1 SSZ2 SSZ3 SSZ4",
    "mx": "QSX1 QSX3 QSX2 QSX10 QSX11 PPMX1 QSX4 QSX5 QSX6 QSX7 QSX8 QSX9 QSX12 QSX13 QSX14",
    "my": "QSY1 QSY3 QSY4 QSY7 QSY5 QSY6 QSY8 QSY2",
    "vertical": "VERTICAL_STIFFNESS Q_FZ2 Q_RE0 PFZ1 Q_V1 Q_V2 Q_FCX Q_FCY Q_FCY2 Q_CAM1 Q_CAM2 Q_CAM3 Q_FYS1 Q_FYS2 "
                "Q_FYS3",
    "rolling_radius": "BREFF DREFF FREFF",
}

#: Stage -> its parameters, in the order of :data:`_STAGE` (the order the refits free them).
STAGE_MEMBERS: dict[str, tuple[str, ...]] = {stage: tuple(names.split()) for stage, names in _STAGE.items()}


def _build() -> dict[str, ParamSpec]:
    out: dict[str, ParamSpec] = {}
    stage_of = {n: stage for stage, names in STAGE_MEMBERS.items() for n in names}
    for section in SECTIONS:
        for row in _TABLE.get(section, ()):
            name, default, unit, vcode, desc = row[:5]
            optional = bool(row[5]) if len(row) > 5 else False
            if name in out:  # pragma: no cover - guards the table itself
                raise RuntimeError(f"duplicate parameter {name} in the schema")
            out[name] = ParamSpec(name, section, default, unit, desc, _V[vcode], optional,
                                  bounds=_FIT_BOUNDS.get(name), selects_form=name in _SELECTS_FORM,
                                  neutral=_NEUTRAL.get(name), stage=stage_of.get(name))
    unknown = (set(_FIT_BOUNDS) | _SELECTS_FORM | set(_NEUTRAL) | set(stage_of)) - set(out)
    if unknown:  # pragma: no cover - guards the tables
        raise RuntimeError(f"facts about parameters not in the schema: {sorted(unknown)}")
    return out


#: The schema, in canonical order (section order, then the usual TNO order within a section).
PARAMETERS: dict[str, ParamSpec] = _build()

#: Views of the fitting facts: name -> fit bounds; the names whose value selects the equations' form.
FIT_BOUNDS: dict[str, tuple[float, float]] = {n: s.bounds for n, s in PARAMETERS.items() if s.bounds is not None}
SELECTS_FORM: frozenset[str] = frozenset(n for n, s in PARAMETERS.items() if s.selects_form)

#: Parameters whose default is computed from other parameters when they are absent: name -> (source
#: parameters, function of the values dict). Applied after all constant defaults are in place.
DERIVED_DEFAULTS: dict[str, tuple[tuple[str, ...], Any]] = {
    "INFLPRES": (("NOMPRES",), lambda v: v["NOMPRES"]),
}


#: The coefficients a file of each model version must define itself: without them the pure-slip curves
#: (peak D, shape C, slip stiffness K), the pneumatic trail or the vertical stiffness are generic defaults, not
#: the measured tyre (a misspelt PKY1 would silently become the default). ``check_tir`` reports their absence
#: as an error; ``load_tir`` warns (MissingParameterWarning) as for every missing parameter.
CORE_PARAMETERS: dict[str, tuple[str, ...]] = {
    "52": ("FNOMIN", "UNLOADED_RADIUS", "VERTICAL_STIFFNESS", "PCX1", "PDX1", "PKX1", "PCY1", "PDY1", "PKY1",
           "PKY2", "QBZ1", "QCZ1", "QDZ1"),
    "61": ("FNOMIN", "UNLOADED_RADIUS", "VERTICAL_STIFFNESS", "NOMPRES", "PCX1", "PDX1", "PKX1", "PCY1", "PDY1",
           "PKY1", "PKY2", "QBZ1", "QCZ1", "QDZ1"),
}
CORE_PARAMETERS["62"] = CORE_PARAMETERS["61"]

_POSITIVE = {
    "FNOMIN": "the nominal load Fz0, which every normalised load divides by",
    "LFZO": "the scale factor of the nominal load (a negative one flips the force signs)",
    "LONGVL": "the reference speed, which the speed terms divide by",
    "UNLOADED_RADIUS": "the free tyre radius",
    "WIDTH": "the tyre width",
    "VERTICAL_STIFFNESS": "the vertical stiffness",
    "NOMPRES": "the nominal pressure, which the pressure increment divides by",
    "INFLPRES": "the inflation pressure",
    "VXLOW": "the low-speed limit, which the low-speed scaling divides by",
    "FZMAX": "the largest load (loads are saturated to it)",
}

#: Free radius growth with speed, Q_V1 (V/LONGVL)^2 of UNLOADED_RADIUS: less than _GROWTH_LIMIT at three times the
#: reference speed (published tyres: ~0.7 % there; the files declare no top speed, the reference speed is the scale
#: they give, 3 m/s for a tractor tyre, 16.7 m/s for a car's); loads at which Re is checked: FZMAX k/_LOAD_POINTS.
_GROWTH_LIMIT = 0.1
_SPEED_RATIO = 3.0
_LOAD_POINTS = 64


def _geometry_problems(prm) -> list[tuple[str, str]]:
    """The vertical relations of a tyre whose scales are positive must give outputs a tyre can have over the load
    range 0..FZMAX at the nominal pressure: a real Q_FZ1, an effective rolling radius Re > 0, a free radius that
    does not run away with speed, a contact patch of positive size. Plain float arithmetic (inf, never an
    OverflowError, for extreme values)."""
    out = []
    R0, Fz0, Cz0, Fzmax = (float(prm[n]) for n in ("UNLOADED_RADIUS", "FNOMIN", "VERTICAL_STIFFNESS", "FZMAX"))
    ratio = Cz0 * R0 / Fz0  # the stiffness ratio of Q_FZ1, paper (4); about 10 to 30 for real tyres
    disc = ratio * ratio - 4.0 * prm["Q_FZ2"]
    if not math.isfinite(disc):  # the name: the factor furthest from a real tyre's (Fz0 > 1 N, R0 < 100 m)
        name = "FNOMIN" if Fz0 < 1.0 else "UNLOADED_RADIUS" if R0 > 100.0 else "VERTICAL_STIFFNESS"
        out.append((name, f"the stiffness ratio VERTICAL_STIFFNESS*UNLOADED_RADIUS/FNOMIN = {Cz0!r}*{R0!r}/{Fz0!r} "
                          f"has no finite square (real tyres: about 10 to 30)"))
        return out
    if disc < 0:
        out.append(("Q_FZ2", f"(Cz0*R0/Fz0)^2 - 4*Q_FZ2 = {disc!r} < 0: Q_FZ1 = sqrt(...) is undefined "
                             "(VERTICAL_STIFFNESS too small or Q_FZ2 too large)"))
    if not abs(prm["Q_RE0"] - 1.0) < 0.5:
        out.append(("Q_RE0", f"must be within 0.5..1.5 (the free radius at standstill is Q_RE0*UNLOADED_RADIUS; "
                             f"published tyres: about 0.997-1), got {prm['Q_RE0']!r}"))
    # effective rolling radius, paper (7): Re = R_omega - Fz0/Cz (DREFF atan(BREFF Fz/Fz0) + FREFF Fz/Fz0) between
    # 0 and twice the free radius at every load up to FZMAX (the reduction is not monotone when the signs differ)
    free = R0 * prm["Q_RE0"]
    for k in range(1, _LOAD_POINTS + 1):
        fz = Fzmax * k / _LOAD_POINTS
        reduction = Fz0 / Cz0 * (prm["DREFF"] * math.atan(prm["BREFF"] * fz / Fz0) + prm["FREFF"] * fz / Fz0)
        if not -free < reduction < free:
            name = "DREFF" if abs(prm["DREFF"]) * math.pi / 2 >= abs(prm["FREFF"]) * fz / Fz0 else "FREFF"
            out.append((name, f"gives an effective rolling radius Re = {free - reduction!r} m at Fz = {fz!r} N "
                              f"(Re = R_omega - Fz0/Cz0 (DREFF atan(BREFF Fz/Fz0) + FREFF Fz/Fz0), R_omega = {free!r} m): "
                              f"expected 0 < Re < 2 R_omega (published: DREFF about 0.2-0.3, FREFF about 0.01-0.1), "
                              f"got DREFF = {prm['DREFF']!r}, FREFF = {prm['FREFF']!r}"))
            break
    growth = prm["Q_V1"] * _SPEED_RATIO**2  # free radius growth with speed, paper (1), at _SPEED_RATIO LONGVL
    if not abs(growth) < _GROWTH_LIMIT:
        out.append(("Q_V1", f"makes the free radius change by {100 * growth:.3g} % of UNLOADED_RADIUS at "
                            f"{_SPEED_RATIO:g} LONGVL (Q_V1 (V/LONGVL)^2): expected less than {100 * _GROWTH_LIMIT:g} % "
                            f"(published tyres: Q_V1 about 1e-3), got Q_V1 = {prm['Q_V1']!r}"))
    # contact patch, paper (9), (10) (MF 5.2: Q_A1, Q_A2): a/sqrt(x) and b/x^(1/3) are monotone in the load x,
    # so a, b >= 0 over (0, FZMAX] when the root term is not negative and the size at FZMAX is not negative
    if prm.version == "52":
        if prm["Q_A1"] != 0.0 or prm["Q_A2"] != 0.0:
            y = Fzmax / Fz0
            terms = [("A", "Q_A1", "Q_A2", R0 * (prm["Q_A2"] * y + prm["Q_A1"] * math.sqrt(y)))]
        else:
            terms = []
    else:
        x = min(Fzmax / (Cz0 * R0), 1.0)  # the load term Fz/(Cz R0), at most the deflection of a flat tyre
        terms = [("A", "Q_RA1", "Q_RA2", R0 * (prm["Q_RA2"] * x + prm["Q_RA1"] * math.sqrt(x))),
                 ("B", "Q_RB1", "Q_RB2", prm["WIDTH"] * (prm["Q_RB2"] * x + prm["Q_RB1"] * x ** (1.0 / 3.0)))]
    for size, root, linear, at_max in terms:
        half = "half length a" if size == "A" else "half width b"
        if prm[root] < 0:
            out.append((root, f"must not be negative (the root term of the contact-patch {half}: a negative one "
                              f"gives a negative patch at small loads), got {prm[root]!r}"))
        elif not at_max >= 0:
            out.append((linear, f"gives a negative contact-patch {half} = {at_max!r} m at FZMAX = {Fzmax!r} N "
                                f"({linear} = {prm[linear]!r}, {root} = {prm[root]!r})"))
    return out


#: The pressures any real tyre runs at, relative to NOMPRES: (1 - span .. 1 + span) NOMPRES = 0.5-1.5 NOMPRES (the
#: published files declare 0.85-1.15, the TNO file 0.05-4.5). The fit's verification checks this domain
#: (fit.verify.physical_domain), and the SWIFT sidewall factors f_c = 1 + SWIFT_PSTIFF dpi and f_d = 1 +
#: SWIFT_PDAMP dpi (swift.ring notes; f_d = 1/sqrt(f_c) when SWIFT_PDAMP is absent) must stay positive over it.
PHYSICAL_PRESSURE_SPAN = 0.5
_SWIFT_MASSES = {"BELT_MASS": "the belt mass", "BELT_IXX": "the belt's diametral inertia",
                 "BELT_IYY": "the belt's polar inertia"}
_SWIFT_FREQUENCIES = {"FREQ_LONG": "BELT_MASS", "FREQ_LAT": "BELT_MASS", "FREQ_YAW": "BELT_IXX",
                      "FREQ_WINDUP": "BELT_IYY"}
_SWIFT_DAMPING = ("DAMP_LONG", "DAMP_LAT", "DAMP_YAW", "DAMP_WINDUP", "DAMP_RESIDUAL", "DAMP_VLOW")


def swift_invalid_values(prm) -> list[tuple[str, str]]:
    """(parameter, message) for every SWIFT ring value no tyre can have (part of :func:`invalid_values`, also
    checked by ``swift.simulate.SwiftTyre`` on parameters built by hand): belt masses, inertias and ring
    frequencies not negative (0 is how files without a ring fill [STRUCTURAL]: the ring itself refuses it,
    swift.ring.RingConstants), the frequencies with a finite stiffness (mass (2 pi f)^2), damping ratios and time constants
    finite and not negative (the time constants with a finite damping), SWIFT_PSTIFF / SWIFT_PDAMP keeping the sidewall stiffness and damping factors positive
    over 0.5-1.5 NOMPRES. Plain float arithmetic (inf, never an OverflowError)."""
    out = []
    for name, meaning in _SWIFT_MASSES.items():
        if not prm[name] >= 0:
            out.append((name, f"must not be negative ({meaning}; 0: no SWIFT ring), got {prm[name]!r}"))
    for name, mass in _SWIFT_FREQUENCIES.items():
        omega = 2.0 * math.pi * float(prm[name])
        if not prm[name] >= 0:
            out.append((name, f"must not be negative (an undamped ring-mode frequency in Hz, published: 30-110; "
                              f"0: no SWIFT ring), got {prm[name]!r}"))
        elif 0 < prm[mass] < math.inf and not math.isfinite(prm[mass] * omega * omega):
            out.append((name, f"gives an infinite ring stiffness {mass} (2 pi {name})^2 = {prm[mass]!r} (2 pi "
                              f"{prm[name]!r})^2 (a frequency in Hz, published: 30-110; a mass in kg)"))
    for name in _SWIFT_DAMPING:
        if not 0 <= prm[name] < math.inf:
            out.append((name, f"must be finite and not negative (a damping ratio or time constant), got {prm[name]!r}"))
        elif name in ("DAMP_RESIDUAL", "DAMP_VLOW") and not math.isfinite(prm[name] * float(prm["VERTICAL_STIFFNESS"])):
            out.append((name, f"gives an infinite residual damping {name} * VERTICAL_STIFFNESS (a stiffness-"
                              f"proportional time constant in s; published: about 0.001-0.003), got {prm[name]!r}"))
    for name in ("SWIFT_PSTIFF", "SWIFT_PDAMP"):
        if name in prm.missing:
            continue
        factors = [1.0 + prm[name] * dpi for dpi in (-PHYSICAL_PRESSURE_SPAN, PHYSICAL_PRESSURE_SPAN)]
        if not all(f > 0 for f in factors):
            what = "stiffness" if name == "SWIFT_PSTIFF" else "damping"
            out.append((name, f"makes the SWIFT sidewall {what} factor 1 + {name} (p - NOMPRES)/NOMPRES = "
                              f"{min(factors)!r} <= 0 within {1 - PHYSICAL_PRESSURE_SPAN:g}-{1 + PHYSICAL_PRESSURE_SPAN:g} "
                              f"NOMPRES (a negative {what}): expected |{name}| < {1 / PHYSICAL_PRESSURE_SPAN:g} "
                              f"(published PFZ1: about 0.7-0.9), got {prm[name]!r}"))
    return out


def invalid_values(prm) -> list[tuple[str, str]]:
    """(parameter, what is wrong and what is expected) for every value no tyre can have.

    The one rule shared by the .tir reader (a TirError naming file, line and parameter), the writer and
    ``check_tir``, ``MFModel.with_params`` and the FMU builders: positive scales and dimensions, slip stiffness
    scales not negative, radii in order, ranges not inverted, vertical relations a tyre can have over 0..FZMAX (a
    real Q_FZ1, Re > 0, a bounded speed growth Q_V1, a contact patch of positive size), SWIFT ring values a tyre
    can have (:func:`swift_invalid_values`), a known tyre side.
    """
    out = []
    for name, meaning in _POSITIVE.items():
        if not prm[name] > 0:
            out.append((name, f"must be positive ({meaning}), got {prm[name]!r}"))
    if not 0 <= prm["RIM_RADIUS"] < prm["UNLOADED_RADIUS"]:
        out.append(("RIM_RADIUS", f"must be at least 0 and smaller than UNLOADED_RADIUS "
                                  f"{prm['UNLOADED_RADIUS']!r}, got {prm['RIM_RADIUS']!r}"))
    for name, force in (("LKX", "Fx"), ("LKY", "Fy")):  # scales of the slip stiffnesses Kxk (4.E15), Kya (4.E25)
        if prm[name] < 0:
            out.append((name, f"must not be negative (the scale factor of the slip stiffness: a negative one turns "
                              f"{force} along the slip instead of against it), got {prm[name]!r}"))
    if prm["BOTTOM_STIFF"] < 0:
        out.append(("BOTTOM_STIFF", f"must not be negative, got {prm['BOTTOM_STIFF']!r}"))
    for lo, hi in (("PRESMIN", "PRESMAX"), ("FZMIN", "FZMAX"), ("KPUMIN", "KPUMAX"), ("ALPMIN", "ALPMAX"),
                   ("CAMMIN", "CAMMAX")):
        if prm[lo] > prm[hi]:
            out.append((lo, f"inverted range: {lo} = {prm[lo]!r} > {hi} = {prm[hi]!r}"))
    if all(prm[n] > 0 for n in _POSITIVE):
        out += _geometry_problems(prm)
    out += swift_invalid_values(prm)
    side = str(prm["TYRESIDE"]).strip().strip("'\"").upper()
    if side not in ("LEFT", "RIGHT"):
        out.append(("TYRESIDE", f"expected 'LEFT' or 'RIGHT' (the side the tyre was measured on; mftyre mirrors "
                                f"it to the other side), got {prm['TYRESIDE']!r}"))
    return out


#: Values real tyres have (SI): parameter -> (low, high, the unit a value outside probably is in). A value outside
#: is legal for the equations but no tyre has it: ``mftyre check`` reports it as an error (mm read as m, kPa as
#: Pa, degrees as radians, km/h as m/s). Ranges span bicycle to earthmover tyres.
PLAUSIBLE_RANGES = {
    "UNLOADED_RADIUS": (0.05, 3.0, "mm or inch"),
    "RIM_RADIUS": (0.0, 2.5, "mm or inch"),
    "WIDTH": (0.01, 2.0, "mm or inch"),
    "ASPECT_RATIO": (0.05, 2.0, "percent"),
    "NOMPRES": (2e4, 1.5e7, "kPa, bar or psi"),
    "INFLPRES": (2e4, 1.5e7, "kPa, bar or psi"),
    "PRESMIN": (0.0, 1.5e7, "kPa, bar or psi"),
    "PRESMAX": (2e4, 1.5e7, "kPa, bar or psi"),
    "FNOMIN": (10.0, 1e6, "kN"),
    "FZMAX": (10.0, 1e7, "kN"),
    "LONGVL": (0.1, 100.0, "km/h or mph"),
    "VXLOW": (0.0, 30.0, "km/h or mph"),
    "ALPMIN": (-1.6, 1.6, "degrees"),  # about pi/2 (files round it to 1.5708 and 1.571)
    "ALPMAX": (-1.6, 1.6, "degrees"),
    "CAMMIN": (-1.6, 1.6, "degrees"),
    "CAMMAX": (-1.6, 1.6, "degrees"),
    "VERTICAL_STIFFNESS": (1e3, 1e9, "N/mm or kN/m"),
}


def implausible_values(prm) -> list[tuple[str, str]]:
    """(parameter, message) for every value outside :data:`PLAUSIBLE_RANGES`: legal for the equations, but no
    tyre has it (a unit mistaken for SI, most likely)."""
    out = []
    for name, (low, high, unit) in PLAUSIBLE_RANGES.items():
        if name not in PARAMETERS:
            continue
        value = prm[name]
        if isinstance(value, (int, float)) and not low <= value <= high:
            out.append((name, f"{value!r} is outside {low:g} .. {high:g} ({PARAMETERS[name].unit} in SI), where "
                              f"every tyre lies: written in {unit}? (check [UNITS] of the file, or the value)"))
    return out


def version_of_fittyp(fittyp: int) -> str:
    """Model version ("52", "61" or "62") selected by a FITTYP code; ModelInputError when invalid."""
    try:
        return VALID_FITTYP[int(fittyp)]
    except (KeyError, TypeError, ValueError):
        raise ModelInputError(
            f"unknown FITTYP {fittyp!r}: expected 61 (MF 6.1), 62 (MF 6.2) or an MF 5.2 code (6, 21, 50-59)"
        ) from None


def parameters_by_section() -> dict[str, list[ParamSpec]]:
    """The schema grouped by canonical section (every section of SECTIONS, [UNITS] empty)."""
    out: dict[str, list[ParamSpec]] = {s: [] for s in SECTIONS}
    for spec in PARAMETERS.values():
        out[spec.section].append(spec)
    return out


def describe(name: str) -> str:
    """One paragraph describing parameter ``name`` (for docs, CLI help and error messages)."""
    spec = PARAMETERS.get(str(name).upper())
    if spec is None:
        raise ModelInputError(f"unknown parameter {name!r}: not in the mftyre parameter schema")
    vers = ", ".join(f"MF {v[0]}.{v[1]}" for v in sorted(spec.versions)) or "none (file/ADAMS setting)"
    default = "required" if spec.default is None else repr(spec.default)
    if spec.name in DERIVED_DEFAULTS:
        default += " (when absent: " + ", ".join(DERIVED_DEFAULTS[spec.name][0]) + ")"
    opt = "; optional (default means the effect is absent)" if spec.optional else ""
    return (
        f"{spec.name} [{spec.section}]: {spec.description}. Unit kind: {spec.unit}; default: {default}; "
        f"used by: {vers}{opt}."
    )


# ----------------------------------------------------------------------------------------------------
# Values
# ----------------------------------------------------------------------------------------------------


def _coerce(spec: ParamSpec, value: Any) -> float | int | str:
    """Check ``value`` against the kind of ``spec`` and return it as a plain Python value."""
    if spec.is_string:
        if not isinstance(value, str):
            raise ModelInputError(f"{spec.name} must be a string, got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ModelInputError(f"{spec.name} must be a number ({spec.description}), got {value!r}")
    fval = float(value)
    if not math.isfinite(fval):
        raise ModelInputError(f"{spec.name} must be finite, got {value!r}")
    if spec.is_integer:
        if fval != int(fval):
            raise ModelInputError(f"{spec.name} must be an integer, got {value!r}")
        ival = int(fval)
        if spec.name == "FITTYP":
            version_of_fittyp(ival)
        return ival
    return fval


class TyreParameters(Mapping):
    """An immutable mapping parameter name -> value, numbers in SI.

    Every schema parameter is present (absent ones hold their default). Numbers are Python ``float``
    (``int`` for integer parameters such as FITTYP), strings are ``str``. Access as ``prm.PCX1`` or
    ``prm["PCX1"]``; iteration follows the canonical order of :data:`PARAMETERS`. Equality compares the
    schema values only.

    Attributes: ``source`` (file it came from or None), ``missing`` (parameters absent from the source and
    filled with defaults, all of them), ``missing_reported`` (those among them that the file's model
    version uses and that are not optional: the ones a reader warns about), ``unknown`` (name ->
    (section, value) for parameters not in the schema, kept for writing), ``extra_sections`` (unknown or
    tabular sections kept verbatim), ``units_as_read`` (the [UNITS] entries as written in the file),
    ``lines`` (name -> line number in the source).
    """

    __slots__ = (
        "_values",
        "source",
        "missing",
        "missing_reported",
        "unknown",
        "extra_sections",
        "units_as_read",
        "lines",
    )

    def __init__(
        self,
        values: Mapping[str, Any],
        *,
        source: str | None = None,
        missing: tuple[str, ...] | None = None,
        unknown: Mapping[str, tuple[str, object]] | None = None,
        extra_sections: Mapping[str, str] | None = None,
        units_as_read: Mapping[str, str] | None = None,
        lines: Mapping[str, int] | None = None,
    ):
        given = {}
        for key, val in values.items():
            name = str(key).upper()
            spec = PARAMETERS.get(name)
            if spec is None:
                raise ModelInputError(f"unknown parameter {key!r}: not in the mftyre parameter schema")
            given[name] = _coerce(spec, val)
        if "FITTYP" not in given:
            raise ModelInputError("FITTYP is required (61, 62, or an MF 5.2 code 6/21/52)")
        full: dict[str, Any] = {}
        absent = []
        for name, spec in PARAMETERS.items():
            if name in given:
                full[name] = given[name]
            else:
                full[name] = spec.default
                absent.append(name)
        for name, (_, fn) in DERIVED_DEFAULTS.items():
            if name not in given:
                full[name] = _coerce(PARAMETERS[name], fn(full))
        version = version_of_fittyp(full["FITTYP"])
        missing_t = tuple(absent) if missing is None else tuple(missing)
        reported = tuple(
            n for n in missing_t if version in PARAMETERS[n].versions and not PARAMETERS[n].optional
        )
        _set = object.__setattr__
        _set(self, "_values", full)
        _set(self, "source", None if source is None else str(source))
        _set(self, "missing", missing_t)
        _set(self, "missing_reported", reported)
        _set(self, "unknown", dict(unknown or {}))
        _set(self, "extra_sections", dict(extra_sections or {}))
        _set(self, "units_as_read", dict(units_as_read or {}))
        _set(self, "lines", dict(lines or {}))

    # -- mapping protocol -----------------------------------------------------------------------------
    def __getitem__(self, name: str):
        try:
            return self._values[name]
        except KeyError:
            raise KeyError(f"{name!r} is not a parameter of the mftyre schema") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __getattr__(self, name: str):
        # only called when normal lookup fails, i.e. for parameter names
        try:
            return object.__getattribute__(self, "_values")[name]
        except KeyError:
            raise AttributeError(f"TyreParameters has no parameter or attribute {name!r}") from None

    def __setattr__(self, name, value):
        raise AttributeError("TyreParameters is immutable; use .replace(NAME=value)")

    def __delattr__(self, name):
        raise AttributeError("TyreParameters is immutable")

    def __reduce__(self):
        state = {k: getattr(self, k) for k in self.__slots__}
        return (_restore, (state,))

    def __repr__(self) -> str:
        src = f", source={self.source!r}" if self.source else ""
        return f"TyreParameters(FITTYP={self.fittyp}, {len(self)} parameters{src})"

    # -- properties --------------------------------------------------------------------------------------
    @property
    def fittyp(self) -> int:
        return self._values["FITTYP"]

    @property
    def version(self) -> str:
        """"52", "61" or "62"."""
        return version_of_fittyp(self._values["FITTYP"])

    # -- derived objects ---------------------------------------------------------------------------------
    def replace(self, **changes) -> "TyreParameters":
        """A new object with ``changes`` applied (schema names only; values checked against their kind). The
        values not changed are this object's, already checked: only the changes are coerced."""
        values = dict(self._values)
        changed = set()
        for key, val in changes.items():
            name = key.upper()
            spec = PARAMETERS.get(name)
            if spec is None:
                raise ModelInputError(f"unknown parameter {key!r}: not in the mftyre parameter schema")
            values[name] = _coerce(spec, val)
            changed.add(name)
        version = version_of_fittyp(values["FITTYP"])
        missing = tuple(n for n in self.missing if n not in changed)
        new = object.__new__(TyreParameters)
        _set = object.__setattr__
        _set(new, "_values", values)
        _set(new, "source", self.source)
        _set(new, "missing", missing)
        _set(new, "missing_reported", tuple(n for n in missing if version in PARAMETERS[n].versions
                                            and not PARAMETERS[n].optional))
        for name in ("unknown", "extra_sections", "units_as_read", "lines"):
            _set(new, name, dict(getattr(self, name)))
        return new

    def to_dict(self) -> dict:
        """name -> value for every schema parameter, in canonical order (unknown ones not included)."""
        return dict(self._values)

    @classmethod
    def from_defaults(cls, fittyp: int = 61, **values) -> "TyreParameters":
        """Every parameter at its default, FITTYP = ``fittyp``, then ``values`` (``missing`` is empty)."""
        vals = {"FITTYP": fittyp}
        vals.update({k.upper(): v for k, v in values.items()})
        return cls(vals, missing=())


def _restore(state: dict) -> TyreParameters:
    obj = TyreParameters.__new__(TyreParameters)
    for key, val in state.items():
        object.__setattr__(obj, key, val)
    return obj
