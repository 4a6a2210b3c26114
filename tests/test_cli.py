"""mftyre eval: sweeps, units, table, CSV, plot and errors."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import mftyre
from conftest import PROJECT, TIR_FILES
from mftyre import cli

TIR = TIR_FILES / "car_205_60R15_mf61.tir"


def test_eval_table_equals_model_evaluate(capsys, tmp_path):
    csv = tmp_path / "out.csv"
    assert cli.main(["eval", str(TIR), "--fz", "4kN", "--alpha", "-10deg:10deg:5", "--p", "1.8bar,2.6bar",
                     "--csv", str(csv), "--outputs", "all", "-q"]) == 0
    frame = pd.read_csv(csv)
    assert len(frame) == 10  # outer product of the sweeps
    model = mftyre.load_tir(TIR)
    ref = model.evaluate(fz=4000.0, kappa=0.0, alpha=frame["alpha [rad]"].to_numpy(), p=frame["p [Pa]"].to_numpy())
    np.testing.assert_allclose(frame["alpha [rad]"].unique(), np.radians(np.linspace(-10, 10, 5)), rtol=1e-15)
    assert sorted(frame["p [Pa]"].unique()) == [1.8e5, 2.6e5]
    for name in ("fx", "fy", "mz", "mx", "my", "rl", "kya"):
        column = next(c for c in frame.columns if c.split(" [")[0] == name)
        np.testing.assert_allclose(frame[column], ref[name], rtol=1e-12, atol=1e-9, err_msg=name)


def test_eval_units_and_negative_range_without_equals(capsys):
    assert cli.main(["eval", str(TIR), "--fz", "4.5kN", "--alpha", "-0.1:0.1:3", "--vx", "72km/h",
                     "--p", "32psi", "--gamma", "2deg", "--outputs", "fy"]) == 0
    printed = capsys.readouterr().out
    ref = mftyre.load_tir(TIR).evaluate(4500.0, 0.0, np.array([-0.1, 0.0, 0.1]), gamma=np.radians(2.0), vx=20.0,
                                        p=32 * 6894.757293168361)
    values = [float(line.split()[-1]) for line in printed.splitlines() if line.strip() and line.split()[0][0] in "-0"]
    np.testing.assert_allclose(values[-3:], ref.fy, rtol=1e-5)


def test_eval_plot_is_written_into_a_new_folder(tmp_path, capsys):
    png = tmp_path / "new" / "fy.png"
    assert cli.main(["eval", str(TIR), "--alpha", "-8deg:8deg:17", "--p", "1.8bar,2.2bar", "--plot", str(png),
                     "-q"]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 5000


@pytest.mark.parametrize("args,needle", [
    (["--alpha", "0:1"], "--alpha"),
    (["--alpha", "0:1:1"], "COUNT"),
    (["--p", "2.2furlong"], "unknown unit"),
    (["--fz", "abc"], "--fz"),
    (["--outputs", "fy,force"], "force"),
    (["--alpha", "1deg,2"], "mixes"),
])
def test_eval_bad_option_exits_2_naming_it(args, needle, capsys):
    assert cli.main(["eval", str(TIR), *args]) == 2
    assert needle in capsys.readouterr().err


def test_eval_refuses_to_overwrite_the_tir(tmp_path, capsys):
    copy = tmp_path / "tyre.tir"
    copy.write_text(TIR.read_text())
    before = copy.read_bytes()
    assert cli.main(["eval", str(copy), "--alpha", "0:0.1:3", "--csv", str(copy)]) == 2
    assert copy.read_bytes() == before
    assert "input .tir" in capsys.readouterr().err


def test_eval_missing_file_and_bad_pressure_exit_1(tmp_path, capsys):
    assert cli.main(["eval", str(tmp_path / "absent.tir"), "--alpha", "0"]) == 1
    assert "absent.tir" in capsys.readouterr().err
    assert cli.main(["eval", str(TIR), "--p", "-1bar"]) == 1
    assert "pressure" in capsys.readouterr().err


def test_python_m_mftyre_eval_subprocess():
    run = subprocess.run([sys.executable, "-m", "mftyre", "eval", str(TIR), "--alpha", "-2deg:2deg:3",
                          "--outputs", "fy,mz"], capture_output=True, text=True, cwd=PROJECT, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "fy [N]" in run.stdout and "mz [N m]" in run.stdout
