"""The dynamic gap finder (mftyre.gaps.dynamic): data layout, alignment and noise against the generator's known
measurement chain, naming a hidden changed effect among its rivals, the control, the command line.

Hidden cases: runs generated from a file with one parameter changed (the generator's truth), through noise, a
causal anti-alias filter and a delay; the finder gets the unchanged file and a few rivals from the catalogue (the
whole catalogue: benchmarks/bench_dynamic_gaps.py). Tests compare against the generator's own settings (delay,
cutoff, noise) and the changed parameter, never against snapshots of our output, so they hold while the SWIFT
equations change. About 35 s of CPU together when the SWIFT library of the structure is in the cache (parameters are
its run-time input: a refit compiles nothing).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import signal as sps

import mftyre
from mftyre.errors import DataError
from mftyre.gaps.dynamic import align, find_dynamic_gaps, noise_from_data
from mftyre.gaps import dynamic_catalogue
from mftyre.gaps.dynamic_runs import read_runs, simulate, synthetic_runs, write_runs

from conftest import PROJECT, SHORT_RUNS as SHORT, SWIFT_SAMPLE as SAMPLE, require_shared

TNO = PROJECT.parent / "shared" / "reference" / "tir" / "TNO_car205_60R15.tir"


def _effects(*names):
    return tuple(e for e in dynamic_catalogue.DYNAMIC_CATALOGUE if set(names) & set(e.parameters))


def test_csv_round_trip_and_errors(short_runs, tmp_path):
    runs = short_runs
    path = write_runs(runs, tmp_path / "runs.csv")
    with pytest.raises(DataError, match="exists"):
        write_runs(runs, path)
    back = read_runs(path)
    assert [r.name for r in back] == [r.name for r in runs]
    assert [r.kind for r in back] == ["cleat", "steer"]
    np.testing.assert_allclose(back[0].measured["FX"], runs[0].measured["FX"], rtol=1e-6, atol=1e-3)
    assert back[0].road == runs[0].road
    # a folder of CSV files, one run each, named by the file
    folder = tmp_path / "runs"
    folder.mkdir()
    frame = __import__("pandas").read_csv(path)
    for name, grp in frame.groupby("RUN"):
        grp.drop(columns="RUN").to_csv(folder / f"{name}.csv", index=False)
    assert sorted(r.name for r in read_runs(folder)) == sorted(r.name for r in runs)
    # bad inputs name the run and the column
    frame.drop(columns="VX").to_csv(tmp_path / "novx.csv", index=False)
    with pytest.raises(DataError, match="VX"):
        read_runs(tmp_path / "novx.csv")
    bad = frame.copy()
    bad["LOAD"] = 4000.0
    bad.to_csv(tmp_path / "both.csv", index=False)
    with pytest.raises(DataError, match="exactly one of Z"):
        read_runs(tmp_path / "both.csv")


def test_alignment_and_noise_recover_the_generators_chain(sample):
    """Delay, anti-alias cutoff and the noise after the filter (sigma_sensor sqrt(sum h^2) of the filter's impulse
    response) come back from the data."""
    noise = {"FX": 20.0, "FZ": 30.0, "FY": 20.0, "MZ": 1.5}
    runs = synthetic_runs(sample, speeds=(20.0, 50.0), cutoff=120.0, delay=7e-3, noise=noise, seed=3,
                          duration=0.6, lead=0.3)
    pred = simulate(sample, runs)
    chain, _ = align(runs, pred)
    assert chain.delay == pytest.approx(7e-3, abs=0.6e-3)
    assert chain.cutoff in (100.0, 120.0, 150.0)
    est = noise_from_data(runs, pred, chain)
    sos = sps.butter(4, 120.0, fs=1000.0, output="sos")
    h = sps.sosfilt(sos, np.r_[1.0, np.zeros(400)])
    gain = float(np.sqrt(np.sum(h**2)))
    for c in ("FX", "FZ"):
        assert est[c]["sigma"] == pytest.approx(noise[c] * gain, rel=0.25)  # ~100 independent samples
        assert est[c]["tau"] > 1.5  # the filter correlates the noise: fewer independent samples than rows



@pytest.mark.parametrize("phase", [0.0, 1.5, 3.0, -2.9])
def test_a_free_decay_gives_its_frequency_and_damping_for_any_starting_phase(phase):
    """The cleat's free decay (150 ms at 1 kHz, noise 2 % of its amplitude): the damped sine's frequency and damping
    are found whatever the phase it starts with. A decay starting near the opposite phase (a negative first swing)
    took the fit thousands of iterations from phase 0 and then gave none (nan)."""
    from mftyre.gaps.dynamic_locate import _decay

    rng = np.random.default_rng(4)
    dt, f, zeta, amp = 1e-3, 78.0, 0.11, 200.0
    t = dt * np.arange(150)
    w = 2 * math.pi * f
    y = amp * np.exp(-zeta * w * t) * np.cos(w * math.sqrt(1 - zeta**2) * t + phase) + 40.0
    got_f, got_zeta, f_se, zeta_se = _decay(y + rng.normal(0.0, 0.02 * amp, t.size), dt)
    assert abs(got_f - f) < 3 * f_se + 0.5 and abs(got_zeta - zeta) < 3 * zeta_se + 0.01, (got_f, got_zeta)
    assert f_se < 0.01 * f and zeta_se < 0.1 * zeta


def test_only_testable_effects_are_tried(sample):
    runs = synthetic_runs(sample, speeds=(30.0,), steer_speeds=(), **SHORT)  # one pressure, one load, cleat only
    ok, why = dynamic_catalogue.testable_effects(runs, sample)
    names = [e.name for e in ok]
    assert any("SWIFT_REVAR" in n for n in names)
    assert "two pressures" in why["sidewall stiffness over pressure (SWIFT_PSTIFF)"]
    assert "steer" in why["lateral carcass stiffness (relaxation length K_ya/C_y)"]
    assert "relaxation lengths PTX1-PTX3, PTY1-PTY2" in why


def test_control_adds_nothing(dynamic_control):
    _, rep = dynamic_control
    assert rep.effects_added == []
    for c, e in rep.error_after.items():  # the given model is at the noise floor already
        assert e < 1.25 * rep.noise_floor[c]


def _hidden_case(model, change, rivals, **kw):
    truth = model.with_params(**change)
    settings = dict(speeds=(20.0, 60.0), pressures=(1.9e5, 2.5e5), steer_speeds=(), seed=7, **SHORT)
    settings.update(kw)
    runs = synthetic_runs(model, truth=truth, **settings)
    rep = find_dynamic_gaps(runs, model, catalogue=_effects(*rivals), refit_top=2)
    return rep, truth


def _assert_found(rep, truth, name):
    assert [c.parameters for c in rep.effects_added] == [(name,)], rep.effect_names
    for c in rep.error_before:
        # the held-out error shrinks to within 30 % above the noise floor wherever the change showed
        if rep.error_before[c] > 1.5 * rep.noise_floor[c]:
            assert rep.error_after[c] < 1.3 * rep.noise_floor[c]
    (p, value), = rep.effects_added[0].values.items()
    assert value == pytest.approx(truth.params[p], abs=4 * rep.effects_added[0].stderr[p] + 0.05 * abs(
        truth.params[p]) + 0.02)


def test_sidewall_pressure_effect_is_named_on_the_tno_file():
    model = mftyre.load_tir(require_shared(TNO))
    rep, truth = _hidden_case(model, {"SWIFT_PSTIFF": 0.6},
                              ("SWIFT_PSTIFF", "SWIFT_PDAMP", "DAMP_LONG"))
    _assert_found(rep, truth, "SWIFT_PSTIFF")


def test_lateral_relaxation_is_named_from_step_steer(sample):
    rep, truth = _hidden_case(sample, {"LATERAL_STIFFNESS": 0.7 * sample.params.LATERAL_STIFFNESS},
                              ("LATERAL_STIFFNESS", "YAW_STIFFNESS", "FREQ_LAT"), speeds=(), pressures=None,
                              steer_speeds=(20.0, 45.0, 70.0), duration=0.6, lead=0.2)
    _assert_found(rep, truth, "LATERAL_STIFFNESS")


def test_command_line(sample, short_runs, tmp_path, capsys, monkeypatch):
    from mftyre.cli import main

    data = write_runs(short_runs, tmp_path / "runs.csv")
    out = tmp_path / "improved.tir"
    import mftyre.gaps.dynamic as dynamic

    given = []

    def recorded(*args, runner=None, **kw):  # the runner the options made (its cluster not started), then the search
        given.append(runner.describe())
        return find_dynamic_gaps(*args, **kw)

    monkeypatch.setattr(dynamic, "find_dynamic_gaps", recorded)
    assert main(["gaps", "--dynamic", str(data), "--model", str(SAMPLE), "-o", str(out), "--report",
                 str(tmp_path / "rep"), "--quiet", "--workers", "3"]) == 0
    assert given == ["a local cluster of 3 worker processes"]
    text = capsys.readouterr().out
    assert "nothing added" in text and out.exists() and (tmp_path / "rep" / "histories.png").exists()
    assert mftyre.load_tir(out).params.SWIFT_REVAR == sample.params.SWIFT_REVAR
    # an existing output needs --overwrite; DATA and --dynamic exclude each other
    assert main(["gaps", "--dynamic", str(data), "--model", str(SAMPLE), "-o", str(out), "--quiet"]) == 2
    assert main(["gaps", str(data), "--dynamic", str(data), "--model", str(SAMPLE)]) == 2
    assert main(["gaps", str(data), "--model", str(SAMPLE), "--workers", "2"]) == 2  # steady: no runner
    assert "--workers and --scheduler are for --dynamic" in capsys.readouterr().err


def test_rolling_radius_variation_is_named_and_on_the_runner_the_search_is_the_serial_one_bit_for_bit(sample,
                                                                                                        tmp_path):
    """The sample file's rolling radius variation is named; on a local cluster of 2 worker processes
    (mftyre.runner: the runs of each simulation and the parameter sets of each Jacobian as tasks, the model sent as
    its .tir text with the road layout of all the runs) the search is the serial one: the same effect added, every
    candidate's refitted values and chi-squares, every error and every simulated history equal to the last bit, the
    same file written."""
    from mftyre.runner import Runner

    truth = sample.with_params(SWIFT_REVAR=0.4)
    runs = synthetic_runs(sample, truth=truth, speeds=(20.0, 60.0), pressures=(1.9e5, 2.5e5), steer_speeds=(),
                          seed=7, **SHORT)
    options = dict(catalogue=_effects("SWIFT_REVAR", "LONGITUDINAL_STIFFNESS"), refit_top=2)
    serial = find_dynamic_gaps(runs, sample, **options)
    _assert_found(serial, truth, "SWIFT_REVAR")
    with Runner(workers=2) as runner:
        parallel = find_dynamic_gaps(runs, sample, runner=runner, **options)
    assert sum(math.isfinite(c.chi2_train_after) for r in serial.rounds for c in r) >= 2  # refits ran
    as_json = [json.dumps({k: v for k, v in rep.to_dict().items() if k != "seconds"}) for rep in (serial, parallel)]
    assert as_json[1] == as_json[0]
    for r in runs:
        for c in r.measured:
            assert np.array_equal(parallel.pred_after[r.name][c], serial.pred_after[r.name][c])
    for name, rep in (("serial", serial), ("parallel", parallel)):
        rep.write_tir(tmp_path / f"{name}.tir")
    assert (tmp_path / "parallel.tir").read_text() == (tmp_path / "serial.tir").read_text()


def test_a_simulation_task_is_the_simulation_and_returns_what_went_wrong(sample, short_runs):
    """simulate_task (what a worker runs: the model from its .tir text, the tyres from the road layout) gives the
    in-process simulation's outputs exactly; a run beyond its road table comes back as the model's error, not a
    crash of the task."""
    from mftyre.gaps.dynamic_runs import road_layout, run_data, simulate_task
    from mftyre.runner import unpack
    from mftyre.tir import tir_text

    layout = [[*key, *xr] for key, xr in road_layout(short_runs).items()]
    got = simulate_task(tir_text(sample.params), sample.side, "swift", layout, [run_data(r) for r in short_runs])
    want = simulate(sample, short_runs)
    assert set(got["outputs"]) == set(want)
    for name, channels in want.items():
        assert all(np.array_equal(unpack(got["outputs"][name][c]), v) for c, v in channels.items())
    short = [[*row[:3], row[3], row[3] + 0.5] for row in layout]
    assert "error" in simulate_task(tir_text(sample.params), sample.side, "swift", short, [run_data(short_runs[0])])


def test_stated_uncertainty_covers_the_truth_with_correlated_noise_and_model_error():
    """The refit's standard error (mftyre.gaps.dynamic._covariance) on a linear model whose 8 runs carry AR(1) noise
    (rho 0.8, weighted by its integrated autocorrelation time as the finder does) and, in the second set, a
    run-level model error (a slope error of sd 0.2 per run, which no noise estimate sees): +- 2 standard errors
    hold the truth in 85-99.5 % of 200 Monte Carlo repetitions either way (88-98 % over three seeds), where the plain least-squares error
    (J'J)^-1 covers only ~65 % with the model error (the stated 0.532 +- 0.009 for 0.6 of notebook 08)."""
    from types import SimpleNamespace

    from mftyre.gaps.dynamic import _covariance

    rng = np.random.default_rng(1)
    runs_, n, rho = 8, 400, 0.8
    tau = (1 + rho) / (1 - rho)
    runs = [SimpleNamespace(name=f"r{g}", t=np.zeros(n)) for g in range(runs_)]
    keys = [(r.name, "FX") for r in runs]
    x = np.concatenate([np.sin(np.linspace(0, 3 + g, n)) * (1 + 0.2 * g) for g in range(runs_)])
    J = (x / np.sqrt(tau))[:, None]

    def trial(spread):
        e = np.concatenate([sps.lfilter([np.sqrt(1 - rho**2)], [1, -rho], rng.standard_normal(n))
                            + rng.normal(0, spread) * x[g * n:(g + 1) * n] for g in range(runs_)])
        y = x + e  # the true slope 1
        slope = float(x @ y / (x @ x))
        se = math.sqrt(_covariance(J, (slope * x - y) / np.sqrt(tau), runs, keys, runs_ * n / tau)[0, 0])
        return abs(slope - 1.0), se, math.sqrt(np.linalg.pinv(J.T @ J)[0, 0])

    for spread in (0.0, 0.2):
        err, se, plain = np.array([trial(spread) for _ in range(200)]).T
        assert 0.85 <= np.mean(err < 2 * se) <= 0.995
        if spread:
            assert np.mean(err < 2 * plain) < 0.8


def test_the_structures_equilibrium_is_the_models(sample):
    """The gap finder's tyres take the static equilibrium's Jacobian from the structure's graph (built once for every
    parameter set): the same root as the model's own graph, and the same run."""
    from swift import StepInputs, SwiftTyre
    from swift.road import parse_road

    model = sample.with_params(FREQ_LONG=0.9 * sample.params.FREQ_LONG)
    road, u = parse_road("cleat(x0=1.0, length=0.02, height=0.01)"), StepInputs(x=0.0, vx=12.0, z=0.29, omega=40.0)
    ref, new = (SwiftTyre(model, road, x_range=(0.0, 4.0), equilibrium=kind) for kind in ("model", "structure"))
    np.testing.assert_allclose(new.initial_state(u), ref.initial_state(u), rtol=0, atol=1e-12)
    np.testing.assert_allclose(new.run(0.2, u).outputs["fz"], ref.run(0.2, u).outputs["fz"], rtol=1e-12)
    with pytest.raises(mftyre.errors.ModelInputError, match="equilibrium"):
        SwiftTyre(model, road, equilibrium="fast")


def test_one_acceptance_rule():
    """mftyre.gaps.search.judge, the rule of both finders: training significance at the family-wise level, the
    held-out test where there is one (NaN: none), and a held-out gain above the materiality bar."""
    from mftyre.gaps.search import judge

    assert judge(1e-6, 1e-4, math.nan, 0.05, 3.0) == ""
    assert "training" in judge(1e-3, 1e-4, math.nan, 0.05, 3.0)
    assert "held-out decrease" in judge(1e-6, 1e-4, 0.2, 0.05, 3.0)
    assert "penalty" in judge(1e-6, 1e-4, 0.01, 0.05, -1.0)
    assert "9.0 %" in judge(1e-6, 1e-4, 1e-6, 1e-4, 9.0, material=0.1, excess=100.0)
    assert judge(1e-6, 1e-4, 1e-6, 1e-4, 11.0, material=0.1, excess=100.0) == ""
