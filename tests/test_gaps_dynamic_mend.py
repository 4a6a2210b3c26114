"""Issue 33: the dynamic gap finder mended: what is written is what was scored, any sample rate from 200 Hz up, the
one reader and the one writer, held-out runs stratified by the steady finder's rule, the measurement chain's gain
and drift as nuisances, identifiability before precision.

The reader tests write small CSV files by hand (no simulation); the finder tests use two short runs at two
pressures of the sample SWIFT file, which (like the TNO file) has no SWIFT_PSTIFF / SWIFT_PDAMP.
"""
from __future__ import annotations

import math
import os
import warnings

import numpy as np
import pandas as pd
import pytest

import mftyre
from mftyre.errors import DataError
from mftyre.files import OutputError
from mftyre.gaps.dynamic import find_dynamic_gaps
from mftyre.gaps.dynamic_runs import read_runs, synthetic_runs, write_runs

from conftest import SWIFT_SAMPLE as SAMPLE


# ------------------------------------------------------------------------------ item 1: written = scored
def test_the_written_file_is_the_tyre_that_was_scored(sample, dynamic_control, tmp_path):
    """On the control of tests/conftest.py (two pressures away from NOMPRES, where SWIFT_PSTIFF matters)."""
    runs, rep = dynamic_control
    assert "SWIFT_PSTIFF" in sample.params.missing and "SWIFT_PDAMP" in sample.params.missing
    path = rep.write_tir(tmp_path / "improved.tir")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        written = mftyre.load_tir(path)
    # absent parameters stay absent (written as 0.0 they switched the sidewall's pressure dependence off)
    assert {"SWIFT_PSTIFF", "SWIFT_PDAMP"} <= set(written.params.missing)
    assert "SWIFT_PSTIFF" not in path.read_text()
    # re-evaluated on the data, the written file gives the reported error
    again = rep.evaluate(written)
    for c, e in rep.error_after.items():
        assert again[c] == pytest.approx(e, rel=1e-9), c


# ------------------------------------------------------------------------------ item 2: any rate from 200 Hz
@pytest.mark.parametrize("rate, cutoff", [(500.0, 120.0), (800.0, 200.0)])
def test_runs_sampled_at_800_hz_or_less_are_read_and_searched(sample, rate, cutoff):
    runs = synthetic_runs(sample, speeds=(30.0,), steer_speeds=(), dt=1.0 / rate, cutoff=cutoff, seed=4,
                          duration=0.35, lead=0.12)
    rep = find_dynamic_gaps(runs, sample, max_effects=0)
    assert rep.chain.cutoff is None or rep.chain.cutoff < 0.5 * rate
    assert rep.chain.delay == pytest.approx(5e-3, abs=1.5 / rate + 1e-3)


def test_a_rate_below_200_hz_is_refused_by_name(tmp_path):
    path = _write(tmp_path / "slow.csv", _frame(dt=0.01))
    with pytest.raises(DataError, match="100 Hz.*at least 200 Hz"):
        read_runs(path)


# ------------------------------------------------------------------------------ item 6: the one reader/writer
def _frame(n=60, dt=1e-3, run="r1"):
    t = dt * np.arange(n)
    return pd.DataFrame(dict(RUN=run, TIME=t, VX=10.0, X=10.0 * t, Z=0.29, OMEGA=33.0, P=2.2e5,
                             ROAD="cleat(x0=0.3, length=0.02, height=0.01)", FX=np.sin(t), FZ=4000.0 + t))


def _write(path, frame):
    frame.to_csv(path, index=False)
    return path


