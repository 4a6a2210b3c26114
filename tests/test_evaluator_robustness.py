"""evaluate() at any finite input: typed errors for non-finite inputs, a spin solve that converges at any speed and
slip, finite outputs over a fuzzing grid of extreme inputs (every mode, every sample file)."""
from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest

import mftyre
from mftyre import cli
from mftyre.backend import NUMPY
from mftyre.formula import OUTPUT_NAMES, vertical
from mftyre.inputs import beyond_limits

from conftest import MFEVAL_DIR, SHARED, TIR_FILES

pytestmark = pytest.mark.filterwarnings("ignore::mftyre.errors.InputClippedWarning")

TIR61 = TIR_FILES / "car_205_60R15_mf61.tir"
TIR62 = TIR_FILES / "car_205_60R15_mf62_swift.tir"
EXTRA = [MFEVAL_DIR / "MagicFormula62_Parameters.tir", MFEVAL_DIR / "MagicFormula52_Parameters.tir",
         SHARED / "reference" / "tir" / "TNO_car205_60R15.tir"]


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(path)


@pytest.mark.parametrize("which", ["fz", "kappa", "alpha", "gamma", "phit", "vx", "p", "omega"])
@pytest.mark.parametrize("value", [np.inf, -np.inf])
def test_infinite_input_raises(which, value):
    model = _load(TIR61)
    kw = dict(fz=4000.0, kappa=0.0, alpha=0.0, gamma=0.0, phit=0.0, vx=10.0, p=2.2e5, omega=30.0)
    kw[which] = np.array([1.0, value])
    with pytest.raises(mftyre.ModelInputError, match=f"{which}.*finite"):
        model.evaluate(**kw)
    kw[which] = value  # scalar too
    with pytest.raises(mftyre.ModelInputError, match="finite"):
        model.evaluate(**kw)


@pytest.mark.parametrize("tir", [TIR61, TIR62], ids=["mf61", "mf62"])
def test_spin_solved_at_any_speed_and_slip(tir):
    """omega Re = (1 + kappa) Vx (2.5) with Re = R_omega(omega) - (R_omega - Re) (paper (1), (7)), also where the
    old fixed-point iteration diverged (Vx > ~840 m/s, kappa > ~52): evaluate refuses such speeds (the free radius
    would grow by more than 10 %), the equations behind it (MFModel._evaluate_arrays, no checks) solve them."""
    from mftyre.formula import Modes
    from mftyre.model import as_float_arrays

    model = _load(tir)
    prm = model.params
    vx = np.array([0.0, 1.0, 30.0, 900.0, 5000.0, 1.0e5, 30.0, 30.0, -30.0, 200.0])
    kappa = np.array([0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 100.0, -3.0, 60.0, 500.0])
    arrays = as_float_arrays(dict(fz=4000.0, kappa=kappa, alpha=0.0, gamma=0.0, phit=0.0, vx=vx, p=prm.INFLPRES,
                                  omega=0.0))
    out = model._evaluate_arrays(arrays, False, Modes(limits=False), check_finite=True)
    for name in OUTPUT_NAMES:
        assert np.all(np.isfinite(out[name])), name
    dpi = (out["p"] - prm.NOMPRES) / prm.NOMPRES
    reduction = vertical.rolling_radius_reduction(prm, out["fz"], dpi, NUMPY)
    re = vertical.free_radius(prm, out["omega"], NUMPY) - reduction
    np.testing.assert_allclose(re, out["re"], rtol=1e-13)
    np.testing.assert_allclose(out["omega"] * out["re"], (1.0 + kappa) * vx, rtol=1e-12, atol=1e-12)
    with pytest.raises(mftyre.ModelInputError, match="kappa = 100 .*rim speed"):
        model.evaluate(4000.0, kappa[6], 0.0, vx=vx[6])


