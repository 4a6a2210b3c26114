"""The steady-state two-track vehicle and its optimisations (mftyre.vehicle).

Every optimum is checked against a search that shares only the model with it: IPOPT (CasADi, exact derivatives)
against a continuation of the steady-state curve on the NumPy path with finite differences, and against fine grids.
"""
from __future__ import annotations


import numpy as np
import pytest

from conftest import MFEVAL_DIR, TIR_FILES, require_shared

casadi = pytest.importorskip("casadi")

import mftyre  # noqa: E402
from mftyre.errors import ModelInputError  # noqa: E402
from mftyre.backend import LIMITS_SLACK  # noqa: E402
from mftyre.vehicle import (WHEELS, Vehicle, VehicleParams, brute_force_braking_slip,  # noqa: E402
                            optimal_braking_slip)

TIR = TIR_FILES / "car_205_60R15_mf61.tir"
MFEVAL_61 = MFEVAL_DIR / "MagicFormula61_Parameters.tir"
V = 20.0


@pytest.fixture(scope="module")
def car():
    return Vehicle.from_tir(TIR)


@pytest.fixture(scope="module")
def max_fixed(car):
    return car.max_lateral_acceleration(V)


@pytest.fixture(scope="module")
def max_optimised(car):
    return car.max_lateral_acceleration(V, pressures="optimise")


# --------------------------------------------------------------------------------------------- (a) IPOPT = search
@pytest.mark.parametrize("speed,turn", [(V, "left"), (12.0, "right")])
def test_ipopt_max_lateral_acceleration_matches_brute_force(car, speed, turn):
    ipopt = car.max_lateral_acceleration(speed, turn=turn)
    brute = car.brute_force_max_lateral_acceleration(speed, turn=turn)
    print(f"\nV={speed} {turn}: IPOPT ay={ipopt.ay:.6f} m/s^2 ({ipopt.stats}); "
          f"continuation ay={brute.ay:.6f} ({brute.n_points} steady states, {brute.solve_time:.2f} s)")
    assert ipopt.stats.success, ipopt.stats
    assert ipopt.active_bounds == ()
    assert ipopt.ay == pytest.approx(brute.ay, rel=5e-3)
    # the search walked past the optimum: no steady state on its curve is higher than IPOPT's
    assert np.max(np.abs(brute.curve["ay"])) <= abs(ipopt.ay) * (1 + 1e-9)
    # the two optima are the same state, not just the same ay
    for name, tol in (("delta", 2e-3), ("beta", 2e-3), ("r", 1e-3)):
        assert getattr(ipopt.state, name) == pytest.approx(getattr(brute.state, name), abs=tol), name


# --------------------------------------------------------------------------------------------- (b) pressures
def test_optimised_pressures_do_not_lose_and_stay_in_range(car, max_fixed, max_optimised):
    lo, hi = car.pressure_bounds()
    prm = car.tyres["FL"].params
    assert (lo, hi) == (prm.PRESMIN, prm.PRESMAX)
    print(f"\nfixed p = {max_fixed.p_front / 1e5:.3f}/{max_fixed.p_rear / 1e5:.3f} bar: ay_max = "
          f"{max_fixed.ay_g:.4f} g ({max_fixed.stats})\noptimised p = {max_optimised.p_front / 1e5:.4f}/"
          f"{max_optimised.p_rear / 1e5:.4f} bar: ay_max = {max_optimised.ay_g:.4f} g ({max_optimised.stats}), "
          f"gain {100 * (max_optimised.ay / max_fixed.ay - 1):.2f} %, active {max_optimised.active_bounds}")
    assert max_optimised.stats.success
    assert max_optimised.pressures_optimised
    assert max_optimised.ay >= max_fixed.ay - 1e-6 * abs(max_fixed.ay)
    for p in (max_optimised.p_front, max_optimised.p_rear):
        assert lo - 1e-3 <= p <= hi + 1e-3
    # no pressure pair of a small grid (re-solved with fixed pressures) does better
    for pf in np.linspace(lo, hi, 3):
        for pr in np.linspace(lo, hi, 3):
            res = car.max_lateral_acceleration(V, (pf, pr))
            assert res.stats.success
            assert res.ay <= max_optimised.ay + 1e-6 * max_optimised.ay, (pf, pr)