def test_time_histories_read_by_the_one_reader(tmp_path):
    good = pd.concat([_frame(run="a"), _frame(run="b")], ignore_index=True)
    runs = read_runs(_write(tmp_path / "good.csv", good))
    assert [r.name for r in runs] == ["a", "b"] and runs[0].kind == "cleat"
    # a row with one field more would shift the channels: refused, naming the line
    text = (tmp_path / "good.csv").read_text().splitlines()
    text[5] += ",7"
    (tmp_path / "shift.csv").write_text("\n".join(text) + "\n")
    with pytest.raises(DataError, match="line 6: 11 fields, but the header has 10"):
        read_runs(tmp_path / "shift.csv")
    bad = good.copy()
    bad.loc[7, "RUN"] = ""
    with pytest.raises(DataError, match="line 9: column RUN is empty"):
        read_runs(_write(tmp_path / "run.csv", bad))
    bad = good.astype({"FX": object})
    bad.loc[4, "FX"] = "12,5"
    with pytest.raises(DataError, match="line 6.*FX.*non-numeric"):
        read_runs(_write(tmp_path / "text.csv", bad))
    bad = good.rename(columns={"FZ": "fx"})
    with pytest.raises(DataError, match="appears twice"):
        read_runs(_write(tmp_path / "dup.csv", bad))
    bad = good.drop(columns="Z").assign(LOAD=4000.0)
    bad.loc[3, "LOAD"] = math.inf
    with pytest.raises(DataError, match="line 5.*LOAD.*infinite"):
        read_runs(_write(tmp_path / "inf.csv", bad))
    bad.loc[3, "LOAD"] = -4000.0
    with pytest.raises(DataError, match="line 5.*LOAD.*positive"):
        read_runs(_write(tmp_path / "neg.csv", bad))
    bad = good.copy()
    bad.loc[10, "TIME"] = 0.0105
    with pytest.raises(DataError, match="equal steps"):
        read_runs(_write(tmp_path / "step.csv", bad))


def test_fifo_and_device_are_refused(tmp_path):
    fifo = tmp_path / "runs.csv"
    os.mkfifo(fifo)
    with pytest.raises(DataError, match="not a regular file|regular"):
        read_runs(fifo)
    with pytest.raises(DataError):
        read_runs("/dev/zero")


def test_columns_units_and_axes(tmp_path):
    good = _frame()
    ref = read_runs(_write(tmp_path / "si.csv", good))[0]
    rig = good.rename(columns={"VX": "speed", "FZ": "Fz_kN"}).assign(speed=good.VX * 3.6, Fz_kN=-good.FZ / 1e3,
                                                                      TIME=good.TIME * 1e3)
    run = read_runs(_write(tmp_path / "rig.csv", rig), columns={"speed": "VX", "Fz_kN": "FZ"},
                    units={"VX": "km/h", "FZ": "kN", "TIME": "ms"}, axes="SAE")[0]
    np.testing.assert_allclose(run.inputs["VX"], ref.inputs["VX"], rtol=1e-12)
    np.testing.assert_allclose(run.measured["FZ"], ref.measured["FZ"], rtol=1e-12)
    np.testing.assert_allclose(run.t, ref.t, rtol=1e-12, atol=1e-15)
    with pytest.raises(DataError, match="negative.*SAE"):  # the load's sign: the plausibility check names the axes
        read_runs(_write(tmp_path / "sae.csv", good.assign(FZ=-good.FZ)))


def test_cli_reads_runs_with_the_data_options(short_runs, tmp_path, capsys):
    from mftyre.cli import main

    frame = pd.read_csv(write_runs(short_runs[:1], tmp_path / "runs.csv"))  # the cleat run
    frame.assign(VX=frame.VX * 3.6).rename(columns={"VX": "speed_kmh"}).to_csv(tmp_path / "rig.csv", index=False)
    args = ["gaps", "--dynamic", str(tmp_path / "rig.csv"), "--model", str(SAMPLE), "--max-effects", "0", "--quiet"]
    assert main(args) == 1
    assert "missing channel(s) VX" in capsys.readouterr().err
    assert main(args + ["--columns", "VX=speed_kmh", "--units", "VX=km/h"]) == 0
    assert "nothing added" in capsys.readouterr().out


