"""Test-programme recognition, time-series reduction and the realistic rig generator (issue 11).

Independent evidence: the levels and sweeps the generator was told to run, the relaxation-length hysteresis
vanishing when relaxation is switched off, the AR(1) rule for the effective sample size, the noise-free model.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import mftyre
from mftyre.data import levels, trailer_programme
from mftyre.programme import cluster_levels, recognise
from mftyre.rig import rig_programme
from mftyre.timeseries import effective_samples, lag_one_correlation, needs_reduction, reduce_sweeps

from conftest import TIR_FILES


@pytest.fixture(scope="module")
def truth():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")


@pytest.fixture(scope="module")
def rig(truth):
    return rig_programme(truth, loads=(0.5, 1.0, 1.5), pressures=(1.0,), seed=3)


# ----------------------------------------------------------------------------------------------- levels
def test_close_levels_with_scatter_are_separate_levels():
    """1650 / 2200 / 2750 N with 4 % scatter: the old rule (tolerance 5 % of the largest value) chained them."""
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(c, 0.04 * c, 3000) for c in (1650.0, 2200.0, 2750.0)])
    rng.shuffle(x)
    assert len(levels(x)[1]) == 1  # the old rule: one level
    labels, centres = cluster_levels(x, scatter=0.04 * 1650)
    np.testing.assert_allclose(centres, [1650, 2200, 2750], rtol=0.01)
    assert np.mean(labels >= 0) > 0.99


def test_five_loads_in_time_order_with_ramps_between():
    rng = np.random.default_rng(1)
    parts = []
    targets = [450.0, 1100.0, 1650.0, 2200.0, 2750.0]
    for a, b in zip(targets, targets[1:] + [targets[0]]):
        parts += [a * (1 + 0.02 * rng.normal(size=800)), np.linspace(a, b, 60)]  # hold, then a ramp
    x = np.concatenate(parts)
    assert len(levels(x)[1]) == 1  # the old rule: the ramps chain everything into one level
    labels, centres = cluster_levels(x)
    np.testing.assert_allclose(centres, targets, rtol=0.01)
    ramp = np.concatenate([np.zeros(800, bool), np.ones(60, bool)] * 5)
    assert np.mean(labels[ramp] == -1) > 0.4  # most ramp samples belong to no level


def test_few_points_repeated_settings():
    labels, centres = cluster_levels([10000, 10020, 20000, 20030, 30000, 30010, 40000, 39990.0])
    np.testing.assert_allclose(centres, [10010, 20015, 30005, 39995])
    assert list(labels) == [0, 0, 1, 1, 2, 2, 3, 3]
    assert len(cluster_levels([1.0, 2.0, 3.0, 4.0])[1]) == 4  # evenly spaced: all levels


# ------------------------------------------------------------------------------------------- generator
def test_rig_programme_is_a_realistic_time_series(truth, rig):
    f = rig.frame
    assert np.allclose(np.diff(f["TIME"]), 0.01)  # 100 Hz
    again = rig_programme(truth, loads=(0.5, 1.0, 1.5), pressures=(1.0,), seed=3)
    assert again.frame.equals(f)  # deterministic
    # levels are not round numbers
    lat = f[f["TEST"] == "pure_lateral"]
    assert all(abs(c / 4000.0 - r) > 0.002 for c, r in zip(cluster_levels(lat["FZ"].to_numpy())[1], (0.5, 1, 1.5)))
    # noise is autocorrelated (AR(1), 30 ms at 100 Hz: r1 = exp(-1/3) = 0.72) and about realistic in size:
    # free-rolling samples at a held speed carry the noise of FY
    quiet = rig_programme(truth, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), longitudinal=False, noise=0.0,
                          load_scatter=0.0, friction_drift=0.0, seed=3)
    noisy = rig_programme(truth, loads=(1.0,), pressures=(1.0,), cambers_deg=(0.0,), longitudinal=False,
                          load_scatter=0.0, friction_drift=0.0, seed=3)
    e = (noisy.frame["FY"] - quiet.frame["FY"]).to_numpy()
    assert lag_one_correlation(e) == pytest.approx(math.exp(-1 / 3), abs=0.1)
    assert np.std(e) > 0.5 * 0.005 * 4000  # at least half the realistic level (0.5 % of FNOMIN)
    assert {"vertical", "free_rolling", "pure_lateral", "pure_longitudinal", "combined"} <= set(f["TEST"])
    assert f["VX"].max() > 39.0 and f[f["TEST"] == "free_rolling"]["VX"].min() < 1.5
    with pytest.raises(ValueError, match="sample_rate must be a positive number"):
        rig_programme(truth, sample_rate=0.0)


# ----------------------------------------------------------------------------------------- programme
def test_recognise_finds_the_programme_it_was_told(rig):
    prog = recognise(rig)
    assert prog.levels["FZ"].size == 3 and prog.levels["P"].size == 1 and prog.levels["IA"].size == 3
    assert prog.count("slip_angle") == 3 * 3  # loads x cambers
    assert prog.count("slip_ratio") == 3 * 3  # loads x (pure + two combined angles)
    assert prog.count("speed") == 3 and prog.count("load") == 1  # a speed sweep per load, a load sweep per pressure
    assert prog.sample_rate == pytest.approx(100.0)
    text = prog.summary()
    assert "3 loads" in text and "3 cambers" in text and "1 pressure" in text and "9 slip-angle sweeps" in text
    assert "not fittable: pressure terms" in text
    # sweeps keep their direction: each slip-angle sweep goes up, down and up again
    sa = prog.sweeps[prog.sweeps["kind"] == "slip_angle"]
    assert (sa["reversals"] == 2).all() and (sa["up"] > 0).all() and (sa["down"] > 0).all()
    # recognised kinds agree with the generator's tests on nearly every row
    rows = prog.rows
    test = rig.frame["TEST"].to_numpy()
    for kind, t in (("slip_angle", "pure_lateral"), ("speed", "free_rolling")):
        assert np.mean(rows["KIND"].to_numpy()[test == t] == kind) > 0.95


def test_messages_are_true_of_the_data(truth):
    data = rig_programme(truth, loads=(0.6, 1.2), pressures=(1.0,), longitudinal=False, seed=4)
    spikes = data.frame["SL"].to_numpy().copy()
    spikes[::5000] = 0.05  # a few noise spikes in the slip channel are no longitudinal-slip test
    data.frame["SL"] = spikes
    prog = recognise(data)
    text = prog.summary()
    assert "no slip-ratio sweeps" in text and not prog.fittable["pure Fx"]
    # SL is not zero throughout: "no longitudinal slip" would be untrue; the spikes are named instead
    assert "no longitudinal slip" not in text and "longitudinal slip in isolated samples only" in text
    assert "no longitudinal slip" in recognise(rig_programme(truth, loads=(0.6, 1.2), pressures=(1.0,),
                                                             longitudinal=False, seed=4)).summary()
    assert prog.fittable["camber terms"] and prog.fittable["load terms"]
    assert "2 loads" in text and "3 cambers" in text and "1 vertical load sweeps" in text
    assert "6 slip-angle sweeps" in text and "2 speed sweeps" in text


def _counts(prog):
    return (prog.levels["FZ"].size, prog.levels["P"].size, prog.levels["IA"].size, prog.count("slip_angle"),
            prog.count("slip_ratio"), prog.count("speed"), prog.count("load"))


@pytest.mark.parametrize("options, counts", [
    # one camber level: the slip-ratio sweeps at the three slip angles were split in two (15-18 instead of 9)
    (dict(cambers_deg=(0.0,), pressures=(1.0,)), (3, 1, 1, 3, 9, 3, 1)),
    # lateral sweeps only: a fourth load from the ramps, 11 load sweeps instead of one per pressure
    (dict(longitudinal=False), (3, 3, 3, 27, 0, 9, 3)),
    # longitudinal tests on, three cambers: the free-rolling speed sweeps are one per load and pressure
    (dict(), (3, 3, 3, 27, 27, 9, 3)),
    (dict(speed=25.0, pressures=(1.0,)), (3, 1, 3, 9, 9, 3, 1)),
    (dict(sample_rate=200.0, pressures=(1.0,)), (3, 1, 3, 9, 9, 3, 1)),
])
def test_recognised_counts_match_the_rig_programme(truth, options, counts):
    """(loads, pressures, cambers, slip-angle, slip-ratio, speed, load sweeps) exactly as the rig ran them."""
    data = rig_programme(truth, **{"loads": (0.5, 1.0, 1.5), "seed": 0, **options})
    assert _counts(recognise(data)) == counts


def test_point_data_are_recognised_too(truth):
    data = trailer_programme(truth, points=15, noise=1.0, seed=7)
    prog = recognise(data)
    assert prog.levels["FZ"].size == 3 and prog.levels["P"].size == 3 and prog.levels["IA"].size == 3
    assert prog.count("slip_angle") == 27 and prog.count("slip_ratio") == 27
    assert not needs_reduction(data, prog)


# ---------------------------------------------------------------------------------------- reduction
def test_reduction_keeps_branches_and_measures_the_relaxation_hysteresis(truth, rig):
    red = reduce_sweeps(rig)
    assert needs_reduction(rig) and len(red.mean) < len(rig) / 10
    h = red.hysteresis
    lag = h[(h.kind == "slip_angle") & (h.channel == "FY")]["amplitude"].median()
    still = rig_programme(truth, loads=(0.5, 1.0, 1.5), pressures=(1.0,), seed=3, relaxation=False)
    h0 = reduce_sweeps(still).hysteresis
    no_lag = h0[(h0.kind == "slip_angle") & (h0.channel == "FY")]["amplitude"].median()
    assert lag > 1.8 * no_lag  # the relaxation length is the largest structure up vs down
    # the up/down mean cancels the lag: close to the steady-state model at the bin means (no friction drift and
    # load scatter here: they are not what the branches differ by)
    plain = rig_programme(truth, loads=(0.5, 1.0, 1.5), pressures=(1.0,), seed=3, friction_drift=0.0,
                          load_scatter=0.0)
    red = reduce_sweeps(plain)
    m = red.mean.frame
    sel = (m["KIND"] == "slip_angle").to_numpy()
    sub = red.mean.select(sel)
    model = truth.evaluate(**sub.inputs())
    dev_mean = np.sqrt(np.mean((model.fy - sub.array("FY")) ** 2))
    b = red.branches.select((red.branches.frame["KIND"] == "slip_angle").to_numpy())
    dev_branch = np.sqrt(np.mean((truth.evaluate(**b.inputs()).fy - b.array("FY")) ** 2))
    assert dev_mean < 0.7 * dev_branch
    assert "hysteresis" in red.summary() and "FY" in red.summary()


def test_relaxed_slip_is_the_first_order_lag_of_a_ramp():
    """d(x_t)/ds = (x - x_t) / sigma for a ramp x = r s from x_t = 0: x_t = r (s - sigma (1 - exp(-s / sigma)))
    (analytic); the recursion holds the slip over each step, so it lags by half a step more. Constant and
    per-sample steps and lengths give the same."""
    from mftyre.timeseries import relaxed_slip

    ds, sigma, r = 0.01, 0.7, 0.05
    s = np.arange(600) * ds
    exact = r * (s - sigma * (1.0 - np.exp(-s / sigma)))
    got = relaxed_slip(r * s, ds, sigma)
    np.testing.assert_allclose(got, exact, atol=r * ds)
    np.testing.assert_allclose(relaxed_slip(r * s, np.full(s.size, ds), np.full(s.size, sigma)), got, rtol=1e-12)
    np.testing.assert_array_equal(relaxed_slip(r * s, ds, 0.0), r * s)


@pytest.mark.parametrize("name, longitudinal", [("agri_460_85R34_mf61", False), ("agri_420_85R24_mf61", True)])
def test_reduction_undoes_the_relaxation_lag_of_a_large_tyre(name, longitudinal):
    """A tractor tyre at 3 m/s with 2-4 m relaxation length, slip swept at 6 deg/s (0.1 /s): the force lags the
    recorded slip by 6-8 deg (0.05). The up/down mean of the recorded slip is far from the steady-state curve
    (the fit then chased the lag: mz 60-370 %); the relaxation length that collapses each sweep onto one curve is
    the model's sigma (outputs sigmay, sigmax at the sweep's load), and the means over the relaxed slips (the
    swept one and the held one) lie on the tyre's steady-state curve."""
    from mftyre.fit import normalised_rms
    from mftyre.timeseries import both_ways

    tyre = mftyre.load_tir(TIR_FILES / f"{name}.tir")
    run = rig_programme(tyre, loads=(0.6, 1.2), pressures=(1.0,), cambers_deg=(0.0,), longitudinal=longitudinal,
                        seed=1)
    red = reduce_sweeps(run)
    rows = red.programme.rows
    assert len(red.relaxation) == red.programme.count("slip_angle") + red.programme.count("slip_ratio")
    for _, row in red.relaxation.iterrows():
        sel = (rows["SWEEP"] == row["sweep"]).to_numpy()
        model = tyre.evaluate(float(np.mean(run.array("FZ")[sel])), 0.0, 0.0, 0.0, 0.0, tyre.params.LONGVL)
        sigma = float(model.sigmay if row["kind"] == "slip_angle" else model.sigmax)
        assert row["length"] == pytest.approx(sigma, rel=0.1), row
    assert "relaxation length" in red.summary()
    # (the slip-ratio sweeps at 3 and 6 deg start while the slip angle still relaxes from the ramp before them)
    for kind, channels in (("slip_angle", ("FY", "MZ")), ("slip_ratio", ("FX", "FY", "MZ")))[:1 + longitudinal]:
        mean = red.mean.select((red.mean.frame["KIND"] == kind).to_numpy())
        steady = tyre.evaluate(**mean.inputs())
        for ch in channels:
            assert normalised_rms(mean.array(ch), steady[ch.lower()]) < 3.0, (kind, ch)
    # what the fit was given before: the up/down mean of the recorded slip, far off (Fy 20-45 %)
    branches = red.branches.frame
    recorded = [both_ways(g) for _, g in branches[branches["KIND"] == "slip_angle"].groupby("SWEEP")]
    fy = np.concatenate([0.5 * (u["FY"].to_numpy() + d["FY"].to_numpy()) for u, d in recorded])
    inputs = {k: np.concatenate([0.5 * (u[c].to_numpy() + d[c].to_numpy()) for u, d in recorded])
              for k, c in (("fz", "FZ"), ("alpha", "SA"), ("vx", "VX"), ("p", "P"))}
    assert normalised_rms(fy, tyre.evaluate(kappa=0.0, **inputs).fy) > 15.0


