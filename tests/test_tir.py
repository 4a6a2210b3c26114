"""Tests of the .tir reader, writer and checker (mftyre.tir) and of `mftyre check`."""

from __future__ import annotations

import csv
import math
import re
import warnings
from pathlib import Path

import pytest

from mftyre import cli
from mftyre.errors import TirError
from mftyre.params import MissingParameterWarning, TyreParameters
from mftyre.tir import check_tir, parse_tir, read_tir, write_tir

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
MFEVAL = SHARED / "reference" / "mfeval"
TNO = SHARED / "reference" / "tir" / "TNO_car205_60R15.tir"
CSV_OF = {
    "mf61": "MagicFormula61_Parameters.tir",
    "mf62": "MagicFormula62_Parameters.tir",
    "mf52": "MagicFormula52_Parameters.tir",
    "fsae61": "FSAE_Defaults.tir",
    "pacejkabook61": "PacejkaBook_Defaults.tir",
}
ALL_TIR = [MFEVAL / f for f in CSV_OF.values()] + [TNO]
UNIT_KEYS = {"LENGTH", "FORCE", "ANGLE", "MASS", "TIME"}


def need(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"shared reference file {path} not found (tests read ../shared relative to the project root)")
    return path


def read_quiet(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingParameterWarning)
        return read_tir(path, **kw)


def parse_quiet(text, source="<string>"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingParameterWarning)
        return parse_tir(text, source)


# ------------------------------------------------------------------------ agreement with MFeval's readTIR
@pytest.mark.parametrize("prefix", sorted(CSV_OF))
def test_every_parameter_matches_mfeval_readtir(prefix):
    """Each value (including MFeval's defaults for absent parameters) equals the reference table."""
    tir = need(MFEVAL / CSV_OF[prefix])
    prm = read_quiet(tir)
    rows = list(csv.reader((MFEVAL / f"{prefix}_parameters.csv").open()))[1:]
    assert len(rows) > 280
    for name, text in rows:
        if name in UNIT_KEYS:
            got = prm.units_as_read[name]
        else:
            got = prm["MASS" if name == "MASS1" else name]
        try:
            ref = float(text)
        except ValueError:
            assert isinstance(got, str), name
            assert got.strip("'\"").lower() == text.strip("'\"").lower(), name
            continue
        assert not isinstance(got, str), name
        assert got == ref or math.isclose(got, ref, rel_tol=1e-15), (name, got, ref)


def test_tno_mf62_swift_file_against_an_independent_scan():
    tir = need(TNO)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a complete MF 6.2 file: no warning at all
        prm = read_tir(tir)
    assert prm.fittyp == 62 and prm.version == "62"
    assert prm.unknown == {} and prm.extra_sections == {} and prm.missing_reported == ()
    assert prm.TYRESIDE == "Left" and prm.FUNCTION_NAME == "TNO_DelftTyre_Adams_interface::TYR815"
    section = None
    n = 0
    for raw in tir.read_text().splitlines():
        if raw.startswith("["):
            section = raw.strip()[1:-1]
            continue
        m = re.match(r"^([A-Z_0-9]+)\s*=\s*([-+0-9.Ee]+)\s*(\$.*)?$", raw.strip())
        if m and section != "UNITS":
            assert prm[m.group(1)] == float(m.group(2)), m.group(1)
            n += 1
    assert n > 200


def test_mf52_shape_section_kept_verbatim_and_52_scale_factors_read():
    prm = read_quiet(need(MFEVAL / "MagicFormula52_Parameters.tir"))
    assert prm.version == "52" and prm.fittyp == 6
    assert prm.extra_sections["SHAPE"].split("\n") == ["{radial width}", " 1.0    0.0", " 1.0    0.4",
                                                        " 1.0    0.9", " 0.9    1.0"]
    assert (prm.LGAX, prm.LGAY, prm.LGAZ, prm.LGYR, prm.QTZ1, prm.MBELT) == (1, 1, 1, 1, 0, 0)
    assert prm.unknown == {}


