"""The files a user hands to mftyre and the files it writes (mftyre.files): .tir tokenising in linear time, regular
files only with a size limit, the one output rule of every command, ordinary permissions, CSV/TYDEX checks,
the eval grid limit."""
from __future__ import annotations

import os
import stat
import subprocess
import sys
import threading
import warnings

import numpy as np
import pytest

import mftyre
from mftyre import cli
from mftyre.data import TyreData, read_csv, read_tydex, trailer_programme, write_tydex
from mftyre.errors import DataError, TirError
from mftyre.files import OutputError, check_outputs, sample_tir
from mftyre.demo import run_demo
from mftyre.tir import parse_tir, read_tir, write_tir

from conftest import PROJECT, TIR_FILES

TIR61 = TIR_FILES / "car_205_60R15_mf61.tir"


def _quiet_load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(path)


# ---------------------------------------------------------------------------------------- .tir reading
def test_long_garbage_number_is_rejected_quickly_naming_line_and_parameter():
    """100,000 digits followed by a letter: the old number pattern backtracked quadratically (40,000 digits took
    37 s, 100,000 would take minutes); a linear match takes milliseconds. Run in a child process so that a
    regression fails on the timeout (60 s, ~1000 x the expected time) instead of hanging the suite."""
    code = ("import sys, warnings; from mftyre.tir import parse_tir; from mftyre.errors import TirError\n"
            "text = open(sys.argv[1]).read().replace('PCX1                      = 1.579',"
            " 'PCX1 = ' + '1' * 100000 + 'x')\n"
            "try:\n    parse_tir(text, 'big.tir')\nexcept TirError as exc:\n    print(exc)\n")
    env = dict(os.environ, PYTHONPATH=str(PROJECT))
    out = subprocess.run([sys.executable, "-c", code, str(TIR61)], capture_output=True, text=True, timeout=60,
                         env=env, cwd=PROJECT)
    message = out.stdout.strip()
    assert message.startswith("big.tir:194: PCX1: expected a number"), out.stderr
    assert "(100001 characters)" in message and len(message) < 300  # the value is shortened in the message


def test_number_tokens_still_read_every_spelling():
    base = TIR61.read_text()
    for text, value in (("1.5", 1.5), ("-.5", -0.5), ("+2.", 2.0), ("1.0D+1", 10.0), ("3e-2", 0.03), ("7", 7.0)):
        prm = parse_tir(base.replace("PCX1                      = 1.579", f"PCX1 = {text}"), "x.tir")
        assert prm.PCX1 == value
    for bad in ("1.2.3", "1e", "e5", "1x", "--1"):
        with pytest.raises(TirError, match="PCX1: expected a number"):
            parse_tir(base.replace("PCX1                      = 1.579", f"PCX1 = {bad}"), "x.tir")


def _returns_within(fn, seconds=20.0):
    """Run fn in a daemon thread: (finished, exception). A read that blocks (a FIFO with no writer) does not
    finish; the thread is left behind rather than hanging the suite."""
    result = {}

    def target():
        try:
            fn()
        except Exception as exc:  # noqa: BLE001 - handed back to the test
            result["exc"] = exc

    t = threading.Thread(target=target, daemon=True)
    t.start()
    t.join(seconds)
    return not t.is_alive(), result.get("exc")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("reader, error", [(read_tir, TirError), (read_csv, DataError), (read_tydex, DataError)])
def test_a_fifo_is_refused_without_blocking(tmp_path, reader, error):
    fifo = tmp_path / "pipe.tir"
    os.mkfifo(fifo)
    finished, exc = _returns_within(lambda: reader(fifo))
    assert finished, f"{reader.__name__} blocked on a FIFO"
    assert isinstance(exc, error) and "not a regular file" in str(exc) and "pipe.tir" in str(exc)


@pytest.mark.skipif(not os.path.exists("/dev/null"), reason="no /dev/null")
def test_a_device_is_refused():
    with pytest.raises(TirError, match="not a regular file"):
        read_tir("/dev/null")
    with pytest.raises(DataError, match="not a regular file"):
        read_csv("/dev/null")


