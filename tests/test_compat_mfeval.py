"""compat.mfeval: the deflection reported at zero load follows MFeval's version branches."""
from __future__ import annotations

import warnings

import numpy as np

import mftyre
from mftyre.params import MissingParameterWarning
from mftyre.compat import MFEVAL_COLUMNS, mfeval

from conftest import MFEVAL_DIR, require_shared

RHO = MFEVAL_COLUMNS.index("rho")


def _load(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingParameterWarning)
        return mftyre.load_tir(require_shared(MFEVAL_DIR / name))


def test_mf52_zero_load_reports_the_computed_deflection():
    """MF 5.2: the deflection at FZMIN (limit checks raise the load to FZMIN), FZMIN/Cz = 100/463000 = 2.16e-4 m
    for the nearly linear sample tyre (Q_FZ2 = 1e-4), not MF 6.x's placeholder 1e-6 m."""
    model = _load("MagicFormula52_Parameters.tir")
    prm = model.params
    rows = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 16.7], [0.0, 0.05, 0.1, 0.0, 0.0, 10.0]])
    rho = mfeval(model, rows, 111)[:, RHO]
    np.testing.assert_allclose(rho, prm.FZMIN / prm.VERTICAL_STIFFNESS, rtol=1e-3)
    assert abs(rho[0] - 2.16e-4) < 1e-6
    # limits off: no load, MFeval's placeholder 1e-6 m (its MF 5.2 branch is its MF 6.1 one; MFeval 4.3.1 under
    # Octave gives 1e-6 there, tests/data/mfeval_extra/MagicFormula52_Parameters.csv.gz)
    np.testing.assert_array_equal(mfeval(model, rows, 211)[:, RHO], 1e-6)


def test_mf61_zero_load_keeps_the_placeholder():
    model = _load("MagicFormula61_Parameters.tir")
    rows = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 16.7]])
    assert mfeval(model, rows, 111)[0, RHO] == 1e-6
