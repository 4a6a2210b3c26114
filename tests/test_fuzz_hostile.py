"""Hostile files, planted links and shifted columns (issue 25): every output goes through the one atomic no-follow
routine (mftyre.files.write_atomically), malformed inputs give MFTyreError subclasses naming what was wrong, and
no impossible result leaves the library silently. The seeded fuzz cases at the end count raw exceptions, silent
impossible results and writes outside the requested output; each count must be 0."""
from __future__ import annotations

import os
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import mftyre
from mftyre import cli
from mftyre.errors import DataError, MFTyreError, TirError
from mftyre import files
from mftyre.files import OutputError, write_atomically

from conftest import TIR_FILES

T61 = TIR_FILES / "car_205_60R15_mf61.tir"
T62 = TIR_FILES / "car_205_60R15_mf62_swift.tir"
VICTIM = b"the victim's own bytes\n"


def _victim(tmp_path) -> Path:
    victim = tmp_path / "victim.txt"
    victim.write_bytes(VICTIM)
    return victim


def _quiet(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args, **kwargs)


# ------------------------------------------------------------------------------------ 1+2: the one write routine
def test_write_atomically_refuses_links_and_fifos_and_leaves_no_temporary(tmp_path):
    victim = _victim(tmp_path)
    link = tmp_path / "out.csv"
    link.symlink_to(victim)
    with pytest.raises(OutputError, match="symbolic link"):
        write_atomically(link, "x")
    dangling = tmp_path / "dangling.csv"
    dangling.symlink_to(tmp_path / "created_by_link.txt")
    with pytest.raises(OutputError, match="symbolic link"):
        write_atomically(dangling, "x")
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match="not a regular file"):
        write_atomically(fifo, "x")
    assert victim.read_bytes() == VICTIM and not (tmp_path / "created_by_link.txt").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dangling.csv", "fifo.csv", "out.csv", "victim.txt"]
    with pytest.raises(OutputError, match="below_a_file.txt"):
        write_atomically(victim / "below_a_file.txt", "x")  # a parent that is a file: an OutputError, not raw


def test_figures_and_tables_are_rendered_in_memory_then_written_by_the_routine(tmp_path):
    import pandas as pd
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure()
    FigureCanvasAgg(fig)
    fig.subplots().plot([0, 1])
    assert files.write_figure(fig, tmp_path / "a.png").read_bytes()[:4] == b"\x89PNG"
    assert files.write_figure(fig, tmp_path / "a.svg").read_text().lstrip().startswith("<?xml")
    files.write_frame_csv(pd.DataFrame({"a": [1, 2]}), tmp_path / "t.csv", index=False)
    assert (tmp_path / "t.csv").read_text() == "a\n1\n2\n"
    victim = _victim(tmp_path)
    (tmp_path / "link.png").symlink_to(victim)
    with pytest.raises(OutputError):
        files.write_figure(fig, tmp_path / "link.png")
    assert victim.read_bytes() == VICTIM


@pytest.mark.parametrize("command", [["eval", str(T61), "--alpha", "0:0.1:3", "-q"],
                                     ["soil", str(T61), "--soil", "dry_sand", "--slip", "0:0.2:3", "-q"]])
@pytest.mark.parametrize("option", ["--csv", "--plot"])
def test_eval_and_soil_never_write_through_a_link_even_with_overwrite(tmp_path, capsys, command, option):
    victim = _victim(tmp_path)
    link, dangling = tmp_path / "out.png", tmp_path / "dangling.png"
    link.symlink_to(victim)
    dangling.symlink_to(tmp_path / "new_target.png")
    for target in (link, dangling):
        assert cli.main([*command, option, str(target), "--overwrite"]) != 0
        assert "symbolic link" in capsys.readouterr().err
    assert victim.read_bytes() == VICTIM and not (tmp_path / "new_target.png").exists()


def test_eval_csv_to_a_fifo_is_refused_without_blocking(tmp_path, capsys):
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    result = []
    worker = threading.Thread(target=lambda: result.append(cli.main(
        ["eval", str(T61), "--alpha", "0:0.1:3", "-q", "--csv", str(fifo), "--overwrite"])), daemon=True)
    worker.start()
    worker.join(30)
    if worker.is_alive():  # unblock the writer so the test process can exit, then fail
        with open(fifo, "rb") as fh:
            fh.read()
        pytest.fail("mftyre eval --csv FIFO --overwrite blocked")
    assert result == [2] and "not a regular file" in capsys.readouterr().err


def test_fit_report_and_its_plots_are_never_written_through_links(tmp_path, capsys):
    data = tmp_path / "d.csv"
    data.write_text("FZ,SA,SL,VX,P\n4000,0,0,16,2e5\n")
    victim = _victim(tmp_path)
    for name in ("r.md", "r_pure_fx.png"):
        (tmp_path / name).symlink_to(victim)
        assert cli.main(["fit", str(data), "-o", str(tmp_path / "f.tir"), "--report", str(tmp_path / "r.md"),
                         "--quiet", "--overwrite"]) == 2
        assert "symbolic link" in capsys.readouterr().err
        (tmp_path / name).unlink()
    assert victim.read_bytes() == VICTIM and not (tmp_path / "f.tir").exists()