def test_size_limits(tmp_path):
    big = tmp_path / "big.tir"
    with open(big, "wb") as fh:  # sparse: no disk used
        fh.truncate(17 * 2**20)
    with pytest.raises(TirError, match=r"big.tir: 17825792 bytes, more than the limit of 16777216 bytes"):
        read_tir(big)
    csv = tmp_path / "d.csv"
    csv.write_text("FZ,SA,SL,VX,P\n" + "4000,0,0,16,2e5\n" * 20)
    assert len(read_csv(csv)) == 20
    with pytest.raises(DataError, match="more than the limit of 100 bytes"):
        read_csv(csv, max_bytes=100)
    tdx = write_tydex(read_csv(csv), tmp_path / "d.tdx")
    with pytest.raises(DataError, match="more than the limit of 100 bytes"):
        read_tydex(tdx, max_bytes=100)


def test_missing_and_directory(tmp_path):
    with pytest.raises(TirError, match="file not found"):
        read_tir(tmp_path / "none.tir")
    with pytest.raises(TirError, match="is a directory"):
        read_tir(tmp_path)
    with pytest.raises(DataError, match="file not found"):
        read_csv(tmp_path / "none.csv")


# --------------------------------------------------------------------------------------- output rule
def test_check_outputs_compares_resolved_paths_and_inodes(tmp_path):
    data = tmp_path / "d.csv"
    data.write_text("x\n")
    link = tmp_path / "hard.csv"
    os.link(data, link)
    for out in (data, tmp_path / "." / "d.csv", link, str(data)):
        with pytest.raises(OutputError, match="an input is never overwritten"):
            check_outputs({"-o": out}, {"DATA": data}, overwrite=True)
    with pytest.raises(OutputError, match="is also the --json output"):
        check_outputs({"-o": tmp_path / "a.tir", "--json": tmp_path / "sub" / ".." / "a.tir"})
    with pytest.raises(OutputError, match=r"-o .*new.tir: exists; pass --overwrite"):
        (tmp_path / "new.tir").write_text("")
        check_outputs({"-o": tmp_path / "new.tir"})
    check_outputs({"-o": tmp_path / "new.tir"}, overwrite=True)
    check_outputs({"-o": tmp_path / "fresh.tir"}, {"DATA": data}, folders={"--report": tmp_path / "empty"})
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "old.md").write_text("")
    with pytest.raises(OutputError, match="not empty"):
        check_outputs({}, folders={"--report": tmp_path / "full"})


def test_fit_never_replaces_its_data_with_the_report(tmp_path, capsys):
    """`mftyre fit d.csv -o f.tir --report d.csv` wrote the report over the data."""
    data = tmp_path / "d.csv"
    data.write_text("FZ,SA,SL,VX,P\n4000,0,0,16,2e5\n")
    before = data.read_bytes()
    assert cli.main(["fit", str(data), "-o", str(tmp_path / "f.tir"), "--report", str(data), "--quiet"]) == 2
    assert "an input is never overwritten" in capsys.readouterr().err
    assert cli.main(["fit", str(data), "-o", str(tmp_path / "f.tir"), "--report", str(data), "--quiet",
                     "--overwrite"]) == 2
    assert data.read_bytes() == before and not (tmp_path / "f.tir").exists()


def test_fit_needs_overwrite_for_an_existing_report(tmp_path, capsys):
    data = tmp_path / "d.csv"
    data.write_text("FZ,SA,SL,VX,P\n4000,0,0,16,2e5\n")
    report = tmp_path / "r.md"
    report.write_text("mine\n")
    assert cli.main(["fit", str(data), "-o", str(tmp_path / "f.tir"), "--report", str(report), "--quiet"]) == 2
    assert "--report" in capsys.readouterr().err and report.read_text() == "mine\n"
    plot = tmp_path / "r_pure_fx.png"  # the report's plots beside it are outputs too
    report.unlink()
    plot.write_text("mine\n")
    assert cli.main(["fit", str(data), "-o", str(tmp_path / "f.tir"), "--report", str(report), "--quiet"]) == 2
    assert "r_pure_fx.png" in capsys.readouterr().err and plot.read_text() == "mine\n"