# --------------------------------------------------------------------------------------------- syntax
HEAD = """[MDI_HEADER]
FILE_TYPE = 'tir'
[MODEL]
FITTYP = 61
"""


def test_syntax_as_found_in_the_wild():
    text = (
        "$ leading comment\r\n"
        "! another\r\n"
        "{ a brace comment }\r\n"
        "[mdi_header]   $ header comment\r\n"
        "file_type\t=\t'tir'   ! trailing bang comment\r\n"
        "FUNCTION_NAME = 'lib$name::TYR815'  $ the first $ is inside quotes\r\n"
        "\r\n"
        "[Model]\r"
        "FITTYP=61{fit type}\r"
        "TYRESIDE = RIGHT\r"
        "PROPERTY_FILE_FORMAT = \"USER\"\r"
        "[VERTICAL]\n"
        "FNOMIN = 4.0D+3\n"
        "Q_V1 = 7.724d-4\n"
        "Q_V2 = 1.E-2\n"
        "BREFF = .5\n"
        "DREFF = +2e-1 $ comment\n"
        "[ SCALING_COEFFICIENTS ]\n"
        "lmux = 1.0\n"
    )
    prm = parse_quiet(text, "wild.tir")
    assert prm.FILE_TYPE == "tir" and prm.FUNCTION_NAME == "lib$name::TYR815"
    assert prm.FITTYP == 61 and type(prm.FITTYP) is int
    assert prm.TYRESIDE == "RIGHT" and prm.PROPERTY_FILE_FORMAT == "USER"
    assert prm.FNOMIN == 4000.0 and prm.Q_V1 == 7.724e-4 and prm.Q_V2 == 0.01
    assert prm.BREFF == 0.5 and prm.DREFF == 0.2 and prm.LMUX == 1.0
    assert prm.lines["FNOMIN"] == 13 and prm.lines["FITTYP"] == 9


def test_unknown_parameters_and_sections_kept():
    text = HEAD + "MY_FLAG = 3\n[VERTICAL]\nFNOMIN = 4000\nMY_WORD = hello\n[MY_TABLE]\n 1 2\n 3 4\n" \
                  "[MY_PARAMS]\nFOO = 'bar'\nBAZ = 1.5E3\n"
    prm = parse_quiet(text)
    assert prm.unknown == {"MY_FLAG": ("MODEL", 3.0), "MY_WORD": ("VERTICAL", "hello"),
                           "FOO": ("MY_PARAMS", "bar"), "BAZ": ("MY_PARAMS", 1500.0)}
    assert prm.extra_sections == {"MY_TABLE": " 1 2\n 3 4"}
    assert "MY_FLAG" not in prm