def test_demo_never_writes_through_a_link_in_its_folder_and_reports_an_unwritable_folder(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    victim = _victim(tmp_path)
    (out / "characteristics.png").symlink_to(victim)
    assert cli.main(["demo", "--out", str(out), "--overwrite"]) == 2
    assert "symbolic link" in capsys.readouterr().err and victim.read_bytes() == VICTIM
    assert cli.main(["demo", "--out", str(victim / "out")]) == 2  # below a file: cannot be created
    assert "cannot create" in capsys.readouterr().err


def test_native_fmu_build_never_writes_through_a_planted_partial_link(tmp_path, monkeypatch):
    """The zip went to the predictable `.<name>.<pid>.partial` opened with ZipFile(path, "w"), following a link
    planted there; now it is zipped in memory and written by write_atomically (random name, O_EXCL|O_NOFOLLOW)."""
    from mftyre.fmu import native_build

    def fake_compile(sources, library):  # the compiler is not what is tested here
        library.parent.mkdir(parents=True, exist_ok=True)
        library.write_bytes(b"\x7fELF not really")

    monkeypatch.setattr(native_build, "compile_sources", fake_compile)
    victim = _victim(tmp_path)
    output = tmp_path / "t.fmu"
    (tmp_path / f".t.fmu.{os.getpid()}.partial").symlink_to(victim)
    native_build.build_native_fmu(T61, output, model="steady")
    assert victim.read_bytes() == VICTIM
    import zipfile

    with zipfile.ZipFile(output) as zf:
        assert "modelDescription.xml" in zf.namelist()
    output.unlink()
    output.symlink_to(victim)
    with pytest.raises(MFTyreError, match="symbolic link"):
        native_build.build_native_fmu(T61, output, model="steady", overwrite=True)
    assert victim.read_bytes() == VICTIM


# ------------------------------------------------------------------------------------ 3: CSV field counts
@pytest.mark.parametrize("rows, line, count", [
    ("4000,0.1,0.0,10,220000,99\n", 2, 6),  # pandas took FZ as the index: FZ = 0.1, VX = 220000, P = 99
    ("4000,0.1,0.0,10,220000\n4000,0.1,0.0\n", 3, 3),  # a short row was padded with "not measured"
    ("4000,0.1,0.0,10,220000\n" + ",".join(["1"] * 60000) + "\n", 3, 60000),  # took 42 s
])
def test_a_row_whose_field_count_differs_from_the_header_names_file_and_line(tmp_path, rows, line, count):
    from mftyre.data import read_csv

    path = tmp_path / "d.csv"
    path.write_text("FZ,SA,SL,VX,P\n" + rows)
    start = time.process_time()
    with pytest.raises(DataError, match=rf"d\.csv: line {line}: {count} fields, but the header has 5 columns"):
        read_csv(path)
    assert time.process_time() - start < 5.0  # milliseconds in fact; the old reader took 42 s on 60,000 fields


def test_csv_with_cr_only_line_ends_quoted_commas_and_a_huge_header_field(tmp_path):
    from mftyre.data import read_csv

    path = tmp_path / "cr.csv"
    path.write_bytes(b"FZ,SA,SL,VX,P\r4000,0.1,0.0,10,220000\r3000,0.0,0.1,10,220000\r")
    frame = read_csv(path).frame
    assert frame["FZ"].tolist() == [4000.0, 3000.0] and frame["VX"].tolist() == [10.0, 10.0]
    path.write_bytes(b'FZ,SA,SL,VX,P,NOTE\n4000,0.1,0.0,10,220000,"a,b"\n')  # a quoted comma is one field
    assert read_csv(path).frame["NOTE"].tolist() == ["a,b"]
    path.write_bytes(b"FZ,SA,SL,VX,P," + b"X" * (128 * 1024 + 10) + b"\n4000,0.1,0.0,10,220000,1\n")
    with pytest.raises(DataError, match="line 1"):
        read_csv(path)


# ------------------------------------------------------------------------------------ 4: linear .tir parsing
def test_repeated_unknown_sections_parse_in_linear_time():
    """320,000 repeated `[SHAPE]` tables (5 MB) took 27.9 s (each repetition copied the kept text); lists joined
    once take under a second. CPU time, bounded at 10 s."""
    from mftyre.tir import parse_tir

    text = T61.read_text() + "[SHAPE]\n1.0 0.0\n" * 320_000
    start = time.process_time()
    prm = _quiet(parse_tir, text, "big.tir")
    assert time.process_time() - start < 10.0
    assert prm.extra_sections["SHAPE"].count("1.0 0.0") == 320_000