def test_fmu_build_refuses_its_input_and_an_existing_fmu(tmp_path, capsys):
    fmu = tmp_path / "x.fmu"
    fmu.write_bytes(b"PK not really")
    assert cli.main(["fmu", "build", str(fmu), "-o", str(fmu)]) == 2
    assert "an input is never overwritten" in capsys.readouterr().err
    assert cli.main(["fmu", "build", str(TIR61), "-o", str(fmu)]) == 2
    assert "pass --overwrite" in capsys.readouterr().err
    assert fmu.read_bytes() == b"PK not really"


@pytest.mark.parametrize("option", ["--csv", "--plot"])
def test_eval_needs_overwrite_for_an_existing_output(tmp_path, capsys, option):
    target = tmp_path / "out.x"
    target.write_bytes(b"mine\n")
    assert cli.main(["eval", str(TIR61), "--alpha", "0:0.1:3", option, str(target), "-q"]) == 2
    assert option in capsys.readouterr().err and target.read_bytes() == b"mine\n"
    assert cli.main(["eval", str(TIR61), "--alpha", "0:0.1:3", option, str(target), "-q", "--overwrite"]) == 0
    assert target.read_bytes() != b"mine\n"


def test_gaps_outputs_follow_the_rule(tmp_path, capsys):
    data = tmp_path / "d.csv"
    data.write_text("FZ,SA,SL,VX,P\n4000,0,0,16,2e5\n")
    base = tmp_path / "base.tir"
    base.write_bytes(TIR61.read_bytes())
    for extra in (["-o", str(base)], ["--json", str(data)], ["--report", str(data)]):
        assert cli.main(["gaps", str(data), "--model", str(base), *extra, "--quiet", "--overwrite"]) == 2
        assert "an input is never overwritten" in capsys.readouterr().err
    (tmp_path / "rep").mkdir()
    (tmp_path / "rep" / "notes.txt").write_text("mine\n")
    assert cli.main(["gaps", str(data), "--model", str(base), "--report", str(tmp_path / "rep"), "--quiet"]) == 2
    assert "not empty" in capsys.readouterr().err
    assert base.read_bytes() == TIR61.read_bytes()


