"""Finite first derivatives of every force and moment at the awkward points an optimiser reaches: standstill
(vx = 0 exactly, and a hair away from it), zero load, and every .tir range bound (kappa, alpha, gamma, p at
their limits, Fz at FZMAX), for limits True, False and "smooth", exact and smoothed kinks, with and without turn
slip, and with the slip-speed friction decay LMUV switched on (its sqrt(Vsx^2 + Vsy^2) vanishes at zero slip).
On the old code the Mz Jacobian was NaN at vx = 0 (sqrt(Vx^2 + Vsy^2) and sqrt(tan^2 alpha_t + ...) have an
infinite slope at 0, times a zero one)."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

import mftyre

from conftest import MFEVAL_DIR, TIR_FILES, require_shared

INPUTS = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p")
OUTPUTS = ("fx", "fy", "mz", "mx", "my", "rl")


def _grid(model):
    prm = model.params
    kappa, alpha, gamma, p = (model.input_range(n) for n in ("kappa", "alpha", "gamma", "p"))
    values = dict(fz=[0.0, 1e-9, 3000.0, prm.FZMAX], kappa=[kappa[0], 0.0, 0.05, kappa[1]],
                  alpha=[alpha[0], 0.0, 0.05, alpha[1]], gamma=[gamma[0], 0.0, gamma[1]], phit=[0.0, 0.2],
                  vx=[0.0, 1e-9, -1e-9, prm.VXLOW, 15.0], p=[p[0], p[1]])
    return np.array(list(itertools.product(*values.values()))).T


@pytest.mark.parametrize("path, lmuv", [(TIR_FILES / "car_205_60R15_mf61.tir", 0.0),
                                        (TIR_FILES / "car_205_60R15_mf62_swift.tir", 0.5),
                                        (MFEVAL_DIR / "MagicFormula62_Parameters.tir", None)],
                         ids=["mf61", "mf62_lmuv", "mfeval_mf62"])
@pytest.mark.parametrize("limits, smooth, turn_slip", [(True, None, False), (False, None, "published"),
                                                       (True, None, "mfeval"), ("smooth", 1e-6, "published")])
def test_jacobian_finite_at_standstill_zero_load_and_range_bounds(path, lmuv, limits, smooth, turn_slip):
    import casadi as ca

    model = mftyre.load_tir(require_shared(path))
    if lmuv is not None:
        model = model.with_params(LMUV=lmuv)
    f = model.casadi_function(INPUTS, OUTPUTS, limits=limits, smooth=smooth, turn_slip=bool(turn_slip),
                              turn_slip_form=turn_slip or "published")
    x = ca.SX.sym("x", len(INPUTS))
    out = ca.vertcat(*f(*ca.vertsplit(x)))
    jac = ca.Function("jacobian", [x], [ca.densify(ca.jacobian(out, x))])
    points = _grid(model)
    values = np.array(jac.map(points.shape[1])(points)).reshape(len(OUTPUTS), points.shape[1], len(INPUTS))
    bad = ~np.isfinite(values)
    where = [(dict(zip(INPUTS, points[:, j])), [f"d{OUTPUTS[o]}/d{INPUTS[i]}" for o, i in np.argwhere(bad[:, j])])
             for j in np.nonzero(bad.any(axis=(0, 2)))[0][:3]]
    assert not bad.any(), f"{bad.any(axis=(0, 2)).sum()} of {points.shape[1]} points: {where}"
