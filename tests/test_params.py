"""Tests of the parameter schema (mftyre.params)."""

from __future__ import annotations

import math
import pickle
import re
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from mftyre.errors import ModelInputError
from mftyre.params import (
    PARAMETERS,
    SECTIONS,
    MissingParameterWarning,
    ParamSpec,
    TyreParameters,
    describe,
    parameters_by_section,
)
from mftyre.tir import unit_factor

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
MFEVAL = SHARED / "reference" / "mfeval"
TIR_FILES = sorted(MFEVAL.glob("*.tir")) + [SHARED / "reference" / "tir" / "TNO_car205_60R15.tir"]
UNIT_KEYS = {"LENGTH", "FORCE", "ANGLE", "MASS", "TIME"}


def _need_shared():
    if not MFEVAL.is_dir():
        pytest.skip(f"shared reference folder not found at {MFEVAL} (tests read ../shared relative to the project)")


# ---------------------------------------------------------------------------------------- schema shape
def test_sections_and_canonical_order():
    assert SECTIONS[0] == "MDI_HEADER" and SECTIONS[1] == "UNITS" and SECTIONS[-1] == "TURNSLIP_COEFFICIENTS"
    assert len(set(SECTIONS)) == len(SECTIONS) == 21
    order = [SECTIONS.index(s.section) for s in PARAMETERS.values()]
    assert order == sorted(order), "PARAMETERS must be grouped in SECTIONS order"
    for name, spec in PARAMETERS.items():
        assert isinstance(spec, ParamSpec)
        assert spec.name == name == name.upper()
        assert spec.section in SECTIONS and spec.section != "UNITS"
        assert spec.versions <= {"52", "61", "62"}
        assert spec.description and "\n" not in spec.description


def test_every_spec_default_matches_its_kind():
    base = {k: Fraction(2) for k in ("length", "force", "mass", "time", "angle", "pressure")}
    for spec in PARAMETERS.values():
        unit_factor(spec.unit, base)  # every kind parses
        if spec.default is None:
            assert spec.name == "FITTYP"
        elif spec.unit == "string":
            assert isinstance(spec.default, str), spec.name
        elif spec.unit == "integer":
            assert type(spec.default) is int, spec.name
        else:
            assert type(spec.default) is float, spec.name


def test_compound_unit_kind_factors():
    base = {"length": Fraction(1, 1000), "force": Fraction(1000), "mass": Fraction(3), "time": Fraction(1, 10),
            "angle": Fraction(7), "pressure": Fraction(5)}
    assert unit_factor("force/length", base) == Fraction(10**6)
    assert unit_factor("force*time/length", base) == Fraction(10**5)
    assert unit_factor("mass*length^2", base) == Fraction(3, 10**6)
    assert unit_factor("1/length^2", base) == Fraction(10**6)
    assert unit_factor("length/time^2", base) == Fraction(1, 10)
    assert unit_factor("force*length/angle", base) == Fraction(1, 7)
    assert unit_factor("-", base) == 1 and unit_factor("integer", base) == 1


def test_unit_kind_rule():
    # MF coefficients and scale factors are dimensionless (MBELT is a physical mass in the aligning section)
    for spec in PARAMETERS.values():
        if spec.section.endswith("_COEFFICIENTS") and spec.name != "MBELT":
            assert spec.unit == "-", spec.name
    for name in ("BREFF", "DREFF", "FREFF", "Q_RE0", "Q_V1", "Q_V2", "Q_FZ2", "Q_FCX", "Q_FCY", "Q_FCY2", "PFZ1",
                 "Q_RA1", "Q_RA2", "Q_RB1", "Q_RB2", "PCFX1", "PCFY3", "ELLIPS_SHIFT", "ELLIPS_LENGTH",
                 "ELLIPS_HEIGHT", "ELLIPS_ORDER", "ASPECT_RATIO", "KPUMIN", "KPUMAX", "DAMP_LONG"):
        assert PARAMETERS[name].unit == "-", name
    expected = {
        "UNLOADED_RADIUS": "length", "RIM_RADIUS": "length", "WIDTH": "length", "BOTTOM_OFFST": "length",
        "ELLIPS_MAX_STEP": "length", "FNOMIN": "force", "FZMIN": "force", "FZMAX": "force",
        "Q_FYS1": "force", "Q_FYS2": "force", "Q_FYS3": "force",
        "VERTICAL_STIFFNESS": "force/length", "BOTTOM_STIFF": "force/length",
        "LONGITUDINAL_STIFFNESS": "force/length", "LATERAL_STIFFNESS": "force/length",
        "VERTICAL_DAMPING": "force*time/length", "MASS": "mass", "BELT_MASS": "mass", "MBELT": "mass",
        "IXX": "mass*length^2", "BELT_IYY": "mass*length^2", "LONGVL": "length/time", "VXLOW": "length/time",
        "NOMPRES": "pressure", "INFLPRES": "pressure", "PRESMIN": "pressure", "PRESMAX": "pressure",
        "ALPMIN": "angle", "ALPMAX": "angle", "CAMMIN": "angle", "CAMMAX": "angle",
        "Q_CAM1": "1/length", "Q_CAM2": "1/length^2", "GRAVITY": "length/time^2",
        "FREQ_LONG": "1/time", "FREQ_LAT": "1/time", "FREQ_YAW": "1/time", "FREQ_WINDUP": "1/time",
        "FITTYP": "integer", "TYRESIDE": "string", "FUNCTION_NAME": "string",
    }
    for name, kind in expected.items():
        assert PARAMETERS[name].unit == kind, name


