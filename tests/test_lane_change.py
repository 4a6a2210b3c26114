"""The minimum-time lane change (mftyre.lane_change): IPOPT with its default settings converges on four MF tyres
with the pressures as design variables (the optimum at PRESMIN on the sample file), the trajectory meets the
manoeuvre and stays within the friction the tyres offer, and an independent integration of the same dynamics
(NumPy tyres, scipy's adaptive Runge-Kutta, the optimal controls interpolated) ends where the collocation does."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

pytest.importorskip("casadi")

import mftyre  # noqa: E402
from mftyre.lane_change import LaneChange  # noqa: E402
from mftyre.vehicle import WHEELS  # noqa: E402

from conftest import TIR_FILES  # noqa: E402

TIR = TIR_FILES / "car_205_60R15_mf61.tir"


@pytest.fixture(scope="module")
def problem():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return LaneChange.from_tir(TIR, intervals=24)


@pytest.fixture(scope="module")
def best(problem):
    return problem.solve("mf", "expand")


def _rhs(t, x, problem, times, controls, pf, pr):
    """The module's dynamics with NumPy tyres (MFModel.evaluate, limits=True: inside the ranges the same model)."""
    P = problem.params
    X, Y, psi, vx, vy, r = x
    delta = np.interp(t, times, controls["delta"])
    kappa = np.interp(t, times, controls["kappa"])
    L = P.wheelbase
    ay = vx * r
    transfer = {"F": P.mass * ay / P.track_front * P.roll_stiffness_front * P.h_cog,
                "R": P.mass * ay / P.track_rear * (1 - P.roll_stiffness_front) * P.h_cog}
    static = {"F": P.mass * P.g * P.b / L / 2, "R": P.mass * P.g * P.a / L / 2}
    sum_fx = sum_fy = yaw = 0.0
    for w, (xw, yw) in P.positions().items():
        front = w[0] == "F"
        d = delta if front else 0.0
        bx, by = vx - r * yw, vy + r * xw
        vxw, vyw = bx * np.cos(d) + by * np.sin(d), -bx * np.sin(d) + by * np.cos(d)
        axle = "F" if front else "R"
        fz = static[axle] + (-1.0 if yw > 0 else 1.0) * transfer[axle]
        out = problem.tyres[w].evaluate(fz, 0.0 if front else kappa, np.arctan(vyw / vxw), vx=vxw,
                                        p=pf if front else pr)
        fx_b = float(out.fx) * np.cos(d) - float(out.fy) * np.sin(d)
        fy_b = float(out.fx) * np.sin(d) + float(out.fy) * np.cos(d)
        sum_fx, sum_fy = sum_fx + fx_b, sum_fy + fy_b
        yaw += xw * fy_b - yw * fx_b + float(out.mz)
    return [vx * np.cos(psi) - vy * np.sin(psi), vx * np.sin(psi) + vy * np.cos(psi), r,
            sum_fx / P.mass + vy * r, sum_fy / P.mass - vx * r, yaw / problem.yaw_inertia]


def test_lane_change_converges_with_ipopt_defaults_and_meets_the_manoeuvre(problem, best):
    print("\n", best)
    assert best.success and best.iterations <= 60, best
    s = best.states
    assert s["X"][-1] == pytest.approx(problem.length) and s["Y"][-1] == pytest.approx(problem.width)
    # faster than driving the distance at the start speed would allow only by accelerating; not absurd either
    assert 0.8 * problem.length / problem.speed < best.time < 1.3 * problem.length / problem.speed
    # lateral acceleration within the friction the tyres offer (|PDY1| ~ 1)
    lo, hi = problem.pressure_bounds
    assert lo <= best.p_front <= hi and lo <= best.p_rear <= hi
    prm = problem.tyres["FL"].params
    assert np.max(np.abs(s["vx"] * s["r"])) < 1.2 * abs(prm.PDY1) * 9.81
    # the optimum uses the tyres near their limit (a lane change as fast as they allow)
    assert np.max(np.abs(s["vx"] * s["r"])) > 0.5 * abs(prm.PDY1) * 9.81


def test_lane_change_trajectory_matches_an_independent_integration(problem, best):
    """Each collocation interval integrated from its first node with the optimal controls (interpolated linearly,
    as the trapezoidal rule takes them) ends at the next node: the local error of the trapezoidal rule on 24
    intervals (the whole manoeuvre integrated open loop drifts away: a car at its limits is unstable open loop)."""
    from scipy.integrate import solve_ivp

    names = ("X", "Y", "psi", "vx", "vy", "r")
    times = np.linspace(0.0, best.time, problem.intervals + 1)
    nodes = np.array([best.states[k] for k in names])
    errors = np.zeros((len(names), problem.intervals))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mftyre.InputClippedWarning)
        for j in range(problem.intervals):
            sol = solve_ivp(_rhs, (times[j], times[j + 1]), nodes[:, j], rtol=1e-9, atol=1e-9,
                            args=(problem, times, best.controls, best.p_front, best.p_rear))
            assert sol.success
            errors[:, j] = sol.y[:, -1] - nodes[:, j + 1]
    largest = dict(zip(names, np.abs(errors).max(axis=1)))
    limits = {"X": 0.005, "Y": 0.005, "psi": 0.005, "vx": 0.03, "vy": 0.1, "r": 0.03}
    assert all(largest[k] < limits[k] for k in names), largest


