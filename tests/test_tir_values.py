"""Values no tyre can have are refused at load (TirError naming file, line and parameter), by the writer and by
`mftyre check`, from the one rule in mftyre.params.invalid_values; `check` fails when a core coefficient is
missing (CORE_PARAMETERS)."""
from __future__ import annotations

import re
import warnings

import pytest

import mftyre
from mftyre import cli
from mftyre.errors import TirError
from mftyre.params import CORE_PARAMETERS, MissingParameterWarning
from mftyre.tir import write_tir

from conftest import TIR_FILES

TIR61 = TIR_FILES / "car_205_60R15_mf61.tir"
TIR62 = TIR_FILES / "car_205_60R15_mf62_swift.tir"


def _with_value(tmp_path, source, name, value):
    """A copy of ``source`` with parameter ``name`` set to ``value``; returns (path, line number)."""
    lines = source.read_text().splitlines()
    for i, line in enumerate(lines):
        if re.match(rf"\s*{name}\s*=", line):
            lines[i] = f"{name} = {value}"
            path = tmp_path / f"{name}.tir"
            path.write_text("\n".join(lines) + "\n")
            return path, i + 1
    raise AssertionError(f"{name} not in {source}")


BAD_VALUES = [("FNOMIN", "0"), ("LFZO", "0"), ("LFZO", "-1"), ("LONGVL", "0"), ("NOMPRES", "0"),
              ("UNLOADED_RADIUS", "-0.3"), ("VERTICAL_STIFFNESS", "0"), ("VXLOW", "0"), ("RIM_RADIUS", "0.5"),
              ("TYRESIDE", "'SYMMETRIC'"), ("PRESMIN", "900000"), ("LKX", "-1"), ("LKY", "-1")]


@pytest.mark.parametrize("source", [TIR61, TIR62], ids=["mf61", "mf62"])
@pytest.mark.parametrize("name,value", BAD_VALUES)
def test_value_no_tyre_can_have_is_refused_at_load(tmp_path, source, name, value):
    path, line = _with_value(tmp_path, source, name, value)
    with pytest.raises(TirError) as info:
        mftyre.load_tir(path)
    msg = str(info.value)
    assert str(path) in msg and f":{line}:" in msg and name in msg
    assert cli.main(["check", str(path)]) != 0
    assert cli.main(["eval", str(path), "-q"]) != 0


def test_writer_refuses_invalid_values(tmp_path):
    prm = mftyre.load_tir(TIR61).params
    with pytest.raises(TirError, match="LFZO"):
        write_tir(prm.replace(LFZO=-1.0), tmp_path / "bad.tir")
    assert not (tmp_path / "bad.tir").exists()


@pytest.mark.parametrize("core", ["PKY1", "PDX1", "QDZ1"])
def test_check_fails_when_a_core_coefficient_is_missing(tmp_path, capsys, core):
    lines = TIR61.read_text().splitlines()
    text = "\n".join(re.sub(rf"^\s*{core}\s*=", f"{core}X =", ln) for ln in lines) + "\n"  # misspelt
    path = tmp_path / "typo.tir"
    path.write_text(text)
    assert cli.main(["check", str(path)]) == 1
    out = capsys.readouterr().out
    assert re.search(rf"error: {core}: missing.*core coefficient", out), out
    with pytest.warns(MissingParameterWarning, match=core):
        mftyre.load_tir(path)


def test_core_parameters_are_schema_parameters_of_their_versions():
    from mftyre.params import PARAMETERS

    for version, names in CORE_PARAMETERS.items():
        for name in names:
            assert version in PARAMETERS[name].versions, (version, name)


def test_sample_files_pass_check():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cli.main(["check", str(TIR61), str(TIR62)]) == 0