# ------------------------------------------------------------------------------------------------ units
def test_units_mm_kn_deg_lbm_ms_psi(tmp_path):
    text = """[MDI_HEADER]
FILE_TYPE = 'tir'
[UNITS]
LENGTH = 'mm'
FORCE = 'kN'
ANGLE = 'DEG'
MASS = lbm
TIME = 'ms'
PRESSURE = 'psi'
[MODEL]
FITTYP = 61
LONGVL = 16.7
[DIMENSION]
UNLOADED_RADIUS = 313.5
ASPECT_RATIO = 0.6
[OPERATING_CONDITIONS]
NOMPRES = 30
[INERTIA]
MASS = 20
IXX = 1000
GRAVITY = -9.81e-3
[VERTICAL]
FNOMIN = 4
VERTICAL_STIFFNESS = 200
VERTICAL_DAMPING = 0.5
Q_CAM1 = 0.1
Q_CAM2 = 0.001
Q_FYS1 = -20
Q_V2 = 0.04
[STRUCTURAL]
YAW_STIFFNESS = 5000
FREQ_LONG = 0.08
DAMP_LONG = 0.04
[CONTACT_PATCH]
ELLIPS_NWIDTH = 10
[LONG_SLIP_RANGE]
KPUMAX = 1.5
[SLIP_ANGLE_RANGE]
ALPMAX = 30
[LONGITUDINAL_COEFFICIENTS]
PCX1 = 1.5
"""
    path = tmp_path / "nonsi.tir"
    path.write_text(text)
    with pytest.warns(MissingParameterWarning):
        prm = read_tir(path)
    lbm, lbf, inch = 0.45359237, 4.4482216152605, 0.0254
    expected = {
        "UNLOADED_RADIUS": 0.3135, "FNOMIN": 4000.0, "VERTICAL_STIFFNESS": 2.0e8, "VERTICAL_DAMPING": 500.0,
        "LONGVL": 16.7, "NOMPRES": 30 * lbf / inch**2, "INFLPRES": 30 * lbf / inch**2, "MASS": 20 * lbm,
        "IXX": 1000 * lbm * 1e-6, "GRAVITY": -9.81, "Q_CAM1": 100.0, "Q_CAM2": 1000.0, "Q_FYS1": -20000.0,
        "YAW_STIFFNESS": 5000 * 1000 * 0.001 / (math.pi / 180), "FREQ_LONG": 80.0, "ALPMAX": math.pi / 6,
        # dimensionless and integer parameters are never converted
        "ASPECT_RATIO": 0.6, "Q_V2": 0.04, "DAMP_LONG": 0.04, "KPUMAX": 1.5, "PCX1": 1.5, "ELLIPS_NWIDTH": 10,
    }
    for name, value in expected.items():
        assert prm[name] == pytest.approx(value, rel=1e-14), name
    assert prm.units_as_read == {"LENGTH": "mm", "FORCE": "kN", "ANGLE": "DEG", "MASS": "lbm", "TIME": "ms",
                                 "PRESSURE": "psi"}
    # round trip of a non-SI file: written in SI, read back identical
    out = write_tir(prm, tmp_path / "si.tir")
    back = read_tir(out)
    assert back.to_dict() == prm.to_dict()
    assert back.units_as_read == {"LENGTH": "meter", "FORCE": "newton", "ANGLE": "radians", "MASS": "kg",
                                  "TIME": "second"}


def test_units_inch_lbf_bar_and_others():
    text = """[UNITS]
LENGTH = inch
FORCE = 'pound_force'
ANGLE = 'RAD'
MASS = 'slug'
TIME = 'sec'
PRESSURE = "BAR"
[MODEL]
FITTYP = 62
VXLOW = 12
[DIMENSION]
UNLOADED_RADIUS = 12
[OPERATING_CONDITIONS]
NOMPRES = 2.2
[INERTIA]
MASS = 1
[VERTICAL]
FNOMIN = 1000
BOTTOM_STIFF = 1
[SLIP_ANGLE_RANGE]
ALPMIN = -0.5
"""
    prm = parse_quiet(text)
    assert prm.UNLOADED_RADIUS == pytest.approx(0.3048, rel=1e-15)
    assert prm.VXLOW == pytest.approx(0.3048, rel=1e-15)
    assert prm.NOMPRES == pytest.approx(220000.0, rel=1e-15)
    assert prm.FNOMIN == pytest.approx(4448.2216152605, rel=1e-15)
    assert prm.MASS == pytest.approx(4.4482216152605 / 0.3048, rel=1e-15)
    assert prm.BOTTOM_STIFF == pytest.approx(4.4482216152605 / 0.0254, rel=1e-15)
    assert prm.ALPMIN == -0.5


@pytest.mark.parametrize("length,force,mass,expected_r0", [("feet", "kgf", "gram", 0.3048),
                                                           ("cm", "kilonewton", "kilogram", 0.01),
                                                           ("KM", "N", "KG", 1000.0)])
def test_more_unit_spellings(length, force, mass, expected_r0):
    text = f"[UNITS]\nLENGTH='{length}'\nFORCE='{force}'\nMASS='{mass}'\n[MODEL]\nFITTYP=61\n" \
           "[DIMENSION]\nUNLOADED_RADIUS = 1\nRIM_RADIUS = 0.5\n[VERTICAL]\nFNOMIN = 1\nQ_FZ2 = 0\n[INERTIA]\nMASS = 1\n"
    prm = parse_quiet(text)
    assert prm.UNLOADED_RADIUS == pytest.approx(expected_r0, rel=1e-15)
    assert prm.FNOMIN == pytest.approx({"kgf": 9.80665, "kilonewton": 1000.0, "N": 1.0}[force], rel=1e-15)
    assert prm.MASS == pytest.approx({"gram": 1e-3, "kilogram": 1.0, "KG": 1.0}[mass], rel=1e-15)


