"""The relaxed wheel as the dynamic gap finder's model (mftyre.gaps.dynamic, model kind "relaxed"): its response
against the first-order relaxation the MF's own relaxation length predicts, a hidden relaxation length named on
step-steer and braking runs of a public MF 5.2 file we did not write, the control, the choice of the model.

Hidden cases: runs generated from the file with one parameter changed, through noise, a causal anti-alias filter
and a delay (mftyre.gaps.dynamic_runs.synthetic_runs); the finder gets the unchanged file and the whole catalogue.
About 13 s of CPU together (the relaxed wheel runs on the CasADi VM, one call per run).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

import mftyre
from mftyre.errors import ModelInputError
from mftyre.gaps.dynamic import find_dynamic_gaps, model_kind_for
from mftyre.gaps.dynamic_runs import RelaxedWheels, simulate, simulate_relaxed, synthetic_runs

from conftest import MFEVAL_DIR, PROJECT, require_shared

MF52 = MFEVAL_DIR / "MagicFormula52_Parameters.tir"
SWIFT_FILE = PROJECT / "tir_files" / "car_205_60R15_mf62_swift.tir"
QUIET = {c: 0.0 for c in ("FX", "FY", "FZ", "MZ", "SPIN")}
#: Few short runs: two step steers and two braking steps at two loads, 0.7 s each.
RUNS = dict(speeds=(), steer_speeds=(30.0, 70.0), brake_speeds=(30.0, 70.0), loads=(6000.0, 9000.0), duration=0.7,
            lead=0.2, seed=5, model_kind="relaxed")


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(path)


@pytest.fixture(scope="module")
def mf52():
    return _load(require_shared(MF52))


def test_relaxed_step_steer_follows_the_relaxation_length_of_the_mf(mf52):
    """A small yaw step (0.2 deg: linear range) at 50 km/h: Fy(x) = Fy_ss (1 - exp(-x / sigma_y)) over the travel x
    after the step, sigma_y the MF's own relaxation length at the load (model.evaluate), within 3 %; the final
    value the steady MF's at that slip angle (the same sign convention as the SWIFT wheel's yaw input)."""
    v, load = 50 / 3.6, 6000.0
    runs = synthetic_runs(mf52, speeds=(), steer_speeds=(50.0,), steer_angle=0.2, loads=(load,), duration=0.6,
                          lead=0.1, noise=QUIET, cutoff=None, delay=0.0, model_kind="relaxed")
    run = runs[0]
    fy = simulate(mf52, runs, model_kind="relaxed")[run.name]["FY"]
    steady = mf52.evaluate(load, 0.0, 0.0, 0.0, 0.0, v, mf52.params.NOMPRES)
    sigma = float(np.squeeze(steady["sigmay"]))
    # the wheel turned left by psi slides to its right: vy = -V sin(psi) in its axes, the MF's alpha = -psi
    final = mf52.evaluate(load, 0.0, -math.radians(0.2), 0.0, 0.0, v, mf52.params.NOMPRES)
    after = fy[-1] - fy[0]
    assert after == pytest.approx(float(np.squeeze(final["fy"] - steady["fy"])), rel=2e-3)
    k0 = int(round(0.12 / run.dt))  # the yaw ramp (20 ms) done: from here a free first-order decay
    x = v * run.dt * np.arange(fy.size - k0)
    gap = (fy[-1] - fy[k0:]) / after
    use = gap > 0.05
    slope = np.polyfit(x[use], np.log(gap[use]), 1)[0]
    assert -1.0 / slope == pytest.approx(sigma, rel=0.03)


@pytest.mark.parametrize("path", [MF52, MFEVAL_DIR / "MagicFormula62_Parameters.tir", SWIFT_FILE],
                         ids=lambda p: p.stem)
def test_models_of_one_refit_share_a_graph_and_give_what_their_own_graphs_give(path):
    """RelaxedWheels (the finder's graphs): the parameters a model moves from the reference are run-time entries of
    q, so two trials of one refit share one graph; each gives its own graph's outputs (the model's values as
    numbers) to 1e-12, with the axle height (MF 6.2: Fz from the loaded radius with the Fx, Fy terms) and with the
    load imposed. A parameter at 0 in the reference moved off 0 (a term switched on) stays a number: another
    graph, the same outputs as its own."""
    ref = _load(require_shared(path))
    runs = synthetic_runs(ref, speeds=(), steer_speeds=(40.0,), brake_speeds=(40.0,), duration=0.3, lead=0.1,
                          noise=QUIET, cutoff=None, delay=0.0, model_kind="relaxed")
    by_load = [replace(r, inputs={**{k: v for k, v in r.inputs.items() if k != "Z"},
                                  "LOAD": r.measured["FZ"]}) for r in runs]
    p = ref.params
    trials = [ref.with_params(PTX1=1.3 * p.PTX1 if "PTX1" in p and p.PTX1 else p.PTX1, PKY1=0.9 * p.PKY1,
                              FNOMIN=1.05 * p.FNOMIN),
              ref.with_params(PTX1=1.1 * p.PTX1 if "PTX1" in p and p.PTX1 else p.PTX1, PKY1=0.8 * p.PKY1,
                              FNOMIN=0.97 * p.FNOMIN)]
    zero = next(n for n in ("PCFX3", "PDXP3", "PHY3", "PPX4") if n in p and p[n] == 0.0)
    switched = ref.with_params(**{zero: 0.05})
    wheels = RelaxedWheels(ref)
    for vertical, cases in (("position", runs), ("load", by_load)):
        shared = [wheels.functions(m, vertical) for m in trials]
        assert shared[0] is shared[1] and {"PKY1", "FNOMIN"} <= set(shared[0].run_time)
        assert zero not in wheels.functions(switched, vertical).run_time
        assert wheels.functions(switched, vertical) is not shared[0]
        for m in (*trials, switched):
            got, own = simulate_relaxed(m, cases, wheels), simulate_relaxed(m, cases)
            for name, channels in own.items():
                for c, values in channels.items():
                    scale = 1.0 + np.max(np.abs(values))
                    assert np.max(np.abs(got[name][c] - values)) < 1e-12 * scale, (path.name, vertical, name, c)


def test_a_parameter_that_cannot_be_a_run_time_input_is_refused(mf52):
    from mftyre.transient import wheel_functions

    zero = next(n for n in mf52.params if mf52.params[n] == 0.0)
    for name in (zero, "FITTYP", "NO_SUCH_PARAMETER"):
        with pytest.raises(ModelInputError, match=name):
            wheel_functions(mf52, "transient", "load", run_time=(name,))


def test_relaxed_hidden_lateral_relaxation_length_is_named_and_refitted(mf52):
    """PTY1 x 0.75 on the step steers: the finder (relaxed wheel, whole catalogue) adds exactly that effect, the
    refitted PTY1 is within 5 % of the truth and the held-out FY error ends near the noise floor."""
    truth = mf52.with_params(PTY1=0.75 * mf52.params.PTY1)
    rep = find_dynamic_gaps(synthetic_runs(mf52, truth=truth, **RUNS), mf52, model_kind="relaxed")
    assert rep.model_kind == "relaxed"
    assert rep.effect_names == ["lateral relaxation length (PTY1)"]
    assert rep.model.params.PTY1 == pytest.approx(truth.params.PTY1, rel=0.05)
    assert rep.error_after["FY"] < 1.3 * rep.noise_floor["FY"] < rep.error_before["FY"]


def test_relaxed_hidden_longitudinal_relaxation_length_is_named(mf52):
    """PTX1 x 1.4 on the braking steps: named alone, Fx's held-out error near the noise floor."""
    truth = mf52.with_params(PTX1=1.4 * mf52.params.PTX1)
    rep = find_dynamic_gaps(synthetic_runs(mf52, truth=truth, **RUNS), mf52, model_kind="relaxed")
    assert rep.effect_names == ["longitudinal relaxation length (PTX1)"]
    assert rep.error_after["FX"] < 1.3 * rep.noise_floor["FX"] < rep.error_before["FX"]


