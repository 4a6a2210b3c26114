"""MFModel.casadi_function evaluates the same equations as the NumPy path."""
from __future__ import annotations

import numpy as np
import pytest

import mftyre
from conftest import TIR_FILES
from mftyre.errors import ModelInputError
from mftyre.formula import OUTPUT_NAMES

casadi = pytest.importorskip("casadi")


def _random_inputs(prm, n, seed, turn_slip):
    rng = np.random.default_rng(seed)
    return dict(fz=rng.uniform(0.1, 2.5, n) * prm.FNOMIN, kappa=rng.uniform(-0.6, 0.6, n),
                alpha=rng.uniform(-0.4, 0.4, n), gamma=rng.uniform(-0.08, 0.08, n),
                phit=rng.uniform(-0.5, 0.5, n) if turn_slip else np.zeros(n),
                vx=rng.uniform(-30, 35, n), p=rng.uniform(0.8, 1.2, n) * prm.NOMPRES)


@pytest.mark.parametrize("tir", ["car_205_60R15_mf61.tir", "car_205_60R15_mf62_swift.tir"])
@pytest.mark.parametrize("turn_slip,alpha_star,limits", [(False, False, True), (True, False, True),
                                                          (False, True, False), (True, True, False)])
def test_casadi_matches_numpy(tir, turn_slip, alpha_star, limits):
    model = mftyre.load_tir(TIR_FILES / tir)
    x = _random_inputs(model.params, 400, seed=7, turn_slip=turn_slip)
    f = model.casadi_function(turn_slip=turn_slip, alpha_star=alpha_star, limits=limits)
    values = f.map(len(x["fz"]))(*[v[None, :] for v in x.values()])
    ref = model.evaluate(**x, turn_slip=turn_slip, alpha_star=alpha_star, limits=limits)
    for name, value in zip(OUTPUT_NAMES, values):
        ours, expected = np.asarray(value).ravel(), ref[name]
        scale = max(1.0, np.max(np.abs(expected)))
        np.testing.assert_allclose(ours, expected, rtol=1e-10, atol=1e-10 * scale, err_msg=name)


def test_casadi_subset_of_inputs_and_outputs_with_fixed_values():
    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir").with_side("right")
    f = model.casadi_function(inputs=("alpha", "kappa"), outputs=("fy", "mz", "alpha"),
                              fixed=dict(fz=5000.0, gamma=0.03, p=2.0e5))
    assert f.name_in() == ["alpha", "kappa"] and f.name_out() == ["fy", "mz", "alpha_used"]
    fy, mz, alpha_used = (float(v) for v in f(0.05, 0.02))
    ref = model.evaluate(5000.0, 0.02, 0.05, gamma=0.03, p=2.0e5)
    assert fy == pytest.approx(float(ref.fy), rel=1e-12)
    assert mz == pytest.approx(float(ref.mz), rel=1e-12)
    assert alpha_used == pytest.approx(0.05)
    # the Jacobian exists and matches a central difference
    a = casadi.SX.sym("a")
    dfy = casadi.Function("dfy", [a], [casadi.jacobian(f(a, 0.02)[0], a)])
    h = 1e-6
    fd = (float(f(0.05 + h, 0.02)[0]) - float(f(0.05 - h, 0.02)[0])) / (2 * h)
    assert float(dfy(0.05)) == pytest.approx(fd, rel=1e-6)


@pytest.mark.parametrize("turn_slip", [False, True])
def test_low_speed_false_leaves_out_a_model_that_is_1_from_vxlow_up(turn_slip):
    """low_speed=False (SWIFT's slip model, whose speed is at least VXLOW): the same outputs, bit for bit, at
    |vx| >= VXLOW with fewer operations; below VXLOW the low-speed model is missing indeed (the caller's contract)."""
    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")
    prm = model.params
    x = _random_inputs(prm, 200, seed=3, turn_slip=turn_slip)
    x["vx"] = np.sign(x["vx"]) * np.maximum(np.abs(x["vx"]), prm.VXLOW)
    x["vx"][:3] = [prm.VXLOW, -prm.VXLOW, 1.5 * prm.VXLOW]  # the edge itself (the factors 1 exactly)
    full, lean = (model.casadi_function(turn_slip=turn_slip, low_speed=flag) for flag in (True, False))
    assert lean.n_instructions() < full.n_instructions()
    args = [v[None, :] for v in x.values()]
    for name, a, b in zip(OUTPUT_NAMES, full.map(200)(*args), lean.map(200)(*args)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b), err_msg=name)
    slow = [v[None, :1] for v in {**x, "vx": np.array([0.3 * prm.VXLOW])}.values()]
    assert float(full(*slow)[0]) != pytest.approx(float(lean(*slow)[0]), rel=1e-3)  # fx: kappa scaled by |vx|/VXLOW


def test_casadi_function_rejects_unknown_names():
    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")
    with pytest.raises(ModelInputError, match="unknown input"):
        model.casadi_function(inputs=("fz", "slip"))
    with pytest.raises(ModelInputError, match="unknown output"):
        model.casadi_function(outputs=("fy", "force"))


@pytest.mark.parametrize("name", ["Q_FCY", "Q_FZ2"])
def test_symbolic_mf62_solver_form_parameters_are_refused_by_name(name):
    """The MF 6.2 loaded-radius solver branches on Q_FCY, Q_FCY2, Q_FYS2, Q_FYS3, Q_FZ2 in Python: as symbols they
    raised CasADi's 'Cannot compute the truth value' from deep inside the solver; now an error naming them."""
    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")
    with pytest.raises(ModelInputError, match=f"{name}.*must stay numbers"):
        model.casadi_function(parameters=(name,))
    mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir").casadi_function(parameters=(name,))  # MF 6.1: smooth
