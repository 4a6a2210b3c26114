"""compat.mfeval and turn_slip_form="mfeval" against MFeval 4.3.1 where the shared tables are silent: loads from 0 to
1.5 FZMAX, speeds around VXLOW and far above LONGVL, pressures beyond PRESMIN..PRESMAX, every use mode, every
sample file (tables made by tests/data/mfeval_extra/make_tables.py with MFeval run by GNU Octave; these tests read
the tables only). A cell MFeval answers with NaN or inf is no reference (e.g. Cz where its MF 6.1 deflection divides
by 2 Q_FZ2 = 0); every other cell is, MFeval's artefacts included (its MF 6.2 secant iterate where it stopped short of
its tolerance, its MF 6.1 root without bottoming): compat returns them, with a warning."""
from __future__ import annotations

import gzip
import hashlib
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import mftyre
from mftyre.compat import MFEVAL_COLUMNS, mfeval
from mftyre.errors import InputClippedWarning, ReferenceValueWarning

from conftest import MFEVAL_DIR, TIR_FILES

TABLES = Path(__file__).parent / "data" / "mfeval_extra"
MANIFEST = json.loads((TABLES / "manifest.json").read_text())
FILES = sorted(MANIFEST["files"])

FORCES = ("Fx", "Fy", "Fz")
MOMENTS = ("Mx", "My", "Mz", "Mzr")
#: relative tolerance of every column (with an absolute floor 1e-3 times the column's scale)
TOLERANCE = 1e-9


def tir_path(name: str) -> Path:
    info = MANIFEST["files"][name]
    path = (TIR_FILES if info["where"] == "tir_files" else MFEVAL_DIR) / name
    if not path.exists():
        pytest.skip(f"{path} not found: the MFeval sample files live in ../shared beside the project (present in "
                    "CI, absent in a user's clone)")
    if hashlib.md5(path.read_bytes()).hexdigest() != info["md5"]:
        pytest.skip(f"{path} differs from the file the MFeval table was made from (md5 {info['md5']})")
    return path


def read_table(name: str) -> dict:
    with gzip.open(TABLES / MANIFEST["files"][name]["table"], "rt") as f:
        header = f.readline().strip().split(",")
        data = np.loadtxt(f, delimiter=",", ndmin=2)
    return {h: data[:, j] for j, h in enumerate(header)}


def load(name: str) -> mftyre.MFModel:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(tir_path(name))


def evaluate_table(model, table) -> np.ndarray:
    """compat.mfeval of every row of ``table``, rows of one (useMode, ncols) in one call (compat decides per row)."""
    inputs = np.column_stack([table[c] for c in ("in_Fz", "in_kappa", "in_alpha", "in_gamma", "in_phit", "in_Vx",
                                                 "in_P", "in_omega")])
    result = np.full((len(inputs), len(MFEVAL_COLUMNS)), np.nan)
    for mode in np.unique(table["useMode"]):
        for ncols in (7, 8):
            rows = (table["useMode"] == mode) & (table["ncols"] == ncols)
            if rows.any():
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    result[rows] = mfeval(model, inputs[rows, :ncols], int(mode), turn_slip_form="mfeval")
    return result


def errors(model, table, result) -> dict:
    """{column: (max scaled error, row)} over the cells MFeval answers."""
    prm = model.params
    scale = {**{c: prm.FNOMIN for c in FORCES}, **{c: prm.FNOMIN * prm.UNLOADED_RADIUS for c in MOMENTS},
             "Rl": prm.UNLOADED_RADIUS, "rho": prm.UNLOADED_RADIUS, "Cz": prm.VERTICAL_STIFFNESS}
    out = {}
    for j, col in enumerate(MFEVAL_COLUMNS):
        if col == "iKya":
            continue
        ref, got = table[col], result[:, j]
        valid = np.isfinite(ref)
        with np.errstate(invalid="ignore"):
            err = np.abs(got - ref) / np.maximum(np.abs(ref), 1e-3 * scale.get(col, 1.0))
        err = np.where(valid, err, 0.0)
        err = np.where(valid & ~np.isfinite(got), np.inf, err)
        i = int(np.argmax(err))
        out[col] = (float(err[i]), i)
    return out


@pytest.fixture(scope="module")
def evaluated():
    cache = {}

    def get(name):
        if name not in cache:
            model = load(name)
            table = read_table(name)
            cache[name] = model, table, evaluate_table(model, table)
        return cache[name]

    return get


@pytest.mark.parametrize("name", FILES)
def test_compat_equals_mfeval_everywhere_it_answers(name, evaluated):
    """Every output of every row to 1e-9 relative (floors 1e-12 FNOMIN, FNOMIN R0 for forces and moments near zero,
    1e-12 R0, 1e-12 Cz0 for the radii and Cz, 1e-12 of the unit elsewhere). Before: Re, 2a, 2b, My, Rl above
    FZMAX (held at FZMAX), omega and the turn-slip forces ~1e-8 (the converged spin, not MFeval's iterate), the MF 6.1
    deflection beyond bottoming, the MF 6.2 Rl where MFeval's secant stops short."""
    model, table, result = evaluated(name)
    bad = {}
    for col, (err, i) in errors(model, table, result).items():
        if not err <= TOLERANCE:
            bad[col] = (err, {k: table[k][i] for k in ("in_Fz", "in_Vx", "in_P", "useMode", "ncols")},
                        result[i, MFEVAL_COLUMNS.index(col)], table[col][i])
    assert not bad, bad


