"""One prediction rule for a measured channel (issue 22): the fit (its batch predictor and its stage rule), the
fit report and the gap finder predict the same values, with and without a measured wheel spin OMEGA."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import mftyre
from mftyre.data import TyreData
from mftyre.fit.predict import BatchPredictor
from mftyre.fit.predict import predict, predict_stage, wheel_spin
from mftyre.fit.stages import STAGES, stage_rows
from mftyre.gaps import Evaluator

from conftest import TIR_FILES


@pytest.fixture(scope="module")
def model():
    m = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")
    # speed terms switched on, so that the spin matters to the vertical force
    return m.with_params(Q_V1=5e-4, Q_V2=0.04)


def _vertical_data(model, omega: bool):
    """Load-deflection points rolling at 30 m/s (the spin from the model itself), 3 pressures, 5 loads."""
    prm = model.params
    fz = np.tile(np.linspace(0.3, 1.8, 5) * prm.FNOMIN, 3)
    p = np.repeat([0.85, 1.0, 1.15], 5) * prm.NOMPRES
    vx = np.full(fz.size, 30.0)
    spin = model.evaluate(fz, 0.0, 0.0, 0.0, vx=vx, p=p).omega
    rl, rho = model.loaded_radius(fz, p=p, omega=spin)
    frame = pd.DataFrame(dict(TEST="vertical", SWEEP=np.repeat([0, 1, 2], 5), FZ=fz, SL=0.0, SA=0.0, IA=0.0,
                              VX=vx, P=p, RL=rl, RHO=rho, FX=0.0, FY=0.0, MZ=0.0))
    if omega:
        frame["OMEGA"] = spin
    return TyreData(frame, source="30 m/s" + ("" if omega else ", without OMEGA"))


@pytest.mark.parametrize("omega", [True, False], ids=["with OMEGA", "without OMEGA"])
def test_fit_and_gap_finder_predict_the_same(model, omega):
    data = _vertical_data(model, omega)
    assert data.has("OMEGA") == omega
    stage = STAGES["vertical"]
    sub = data.select(stage_rows(STAGES["vertical"], data))
    fit_rule = predict_stage(stage, model, sub, sub.inputs())
    batch = BatchPredictor(model.params, sub, ("FZ",), ["VERTICAL_STIFFNESS"])
    batch_rule = batch(np.array([[float(model.params.VERTICAL_STIFFNESS)]]))["FZ"][0]
    ev = Evaluator(sub, channels=["FZ", "FX", "FY", "MZ"])
    gaps_rule = ev.predict(model)
    np.testing.assert_allclose(gaps_rule["FZ"], fit_rule[ev.rows["FZ"]], rtol=1e-12)
    np.testing.assert_allclose(batch_rule, fit_rule, rtol=1e-9)
    for c in ("FX", "FY", "MZ"):
        np.testing.assert_allclose(gaps_rule[c], predict(model, sub, [c])[c][ev.rows[c]], rtol=1e-12)


def test_spin_without_omega_is_the_rolling_spin(model):
    """Without OMEGA the vertical relation sees the spin the model estimates for the forces, (1 + kappa) Vx / Re
    (not a standing wheel): at 30 m/s data generated with the model's own spin are reproduced, where a standing
    wheel (spin 0, the fit's rule before) misses by the speed terms."""
    with_omega, without = _vertical_data(model, True), _vertical_data(model, False)
    sub_w, sub_wo = (d.select(stage_rows(STAGES["vertical"], d)) for d in (with_omega, without))
    spin = wheel_spin(model, sub_wo)
    np.testing.assert_allclose(spin, sub_w.array("OMEGA"), rtol=1e-9)
    fz = sub_wo.array("FZ")
    fz_without = predict(model, sub_wo, ["FZ"])["FZ"]
    fz_standing = model.vertical_force(sub_wo.array("RL"), p=sub_wo.array("P"), omega=0.0,
                                       fx=sub_wo.array("FX"), fy=sub_wo.array("FY"), gamma=sub_wo.array("IA"))
    assert np.max(np.abs(fz_without - fz)) < 1e-6 * np.max(fz)
    assert np.max(np.abs(fz_standing - fz)) > 1e-3 * np.max(fz)


def test_rows_without_loaded_radius_are_not_predicted(model):
    """Rows where neither RL nor RHO is measured get NaN for FZ (the gap finder leaves them out), not an error."""
    data = _vertical_data(model, False)
    frame = data.frame.copy()
    frame.loc[frame.index[:4], "RL"] = np.nan
    data = data.with_frame(frame, "RL missing in 4 rows")
    fz = predict(model, data, ["FZ"])["FZ"]
    assert np.isnan(fz[:4]).all() and np.isfinite(fz[4:]).all()
    ev = Evaluator(data, channels=["FZ"])
    assert ev.residuals(model)["FZ"].size == len(data) - 4


@pytest.mark.parametrize("turn_slip", [False, True], ids=["plain", "turn slip"])
def test_outputs_asked_for_are_the_full_evaluation_bit_for_bit(model, turn_slip):
    """steady_state(outputs=...) skips the parts no asked output needs (the batched refits ask for one channel's):
    every output alone, and the channels' groups, equal the full evaluation exactly, on 6.1 and 6.2 files."""
    from mftyre.backend import NUMPY
    from mftyre.formula import Modes, steady_state
    from mftyre.formula.steady_state import OUTPUT_NAMES

    rng = np.random.default_rng(3)
    for prm in (model.params, mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir").params):
        n = 300
        args = (rng.uniform(0.2, 1.8, n) * prm.FNOMIN, rng.uniform(-0.3, 0.3, n), rng.uniform(-0.3, 0.3, n),
                rng.uniform(-0.1, 0.1, n), rng.uniform(-0.5, 0.5, n), rng.uniform(1.0, 40.0, n),
                rng.uniform(0.8, 1.2, n) * prm.NOMPRES, np.zeros(n), False, Modes(turn_slip=turn_slip), NUMPY)
        with np.errstate(all="ignore"):
            full = steady_state(prm, *args)
            for asked in [(name,) for name in OUTPUT_NAMES] + [("fx", "my"), ("fy", "mz", "mx"), ("omega",)]:
                part = steady_state(prm, *args, outputs=asked)
                assert sorted(part) == sorted(asked), asked
                for name in asked:
                    np.testing.assert_array_equal(part[name], full[name], err_msg=f"{name} of {asked}")


def test_batched_sets_are_the_gap_finders_one_rule_set_by_set(model):
    """Evaluator.batch (the gap finder's refits and covariances: K parameter sets in one evaluation, the friction
    drift's nodes of every set in the same one) gives each set what Evaluator.predict gives that set alone, the
    vertical channel, a structural parameter (looped) and drift coefficients included."""
    from mftyre.data import trailer_programme
    from mftyre.gaps.drift import Drifting, with_progress

    data = with_progress(trailer_programme(model, loads=(0.6, 1.2), pressures=(0.9, 1.1), cambers_deg=(0.0, 3.0),
                                           points=7, noise=1.0, seed=2))
    ev = Evaluator(data)
    assert {"FX", "FY", "MZ", "MX", "MY", "FZ"} <= set(ev.channels)
    rng = np.random.default_rng(5)
    drifting = Drifting.of(model.params, {"DRIFT1": 0.03, "DRIFT2": -0.01, "DRIFT3": 0.0})
    for prm, names in ((model.params, ["PKY1", "PDY1", "QSX3", "VERTICAL_STIFFNESS", "PKX1"]),
                       (model.params.replace(QSX12=0.05, QSX13=0.1), ["QSX12", "QSX1"]),  # the form: set by set
                       (drifting, ["PKY1", "DRIFT1", "DRIFT3", "LMUY"])):
        x = np.array([float(prm[n]) for n in names])
        values = x * (1.0 + 0.02 * rng.standard_normal((4, len(names)))) + 1e-3 * rng.standard_normal((4, len(names)))
        batch = ev.batch(prm, names)(values)
        for row, v in enumerate(values):
            alone = ev.predict(prm.replace(**dict(zip(names, v))))
            for c in ev.channels:
                np.testing.assert_allclose(batch[c][row], alone[c], rtol=1e-12, atol=1e-9, err_msg=f"{names} {c}")
