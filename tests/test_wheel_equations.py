"""The wheel's equations in mftyre.transient (one home for the native wheel model and the pythonfmu steady tyre):
against MFModel.vertical_force, an explicit cross product, the slip definitions written out, and NumPy against
CasADi."""
from __future__ import annotations

import math

import numpy as np
import pytest

import mftyre
from conftest import SHARED, TIR_FILES, require_shared
from mftyre.backend import NUMPY, casadi_backend
from mftyre.formula.vertical import free_radius
from mftyre.transient import (VX_MIN, contact_load, kinematic_slips, mf_slip, slip_speeds, wheel_centre_moments,
                              wheel_vertical_force)


@pytest.mark.parametrize("name", ["car_205_60R15_mf61.tir", "car_205_60R15_mf62_swift.tir"])
@pytest.mark.parametrize("side", ["left", "right"])
def test_vertical_force_is_the_model_s_on_either_side(name, side):
    import casadi as ca

    model = mftyre.load_tir(TIR_FILES / name, side=side)
    rng = np.random.default_rng(3)
    r0 = model.params.UNLOADED_RADIUS
    rl, p, omega = r0 - rng.uniform(0.0, 0.04, 50), rng.uniform(1.6e5, 2.6e5, 50), rng.uniform(0, 120, 50)
    fx, fy, gamma = rng.uniform(-4e3, 4e3, 50), rng.uniform(-4e3, 4e3, 50), rng.uniform(-0.08, 0.08, 50)
    fz, r_omega = wheel_vertical_force(model, rl, p, omega, fx, fy, gamma, NUMPY)
    np.testing.assert_allclose(fz, model.vertical_force(rl, p, omega, fx, fy, gamma), rtol=1e-13, atol=1e-9)
    np.testing.assert_array_equal(r_omega, free_radius(model.params, omega, NUMPY))
    sym = [ca.SX.sym(n) for n in ("rl", "p", "omega", "fx", "fy", "gamma")]
    f = ca.Function("f", sym, list(wheel_vertical_force(model, *sym, casadi_backend())))
    fz_ca, ro_ca = f(rl, p, omega, fx, fy, gamma)
    np.testing.assert_allclose(np.ravel(fz_ca), fz, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(np.ravel(ro_ca), r_omega, rtol=1e-15)


def test_contact_load_lifts_off_above_the_free_radius():
    fz = np.array([1e3, -5.0, 1e3, 2e3])
    rl = np.array([0.30, 0.30, 0.31, 0.3099])
    np.testing.assert_array_equal(contact_load(fz, rl, 0.31, NUMPY), [1e3, 0.0, 0.0, 2e3])


def test_kinematic_slips_and_slip_speeds():
    """kappa = (omega Re - vx) / |vx| (> 0 driving), alpha = atan2(vy, |vx|) (> 0 sliding left), finite at
    standstill; the MF gets (omega Re - vx) / vx; the slip speeds given back from the MF's slips are
    Vsx = vx - omega Re, Vsy = vy (|vx| >= VX_MIN)."""
    re = 0.3
    kappa, alpha = kinematic_slips(20.0, 1.0, 22.0 / re, re, NUMPY)
    assert kappa == pytest.approx(0.1, rel=1e-14) and alpha == pytest.approx(math.atan(1.0 / 20.0), rel=1e-15)
    kappa, alpha = kinematic_slips(-20.0, -1.0, -18.0 / re, re, NUMPY)  # reversing: Vsx = -2 m/s, -Vsx / |vx|
    assert kappa == pytest.approx(0.1, rel=1e-14) and alpha == pytest.approx(-math.atan(1.0 / 20.0), rel=1e-15)
    kappa, alpha = kinematic_slips(0.0, 0.0, 1.0, re, NUMPY)
    assert kappa == pytest.approx(re / VX_MIN) and alpha == 0.0
    vx, vy, omega = np.array([15.0, -7.0, 0.2]), np.array([0.5, -0.3, 0.0]), np.array([48.0, -25.0, 0.1])
    kappa, alpha = kinematic_slips(vx, vy, omega, re, NUMPY)
    np.testing.assert_allclose(mf_slip(kappa, vx, NUMPY), (omega * re - vx) / vx, rtol=1e-13)
    vsx, vsy = slip_speeds(mf_slip(kappa, vx, NUMPY), alpha, vx, NUMPY)
    np.testing.assert_allclose(vsx, vx - omega * re, rtol=1e-13)
    np.testing.assert_allclose(vsy, vy, rtol=1e-13)


def test_wheel_centre_moments_are_the_cross_product():
    """M_W = M_C + (C - W) x F with W = C + Rl (0, -sin g, cos g)."""
    rng = np.random.default_rng(5)
    for _ in range(20):
        f, m = rng.uniform(-5e3, 5e3, 3), rng.uniform(-300, 300, 3)
        rl, g = rng.uniform(0.25, 0.32), rng.uniform(-0.2, 0.2)
        c_minus_w = -rl * np.array([0.0, -math.sin(g), math.cos(g)])
        expected = m + np.cross(c_minus_w, f)
        got = wheel_centre_moments(*f, *m, rl, g, NUMPY)
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("kind", ["steady", "transient", "swift"])
def test_state_functions_describe_their_vectors(kind):
    """The native FMU is generated from any StateFunctions (wheel or SWIFT): the names and start values given
    match the sizes of the CasADi functions' x, u, q and y."""
    import warnings

    from mftyre.transient import StateFunctions, wheel_functions
    from swift.fmu_model import swift_functions

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if kind == "swift":
            f = swift_functions(mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir"),
                                "cleat(x0=2, length=0.05, height=0.01)")
        else:
            f = wheel_functions(mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir"), kind)
    assert isinstance(f, StateFunctions)
    sizes = {name: f.step.size1_in(i) for i, name in enumerate(f.step.name_in())}
    assert f.init.size1_out(0) == sizes["x"] == len(f.state_names)
    assert f.out.size1_out(0) == len(f.output_names)
    assert sizes["u"] == len(f.input_names) == len(f.input_starts)
    assert f.init.size1_in(f.init.name_in().index("q")) == len(f.parameter_names) == len(f.parameter_starts)


@pytest.mark.parametrize("path", [SHARED / "reference" / "tir" / "TNO_car205_60R15.tir",
                                  SHARED / "reference" / "mfeval" / "MagicFormula61_Parameters.tir"])
@pytest.mark.parametrize("kind", ["steady", "transient"])
def test_position_mode_load_is_the_fixed_point_of_the_coupled_vertical_force(path, kind):
    """Public .tir files whose vertical force depends on Fx and Fy (Q_FCX, Q_FCY != 0; MF 6.2 and 6.1): with the
    wheel centre at Rl, the wheel's Fz is MFModel.vertical_force at Rl with the wheel's own Fx and Fy, and differs
    from the force at Fx = Fy = 0 where the tyre slips (old wheel: the force at Fx = Fy = 0)."""
    from mftyre.transient import WheelTyre

    model = mftyre.load_tir(require_shared(path))
    prm = model.params
    tyre = WheelTyre(model, kind, "position")
    rng = np.random.default_rng(7)
    moved = 0.0
    for _ in range(8):
        vx = rng.uniform(3.0, 30.0)
        inputs = dict(vx=vx, vy=rng.uniform(-3.0, 3.0), omega=vx / prm.UNLOADED_RADIUS * rng.uniform(0.85, 1.15),
                      gamma=rng.uniform(-0.05, 0.05), p=prm.INFLPRES, z=prm.UNLOADED_RADIUS * rng.uniform(0.95, 0.99),
                      road_z=0.0)
        tyre.set_inputs(**inputs)
        tyre.initialise()
        out = tyre.outputs()
        rl = inputs["z"] / math.cos(inputs["gamma"])
        coupled = model.vertical_force(rl, prm.INFLPRES, inputs["omega"], out["Fx"], out["Fy"], inputs["gamma"])
        uncoupled = model.vertical_force(rl, prm.INFLPRES, inputs["omega"], 0.0, 0.0, inputs["gamma"])
        assert out["Fz"] == pytest.approx(float(coupled), rel=1e-9), inputs
        moved = max(moved, abs(float(uncoupled) - out["Fz"]) / out["Fz"])
    assert moved > 1e-3
