"""CasADi for optimisers: smooth=1e-6 finite at any finite load (it gave NaN Fy, Mz below Fz = -1 N), and
limits="smooth" keeps derivatives non-zero beyond the .tir ranges where limits=True makes them exactly zero."""
from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import mftyre

from conftest import TIR_FILES

FILES = [TIR_FILES / "car_205_60R15_mf61.tir", TIR_FILES / "car_205_60R15_mf62_swift.tir"]
INPUTS = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p")
OUTPUTS = ("fx", "fy", "mz", "mx", "my", "rl")


def _jacobian_function(model, **kw):
    f = model.casadi_function(INPUTS, OUTPUTS, **kw)
    x = ca.SX.sym("x", len(INPUTS))
    y = ca.vertcat(*f(*ca.vertsplit(x)))
    return ca.Function("fj", [x], [y, ca.jacobian(y, x)])


@pytest.mark.parametrize("path", FILES, ids=["mf61", "mf62"])
@pytest.mark.parametrize("limits", [True, False, "smooth"])
@pytest.mark.parametrize("turn_slip", [False, True])
def test_smooth_model_is_finite_with_finite_jacobian_at_negative_loads(path, limits, turn_slip):
    model = mftyre.load_tir(path)
    prm = model.params
    fj = _jacobian_function(model, smooth=1e-6, limits=limits, turn_slip=turn_slip)
    for fz in (-2000.0, -100.0, -1.5, -1e-3, 0.0, 1e-9, 50.0, prm.FNOMIN):
        y, jac = fj([fz, 0.05, 0.05, 0.02, 0.01, 20.0, prm.NOMPRES])
        assert np.all(np.isfinite(np.array(y))), (fz, np.array(y).ravel())
        assert np.all(np.isfinite(np.array(jac))), fz


@pytest.mark.parametrize("path", FILES, ids=["mf61", "mf62"])
def test_smooth_limits_keep_derivatives_beyond_the_ranges(path):
    model = mftyre.load_tir(path)
    prm = model.params
    hard = _jacobian_function(model, smooth=1e-6, limits=True)
    soft = _jacobian_function(model, smooth=1e-6, limits="smooth")
    inside = [prm.FNOMIN, 0.05, 0.05, 0.01, 0.0, 20.0, prm.NOMPRES]
    y_hard, _ = hard(inside)
    y_soft, _ = soft(inside)
    np.testing.assert_allclose(np.array(y_soft), np.array(y_hard), rtol=1e-12, atol=1e-9)  # same model inside
    outside = {"alpha": prm.ALPMAX + 0.2, "kappa": prm.KPUMAX + 0.5, "p": prm.PRESMAX * 1.2,
               "gamma": prm.CAMMAX + 0.05}
    fy, fx = OUTPUTS.index("fy"), OUTPUTS.index("fx")
    for name, value in outside.items():
        x = list(inside)
        j = INPUTS.index(name)
        x[j] = value
        out = fx if name == "kappa" else fy
        d_hard = float(np.array(hard(x)[1])[out, j])
        d_soft = float(np.array(soft(x)[1])[out, j])
        assert abs(d_hard) < 1e-6 * abs(d_soft), (name, d_hard, d_soft)  # saturated: (nearly) flat
        assert np.isfinite(d_soft) and d_soft != 0.0, name


def test_limits_option_is_validated():
    model = mftyre.load_tir(FILES[0])
    with pytest.raises(ValueError, match="limits"):
        model.evaluate(4000.0, 0.0, 0.0, limits="soft")
