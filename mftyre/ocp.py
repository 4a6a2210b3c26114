"""Exact derivatives of an optimal-control problem (NLP) that calls tyre functions at many points, assembled by the
chain rule from the problem's own SX part and the tyres' compiled derivative kernels (the lane change's route
``"assembled"``, :mod:`mftyre.lane_change`; benchmarks/bench_ocp.py).

CasADi differentiating an MX graph around a tyre called at every collocation node pays its MX evaluation of the
derivative graph and separate value, Jacobian, adjoint and Hessian calls of the tyre (the route ``"external"``);
expanding the problem (route ``"expand"``) copies the tyre's graph to every node. Here the vehicle part is SX with
the tyres' outputs as symbols, and each tyre contributes, per point, its value, its Jacobian J and the Hessian
H(mu) of mu^T y (mu: the multipliers the Lagrangian gives the tyre's outputs) from two fused kernels, mapped
over all points in one call each:

* :func:`mftyre.compiled.tyre_kernels`: from a tyre ``casadi.Function`` of scalars, (value, value + Jacobian,
  value + Jacobian + upper Hessian of mu^T y) as SX functions, common subexpressions shared;
* :func:`mftyre.compiled.compile_tyre_kernels`: the same three for an :class:`mftyre.MFModel`, compiled to C once
  (cached) and loaded with ``casadi.external``;
* :func:`assembled_nlp` (here): the NLP for ``casadi.nlpsol`` with its ``jac_g`` and ``hess_lag``.
"""
from __future__ import annotations

import numpy as np

__all__ = ["assembled_nlp"]


def _rows(matrix, count):
    """The first ``count`` rows of ``matrix``, each a 1 x n row (the arguments of a mapped scalar function)."""
    import casadi as ca

    return ca.vertsplit(matrix, list(range(count + 1)))


