"""Rig files as labs deliver them: wrong units and axes refused with the channel named (and the option that fixes
it), converted when the option is given (checked against data converted by hand), constant channels, and the
Calspan tyre test consortium (TTC) format written here from a synthetic programme (.dat and .mat)."""
from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest

import mftyre
from mftyre.cli import main
from mftyre.data import (TyreData, check_plausible, data_format, read_csv, read_data, read_ttc, speaking_cli,
                         trailer_programme)
from mftyre.errors import DataError

from conftest import TIR_FILES

DEG = math.pi / 180
CHANNELS = ["FZ", "SL", "SA", "IA", "VX", "P", "FX", "FY", "MX", "MY", "MZ", "OMEGA", "RL", "RE"]


@pytest.fixture(scope="module")
def si():
    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")
    data = trailer_programme(model, loads=(0.6, 1.0), pressures=(1.0,), cambers_deg=(0.0, 3.0), points=11,
                             noise=0.5, seed=2)
    return data.frame[CHANNELS].copy()


def _csv(tmp_path, frame, name="rig.csv"):
    path = tmp_path / name
    frame.to_csv(path, index=False, float_format="%.17g")
    return path


def _close(data, si, channels=CHANNELS):
    for ch in channels:
        np.testing.assert_allclose(data.array(ch), si[ch].to_numpy(), rtol=1e-12, atol=1e-12, err_msg=ch)


def test_degrees_refused_with_the_column_named_then_converted(si, tmp_path):
    raw = si.copy()
    raw["SA"] *= 180 / math.pi  # hand conversion: the rig wrote degrees
    raw["IA"] *= 180 / math.pi
    path = _csv(tmp_path, raw)
    with pytest.raises(DataError, match=r"channel SA: 99th percentile of \|SA\| is 12 rad.*deg.*channel IA") as exc:
        read_csv(path)
    assert "units={'SA': 'deg', 'IA': 'deg'}" in str(exc.value)
    _close(read_csv(path, units={"SA": "deg", "IA": "deg"}), si)


def test_kpa_and_kmh_refused_then_converted(si, tmp_path):
    raw = si.copy()
    raw["P"] /= 1000.0          # kPa
    raw["VX"] *= 3.6            # km/h (60 km/h: a plausible speed in m/s; found by VX / (OMEGA x RE))
    path = _csv(tmp_path, raw)
    with pytest.raises(DataError, match=r"channel VX: 99th percentile of \|VX\| is 108 m/s.*km/h.*channel P: median P "
                                          r"is 220 Pa.*kPa.*units=\{'VX': 'km/h', 'P': 'kPa'\}"):
        read_csv(path)
    slow = si[si["VX"] < 25].copy()  # below 100 m/s in km/h: found by VX / (OMEGA x RE) = 3.6
    slow["VX"] *= 3.6
    with pytest.raises(DataError, match=r"channel VX: VX / \(OMEGA x radius\) is 3.6.*VX looks like km/h"):
        read_csv(_csv(tmp_path, slow, "slow.csv"))
    rpm = si.copy()
    rpm["OMEGA"] *= 60 / (2 * math.pi)
    with pytest.raises(DataError, match=r"channel OMEGA: VX / \(OMEGA x radius\) is 0.105.*units=\{'OMEGA': 'rpm'\}"):
        read_csv(_csv(tmp_path, rpm, "rpm.csv"))
    _close(read_csv(path, units={"P": "kPa", "VX": "km/h"}), si)


def test_newcomers_file_mapped_columns_mm_and_psi(si, tmp_path):
    raw = pd.DataFrame({"Load [N]": si["FZ"], "kappa": si["SL"], "alpha_deg": si["SA"] / DEG,
                        "camber": si["IA"] / DEG, "v_kph": si["VX"] * 3.6, "p_psi": si["P"] / 6894.757293168361,
                        "Fy": si["FY"], "RL_mm": si["RL"] * 1000.0})
    path = _csv(tmp_path, raw)
    columns = {"Load [N]": "FZ", "kappa": "SL", "alpha_deg": "SA", "camber": "IA", "v_kph": "VX", "p_psi": "P",
               "Fy": "FY", "RL_mm": "RL"}
    with pytest.raises(DataError, match=r"channel SA \(file column 'alpha_deg'\).*channel IA \(file column 'camber'\)"
                                          r".*channel VX.*channel P \(file column 'p_psi'\): median P is 31.9.*psi"
                                          r".*channel RL \(file column 'RL_mm'\).*mm"):
        read_csv(path, columns=columns)
    data = read_csv(path, columns=columns, units={"SA": "deg", "IA": "deg", "P": "psi", "VX": "km/h", "RL": "mm"})
    _close(data, si, ["FZ", "SL", "SA", "IA", "VX", "P", "FY", "RL"])