def test_pressure_without_pressure_unit_is_force_per_length_squared():
    text = "[UNITS]\nLENGTH = 'mm'\nFORCE = 'newton'\n[MODEL]\nFITTYP = 61\n[OPERATING_CONDITIONS]\nNOMPRES = 0.22\n"
    assert parse_quiet(text).NOMPRES == pytest.approx(220000.0, rel=1e-15)
    si = "[MODEL]\nFITTYP = 61\n[OPERATING_CONDITIONS]\nNOMPRES = 220000\n"
    assert parse_quiet(si).NOMPRES == 220000.0


def test_unknown_unit_is_an_error_naming_file_line_and_spellings(tmp_path):
    path = tmp_path / "badunit.tir"
    path.write_text("[MDI_HEADER]\nFILE_TYPE='tir'\n[UNITS]\nLENGTH = 'furlong'\n[MODEL]\nFITTYP=61\n")
    with pytest.raises(TirError) as info:
        read_tir(path)
    msg = str(info.value)
    assert str(path) in msg and ":4:" in msg and "LENGTH" in msg and "furlong" in msg
    assert "mm" in msg and "inch" in msg


# ---------------------------------------------------------------------------------------- malformed input
BASE_LINES = [
    "[MDI_HEADER]",  # 1
    "FILE_TYPE = 'tir'",  # 2
    "[MODEL]",  # 3
    "FITTYP = 61",  # 4
    "[VERTICAL]",  # 5
    "FNOMIN = 4000",  # 6
    "[LONGITUDINAL_COEFFICIENTS]",  # 7
    "PCX1 = 1.5",  # 8
]


@pytest.mark.parametrize(
    "lineno,bad,parameter,expect",
    [
        (8, "PCX1 = 1.5.3", "PCX1", "expected a number"),
        (8, "PCX1 1.5", "PCX1", "'='"),
        (6, "FNOMIN = 'heavy'", "FNOMIN", "quoted string"),
        (6, "FNOMIN = heavy", "FNOMIN", "expected a number"),
        (6, "FNOMIN = nan", "FNOMIN", "expected a number"),
        (8, "PCX1 = 1.5 2.0", "PCX1", "expected a number"),
        (8, "PCX1 = ", "PCX1", "missing value"),
        (8, "PCX1 = 'abc $ unterminated", "PCX1", "unterminated"),
        (8, "PCX1 = 'abc' xyz", "PCX1", "unexpected text"),
        (4, "FITTYP = 99", "FITTYP", "unknown FITTYP"),
        (4, "FITTYP = 61.5", "FITTYP", "integer"),
        (4, "FITTYP = sixty-one", "FITTYP", "integer"),
        (8, "1PCX = 1.5", "1PCX", "invalid parameter name"),
    ],
)
def test_malformed_line_names_file_line_and_parameter(tmp_path, lineno, bad, parameter, expect):
    lines = list(BASE_LINES)
    lines[lineno - 1] = bad
    path = tmp_path / "bad.tir"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(TirError) as info:
        read_quiet(path)
    msg = str(info.value)
    assert f"{path}:{lineno}:" in msg, msg
    assert parameter in msg and expect in msg, msg
    assert info.value.line == lineno and info.value.parameter == parameter


def test_duplicate_parameter_names_both_lines(tmp_path):
    path = tmp_path / "dup.tir"
    path.write_text("\n".join(BASE_LINES + ["[SCALING_COEFFICIENTS]", "LMUX = 1", "[LONGITUDINAL_COEFFICIENTS]",
                                            "pcx1 = 1.6"]) + "\n")
    with pytest.raises(TirError) as info:
        read_quiet(path)
    msg = str(info.value)
    assert str(path) in msg and "PCX1" in msg and "line 8" in msg and "line 12" in msg