def assembled_nlp(w, f, g, inputs, outputs, kernels):
    """The NLP min f(w) s.t. g(w) with tyres called over many points, for ``casadi.nlpsol``: ``(nlp, options)``,
    the MX problem and its exact ``jac_g`` and ``hess_lag`` assembled by the chain rule.

    ``w``: the SX decision variables; ``f``, ``g``: SX expressions of ``w`` and of the tyres' outputs, the SX
    symbols ``outputs[k]`` (n_out x n: one column per point) of tyre k at ``inputs[k]`` (n_in x n SX expressions of
    ``w``); ``kernels[k]``: tyre k's (value, value_jacobian, value_hessian) (:func:`mftyre.compiled.tyre_kernels`,
    :func:`mftyre.compiled.compile_tyre_kernels`).

    With u(w) the tyre inputs, J the tyre Jacobians there and H(mu) the Hessians of mu^T y (mu = dL/dy, the
    multipliers the Lagrangian L gives the tyre outputs), the NLP's derivatives are those of the local model
    y ~ y(u0) + J d + d^T H d / 2 in d = u(w) - u(w0) at w0 = w, which SX differentiates: the constraint Jacobian
    g_w + g_y J u_w and the Hessian L_ww + L_wy J u_w + (L_wy J u_w)^T + u_w^T (J^T L_yy J + H(mu)) u_w
    + sum_i (J^T mu)_i u_i,ww. Per iteration the tyres cost one mapped value call (the constraints), one mapped
    value + Jacobian call (their Jacobian) and one mapped value + Jacobian + Hessian call; the rest is SX."""
    import casadi as ca

    w0, lam_f, lam_g = ca.SX.sym("w0", w.sparsity()), ca.SX.sym("lam_f"), ca.SX.sym("lam_g", g.numel())
    n_in = [u.size1() for u in inputs]
    n_out = [y.size1() for y in outputs]
    n = [y.size2() for y in outputs]
    jac = [ca.SX.sym(f"jac{k}", n_out[k] * n_in[k], n[k]) for k in range(len(outputs))]  # row o * n_in + i
    upper = [[(i, j) for i in range(m) for j in range(i, m)] for m in n_in]
    hess = [ca.SX.sym(f"hess{k}", len(upper[k]), n[k]) for k in range(len(outputs))]
    local, quadratic = [], 0.0
    for k, (u, y) in enumerate(zip(inputs, outputs)):
        d = u - ca.substitute(u, w, w0)  # zero at w0 = w, its derivatives those of u
        local.append(ca.vertcat(*(y[o, :] + sum(jac[k][o * n_in[k] + i, :] * d[i, :] for i in range(n_in[k]))
                                  for o in range(n_out[k]))))
        quadratic += sum(ca.sum2((0.5 if i == j else 1.0) * hess[k][r, :] * d[i, :] * d[j, :])
                         for r, (i, j) in enumerate(upper[k]))
    y_all = ca.vertcat(*(ca.vec(y) for y in outputs))
    f_local, g_local = (ca.substitute(e, y_all, ca.vertcat(*(ca.vec(y) for y in local))) for e in (f, g))
    hessian = ca.triu(ca.hessian(lam_f * f_local + ca.dot(lam_g, g_local) + quadratic, w)[0])
    multipliers = ca.jacobian(lam_f * f + ca.dot(lam_g, g), y_all).T  # dL/dy at the tyres' outputs
    sx_in = [w, w0, *outputs, *jac]
    jacobian_part = ca.Function("nlp_jac_g_local", sx_in, [g_local, ca.jacobian(g_local, w)])
    hessian_part = ca.Function("nlp_hess_l_local", [*sx_in, lam_f, lam_g, *hess], [hessian])
    tyre_inputs = ca.Function("tyre_inputs", [w], inputs)
    multiplier_part = ca.Function("tyre_multipliers", [w, *outputs, lam_f, lam_g], [multipliers])
    objective = ca.Function("nlp_f_local", [w, *outputs], [f])
    constraints = ca.Function("nlp_g_local", [w, *outputs], [g])

    x, p = ca.MX.sym("x", w.sparsity()), ca.MX.sym("p", 0, 1)
    mx_lam_f, mx_lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", g.numel())
    u = tyre_inputs(x)
    u = u if isinstance(u, (list, tuple)) else [u]
    rows = [_rows(u[k], n_in[k]) for k in range(len(kernels))]
    y = [ca.vertcat(*kernel[0].map(n[k])(*rows[k])) for k, kernel in enumerate(kernels)]
    g_mx = constraints(x, *y)
    f_mx = objective(x, *(y if ca.depends_on(f, y_all) else [ca.MX(v.sparsity()) for v in outputs]))

    y_jac, jacobians = [], []
    for k, kernel in enumerate(kernels):
        out = kernel[1].map(n[k])(*rows[k])
        y_jac.append(ca.vertcat(*out[:n_out[k]]))
        jacobians.append(ca.vertcat(*out[n_out[k]:]))
    jac_g = ca.Function("nlp_jac_g", [x, p], jacobian_part(x, x, *y_jac, *jacobians), ["x", "p"],
                        ["g", "jac_g_x"])

    # the multipliers of the tyres' outputs need the outputs only where the problem is not linear in them
    linear = not ca.depends_on(multipliers, y_all)
    mu = multiplier_part(x, *([ca.MX(v.sparsity()) for v in outputs] if linear else y), mx_lam_f, mx_lam_g)
    mu = ca.vertsplit(mu, [int(v) for v in np.cumsum([0] + [o * m for o, m in zip(n_out, n)])])
    y_hess, jacobians, hessians = [], [], []
    for k, kernel in enumerate(kernels):
        out = kernel[2].map(n[k])(*rows[k], *_rows(ca.reshape(mu[k], n_out[k], n[k]), n_out[k]))
        y_hess.append(ca.vertcat(*out[:n_out[k]]))
        jacobians.append(ca.vertcat(*out[n_out[k]:n_out[k] * (1 + n_in[k])]))
        hessians.append(ca.vertcat(*out[n_out[k] * (1 + n_in[k]):]))
    hess_lag = ca.Function("nlp_hess_l", [x, p, mx_lam_f, mx_lam_g],
                           [hessian_part(x, x, *y_hess, *jacobians, mx_lam_f, mx_lam_g, *hessians)],
                           ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    return {"x": x, "f": f_mx, "g": g_mx}, {"jac_g": jac_g, "hess_lag": hess_lag}
