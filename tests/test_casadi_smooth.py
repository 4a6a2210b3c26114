"""CasADi for optimisers: smooth=1e-6 finite at any finite load (it gave NaN Fy, Mz below Fz = -1 N), and
limits="smooth" keeps derivatives non-zero beyond the .tir ranges where limits=True makes them exactly zero."""
from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import mftyre
from mftyre.backend import SMOOTH_WIDTHS

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


def _derivative(model, name, outputs, fixed, **kw):
    """d(outputs)/d(name) as a function of input ``name`` with the other inputs fixed."""
    f = model.casadi_function((name,), outputs, fixed=fixed, **kw)
    x = ca.SX.sym(name)
    y = ca.vertcat(*f.call([x]))
    return ca.Function("derivative", [x], [y, ca.jacobian(y, x)])


@pytest.mark.parametrize("path", FILES, ids=["mf61", "mf62"])
def test_smooth_widths_per_quantity_round_the_contact_and_low_speed_kinks(path):
    """smooth=True rounds each kink over the width of its own quantity (mftyre.backend.SMOOTH_WIDTHS): the slope
    of Fy in Fz changes gradually through Fz = 0 (1 N wide; one width of 1e-6 for every quantity left a step of
    the whole slope within a micronewton), the slope of Fx in Vx through the low-speed switch at VXLOW (a kink
    of the exact model, 1 cm/s wide); away from the kinks the model is the exact one (angles and slips rounded
    over 1e-4 rad, not over the force width: 1e-4 relative)."""
    model = mftyre.load_tir(path)
    prm = model.params
    common = dict(kappa=0.02, alpha=0.05, gamma=0.02, phit=0.0, p=prm.NOMPRES)
    d_fz = _derivative(model, "fz", ("fy",), {**common, "vx": 20.0}, smooth=True)
    loads = np.linspace(-3.0, 3.0, 61)
    slopes = np.array([float(d_fz(v)[1]) for v in loads])
    full = float(d_fz(3.0 * SMOOTH_WIDTHS["force"] + 50.0)[1])
    assert np.all(np.abs(np.diff(slopes)) <= 0.1 * abs(full)), np.diff(slopes)
    d_vx = _derivative(model, "vx", ("fx", "fy"), {**common, "fz": 4000.0}, smooth=True)
    exact_vx = _derivative(model, "vx", ("fx", "fy"), {**common, "fz": 4000.0})
    step = 1e-4
    below, above = (np.array(d_vx(prm.VXLOW + d)[1]).ravel() for d in (-step, step))
    exact_below, exact_above = (np.array(exact_vx(prm.VXLOW + d)[1]).ravel() for d in (-step, step))
    kink = np.abs(exact_above - exact_below)
    assert np.all(kink > 1.0)  # the exact model's slope jumps at VXLOW
    assert np.all(np.abs(above - below) < 0.1 * kink)
    # away from the kinks: the exact model
    smooth_f = model.casadi_function(INPUTS, ("fx", "fy", "mz"), smooth=True)
    exact_f = model.casadi_function(INPUTS, ("fx", "fy", "mz"))
    point = [4000.0, 0.02, 0.05, 0.02, 0.0, 20.0, prm.NOMPRES]
    np.testing.assert_allclose(np.array(ca.vertcat(*smooth_f(*point))).ravel(),
                               np.array(ca.vertcat(*exact_f(*point))).ravel(), rtol=1e-4)


def test_smooth_widths_are_validated_and_partial_mappings_keep_the_defaults():
    model = mftyre.load_tir(FILES[0])
    for bad in ({"load": 1.0}, {"force": -1.0}, 0.0, "1e-6"):
        with pytest.raises(ValueError, match="smooth"):
            model.casadi_function(("fz",), ("fy",), fixed={"kappa": 0.0, "alpha": 0.05}, smooth=bad)
    d_default = _derivative(model, "fz", ("fy",), {"kappa": 0.0, "alpha": 0.05}, smooth=True)
    d_wide = _derivative(model, "fz", ("fy",), {"kappa": 0.0, "alpha": 0.05}, smooth={"force": 100.0})
    # the slope at Fz = 0 is half the slope beyond the kink for either width; 20 N away the narrow one is full
    for d in (d_default, d_wide):
        assert float(d(0.0)[1]) == pytest.approx(0.5 * float(d(1000.0)[1]), rel=0.05)
    assert float(d_default(20.0)[1]) == pytest.approx(float(d_default(1000.0)[1]), rel=0.05)
    assert abs(float(d_wide(20.0)[1])) < 0.7 * abs(float(d_wide(1000.0)[1]))