def test_effective_samples_follow_the_ar1_rule():
    rng = np.random.default_rng(2)
    from scipy.signal import lfilter

    white = rng.normal(size=20000)
    assert effective_samples(white) == pytest.approx(20000, rel=0.05)
    ar = lfilter([1.0], [1.0, -0.8], white)
    assert effective_samples(ar) == pytest.approx(20000 * 0.2 / 1.8, rel=0.15)
    groups = np.repeat(np.arange(20), 1000)
    assert effective_samples(ar, groups) == pytest.approx(20000 * 0.2 / 1.8, rel=0.15)


def test_both_ways_pairs_the_bins_measured_up_and_down():
    """One home for pairing a sweep's branches (hysteresis and the gap finder's relaxation check): the bins both
    branches have, in the same order, whatever order the rows come in."""
    import pandas as pd

    from mftyre.timeseries import both_ways, hysteresis

    sweep = pd.DataFrame({"SWEEP": 0, "KIND": "slip_angle", "BRANCH": [1, 1, 1, 1, -1, -1, -1, -1],
                          "BIN": [0, 1, 2, 3, 4, 3, 2, 1], "FY": [0.0, 10.0, 20.0, 30.0, 45.0, 36.0, 26.0, 16.0]})
    up, down = both_ways(sweep)
    assert list(up.index) == list(down.index) == [1, 2, 3]
    assert list(up["FY"]) == [10.0, 20.0, 30.0] and list(down["FY"]) == [16.0, 26.0, 36.0]
    row = hysteresis(sweep).iloc[0]
    assert row["bins"] == 3 and row["amplitude"] == pytest.approx(3.0) and row["peak"] == pytest.approx(3.0)