def _to_sae(frame):
    """ISO-W -> SAE by hand: y and z turned half a turn about x."""
    out = frame.copy()
    for ch in ("FY", "FZ", "MY", "MZ", "SA"):
        out[ch] = -out[ch]
    return out


def test_sae_axes_refused_then_converted(si, tmp_path):
    path = _csv(tmp_path, _to_sae(si))
    with pytest.raises(DataError, match=r"channel FZ: 100 % of the values are negative.*axes='SAE'"):
        read_csv(path)
    _close(read_csv(path, axes="SAE"), si)
    adapted = _to_sae(si)
    adapted["FZ"], adapted["SA"] = -adapted["FZ"], -adapted["SA"]  # Pacejka's adapted SAE: load and alpha positive
    _close(read_csv(_csv(tmp_path, adapted, "adapted.csv"), axes="adapted-SAE"), si)


def test_reversed_slip_angle_refused(si, tmp_path):
    raw = si.copy()
    raw["SA"] = -raw["SA"]
    path = _csv(tmp_path, raw)
    with pytest.raises(DataError, match=r"channel FY rises with channel SA.*adapted-ISO"):
        read_csv(path)
    _close(read_csv(path, axes="adapted-ISO"), si)


def test_constant_channels_and_their_errors(si, tmp_path):
    path = _csv(tmp_path, si.drop(columns=["P", "IA"]))
    with pytest.raises(DataError, match=r"missing channel\(s\) P.*defaults=\{'P': 'VALUE'\}"):
        read_csv(path)
    data = read_csv(path, defaults={"P": "2.2bar", "IA": 0})
    np.testing.assert_allclose(data.array("P"), 2.2e5, rtol=1e-15)
    with pytest.raises(DataError, match=r"channel FZ is measured in the file"):
        read_csv(path, defaults={"P": 2.2e5, "FZ": "4kN"})


def test_messages_speak_the_command_line_in_the_cli(si, tmp_path, capsys):
    raw = si.copy()
    raw["SA"] /= DEG
    path = _csv(tmp_path, raw)
    with speaking_cli(), pytest.raises(DataError, match=r"--units SA=deg"):
        read_csv(path)
    for command in (["fit", str(path), "-o", str(tmp_path / "out.tir")], ["gaps", str(path), "--model", str(path)],
                    ["plot", str(path), "-o", str(tmp_path / "p.png")]):
        status = main([*command, "--quiet"] if command[0] != "plot" else command)
        err = capsys.readouterr().err
        assert status == 1 and "--units SA=deg" in err and "units={" not in err, command


# ------------------------------------------------------------------------------------------ TTC
TTC_NAMES = ["ET", "V", "N", "SA", "IA", "RL", "RE", "P", "FX", "FY", "FZ", "MX", "MZ", "NFX", "NFY", "TSTC", "SL"]
TTC_UNITS = ["s", "kph", "rpm", "deg", "deg", "cm", "cm", "kPa", "N", "N", "N", "N-m", "N-m", "none", "none",
             "degC", "none"]


def _ttc_columns(si):
    """The programme as the consortium's metric SAE files hold it, converted by hand."""
    sae = _to_sae(si)
    return {"ET": np.arange(len(si)) * 0.01, "V": sae["VX"] * 3.6, "N": sae["OMEGA"] * 60 / (2 * math.pi),
            "SA": sae["SA"] / DEG, "IA": sae["IA"] / DEG, "RL": sae["RL"] * 100, "RE": sae["RE"] * 100,
            "P": sae["P"] / 1000, "FX": sae["FX"], "FY": sae["FY"], "FZ": sae["FZ"], "MX": sae["MX"],
            "MZ": sae["MZ"], "NFX": sae["FX"] / sae["FZ"], "NFY": sae["FY"] / sae["FZ"],
            "TSTC": np.full(len(si), 45.0), "SL": sae["SL"]}