def test_schema_contains_named_extras_and_scale_defaults():
    for name in ("LMUV", "LGAX", "LGAY", "LGAZ", "LGYR", "LSGKP", "LSGAL", "QTZ1", "MBELT", "ENV_C1", "ENV_C2",
                 "Q_RA1", "Q_RB2", "ELLIPS_NLENGTH", "FREQ_WINDUP", "DAMP_VLOW", "FILE_TYPE", "FILE_VERSION",
                 "FILE_FORMAT", "LONGVL", "VXLOW", "ROAD_INCREMENT", "ROAD_DIRECTION", "PROPERTY_FILE_FORMAT",
                 "USER_SUB_ID", "N_TIRE_STATES", "USE_MODE", "HMAX_LOCAL", "TIME_SWITCH_INTEG",
                 "SWITCH_INTEG", "FUNCTION_NAME", "PDXP1", "QDRP1"):
        assert name in PARAMETERS, name
    scale = [s for s in PARAMETERS.values() if s.section == "SCALING_COEFFICIENTS"]
    assert len(scale) >= 30
    for spec in scale:
        assert spec.default == (0.0 if spec.name == "LMUV" else 1.0), spec.name
    assert PARAMETERS["LMUV"].optional
    assert PARAMETERS["PDXP1"].default == 0.4


def test_schema_covers_every_name_in_the_shared_files():
    _need_shared()
    names = set()
    for path in TIR_FILES:
        section = None
        for raw in path.read_text().splitlines():
            s = raw.strip()
            if s.startswith("["):
                section = s.strip("[]").upper()
                continue
            m = re.match(r"([A-Za-z_0-9]+)\s*=", s)
            if m and section not in ("UNITS", "SHAPE"):
                names.add(m.group(1).upper())
    for csv in MFEVAL.glob("*_parameters.csv"):
        for line in csv.read_text().splitlines()[1:]:
            name = line.split(",")[0]
            if name not in UNIT_KEYS:
                names.add("MASS" if name == "MASS1" else name)
    assert len(names) > 280
    assert sorted(names - set(PARAMETERS)) == []


def test_parameters_by_section_and_describe():
    groups = parameters_by_section()
    assert list(groups) == list(SECTIONS)
    assert sum(len(v) for v in groups.values()) == len(PARAMETERS)
    assert [s.name for s in groups["LONG_SLIP_RANGE"]] == ["KPUMIN", "KPUMAX"]
    text = describe("pcx1")
    assert "PCX1" in text and "LONGITUDINAL_COEFFICIENTS" in text and "1.65" in text
    assert "NOMPRES" in describe("INFLPRES")
    with pytest.raises(ModelInputError, match="NOPE"):
        describe("NOPE")


# ---------------------------------------------------------------------------------------- TyreParameters
def test_from_defaults_mapping_protocol():
    prm = TyreParameters.from_defaults(62, FNOMIN=5000)
    assert prm.fittyp == 62 and prm.version == "62"
    assert prm.FNOMIN == prm["FNOMIN"] == 5000.0 and type(prm.FNOMIN) is float
    assert list(prm) == list(PARAMETERS)
    assert len(prm) == len(PARAMETERS)
    assert "PCX1" in prm and "NOT_A_PARAMETER" not in prm
    assert prm.PCX1 == PARAMETERS["PCX1"].default
    assert prm.missing == () and prm.source is None and prm.unknown == {} and prm.extra_sections == {}
    for name, value in prm.items():
        assert type(value) in (float, int, str), name
    with pytest.raises(AttributeError):
        prm.NOT_A_PARAMETER
    with pytest.raises(KeyError):
        prm["NOT_A_PARAMETER"]


