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