@pytest.mark.parametrize("name", FILES)
def test_the_tables_cover_what_the_shared_ones_leave_out(name):
    """The regions of the issue are in every table: loads to 1.5 FZMAX, speeds to 30 LONGVL, pressures beyond the
    range, all eight use modes, omega given and estimated."""
    table = read_table(name)
    model = load(name)
    prm = model.params
    assert table["in_Fz"].max() >= 1.5 * prm.FZMAX - 0.01 and (table["in_Fz"] == 0).any()
    assert np.abs(table["in_Vx"]).max() >= 29 * prm.LONGVL and (table["in_Vx"] < 0).any()
    assert table["in_P"].min() < prm.PRESMIN and table["in_P"].max() > prm.PRESMAX
    assert set(np.unique(table["useMode"]).astype(int)) == {111, 112, 121, 122, 211, 212, 221, 222}
    assert set(np.unique(table["ncols"]).astype(int)) == {7, 8}
    above = (table["in_Fz"] > prm.FZMAX * 1.01) & (table["useMode"] < 200) & np.isfinite(table["Re"])
    assert above.sum() >= 30


@pytest.mark.parametrize("name", FILES)
def test_above_fzmax_the_vertical_outputs_follow_the_load_and_the_forces_stay(name, evaluated):
    """MFeval's split above FZMAX, read from its tables: Re, 2a, 2b and My change with the load beyond FZMAX, Fx, Fy,
    Mz, Mx do not; compat follows both (the test of the identity above is the strict one; this one names the
    physics: on the old code, which held every output at FZMAX, Re, 2a and My differ)."""
    model, table, result = evaluated(name)
    prm = model.params
    sweep = (table["in_Vx"] == prm.LONGVL) & (table["in_kappa"] == 0) & (table["in_alpha"] == 0) \
        & (table["useMode"] == 111) & (table["ncols"] == 7) & (table["in_P"] == prm.NOMPRES)
    rows = np.flatnonzero(sweep & (table["in_Fz"] >= prm.FZMAX))
    rows = rows[np.argsort(table["in_Fz"][rows])]
    assert len(rows) >= 5
    for col in ("Re", "2a", "My"):
        ref = table[col][rows]
        assert np.all(np.diff(ref) != 0), col
        np.testing.assert_allclose(result[rows, MFEVAL_COLUMNS.index(col)], ref, rtol=1e-9, err_msg=col)
    for col in ("Fx", "Fy", "Mz", "Mx"):
        ref = table[col][rows]
        np.testing.assert_allclose(ref, ref[0], rtol=1e-12, atol=1e-9 * prm.FNOMIN * prm.UNLOADED_RADIUS)


def test_compat_warns_where_mfeval_gives_a_value_no_tyre_has():
    """The MF 6.1 deflection above FZMAX is MFeval's (frozen at FZMAX) with a warning; at 1e4 m/s compat returns
    MFeval's answer with a warning, where the model refuses."""
    model = load("MagicFormula61_Parameters.tir")
    prm = model.params
    with pytest.warns(ReferenceValueWarning, match="FZMAX"):
        row = mfeval(model, [[1.2 * prm.FZMAX, 0, 0, 0, 0, prm.LONGVL, prm.NOMPRES]], 111)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputClippedWarning)
        at_max = mfeval(model, [[prm.FZMAX, 0, 0, 0, 0, prm.LONGVL, prm.NOMPRES]], 111)[0]
    rho = MFEVAL_COLUMNS.index("rho")
    assert row[rho] == pytest.approx(at_max[rho], rel=1e-3)  # (the spin, at the load, changes Q_V2's term)
    with pytest.warns(InputClippedWarning):
        own = model.evaluate(1.2 * prm.FZMAX, 0.0, 0.0, vx=prm.LONGVL, p=prm.NOMPRES)
    assert own.rho > 1.1 * row[rho]
    with pytest.warns(ReferenceValueWarning, match="vx = 10000"):
        mfeval(model, [[4000, 0, 0, 0, 0, 1e4, prm.NOMPRES]], 111)
    with pytest.raises(mftyre.ModelInputError, match="vx"):
        model.evaluate(4000, 0, 0, vx=1e4)


def max_errors() -> dict:
    """{file: {column: max error}} (python -c 'import test_mfeval_extra as t; t.report()' from tests/)."""
    found = {}
    for name in FILES:
        model = load(name)
        table = read_table(name)
        found[name] = {c: e for c, (e, _) in errors(model, table, evaluate_table(model, table)).items()}
    return found


def report() -> None:
    for name, cols in max_errors().items():
        worst = sorted(cols.items(), key=lambda kv: -kv[1])[:6]
        print(f"{name}: " + ", ".join(f"{c} {e:.2g}" for c, e in worst))