@pytest.mark.parametrize("fittyp,version", [(6, "52"), (21, "52"), (52, "52"), (55, "52"), (61, "61"), (62, "62")])
def test_version_of_fittyp(fittyp, version):
    assert TyreParameters.from_defaults(fittyp).version == version


def test_invalid_fittyp_and_missing_fittyp():
    with pytest.raises(ModelInputError, match="FITTYP"):
        TyreParameters.from_defaults(63)
    with pytest.raises(ModelInputError, match="FITTYP"):
        TyreParameters({"PCX1": 1.0})


def test_immutable_and_replace():
    prm = TyreParameters.from_defaults(61)
    with pytest.raises(AttributeError):
        prm.PCX1 = 2.0
    new = prm.replace(PCX1=np.float64(1.7), LMUV=0.1, USE_MODE=np.int64(111))
    assert prm.PCX1 == 1.65 and new.PCX1 == 1.7 and new.LMUV == 0.1
    assert type(new.PCX1) is float and type(new.USE_MODE) is int and new.USE_MODE == 111
    with pytest.raises(ModelInputError, match="PCX99"):
        prm.replace(PCX99=1.0)
    with pytest.raises(ModelInputError, match="PCX1"):
        prm.replace(PCX1="big")
    with pytest.raises(ModelInputError, match="TYRESIDE"):
        prm.replace(TYRESIDE=1.0)
    with pytest.raises(ModelInputError, match="FNOMIN"):
        prm.replace(FNOMIN=float("nan"))
    with pytest.raises(ModelInputError, match="USE_MODE"):
        prm.replace(USE_MODE=1.5)
    with pytest.raises(ModelInputError, match="PCX1"):
        prm.replace(PCX1=True)


def test_inflpres_default_is_derived_from_nompres():
    prm = TyreParameters.from_defaults(61, NOMPRES=260000)
    assert prm.INFLPRES == 260000.0
    prm2 = TyreParameters.from_defaults(61, NOMPRES=260000, INFLPRES=240000)
    assert prm2.INFLPRES == 240000.0


def test_missing_reported_follows_versions_and_optional():
    prm = TyreParameters({"FITTYP": 61})
    assert "PCX1" in prm.missing_reported
    assert "LMUV" in prm.missing and "LMUV" not in prm.missing_reported  # optional
    assert "PTX1" not in prm.missing_reported  # MF 5.2 only
    assert "USE_MODE" not in prm.missing_reported  # ADAMS setting
    assert "Q_CAM1" not in prm.missing_reported and "Q_CAM1" in TyreParameters({"FITTYP": 62}).missing_reported


def test_pickle_round_trip():
    prm = TyreParameters.from_defaults(62, PCX1=1.5)
    back = pickle.loads(pickle.dumps(prm))
    assert back == prm and back.PCX1 == 1.5 and back.fittyp == 62


def test_warning_class():
    assert issubclass(MissingParameterWarning, UserWarning)
    assert math.isclose(TyreParameters.from_defaults().GRAVITY, -9.81)


# ------------------------------------------------------- fitting facts on the schema (issue 22 item 2)
#: fit.core.BOUNDS before the facts moved to the schema
OLD_BOUNDS = {'PCX1': (0.3, 3.0), 'PCY1': (0.3, 3.0), 'QCZ1': (0.3, 3.0), 'RCX1': (0.3, 3.0), 'RCY1': (0.3, 3.0),
    'PDX1': (0.05, 5.0), 'PDY1': (0.05, 5.0), 'PKX1': (0.5, 300.0), 'PKY1': (-300.0, -0.5), 'PKY2':
    (0.1, 20.0), 'PKY4': (0.5, 3.0), 'PEX1': (-30.0, 1.0), 'PEY1': (-30.0, 1.0), 'QEZ1': (-30.0, 1.0),
    'REX1': (-30.0, 1.0), 'REY1': (-30.0, 1.0), 'QDZ1': (0.0, 1.0), 'QBZ1': (0.3, 200.0), 'QBZ9': (0.0,
    200.0), 'RBX1': (0.1, 300.0), 'RBY1': (0.1, 300.0), 'RVY4': (0.0, 500.0), 'RVY5': (-3.0, 3.0),
    'RVY6': (0.0, 200.0), 'RBX2': (-300.0, 300.0), 'VERTICAL_STIFFNESS': (10000.0, 10000000.0), 'Q_FZ2':
    (0.0, 60.0), 'Q_RE0': (0.8, 1.2), 'BREFF': (0.0, 100.0), 'DREFF': (0.0, 5.0), 'FREFF': (-2.0, 2.0),
    'QSY1': (-0.1, 0.1), 'QSY7': (0.0, 3.0), 'PFZ1': (-5.0, 5.0), 'QSX11': (0.0, 100.0)}