def test_units_mass_and_inertia_mass_are_not_duplicates():
    prm = parse_quiet("[UNITS]\nMASS = 'kg'\n[MODEL]\nFITTYP = 61\n[INERTIA]\nMASS = 9.5\n")
    assert prm.MASS == 9.5 and prm.units_as_read["MASS"] == "kg"


@pytest.mark.parametrize(
    "text,line,expect",
    [
        ("PCX1 = 1\n[MODEL]\nFITTYP = 61\n", 1, "before the first [SECTION]"),
        ("just some text\nwith no sections\n", None, "not a .tir"),
        ("", None, "not a .tir"),
        ("[MODEL\nFITTYP = 61\n", 1, "malformed section header"),
        ("[MDI_HEADER]\nFILE_TYPE = 'tir'\n", None, "FITTYP is missing"),
    ],
)
def test_structural_errors(text, line, expect):
    with pytest.raises(TirError) as info:
        parse_quiet(text, "x.tir")
    msg = str(info.value)
    assert msg.startswith("x.tir") and expect in msg, msg
    assert info.value.line == line
    if line is not None:
        assert f"x.tir:{line}:" in msg


def test_file_not_found_names_the_file(tmp_path):
    path = tmp_path / "nope.tir"
    with pytest.raises(TirError, match="nope.tir.*not found"):
        read_tir(path)


# -------------------------------------------------------------------------------------- missing params
def test_missing_parameters_give_exactly_one_warning_listing_them():
    text = "[MODEL]\nFITTYP = 61\n[VERTICAL]\nFNOMIN = 4000\n"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        prm = parse_tir(text, "few.tir")
    assert len(caught) == 1 and issubclass(caught[0].category, MissingParameterWarning)
    msg = str(caught[0].message)
    assert "few.tir" in msg and "PCX1=1.65" in msg and "NOMPRES=220000.0" in msg and "PDXP1=0.4" in msg
    assert "FNOMIN" not in msg.split("defaults:")[1] and "LMUV" not in msg and "PTX1" not in msg
    assert "PCX1" in prm.missing and "FNOMIN" not in prm.missing
    assert prm.PCX1 == 1.65


def test_strict_missing_parameters_is_an_error():
    with pytest.raises(TirError) as info:
        parse_tir("[MODEL]\nFITTYP = 61\n", "few.tir", strict=True)
    msg = str(info.value)
    assert "few.tir" in msg and "PCX1" in msg and "strict" in msg


def test_complete_file_gives_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_tir(need(MFEVAL / "MagicFormula61_Parameters.tir"), strict=True)


def test_mf52_missing_parameters_warned_once():
    path = need(MFEVAL / "MagicFormula52_Parameters.tir")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_tir(path)
    assert len(caught) == 1 and "Q_FZ2=0.0001" in str(caught[0].message)


# -------------------------------------------------------------------------------------------- writing
@pytest.mark.parametrize("path", ALL_TIR, ids=lambda p: p.name)
def test_read_write_read_identity(tmp_path, path):
    prm = read_quiet(need(path))
    out = write_tir(prm, tmp_path / ("copy_" + path.name))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # everything the version uses was written
        back = read_tir(out)
    a, b = prm.to_dict(), back.to_dict()
    assert list(a) == list(b)
    for name in a:
        assert type(a[name]) is type(b[name]) and a[name] == b[name], name
    assert back.unknown == prm.unknown and back.extra_sections == prm.extra_sections
    text = out.read_text()
    assert "mftyre" in text and str(path) in text
    assert text.index("[UNITS]") < text.index("[MODEL]") < text.index("[VERTICAL]")


def test_write_keeps_unknown_parameters_sections_and_exact_numbers(tmp_path):
    text = HEAD + "MY_FLAG = 3\n[VERTICAL]\nFNOMIN = 4000.000000000001\nQ_V1 = 0.01\n[SHAPE]\n{r w}\n 1.0 0.0\n" \
                  "[MY_PARAMS]\nFOO = \"it's\"\nBAZ = 1.5E3\n"
    prm = parse_quiet(text).replace(PCX1=0.1 + 0.2, PDX1=1e-300, PKX1=123456789.123456789)
    out = write_tir(prm, tmp_path / "w.tir")
    back = read_quiet(out)
    assert back.FNOMIN == 4000.000000000001 and back.PCX1 == 0.1 + 0.2 and back.PDX1 == 1e-300
    assert back.PKX1 == prm.PKX1
    assert prm.unknown["FOO"] == ("MY_PARAMS", "it's")
    assert back.unknown == prm.unknown and back.extra_sections == prm.extra_sections == {"SHAPE": "{r w}\n 1.0 0.0"}


