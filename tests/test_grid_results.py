"""mftyre.grid_results: the one home of writing a grid command's results; `mftyre eval` and `mftyre soil` follow
the same output rule (mftyre.files.check_outputs) and write the same way."""
from __future__ import annotations

import types

import numpy as np
import pandas as pd
import pytest

from conftest import TIR_FILES
from mftyre.arguments import parse_sweep
from mftyre.cli import main
from mftyre.grid_results import grid_frame, sweep_grid

CAR = str(TIR_FILES / "car_205_60R15_mf61.tir")
AGRI = str(TIR_FILES / "agri_460_85R34_mf61.tir")

COMMANDS = {  # a swept run of each command, without outputs
    "eval": ["eval", CAR, "--alpha", "-5deg:5deg:5", "--fz", "3kN,5kN"],
    "soil": ["soil", AGRI, "--soil", "sandy_loam", "--slip", "0%:40%:5", "--fz", "20kN,25kN"],
}


@pytest.fixture(params=sorted(COMMANDS))
def argv(request):
    return COMMANDS[request.param]


def test_existing_output_or_dangling_link_needs_overwrite(argv, tmp_path, capsys):
    csv, link = tmp_path / "out.csv", tmp_path / "link.png"
    csv.write_text("keep me")
    link.symlink_to(tmp_path / "nowhere.png")  # writing would create a file through the link
    assert main([*argv, "--csv", str(csv), "-q"]) == 2
    assert "pass --overwrite to replace" in capsys.readouterr().err and csv.read_text() == "keep me"
    assert main([*argv, "--plot", str(link), "-q"]) == 2
    assert "is a symbolic link" in capsys.readouterr().err  # a link is never replaced, even with --overwrite
    assert not (tmp_path / "nowhere.png").exists()


def test_refusals_before_any_work(argv, tmp_path, capsys):
    folder = tmp_path / "a_folder"
    folder.mkdir()
    same = tmp_path / "both.out"
    assert main([*argv, "--csv", str(folder), "--overwrite", "-q"]) == 2
    assert "is a folder: expected a file path" in capsys.readouterr().err
    assert main([*argv, "--csv", str(same), "--plot", str(same), "-q"]) == 2
    assert "is also the --plot output" in capsys.readouterr().err
    assert main([*argv, "--csv", argv[1], "--overwrite", "-q"]) == 2
    assert "an input is never overwritten" in capsys.readouterr().err
    assert main([*argv, "--x", "vx", "-q"]) == 2
    assert "'vx' is not swept" in capsys.readouterr().err
    assert not same.exists()


def test_both_commands_write_csv_and_plot_into_new_folders(argv, tmp_path, capsys):
    csv, png = tmp_path / "new" / "t.csv", tmp_path / "other" / "t.png"
    assert main([*argv, "--csv", str(csv), "--plot", str(png), "-q"]) == 0
    err = capsys.readouterr().err
    frame = pd.read_csv(csv)
    assert len(frame) == 10
    assert f"wrote {csv} (10 rows, {frame.shape[1]} columns)" in err and f"wrote {png}" in err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main([*argv, "--csv", str(csv), "--overwrite", "-q"]) == 0  # replaced with --overwrite
    assert pd.read_csv(csv).equals(frame)


def _args(**sweeps):
    return types.SimpleNamespace(**{n: parse_sweep(n, text) for n, text in sweeps.items()})


def test_grid_frame_columns():
    """Inputs in 'ij' order with their SI unit, a name_used column where the model used other values, an output
    named like a swept input labelled with the `repeated` suffix."""
    args = _args(fz="3kN,5kN", alpha="-0.1:0.1:3")
    swept = ["fz", "alpha"]
    grids, shape = sweep_grid(args, swept)
    assert shape == (2, 3) and grids["fz"][:, 0].tolist() == [3e3, 5e3]
    out = {"fy": grids["alpha"] * 10.0, "fz": grids["fz"]}
    frame = grid_frame(args, out, swept, shape, ["fy"], input_units={"fz": "N", "alpha": "rad"},
                       output_units={"fy": ("N", "lateral force")},
                       used=lambda name, v: np.minimum(v, 4e3) if name == "fz" else v)
    assert list(frame.columns) == ["fz [N]", "fz_used [N]", "alpha [rad]", "fy [N]"]
    assert frame["fz [N]"].tolist() == [3e3] * 3 + [5e3] * 3
    assert frame["fz_used [N]"].tolist() == [3e3] * 3 + [4e3] * 3
    np.testing.assert_array_equal(frame["fy [N]"], np.tile([-1.0, 0.0, 1.0], 2))
    units = {"fy": ("N", ""), "fz": ("N", "")}
    frame = grid_frame(args, out, swept, shape, ["fz"], input_units={"fz": "N", "alpha": "rad"},
                       output_units=units, repeated="_out")
    assert list(frame.columns) == ["fz [N]", "alpha [rad]", "fz_out [N]"]
