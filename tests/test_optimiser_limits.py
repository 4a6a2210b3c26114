"""casadi_function's default limits are safe for optimisers: a user's problem with the pressure bounded to
PRESMIN..PRESMAX, IPOPT with its default options, ends a hair outside the active bound (bound_relax_factor); there
the tyre keeps its full slope, so the bound multiplier IPOPT reports is the design sensitivity, checked against
finite differences of the optimum. (On the old code the plain clip made the tyre flat at 1e-12 outside the bound:
the multiplier came out 0, against 0.405 kN/bar, with no warning.) NumPy keeps the exact clip with its warning."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

ca = pytest.importorskip("casadi")

import mftyre  # noqa: E402
from mftyre.backend import LIMITS_SLACK  # noqa: E402
from mftyre.errors import InputClippedWarning  # noqa: E402

from conftest import TIR_FILES  # noqa: E402

TIR = TIR_FILES / "car_205_60R15_mf61.tir"


@pytest.fixture(scope="module")
def model():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(TIR)


def test_the_peak_side_force_bound_multiplier_is_the_sensitivity_of_the_optimum(model):
    """max |Fy| over alpha in [0, 0.25] and p in PRESMIN..PRESMAX [bar] at 4 kN (a user's problem, written from the
    README): the optimum lies on PRESMIN; IPOPT's multiplier equals d(optimum)/d(PRESMIN) by finite differences
    (re-solved with the bound moved inwards by h and 2h, second order)."""
    prm = model.params
    f = model.casadi_function(("alpha", "p"), ("fy",), fixed={"fz": 4000.0, "kappa": 0.0})
    x = ca.SX.sym("x", 2)
    solver = ca.nlpsol("peak", "ipopt", {"x": x, "f": f(x[0], 1e5 * x[1]) / 1000.0},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes"})

    def solve(lo, hi):
        r = solver(x0=[0.05, 0.5 * (lo + hi)], lbx=[0.0, lo], ubx=[0.25, hi])
        assert solver.stats()["success"], solver.stats()["return_status"]
        return float(r["f"]), np.array(r["x"]).ravel(), np.array(r["lam_x"]).ravel()

    lo, hi = prm.PRESMIN / 1e5, prm.PRESMAX / 1e5
    best, x_opt, lam = solve(lo, hi)
    assert x_opt[1] == pytest.approx(lo, abs=1e-6) and 0.05 < x_opt[0] < 0.25  # on PRESMIN, at the peak slip
    h = 1e-4
    j1, j2 = solve(lo + h, hi)[0], solve(lo + 2 * h, hi)[0]
    sensitivity = (4.0 * (j1 - best) - (j2 - best)) / (2.0 * h)  # d(optimum)/d(lower bound) [kN/bar]
    assert sensitivity > 0.1
    assert -lam[1] == pytest.approx(sensitivity, rel=1e-4)  # old code: lam 5e-18


def test_the_symbolic_saturation_keeps_the_slope_a_margin_beyond_the_bound_then_holds(model):
    """Beyond PRESMAX by d = LIMITS_SLACK PRESMAX: the full slope (100 times IPOPT's relaxation); beyond 2 d: the
    value at the bound, NumPy's exact clip (which warns)."""
    prm = model.params
    f = model.casadi_function(("p",), ("fy",), fixed={"fz": 4000.0, "kappa": 0.0, "alpha": 0.05})
    p = ca.SX.sym("p")
    slope = ca.Function("slope", [p], [ca.jacobian(f(p), p)])
    d = LIMITS_SLACK * prm.PRESMAX
    inside = float(slope(prm.PRESMAX - 1.0))
    assert float(slope(prm.PRESMAX + 1e-8 * prm.PRESMAX)) == pytest.approx(inside, rel=1e-3)
    assert float(slope(prm.PRESMAX + 0.5 * d)) == pytest.approx(inside, rel=1e-3) and inside != 0
    assert float(slope(prm.PRESMAX + 3 * d)) == 0.0
    with pytest.warns(InputClippedWarning, match="p outside PRESMIN..PRESMAX"):
        far = model.evaluate(4000.0, 0.0, 0.05, p=prm.PRESMAX + 3 * d)
    at = model.evaluate(4000.0, 0.0, 0.05, p=prm.PRESMAX)
    assert float(f(prm.PRESMAX + 3 * d)) == pytest.approx(float(far.fy), rel=1e-12) == float(at.fy)