#: model.STRUCTURAL_PARAMETERS before
OLD_SELECTS_FORM = ['FITTYP', 'FZMIN', 'PHYP4', 'QSX1', 'QSX10', 'QSX11', 'QSX12', 'QSX13', 'QSX14', 'QSX2', 'QSX3',
    'QSX4', 'QSX5', 'QSX6', 'QSX7', 'QSX8', 'QSX9', 'Q_A1', 'Q_A2', 'Q_CAM1', 'Q_CAM2', 'TYRESIDE']
#: gaps.catalogue.PARAM_STAGE before, in its order (name:stage)
OLD_PARAM_STAGE = """
    PCX1:pure_fx PDX1:pure_fx PEX1:pure_fx PKX1:pure_fx PEX4:pure_fx PHX1:pure_fx PVX1:pure_fx PDX2:pure_fx
    PEX2:pure_fx PKX2:pure_fx PHX2:pure_fx PVX2:pure_fx PEX3:pure_fx PKX3:pure_fx PDX3:pure_fx PPX1:pure_fx
    PPX3:pure_fx PPX2:pure_fx PPX4:pure_fx PCY1:pure_fy PDY1:pure_fy PEY1:pure_fy PKY1:pure_fy PEY3:pure_fy
    PHY1:pure_fy PVY1:pure_fy PDY2:pure_fy PEY2:pure_fy PKY2:pure_fy PHY2:pure_fy PVY2:pure_fy PKY4:pure_fy
    PDY3:pure_fy PEY4:pure_fy PEY5:pure_fy PKY3:pure_fy PKY6:pure_fy PVY3:pure_fy PKY5:pure_fy PKY7:pure_fy
    PVY4:pure_fy PPY1:pure_fy PPY3:pure_fy PPY2:pure_fy PPY4:pure_fy PPY5:pure_fy QBZ1:mz QCZ1:mz QDZ1:mz QEZ1:mz
    QDZ6:mz QBZ9:mz QEZ4:mz QHZ1:mz QBZ2:mz QDZ2:mz QEZ2:mz QDZ7:mz QHZ2:mz QBZ3:mz QEZ3:mz QBZ4:mz QBZ5:mz
    QDZ3:mz QDZ4:mz QEZ5:mz QHZ3:mz QDZ8:mz QDZ10:mz QHZ4:mz QDZ9:mz QDZ11:mz PPZ1:mz PPZ2:mz RBX1:combined_fx
    RBX2:combined_fx RCX1:combined_fx REX1:combined_fx RHX1:combined_fx REX2:combined_fx RBX3:combined_fx
    RBY1:combined_fy RBY2:combined_fy RBY3:combined_fy RCY1:combined_fy REY1:combined_fy RHY1:combined_fy
    RVY1:combined_fy RVY4:combined_fy RVY5:combined_fy RVY6:combined_fy REY2:combined_fy RHY2:combined_fy
    RVY2:combined_fy RBY4:combined_fy RVY3:combined_fy SSZ1:mz_combined SSZ2:mz_combined SSZ3:mz_combined
    SSZ4:mz_combined QSX1:mx QSX3:mx QSX2:mx QSX10:mx QSX11:mx PPMX1:mx QSY1:my QSY3:my QSY4:my QSY7:my QSY5:my
    QSY6:my QSY8:my VERTICAL_STIFFNESS:vertical Q_FZ2:vertical Q_RE0:vertical PFZ1:vertical Q_V1:vertical
    Q_V2:vertical Q_FCX:vertical Q_FCY:vertical BREFF:rolling_radius DREFF:rolling_radius FREFF:rolling_radius
    LMUV:pure_fy QSY2:my QSX4:mx QSX5:mx QSX6:mx QSX7:mx QSX8:mx QSX9:mx QSX12:mx QSX13:mx QSX14:mx QBZ10:mz
    Q_FCY2:vertical Q_CAM1:vertical Q_CAM2:vertical Q_CAM3:vertical Q_FYS1:vertical Q_FYS2:vertical
    Q_FYS3:vertical PDXP1:pure_fx PDXP2:pure_fx PDXP3:pure_fx PDYP1:pure_fy PDYP2:pure_fy PDYP3:pure_fy
    PDYP4:pure_fy PKYP1:pure_fy PHYP1:pure_fy PHYP2:pure_fy PHYP3:pure_fy PHYP4:pure_fy PECP1:pure_fy
    PECP2:pure_fy QDTP1:mz QCRP1:mz QCRP2:mz QBRP1:mz QDRP1:mz QDRP2:mz""".split()
