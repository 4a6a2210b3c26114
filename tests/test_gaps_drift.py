"""Friction drift over the run (issue 18): the gap finder names it as a nuisance of the test, never as a tyre effect.

Evidence: the rig generator's friction drift (:func:`mftyre.rig.rig_programme`, LMUX/LMUY following the tread
temperature over the day, pressure blocks run one after another) on a pressure-blind published tyre (the
Pacejka-book file of MFeval): before, the drift was read as pressure effects on friction and trail. The generator's
own drift curve is the independent reference for the fitted one; the same run without drift is the control; a tyre
with a real pressure effect on friction as well keeps it; point data in the order they were measured (no TIME) with
the same kind of drift are read by their row order.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import mftyre
from mftyre.data import trailer_programme
from mftyre.gaps import find_gaps, neutralise
from mftyre.gaps.drift import FRICTION_DRIFT, Drifting, drift_factor, with_progress
from mftyre.params import TyreParameters
from mftyre.rig import rig_programme

from conftest import MFEVAL_DIR, require_shared


@pytest.fixture(scope="module")
def book():
    return mftyre.load_tir(require_shared(MFEVAL_DIR / "PacejkaBook_Defaults.tir"))


def _rig(model, drift, loads=(0.5, 1.0, 1.5)):
    """A short day on the rig: loads x 3 pressures, camber 0, slip-angle sweeps, pressures in order."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return rig_programme(model, loads=loads, cambers_deg=(0.0,), longitudinal=False, seed=5,
                             friction_drift=drift)


def _day_drift(u, peak_to_peak):
    """The generator's friction factor over the day (mftyre.rig: warm-up, then a slow decline)."""
    return 1.0 + peak_to_peak * (0.5 * (1.0 - np.exp(-u / 0.1)) - u + 0.25)


def _gaps(data, model):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return find_gaps(data, model)


def test_friction_drift_of_the_test_day_is_named_and_not_taken_for_pressure_effects(book, tmp_path):
    """The drifting day on the pressure-blind tyre: nothing added to the tyre (the old finder added
    pressure_friction_y and pressure_trail), the drift named, its curve the generator's within 30 % RMS (mean
    removed: the mean friction stays with the tyre), the improved .tir without drift coefficients."""
    rep = _gaps(_rig(book, 0.03), book)
    assert rep.effect_names == [], rep.message
    assert [a.name for a in rep.nuisances] == ["friction_drift"], rep.message
    assert "friction drift over the run" in rep.message
    u = np.linspace(0.0, 1.0, 201)
    fitted = drift_factor({k: v["value"] for k, v in rep.nuisances[0].parameters.items()}, u) - 1.0
    truth = _day_drift(u, 0.03)
    truth -= truth.mean()
    assert np.sqrt(np.mean((fitted - truth) ** 2)) < 0.3 * np.sqrt(np.mean(truth**2))
    assert type(rep.model.params) is TyreParameters
    rep.write_tir(tmp_path / "improved.tir")
    assert "DRIFT" not in (tmp_path / "improved.tir").read_text()
    assert rep.to_dict()["nuisances"][0]["name"] == "friction_drift"


def test_a_day_without_drift_names_no_drift(book):
    """The same run without drift: no drift named, nothing added."""
    rep = _gaps(_rig(book, 0.0), book)
    assert rep.effect_names == [] and rep.nuisances == [], rep.message


def test_a_real_pressure_effect_on_friction_is_kept_beside_the_drift(book):
    """The tyre has a pressure effect on lateral friction (PPY3 = -0.25: -3.5 % per pressure step) and the day
    drifts: the pressure effect is named (the drift cannot make steps at the pressure changes)."""
    truth = book.with_params(PPY3=-0.25)
    rep = _gaps(_rig(truth, 0.03, loads=(0.6, 1.2)), neutralise(truth, "pressure_friction_y"))
    assert "pressure_friction_y" in rep.effect_names, rep.message
    assert rep.model.params.PPY3 == pytest.approx(-0.25, abs=0.08)


def test_point_data_without_time_drift_along_their_row_order(book):
    """Trailer points (no TIME) measured pressure after pressure while the friction falls by 4 % over the run:
    read by their row order, the drift is named and no pressure effect added; the same points without drift
    name nothing."""
    plain = trailer_programme(book, points=11, noise=1.0, seed=3, cambers_deg=(0.0,), combined_alpha_deg=())
    assert "TIME" not in plain
    u = np.arange(len(plain)) / (len(plain) - 1)
    mu = 1.0 + 0.04 * (0.5 - u)
    frame = plain.frame.copy()
    # the friction of each sweep is the drift's at its middle row (a sweep takes a minute, the day many)
    for s in np.unique(frame["SWEEP"]):
        rows = np.flatnonzero(frame["SWEEP"].to_numpy() == s)
        m = float(np.mean(mu[rows]))
        tyre = book.with_params(LMUX=book.params.LMUX * m, LMUY=book.params.LMUY * m)
        f = frame.iloc[rows]
        out = tyre.evaluate(f["FZ"].to_numpy(), f["SL"].to_numpy(), f["SA"].to_numpy(), f["IA"].to_numpy(), 0.0,
                            f["VX"].to_numpy(), f["P"].to_numpy())
        for ch, name in (("FX", "fx"), ("FY", "fy"), ("MZ", "mz"), ("MX", "mx")):
            exact = book.evaluate(f["FZ"].to_numpy(), f["SL"].to_numpy(), f["SA"].to_numpy(), f["IA"].to_numpy(),
                                  0.0, f["VX"].to_numpy(), f["P"].to_numpy())[name]
            frame.loc[frame.index[rows], ch] = f[ch].to_numpy() + np.asarray(out[name]) - np.asarray(exact)
    drifting = plain.with_frame(frame, "friction drift 4 % over the rows")
    rep = _gaps(drifting, book)
    assert rep.effect_names == [] and [a.name for a in rep.nuisances] == ["friction_drift"], rep.message
    assert _gaps(plain, book).nuisances == []


def test_drifting_parameters_are_the_tyre_plus_coefficients(book):
    """Indexing and replace reach both; the tyre alone is what a model, a check or a .tir sees; the run's progress
    comes from TIME, else from the row order."""
    prm = FRICTION_DRIFT.admit(book.params).replace(DRIFT1=0.01, PDY1=1.1)
    assert isinstance(prm, Drifting) and prm["DRIFT1"] == 0.01 and prm.PDY1 == 1.1
    assert type(prm.tyre) is TyreParameters and prm.tyre == book.params.replace(PDY1=1.1)
    assert FRICTION_DRIFT.admit(prm) is prm
    assert drift_factor(prm.drift, np.array([0.0, 0.5, 1.0])) == pytest.approx([0.99, 1.0, 1.01])
    data = trailer_programme(book, points=5, cambers_deg=(0.0,), combined_alpha_deg=(), pressures=(1.0,),
                             loads=(1.0,))
    u = with_progress(data).array("RUN_PROGRESS")
    assert u[0] == 0.0 and u[-1] == 1.0 and np.all(np.diff(u) > 0)
    n = len(data)
    timed = data.with_frame(data.frame.assign(TIME=np.r_[0.0, 100.0 + 10.0 * np.arange(n - 1)]), "a pause")
    assert with_progress(timed).array("RUN_PROGRESS")[1] == pytest.approx(100.0 / (100.0 + 10.0 * (n - 2)))
