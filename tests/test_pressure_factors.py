"""A file whose fitted pressure factor changes sign inside its declared pressure range (TNO_car205_60R15.tir:
PPY1 = -0.6249, so 1 + PPY1 dpi of the cornering stiffness is zero at 2.2 (1 + 1/0.6249) = 5.72 bar, PRESMAX
10 bar) still loads and checks without errors, and the evaluator and SWIFT warn once, naming the file, the
parameter and the pressure, when used beyond it."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import mftyre
from mftyre.inputs import pressure_factor_edges
from mftyre.tir import check_tir
from swift import Flat, StepInputs, SwiftTyre

from conftest import MFEVAL_DIR, SHARED, TIR_FILES, require_shared


def _tno_path():
    return require_shared(SHARED / "reference" / "tir" / "TNO_car205_60R15.tir")


def _caught(call):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    return [w for w in caught if issubclass(w.category, mftyre.PressureFactorWarning)]


def test_edge_is_where_the_cornering_stiffness_changes_sign():
    model = mftyre.load_tir(_tno_path())
    edges = {e[2].split(" ")[0]: e for e in pressure_factor_edges(model.params)}
    p_edge = 2.2e5 * (1.0 + 1.0 / 0.6249)  # 1 + PPY1 dpi = 0
    assert edges["PPY1"][0] == pytest.approx(p_edge, rel=1e-9) and edges["PPY1"][1] == 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kya = model.evaluate(4000.0, 0.0, 0.0, p=[0.99 * p_edge, 1.01 * p_edge]).kya
    assert kya[0] * kya[1] < 0  # the model itself: the cornering stiffness does change sign there


def test_file_loads_and_checks_without_errors_and_names_the_factor():
    findings = check_tir(_tno_path())
    assert not [f for f in findings if f.severity == "error"]
    named = [f for f in findings if f.parameter == "PPY1"]
    assert len(named) == 1 and named[0].severity == "warning" and "572056" in named[0].message


def test_evaluator_warns_once_beyond_the_edge():
    model = mftyre.load_tir(_tno_path())
    assert not _caught(lambda: model.evaluate(4000.0, 0.0, 0.05, p=np.linspace(1.8e5, 5.6e5, 5)))
    first = _caught(lambda: model.evaluate(4000.0, 0.0, 0.05, p=6e5))
    assert len(first) == 1
    message = str(first[0].message)
    assert "TNO_car205_60R15.tir" in message and "PPY1 = -0.6249" in message and "572056" in message
    assert "600000" in message
    assert not _caught(lambda: model.evaluate(4000.0, 0.0, 0.05, p=7e5))  # once per model and factor


def test_saturated_pressure_is_what_counts():
    """limits=True evaluates PRESMAX where p exceeds it: a file whose factor changes sign only beyond PRESMAX
    does not warn then, and warns with limits=False."""
    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")
    prm = model.params
    p_zero = prm.NOMPRES * (1.0 + 1.0 / 0.5)  # 1 - 0.5 dpi = 0: beyond PRESMAX 2.55 bar
    bent = model.with_params(PPY1=-0.5)
    assert not _caught(lambda: bent.evaluate(4000.0, 0.0, 0.05, p=1.2 * p_zero))
    assert len(_caught(lambda: bent.evaluate(4000.0, 0.0, 0.05, p=1.2 * p_zero, limits=False))) == 1
    assert prm.PRESMAX < p_zero


@pytest.mark.parametrize("name", ["MagicFormula61_Parameters.tir", "MagicFormula62_Parameters.tir"])
def test_other_files_do_not_warn_in_their_range(name):
    model = mftyre.load_tir(require_shared(MFEVAL_DIR / name))
    prm = model.params
    assert not _caught(lambda: model.evaluate(4000.0, 0.0, 0.05, p=np.linspace(prm.PRESMIN, prm.PRESMAX, 7)))


def test_swift_warns_beyond_the_edge():
    model = mftyre.load_tir(_tno_path())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tyre = SwiftTyre(model, Flat(), x_range=(0.0, 2.0), compiled=False)
    rl, _ = model.loaded_radius(4000.0, p=6e5)
    u = StepInputs(x=0.5, vx=10.0, z=float(rl), omega=10.0 / 0.3, p=6e5)
    caught = _caught(lambda: tyre.initial_state(u))
    assert len(caught) == 1 and "PPY1" in str(caught[0].message) and "600000" in str(caught[0].message)


def test_eval_command_names_the_file_once(capsys):
    from mftyre import cli

    path = _tno_path()
    assert cli.main(["eval", str(path), "--p", "6bar"]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if "PPY1" in line]
    assert len(err) == 1 and err[0].count(path.name) == 1 and "5.72 bar" in err[0]
