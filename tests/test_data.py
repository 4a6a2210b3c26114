"""mftyre.data: TyreData, CSV and TYDEX reading (every kind of malformed input), TYDEX round trip,
preparation helpers and the synthetic trailer programme (checked against direct model evaluation)."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import mftyre
from mftyre.data import (CHANNELS, TyreData, bin_sweeps, levels, read_csv, read_tydex, reject_outliers,
                         resample_sweeps, split_conditions, split_sweeps, trailer_programme, unit_to_si, write_tydex)
from mftyre.errors import DataError

from conftest import TIR_FILES


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")


@pytest.fixture(scope="module")
def programme(model):
    return trailer_programme(model, loads=(0.5, 1.0), pressures=(0.9, 1.1), cambers_deg=(0.0, 2.0), points=11,
                             noise=1.0, seed=3)


# ------------------------------------------------------------------------------------ programme
def test_programme_is_the_model_plus_documented_noise(model):
    clean = trailer_programme(model, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), points=11)
    out = model.evaluate(clean.array("FZ"), clean.array("SL"), clean.array("SA"), clean.array("IA"), 0.0,
                         clean.array("VX"), clean.array("P"))
    for ch in ("FX", "FY", "MX", "MY", "MZ", "RL", "RE"):
        np.testing.assert_array_equal(clean.array(ch), out[ch.lower()])
    noisy = trailer_programme(model, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), points=201, noise=1.0,
                              seed=1)
    ref = trailer_programme(model, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), points=201)
    sd = np.std(noisy.array("FY") - ref.array("FY"))
    assert sd == pytest.approx(0.005 * model.params.FNOMIN, rel=0.1)  # NOISE["FY"] x FNOMIN


def test_programme_covers_the_tests_and_conditions(programme):
    tests = set(programme["TEST"])
    assert tests == {"pure_lateral", "pure_longitudinal", "combined", "free_rolling", "vertical"}
    lat = programme.select(programme["TEST"] == "pure_lateral")
    assert np.all(lat.array("SL") == 0.0)
    assert len(split_conditions(lat, by=("FZ", "P", "IA"))) == 2 * 2 * 2


def test_offsets_and_hysteresis(model):
    base = dict(loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), points=21)
    ref = trailer_programme(model, **base)
    off = trailer_programme(model, **base, offsets={"FY": 25.0})
    np.testing.assert_allclose(off.array("FY") - ref.array("FY"), 25.0)
    hyst = trailer_programme(model, **base, hysteresis=0.02)
    lat = (hyst["TEST"] == "pure_lateral").to_numpy()
    sa, fy = hyst.array("SA")[lat], hyst.array("FY")[lat]
    # the same recorded slip angle on the way out and back gives different forces (a hysteresis loop)
    up, down = fy[:11], fy[10:][::-1]
    np.testing.assert_array_equal(sa[:11], sa[10:][::-1])
    assert np.max(np.abs(up - down)[1:-1]) > 50.0


# ---------------------------------------------------------------------------------------- units
def test_units():
    assert unit_to_si("SA", "deg") == pytest.approx(math.pi / 180)
    assert unit_to_si("FZ", "kN") == 1000.0
    assert unit_to_si("MZ", "N*m") == 1.0 and unit_to_si("MZ", "kNm") == 1000.0
    assert unit_to_si("P", "bar") == 1e5 and unit_to_si("P", "kPa") == 1e3
    assert unit_to_si("VX", "km/h") == pytest.approx(1 / 3.6)
    assert unit_to_si("SL", "%") == 0.01
    assert unit_to_si("OMEGA", "rpm") == pytest.approx(2 * math.pi / 60)
    with pytest.raises(ValueError, match="unknown unit 'furlong'"):
        unit_to_si("RL", "furlong")


# ------------------------------------------------------------------------------------------ CSV
def _write(path, text):
    path.write_text(text)
    return path


def test_csv_canonical_si_and_mapped_units(tmp_path):
    p = _write(tmp_path / "a.csv", "FZ,SA,SL,VX,P,FY\n4000,0.01,0,16.7,220000,-500\n")
    d = read_csv(p)
    assert d.array("SA")[0] == 0.01 and d.array("IA")[0] == 0.0 and "IA absent" in d.history[0]
    p = _write(tmp_path / "b.csv", "load,alpha,fy,v\n4,1.0,-0.5,60\n")
    d = read_csv(p, columns={"load": "FZ", "alpha": "SA", "fy": "FY", "v": "VX"},
                 units={"FZ": "kN", "SA": "deg", "FY": "kN", "VX": "km/h"}, defaults={"SL": 0.0, "P": 2.2e5})
    assert d.array("FZ")[0] == 4000.0 and d.array("SA")[0] == pytest.approx(math.radians(1.0))
    assert d.array("FY")[0] == -500.0 and d.array("VX")[0] == pytest.approx(60 / 3.6)


@pytest.mark.parametrize("text, kwargs, match", [
    ("FZ,SA,SL,VX\n4000,0,0,16\n", {}, r"missing channel\(s\) P"),
    ("FZ,SA,SL,VX,P\n4000,0,0,16,x2\n", {}, r"line 2: column 'P' \(P\): non-numeric value 'x2'"),
    ("FZ,SA,SL,VX,P\n4000,0,0,16,2e5\n4000,,0,16,2e5\n", {}, r"line 3: channel SA: NaN in a required channel"),
    ("FZ,SA,SL,VX,P\n4,0,0,16,2e5\n", {"units": {"FZ": "stone"}}, r"column 'FZ': unknown unit 'stone'"),
    ("FZ,SA,SL,VX,P\n4,0,0,16,2e5\n", {"columns": {"load": "FZ"}}, r"line 1: column 'load'"),
])
def test_csv_errors(tmp_path, text, kwargs, match):
    p = _write(tmp_path / "bad.csv", text)
    with pytest.raises(DataError, match=match) as info:
        read_csv(p, **kwargs)
    assert "bad.csv" in str(info.value)


# ---------------------------------------------------------------------------------------- TYDEX
def test_tydex_round_trip(programme, tmp_path):
    path = write_tydex(programme, tmp_path / "prog.tdx")
    back = read_tydex(path)
    for ch in programme.channels:
        np.testing.assert_array_equal(back.array(ch), programme.array(ch))
    np.testing.assert_array_equal(back.array("SWEEP"), programme.array("SWEEP"))
    assert back.constants["FNOMIN"] == 4000.0 and back.constants["NOMPRES"] == 220000.0
    with pytest.raises(FileExistsError):
        write_tydex(programme, path)


_TDX = """**HEADER
RELEASE   Release of TYDEX-format                 1.3
MEASID    Measurement id.                         test 1
**COMMENTS
a hand-made file in other units
**CONSTANTS
FNOMIN    Nominal vertical load         kN        4
INFLPRES  Inflation pressure            bar       2.2
**MEASURCHANNELS
! name    description                   unit      factor offsets
FZW       vertical force                kN        1
SLIPANGL  slip angle                    deg       0.1       0.5
LONGSLIP  longitudinal slip             %         1
LONGVEL   speed                         km/h      1
FYW       lateral force                 N         1
**MEASURDATA
4.0 10 0 60 -1000
4.0 20 0 60 -1500
**END
"""


def test_tydex_units_factors_offsets_and_constants(tmp_path):
    d = read_tydex(_write(tmp_path / "h.tdx", _TDX))
    np.testing.assert_allclose(d.array("SA"), np.radians([1.5, 2.5]))  # 0.1 * raw + 0.5 deg
    np.testing.assert_allclose(d.array("FZ"), 4000.0)
    np.testing.assert_allclose(d.array("P"), 2.2e5)  # from the constant
    np.testing.assert_allclose(d.array("VX"), 60 / 3.6)
    assert d.tyre == "test 1" and d.constants["FNOMIN"] == 4000.0


@pytest.mark.parametrize("old, new, match", [
    ("FYW       lateral force                 N         1", "FYW       lateral force                 Nwt       1",
     r"h.tdx:15: columns 41-50: channel FYW: unknown unit 'Nwt'"),
    ("4.0 20 0 60 -1500", "4.0 20 0 60 -15x0", r"h.tdx:18: value 5 \(channel FYW\): non-numeric value '-15x0'"),
    ("4.0 20 0 60 -1500", "4.0 20 0 60", r"h.tdx:18: 4 values, expected 5"),
    ("4.0 20 0 60 -1500", "4.0 nan 0 60 -1500", r"h.tdx:18: channel SA: NaN in a required channel"),
    ("INFLPRES  Inflation pressure            bar       2.2\n", "", r"missing channel\(s\) P"),
    ("**MEASURDATA", "**MEASURDATAX", r"h.tdx:16: unknown block"),
    ("FZW       vertical force                kN        1", "FZW       vertical force                kN        one",
     r"h.tdx:11: column 51: channel FZW: non-numeric factor"),
])
def test_tydex_errors(tmp_path, old, new, match):
    assert old in _TDX
    with pytest.raises(DataError, match=match):
        read_tydex(_write(tmp_path / "h.tdx", _TDX.replace(old, new)))


def test_tydex_missing_blocks(tmp_path):
    with pytest.raises(DataError, match="no \\*\\*MEASURDATA block"):
        read_tydex(_write(tmp_path / "h.tdx", _TDX.split("**MEASURDATA")[0]))


# ---------------------------------------------------------------------------------- preparation
def test_levels_and_sweeps(programme):
    labels, centres = levels([1.0, 1.01, 2.0, 2.02, 3.0], tol=0.1)
    assert labels.tolist() == [0, 0, 1, 1, 2] and centres == pytest.approx([1.005, 2.01, 3.0])
    renumbered = split_sweeps(programme.select(programme["TEST"] != "free_rolling"))
    kept = programme.select(programme["TEST"] != "free_rolling")
    # every sweep of the programme is one sweep, whatever the swept channel
    pairs = pd.crosstab(renumbered["SWEEP"], kept["SWEEP"].to_numpy())
    assert ((pairs > 0).sum(axis=1) == 1).all()


def test_binning_and_resampling(programme):
    lat = programme.select(programme["TEST"] == "pure_lateral")
    binned = bin_sweeps(lat, "SA", width=math.radians(2.4))
    assert len(binned) < len(lat) and "binned SA" in binned.history[-1]
    grid = np.radians([-5.0, 0.0, 5.0])
    res = resample_sweeps(binned, "SA", grid)
    assert len(res) == 3 * lat["SWEEP"].nunique()


def test_outliers_are_found_and_reported(model):
    data = trailer_programme(model, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), points=41, noise=1.0,
                             seed=5)
    clean, rejected = reject_outliers(data)
    assert len(rejected) == 0 and len(clean) == len(data)
    frame = data.frame.copy()
    lat = np.flatnonzero((frame["TEST"] == "pure_lateral").to_numpy())
    frame.loc[lat[30], "FY"] += 600.0
    frame.loc[lat[8], "FY"] -= 600.0
    clean, rejected = reject_outliers(data.with_frame(frame, "two outliers added"))
    assert sorted(rejected.index.tolist()) == sorted([lat[8], lat[30]])
    assert set(rejected["REJECTED_CHANNEL"]) == {"FY"} and "2 of" in clean.history[-1]


def test_tyredata_validation():
    frame = pd.DataFrame(dict(FZ=[1.0], SA=[0.0], SL=[np.nan], VX=[1.0], P=[2e5]))
    with pytest.raises(DataError, match="row 0: channel SL: NaN in a required channel"):
        TyreData(frame)
    with pytest.raises(DataError, match="missing channel"):
        TyreData(frame.drop(columns="P"))
    assert set(CHANNELS) >= {"FX", "FY", "FZ", "MX", "MY", "MZ", "SL", "SA", "IA", "PHIT", "VX", "P", "OMEGA",
                             "RL", "RHO", "RE"}


def test_synthetic_programmes_record_alike(model):
    """The trailer and the rig generator share one home for what they record (mftyre.data.synthetic_data): the
    model's outputs in the output channels, SI units, the .tir's constants and the test speed."""
    from mftyre.data import OUTPUTS
    from mftyre.rig import rig_programme

    prm = model.params
    trailer = trailer_programme(model, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), speed=15.0)
    rig = rig_programme(model, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), speed=15.0, noise=0.0,
                        load_scatter=0.0, friction_drift=0.0, relaxation=False)
    expected = {"FNOMIN": prm.FNOMIN, "NOMPRES": prm.NOMPRES, "RFREE": prm.UNLOADED_RADIUS, "NOMWIDTH": prm.WIDTH,
                "LONGVEL": 15.0}
    for data in (trailer, rig):
        assert data.constants == expected and data.units == trailer.units and data.units["MZ"] == "N*m"
        f = data.frame
        ref = model.evaluate(f["FZ"].to_numpy(), f["SL"].to_numpy(), f["SA"].to_numpy(), f["IA"].to_numpy(), 0.0,
                             f["VX"].to_numpy(), f["P"].to_numpy())
        for ch in OUTPUTS:
            np.testing.assert_allclose(f[ch], ref[ch.lower()], rtol=1e-12, atol=1e-9, err_msg=ch)
    assert (trailer.source, rig.source) == ("trailer_programme", "rig_programme")