def test_ttc_dat_round_trip(si, tmp_path):
    cols = _ttc_columns(si)
    lines = ["Tire Test Consortium test; run 12 (written by this test, synthetic)", "\t".join(TTC_NAMES),
             "\t".join(TTC_UNITS)]
    lines += ["\t".join(f"{cols[n][i]:.15g}" for n in TTC_NAMES) for i in range(len(si))]
    path = tmp_path / "B0000run12.dat"
    path.write_text("\r\n".join(lines) + "\r\n")
    assert data_format(path) == "ttc"
    data = read_data(path)
    _close(data, si, ["FZ", "SL", "SA", "IA", "VX", "P", "FX", "FY", "MX", "MZ", "OMEGA", "RL", "RE"])
    np.testing.assert_allclose(data.array("TIME"), cols["ET"])
    assert np.all(data.array("TSTC") == 45.0)
    with pytest.raises(DataError, match=r"channel FZ: 100 % of the values are negative.*axes='SAE'"):
        read_data(path, axes="ISO-W")


def test_ttc_mat_round_trip_and_us_units(si, tmp_path):
    import scipy.io

    cols = _ttc_columns(si)
    path = tmp_path / "B0000run13.mat"
    scipy.io.savemat(path, {k: np.asarray(v, float) for k, v in cols.items()} | {"tireid": "synthetic"})
    assert data_format(path) == "ttc"
    _close(read_ttc(path), si, ["FZ", "SL", "SA", "IA", "VX", "P", "FX", "FY", "MX", "MZ", "OMEGA", "RL", "RE"])
    # US units, stated by the file's channel struct
    us = dict(cols, V=cols["V"] / 1.609344, RL=cols["RL"] / 2.54, P=cols["P"] / 6.894757293168361,
              FZ=cols["FZ"] / 4.4482216152605, MZ=cols["MZ"] / 1.3558179483314004)
    units = dict(zip(TTC_NAMES, TTC_UNITS)) | {"V": "mph", "RL": "in", "P": "psi", "FZ": "lb", "MZ": "ft-lb"}
    channel = np.array([(n, units[n]) for n in TTC_NAMES], dtype=[("name", object), ("units", object)])
    path_us = tmp_path / "B0000run14.mat"
    scipy.io.savemat(path_us, {k: np.asarray(v, float) for k, v in us.items()} | {"channel": channel})
    _close(read_data(path_us), si, ["FZ", "SA", "VX", "P", "RL", "MZ"])


def test_ttc_errors(tmp_path):
    bad = tmp_path / "bad.dat"
    bad.write_text("header\nET\tV\tSA\tFZ\ns\tkph\tdeg\n1\t2\t3\t4\n")
    with pytest.raises(DataError, match=r"bad.dat:3: 3 units for 4 channels"):
        read_ttc(bad)
    bad.write_text("header\nET\tV\tSA\tFZ\ns\tkph\tdeg\tfurlongs\n1\t2\t3\t-400\n")
    with pytest.raises(DataError, match=r"channel FZ: unknown unit 'furlongs'"):
        read_ttc(bad)
    bad.write_bytes(b"MATLAB 5.0 MAT-file, damaged")
    with pytest.raises(DataError, match=r"cannot read as a MATLAB .mat file"):
        read_ttc(bad)


# ------------------------------------------------------------------ files we did not write (MFeval)
def test_plausibility_on_every_mfeval_reference_table(mfeval_dir):
    """Every MFeval 4.3.1 reference table (ISO-W, SI, the whole range of load, speed, pressure and slip of five
    tyres from FSAE to truck-like) read as a rig file passes; the same in degrees or SAE axes is refused."""
    tables = [p for p in sorted(mfeval_dir.glob("*.csv")) if not p.name.endswith("_parameters.csv")]
    assert len(tables) >= 20
    for path in tables:
        d = pd.read_csv(path)
        frame = pd.DataFrame({"FZ": d.Fz, "SA": d.alpha, "IA": d.gamma, "SL": d.kappa, "VX": d.Vx, "P": d.P,
                              "FX": d.Fx, "FY": d.Fy, "MZ": d.Mz, "OMEGA": d.omega, "RL": d.Rl, "RE": d.Re})
        check_plausible(frame, path.name)
        sae = frame.assign(FZ=-frame.FZ, FY=-frame.FY, MZ=-frame.MZ, SA=-frame.SA)
        with pytest.raises(DataError, match="channel FZ.*negative"):
            check_plausible(sae, path.name)
        if frame.SA.abs().max() > 0.05:
            with pytest.raises(DataError, match=r"channel SA.*deg"):
                check_plausible(frame.assign(SA=frame.SA / DEG), path.name)