def test_report_never_written_through_a_planted_link(dynamic_control, tmp_path):
    _, rep = dynamic_control
    folder = tmp_path / "rep"
    folder.mkdir()
    target = tmp_path / "elsewhere.png"
    target.write_bytes(b"keep")
    (folder / "histories.png").symlink_to(target)
    with pytest.raises(OutputError, match="symbolic link"):
        rep.save(folder, overwrite=True)
    assert target.read_bytes() == b"keep"


# ------------------------------------------------------------------------------ item 5: stratified hold-out
def test_held_out_runs_cover_every_load_and_pressure():
    """12 cleat runs (3 speeds x 2 pressures x 2 loads) and 4 step steers, a quarter held out: every pressure, load
    and manoeuvre is held out somewhere and stays in the training runs (the old rule, every 4th run ordered by
    speed, pressure, load, held out three runs at one pressure and one load)."""
    from mftyre.gaps.dynamic import _holdout
    from mftyre.gaps.dynamic_runs import DynamicRun

    t = 1e-3 * np.arange(50)
    runs = []
    for v in (10.0, 40.0, 70.0):
        for p in (1.8e5, 2.6e5):
            for load in (3000.0, 5000.0):
                runs.append(DynamicRun(f"c{v}_{p}_{load}", t, dict(VX=np.full(50, v / 3.6), LOAD=np.full(50, load),
                                                                    OMEGA=np.full(50, 30.0), P=np.full(50, p)),
                                       "cleat(x0=1, length=0.02, height=0.01)", {"FX": np.zeros(50)}))
    for v in (20.0, 40.0, 60.0, 80.0):
        runs.append(DynamicRun(f"s{v}", t, dict(VX=np.full(50, v / 3.6), LOAD=np.full(50, 4000.0),
                                                OMEGA=np.full(50, 30.0), PSI=np.r_[np.zeros(25), np.full(25, 0.03)],
                                                P=np.full(50, 2.2e5)), "", {"FY": np.zeros(50)}))
    for seed in range(4):
        held = _holdout(runs, 0.25, seed)
        cond = {r.name: (r.kind, r.condition["pressure"], r.condition["load"]) for r in runs}
        out = [cond[n] for n in held]
        kept = [cond[r.name] for r in runs if r.name not in held]
        assert {k for k, _, _ in out} == {"cleat", "steer"}
        assert {p for k, p, _ in out if k == "cleat"} == {1.8, 2.6}
        assert {f for k, _, f in out if k == "cleat"} == {3000.0, 5000.0}
        assert {(p, f) for k, p, f in kept if k == "cleat"} == {(1.8, 3000.0), (1.8, 5000.0), (2.6, 3000.0),
                                                                (2.6, 5000.0)}


# ------------------------------------------------------------------------------ item 3: the chain's nuisances
def test_alignment_recovers_gain_drift_filter_order_and_delay(sample):
    """A rig chain the old alignment could not express: a 2nd-order filter at 110 Hz, 9 ms, FZ gain 1.018 and a
    drift of -150 N/s, FX gain 0.985; AR(1) sensor noise. The calibration comes back, and the given (true) model
    then sits at the noise floor (the old chain, delay and 4th-order filter only, left the gain's 70 N)."""
    from mftyre.gaps.dynamic import align, noise_from_data
    from mftyre.gaps.dynamic_runs import simulate

    gain, drift = {"FZ": 1.018, "FX": 0.985}, {"FZ": -150.0, "FX": 20.0}
    runs = synthetic_runs(sample, speeds=(20.0, 50.0), steer_speeds=(), cutoff=110.0, order=2, delay=9e-3,
                          gain=gain, drift=drift, ar=0.5, seed=6, duration=0.5, lead=0.2)
    pred = simulate(sample, runs)
    chain, _ = align(runs, pred)
    assert chain.order == 2 and chain.delay == pytest.approx(9e-3, abs=1e-3)
    # FZ's gain shows in the static load (4 kN): tight; FX's only in the cleat response (a few hundred N) beside
    # the noise: within 2 %
    assert chain.gain["FZ"] == pytest.approx(gain["FZ"], abs=0.003)
    assert chain.drift["FZ"] == pytest.approx(drift["FZ"], abs=60.0)
    assert chain.gain["FX"] == pytest.approx(gain["FX"], abs=0.02)
    noise = noise_from_data(runs, pred, chain)
    for c in gain:
        rms = math.sqrt(np.mean(np.concatenate([(chain(pred[r.name][c], r, c) - r.measured[c]) ** 2 for r in runs])))
        assert rms < 1.2 * noise[c]["sigma"]


