"""The turn-slip moment's shape factor C_r = (2/pi) acos(M_zphi90 / |D_rphi|) (Pacejka 2012 (4.104)) at zero turn
slip and zero camber: both M_zphi90 (4.103) and D_rphi (4.93) are 0 there, and the evaluator takes the ratio at its
limit (the ratio of their slopes in R0 phit), so that M_z is continuous in phit through 0 with a finite derivative,
in NumPy and CasADi, in the published and the reference evaluator's form. (It held C_r = 1 at phit = 0 exactly, its
limit beside 0 being another value: M_z jumped by 0.065 of 15.4 N m on the sample file at 4 kN and 0.1 rad, by 0.77
of 183 N m on the 420/85 R24 file, and CasADi's derivative at 0 was 10 % off the one beside it.)"""
from __future__ import annotations

import warnings

import casadi as ca
import numpy as np
import pytest

import mftyre
from conftest import MFEVAL_DIR, TIR_FILES, require_shared

FILES = [("sample", lambda: TIR_FILES / "car_205_60R15_mf62_swift.tir"),
         ("agri", lambda: TIR_FILES / "agri_420_85R24_mf61.tir"),
         ("mfeval62", lambda: require_shared(MFEVAL_DIR / "MagicFormula62_Parameters.tir"))]
TINY = np.array([-1e-6, -1e-9, -1e-20, 1e-20, 1e-9, 1e-6])  # R0 phit of order 1e-7 .. 1e-21


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(path())


@pytest.mark.parametrize("form", ["published", "mfeval"])
@pytest.mark.parametrize("name, path", FILES, ids=[f[0] for f in FILES])
def test_mz_is_continuous_through_zero_turn_slip(name, path, form):
    """gamma = 0: M_z (and M_zr) at phit = 0 equal their values at |phit| <= 1e-6 1/m to within the change that the
    slope there explains, at several slip angles and loads."""
    model = _load(path)
    fz0 = model.params.FNOMIN
    for fz in (0.5 * fz0, fz0, 1.5 * fz0):
        for alpha in (-0.2, 0.0, 0.1):
            at = model.evaluate(fz, 0.0, alpha, 0.0, np.concatenate([[0.0], TINY]), vx=10.0, turn_slip=True,
                                turn_slip_form=form)
            for name_ in ("mz", "mzr"):
                values = at[name_]
                slope = (values[-1] - values[1]) / (TINY[-1] - TINY[0])
                allowed = abs(slope) * np.abs(TINY) * 2 + 1e-9 * max(1.0, abs(values[0]))
                assert np.all(np.abs(values[1:] - values[0]) <= allowed), (name_, fz, alpha, values[0], values[1:])


@pytest.mark.parametrize("form", ["published", "mfeval"])
@pytest.mark.parametrize("name, path", FILES, ids=[f[0] for f in FILES])
def test_casadi_derivative_in_turn_slip_is_finite_and_continuous(name, path, form):
    """dM_z/dphit of the CasADi graph at phit = 0 and at tiny phit equals the central difference over +-1e-5 1/m
    (the function is smooth there) to 1e-3, and the graph's value equals NumPy's."""
    model = _load(path)
    fz = model.params.FNOMIN
    f = model.casadi_function(inputs=("fz", "kappa", "alpha", "gamma", "phit", "vx"), outputs=("mz",),
                              turn_slip=True, turn_slip_form=form)
    phit = ca.SX.sym("phit")
    mz = f(fz, 0.0, 0.1, 0.0, phit, 10.0)
    graph = ca.Function("d", [phit], [mz, ca.jacobian(mz, phit)])
    h = 1e-5
    for at in np.concatenate([[0.0], TINY]):
        value, derivative = (float(v) for v in graph(at))
        central = (float(graph(at + h)[0]) - float(graph(at - h)[0])) / (2 * h)
        assert np.isfinite(derivative)
        assert derivative == pytest.approx(central, rel=1e-3, abs=1e-6 * max(1.0, abs(value))), at
        numpy = float(model.evaluate(fz, 0.0, 0.1, 0.0, at, vx=10.0, turn_slip=True, turn_slip_form=form).mz)
        assert value == pytest.approx(numpy, rel=1e-9, abs=1e-9), at