def test_simple_tyre_and_routes_agree(problem, best):
    """The simple 4-parameter tyre (matched peaks and slip stiffness) gives a similar time; the plain SX route
    the same optimum as the expanded one."""
    simple = problem.solve("simple", "expand")
    assert simple.success
    assert simple.time == pytest.approx(best.time, rel=0.05)
    sx = problem.solve("mf", "sx")
    assert sx.success and sx.time == pytest.approx(best.time, rel=1e-6)
    assert set(WHEELS) == set(problem.tyres)


def test_assembled_route_reaches_the_same_optimum(problem, best):
    """Route "assembled" (compiled tyre kernels, the NLP's exact derivatives assembled by the chain rule; the
    free-rolling wheels' tyres specialised to kappa = 0) solves the same NLP: the same time and pressures."""
    result = problem.solve("mf", "assembled")
    assert result.success
    # its derivatives are CasADi's own (the expanded NLP's) at a random point near the initial guess
    ours, arguments, _ = problem.build("mf", "assembled")
    theirs = problem.build("mf", "expand")[0]
    rng = np.random.default_rng(3)
    x = arguments["x0"] * (1 + 0.05 * rng.standard_normal(arguments["x0"].size))
    lam_g = rng.standard_normal(arguments["lbg"].size)
    for name, args in (("nlp_jac_g", (x, [])), ("nlp_hess_l", (x, [], 0.7, lam_g))):
        a, b = ours.get_function(name)(*args), theirs.get_function(name)(*args)
        a, b = (np.array(m[-1] if isinstance(m, (list, tuple)) else m) for m in (a, b))
        assert np.max(np.abs(a - b)) < 1e-9 * np.max(np.abs(b)), name
    assert result.time == pytest.approx(best.time, rel=1e-6)
    assert result.p_front == pytest.approx(best.p_front, rel=1e-6)
    assert result.p_rear == pytest.approx(best.p_rear, rel=1e-6)
    assert result.iterations <= best.iterations + 2


def test_pressure_yardstick_follows_the_mf_tyres_pressure_slopes(problem):
    """tyre "simple-p": at NOMPRES the simple tyre (INFLPRES = NOMPRES in this file); its cornering stiffness and
    friction change with the pressure by the MF tyre's first-order slopes (the stiffness measured on the MF tyre,
    the friction by PPY3)."""
    from mftyre.lane_change import simple_tyre_function

    model = problem.tyres["FL"]
    prm = model.params
    plain, with_p = simple_tyre_function(model), simple_tyre_function(model, pressure=True)
    fz0, p0 = float(prm.FNOMIN), float(prm.NOMPRES)
    for alpha in (-0.01, 0.02, 0.2):
        assert float(with_p(fz0, 0.0, alpha, 20.0, p0)[1]) == pytest.approx(float(plain(fz0, 0.0, alpha, 20.0, p0)[1]))

    def mf_stiffness(p):  # (the MF tyre's force at zero slip, its offset SVy, excluded)
        fy = model.evaluate(fz0, 0.0, np.array([0.0, -1e-4]), p=p).fy
        return float(fy[1] - fy[0]) / 1e-4

    def simple_stiffness(p):
        return float(with_p(fz0, 0.0, -1e-4, 20.0, p)[1]) / 1e-4

    for p in (0.95 * p0, 1.05 * p0):
        assert simple_stiffness(p) / simple_stiffness(p0) - 1 == pytest.approx(mf_stiffness(p) / mf_stiffness(p0) - 1,
                                                                                rel=0.1)
    # far beyond the peak the force is D Fz sin(C pi / 2): the friction's linear pressure term alone
    ratio = float(with_p(fz0, 0.0, -1.5, 20.0, 1.05 * p0)[1]) / float(with_p(fz0, 0.0, -1.5, 20.0, p0)[1])
    assert ratio == pytest.approx(1 + 0.05 * float(prm.PPY3), rel=1e-3)


def test_lane_change_rejects_bad_inputs(problem):
    from mftyre.errors import ModelInputError

    left = problem.tyres["FL"]
    with pytest.raises(ModelInputError, match="FR is mounted on the left"):
        LaneChange({"FL": left, "FR": left, "RL": left, "RR": problem.tyres["RR"]})
    with pytest.raises(ModelInputError, match="intervals"):
        LaneChange(problem.tyres, intervals=2)
    with pytest.raises(ModelInputError, match="route"):
        problem.build("mf", "fastest")