def test_from_defaults_writes_and_reads_back(tmp_path):
    prm = TyreParameters.from_defaults(62, FNOMIN=5000.0, TYRESIDE="RIGHT")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = read_tir(write_tir(prm, tmp_path / "d.tir"))
    assert back.to_dict() == prm.to_dict()


def test_overwrite_protection(tmp_path):
    prm = TyreParameters.from_defaults(61)
    target = tmp_path / "t.tir"
    write_tir(prm, target)
    before = target.read_text()
    with pytest.raises(TirError, match="overwrite=True"):
        write_tir(prm.replace(PCX1=2.0), target)
    assert target.read_text() == before
    with pytest.raises(FileExistsError):
        write_tir(prm, target)
    write_tir(prm.replace(PCX1=2.0), target, overwrite=True)
    assert read_quiet(target).PCX1 == 2.0


def test_never_overwrites_the_source_file(tmp_path):
    src = tmp_path / "src.tir"
    src.write_text("\n".join(BASE_LINES) + "\n")
    original = src.read_text()
    prm = read_quiet(src)
    for target in (src, tmp_path / "." / "src.tir", str(src)):
        with pytest.raises(TirError, match="read from"):
            write_tir(prm, target, overwrite=True)
    assert src.read_text() == original


# -------------------------------------------------------------------------------------------- checking
BAD_VALUES = """[MDI_HEADER]
FILE_TYPE = 'tir'
[MODEL]
FITTYP = 61
LONGVL = 16.7
[DIMENSION]
UNLOADED_RADIUS = 0.3
RIM_RADIUS = 0.2
[OPERATING_CONDITIONS]
INFLPRES = 500000
NOMPRES = 220000
[VERTICAL]
FNOMIN = -4000
VERTICAL_STIFFNESS = 200000
Q_FZ2 = 10
[INFLATION_PRESSURE_RANGE]
PRESMIN = 400000
PRESMAX = 100000
[VERTICAL_FORCE_RANGE]
FZMIN = 100
FZMAX = 10
[LONG_SLIP_RANGE]
KPUMIN = 1
KPUMAX = -1
[SLIP_ANGLE_RANGE]
ALPMIN = 1
ALPMAX = -1
[INCLINATION_ANGLE_RANGE]
CAMMIN = 0.1
CAMMAX = -0.1
[LONGITUDINAL_COEFFICIENTS]
PCX1 = -1.5
MY_TYPO = 3
"""


def test_check_reports_suspicious_values_with_lines(tmp_path):
    path = tmp_path / "bad_values.tir"
    path.write_text(BAD_VALUES)
    findings = check_tir(path)
    by = {(f.severity, f.parameter): f for f in findings}
    for name, line in (("FNOMIN", 13), ("PRESMIN", 17), ("FZMIN", 20), ("KPUMIN", 23), ("ALPMIN", 26),
                       ("CAMMIN", 29)):
        assert ("error", name) in by, name
        assert by[("error", name)].line == line, name
    assert "inverted range" in by[("error", "CAMMIN")].message
    assert ("warning", "PCX1") in by and by[("warning", "PCX1")].line == 32
    assert ("warning", "MY_TYPO") in by and "unknown" in by[("warning", "MY_TYPO")].message
    assert ("warning", "PDXP1") in by  # missing parameter
    assert ("error", "RIM_RADIUS") not in by and ("error", "NOMPRES") not in by
    assert all(f.severity in ("error", "warning", "info") for f in findings)


