"""SwiftTyre.step as a co-simulation master calls it: results are views that later steps never overwrite, the
state returned last is read in place, every bad input raises a ModelInputError naming it (compiled C and CasADi
virtual machine alike), StepInputs stays an immutable dataclass."""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import mftyre
from mftyre.errors import ModelInputError
from swift import OUTPUT_NAMES, STATE_NAMES, Cleat, StepInputs, SwiftTyre
from swift.simulate import _BLOCK_ROWS, Outputs

from conftest import TIR_FILES

V = 40 / 3.6
Z = 0.2915


@pytest.fixture(scope="module")
def tyres():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the sample file's unmodelled parameters
        model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")
        road = Cleat(1.0, 0.05, 0.01)
        return {True: SwiftTyre(model, road, x_range=(0.0, 12.0)),
                False: SwiftTyre(model, road, x_range=(0.0, 12.0), compiled=False)}


def _inputs(k, **changes):
    return StepInputs(**{"x": V * k * 1e-3, "vx": V, "z": Z, "omega": V / 0.3044, **changes})


def test_step_results_stay_valid_over_blocks_and_equal_run(tyres):
    """States and outputs are rows of blocks the C writes once: after 2.5 blocks every kept result still equals
    run() (the same C loop), so no row was reused."""
    tyre = tyres[True]
    n = 5 * _BLOCK_ROWS // 2
    res = tyre.run(n * 1e-3, lambda t: _inputs(round(t * 1e3)))
    s, kept = tyre.initial_state(_inputs(0)), []
    for k in range(n):
        s, out = tyre.step(s, _inputs(k), 1e-3)
        kept.append((s, out))
    np.testing.assert_array_equal(np.array([st for st, _ in kept]), res.states[1:])
    np.testing.assert_array_equal(np.array([o.array for _, o in kept]), np.column_stack(
        [res[name][1:] for name in OUTPUT_NAMES]))
    assert np.ptp(res["fz"]) > 500.0  # the cleat was met


def test_the_state_returned_last_is_read_as_it_is_now(tyres):
    """A master may correct the returned state in place (the FMU moves the belt's y and x): the step reads it."""
    tyre = tyres[True]
    s = tyre.initial_state(_inputs(0))
    s, _ = tyre.step(s, _inputs(0), 1e-3)
    edited = s.copy()
    edited[STATE_NAMES.index("yb")] += 1e-3
    s[STATE_NAMES.index("yb")] += 1e-3  # in place: the C reads this row of the block
    in_place, out_in_place = tyre.step(s, _inputs(1), 1e-3)
    copied, out_copied = tyre.step(edited, _inputs(1), 1e-3)  # a new array: copied in
    np.testing.assert_array_equal(in_place, copied)
    assert dict(out_in_place) == dict(out_copied) and out_copied["fy"] != 0.0


def test_a_state_without_contact_solution_is_solved_first(tyres):
    tyre = tyres[True]
    s = np.array(tyre.initial_state(_inputs(0)))
    expected, _ = tyre.step(s, _inputs(0), 1e-3)
    s[STATE_NAMES.index("lsm")] = 0.0  # built by hand: no contact solution
    np.testing.assert_allclose(tyre.step(s, _inputs(0), 1e-3)[0], expected, rtol=1e-9, atol=1e-12)