def test_relaxed_control_adds_nothing(mf52):
    rep = find_dynamic_gaps(synthetic_runs(mf52, **RUNS), mf52, model_kind="relaxed")
    assert rep.effect_names == []
    assert "MF 6.1/6.2 only" in rep.untestable["lateral relaxation length (LATERAL_STIFFNESS)"]


def test_model_kind_auto_and_the_relaxed_wheels_limits(mf52):
    """auto: SWIFT where the file has the ring's sections, else the relaxed wheel; the relaxed wheel refuses an
    obstacle (no enveloping) with a message naming the run."""
    swift_file = _load(SWIFT_FILE)
    assert model_kind_for(swift_file, []) == "swift" and model_kind_for(mf52, []) == "relaxed"
    assert model_kind_for(swift_file, [], "relaxed") == "relaxed"
    with pytest.raises(ModelInputError, match="model kind"):
        model_kind_for(mf52, [], "ring")
    cleat = synthetic_runs(swift_file, speeds=(30.0,), steer_speeds=(), duration=0.3, lead=0.1)
    with pytest.raises(ModelInputError, match=f"{cleat[0].name}.*SWIFT"):
        simulate(swift_file, cleat, model_kind="relaxed")


def test_command_line_model_kind(mf52, tmp_path, capsys):
    """``--model-kind relaxed`` from the command line: the CSV round trip of braking and steer runs (the kind
    "brake" read back from OMEGA), the hidden PTX1 named and written into the improved file."""
    from mftyre.cli import main
    from mftyre.gaps.dynamic_runs import read_runs, write_runs

    truth = mf52.with_params(PTX1=1.4 * mf52.params.PTX1)
    data = write_runs(synthetic_runs(mf52, truth=truth, **RUNS), tmp_path / "runs.csv")
    assert sorted({r.kind for r in read_runs(data)}) == ["brake", "steer"]
    out = tmp_path / "improved.tir"
    assert main(["gaps", "--dynamic", str(data), "--model", str(MF52), "--model-kind", "relaxed", "-o", str(out),
                 "--quiet"]) == 0
    assert "longitudinal relaxation length (PTX1)" in capsys.readouterr().out
    assert _load(out).params.PTX1 == pytest.approx(truth.params.PTX1, rel=0.05)
