"""Levels of condition channels held exactly (generated data, quantised rig channels) and with scatter (issue 26).

A warm-up that holds the load exactly constant, channels rounded to the resolution a rig records (10 N, 0.01 deg,
100 Pa, 0.01 m/s, 1e-4 slip) and noisy channels must all give the levels and sweeps the run was planned with: the
short-term scatter of a channel is that of the samples that scatter, not zero because many samples sit exactly on
a plateau. Independent evidence: the programme :func:`mftyre.rig.rig_programme` was told to run.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest

import mftyre
from mftyre.data import TyreData
from mftyre.errors import InputClippedWarning
from mftyre.programme import cluster_levels, recognise
from mftyre.rig import rig_programme

from conftest import TIR_FILES

DEG = math.pi / 180.0
PLAN = dict(loads=(0.6, 1.2), pressures=(0.9, 1.1), cambers_deg=(-3.0, 0.0, 3.0), combined_alpha_deg=(4.0,), seed=4)
PLANNED = dict(FZ=2, P=2, IA=3, VX=1, slip_angle=12, slip_ratio=8, speed=4, load=2)


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")


@pytest.fixture(scope="module")
def runs(model):
    """The planned run noisy (rig_programme's defaults) and exact (no noise, no load scatter)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputClippedWarning)  # pressures beyond the file's PRESMIN..PRESMAX
        return {"noisy": rig_programme(model, **PLAN).frame.drop(columns=["TEST"]),
                "exact": rig_programme(model, noise=0.0, load_scatter=0.0, **PLAN).frame.drop(columns=["TEST"])}


def _warm_up(frame: pd.DataFrame, seconds: float = 20.0, scatter: float = 0.0, seed: int = 1) -> pd.DataFrame:
    """``frame`` after a warm-up at its first condition: every channel held exactly (the load with ``scatter``
    relative), the slip angle weaving +-4 deg at 0.2 Hz."""
    t = np.arange(0.0, seconds, 0.01)
    first = frame.iloc[0]
    warm = pd.DataFrame({c: np.full(t.size, float(first[c])) for c in frame.columns})
    warm["TIME"] = t
    warm["FZ"] = first.FZ * (1.0 + scatter * np.random.default_rng(seed).standard_normal(t.size))
    warm["SA"] = 4 * DEG * np.sin(2 * math.pi * t / 5)
    warm["SL"] = 0.0
    return pd.concat([warm, frame.assign(TIME=frame.TIME + seconds)], ignore_index=True)


def _quantised(frame: pd.DataFrame) -> pd.DataFrame:
    """The channels at the resolution a rig records them."""
    out = frame.copy()
    for ch, step in (("FZ", 10.0), ("SA", 0.01 * DEG), ("IA", 0.01 * DEG), ("P", 100.0), ("VX", 0.01), ("SL", 1e-4)):
        out[ch] = np.round(out[ch] / step) * step
    return out


def _counts(prog) -> dict:
    return {**{ch: prog.levels[ch].size for ch in ("FZ", "P", "IA", "VX")},
            **{k: prog.count(k) for k in ("slip_angle", "slip_ratio", "speed", "load")}}


@pytest.mark.parametrize("variant", ["noisy", "exact", "quantised", "quantised exact"])
@pytest.mark.parametrize("warm_up", [False, True], ids=["", "exact warm-up"])
def test_planned_levels_and_sweeps_whatever_the_resolution(runs, variant, warm_up):
    """Loads, pressures, cambers, the speed of the slip tests and the slip angles of the combined-slip sweeps
    (each slip-ratio sweep split by the held slip angle) as planned: noisy, exact, quantised (old code: the
    quantised noisy run read as 1 load, 1 pressure, 1 camber, 10 speeds, 1 slip-angle sweep)."""
    frame = runs["noisy" if variant == "quantised" else variant.split()[-1]]
    if variant.startswith("quantised"):
        frame = _quantised(frame)
    if warm_up:
        frame = _warm_up(frame)
    prog = recognise(TyreData(frame))
    assert _counts(prog) == PLANNED
    np.testing.assert_allclose(np.sort(prog.levels["IA"]) / DEG, [-3.0, 0.0, 3.0], atol=0.2)


@pytest.mark.parametrize("scatter", [0.0, 0.01])
def test_exact_warm_up_at_the_first_load_is_no_lost_level(model, scatter):
    """The run of issue 21: a 20 s warm-up at the first load held exactly (old code: '1 load', and its speed of
    the slip tests as 18 levels of noise) or with 1 % scatter reads like the run alone."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputClippedWarning)
        run = rig_programme(model, loads=(0.6, 1.2), pressures=(1.0,), cambers_deg=(0.0,), longitudinal=False,
                            seed=2).frame.drop(columns=["TEST"])
    alone, warmed = recognise(TyreData(run)), recognise(TyreData(_warm_up(run, scatter=scatter)))
    assert _counts(warmed) == _counts(alone) == dict(FZ=2, P=1, IA=1, VX=1, slip_angle=2, slip_ratio=0, speed=2,
                                                     load=1)
    np.testing.assert_allclose(warmed.levels["FZ"], alone.levels["FZ"], rtol=0.01)


def test_cluster_levels_of_exact_plateaus_beside_noisy_levels():
    """Most values exactly on one plateau, two levels with 2 % scatter beside it: three levels, each noisy
    level whole (the scatter is that of the samples that scatter; a guard, this case passed before too)."""
    rng = np.random.default_rng(3)
    x = np.concatenate([np.full(6000, 1000.0), rng.normal(2000.0, 40.0, 2000), rng.normal(3000.0, 60.0, 2000)])
    labels, centres = cluster_levels(x)
    np.testing.assert_allclose(centres, [1000.0, 2000.0, 3000.0], rtol=0.01)
    assert np.mean(labels[6000:] >= 0) > 0.99


@pytest.mark.parametrize("table, channel, column", [("mf61_camber", "IA", "gamma"), ("mf61_load", "FZ", "Fz"),
                                                    ("mf62_combined", "IA", "gamma"), ("mf61_combined", "FZ", "Fz")])
def test_exact_settings_of_tables_we_did_not_write_are_each_a_level(mfeval_dir, table, channel, column):
    """MFeval's reference tables hold their conditions exactly, in staircases (21 cambers, 7 rows each), ramps
    (51 loads, a sawtooth) or blocks: every distinct setting is a level. Neither staircase steps nor sawtooth
    resets may pass for scatter (they would merge the settings)."""
    d = pd.read_csv(mfeval_dir / f"{table}.csv")
    frame = pd.DataFrame({"FZ": d.Fz, "SA": d.alpha, "IA": d.gamma, "SL": d.kappa, "VX": d.Vx, "P": d.P})
    assert recognise(TyreData(frame)).levels[channel].size == np.unique(d[column]).size


def test_settings_stepping_every_row_are_still_levels():
    """Point data whose load steps every row between three settings (5 N scatter) keep their three levels."""
    rng = np.random.default_rng(6)
    x = np.tile([2000.0, 4000.0, 6000.0], 200) + rng.normal(0.0, 5.0, 600)
    labels, centres = cluster_levels(x)
    np.testing.assert_allclose(centres, [2000.0, 4000.0, 6000.0], rtol=0.01)
    assert np.all(labels >= 0)


def _mfeval_tables(mfeval_dir):
    """(name, table, random) of every MFeval reference table; random: no condition (load, pressure, camber) is
    ever repeated (9 rows in 10 distinct), as in MFeval's tables of random points."""
    out = []
    for path in sorted(mfeval_dir.glob("*.csv")):
        if path.stem.endswith("_parameters"):
            continue
        d = pd.read_csv(path)
        out.append((path.stem, d, all(d[c].nunique() > 0.9 * len(d) for c in ("in_Fz", "in_P", "in_gamma"))))
    return out


def _recognised(d):
    return recognise(TyreData(pd.DataFrame({"FZ": d.in_Fz, "SA": d.in_alpha, "IA": d.in_gamma, "SL": d.in_kappa,
                                            "VX": d.in_Vx, "P": d.in_P})))


def test_random_point_tables_we_did_not_write_have_no_levels_but_a_spread(mfeval_dir):
    """MFeval's tables of random points (loads, pressures, cambers drawn anew every row) read as 27-55 "levels"
    per channel (the every-row rule took the spacing of the values for the scatter of a setting) and some as
    "1 load 7732 N": they hold no level; their conditions are spread over a range, which still determines the
    load, pressure and camber terms; no load sweep is read into their jumps."""
    tables = [(name, d) for name, d, random in _mfeval_tables(mfeval_dir) if random]
    assert len(tables) >= 10
    for name, d in tables:
        prog = _recognised(d)
        assert all(prog.levels[ch].size == 0 for ch in ("FZ", "P", "IA")), (name, prog.summary())
        assert prog.spread["FZ"] == (d.in_Fz.min(), d.in_Fz.max()), name
        assert set(prog.spread) == {"FZ", "P", "IA"}, name
        assert prog.fittable["load terms"] and prog.fittable["pressure terms"] and prog.fittable["camber terms"]
        assert prog.count("load") == 0, (name, prog.summary())
        assert "loads spread over" in prog.summary()


def test_sweep_tables_we_did_not_write_keep_one_level_per_setting(mfeval_dir):
    """Every other MFeval table (sweeps, staircases, ramps of exact settings): one level per distinct setting of
    load, pressure and camber (a guard for the rule above)."""
    tables = [(name, d) for name, d, random in _mfeval_tables(mfeval_dir) if not random]
    assert len(tables) >= 15
    for name, d in tables:
        prog = _recognised(d)
        for ch, col in (("FZ", "in_Fz"), ("P", "in_P"), ("IA", "in_gamma")):
            assert prog.levels[ch].size == d[col].nunique(), (name, ch, prog.summary())


def test_unordered_values_are_settings_only_when_they_leave_empty_room():
    """Without an order to read the scatter from: one noisy level shuffled is one level (was 7: the distance to
    the third-nearest value is the spacing of the values, not their scatter), three noisy settings shuffled are
    three (their scatter is their own), values drawn uniformly over a range are no level (was 28)."""
    rng = np.random.default_rng(4)
    x = rng.permutation(np.repeat([2000.0, 4000.0, 6000.0], 200) * (1 + 0.02 * rng.standard_normal(600)))
    labels, centres = cluster_levels(x)
    np.testing.assert_allclose(centres, [2000.0, 4000.0, 6000.0], rtol=0.01)
    assert np.all(labels >= 0)
    labels, centres = cluster_levels(rng.permutation(16.7 + 0.02 * rng.standard_normal(3000)))
    assert centres.size == 1 and np.mean(labels == 0) > 0.99
    labels, centres = cluster_levels(rng.uniform(2000.0, 8000.0, 1500))
    assert centres.size == 0 and np.all(labels == -1)