#: effects whose switches were not all their parameters at 0 (catalogue before)
OLD_SWITCHES = {'camber_overturning': {'QSX2': 0.0, 'QSX10': 0.0}, 'load_rolling_resistance': {'QSY7': 1.0},
    'combined_fx': {'RBX1': 0.0}, 'combined_fy': {'RBY1': 0.0}, 'kappa_induced_fy': {'RVY1': 0.0},
    'combined_overturning': {'QSX4': 0.0}, 'turn_slip_fx': {'PDXP1': 0.0}, 'turn_slip_fy_peak':
    {'PDYP1': 0.0}, 'turn_slip_moment': {'QCRP1': 0.0}}
#: effects whose every parameter was a switch at neutral 0
OLD_ALL_SWITCH_ZERO = """
    pressure_cornering_stiffness pressure_slip_stiffness pressure_friction_x pressure_friction_y
    pressure_camber_stiffness pressure_trail pressure_residual_torque pressure_vertical_stiffness
    pressure_overturning pressure_rolling_resistance camber_cornering_stiffness camber_thrust camber_fy_peak
    camber_friction_x camber_trail camber_aligning_moment camber_squared_overturning camber_rolling_resistance
    camber_combined_fx camber_combined_fy camber_fx_moment_arm camber_vertical camber_side_force_vertical
    load_friction_x load_friction_y load_curvature_x load_curvature_y load_slip_stiffness load_trail
    load_residual_torque load_shift_x load_shift_y load_combined_fx load_combined_fy speed_friction
    speed_rolling_resistance speed_vertical fx_moment_arm fx_rolling_resistance fx_shift fy_shift trail_shift
    fx_curvature_asymmetry fy_curvature_asymmetry trail_curvature_asymmetry residual_torque
    residual_torque_stiffness overturning_offset lateral_force_overturning lateral_force_overturning_camber
    vertical_hardening force_vertical_stiffness side_force_deflection_vertical turn_slip_cornering_stiffness
    turn_slip_trail turn_slip_residual_torque""".split()
#: gaps.catalogue.BASE before, in its order
OLD_BASE = """
    PCX1 PDX1 PEX1 PKX1 PCY1 PDY1 PEY1 PKY1 PKY2 PKY4 QBZ1 QCZ1 QDZ1 QEZ1 QBZ9 QSY1 VERTICAL_STIFFNESS Q_RE0 PHYP1
    PHYP2 PHYP3 PHYP4 PECP1 PECP2""".split()


def test_the_fitting_facts_read_off_the_schema_are_those_the_fit_used():
    from mftyre.fit.core import BOUNDS
    from mftyre.gaps.catalogue import BASE, CATALOGUE, PARAM_STAGE
    from mftyre.params import FIT_BOUNDS, SELECTS_FORM, STAGE_MEMBERS

    assert FIT_BOUNDS == OLD_BOUNDS and BOUNDS == OLD_BOUNDS
    assert {n: s.bounds for n, s in PARAMETERS.items() if s.bounds} == OLD_BOUNDS
    assert sorted(SELECTS_FORM) == OLD_SELECTS_FORM
    old_stage = dict(x.split(":") for x in OLD_PARAM_STAGE)
    assert PARAM_STAGE == old_stage and {n: s.stage for n, s in PARAMETERS.items() if s.stage} == old_stage

    def in_order(pairs, stage):  # what the refits read: each stage's parameters in order
        return [n for n, s in pairs if s == stage]

    for stage in set(old_stage.values()):
        assert in_order(PARAM_STAGE.items(), stage) == in_order(old_stage.items(), stage)
    assert {n for names in STAGE_MEMBERS.values() for n in names} == set(PARAM_STAGE)
    assert list(BASE) == OLD_BASE
    old_neutral = {**{n: {p: 0.0 for p in CATALOGUE[n].parameters} for n in OLD_ALL_SWITCH_ZERO}, **OLD_SWITCHES}
    assert {e.name: e.neutral for e in CATALOGUE.values()} == old_neutral
    # each neutral value of the catalogue is the schema's
    assert all(PARAMETERS[p].neutral == v for e in CATALOGUE.values() for p, v in e.neutral.items())
