"""Tests of `mftyre eval` (mftyre.cli): same numbers as MFModel.evaluate, unit parsing, grid, CSV, plot, errors."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest

import mftyre
from mftyre import arguments, cli
from mftyre.model import OUTPUT_UNITS

from conftest import PROJECT, TIR_FILES

TIR61 = TIR_FILES / "car_205_60R15_mf61.tir"
TIR62 = TIR_FILES / "car_205_60R15_mf62_swift.tir"


def _model(path=TIR61, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mftyre.params.MissingParameterWarning)
        return mftyre.load_tir(path, **kw)


def _read_csv(path) -> pd.DataFrame:
    return pd.read_csv(path)


def _close(a, b, tol=1e-12):
    a, b = np.asarray(a, float), np.asarray(b, float)
    np.testing.assert_allclose(a, b, rtol=tol, atol=tol * max(1.0, float(np.max(np.abs(b)))))


# --------------------------------------------------------------------------------------- same numbers
@pytest.mark.parametrize("tir", [TIR61, TIR62], ids=["mf61", "mf62"])
def test_eval_matches_model_evaluate(tir, tmp_path, capsys):
    out_csv = tmp_path / "out.csv"
    rc = cli.main(["eval", str(tir), "--fz", "4000", "--alpha", "-0.2:0.2:41", "--kappa", "-0.05,0,0.1",
                   "--gamma", "0.03", "--csv", str(out_csv), "-q"])
    assert rc == 0, capsys.readouterr().err
    df = _read_csv(out_csv)
    # grid: outer product in command-line order (alpha outer, kappa fastest)
    alpha, kappa = np.meshgrid(np.linspace(-0.2, 0.2, 41), [-0.05, 0.0, 0.1], indexing="ij")
    ref = _model(tir).evaluate(4000.0, kappa, alpha, gamma=0.03)
    assert len(df) == 41 * 3
    _close(df["alpha [rad]"], alpha.ravel())
    _close(df["kappa [-]"], kappa.ravel(), tol=0)
    for name, (unit, _) in OUTPUT_UNITS.items():
        col = f"{name}_used [{unit}]" if name in ("alpha", "kappa") else f"{name} [{unit}]"
        _close(df[col], np.ravel(ref[name]))


def test_eval_modes_side_and_defaults(tmp_path, capsys):
    """--side, --turn-slip, --no-limits, --alpha-star reach evaluate(); unset vx/p/omega use the model defaults."""
    out_csv = tmp_path / "out.csv"
    rc = cli.main(["eval", str(TIR61), "--alpha", "-8deg:8deg:9", "--phit", "0.1", "--fz", "9kN",
                   "--side", "right", "--turn-slip", "--no-limits", "--alpha-star", "--turn-slip-form", "mfeval",
                   "--csv", str(out_csv), "-q"])
    assert rc == 0, capsys.readouterr().err
    df = _read_csv(out_csv)
    alpha = np.radians(np.linspace(-8, 8, 9))
    ref = _model(side="right").evaluate(9000.0, 0.0, alpha, phit=0.1, turn_slip=True, limits=False,
                                        alpha_star=True, turn_slip_form="mfeval")
    for name in ("fx", "fy", "mz", "mx", "my", "rl", "re", "vx", "p", "omega"):
        _close(df[f"{name} [{OUTPUT_UNITS[name][0]}]"], ref[name])


def test_eval_prints_table_with_si_units(capsys):
    rc = cli.main(["eval", str(TIR61), "--fz", "4000", "--alpha", "-0.2:0.2:5"])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    lines = captured.out.splitlines()
    header = next(line for line in lines if "fy [N]" in line)
    for col in ("alpha [rad]", "fx [N]", "fy [N]", "mz [N m]", "mx [N m]", "my [N m]", "rl [m]"):
        assert col in header
    rows = lines[lines.index(header) + 1:]
    assert len(rows) == 5
    ref = _model().evaluate(4000.0, 0.0, np.linspace(-0.2, 0.2, 5))
    fy_printed = [float(r.split()[2]) for r in rows]
    np.testing.assert_allclose(fy_printed, ref.fy, rtol=1e-5)  # 6 significant digits


# ------------------------------------------------------------------------------------------ parsing
@pytest.mark.parametrize("name, text, expected", [
    ("alpha", "-10deg:10deg:5", np.radians([-10, -5, 0, 5, 10])),
    ("alpha", "0.1", [0.1]),
    ("alpha", "0.1rad,2deg", [0.1, math.radians(2)]),
    ("gamma", "3 deg", [math.radians(3)]),
    ("p", "2.2bar", [2.2e5]),
    ("p", "220kPa,250000Pa", [2.2e5, 2.5e5]),
    ("p", "32psi", [32 * 4.4482216152605 / 0.0254**2]),
    ("p", "220000", [2.2e5]),
    ("fz", "4kN", [4000.0]),
    ("fz", "2kN:6kN:3", [2000.0, 4000.0, 6000.0]),
    ("fz", "4000N", [4000.0]),
    ("vx", "36km/h", [10.0]),
    ("vx", "20m/s", [20.0]),
    ("kappa", "-10%:10%:3", [-0.1, 0.0, 0.1]),
    ("kappa", "1e-2", [0.01]),
    ("omega", "60rpm", [2 * math.pi]),
    ("phit", "0.1/m", [0.1]),
])
def test_parse_sweep_units(name, text, expected):
    sweep = arguments.parse_sweep(name, text)
    np.testing.assert_allclose(sweep.values, expected, rtol=1e-15, atol=1e-15)


def test_sweep_remembers_unit_for_plots():
    s = arguments.parse_sweep("alpha", "-10deg:10deg:21")
    assert s.unit == "deg" and s.values.size == 21
    assert s.label(s.values[-1]) == "alpha = 10 deg"
    assert arguments.parse_sweep("p", "1.8bar,2.2bar").unit == "bar"
    assert arguments.parse_sweep("p", "220000").unit == "Pa"


def test_grid_is_outer_product(tmp_path, capsys):
    out_csv = tmp_path / "grid.csv"
    rc = cli.main(["eval", str(TIR61), "--fz", "2kN,4kN,6kN", "--alpha", "-5deg:5deg:11", "--p", "1.8bar,2.6bar",
                   "--outputs", "fy,p", "--csv", str(out_csv), "-q"])
    assert rc == 0, capsys.readouterr().err
    df = _read_csv(out_csv)
    assert len(df) == 3 * 11 * 2
    assert list(df.columns) == ["fz [N]", "alpha [rad]", "p [Pa]", "fy [N]", "p_used [Pa]"]
    # every combination exactly once; last option fastest
    assert len(df.drop_duplicates(["fz [N]", "alpha [rad]", "p [Pa]"])) == 66
    assert list(df["p [Pa]"][:4]) == [1.8e5, 2.6e5, 1.8e5, 2.6e5]
    assert set(df["fz [N]"]) == {2000.0, 4000.0, 6000.0}
    # the pressure as used is saturated to the .tir range [PRESMIN, PRESMAX] (limits on by default)
    prm = _model().params
    assert df["p_used [Pa]"].min() == pytest.approx(max(1.8e5, prm.PRESMIN))
    assert df["p_used [Pa]"].max() == pytest.approx(min(2.6e5, prm.PRESMAX))


def test_negative_values_after_option(capsys):
    """`--alpha -0.2:0.2:41` (a value starting with '-') is accepted without '='."""
    assert cli.main(["eval", str(TIR61), "--alpha", "-0.2:0.2:3", "--gamma", "-2deg", "-q"]) == 0
    assert cli.main(["eval", str(TIR61), "--alpha=-.1", "-q"]) == 0


# ------------------------------------------------------------------------------------ csv and plot
def test_csv_selected_outputs_roundtrip(tmp_path, capsys):
    out_csv = tmp_path / "fy.csv"
    out_csv.write_text("old content\n")  # an existing output is replaced only with --overwrite
    argv = ["eval", str(TIR61), "--alpha", "-0.1:0.1:7", "--fz", "4000", "--outputs", "fy,mz", "--csv", str(out_csv),
            "-q"]
    assert cli.main(argv) == 2 and "--overwrite" in capsys.readouterr().err
    assert out_csv.read_text() == "old content\n"
    rc = cli.main(argv + ["--overwrite"])
    assert rc == 0, capsys.readouterr().err
    df = _read_csv(out_csv)
    assert list(df.columns) == ["alpha [rad]", "fy [N]", "mz [N m]"]
    ref = _model().evaluate(4000.0, 0.0, np.linspace(-0.1, 0.1, 7))
    _close(df["fy [N]"], ref.fy)
    _close(df["mz [N m]"], ref.mz)


def test_plot_written(tmp_path, capsys):
    png = tmp_path / "fy.png"
    rc = cli.main(["eval", str(TIR61), "--fz", "3kN,5kN", "--alpha", "-10deg:10deg:21", "--outputs", "fy,mz",
                   "--plot", str(png), "-q"])
    assert rc == 0, capsys.readouterr().err
    data = png.read_bytes()
    assert len(data) > 1000 and data[:8] == b"\x89PNG\r\n\x1a\n"


def test_outputs_go_into_new_folders(tmp_path, capsys):
    png, csv = tmp_path / "new" / "fy.png", tmp_path / "other" / "fy.csv"
    assert cli.main(["eval", str(TIR61), "--alpha", "-8deg:8deg:17", "--p", "1.8bar,2.2bar", "--plot", str(png),
                     "--csv", str(csv), "-q"]) == 0, capsys.readouterr().err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(_read_csv(csv)) == 34


def test_plot_needs_a_sweep(tmp_path, capsys):
    rc = cli.main(["eval", str(TIR61), "--alpha", "0.1", "--plot", str(tmp_path / "x.png")])
    assert rc == 2
    assert "--plot" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("option", ["--csv", "--plot"])
def test_refuses_to_overwrite_input_tir(tmp_path, capsys, option):
    tir = tmp_path / "tyre.tir"
    tir.write_bytes(TIR61.read_bytes())
    before = tir.read_bytes()
    rc = cli.main(["eval", str(tir), "--alpha", "-0.1:0.1:3", option, str(tir)])
    assert rc == 2
    assert option in capsys.readouterr().err
    assert tir.read_bytes() == before


# ------------------------------------------------------------------------------------------ errors
@pytest.mark.parametrize("option, value, words", [
    ("--alpha", "1:2", "START:STOP:COUNT"),
    ("--alpha", "-1:1:1", "COUNT"),
    ("--alpha", "-1:1:2.5", "COUNT"),
    ("--alpha", "abc", "number"),
    ("--alpha", "1,,2", "empty"),
    ("--p", "2.2bars", "unknown unit"),
    ("--p", "2.2,2.4bar", "unit on every value"),
    ("--fz", "4kg", "unknown unit"),
    ("--vx", "nan", "number"),
    ("--outputs", "fy,foo", "foo"),
])
def test_bad_option_syntax_exit_2(capsys, option, value, words):
    rc = cli.main(["eval", str(TIR61), option, value])
    err = capsys.readouterr().err
    assert rc == 2
    assert f"argument {option}" in err and words in err
    assert "Traceback" not in err


def test_missing_file_exit_1(tmp_path, capsys):
    missing = tmp_path / "nope.tir"
    rc = cli.main(["eval", str(missing), "--alpha", "0.1"])
    captured = capsys.readouterr()
    assert rc == 1
    assert "nope.tir" in captured.err and "not found" in captured.err
    assert "Traceback" not in captured.err


def test_model_input_error_exit_1(capsys):
    rc = cli.main(["eval", str(TIR61), "--p=-2bar"])
    assert rc == 1
    assert "pressure" in capsys.readouterr().err


def test_check_still_works(capsys):
    assert cli.main(["check", str(TIR61), "-q"]) == 0
    assert "checked 1 file" in capsys.readouterr().out


# ------------------------------------------------------------------------------------- real process
def test_python_dash_m(tmp_path):
    out_csv = tmp_path / "out.csv"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(PROJECT), os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, "-m", "mftyre", "eval", str(TIR61), "--fz", "4000",
                           "--alpha", "-0.2:0.2:41", "--p", "2.2bar", "--csv", str(out_csv)],
                          capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "fy [N]" in proc.stdout
    df = _read_csv(out_csv)
    ref = _model().evaluate(4000.0, 0.0, np.linspace(-0.2, 0.2, 41), p=2.2e5)
    _close(df["fy [N]"], ref.fy)

    bad = subprocess.run([sys.executable, "-m", "mftyre", "eval", str(TIR61), "--alpha", "1:2:x"],
                         capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert bad.returncode == 2 and "argument --alpha" in bad.stderr and "Traceback" not in bad.stderr


_STAGES = "pure_fx, pure_fy, mz, combined_fx, combined_fy, mz_combined, mx, my, vertical, rolling_radius"


@pytest.mark.parametrize("argv, message", [
    ("fit t.tir -o out.tir --stages pure_fx,bogus", f"mftyre fit: unknown stage(s) bogus; stages: {_STAGES}"),
    ("fit t.tir -o out.tir", "mftyre fit: -o out.tir: exists; pass --overwrite to replace"),
    ("gaps --model t.tir", "mftyre gaps: give either DATA (steady) or --dynamic DATA (time histories)"),
    ("gaps d.csv --dynamic r.csv --model t.tir",
     "mftyre gaps: give either DATA (steady) or --dynamic DATA (time histories)"),
    ("gaps t.tir --model t.tir --channels FX,QQ", "mftyre gaps: unknown channel(s) QQ; channels: FX,FY,MZ,MX,MY,FZ"),
    ("gaps t.tir --model t.tir -o out.tir", "mftyre gaps: -o out.tir: exists; pass --overwrite to replace"),
    ("gaps --dynamic r.csv --model t.tir -o out.tir", "mftyre gaps: -o out.tir: exists; pass --overwrite to replace"),
    ("plot t.tir -o out.png --max-sweeps 0", "mftyre plot: --max-sweeps: expected an integer >= 1"),
    ("plot t.tir -o out.csv", "mftyre plot: -o out.csv: exists; pass --overwrite to replace"),
    ("swift t.tir --speed 0", "mftyre swift: --speed: expected a forward speed above 0"),
    ("swift t.tir --speed 10 --fz -1", "mftyre swift: --fz: expected a value above 0, got -1"),
    ("swift t.tir --speed 10 --csv out.csv", "mftyre swift: --csv out.csv: exists; pass --overwrite to replace"),
    ("fmu build t.tir -o out.csv", "mftyre fmu build: error: -o out.csv: exists; pass --overwrite to replace"),
    ("demo --out full",
     "mftyre demo: error: --out full (a folder that is not empty): exists; pass --overwrite to replace"),
    ("gaps --dynamic r.csv --model t.tir --channels FX",
     "mftyre gaps: --channels is for steady data; dynamic runs use every measured channel"),
    ("swift t.tir --speed 1e-3 --distance 100 --dt 1e-5", "mftyre swift: --distance 100 m at 0.001 m/s in steps of "
     "--dt 1e-05 s is 1e+10 steps, more than the 10,000,000 one run writes; shorten --distance or raise --dt"),
    # failures (exit 1): the same one line
    ("fit nofile.csv -o new.tir --quiet", "mftyre fit: nofile.csv: file not found: expected an existing measurement "
                                          "file"),
    ("gaps nofile.csv --model t.tir", "mftyre gaps: nofile.csv: file not found: expected an existing measurement file"),
    ("plot nofile.csv -o new.png", "mftyre plot: nofile.csv: file not found: expected an existing measurement file"),
    ("swift t.tir --speed 10 --road nofile.csv", "mftyre swift: road file 'nofile.csv' not found"),
    ("fmu build nofile.tir -o x.fmu", "mftyre fmu build: error: no such property file: 'nofile.tir'"),
    ("eval nofile.tir", "mftyre eval: error: nofile.tir: file not found: expected an existing .tir property file"),
])
def test_command_errors_one_line_with_the_command_named(argv, message, tmp_path, monkeypatch, capsys):
    """Every command's errors as one line on stderr naming the command: usage errors (bad options, outputs the
    output rule refuses) exit 2 before any work, failures exit 1."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.tir").write_bytes(TIR61.read_bytes())
    for name in ("out.tir", "out.csv", "full/a"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("x")
    rc = cli.main(argv.split())
    captured = capsys.readouterr()
    assert (rc, captured.err, captured.out) == (1 if "nofile" in argv else 2, message + "\n", "")