def test_outputs_mapping(tyres):
    for tyre in tyres.values():
        _, out = tyre.step(tyre.initial_state(_inputs(0)), _inputs(0), 1e-3)
        assert isinstance(out, Outputs) and list(out) == list(OUTPUT_NAMES) and len(out) == len(OUTPUT_NAMES)
        assert type(out["fz"]) is float and out["fz"] > 3000.0
        assert out.values() == [out[name] for name in OUTPUT_NAMES] == out.array.tolist()
        assert "fz" in out and "Fz" not in out
        with pytest.raises(KeyError):
            out["Fz"]
        with pytest.raises(TypeError):
            out["fz"] = 0.0


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "casadi"])
@pytest.mark.parametrize("name", ["vx", "z", "vz", "omega", "x", "p", "y", "vy", "gamma", "psi", "road_camber"])
@pytest.mark.parametrize("value", [float("nan"), float("inf")])
def test_each_non_finite_input_is_named(tyres, compiled, name, value):
    """(old: only a NaN vx was caught; the others gave NaN states silently)"""
    tyre = tyres[compiled]
    s = tyre.initial_state(_inputs(0))
    with pytest.raises(ModelInputError, match=f"input '{name}' must be finite"):
        tyre.step(s, _inputs(0, **{name: value}), 1e-3)


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "casadi"])
def test_other_bad_inputs(tyres, compiled):
    tyre = tyres[compiled]
    s = tyre.initial_state(_inputs(0))
    for p in (0.0, -2e5):
        with pytest.raises(ModelInputError, match="'p' .* must be positive"):
            tyre.step(s, _inputs(0, p=p), 1e-3)
    for dt in (-1e-3, float("nan"), float("inf")):
        with pytest.raises(ModelInputError, match="dt must be finite and >= 0"):
            tyre.step(s, _inputs(0), dt)
    with pytest.raises(ModelInputError, match="input 'vx' must be a real number, got 'fast'"):
        tyre.step(s, _inputs(0, vx="fast"), 1e-3)
    with pytest.raises(ModelInputError, match="input 'p' must be a real number, got 'high'"):
        tyre.step(s, _inputs(0, p="high"), 1e-3)
    # inputs the mode ignores (axle height imposed, spin imposed) are not checked
    ok, _ = tyre.step(s, _inputs(0, load=float("nan"), torque=float("nan")), 1e-3)
    assert np.all(np.isfinite(ok))


def test_bad_input_inside_a_run_names_the_step(tyres):
    tyre = tyres[True]

    def inputs(t):
        return _inputs(round(t * 1e3), gamma=float("nan") if t > 0.0045 else 0.0)

    with pytest.raises(ModelInputError, match=r"input 'gamma' must be finite, got nan \(step 5, t = 0.005 s\)"):
        tyre.run(0.01, inputs)


def test_step_inputs_stay_an_immutable_dataclass():
    u = StepInputs(x=1.0, vx=2.0)
    assert (u.z, u.load, u.p, u.road_camber) == (0.0, 4000.0, None, 0.0)
    assert StepInputs(1.0, 2.0) == u and hash(StepInputs(1.0, 2.0)) == hash(u)
    assert dataclasses.replace(u, vx=3.0) == StepInputs(x=1.0, vx=3.0)
    assert [f.name for f in dataclasses.fields(StepInputs)] == list(dataclasses.asdict(u))
    with pytest.raises(dataclasses.FrozenInstanceError):
        u.vx = 5.0
    with pytest.raises(TypeError):
        StepInputs(omgea=3.0)


@pytest.mark.parametrize("compiled", [True, False])
def test_a_step_series_runs_as_its_steps_one_by_one(tyres, compiled):
    """run() with a StepSeries (columns, past the last step the last one holds; the pressure of a step without
    one: the file's INFLPRES, as StepInputs(p=None)) gives, bit for bit, run() with ``t -> StepInputs`` of the same
    steps; bad columns are named."""
    from swift import StepSeries

    tyre, n = tyres[compiled], 300 if compiled else 12
    k = np.arange(n - 5)
    cols = dict(x=V * k * 1e-3, vx=np.full(k.size, V), z=Z + 1e-3 * np.sin(k / 7.0), omega=np.full(k.size, V / 0.3044))
    series = StepSeries(**cols)
    steps = [StepInputs(**{c: float(v[i]) for c, v in cols.items()}) for i in range(k.size)]
    by_steps = tyre.run(n * 1e-3, lambda t: steps[min(int(round(t / 1e-3)), len(steps) - 1)])
    by_series = tyre.run(n * 1e-3, series)
    assert np.array_equal(by_series.states, by_steps.states)
    assert all(np.array_equal(by_series[o], by_steps[o]) for o in OUTPUT_NAMES)
    with pytest.raises(ModelInputError, match="unknown input.*speed"):
        StepSeries(speed=[1.0, 2.0])
    with pytest.raises(ModelInputError, match="one length"):
        StepSeries(x=[0.0, 1.0], vx=[1.0])