def test_optimised_pressure_optimum_is_a_steady_state_maximum(car, max_optimised):
    """At the optimal pressures, the independent search finds the same ay."""
    brute = car.brute_force_max_lateral_acceleration(V, (max_optimised.p_front, max_optimised.p_rear))
    assert max_optimised.ay == pytest.approx(brute.ay, rel=5e-3)


@pytest.mark.parametrize("limits", [True, "smooth"])
def test_pressure_has_its_full_slope_up_to_and_at_its_bounds(limits):
    """Inside PRESMIN..PRESMAX, the bounds included, an input is the identity with its full (one-sided) slope:
    dFy/dp equals that of limits=False (fmin/fmax gave half of it at the bound). Both keep the full slope a hair
    outside (an interior-point solver's bound relaxation: 1e-8); beyond 2 LIMITS_SLACK |bound| True saturates (slope
    0, the value at the bound: NumPy's clip); "smooth" has a slope that fades to 1 % further out, continuous in value
    and slope at the bound."""
    model = mftyre.load_tir(TIR)
    prm = model.params

    def dfy_dp(lim):
        p = casadi.SX.sym("p")
        fy = model.casadi_function(("fz", "kappa", "alpha", "p"), ("fy",), limits=lim)(4000.0, 0.02, 0.05, p)
        return casadi.Function("dfy", [p], [fy, casadi.jacobian(fy, p)])

    free, limited = dfy_dp(False), dfy_dp(limits)
    for bound, outward in ((prm.PRESMIN, -1.0), (prm.PRESMAX, 1.0)):
        for p in (bound - outward * 1e3, bound):
            assert float(limited(p)[1]) == pytest.approx(float(free(p)[1]), rel=1e-12), (bound, p)
        hair = bound * (1.0 + outward * 1e-8)
        far = bound + outward * 0.2 * (prm.PRESMAX - prm.PRESMIN)
        value, slope = (float(v) for v in limited(hair))
        assert slope == pytest.approx(float(free(bound)[1]), rel=1e-6)
        assert value == pytest.approx(float(free(hair)[0]), rel=1e-9)
        if limits is True:
            beyond = bound * (1.0 + outward * 3 * LIMITS_SLACK)
            value, slope = (float(v) for v in limited(beyond))
            assert slope == 0.0 and value == float(free(bound)[0])
        else:
            far_slope = float(limited(far)[1])
            assert 0.0 < far_slope / float(free(bound)[1]) < 0.05


@pytest.mark.parametrize("tir, ipopt_options", [(TIR, {}), (TIR, {"tol": 1e-12}),
                                                 (TIR, {"tol": 1e-8, "acceptable_tol": 1e-6}),
                                                 (MFEVAL_61, {}), (MFEVAL_61, {"tol": 1e-12})],
                         ids=["bound", "bound-tol1e-12", "bound-ipopt-defaults", "interior", "interior-tol1e-12"])