def test_check_more_value_rules(tmp_path):
    path = tmp_path / "more.tir"
    path.write_text(HEAD + "VXLOW = 0\n[DIMENSION]\nUNLOADED_RADIUS = 0.3\nRIM_RADIUS = 0.3\n"
                           "[OPERATING_CONDITIONS]\nNOMPRES = 200000\nINFLPRES = 500000\n"
                           "[VERTICAL]\nFNOMIN = 4000\nVERTICAL_STIFFNESS = 1000\nQ_FZ2 = 0\n"
                           "[INFLATION_PRESSURE_RANGE]\nPRESMIN = 100000\nPRESMAX = 400000\n")
    by = {(f.severity, f.parameter) for f in check_tir(path)}
    assert ("error", "VXLOW") in by and ("error", "RIM_RADIUS") in by
    assert ("warning", "INFLPRES") in by and ("warning", "Q_FZ2") in by
    assert ("error", "Q_FZ2") not in by  # (Cz0 R0/Fz0)^2 - 0 >= 0
    path.write_text(HEAD + "[VERTICAL]\nFNOMIN = 4000\nVERTICAL_STIFFNESS = 1000\nQ_FZ2 = 10\n")
    errs = [f for f in check_tir(path) if f.severity == "error" and "core coefficient" not in f.message]
    assert [f.parameter for f in errs][0] == "Q_FZ2" and "Q_FZ1" in errs[0].message
    assert [f.parameter for f in errs][1:] == ["DREFF"]  # 1 kN/m: Fz0/Cz0 = 4 m, Re < 0 long before FZMAX


def test_check_parse_error_is_one_finding(tmp_path):
    path = tmp_path / "broken.tir"
    path.write_text("\n".join(BASE_LINES[:7] + ["PCX1 = oops"]) + "\n")
    findings = check_tir(path)
    assert len(findings) == 1
    f = findings[0]
    assert f.severity == "error" and f.line == 8 and f.parameter == "PCX1"


@pytest.mark.parametrize("path", ALL_TIR, ids=lambda p: p.name)
def test_shared_files_have_no_check_errors(path):
    findings = check_tir(need(path))
    assert [f for f in findings if f.severity == "error"] == []


def test_check_non_canonical_section_is_info(tmp_path):
    path = tmp_path / "moved.tir"
    path.write_text(HEAD + "[VERTICAL]\nPCX1 = 1.6\n")
    infos = [f for f in check_tir(path) if f.severity == "info" and f.parameter == "PCX1"]
    assert len(infos) == 1 and "LONGITUDINAL_COEFFICIENTS" in infos[0].message
    assert read_quiet(path).PCX1 == 1.6


# ------------------------------------------------------------------------------------------------- CLI
def test_cli_check_exit_status_and_output(tmp_path, capsys):
    bad = tmp_path / "bad_values.tir"
    bad.write_text(BAD_VALUES)
    assert cli.main(["check", str(bad)]) == 1
    out = capsys.readouterr().out
    assert f"{bad}:13: error: FNOMIN" in out
    assert f"{bad}:17: error: PRESMIN" in out
    assert "checked 1 file" in out and "error(s)" in out

    good = need(MFEVAL / "MagicFormula61_Parameters.tir")
    assert cli.main(["check", str(good)]) == 0
    out = capsys.readouterr().out
    assert "0 error(s)" in out

    warn_only = need(MFEVAL / "PacejkaBook_Defaults.tir")  # Q_FZ2 = 0 is a warning, not an error
    assert cli.main(["check", str(warn_only)]) == 0
    assert f"{warn_only}:62: warning: Q_FZ2" in capsys.readouterr().out

    broken = tmp_path / "broken.tir"
    broken.write_text("\n".join(BASE_LINES[:7] + ["PCX1 = oops"]) + "\n")
    assert cli.main(["check", str(good), str(broken)]) == 1
    out = capsys.readouterr().out
    assert f"{broken}:8: error: PCX1" in out and "checked 2 files" in out

    assert cli.main(["check", str(tmp_path / "missing.tir")]) == 1
    assert "not found" in capsys.readouterr().out


def test_cli_usage_errors():
    assert cli.main([]) != 0
    assert cli.main(["check"]) != 0
