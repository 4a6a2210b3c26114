"""The Magic Formula evaluator warns (LoadFactorWarning, once per model and factor) where it is used at loads beyond
which a slip stiffness of the file has the opposite sign to the one at FNOMIN (mftyre.inputs.load_factor_edges), as
SWIFT, the FMU build and `mftyre check` do: FSAE_Defaults.tir of MFeval (PKX1 = 50, PKX2 = -80: K_xk < 0 above
1625 N, FZMAX 2000 N). Files without such an edge up to FZMAX never warn."""
from __future__ import annotations

import threading
import warnings

import numpy as np
import pytest

import mftyre
from mftyre.inputs import load_factor_problems

from conftest import MFEVAL_DIR, SHARED, TIR_FILES, require_shared


def _fsae():
    return mftyre.load_tir(require_shared(MFEVAL_DIR / "FSAE_Defaults.tir"))


def _caught(call):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    return [str(w.message) for w in caught if issubclass(w.category, mftyre.LoadFactorWarning)]


def test_fsae_warns_beyond_its_k_xk_edge_once():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kxk = _fsae().evaluate([1500.0, 1700.0], 0.0, 0.0).kxk
    model = _fsae()
    assert kxk[0] > 0.0 > kxk[1]  # the model itself: the slip stiffness does change sign in between
    assert not _caught(lambda: model.evaluate(np.linspace(0.0, 1500.0, 7), 0.05, 0.0))
    first = _caught(lambda: model.evaluate(1700.0, 0.05, 0.0))
    assert len(first) == 1, first
    assert "FSAE_Defaults.tir" in first[0] and "PKX1 = 50, PKX2 = -80" in first[0] and "1625 N" in first[0]
    assert "Fz = 1700 N, above it" in first[0]
    assert not _caught(lambda: model.evaluate([1000.0, 1900.0], 0.05, 0.0))  # once per model and factor
    assert len(_caught(lambda: _fsae().evaluate([1000.0, 1900.0], 0.05, 0.0))) == 1  # a new model warns again


def test_saturated_load_is_what_counts():
    """limits=True evaluates FZMAX where Fz exceeds it: an edge beyond FZMAX warns only with limits=False."""
    model = _fsae().with_params(PKX2=-40.0)  # K_xk = 0 at 2250 N, FZMAX 2000 N
    assert not _caught(lambda: model.evaluate(2400.0, 0.05, 0.0))
    found = _caught(lambda: model.evaluate(2400.0, 0.05, 0.0, limits=False))
    assert len(found) == 1 and "2250 N" in found[0]


def test_warns_once_from_many_threads():
    model = _fsae()
    barrier = threading.Barrier(6)

    def run():
        barrier.wait()
        for _ in range(20):
            model.evaluate(1800.0, 0.05, 0.0)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        threads = [threading.Thread(target=run) for _ in range(6)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    assert len([w for w in caught if issubclass(w.category, mftyre.LoadFactorWarning)]) == 1


def _all_files():
    shared = [MFEVAL_DIR / n for n in ("FSAE_Defaults.tir", "MagicFormula52_Parameters.tir",
                                       "MagicFormula61_Parameters.tir", "MagicFormula62_Parameters.tir",
                                       "PacejkaBook_Defaults.tir")]
    shared.append(SHARED / "reference" / "tir" / "TNO_car205_60R15.tir")
    return sorted(TIR_FILES.glob("*.tir")) + shared


@pytest.mark.parametrize("path", _all_files(), ids=lambda p: p.name)
def test_files_warn_only_where_they_have_an_edge_up_to_fzmax(path):
    """Every bundled and shared file at loads 0..FZMAX and PRESMIN, INFLPRES, PRESMAX: a warning exactly where
    `mftyre check` finds an edge inside FZMAX (FSAE only)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(require_shared(path))
    prm = model.params
    loads = np.linspace(0.0, prm.FZMAX, 41)
    found = _caught(lambda: [model.evaluate(loads, 0.05, 0.02, p=p) for p in (prm.PRESMIN, prm.INFLPRES,
                                                                               prm.PRESMAX)])
    assert bool(found) == bool(load_factor_problems(prm)), found
    assert bool(found) == (path.name == "FSAE_Defaults.tir")