def test_ttc_time_series_with_warm_up_is_recognised_like_the_original(tmp_path):
    """A rig run written in the TTC format (ET, SAE axes, metric units) after a 20 s warm-up (+-4 deg slip-angle
    weaving at the first load, with 1 % load scatter) reads back as a time series in which the recogniser finds
    the programme of the run alone: the warm-up makes no sweep and no level of its own."""
    from mftyre.programme import recognise
    from mftyre.rig import rig_programme

    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")
    run = rig_programme(model, loads=(0.6, 1.2), pressures=(1.0,), cambers_deg=(0.0,), longitudinal=False, seed=2)
    si = run.frame.drop(columns=["RHO", "MY", "TEST"])
    t = np.arange(0.0, 20.0, 0.01)
    first = si.iloc[0]
    rng = np.random.default_rng(1)
    warm = pd.DataFrame({"TIME": t, "FZ": first.FZ * (1 + 0.01 * rng.standard_normal(t.size)), "SL": 0.0,
                         "SA": 4 * DEG * np.sin(2 * math.pi * t / 5), "IA": 0.0, "PHIT": 0.0, "VX": first.VX,
                         "P": first.P})
    out = model.evaluate(warm.FZ.to_numpy(), 0.0, warm.SA.to_numpy(), 0.0, 0.0, warm.VX.to_numpy(), warm.P.to_numpy())
    for ch in ("FX", "FY", "MX", "MZ", "OMEGA", "RL", "RE"):
        warm[ch] = np.asarray(out[ch.lower()])
    both = pd.concat([warm[si.columns], si.assign(TIME=si.TIME + 20.0)], ignore_index=True)
    cols = _ttc_columns(both.assign(MY=0.0)) | {"ET": both["TIME"].to_numpy()}
    lines = ["synthetic run with warm-up", "\t".join(TTC_NAMES), "\t".join(TTC_UNITS)]
    table = np.column_stack([np.asarray(cols[n], float) for n in TTC_NAMES])
    lines += ["\t".join(f"{v:.12g}" for v in row) for row in table]
    path = tmp_path / "run.dat"
    path.write_text("\n".join(lines) + "\n")
    data = read_data(path)
    np.testing.assert_allclose(data.array("TIME"), both["TIME"])
    original, read = recognise(TyreData(si.copy())), recognise(data)
    for kind in ("slip_angle", "slip_ratio", "speed", "load"):
        assert read.count(kind) == original.count(kind), kind
    np.testing.assert_allclose(read.levels["FZ"], original.levels["FZ"], rtol=0.01)
    assert read.sample_rate == pytest.approx(100.0)


# ------------------------------------------------------------------------------ .tir plausibility
def _tir_files():
    from conftest import SHARED

    files = sorted(TIR_FILES.glob("*.tir"))
    return files + sorted((SHARED / "reference").glob("**/*.tir"))


def test_check_passes_every_sample_and_public_tir(capsys):
    files = [str(p) for p in _tir_files()]
    assert main(["check", "-q", *files]) == 0
    assert "outside" not in capsys.readouterr().out


def test_check_flags_values_no_tyre_has(tmp_path, capsys):
    """A newcomer's file: radius in mm, pressure in kPa, slip limit in degrees: legal for the
    equations, refused by `mftyre check` with each parameter named."""
    text = (TIR_FILES / "car_205_60R15_mf61.tir").read_text()
    for name, value in (("UNLOADED_RADIUS", "313"), ("NOMPRES", "220"), ("ALPMAX", "12.5")):
        text = re.sub(rf"(?m)^({name}\s*=\s*)\S+", rf"\g<1>{value}", text, count=1)
    path = tmp_path / "newcomer.tir"
    path.write_text(text)
    assert main(["check", str(path)]) == 1
    out = capsys.readouterr().out
    for name in ("UNLOADED_RADIUS", "NOMPRES", "ALPMAX"):
        assert re.search(rf"error: {name}: .* is outside", out), name
    assert "written in mm or inch" in out and "written in degrees" in out and "kPa, bar or psi" in out