def test_cli_eval_extreme_slip_has_no_traceback(capsys):
    """Within the limits: exit 0, no NaN; beyond them (a rim speed 100 x 16.7 m/s, 1000 m/s): exit 2 with the
    input, its value and the limit on stderr, no traceback."""
    assert cli.main(["eval", str(TIR61), "--kappa", "2"]) == 0
    assert cli.main(["eval", str(TIR61), "--vx", "100"]) == 0
    assert "nan" not in capsys.readouterr().out.lower()
    for option, value in (("--kappa", "100"), ("--vx", "1000")):
        assert cli.main(["eval", str(TIR61), option, value]) != 0
        err = capsys.readouterr().err
        assert f"= {value}" in err and "beyond the limit" in err and "Traceback" not in err


@pytest.mark.parametrize("path", [TIR61, TIR62, *EXTRA], ids=lambda p: p.stem)
def test_finite_outputs_at_extreme_inputs(path):
    if not path.exists():
        pytest.skip(f"reference material {path} not found (../shared beside the project)")
    model = _load(path)
    rng = np.random.default_rng(5)
    n = 600

    def log_uniform(lo, hi, signed=True):
        v = 10.0 ** rng.uniform(lo, hi, n)
        return v * np.sign(rng.uniform(-1, 1, n)) if signed else v

    for limits, turn_slip, form in itertools.product([True, False], [False, True], ["published", "mfeval"]):
        fz = log_uniform(-3, 6, signed=False)
        fz[:50] = 0.0
        vx = log_uniform(-3, 4)
        vx[50:100] = 0.0
        inputs = dict(fz=fz, kappa=log_uniform(-4, 3.5), alpha=log_uniform(-4, 0.5), gamma=log_uniform(-4, 0.3),
                      phit=log_uniform(-4, 1), vx=vx, p=10.0 ** rng.uniform(4, 7, n))
        refused = beyond_limits(model.params, inputs, limits)  # beyond what a tyre can be: ModelInputError
        assert refused.sum() < n
        if refused.any():
            with pytest.raises(mftyre.ModelInputError, match="beyond the limit"):
                model.evaluate(**inputs, limits=limits, turn_slip=turn_slip, turn_slip_form=form)
        kept = {k: v[~refused] for k, v in inputs.items()}
        options = dict(limits=limits, turn_slip=turn_slip, turn_slip_form=form)
        try:
            outs = [model.evaluate(**kept, **options)]
        except mftyre.ModelInputError as exc:  # without limits (extrapolated): outputs no tyre has, refused
            assert limits is False and "no tyre has it there" in str(exc), exc
            outs = []
            for i in range(int((~refused).sum())):
                try:
                    outs.append(model.evaluate(**{k: v[i] for k, v in kept.items()}, **options))
                except mftyre.ModelInputError as point_error:
                    assert "no tyre has it there" in str(point_error), point_error
            assert len(outs) > 0.8 * (~refused).sum()
        for out in outs:
            bad = [k for k in OUTPUT_NAMES if not np.all(np.isfinite(out[k]))]
            assert not bad, (limits, turn_slip, form, bad)


@pytest.mark.parametrize("path", [TIR61, TIR62, *EXTRA], ids=lambda p: p.stem)
def test_single_point_equals_batch(path):
    """One point is evaluated on NumPy scalars (a faster path): every output equals the batch evaluation."""
    if not path.exists():
        pytest.skip(f"reference material {path} not found (../shared beside the project)")
    model = _load(path)
    rng = np.random.default_rng(2)
    n = 12
    for limits, turn_slip, form in itertools.product([True, False], [False, True], ["published", "mfeval"]):
        x = dict(fz=np.r_[0.0, rng.uniform(0, 9000, n - 1)], kappa=rng.uniform(-1, 1, n),
                 alpha=rng.uniform(-0.5, 0.5, n), gamma=rng.uniform(-0.2, 0.2, n), phit=rng.uniform(-0.1, 0.1, n),
                 vx=np.r_[0.0, -0.5, rng.uniform(-40, 60, n - 2)], p=rng.uniform(1.5e5, 3e5, n))
        kw = dict(limits=limits, turn_slip=turn_slip, turn_slip_form=form)
        batch = model.evaluate(**x, **kw)
        for j in range(n):
            one = model.evaluate(**{k: v[j] for k, v in x.items()}, **kw)
            for name in OUTPUT_NAMES:
                assert np.shape(one[name]) == ()
                np.testing.assert_allclose(one[name], batch[name][j], rtol=1e-12, atol=1e-12, err_msg=name)