def _in_plane_case(change, speeds=(40.0,)):
    """Cleat runs of the TNO file (each of ``speeds`` [km/h] at two pressures and two loads, 0.8 s) from a truth
    with ``change`` (factors of the file's values), through the generator's default chain (a 4th-order filter at
    150 Hz, 5 ms)."""
    from conftest import PROJECT, require_shared

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(require_shared(PROJECT.parent / "shared" / "reference" / "tir" /
                                               "TNO_car205_60R15.tir"))
    truth = model.with_params(**{k: f * model.params[k] for k, f in change.items()})
    runs = synthetic_runs(model, truth=truth, speeds=speeds, pressures=(1.8e5, 2.6e5), loads=(3000.0, 5000.0),
                          steer_speeds=(), duration=0.8, lead=0.3, seed=11)
    return model, truth, runs


def _rivals(*names):
    from mftyre.gaps.dynamic_catalogue import DYNAMIC_CATALOGUE

    return tuple(e for e in DYNAMIC_CATALOGUE if set(names) & set(e.parameters))


def test_the_alignment_weighs_each_channel_by_its_noise_and_the_damping_comes_back():
    """Twice the in-plane damping, the given file's own as the start: the alignment chose its filter by sums of
    squares weighted by each channel's variance, and against a model lacking damping that took a 2nd-order filter
    at 200 Hz for the rig's 4th order at 150 Hz. The damping refitted through that chain stopped at 0.088 for a
    truth of 0.098, and a second effect, SWIFT_PDAMP, took the rest. Weighted by the noise, as the chi-square is,
    the chain is the rig's and DAMP_LONG the truth's. (At one speed the data hardly separate the filter from the
    damping: two speeds.)"""
    from mftyre.gaps.dynamic import _aligned, _chi2, _Problem, align, noise_from_data
    from mftyre.gaps.dynamic_runs import simulate

    model, truth, runs = _in_plane_case({"DAMP_LONG": 2.0}, speeds=(10.0, 70.0))
    # against the given model the chosen cell is the one of least chi-square, as the refits weigh it
    pred = simulate(model, runs)
    chain, _ = align(runs, pred)
    noise = noise_from_data(runs, pred, chain)
    chi2 = {(c.order, c.cutoff): _chi2(_Problem(runs, c.calibrated(runs, pred), noise).residuals(pred))
            for _, c in _aligned(runs, pred)}
    assert chi2[chain.order, chain.cutoff] <= 1.001 * min(chi2.values())
    rep = find_dynamic_gaps(runs, model, catalogue=_rivals("DAMP_LONG", "SWIFT_PDAMP", "FREQ_LONG",
                                                           "DAMP_RESIDUAL"), refit_top=2)
    assert [c.parameters for c in rep.effects_added] == [("DAMP_LONG",)], rep.effect_names
    assert rep.chain.order == 4 and rep.chain.cutoff == pytest.approx(150.0, rel=0.05)
    assert rep.model.params.DAMP_LONG == pytest.approx(truth.params.DAMP_LONG, rel=0.03)