# ---------------------------------------------------------------------------------- command line
def test_fit_reads_a_rig_file_through_the_options_and_records_provenance(si, tmp_path, capsys):
    import hashlib

    raw = si.drop(columns=["P"]).rename(columns={"FZ": "Load"})
    raw["SA"] /= DEG
    raw["IA"] /= DEG
    path = _csv(tmp_path, raw)
    out = tmp_path / "fitted.tir"
    assert main(["fit", str(path), "-o", str(out), "--stages", "pure_fy", "--quiet", "--columns", "FZ=Load",
                 "--units", "SA=deg,IA=deg", "--set", "P=2.2bar"]) == 0
    header = out.read_text().split("[UNITS]")[0]
    assert f"! Data: rig.csv SHA-256 {hashlib.sha256(path.read_bytes()).hexdigest()}, {len(si)} rows" in header
    assert f"mftyre {mftyre.__version__} on " in header and "! Test programme: 2 loads" in header
    assert re.search(r"pure_fy \(FY\) \d+\.\d{3}", header)
    fitted = mftyre.load_tir(out).params
    assert fitted.NOMPRES == pytest.approx(2.2e5)  # the constant pressure, not 2.2 Pa
    capsys.readouterr()
    assert main(["fit", str(path), "-o", str(tmp_path / "x.tir"), "--units", "SA=furlong"]) == 2
    assert "--units: unknown unit 'furlong' for SA" in capsys.readouterr().err
    for command in ("fit", "gaps"):
        assert main([command, "--help"]) == 0
        text = capsys.readouterr().out
        assert "--axes {ISO-W,SAE,adapted-SAE,adapted-ISO}" in text and "--set CH=VALUE" in text