def test_demo_refuses_a_folder_that_is_not_empty(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("mine\n")
    assert cli.main(["demo", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--overwrite" in err and "overwrite=True" not in err  # the command line speaks its own options
    assert [p.name for p in out.iterdir()] == ["mine.txt"]
    with pytest.raises(OutputError, match=r"overwrite=True"):  # Python speaks keywords
        run_demo(out)


def test_written_files_have_ordinary_permissions(tmp_path):
    """write_tir wrote through mkstemp and left its 0600 on the .tir file."""
    old = os.umask(0o022)
    try:
        target = write_tir(_quiet_load(TIR61).params, tmp_path / "t.tir")
    finally:
        os.umask(old)
    assert stat.S_IMODE(target.stat().st_mode) == 0o644
    assert not [p for p in tmp_path.iterdir() if p.name != "t.tir"]  # no temporary file left


# ------------------------------------------------------------------------------------------- CSV/TYDEX
def _csv(tmp_path, text, name="d.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("value", ["inf", "-inf", "1e400"])
def test_infinite_values_are_refused_naming_file_column_and_row(tmp_path, value):
    path = _csv(tmp_path, f"FZ,SA,SL,VX,P,FY\n4000,0,0,16,2e5,10\n4000,{value},0,16,2e5,10\n")
    with pytest.raises(DataError, match=r"d.csv: line 3: channel SA: -?inf \(infinite"):
        read_csv(path)
    path = _csv(tmp_path, f"FZ,SA,SL,VX,P,FY\n4000,0,0,16,2e5,{value}\n")  # measured outputs too
    with pytest.raises(DataError, match=r"line 2: channel FY: -?inf"):
        read_csv(path)
    path = _csv(tmp_path, "load,SA,SL,VX,P\n4000,0,0,16,2e5\n" + f"{value},0,0,16,2e5\n", "m.csv")
    with pytest.raises(DataError, match=r"m.csv: line 3: channel FZ: -?inf .*file column 'load'"):
        read_csv(path, columns={"load": "FZ"})


def test_infinite_values_in_tydex_and_frames_are_refused(tmp_path):
    data = read_csv(_csv(tmp_path, "FZ,SA,SL,VX,P\n4000,0,0,16,2e5\n4000,0.1,0,16,2e5\n"))
    tdx = write_tydex(data, tmp_path / "d.tdx")
    text = tdx.read_text()
    rows = text.split("**MEASURDATA\n")[1].splitlines()
    bad = tdx.with_name("bad.tdx")
    bad.write_text(text.replace(rows[1], rows[1].replace("0.10000000000000001", "1e400", 1)))
    line = text.split("\n").index(rows[1]) + 1
    with pytest.raises(DataError, match=rf"bad.tdx:{line}: channel SA: inf .*file column 'SLIPANGL'"):
        read_tydex(bad)
    frame = data.frame.copy()
    frame.loc[1, "VX"] = np.inf
    with pytest.raises(DataError, match="row 1: channel VX: inf"):
        TyreData(frame, source="mine")


def test_a_duplicated_channel_column_is_refused(tmp_path):
    with pytest.raises(DataError, match=r"line 1: column 'FZ' appears twice"):
        read_csv(_csv(tmp_path, "FZ,SA,SL,VX,P,FZ\n4000,0,0,16,2e5,1\n"))
    with pytest.raises(DataError, match=r"line 1: column 'fz' \(FZ\) appears twice \(also as column 'FZ'\)"):
        read_csv(_csv(tmp_path, "FZ,SA,SL,VX,P,fz\n4000,0,0,16,2e5,1\n"))
    with pytest.raises(DataError, match=r"column 'load' \(FZ\) appears twice"):
        read_csv(_csv(tmp_path, "FZ,SA,SL,VX,P,load\n4000,0,0,16,2e5,1\n"), columns={"load": "FZ"})


def test_a_header_only_csv_is_a_data_error_also_in_fit(tmp_path, capsys):
    path = _csv(tmp_path, "FZ,SA,SL,VX,P\n")
    with pytest.raises(DataError, match="d.csv: no data rows"):
        read_csv(path)
    assert cli.main(["fit", str(path), "-o", str(tmp_path / "f.tir"), "--quiet"]) == 1
    assert "no data rows" in capsys.readouterr().err


def test_tydex_with_a_byte_order_mark_and_crlf_reads(tmp_path):
    model = _quiet_load(TIR61)
    data = trailer_programme(model, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), points=5)
    tdx = write_tydex(data, tmp_path / "d.tdx")
    bom = tmp_path / "bom.tdx"
    bom.write_bytes(b"\xef\xbb\xbf" + tdx.read_bytes().replace(b"\n", b"\r\n"))
    back = read_tydex(bom)
    for ch in data.channels:
        np.testing.assert_array_equal(back.array(ch), data.array(ch))
    csv = tmp_path / "bom.csv"
    csv.write_bytes(b"\xef\xbb\xbfFZ,SA,SL,VX,P\r\n4000,0,0,16,2e5\r\n")
    assert read_csv(csv).array("FZ")[0] == 4000.0


@pytest.mark.parametrize("row, message", [
    ("4000 0 0 0 0 16", "6 values, expected 7"),  # channels FZW LONGSLIP SLIPANGL INCLANGL TURNSLIP LONGVEL INFLPRES
    ("4000 0 0 0 0 16 2e5 1", "8 values, expected 7"),
    ("4000 0 0 0 0 16 2e5 1 2", "9 values, expected 7"),
    ("4000 0 abc 0 0 16 2e5", r"value 3 \(channel SLIPANGL\): non-numeric value 'abc'"),
])
def test_tydex_sample_rows_are_checked_with_their_line(tmp_path, row, message):
    data = read_csv(_csv(tmp_path, "FZ,SA,SL,VX,P\n4000,0,0,16,2e5\n4000,0,0,16,2e5\n4000,0,0,16,2e5\n"))
    text = write_tydex(data, tmp_path / "d.tdx").read_text()
    head, rows = text.split("**MEASURDATA\n")
    lines = rows.splitlines()
    lines[1] = row
    bad = tmp_path / "bad.tdx"
    bad.write_text(head + "**MEASURDATA\n\n! a comment\n" + "\n".join(lines) + "\n")
    line = head.count("\n") + 1 + 3 + 1  # **MEASURDATA, a blank line, a comment, the first row
    with pytest.raises(DataError, match=rf"bad.tdx:{line}: {message}"):
        read_tydex(bad)


# ---------------------------------------------------------------------------------------------- eval
def test_eval_grid_is_bounded(capsys):
    assert cli.main(["eval", str(TIR61), "--alpha", "0:1:1000000000", "-q"]) == 2
    err = capsys.readouterr().err
    assert "--alpha" in err and "1,000,000,000" in err and "10,000,000" in err
    assert cli.main(["eval", str(TIR61), "--alpha", "0:1:5000", "--fz", "1kN:5kN:5000", "-q"]) == 2
    err = capsys.readouterr().err
    assert "5000 x 5000 = 25,000,000 points" in err and "--alpha, --fz" in err


@pytest.mark.parametrize("argv, words", [
    (["gaps", "d.csv", "--model", "m.tir", "--holdout", "nan"], "--holdout: expected a finite number in (0, 1)"),
    (["gaps", "d.csv", "--model", "m.tir", "--holdout", "1"], "--holdout: expected a finite number in (0, 1)"),
    (["gaps", "d.csv", "--model", "m.tir", "--alpha", "inf"], "--alpha: expected a finite number in (0, 1)"),
    (["gaps", "d.csv", "--model", "m.tir", "--max-effects", "-1"], "--max-effects: expected an integer in [0,"),
    (["gaps", "d.csv", "--model", "m.tir", "--seed", "1.5"], "--seed: expected an integer"),
    (["demo", "--seed", "x"], "--seed: expected an integer"),
])
def test_numeric_options_are_validated(capsys, argv, words):
    assert cli.main(argv) == 2
    assert words in capsys.readouterr().err


# ------------------------------------------------------------------------------------------ samples
def test_sample_files_are_found_from_the_package():
    assert sample_tir("car_205_60R15_mf61.tir").read_bytes() == TIR61.read_bytes()
    with pytest.raises(FileNotFoundError, match="car_205_60R15_mf62_swift.tir"):
        sample_tir("nope.tir")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_road_profile_path_is_read_like_every_user_file(tmp_path):
    from swift.road import Sampled

    fifo = tmp_path / "road.csv"
    os.mkfifo(fifo)
    finished, exc = _returns_within(lambda: Sampled.from_csv(fifo))
    assert finished and isinstance(exc, DataError) and "not a regular file" in str(exc)
    good = tmp_path / "good.csv"
    good.write_text("x,z\n0,0\n1,0.01\n")
    assert Sampled.from_csv(good).height_range() == (0.0, 0.01)


def test_write_tydex_never_replaces_the_file_it_read(tmp_path):
    path = _csv(tmp_path, "FZ,SA,SL,VX,P\n4000,0,0,16,2e5\n")
    tdx = write_tydex(read_csv(path), tmp_path / "d.tdx")
    with pytest.raises(OutputError, match="an input is never overwritten"):
        write_tydex(read_tydex(tdx), tdx, overwrite=True)
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_tydex(read_csv(path), tdx)
