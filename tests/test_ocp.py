"""mftyre.ocp: the NLP derivatives assembled from tyre kernels equal CasADi's own (automatic differentiation of the
same problem with the tyre inline) on the MF tyre, for a problem that is nonlinear in the tyre outputs, uses them
in the objective and couples several points through shared variables; the kernels themselves equal CasADi's
Jacobian and Hessian of the tyre."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

ca = pytest.importorskip("casadi")

from mftyre.model import load_tir  # noqa: E402
from mftyre.compiled import tyre_kernels  # noqa: E402
from mftyre.ocp import assembled_nlp  # noqa: E402

from conftest import TIR_FILES  # noqa: E402

INPUTS, OUTPUTS = ("fz", "kappa", "alpha", "vx", "p"), ("fx", "fy", "mz")


@pytest.fixture(scope="module")
def tyre():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = load_tir(TIR_FILES / "car_205_60R15_mf61.tir")
    return model.casadi_function(INPUTS, OUTPUTS, limits="smooth", smooth=True, name="mf")


def _relative_error(a, b):
    a, b = np.asarray(ca.DM(a)), np.asarray(ca.DM(b))
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_kernels_equal_casadis_jacobian_and_hessian(tyre):
    value, value_jacobian, value_hessian = tyre_kernels(tyre)
    u = [4000.0, 0.05, -0.08, 18.0, 2.1e5]
    mu = [0.7, -1.3, 2.0]
    x = ca.vertcat(*tyre.sx_in())
    y = ca.vertcat(*tyre.call(tyre.sx_in()))
    jacobian = ca.Function("j", tyre.sx_in(), [ca.jacobian(y, x)])(*u)
    hessian = ca.Function("h", tyre.sx_in(), [ca.hessian(ca.dot(ca.DM(mu), y), x)[0]])(*u)
    out = value_hessian(*u, *mu)
    n_in, n_out = len(INPUTS), len(OUTPUTS)
    assert _relative_error(ca.vertcat(*value(*u)), ca.vertcat(*tyre(*u))) < 1e-14
    assert _relative_error(ca.vertcat(*value_jacobian(*u)[n_out:]), ca.vec(jacobian.T)) < 1e-12
    assert _relative_error(ca.vertcat(*out[n_out:n_out * (1 + n_in)]), ca.vec(jacobian.T)) < 1e-12
    upper = [hessian[i, j] for i in range(n_in) for j in range(i, n_in)]
    assert _relative_error(ca.vertcat(*out[n_out * (1 + n_in):]), ca.vertcat(*upper)) < 1e-12


def test_assembled_jacobian_and_hessian_equal_casadis_own(tyre):
    """A small NLP: 3 points whose tyre inputs share a pressure and a speed, constraints and objective nonlinear
    in the tyre outputs and the variables; jac_g and hess_lag at a random point against nlpsol's own."""
    n = 3
    w = ca.SX.sym("w", 2 * n + 3)
    fz, alpha, kappa, vx, p = 3000 + 1000 * ca.sin(w[:n]), 0.1 * ca.tanh(w[n:2 * n]), 0.05 * w[-3] * w[:n], \
        15 + w[-2] ** 2, 2e5 * (1 + 0.1 * w[-1])
    inputs = [ca.vertcat(fz.T, kappa.T, alpha.T, ca.repmat(vx, 1, n), ca.repmat(p, 1, n))]
    outputs = [ca.SX.sym("y", 3, n)]

    def problem(y):
        fx, fy, mz = y[0, :], y[1, :], y[2, :]
        g = ca.vertcat((fy * ca.cos(w[n:2 * n].T) + fx ** 2 / 1e3).T, (mz * fy / 1e4 + w[-1] * fx).T,
                       ca.sum2(fy) / 1e3 + w[-2] * w[-3])
        return ca.sumsqr(w) + ca.sum2(fy * mz) / 1e5, g

    f, g = problem(outputs[0])
    nlp, options = assembled_nlp(w, f, g, inputs, outputs, [tyre_kernels(tyre)])
    # CasADi's own: the same problem with the tyre inline
    x = ca.MX.sym("x", w.numel())
    u = ca.Function("u", [w], inputs)(x)
    y = ca.vertcat(*tyre.map(n)(*ca.vertsplit(u, list(range(6)))))
    f_mx, g_mx = ca.Function("fg", [w, outputs[0]], problem(outputs[0]))(x, y)
    reference = ca.nlpsol("reference", "ipopt", {"x": x, "f": f_mx, "g": g_mx}, {"print_time": False})
    assembled = ca.nlpsol("assembled", "ipopt", nlp, {"print_time": False, **options})
    rng = np.random.default_rng(7)
    point = [rng.uniform(-1, 1, w.numel()), [], rng.uniform(0.5, 2.0), rng.uniform(-2, 2, g.numel())]
    for name, args in (("nlp_jac_g", point[:2]), ("nlp_hess_l", point), ("nlp_g", point[:2]),
                       ("nlp_f", point[:2])):
        ours, theirs = assembled.get_function(name)(*args), reference.get_function(name)(*args)
        ours, theirs = ours if isinstance(ours, (list, tuple)) else [ours], \
            theirs if isinstance(theirs, (list, tuple)) else [theirs]
        for a, b in zip(ours, theirs):
            a, b = ca.DM(a), ca.DM(b)
            if a.shape[0] == a.shape[1] and a.shape[0] > 1 and name == "nlp_hess_l":
                a, b = ca.triu(a), ca.triu(b)
            assert a.shape == b.shape
            assert _relative_error(a, b) < 1e-9, name
    # the assembled problem is the same NLP: IPOPT reaches the same optimum
    bounds = dict(x0=np.zeros(w.numel()), lbx=-2, ubx=2, lbg=-np.inf, ubg=np.r_[np.full(2 * n, 5.0), 3.0])
    a, b = assembled(**bounds), reference(**bounds)
    assert assembled.stats()["success"] and reference.stats()["success"]
    assert _relative_error(a["x"], b["x"]) < 1e-6