def test_readme_names_work_after_a_plain_import(tmp_path):
    """`mftyre.files.sample_tir` and `mftyre.write_tir` after `import mftyre` (failed with AttributeError)."""
    import subprocess
    import sys

    code = ("import mftyre; p = mftyre.files.sample_tir('car_205_60R15_mf61.tir'); "
            "prm = mftyre.load_tir(p).with_params(LMUY=0.9).params; "
            f"mftyre.write_tir(prm, {str(tmp_path / 'b.tir')!r}); print(mftyre.read_tir({str(tmp_path / 'b.tir')!r}).LMUY)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "0.9"


def test_plot_measured_against_models(si, tmp_path, capsys):
    """`mftyre plot` on a TTC file: the model that made the data has a small error, a changed one a larger one;
    the figure is written (PNG) and never over an existing file without --overwrite."""
    cols = _ttc_columns(si)
    lines = ["run", "\t".join(TTC_NAMES), "\t".join(TTC_UNITS)]
    lines += ["\t".join(f"{cols[n][i]:.15g}" for n in TTC_NAMES) for i in range(len(si))]
    data = tmp_path / "run.dat"
    data.write_text("\n".join(lines) + "\n")
    truth = TIR_FILES / "car_205_60R15_mf61.tir"
    changed = tmp_path / "lmuy.tir"
    mftyre.write_tir(mftyre.load_tir(truth).with_params(LMUY=0.8).params, changed)
    out = tmp_path / "plot.png"
    assert main(["plot", str(data), "--model", str(truth), str(changed), "-o", str(out)]) == 0
    assert out.read_bytes().startswith(b"\x89PNG")
    text = capsys.readouterr().out
    errors = {m: float(re.search(rf"{m}: .*FY RMS \S+ N \((\S+) %\)", text).group(1))
              for m in ("car_205_60R15_mf61.tir", "lmuy.tir")}
    assert errors["car_205_60R15_mf61.tir"] < 2.0 < errors["lmuy.tir"]
    assert "slip-angle sweeps" in text
    assert main(["plot", str(data), "-o", str(out)]) == 2
    assert "pass --overwrite" in capsys.readouterr().err


def test_eval_overlays_several_tir_files(tmp_path, capsys):
    truth = TIR_FILES / "car_205_60R15_mf61.tir"
    changed = tmp_path / "lmuy.tir"
    mftyre.write_tir(mftyre.load_tir(truth).with_params(LMUY=0.8).params, changed)
    csv, png = tmp_path / "e.csv", tmp_path / "e.png"
    assert main(["eval", str(truth), str(changed), "--fz", "3kN,5kN", "--alpha", "-12deg:12deg:9", "--csv", str(csv),
                 "--plot", str(png)]) == 0
    text = capsys.readouterr().out
    assert text.count("# ") >= 4 and f"# {changed}: FITTYP 61" in text  # one header and table per file
    table = pd.read_csv(csv)
    assert list(table["tir"].unique()) == ["car_205_60R15_mf61.tir", "lmuy.tir"]
    fz, alpha = np.meshgrid([3000.0, 5000.0], np.linspace(-12, 12, 9) * DEG, indexing="ij")
    for name, path in (("car_205_60R15_mf61.tir", truth), ("lmuy.tir", changed)):
        expected = mftyre.load_tir(path).evaluate(fz.ravel(), 0.0, alpha.ravel()).fy
        np.testing.assert_allclose(table.loc[table.tir == name, "fy [N]"], expected, rtol=1e-12)
    assert png.read_bytes().startswith(b"\x89PNG")


def test_swift_from_the_command_line(tmp_path, capsys):
    """`mftyre swift`: on a flat road with the axle held the load stays at the static one; over a 10 mm cleat it
    rises; the wheel advances at the speed given; progress on stderr."""
    tir = TIR_FILES / "car_205_60R15_mf62_swift.tir"
    csv, png = tmp_path / "s.csv", tmp_path / "s.png"
    assert main(["swift", str(tir), "--road", "cleat(x0=1.0, length=0.05, height=0.01)", "--speed", "36km/h",
                 "--fz", "4kN", "--p", "2.2bar", "--distance", "1.5", "--csv", str(csv), "--plot", str(png)]) == 0
    err = capsys.readouterr().err
    assert "building the SWIFT stepper" in err and "running 0.15 s" in err and "done" in err
    table = pd.read_csv(csv)
    np.testing.assert_allclose(table["x"], 10.0 * table["t"], atol=1e-9)
    before = table[table.x < 0.7]
    assert np.ptp(before["fz"]) < 1.0 and before["fz"].iloc[0] == pytest.approx(4000.0, rel=0.03)
    assert table["fz"].max() > 1.2 * before["fz"].iloc[0]
    assert png.read_bytes().startswith(b"\x89PNG")
    assert main(["swift", str(tir), "--speed", "10", "--csv", str(csv)]) == 2  # exists: needs --overwrite


def test_fmu_build_reports_progress(tmp_path, capsys, monkeypatch):
    """`mftyre fmu build` says what it is doing (the compilation takes seconds); the compiler is stubbed here."""
    from fmu import native_build

    def fake_compile(sources, library):
        library.parent.mkdir(parents=True, exist_ok=True)
        library.write_bytes(b"stub")

    monkeypatch.setattr(native_build, "compile_sources", fake_compile)
    out = tmp_path / "t.fmu"
    assert main(["fmu", "build", str(TIR_FILES / "car_205_60R15_mf61.tir"), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    stages = ["building the steady equations", "generating C sources", "compiling", "packing the FMU"]
    positions = [err.find(s) for s in stages]
    assert -1 not in positions and positions == sorted(positions), err


def test_cli_messages_name_options_python_messages_keywords(capsys):
    """The same saturation warning names --no-limits on the command line and limits=False from Python."""
    tir = TIR_FILES / "car_205_60R15_mf61.tir"
    assert main(["eval", str(tir), "--p", "1.5bar", "-q"]) == 0
    err = capsys.readouterr().err
    assert "mftyre eval --no-limits evaluates them as given" in err and "limits=False" not in err
    with pytest.warns(mftyre.InputClippedWarning, match=r"\(limits=False evaluates them as given\)"):
        mftyre.load_tir(tir).evaluate(4000.0, 0.0, 0.0, p=1.5e5)


def test_no_check_reads_values_outside_the_ranges(si, tmp_path):
    """An aircraft tyre above 100 m/s: refused by default, read with check=False (--no-check), and the fitter's
    own check then trusts it."""
    from mftyre.fit import load_data

    fast = si.assign(VX=si["VX"] * 7.0, OMEGA=si["OMEGA"] * 7.0)  # 117 m/s, consistent spin
    path = _csv(tmp_path, fast)
    with pytest.raises(DataError, match="channel VX: 99th percentile"):
        read_csv(path)
    data = read_data(path, check=False)
    assert load_data(data) is data and "plausibility check skipped on request" in data.history
    with pytest.raises(DataError, match="channel VX"):
        load_data(TyreData(data.frame.copy()))


def test_ttc_dat_units_with_blanks_in_a_tab_separated_row(si, tmp_path):
    """Tab-separated names and units rows: a unit such as ``deg C`` holds a blank and is one field."""
    cols = _ttc_columns(si)
    units = ["deg C" if u == "degC" else u for u in TTC_UNITS]
    lines = ["run 12 (written by this test, synthetic)", "\t".join(TTC_NAMES) + "\t", "\t".join(units) + "\t"]
    lines += ["\t".join(f"{cols[n][i]:.15g}" for n in TTC_NAMES) for i in range(len(si))]
    path = tmp_path / "B0000run15.dat"
    path.write_text("\r\n".join(lines) + "\r\n")
    data = read_data(path)
    _close(data, si, ["FZ", "SA", "IA", "VX", "P", "FY", "MZ", "RL"])
    assert data.units.get("FZ") == "N" and np.all(data.array("TSTC") == 45.0)


def test_swift_command_below_presmin_holds_the_load_it_was_asked(tmp_path, capsys):
    """A pressure below PRESMIN is saturated (and said so) for the axle height and for the SWIFT run alike: the
    static load on a flat road is the --fz asked (before, the axle was placed at 2.0 bar and the ring rolled at
    1.0 bar, carrying 40 % less)."""
    tir = TIR_FILES / "car_205_60R15_mf62_swift.tir"
    csv = tmp_path / "low.csv"
    assert main(["swift", str(tir), "--speed", "10", "--fz", "4kN", "--p", "1bar", "--distance", "0.3",
                 "--csv", str(csv), "--quiet"]) == 0
    out = capsys.readouterr()
    assert "saturated" in out.err and "p 1.86 bar" in out.out
    assert pd.read_csv(csv)["fz"].iloc[0] == pytest.approx(4000.0, rel=0.03)


def test_ttc_run_with_sr_only_read_through_the_column_map(si, tmp_path, capsys):
    """Cornering runs that record the slip ratio only as SR: the error names --columns SL=SR, and that option
    works on a TTC file (it was refused: '--columns/--units are for CSV files'); also through fit."""
    cols = {k: v for k, v in _ttc_columns(si).items() if k != "SL"} | {"SR": _to_sae(si)["SL"]}
    names = [n if n != "SL" else "SR" for n in TTC_NAMES]
    lines = ["run 16 (written by this test, synthetic)", "\t".join(names), "\t".join(TTC_UNITS)]
    lines += ["\t".join(f"{cols[n][i]:.15g}" for n in names) for i in range(len(si))]
    path = tmp_path / "B0000run16.dat"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"columns=\{'SR': 'SL'\}"):
        read_data(path)
    _close(read_data(path, columns={"SR": "SL"}), si, ["SL", "SA", "FZ", "FY"])
    assert main(["fit", str(path), "-o", str(tmp_path / "x.tir"), "--stages", "pure_fy", "--quiet"]) == 1
    assert "--columns SL=SR" in capsys.readouterr().err
    assert main(["fit", str(path), "-o", str(tmp_path / "x.tir"), "--stages", "pure_fy", "--quiet",
                 "--columns", "SL=SR"]) == 0


def test_files_that_state_their_units_are_not_told_to_use_units(si, tmp_path, capsys):
    """A TYDEX file whose MEASURCHANNELS say rad for angles written in degrees: the error named --units, which
    such files refuse; it now says where the file states its units and names --no-check."""
    frame = si.assign(SA=si["SA"] / DEG, IA=si["IA"] / DEG)
    lines = ["**HEADER", "RELEASE   Release of TYDEX-format                 1.3", "**MEASURCHANNELS"]
    names = {"FZ": "FZW", "SL": "LONGSLIP", "SA": "SLIPANGL", "IA": "INCLANGL", "VX": "LONGVEL", "P": "INFLPRES",
             "FY": "FYW"}
    units = {"FZ": "N", "SL": "-", "SA": "rad", "IA": "rad", "VX": "m/s", "P": "Pa", "FY": "N"}
    lines += [f"{names[ch]:<10}{ch:<30}{units[ch]:<10}1 0 0" for ch in names] + ["**MEASURDATA"]
    lines += [" ".join(f"{frame[ch].iloc[i]:.12g}" for ch in names) for i in range(len(frame))] + ["**END"]
    path = tmp_path / "lie.tdx"
    path.write_text("\n".join(lines) + "\n")
    assert main(["fit", str(path), "-o", str(tmp_path / "x.tir"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "channel SA (file column 'SLIPANGL')" in err and "**MEASURCHANNELS" in err and "--no-check" in err
    assert "SLIPANGL looks like deg" in err and "--units" not in err
    with pytest.raises(DataError, match="check=False"):
        read_data(path)


def test_load_in_pounds_on_the_command_line():
    """US rig sheets give loads in lbf: `mftyre eval/soil/swift --fz 1200lbf` (was: unknown unit)."""
    from mftyre.arguments import parse_sweep

    np.testing.assert_allclose(parse_sweep("fz", "1200lbf,1000lb").values, [1200 * 4.4482216152605,
                                                                            1000 * 4.4482216152605])


def test_lab_exports_semicolons_tabs_and_a_units_row(si, tmp_path, capsys):
    """Exports as labs make them: ';' with decimal commas, tabs, a units row under the names. Each is named for
    what it is (they read as 'missing channels FZ, SA ...', suggesting --columns, or 'non-numeric value N')."""
    semi = tmp_path / "semi.csv"
    si.to_csv(semi, sep=";", decimal=",", index=False)
    with pytest.raises(DataError, match=r"line 1: one column named 'FZ;SL;SA.*separated by semicolons"):
        read_data(semi)
    tabs = tmp_path / "tabs.txt"
    si.to_csv(tabs, sep="\t", index=False)
    with pytest.raises(DataError, match=r"separated by tabs"):
        read_data(tabs)
    raw = si.assign(SA=si["SA"] / DEG, P=si["P"] / 1e3)
    units = tmp_path / "units.csv"
    names = {"SA": "deg", "P": "kPa", "IA": "rad", "SL": "-", "VX": "m/s", "OMEGA": "rad/s"}
    row = [names.get(c, "N" if c.startswith("F") else "m" if c.startswith("R") else "Nm") for c in raw.columns]
    units.write_text(",".join(raw.columns) + "\n" + ",".join(row) + "\n" + raw.to_csv(index=False, header=False))
    assert main(["fit", str(units), "-o", str(tmp_path / "x.tir"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "line 2 holds units (N, -, deg, rad, m/s, kPa, N, N ...)" in err and "--units SA=deg,P=kPa" in err


def test_kpa_and_kmh_below_100_named_together(tmp_path):
    """Pressure in kPa and speed in km/h at 60 km/h (below the 100 of the range check): one error names both,
    P by its range and VX by VX / (OMEGA x radius) (VX was named only once P had been fixed)."""
    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")
    frame = trailer_programme(model, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), points=11,
                              free_rolling_speeds=(16.7,), noise=0.5, seed=4).frame
    path = _csv(tmp_path, frame.assign(P=frame["P"] / 1e3, VX=frame["VX"] * 3.6))
    with pytest.raises(DataError, match=r"channel P: .*channel VX: VX / \(OMEGA x radius\) is 3.6.*"
                                        r"units=\{'P': 'kPa', 'VX': 'km/h'\}"):
        read_data(path)
    np.testing.assert_allclose(read_data(path, units={"P": "kPa", "VX": "km/h"}).array("VX"), frame["VX"])


def test_degrees_and_sae_axes_named_in_one_error(si, tmp_path):
    """A file in degrees and in SAE axes: one error names the units and the axis system (the axes came only
    after the units had been fixed)."""
    sae = _to_sae(si)
    path = _csv(tmp_path, sae.assign(SA=sae["SA"] / DEG, IA=sae["IA"] / DEG))
    with pytest.raises(DataError, match=r"channel SA: .*units=\{'SA': 'deg', 'IA': 'deg'\}\. Also channel FZ: "
                                        r"100 % of the values are negative.*axes='SAE'"):
        read_data(path)
    _close(read_data(path, units={"SA": "deg", "IA": "deg"}, axes="SAE"), si)


def test_swift_command_refuses_what_it_cannot_run(capsys):
    """A negative axle load ran (as a tyre pulling the road), a distance of 1e9 m died with a NumPy MemoryError;
    a zero pressure in eval said 'np.float64(0.0)'."""
    tir = str(TIR_FILES / "car_205_60R15_mf62_swift.tir")
    assert main(["swift", tir, "--speed", "10", "--fz=-3kN"]) == 2
    assert "--fz: expected a value above 0, got -3000" in capsys.readouterr().err
    assert main(["swift", tir, "--speed", "10", "--distance", "1e9"]) == 2
    assert "1e+11 steps, more than the 10,000,000" in capsys.readouterr().err
    assert main(["eval", tir, "--p", "0"]) != 0
    err = capsys.readouterr().err
    assert "got minimum 0.0" in err and "np." not in err
