"""Inputs outside the .tir ranges: one InputClippedWarning per call naming each input, range and count, tables and
plot legends of `mftyre eval` show the values used."""
from __future__ import annotations

import warnings

import numpy as np

import mftyre
from mftyre import cli
from mftyre.errors import InputClippedWarning

from conftest import TIR_FILES

TIR61 = TIR_FILES / "car_205_60R15_mf61.tir"


def _caught(fn):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn()
    return result, [w for w in caught if issubclass(w.category, InputClippedWarning)]


def test_one_warning_per_call_naming_each_clipped_input_range_and_count():
    model = mftyre.load_tir(TIR61)
    prm = model.params
    p = np.array([1.76e5, 2.2e5, 2.64e5, 3.0e5])
    kappa = np.array([0.0, 0.1, 5.0, -5.0])
    out, caught = _caught(lambda: model.evaluate(4000.0, kappa, 0.0, p=p))
    assert issubclass(InputClippedWarning, UserWarning)
    assert len(caught) == 1  # kappa and p in one warning
    message = str(caught[0].message)
    assert f"kappa outside KPUMIN..KPUMAX = [{prm.KPUMIN:g}, {prm.KPUMAX:g}] - at 2 of 4 point(s)" in message
    assert "p outside PRESMIN..PRESMAX = [186000, 255000] Pa at 3 of 4 point(s)" in message
    assert "alpha" not in message and "fz" not in message and "gamma" not in message
    np.testing.assert_array_equal(out.p, np.clip(p, prm.PRESMIN, prm.PRESMAX))  # outputs carry the used values


def test_fz_warns_above_fzmax_only():
    """FZMAX saturates the load; loads in (0, FZMIN) are evaluated as given except in the aligning torque and
    the deflection (no bound of the input, no warning), Fz <= 0 is no contact."""
    model = mftyre.load_tir(TIR61)
    prm = model.params
    fz = np.array([-100.0, 0.0, 0.5 * prm.FZMIN, 4000.0, prm.FZMAX + 1.0, 1.5 * prm.FZMAX])
    _, caught = _caught(lambda: model.evaluate(fz, 0.0, 0.05))
    assert len(caught) == 1
    assert str(caught[0].message).endswith(f"fz outside FZMAX = [-inf, {prm.FZMAX:g}] N at 2 of 6 point(s)")
    np.testing.assert_array_equal(model.used_input("fz", fz), np.minimum(fz, prm.FZMAX))
    _, caught = _caught(lambda: model.evaluate(np.array([0.5 * prm.FZMIN, 0.0]), 0.0, 0.05))
    assert caught == []


def test_no_warning_in_range_or_without_limits():
    model = mftyre.load_tir(TIR61)
    _, caught = _caught(lambda: model.evaluate(4000.0, 0.1, 0.05, 0.01, p=2.2e5))
    assert caught == []
    out, caught = _caught(lambda: model.evaluate(4000.0, 0.0, 0.0, p=1.5e5, limits=False))
    assert caught == [] and out.p == 1.5e5


def test_mirrored_model_warns_in_its_own_axes():
    """A model mounted on the other side mirrors alpha and gamma, and their ranges with them."""
    model = mftyre.load_tir(TIR61)
    other = model.with_side("right" if model.side == "left" else "left")
    lo, hi = other.input_range("gamma")
    assert (lo, hi) == (-model.params.CAMMAX, -model.params.CAMMIN)
    _, caught = _caught(lambda: other.evaluate(4000.0, 0.0, 0.0, np.array([lo - 0.01, hi - 1e-3])))
    assert len(caught) == 1
    assert f"gamma outside CAMMIN..CAMMAX = [{lo:g}, {hi:g}] rad at 1 of 2 point(s)" in str(caught[0].message)


def test_cli_table_and_header_show_the_pressures_used(capsys):
    assert cli.main(["eval", str(TIR61), "--p", "1.76bar,2.2bar", "--alpha", "0.05"]) == 0
    captured = capsys.readouterr()
    assert "p_used [Pa]" in captured.out and "186000" in captured.out
    assert "outside the .tir range" in captured.err
    assert cli.main(["eval", str(TIR61), "--p", "2.64bar", "--alpha", "0.05,0.1"]) == 0
    assert "p = 264000 Pa (used: 255000" in capsys.readouterr().out


def test_cli_plot_legend_names_the_pressure_used(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    legends = []
    original = Figure.savefig

    def capture(fig, *args, **kw):
        for ax in fig.axes:
            if ax.get_legend() is not None:
                legends.extend(t.get_text() for t in ax.get_legend().get_texts())
        return original(fig, *args, **kw)

    monkeypatch.setattr(Figure, "savefig", capture)
    rc = cli.main(["eval", str(TIR61), "--p", "1.76bar,2.2bar", "--alpha", "-0.1:0.1:5", "--plot",
                   str(tmp_path / "p.png"), "-q"])
    assert rc == 0
    assert legends == ["p = 1.86 bar (asked 1.76 bar)", "p = 2.2 bar"]


def test_cli_used_columns_of_swept_inputs_are_the_values_used(tmp_path):
    """A swept input that is also an output (kappa, alpha, gamma, fz) is labelled NAME_used: it must hold the value
    the model evaluated, saturated to the .tir range, and the forces must equal evaluate() at those values (old:
    the model's echo of the value asked, e.g. gamma_used 0.3 rad where CAMMAX 0.105 rad was used)."""
    import pandas as pd

    model = mftyre.load_tir(TIR61)
    prm = model.params
    csv = tmp_path / "out.csv"
    for option, values, name, unit in (("--gamma", [0.0, 0.15, 0.3, -0.3], "gamma", "rad"),
                                       ("--kappa", [0.5, 1.75, 3.0, -3.0], "kappa", "-"),
                                       ("--alpha", [0.1, 1.2, -1.5], "alpha", "rad"),
                                       ("--fz", [1000.0, 1.4 * prm.FZMAX], "fz", "N")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", InputClippedWarning)
            assert cli.main(["eval", str(TIR61), option, ",".join(map(str, values)), "--outputs", f"fx,fy,{name}",
                             "--csv", str(csv), "--overwrite", "-q"]) == 0
            used = model.used_input(name, np.array(values))
            ref = model.evaluate(**{"fz": 4000.0, "kappa": 0.0, "alpha": 0.0, name: used})
        df = pd.read_csv(csv)
        assert not np.array_equal(used, values)
        np.testing.assert_array_equal(df[f"{name}_used [{unit}]"], used)
        np.testing.assert_allclose(df["fy [N]"], np.ravel(ref.fy), rtol=1e-12, atol=1e-9)