def test_optimal_pressures_converge_with_true_multipliers(tir, ipopt_options):
    """The pressure design problem converges at any IPOPT tolerance (at 1e-12 the old saturation ran 600
    iterations to Maximum_Iterations_Exceeded; at IPOPT's default 1e-8 it took 160): an optimum at PRESMIN (the
    sample car file) and an interior one (the reference evaluator's MF 6.1 file). The bound multipliers are the
    sensitivities d(ay/g)/dp a one-sided finite difference of the fixed-pressure optimum gives."""
    car = Vehicle.from_tir(require_shared(tir))
    lo, hi = car.pressure_bounds()
    best = car.max_lateral_acceleration(V, pressures="optimise", ipopt_options=ipopt_options)
    assert best.stats.success and best.stats.iterations <= 40, best.stats
    h = 2e-3 * (hi - lo)
    for k, (p, name) in enumerate(((best.p_front, "front"), (best.p_rear, "rear"))):
        at_bound = p <= lo + 1.0
        assert at_bound == (tir == TIR), (name, p)
        if not at_bound:
            assert abs(best.pressure_sensitivity[k]) < 1e-10
            continue
        moved = [best.p_front, best.p_rear]
        moved[k] = lo + h
        fd = (car.max_lateral_acceleration(V, pressures=tuple(moved)).ay_g - best.ay_g) / h
        assert best.pressure_sensitivity[k] == pytest.approx(fd, rel=0.02), name


# --------------------------------------------------------------------------------------------- (c) braking slip
@pytest.mark.parametrize("fz,alpha", [(4000.0, 0.0), (4000.0, 0.08), (2500.0, -0.15), (6000.0, 0.04)])
def test_optimal_braking_slip_matches_fine_grid(fz, alpha):
    model = mftyre.load_tir(TIR, side="left")
    best = optimal_braking_slip(model, fz, alpha)
    grid = brute_force_braking_slip(model, fz, alpha, n=20001)
    print(f"\nFz={fz:.0f} N alpha={alpha:+.2f}: IPOPT kappa={best.kappa:.5f} -Fx={-best.fx:.2f} N ({best.stats}); "
          f"grid kappa={grid.kappa:.5f} -Fx={-grid.fx:.2f} N")
    assert best.stats.success, best.stats
    assert -best.fx >= (1 - 1e-3) * -grid.fx
    assert -best.fx <= -grid.fx * (1 + 1e-3)
    assert best.kappa == pytest.approx(grid.kappa, abs=5e-3)
    assert -0.5 < best.kappa < 0.0
    assert best.mu_x == pytest.approx(-best.fx / fz)


def test_braking_slip_grows_with_slip_angle():
    """Combined slip: with a slip angle the longitudinal peak is reached at a larger |kappa| and is lower."""
    model = mftyre.load_tir(TIR, side="right")
    pure, combined = optimal_braking_slip(model, 4000.0, 0.0), optimal_braking_slip(model, 4000.0, 0.1)
    assert combined.kappa < pure.kappa
    assert -combined.fx < -pure.fx


# --------------------------------------------------------------------------------------------- (d) equilibrium
def test_residuals_vanish_at_solved_steady_state(car):
    ss = car.steady_state(V, 0.03)
    assert ss.stats.success, ss.stats
    assert np.max(np.abs(ss.residuals)) < 1e-6
    # the symbolic path gives the same residuals at the same point
    x = casadi.SX.sym("x", 5)
    f = casadi.Function("res", [x], [car.residuals(x[0], x[1], x[2], x[3], x[4])])
    sym = np.asarray(f([V, ss.delta, ss.beta, ss.r, ss.kappa])).ravel()
    assert np.max(np.abs(sym)) < 1e-6
    # and both paths agree away from equilibrium, with non-default pressures
    pt = (V, 0.05, -0.03, 0.3, 0.01, 2.0e5, 2.4e5)
    num = car.residuals(*pt)
    sym = np.asarray(casadi.Function("r", [x], [car.residuals(x[0], x[1], x[2], x[3], x[4], 2.0e5, 2.4e5)])(
        pt[:5])).ravel()
    np.testing.assert_allclose(sym, num, rtol=1e-10, atol=1e-8)
    assert np.max(np.abs(num)) > 100.0


