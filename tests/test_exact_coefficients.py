"""NumPy array evaluations read .tir coefficients that are exactly 0 or 1 as ExactCoefficient (mftyre.backend), so
that a unit scaling factor or an absent term costs no array operation. The folding must not change a result: the
outputs equal, bit for bit, those of the same equations on plain floats, in every mode, on files of every version.
"""
from __future__ import annotations

import numpy as np
import pytest

import mftyre
from mftyre.backend import NUMPY, NUMPY_FOLDING, ExactCoefficient
from mftyre.formula import Modes, steady_state
from mftyre.model import _PlainParameters

from conftest import MFEVAL_DIR, TIR_FILES

ZERO, ONE = NUMPY.known_coefficients({"zero": 0.0, "one": 1.0}).values()
FILES = [TIR_FILES / "car_205_60R15_mf61.tir", TIR_FILES / "car_205_60R15_mf62_swift.tir",
         MFEVAL_DIR / "MagicFormula52_Parameters.tir", MFEVAL_DIR / "MagicFormula62_Parameters.tir"]
MODES = [Modes(limits=limits, alpha_star=alpha_star, turn_slip=turn_slip, turn_slip_form=form)
         for limits in (True, False, "smooth") for alpha_star in (False, True)
         for turn_slip, form in ((False, "published"), (True, "published"), (True, "mfeval"))]


def test_identities_are_skipped_and_the_rest_computed():
    x = np.array([-2.0, 0.0, 3.5])
    assert x * ONE is x and ONE * x is x and x / ONE is x
    assert x + ZERO is x and ZERO + x is x and x - ZERO is x
    assert ZERO * x is ZERO and x * ZERO is ZERO and ZERO / x is ZERO
    np.testing.assert_array_equal(ZERO - x, -x)
    np.testing.assert_array_equal(x + ONE, x + 1.0)
    np.testing.assert_array_equal(ONE / np.array([2.0, 4.0]), [0.5, 0.25])
    np.testing.assert_array_equal(np.maximum(x, ZERO), [0.0, 0.0, 3.5])
    # between numbers: the exact float result, kept an ExactCoefficient where it is 0 or 1
    assert type(1.0 + ZERO * x) is ExactCoefficient and 1.0 + ZERO * x == 1.0
    assert type(ONE - 1.0) is ExactCoefficient and ONE - 1.0 == 0.0
    assert type(ONE * 2.5) is float and ONE * 2.5 == 2.5
    assert type(np.sin(ZERO)) is ExactCoefficient and np.cos(ZERO) == 1.0
    assert ONE ** 3 is ONE and -ZERO == 0.0 and 2 * ONE == 2.0


def test_only_zero_and_one_become_exact():
    values = NUMPY.known_coefficients({"A": 0.0, "B": 1.0, "C": 0.5, "D": -1.0, "N": 3, "S": "LEFT"})
    assert [type(values[k]) for k in "ABCD"] == [ExactCoefficient, ExactCoefficient, float, float]
    assert type(ZERO) is ExactCoefficient and ZERO == 0.0 and type(ONE) is ExactCoefficient and ONE == 1.0
    assert values["N"] == 3 and values["S"] == "LEFT"


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_outputs_bit_identical_to_plain_floats(path):
    if not path.exists():
        pytest.skip(f"{path} not found (../shared beside the project)")
    params = mftyre.load_tir(path).params
    rng = np.random.default_rng(3)
    n = 400
    fz = rng.uniform(-0.2, 2.5, n) * params.FNOMIN
    kappa, alpha = rng.uniform(-1.2, 1.2, n), rng.uniform(-0.5, 0.5, n)
    gamma, phit = rng.uniform(-0.15, 0.15, n), rng.uniform(-1.0, 1.0, n)
    vx, p = rng.uniform(-40.0, 40.0, n), rng.uniform(0.7, 1.3, n) * params.NOMPRES
    fz[::17], vx[::23], gamma[::7], kappa[::11], alpha[::13], phit[::3] = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    inputs = (fz, kappa, alpha, gamma, phit, vx, p, np.zeros(n), False)
    plain, exact = _PlainParameters(params), _PlainParameters(params, exact=True)
    assert any(type(v) is ExactCoefficient for v in vars(exact).values())
    for modes in MODES:
        with np.errstate(all="ignore"):
            expected = steady_state(plain, *inputs, modes, NUMPY)
            got = steady_state(exact, *inputs, modes, NUMPY_FOLDING)
        for name, value in expected.items():
            np.testing.assert_array_equal(np.broadcast_to(got[name], (n,)), np.broadcast_to(value, (n,)),
                                          err_msg=f"{name} {modes}")