def test_an_effect_added_first_is_taken_out_when_a_later_one_explains_it():
    """A softer in-plane sidewall (FREQ_LONG x 0.88) among rivals that also shift the in-plane response: the
    residual damping wins the first round, FREQ_LONG the second; with FREQ_LONG in, the damping explains nothing
    and is taken out (the steady finder's backward check), leaving the truth alone at its value."""
    model, truth, runs = _in_plane_case({"FREQ_LONG": 0.88})
    rep = find_dynamic_gaps(runs, model, catalogue=_rivals("FREQ_LONG", "FREQ_WINDUP", "DAMP_RESIDUAL",
                                                           "DAMP_LONG"), refit_top=2)
    assert [c.parameters for c in rep.effects_added] == [("FREQ_LONG",)], (rep.effect_names, rep.rejected)
    assert rep.model.params.FREQ_LONG == pytest.approx(truth.params.FREQ_LONG, rel=0.005)
    assert rep.model.params.DAMP_RESIDUAL == model.params.DAMP_RESIDUAL
    for c, e in rep.error_after.items():
        assert e < 1.1 * rep.noise_floor[c]


def test_a_cutoff_between_the_grids_cells_is_refined_before_any_candidate_is_credited():
    """A control on a rig whose anti-alias filter (93 Hz) lies between the alignment's cells (80, 100 Hz), its load
    cells 1.2 % high and drifting: aligned on the grid alone, the given (true) model kept a misfit and an FX gain
    of 1.002, and a contact-length change, refitted with the continuous cutoff every candidate has, was credited
    with the chain's own refinement and added. The current model's chain is refined as every candidate's is."""
    from conftest import PROJECT, require_shared

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(require_shared(PROJECT.parent / "shared" / "reference" / "tir" /
                                               "TNO_car205_60R15.tir"))
    gain = {"FX": 1.0119, "FZ": 1.0120}
    runs = synthetic_runs(model, speeds=(20.0, 60.0), pressures=(1.9e5, 2.5e5), steer_speeds=(), duration=2.0,
                          lead=0.3, seed=11, dt=5e-4, cutoff=93.3, delay=0.010, ar=0.43, gain=gain,
                          drift={"FX": -41.7, "FZ": -44.2},
                          roads=("trapezoid(x0={x0}, top_length=0.05, height=0.015, ramp=0.03)",
                                 "cleat(x0={x0}, length=0.12, height=-0.015)"))
    rep = find_dynamic_gaps(runs, model)
    assert rep.effects_added == [], rep.effect_names
    assert rep.chain.cutoff == pytest.approx(93.3, rel=0.02) and rep.chain.delay == pytest.approx(0.010, abs=3e-4)
    for c, g in gain.items():
        assert rep.chain.gain[c] == pytest.approx(g, abs=0.003)


# ------------------------------------------------------------------------------ item 4: identifiability
def _brakes(loads):
    from mftyre.gaps.dynamic_runs import DynamicRun

    t = 1e-3 * np.arange(50)
    return [DynamicRun(f"b{f}", t, dict(VX=np.full(50, 10.0), LOAD=np.full(50, f), P=np.full(50, 2.2e5),
                                        OMEGA=np.r_[np.full(25, 33.0), np.full(25, 31.0)]), "", {"FX": np.zeros(50)})
            for f in loads]


def test_two_loads_give_a_load_slope_not_its_curvature(sample):
    from mftyre.gaps.dynamic_catalogue import testable_effects

    def load_terms(loads):
        ok, why = testable_effects(_brakes(loads), sample, model_kind="relaxed")
        return next(e.parameters for e in ok if "PCFX1" in e.parameters), why

    params, why = load_terms((3000.0, 5000.0))
    assert params == ("PCFX1",)
    assert "need 3 loads" in why["longitudinal relaxation length over load (PCFX1, PCFX2): PCFX2"]
    assert load_terms((3000.0, 4000.0, 5000.0))[0] == ("PCFX1", "PCFX2")