def test_steering_left_and_right_give_mirrored_states(car):
    left, right = car.steady_state(V, 0.03), car.steady_state(V, -0.03)
    assert left.r > 0 and left.ay > 0
    for name in ("beta", "r"):
        assert getattr(right, name) == pytest.approx(-getattr(left, name), rel=1e-9, abs=1e-12)
    assert right.kappa == pytest.approx(left.kappa, rel=1e-9, abs=1e-12)
    for a, b in (("FL", "FR"), ("RL", "RR")):
        assert right.wheels[b]["fz"] == pytest.approx(left.wheels[a]["fz"], rel=1e-9)
        assert right.wheels[b]["fy"] == pytest.approx(-left.wheels[a]["fy"], rel=1e-9)
        assert right.wheels[b]["alpha"] == pytest.approx(-left.wheels[a]["alpha"], rel=1e-9)


def test_sign_convention_of_a_left_turn(car):
    """A left turn: positive yaw rate and ay, negative slip angles, tyre forces to the left, outer wheels loaded."""
    ss = car.steady_state(V, 0.02)
    assert ss.r > 0 and ss.ay > 0
    for w in WHEELS:
        assert ss.wheels[w]["alpha"] < 0 and ss.wheels[w]["fy"] > 0, w
    assert ss.wheels["FR"]["fz"] > ss.wheels["FL"]["fz"] and ss.wheels["RR"]["fz"] > ss.wheels["RL"]["fz"]
    total = sum(ss.wheels[w]["fz"] for w in WHEELS)
    assert total == pytest.approx(car.params.mass * car.params.g, rel=1e-12)


def test_small_steer_matches_linear_single_track_model(car):
    """Analytic limit: at small steer, yaw-rate gain = V / (L + K V^2) with K from the tyres' cornering
    stiffness at the static loads (the aligning moments, which the linear model leaves out, cost ~1 %)."""
    P = car.params
    L = P.wheelbase
    fzf, fzr = P.mass * P.g * P.b / L / 2, P.mass * P.g * P.a / L / 2
    cf = -2 * float(car.tyres["FL"].evaluate(fzf, 0.0, 0.0, vx=V).kya)
    cr = -2 * float(car.tyres["RL"].evaluate(fzr, 0.0, 0.0, vx=V).kya)
    k_us = P.mass / L * (P.b / cf - P.a / cr)
    delta = 0.002
    ss = car.steady_state(V, delta)
    assert ss.r / delta == pytest.approx(V / (L + k_us * V ** 2), rel=0.02)


def test_drag_is_balanced_by_the_driven_wheels(car):
    slippery = car.with_params(cd_area=0.7)
    ss = slippery.steady_state(30.0, 0.0)
    drag = 0.5 * slippery.params.rho_air * 0.7 * 30.0 ** 2
    assert ss.stats.success
    assert ss.kappa > 0
    assert sum(ss.wheels[w]["Fx"] for w in WHEELS) == pytest.approx(drag, rel=1e-6)
    for w in ("FL", "FR"):  # undriven wheels at kappa = 0 carry only the tyre's small zero-slip offset
        assert abs(ss.wheels[w]["fx"]) < 0.01 * ss.wheels[w]["fz"]
    assert abs(ss.r) < 1e-9


def test_vehicle_rejects_tyres_that_are_not_mirror_images():
    left = mftyre.load_tir(TIR, side="left")
    with pytest.raises(ModelInputError, match="with_side"):
        Vehicle(VehicleParams(), [left, left, left, left.with_side("right")])
    with pytest.raises(ModelInputError, match="roll_stiffness_front"):
        VehicleParams(roll_stiffness_front=1.5)


# --------------------------------------------------------------------------------------------- (e) physics
def test_maximum_lateral_acceleration_is_plausible(max_fixed, max_optimised):
    for res in (max_fixed, max_optimised):
        assert 0.7 <= res.ay_g <= 1.2
        # below the friction of the tyres at their nominal load (load sensitivity costs grip)
        state = res.state
        total_fy = sum(abs(state.wheels[w]["fy"]) for w in WHEELS)
        total_fz = sum(state.wheels[w]["fz"] for w in WHEELS)
        assert total_fy / total_fz < 1.0
