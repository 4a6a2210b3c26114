"""The model's one policy for inputs beyond the file's ranges (docs/model-input-policy.md, mftyre.inputs), in every
entry: evaluate, the compiled model, CasADi's fixed inputs, the CLI, SWIFT. Above FZMAX up to 1.5 FZMAX: MFeval's
split, warned; beyond it, at speeds no tyre rolls at and at inputs beyond binary64: a ModelInputError naming the
input, its value and the limit (on the old code: rl 2.16 m at 1e4 m/s, exit 0, raw OverflowError)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import mftyre
from mftyre import cli
from mftyre.compat import MFEVAL_COLUMNS
from mftyre.errors import InputClippedWarning, ModelInputError

from conftest import TIR_FILES

T61 = TIR_FILES / "car_205_60R15_mf61.tir"
T62 = TIR_FILES / "car_205_60R15_mf62_swift.tir"
INPUTS = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p", "omega")


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(path)


@pytest.fixture(scope="module")
def compiled61():
    from mftyre.compiled import compile_model

    return compile_model(_load(T61), outputs=("fx", "fy", "re", "rl", "my"))


@pytest.mark.parametrize("name", INPUTS)
def test_an_int_beyond_float_is_a_typed_error_naming_the_input(name):
    kw = dict(fz=4000.0, kappa=0.0, alpha=0.0, gamma=0.0, phit=0.0, vx=16.7, p=2.2e5, omega=50.0)
    kw[name] = 10**400
    with pytest.raises(ModelInputError, match=f"input '{name}' must be finite; got a number beyond the largest"):
        _load(T61).evaluate(**kw)
    kw[name] = [1, 10**400]
    with pytest.raises(ModelInputError, match=f"input '{name}'"):
        _load(T61).evaluate(**kw)


def test_overflow_in_the_compiled_model_and_casadi_is_typed(compiled61):
    point = [4000.0, 0.0, 0.0, 0.0, 0.0, 16.7, 2.2e5]
    for k, name in enumerate(compiled61.inputs):
        args = list(point)
        args[k] = 10**400
        with pytest.raises(ModelInputError, match=f"input '{name}' must be finite"):
            compiled61(*args)
        with pytest.raises(ModelInputError, match=f"input '{name}' must be finite"):
            compiled61.batch(*args)
    with pytest.raises(ModelInputError, match="input 'vx' must be finite"):
        _load(T61).casadi_function(("fz", "kappa", "alpha"), ("fx",), fixed={"vx": 10**400})


@pytest.mark.parametrize("path", [T61, T62])
def test_speeds_no_tyre_rolls_at_are_refused_naming_the_speed_and_the_limit(path, compiled61):
    """vx = 1e4 m/s gave rl 2.16 m, re 2.15 m on a tyre of R0 0.3135 m; 1000 m/s an My of -1.4 MN m."""
    model = _load(path)
    limit = r"vx = 10000 is beyond the limit of .*\|vx\| <= 173\.167 m/s, where the rolling-resistance terms"
    with pytest.raises(ModelInputError, match=limit):
        model.evaluate(4000.0, 0.0, 0.0, vx=1e4)
    with pytest.raises(ModelInputError, match=r"vx = -1000 at 1 of 3 points"):
        model.evaluate(4000.0, 0.0, 0.0, vx=[10.0, -1000.0, 30.0])
    with pytest.raises(ModelInputError, match=r"omega = 2000 \(rim speed 627 m/s\) .*\|omega R0\| <= 189\.797"):
        model.evaluate(4000.0, 0.0, 0.0, vx=30.0, omega=2000.0)
    if path == T61:
        with pytest.raises(ModelInputError, match=r"vx = 10000 at 1 of 1 point\(s\) is beyond the limit"):
            compiled61(4000.0, 0.0, 0.0, 0.0, 0.0, 1e4, 2.2e5)
        with pytest.raises(ModelInputError, match=r"kappa = 20 \(rim speed 630 m/s\)"):
            compiled61.batch(4000.0, [0.0, 20.0], 0.0, 0.0, 0.0, 30.0, 2.2e5)
    out = model.evaluate(4000.0, 0.0, 0.0, vx=[80.0, 150.0])  # 290 km/h and 540 km/h: answered, radii of a tyre
    r0 = model.params.UNLOADED_RADIUS
    assert np.all(out.rl < 1.1 * r0) and np.all(out.re < 1.1 * r0) and np.all(np.abs(out.my) < 4000 * r0)


def test_loads_within_the_margin_agree_with_mfeval_and_warn_beyond_it_are_refused(compiled61):
    """Up to 1.5 FZMAX the default model is MFeval's answer (the forces and moments at FZMAX, the radii, patch and
    My at the load: the MFeval 4.3.1 table of the file, made with Octave), with the warning; beyond it refused, by
    evaluate and the compiled model alike. (MF 6.1's deflection and Rl: the model's at the load, MFeval's held at
    FZMAX; they are compared in test_mfeval_extra through compat.)"""
    from test_mfeval_extra import read_table

    model = _load(T61)
    prm = model.params
    table = read_table(T61.name)
    rows = ((table["useMode"] == 111) & (table["ncols"] == 7) & (table["in_Fz"] > prm.FZMAX)
            & (np.abs(table["in_Vx"]) > prm.VXLOW) & (np.abs(table["in_Vx"]) < 100))
    assert rows.sum() >= 20
    args = [table[c][rows] for c in ("in_Fz", "in_kappa", "in_alpha", "in_gamma", "in_phit", "in_Vx", "in_P")]
    with pytest.warns(InputClippedWarning, match="fz outside FZMAX"):
        out = model.evaluate(*args[:5], vx=args[5], p=args[6])
    for ours, theirs, rtol in (("fx", "Fx", 1e-9), ("fy", "Fy", 1e-9), ("mz", "Mz", 1e-9), ("mx", "Mx", 1e-9),
                               ("my", "My", 1e-8), ("re", "Re", 1e-8), ("a", "2a", 1e-9), ("b", "2b", 1e-9),
                               ("omega", "omega", 1e-8), ("sigmay", "sigmay", 1e-9)):
        scale = 2.0 if theirs in ("2a", "2b") else 1.0
        np.testing.assert_allclose(scale * out[ours], table[theirs][rows], rtol=rtol, atol=1e-9 * prm.FNOMIN,
                                   err_msg=ours)
    with pytest.warns(InputClippedWarning):  # more load, more deflection (not held at FZMAX)
        rho = model.evaluate(np.array([1.0, 1.2, 1.4]) * prm.FZMAX, 0.0, 0.0).rho
    assert np.all(np.diff(rho) > 1e-3)
    with pytest.raises(ModelInputError, match=r"fz = 15001 is beyond the limit of .*fz <= 1\.5 FZMAX = 15000 N"):
        model.evaluate(15001.0, 0.0, 0.0)
    with pytest.raises(ModelInputError, match=r"fz = 15001 at 1 of 1 point\(s\) is beyond the limit"):
        compiled61(15001.0, 0.0, 0.0, 0.0, 0.0, 16.7, 2.2e5)
    assert model.evaluate(2e4, 0.0, 0.0, limits=False).fz == 2e4  # limits off: extrapolated as asked


def test_a_spin_no_tyre_has_under_load_is_refused():
    """FREFF = 6 (DREFF = 0): Re 0.04 m at FZMAX, 0.014 m at 1.45 FZMAX, where the estimated spin omega = Vx / Re
    runs away (1190 rad/s at 16.7 m/s: a rim speed of 373 m/s)."""
    model = _load(T61)
    steep = mftyre.MFModel(model.params.replace(DREFF=0.0, FREFF=6.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputClippedWarning)
        assert steep.evaluate(4000.0, 0.0, 0.0).re > 0.1
        with pytest.raises(ModelInputError, match=r"spin beyond the limit .*under load.*fz = 14500"):
            steep.evaluate(14500.0, 0.0, 0.0)


def test_cli_refuses_speeds_and_overflow_with_the_limit_and_no_traceback(capsys):
    """`mftyre eval FILE --vx 1e6` and `mftyre swift --speed 1e6` exited 0 with no warning."""
    assert cli.main(["eval", str(T61), "--vx", "1e6"]) == 1
    err = capsys.readouterr().err
    assert "vx = 1e+06 is beyond the limit" in err and "173.167 m/s" in err and "Traceback" not in err
    assert cli.main(["eval", str(T61), "--fz", "1e400"]) != 0
    assert "Traceback" not in capsys.readouterr().err
    assert cli.main(["swift", str(T62), "--road", "flat()", "--speed", "1e6", "--fz", "4000"]) == 1
    err = capsys.readouterr().err
    assert "vx = 1e+06 is beyond the limit" in err and "Traceback" not in err


def test_swift_refuses_a_run_beyond_the_speed_limit():
    from swift import StepInputs, SwiftTyre
    from swift.road import parse_road

    model = _load(T62)
    tyre = SwiftTyre(model, parse_road("flat()"), rim="speed")
    with pytest.raises(ModelInputError, match=r"vx = 1000 is beyond the limit"):
        tyre.initial_state(StepInputs(vx=1000.0, z=0.3, load=4000.0, omega=1000.0 / 0.3))


def test_compat_answers_beyond_the_limits_as_mfeval_does_with_a_warning():
    from mftyre.compat import mfeval

    model = _load(T61)
    with pytest.warns(mftyre.ReferenceValueWarning, match="vx = 300 is beyond the limit"):
        row = mfeval(model, [[4000.0, 0.0, 0.0, 0.0, 0.0, 300.0]], 111)[0]
    assert row[MFEVAL_COLUMNS.index("Re")] > 1.15 * model.params.UNLOADED_RADIUS  # returned as MFeval returns it


def test_the_compiled_model_checks_the_rim_speed_of_an_estimated_spin_at_any_slip(compiled61):
    """vx = 150 m/s (inside 173 m/s) with kappa = 0.5 (inside KPUMIN..KPUMAX): rim speed 225 m/s beyond the file's
    189.8 m/s, refused by evaluate; the compiled model (one point and batch) refused it only where kappa was outside
    its range (old code: answered, without a warning). kappa = 0.2 (180 m/s) is answered by all, unwarned."""
    model = _load(T61)
    with pytest.raises(ModelInputError, match=r"input vx = 150 \(rim speed 225 m/s\) .*\|\(1 \+ kappa\) vx\| <= 189"):
        model.evaluate(4000.0, 0.5, 0.0, vx=150.0)
    with pytest.raises(ModelInputError, match=r"\(rim speed 225 m/s\) at 1 of 1 point\(s\) is beyond the limit of .*"
                                              r"\|\(1 \+ kappa\) vx\| <= 189\.797"):
        compiled61(4000.0, 0.5, 0.0, 0.0, 0.0, 150.0, 2.2e5)
    with pytest.raises(ModelInputError, match=r"\(rim speed 225 m/s\) at 1 of 3 point\(s\)"):
        compiled61.batch(4000.0, [0.0, 0.5, 0.2], 0.0, 0.0, 0.0, 150.0, 2.2e5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        one = compiled61(4000.0, 0.2, 0.0, 0.0, 0.0, 150.0, 2.2e5)
        many = compiled61.batch(4000.0, [0.0, 0.2], 0.0, 0.0, 0.0, 150.0, 2.2e5)
        ref = model.evaluate(4000.0, 0.2, 0.0, vx=150.0)
    assert one[0] == pytest.approx(float(ref.fx), rel=1e-9) and many.fx[1] == pytest.approx(float(ref.fx), rel=1e-9)
    with pytest.warns(InputClippedWarning, match=r"kappa outside KPUMIN..KPUMAX = \[-1, 1\] - at 1 of 2 point"):
        compiled61.batch(4000.0, [0.0, -1.5], 0.0, 0.0, 0.0, 30.0, 2.2e5)  # the count: kappa's range only
