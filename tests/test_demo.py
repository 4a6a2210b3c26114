"""The README's main job (mftyre demo) runs and its fitted model matches the noise-free tyre."""
from __future__ import annotations

import mftyre
from mftyre import cli
from mftyre.demo import run_demo


def test_demo_writes_everything_and_fits_within_target(tmp_path):
    lines = []
    result = run_demo(tmp_path / "out", echo=lines.append)
    for key in ("characteristics", "trailer", "fitted", "report"):
        assert result[key].exists() and result[key].stat().st_size > 0, key
    assert result["check_error"]["FX"] < 1.5 and result["check_error"]["FY"] < 1.5
    assert result["check_error"]["MZ"] < 4.0
    assert mftyre.load_tir(result["fitted"]).params.fittyp == 61
    assert any("check grid" in line for line in lines)
    gaps = result["gaps"]
    assert gaps.effect_names == ["pressure_cornering_stiffness"]
    assert gaps.error_after["FY"] < 0.5 * gaps.error_before["FY"]
    assert (tmp_path / "out" / "gaps" / "report.md").exists() and result["improved"].exists()


def test_demo_command_is_registered(capsys):
    assert cli.main(["demo", "--help"]) == 0
    assert "--out" in capsys.readouterr().out
