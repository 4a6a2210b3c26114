"""`mftyre soil`: table, CSV, plot, units, --overwrite and errors."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from conftest import TIR_FILES
from mftyre.cli import main
from mftyre.soil import SoftSoilTyre

AGRI = str(TIR_FILES / "agri_460_85R34_mf61.tir")


def test_table_csv_and_plot_match_the_model(tmp_path, capsys):
    csv, png = tmp_path / "dp.csv", tmp_path / "dp.png"
    rc = main(["soil", AGRI, "--soil", "sandy_loam", "--fz", "25kN", "--slip", "0%:60%:7", "--p", "1bar,1.6bar",
               "--csv", str(csv), "--plot", str(png)])
    assert rc == 0
    printed = capsys.readouterr().out
    assert "sandy_loam" in printed and "drawbar_pull [N]" in printed and "fz = 25000 N" in printed
    frame = pd.read_csv(csv)
    assert len(frame) == 14 and "efficiency [-]" in frame.columns
    slip, p = np.meshgrid(np.linspace(0, 0.6, 7), [1e5, 1.6e5], indexing="ij")
    expected = SoftSoilTyre(AGRI, "sandy_loam").evaluate(fz=25e3, slip=slip, p=p)
    np.testing.assert_allclose(frame["drawbar_pull [N]"], expected.drawbar_pull.ravel(), rtol=1e-12)
    np.testing.assert_allclose(frame["p [Pa]"], p.ravel())
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_existing_output_needs_overwrite(tmp_path, capsys):
    csv = tmp_path / "out.csv"
    csv.write_text("keep me")
    assert main(["soil", AGRI, "--soil", "dry_sand", "--csv", str(csv)]) == 2
    assert "pass --overwrite" in capsys.readouterr().err and csv.read_text() == "keep me"
    assert main(["soil", AGRI, "--soil", "dry_sand", "--csv", str(csv), "--overwrite", "-q"]) == 0
    assert "sinkage [m]" in csv.read_text()


def test_user_soil_file(tmp_path, capsys):
    soils = tmp_path / "soils.csv"
    soils.write_text("name,n,k_c,k_phi,c,phi,K\nfield_7,0.8,10,800,3.5,25,0.02\n")
    assert main(["soil", AGRI, "--soil", "field_7", "--soil-file", str(soils), "--slip", "20%"]) == 0
    assert "field_7" in capsys.readouterr().out


@pytest.mark.parametrize("argv, rc, message", [
    (["--soil", "moon_dust"], 1, "unknown soil 'moon_dust'"),
    (["--soil", "sandy_loam", "--slip", "120%"], 1, "slip must be finite and below 1"),
    (["--soil", "sandy_loam", "--p", "1 furlong"], 2, "unknown unit 'furlong'"),
    (["--soil", "sandy_loam", "--plot", "x.png"], 2, "nothing to plot"),
    (["--soil", "sandy_loam", "--outputs", "grip"], 2, "unknown output(s) 'grip'"),
])
def test_errors(argv, rc, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["soil", AGRI, *argv]) == rc
    assert message in capsys.readouterr().err


def test_towed_and_effect_options(tmp_path, capsys):
    """--towed solves zero torque over the sweep (slip printed), --slip-sinkage/--bulldozing-depth reach the
    model, and a towed run with --slip is refused."""
    csv = tmp_path / "towed.csv"
    assert main(["soil", AGRI, "--soil", "sandy_loam", "--fz", "20kN", "--p", "1bar,1.6bar", "--vx", "2",
                 "--towed", "--csv", str(csv)]) == 0
    assert "towed (zero driving torque)" in capsys.readouterr().out
    frame = pd.read_csv(csv)
    expected = SoftSoilTyre(AGRI, "sandy_loam").towed(20e3, p=np.array([1e5, 1.6e5]), vx=2.0)
    np.testing.assert_allclose(frame["slip [-]"], expected.slip, rtol=1e-12)
    assert np.all(frame["slip [-]"] < 0) and np.all(np.abs(frame["torque [N m]"]) < 1e-3)
    csv2 = tmp_path / "fx.csv"
    assert main(["soil", AGRI, "--soil", "paddy_soil", "--fz", "8kN", "--slip", "0.3", "--slip-sinkage", "1",
                 "--bulldozing-depth", "0.02", "--csv", str(csv2), "-q"]) == 0
    expected = SoftSoilTyre(AGRI, "paddy_soil", slip_sinkage=1, bulldozing_depth=0.02).evaluate(fz=8e3, slip=0.3)
    frame = pd.read_csv(csv2)
    assert float(frame["bulldozing_resistance [N]"][0]) == pytest.approx(float(expected.bulldozing_resistance))
    assert float(expected.bulldozing_resistance) > 0
    assert main(["soil", AGRI, "--soil", "sandy_loam", "--towed", "--slip", "0.1"]) == 2
    assert "drop --slip" in capsys.readouterr().err
    assert main(["soil", AGRI, "--soil", "sandy_loam", "--bulldozing-depth", "0.05"]) == 1
    assert "needs the unit weight gamma" in capsys.readouterr().err


def test_cone_index_route_on_the_command_line(tmp_path, capsys):
    """--cone-index runs Brixius's model (the same table and CSV), alone or towed; the Bekker-Wong options and a
    --soil with it are refused."""
    from mftyre.soil import ConeIndexTyre

    csv = tmp_path / "ci.csv"
    assert main(["soil", AGRI, "--cone-index", "1.2MPa", "--fz", "25kN", "--slip", "0%:30%:4", "--p", "1.2bar",
                 "--csv", str(csv)]) == 0
    assert "cone index 1.2e+06 Pa (Brixius)" in capsys.readouterr().out
    expected = ConeIndexTyre(AGRI, 1.2e6).evaluate(fz=25e3, slip=np.linspace(0, 0.3, 4), p=1.2e5)
    np.testing.assert_allclose(pd.read_csv(csv)["drawbar_pull [N]"], expected.drawbar_pull, rtol=1e-12)
    assert main(["soil", AGRI, "--cone-index", "800kPa", "--towed", "-q"]) == 0
    assert main(["soil", AGRI, "--cone-index", "1.2MPa", "--slip-sinkage", "1"]) == 2
    assert "belong to the Bekker-Wong model" in capsys.readouterr().err
    assert main(["soil", AGRI, "--cone-index", "1.2MPa", "--soil", "sandy_loam"]) == 2
    assert main(["soil", AGRI, "--cone-index=-3kPa"]) == 2
    assert "must be positive" in capsys.readouterr().err