def test_a_load_read_from_the_measured_fz_is_one_level_whatever_its_noise_and_gain(sample):
    """Cleat runs at one axle height per pressure: the load is read from the measured FZ before the obstacle, which
    moves with the noise and a load cell 1.8 % high. Counted as distinct values those were several loads, the
    contact length's load slope Q_RA2 was refitted from them and named in place of Q_RA1; one load and two
    pressures now, so Q_RA2 is not testable, and the hold-out groups the runs by the same levels."""
    from mftyre.gaps.dynamic import _holdout
    from mftyre.gaps.dynamic_catalogue import testable_effects
    from mftyre.gaps.dynamic_runs import DynamicRun, run_levels

    rng = np.random.default_rng(2)
    t = 1e-3 * np.arange(100)
    runs = [DynamicRun(f"c{v}_{p}", t, dict(VX=np.full(100, v / 3.6), Z=np.full(100, 0.3), OMEGA=np.full(100, 30.0),
                                           P=np.full(100, p)), "cleat(x0=1, length=0.02, height=0.01)",
                       {"FX": rng.normal(0.0, 20.0, 100), "FZ": 1.018 * 4000.0 + rng.normal(0.0, 30.0, 100)})
            for v in (20.0, 60.0) for p in (1.9e5, 2.5e5)]
    assert len({r.condition["load"] for r in runs}) > 1  # the values the old count took for loads
    assert set(run_levels(runs, "load").tolist()) == {0}
    assert set(run_levels(runs, "pressure").tolist()) == {0, 1}
    ok, why = testable_effects(runs, sample)
    assert not any("Q_RA2" in e.parameters for e in ok)
    assert "two loads" in why["contact length over load (Q_RA2)"]
    assert len(_holdout(runs, 0.34, 0)) == 2


def test_near_singular_pairs_report_their_correlation_and_no_error():
    """precision(): a pair correlated at 0.999 (one combination fixed by the data) gets NaN standard errors and its
    correlation; a pair at 0.5 keeps sqrt(diag) x slope."""
    from types import SimpleNamespace

    from mftyre.gaps.dynamic import precision, values_text

    a = np.array([[1.0, 0.999], [0.999, 1.0]]) * 4e-4
    se, pairs = precision(a, [0.5, 2.0], ("ELLIPS_LENGTH", "ELLIPS_HEIGHT"))
    assert all(math.isnan(v) for v in se.values())
    assert pairs == {"ELLIPS_LENGTH~ELLIPS_HEIGHT": pytest.approx(0.999)}
    text = values_text(SimpleNamespace(values={"ELLIPS_LENGTH": 0.4, "ELLIPS_HEIGHT": 0.3}, stderr=se,
                                       correlation=pairs))
    assert "+-" not in text.replace("(no +-)", "") and "correlation 0.999" in text
    b = np.array([[1.0, 0.5], [0.5, 1.0]]) * 4e-4
    se, pairs = precision(b, [0.5, 2.0], ("A", "B"))
    assert pairs == {} and se == pytest.approx({"A": 0.01, "B": 0.04})


def test_a_parameter_set_simulated_again_reuses_its_runs_and_they_stay_read_only(sample, short_runs, monkeypatch):
    """The finder's simulator keeps what the last parameter sets gave on each run: the training runs of a refit's
    result are not simulated again when it is simulated on all runs, the outputs equal a fresh simulation and
    cannot be changed in place (a caller that did would change the kept ones)."""
    import mftyre.gaps.dynamic as dynamic
    from mftyre.gaps.dynamic_runs import simulate

    calls = []

    def counting(model, runs, *args, **kwargs):
        calls.append([r.name for r in runs])
        return simulate(model, runs, *args, **kwargs)

    monkeypatch.setattr(dynamic, "simulate", counting)
    sim = dynamic._Sim(short_runs)
    first, *_ = short_runs
    some = sim(sample, [first])
    every = sim(sample)
    assert calls == [[first.name], [r.name for r in short_runs[1:]]]
    assert every[first.name] is some[first.name]
    fresh = simulate(sample, short_runs)
    for r in short_runs:
        for c, values in every[r.name].items():
            np.testing.assert_array_equal(values, fresh[r.name][c])
            with pytest.raises(ValueError):
                values[0] = 0.0
    changed = sample.with_params(BELT_MASS=1.1 * sample.params.BELT_MASS)
    sim(changed, [first])
    assert calls[-1] == [first.name]          # another parameter set: simulated
