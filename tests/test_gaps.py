"""mftyre.gaps, the evidence of issue #5.

Trailer data (the fitting issue's programme, with noise) are generated from a full tyre model; the gap finder is
handed that model with one (or two) catalogue effects switched off (their switches at the neutral values). It
must name exactly the hidden effect(s) and shrink the held-out error of the effect's primary channel by at least
70 %; handed the full model it must add nothing. Two tyres: A, the MF 6.1 sample; B, the MF 6.2 sample scaled to a
different tyre (5 kN nominal load, 0.33 m radius, 2.5 bar, 12 % more friction, 25 % more cornering stiffness, 10 %
less slip stiffness, 20 % longer trail, stiffer carcass). Noise: the realistic level of :data:`mftyre.data.NOISE`;
the target is the held-out error's excess over the true model's (the noise floor), which must shrink by 70 %.
Issue 11 adds realistic rig time series (100 Hz, AR(1) noise, hysteresis, drift, load scatter: :mod:`mftyre.rig`),
effects the data cannot test, verification before writing, honest statistics and small data.

Independent checks: the catalogue's neutral values reproduce the full model exactly at the nominal condition
(dpi = 0, gamma = 0, dfz = 0, phit = 0: the analytic limit where every switched term vanishes) and change it
elsewhere; the noise estimate recovers the known standard deviation of added noise; pure noise gives no finding.
"""
from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest

import mftyre
from mftyre.data import TyreData, trailer_programme, write_tydex
from mftyre.fit.stages import STAGES
from mftyre.gaps import CATALOGUE, BASE, Evaluator, coverage, find_gaps, holdout_mask, locate, neutralise, noise_levels
from mftyre.gaps.command import register
from mftyre.gaps.drift import FRICTION_DRIFT
from mftyre.params import PARAMETERS
from mftyre.tir import write_tir

from conftest import TIR_FILES

NOISE = 1.0   # the realistic level of mftyre.data.NOISE


def _tyre_a():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")


def _tyre_b():
    m = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")
    p = m.params
    return m.with_params(FNOMIN=5000.0, UNLOADED_RADIUS=0.33, WIDTH=0.235, VERTICAL_STIFFNESS=250000.0,
                         NOMPRES=250000.0, INFLPRES=250000.0, PRESMIN=200000.0, PRESMAX=300000.0, FZMAX=12000.0,
                         PDX1=1.12 * p.PDX1, PDY1=1.12 * p.PDY1, PKY1=1.25 * p.PKY1, PKX1=0.9 * p.PKX1,
                         QDZ1=1.2 * p.QDZ1)


TYRES = {"A": _tyre_a, "B": _tyre_b}
_CACHE = {}


def _data(tyre: str, partial: bool = False):
    key = (tyre, partial)
    if key not in _CACHE:
        # partial: one pressure, camber 0. (Three loads: with two, one of them nominal, the held-out sweeps showed no
        # load effect at all; the given file was as good there as the truth, and only a fair start that made it
        # worse, issue 18 item 3, gave the effect something to repair.)
        kw = dict(loads=(0.5, 1.0, 1.5), pressures=(1.0,), cambers_deg=(0.0,)) if partial else {}
        model = TYRES[tyre]()
        _CACHE[key] = (model, trailer_programme(model, points=15, noise=NOISE, seed=5, **kw))
    return _CACHE[key]


# ------------------------------------------------------------------------------------------- catalogue
REQUIRED_EFFECTS = (
    "pressure_cornering_stiffness", "pressure_slip_stiffness", "pressure_friction_x", "pressure_friction_y",
    "pressure_trail", "pressure_residual_torque", "pressure_vertical_stiffness", "pressure_overturning",
    "pressure_rolling_resistance", "camber_cornering_stiffness", "camber_thrust", "camber_trail",
    "camber_aligning_moment", "camber_overturning", "load_friction_x", "load_friction_y", "load_curvature_x",
    "load_curvature_y", "load_slip_stiffness", "speed_friction", "speed_rolling_resistance", "combined_fx",
    "combined_fy", "turn_slip_fx", "turn_slip_fy_peak", "vertical_hardening")


def test_catalogue_is_schema_data_and_covers_the_schema():
    for name in REQUIRED_EFFECTS:
        assert name in CATALOGUE
    sets = set()
    for e in CATALOGUE.values():
        assert e.description and e.parameters and e.channels and e.variables
        assert set(e.neutral) <= set(e.parameters), e.name
        assert all(n in PARAMETERS for n in e.parameters), e.name
        assert frozenset(e.parameters) not in sets, e.name      # effects are distinct
        sets.add(frozenset(e.parameters))
    cov = coverage()
    assert set(cov) == set(PARAMETERS)
    # every parameter a fitting stage can fit is reachable: in an effect or always active (base)
    for stage in STAGES.values():
        for _, names in stage.groups:
            for n in names:
                assert cov[n][0] in ("effect", "base") or n in ("BREFF", "DREFF", "FREFF"), n
    for n, spec in PARAMETERS.items():
        if spec.section in ("LONGITUDINAL_COEFFICIENTS", "LATERAL_COEFFICIENTS", "ALIGNING_COEFFICIENTS",
                            "OVERTURNING_COEFFICIENTS", "ROLLING_COEFFICIENTS", "TURNSLIP_COEFFICIENTS") \
                and spec.versions & {"61", "62"}:
            assert cov[n][0] in ("effect", "base"), n
    assert "PKY1" in BASE and "PPY1" not in BASE


_NOMINAL_VARS = {"pressure", "camber", "load", "turn_slip"}


@pytest.mark.parametrize("name", [n for n, e in CATALOGUE.items()
                                  if set(e.variables) <= _NOMINAL_VARS and "61" in e.versions])
def test_neutral_values_switch_the_effect_off(name):
    """Analytic limit: every switched term carries dpi, gamma, dfz or phit, so at p = NOMPRES, gamma = 0,
    Fz = FNOMIN, phit = 0 the neutralised model equals the full one; away from it the switch changes the output."""
    e = CATALOGUE[name]
    full = _tyre_a().with_params(**{k: (e.start.get(k, 0.3) if v == 0 else v + 0.3) for k, v in e.neutral.items()
                                    if abs(float(_tyre_a().params[k]) - v) < 1e-12})
    off = neutralise(full, name)
    p0, fz0 = full.params.NOMPRES, full.params.FNOMIN
    ts = "turn_slip" in e.variables
    kappa, alpha = np.meshgrid(np.linspace(-0.2, 0.2, 9), np.radians(np.linspace(-10, 10, 9)))
    a = full.evaluate(fz0, kappa, alpha, 0.0, 0.0, p=p0, turn_slip=ts)
    b = off.evaluate(fz0, kappa, alpha, 0.0, 0.0, p=p0, turn_slip=ts)
    if "FZ" in e.channels:
        rl = np.linspace(0.29, 0.31, 5)
        np.testing.assert_allclose(full.vertical_force(rl, p=p0), off.vertical_force(rl, p=p0), rtol=1e-12)
        assert np.max(np.abs(full.vertical_force(rl, p=1.15 * p0) - off.vertical_force(rl, p=1.15 * p0))) > 1.0
        return
    ch = {"FX": "fx", "FY": "fy", "MZ": "mz", "MX": "mx", "MY": "my"}
    for c in e.channels:
        np.testing.assert_allclose(a[ch[c]], b[ch[c]], rtol=1e-10, atol=1e-9, err_msg=f"{name} {c}")
    away = dict(fz=1.4 * fz0, kappa=kappa, alpha=alpha, gamma=math.radians(3.0), phit=0.5 if ts else 0.0,
                p=1.15 * p0)
    a, b = full.evaluate(**away, turn_slip=ts), off.evaluate(**away, turn_slip=ts)
    assert max(np.max(np.abs(a[ch[c]] - b[ch[c]])) for c in e.channels) > 1e-3, name


# ------------------------------------------------------------------------------------------ statistics
def test_noise_estimate_recovers_known_noise_and_pure_noise_gives_no_finding():
    model = _tyre_a()
    data = trailer_programme(model, points=15, noise=0.0, seed=1)
    rng = np.random.default_rng(4)
    frame = data.frame.copy()
    sd = {"FY": 25.0, "MZ": 0.6, "FX": 15.0}
    for c, s in sd.items():
        frame[c] = frame[c] + rng.normal(0.0, s, len(frame))
    noisy = data.with_frame(frame, "noise added")
    ev = Evaluator(noisy, channels=list(sd))
    res = ev.residuals(model)
    sigma = noise_levels(ev, res)
    for c, s in sd.items():
        assert sigma[c][0] == pytest.approx(s, rel=0.12), (c, sigma[c])
        assert "repeated" in sigma[c][1]
    assert locate(ev, res, sigma) == []
    # a structured error: Fy too large by 3 % of |Fy| at the highest pressure only
    frame2 = frame.copy()
    hi = frame2["P"] > 1.1 * model.params.NOMPRES
    frame2.loc[hi, "FY"] *= 1.03
    ev2 = Evaluator(data.with_frame(frame2, "pressure error"), channels=list(sd))
    findings = locate(ev2, ev2.residuals(model), sigma)
    assert findings and findings[0].channel == "FY" and "pressure" in findings[0].variables


def test_holdout_takes_whole_sweeps_of_every_kind():
    _, data = _data("A")
    mask = holdout_mask(data, 0.25, seed=0)
    sweep = data.frame["SWEEP"].to_numpy()
    for s in np.unique(sweep):
        assert mask[sweep == s].all() or not mask[sweep == s].any()
    kinds = data.frame["TEST"].to_numpy()
    for k in ("pure_lateral", "pure_longitudinal", "combined", "free_rolling"):
        assert mask[kinds == k].any() and (~mask[kinds == k]).any(), k
    assert 0.15 < mask.mean() < 0.35


def _sweep_medians(data, mask, kind, column):
    sweep, kinds = data.frame["SWEEP"].to_numpy(), data.frame["TEST"].to_numpy()
    held, kept = set(), set()
    for s in np.unique(sweep[kinds == kind]):
        rows = sweep == s
        level = round(float(np.median(data.array(column)[rows])) / {"FZ": 1000.0, "P": 1e4, "IA": 0.01}[column])
        (held if mask[rows].all() else kept).add(level)
    return held, kept


def test_holdout_is_stratified_over_load_pressure_and_camber():
    """Issue 18: every 4th sweep in data order held out only nominal-load sweeps of a drive/brake programme (3
    loads, one sweep each), where a load effect is nil; the held-out sweeps now cover the levels of every
    condition, and each level stays in the training data."""
    model = _tyre_a()
    full = trailer_programme(model, points=5, noise=0.0, seed=1)
    mask = holdout_mask(full, 0.25, seed=0)
    for column in ("FZ", "P", "IA"):
        held, kept = _sweep_medians(full, mask, "pure_lateral", column)
        assert held == kept and len(held) == 3, (column, held, kept)
    d = trailer_programme(model, points=5, noise=0.0, seed=1, pressures=(1.0,), cambers_deg=(0.0,),
                          combined_alpha_deg=(-3.0, -6.0))
    test = d.frame["TEST"].to_numpy()
    d = d.select((test == "pure_longitudinal") | (test == "combined") | (test == "free_rolling"))
    for seed in (0, 1, 2):
        mask = holdout_mask(d, 0.25, seed=seed)
        held, kept = _sweep_medians(d, mask, "pure_longitudinal", "FZ")
        nominal = round(model.params.FNOMIN / 1000.0)
        assert held and nominal not in held, (seed, held)
        loads = held | _sweep_medians(d, mask, "combined", "FZ")[0] | _sweep_medians(d, mask, "free_rolling", "FZ")[0]
        assert len(loads) == 3, (seed, loads)


# --------------------------------------------------------------------------------- hidden-effect evidence
CASES = {
    # id: (tyre, hidden effects, partial range)
    "B-fy-camber_thrust": ("B", ("camber_thrust",), False),
    "B-my-pressure_rolling_resistance": ("B", ("pressure_rolling_resistance",), False),
    "B-fz-pressure_vertical_stiffness": ("B", ("pressure_vertical_stiffness",), False),
    "A-two-pressure_slip_stiffness+camber_overturning": ("A", ("pressure_slip_stiffness", "camber_overturning"),
                                                          False),
    "A-partial-range-load_slip_stiffness": ("A", ("load_slip_stiffness",), True),
}
EVIDENCE = {}


@pytest.mark.parametrize("case", list(CASES))
def test_hidden_effect_is_named_added_and_the_gap_shrinks(case):
    tyre, hidden, partial = CASES[case]
    full, data = _data(tyre, partial)
    rep = find_gaps(data, neutralise(full, *hidden))
    shrink = rep.shrink()
    affected = sorted({CATALOGUE[h].channels[0] for h in hidden})
    EVIDENCE[case] = (rep.effect_names, {c: (rep.error_before[c], rep.error_after[c], shrink.get(c)) for c in affected})
    print(case, EVIDENCE[case])
    assert sorted(rep.effect_names) == sorted(hidden), rep.message
    true = rep.held_out_error(full)
    for c in affected:   # the held-out error's excess over the true model's shrinks by at least 70 %
        excess_before, excess_after = rep.error_before[c] - true[c], rep.error_after[c] - true[c]
        assert excess_before > 0 and excess_after <= 0.3 * excess_before, (c, rep.error_before[c],
                                                                            rep.error_after[c], true[c])
    if hidden:
        assert rep.findings_before[0].channel in {c for h in hidden for c in CATALOGUE[h].channels}
        for a in rep.effects_added:   # every added parameter carries a value and a standard error
            assert all(math.isfinite(v["value"]) and v["stderr"] is not None for v in a.parameters.values())
    if partial:   # one pressure, no camber: absent pressure and camber effects are reported untestable, not tried
        assert "pressure_overturning" in rep.untestable and "camber_friction_x" in rep.untestable
        tried = {c.name for r in rep.rounds for c in r}
        offered = dict(CATALOGUE, friction_drift=FRICTION_DRIFT)   # the catalogue and the nuisance of the test day
        assert not any(offered[n].variables[0] in ("pressure", "camber") for n in tried), tried


def test_vertical_problem_leads_to_pressure_and_hardening_terms():
    """Load-deflection data at five pressures (FZ, RL, RHO only) against a linear, pressure-blind vertical model."""
    full = _tyre_a()
    d = trailer_programme(full, loads=(1.0,), pressures=(0.85, 0.925, 1.0, 1.075, 1.15), cambers_deg=(0.0,),
                          points=5, vertical_points=25, noise=NOISE, seed=2)
    d = d.select(d.frame["TEST"].to_numpy() == "vertical")
    d = TyreData(d.frame[["TEST", "SWEEP", "FZ", "SL", "SA", "IA", "VX", "P", "RL", "RHO"]], source="load-deflection")
    rep = find_gaps(d, neutralise(full, "vertical_hardening", "pressure_vertical_stiffness"))
    assert sorted(rep.effect_names) == ["pressure_vertical_stiffness", "vertical_hardening"]
    true = rep.held_out_error(full)["FZ"]    # the excess over the true model's error shrinks by 90 %
    assert rep.error_after["FZ"] - true <= 0.1 * (rep.error_before["FZ"] - true)
    values = {k: v["value"] for a in rep.effects_added for k, v in a.parameters.items()}
    assert values["PFZ1"] == pytest.approx(full.params.PFZ1, rel=0.1)
    assert values["Q_FZ2"] == pytest.approx(full.params.Q_FZ2, rel=0.1)


def test_command_line_writes_tir_report_and_json(tmp_path):
    full, data = _data("A")
    tdx = write_tydex(data, tmp_path / "trailer.tdx")
    base = write_tir(neutralise(full, "pressure_trail").params, tmp_path / "base.tir")
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    args = parser.parse_args(["gaps", str(tdx), "--model", str(base), "-o", str(tmp_path / "improved.tir"),
                              "--report", str(tmp_path / "rep"), "--json", str(tmp_path / "gaps.json"), "--quiet"])
    assert args.func(args) == 0
    report = json.loads((tmp_path / "gaps.json").read_text())
    assert [e["name"] for e in report["effects_added"]] == ["pressure_trail"]
    e = report["effects_added"][0]
    assert {"name", "description", "parameters", "held_out_gain"} <= set(e) and e["parameters"][0]["name"] == "PPZ1"
    true = 2.19   # the true model's held-out MZ error [%] on these data (the noise floor)
    assert report["error_after"]["MZ"] - true < 0.3 * (report["error_before"]["MZ"] - true)
    assert report["findings"] and report["findings"][0]["channel"] == "MZ"
    improved = mftyre.load_tir(tmp_path / "improved.tir")
    assert improved.params.PPZ1 == pytest.approx(full.params.PPZ1, rel=0.05)
    md = (tmp_path / "rep" / "report.md").read_text()
    assert "pressure_trail" in md and (tmp_path / "rep" / "errors.png").exists()
    assert (tmp_path / "rep" / "residual_maps_before_after.png").exists()
    # refuses to overwrite
    assert args.func(args) == 2


# ------------------------------------------------------------------------------- untestable effects (#11)
def test_effects_the_data_cannot_test_are_not_candidates():
    """Free rolling only (SL = SA = 0 throughout) with an Fx offset (rolling resistance seen by the load cell):
    the Fx shifts act along kappa, so from kappa = 0 alone a horizontal shift cancels a vertical one and the curve
    away from kappa = 0 is invented (issue 11: PVX1 = 0.55 gave Fx = -1024 / +2579 N at kappa = -/+0.05). The
    effect is reported untestable with the reason, never tried; the model's Fx stays odd in kappa."""
    full = _tyre_a()
    d = trailer_programme(full, points=15, noise=1.0, seed=3)
    d = d.select(d.frame["TEST"].to_numpy() == "free_rolling")
    frame = d.frame.copy()
    frame["FX"] = frame["FX"] - 0.012 * frame["FZ"]
    rep = find_gaps(d.with_frame(frame, "rolling resistance in Fx"), neutralise(full, "fx_shift"))
    assert rep.findings_before and rep.findings_before[0].channel == "FX"
    assert "fx_shift" not in rep.effect_names
    assert "SL = 0 throughout" in rep.untestable["fx_shift"]
    assert "slip-angle sweep" in rep.untestable["camber_fy_peak"] and "SL = 0" in rep.untestable["camber_friction_x"]
    tried = {c.name for r in rep.rounds for c in r}
    assert not tried & {"fx_shift", "camber_fy_peak", "camber_friction_x", "load_curvature_x"}
    fx = rep.model.evaluate(2750.0, np.array([-0.05, 0.05]), 0.0, 0.0, 0.0)["fx"]
    assert abs(fx[0] + fx[1]) < 0.02 * 2750.0


# ------------------------------------------------------------------------------------------ small data (#11)
def _agricultural_tyre():
    """A 460/85R34-class tractor tyre: free radius 0.80 m, 20 kN nominal load, 1.3 bar nominal (1.0-1.6 bar used),
    vertical stiffness 400 kN/m at nominal load and pressure, hardening Q_FZ2 = 40 (deflection 39-96 mm over
    10-30 kN), stiffness +/- 14 % over the pressure range (PFZ1 = 0.6)."""
    return _tyre_a().with_params(
        UNLOADED_RADIUS=0.80, WIDTH=0.46, RIM_RADIUS=0.432, FNOMIN=20000.0, NOMPRES=1.3e5, INFLPRES=1.3e5,
        PRESMIN=0.9e5, PRESMAX=1.8e5, FZMIN=2000.0, FZMAX=40000.0, VERTICAL_STIFFNESS=4.0e5, Q_FZ2=40.0, PFZ1=0.6,
        Q_RE0=1.0, Q_V1=0.0, Q_V2=0.0, LONGVL=1.0)


def _load_deflection_8_points(full, seed=11):
    """Measured load-deflection table: 2 pressures x 4 loads, the load measured with 1 % noise, rolling at
    0.5 m/s."""
    import pandas as pd

    fz = np.tile([10e3, 16.7e3, 23.3e3, 30e3], 2)
    p = np.repeat([1.0e5, 1.6e5], 4)
    rl, rho = full.loaded_radius(fz, p=p, omega=0.5 / full.params.UNLOADED_RADIUS)
    noisy = fz * (1.0 + 0.01 * np.random.default_rng(seed).normal(size=fz.size))
    frame = pd.DataFrame(dict(TEST="vertical", SWEEP=np.repeat([0, 1], 4), FZ=noisy, SL=0.0, SA=0.0, IA=0.0,
                              VX=0.5, P=p, RL=rl, RHO=rho))
    return TyreData(frame, source="load-deflection 460/85R34, 8 points")


def test_small_data_finds_hardening_and_pressure_stiffness_with_uncertainties():
    """Issue 11: against a linear, pressure-blind model the old search estimated the noise from second differences
    of four-point sweeps (i.e. from the curvature under test) and added nothing while the held-out FZ error was
    12.4 %. With 8 points the effects are judged by AICc and leave-one-out over all points; both are found, each
    with a standard error, and the leave-one-out error falls to the 1 % noise level."""
    full = _agricultural_tyre()
    data = _load_deflection_8_points(full)
    base = neutralise(full, "vertical_hardening", "pressure_vertical_stiffness").with_params(
        VERTICAL_STIFFNESS=3.5e5)
    rep = find_gaps(data, base)
    assert sorted(rep.effect_names) == ["pressure_vertical_stiffness", "vertical_hardening"], rep.message
    assert rep.error_before["FZ"] > 10.0 and rep.error_after["FZ"] < 2.0      # leave-one-out errors [%]
    assert "selected model" in rep.noise["FZ"][1]                             # not from second differences
    values = {k: v for a in rep.effects_added for k, v in a.parameters.items()}
    for name, true in (("PFZ1", 0.6), ("Q_FZ2", 40.0)):
        v = values[name]
        assert v["stderr"] is not None and v["stderr"] < 0.3 * abs(v["value"]), (name, v)
        assert abs(v["value"] - true) < 3.0 * v["stderr"], (name, v)
    md = rep.markdown()
    assert "leave-one-out" in md and "Q_FZ2" in md


@pytest.mark.parametrize("noise", [0.002, 0.01])
def test_small_data_adds_both_vertical_effects_of_a_published_agricultural_file_when_determined(noise):
    """Issue 18 item 5: 8 load-deflection points (1.0 and 1.6 bar x 4 loads) of the bundled 460/85 R34 file with
    PFZ1 = 1.2 and Q_FZ2 = 2, handed the file with both at their neutral values. With a 0.2 % load cell the data
    determine both (noise-free: Q_FZ2 1.99 recovered): both are added and the excess of the leave-one-out error
    over the truth's shrinks by more than 70 %; with 1 % noise the hardening changes the 8 loads by less than the
    noise (the pressure-stiffness fit alone is already closer to the data than the truth): PFZ1 is added, Q_FZ2
    is tried, not added, and stays at its given value."""
    import pandas as pd

    given = mftyre.load_tir(TIR_FILES / "agri_460_85R34_mf61.tir")
    truth = given.with_params(PFZ1=1.2, Q_FZ2=2.0)
    p = truth.params
    fz = np.tile(np.array([0.4, 0.7, 1.0, 1.3]) * p.FNOMIN, 2)
    pressure = np.repeat([1.0e5, 1.6e5], 4)
    rl, rho = truth.loaded_radius(fz, p=pressure, omega=0.5 / p.UNLOADED_RADIUS)
    noisy = fz * (1.0 + noise * np.random.default_rng(1).normal(size=fz.size))
    data = TyreData(pd.DataFrame(dict(TEST="vertical", SWEEP=np.repeat([0, 1], 4), FZ=noisy, SL=0.0, SA=0.0, IA=0.0,
                                      VX=0.5, P=pressure, RL=rl, RHO=rho)), source="460/85R34, 8 points")
    rep = find_gaps(data, given.with_params(PFZ1=0.0, Q_FZ2=0.0))
    tried = {c.name for r in rep.rounds for c in r}
    assert "vertical_hardening" in tried
    if noise < 0.005:
        assert sorted(rep.effect_names) == ["pressure_vertical_stiffness", "vertical_hardening"], rep.message
        true = rep.held_out_error(truth)["FZ"]
        assert (rep.error_after["FZ"] - true) < 0.3 * (rep.error_before["FZ"] - true)
        assert rep.model.params.Q_FZ2 == pytest.approx(2.0, rel=0.5)
    else:
        assert rep.effect_names == ["pressure_vertical_stiffness"], rep.message
        assert rep.model.params.Q_FZ2 == 0.0
        assert rep.model.params.PFZ1 == pytest.approx(1.2, rel=0.05)


# ------------------------------------------------------------------------------------ verify before writing (#11)
def test_shifts_are_untestable_from_slip_of_one_sign():
    """Drive-side slip sweeps only (kappa >= 0) with a large Fx offset: the Fx shifts would fit the data, but the
    .tir would carry the offset into braking, where there are no data (issue 11: Fx = -62 / +171 N at kappa =
    -/+0.05, an invented asymmetry). Shifts act across kappa = 0, so slip of one sign cannot tell them from the
    curve's shape (issue 18): the effect is reported untestable with that reason, never tried, the improved model
    stays odd in kappa and passes verification."""
    full = _tyre_a()
    d = trailer_programme(full, points=21, noise=1.0, seed=3, cambers_deg=(0.0,), combined_alpha_deg=())
    d = d.select((d.frame["TEST"].to_numpy() == "pure_longitudinal") & (d.frame["SL"].to_numpy() >= 0))
    frame = d.frame.copy()
    frame["FX"] = frame["FX"] + 0.3 * frame["FZ"]
    rep = find_gaps(d.with_frame(frame, "Fx offset"), neutralise(full, "fx_shift"))
    assert "fx_shift" not in rep.effect_names   # (a load-curvature term may take up part of the offset)
    assert "one sign only" in rep.untestable["fx_shift"]
    assert not {"fx_shift"} & {c.name for r in rep.rounds for c in r}
    fx = rep.model.evaluate(4000.0, np.array([-0.05, 0.05]), 0.0, 0.0, 0.0, limits=False)["fx"]
    assert abs(fx[0] + fx[1]) < 0.02 * 4000.0
    from mftyre.fit.verify import verify_tir
    assert verify_tir(rep.model) == []


# ------------------------------------------------------------------- realistic rig data, realistic noise (#11)
# 100 Hz time series from the fit helper's generator (mftyre.rig): AR(1) noise at the realistic level (1 x NOISE),
# relaxation hysteresis, friction drifting over the day, load scatter, levels that are not round numbers. The gap
# finder reduces each sweep (up and down branches apart), so its held-out errors are those of binned means; the
# target is the excess of the held-out error over the true model's (friction drift and load scatter are errors
# of every steady-state model): it must shrink by at least 70 %.
# notebooks/04_gap_finder.ipynb runs the Fy case, pressure_cornering_stiffness hidden in these data (the same
# truth, programme and seed), and asserts what these cases assert (tests/test_notebooks.py).
RIG_CASES = {
    # id: (hidden effects, rig_programme keywords)
    "rig-fx-pressure_slip_stiffness": (("pressure_slip_stiffness",), dict(combined_alpha_deg=())),
    "rig-mx-camber_overturning": (("camber_overturning",), dict(longitudinal=False)),
    "rig-control-nothing-hidden": ((), dict(longitudinal=False)),
}
_RIG = {}


def _rig(kw_key, kw):
    from mftyre.rig import rig_programme

    if kw_key not in _RIG:
        _RIG[kw_key] = rig_programme(_tyre_a(), loads=(0.5, 1.0, 1.5), noise=1.0, seed=21, **kw)
    return _RIG[kw_key]


@pytest.mark.parametrize("case", list(RIG_CASES))
def test_rig_data_at_realistic_noise(case):
    hidden, kw = RIG_CASES[case]
    full = _tyre_a()
    data = _rig(repr(sorted(kw.items())), kw)
    rep = find_gaps(data, neutralise(full, *hidden))
    assert rep.reduction and "100 Hz" in rep.programme
    assert "3 loads" in rep.programme and "3 pressures" in rep.programme and "27 slip-angle sweeps" in rep.programme
    assert sorted(rep.effect_names) == sorted(hidden), rep.message
    true = rep.held_out_error(full)
    for c in sorted({CATALOGUE[h].channels[0] for h in hidden}):
        excess_before, excess_after = rep.error_before[c] - true[c], rep.error_after[c] - true[c]
        print(case, c, "held-out", rep.error_before[c], "->", rep.error_after[c], "true model", true[c])
        assert excess_before > 0 and excess_after <= 0.3 * excess_before, (c, rep.error_before[c],
                                                                            rep.error_after[c], true[c])
    # the up/down hysteresis is named as the transient effect it is, with a relaxation length near the model's
    named = {t["channel"]: t for t in rep.transient}
    assert "FY" in named and "PTY1" in named["FY"]["parameters"] and "relaxation length" in rep.message
    assert 0.6 < named["FY"]["relaxation_length"] / named["FY"]["model_relaxation_length"] < 1.4
    assert "Transient effects" in rep.markdown()


# ------------------------------------------------------------------------------- honest statistics (#11)
def test_autocorrelated_samples_do_not_make_a_negligible_gain_significant():
    """100 Hz samples with AR(1) noise (lag-one correlation 0.95): a constant offset fitted to the noise of the
    training sweeps changes the held-out error by a negligible amount (like 7.120 -> 7.119 %). Counted as
    independent rows it passes the F test; with the effective number of samples and whole held-out sweeps it does
    not."""
    import pandas as pd
    from scipy.signal import lfilter

    from mftyre.gaps.core import _n_eff, _sweep_test, f_test
    from mftyre.gaps.refit import refit

    full = _tyre_a()
    rng = np.random.default_rng(8)
    n_sweeps, m, rho, sd = 40, 600, 0.95, 20.0
    alpha = np.tile(np.radians(np.linspace(-8.0, 8.0, m)), n_sweeps)
    fz = np.full(alpha.size, 4000.0)
    fy = full.evaluate(fz, 0.0, alpha, 0.0, 0.0).fy
    noise = lfilter([1.0], [1.0, -rho], rng.normal(0.0, sd * math.sqrt(1 - rho**2), alpha.size))
    frame = pd.DataFrame(dict(FZ=fz, SL=0.0, SA=alpha, IA=0.0, VX=16.7, P=full.params.NOMPRES, PHIT=0.0,
                              FY=fy + noise, SWEEP=np.repeat(np.arange(n_sweeps), m)))
    data = TyreData(frame, source="AR(1) noise")
    train, test = data.select(frame["SWEEP"].to_numpy() % 4 != 0), data.select(frame["SWEEP"].to_numpy() % 4 == 0)
    ev_tr, ev_te = Evaluator(train, ["FY"]), Evaluator(test, ["FY"])
    sigma = {"FY": (sd,)}
    new, res = refit(full.params, ev_tr, ["PVY1"], ["FY"], sigma)
    n = ev_tr.measured["FY"].size
    n_eff = _n_eff(ev_tr, new, ["FY"])
    assert n_eff == pytest.approx(n * (1 - rho) / (1 + rho), rel=0.25)
    err0 = mftyre.fit.metrics.normalised_rms(ev_te.predict(full)["FY"], ev_te.measured["FY"])
    err1 = mftyre.fit.metrics.normalised_rms(ev_te.predict(new)["FY"], ev_te.measured["FY"])
    assert abs(err1 - err0) < 0.01 * err0          # a negligible held-out change
    _, p_rows = f_test(res.chi2_before, res.chi2_after, n, n, 1)
    _, p_eff = f_test(res.chi2_before, res.chi2_after, n, n_eff, 1)
    print("n", n, "n_eff", n_eff, "held-out", err0, err1, "p rows", p_rows, "p n_eff", p_eff)
    assert p_rows < 1e-3 < p_eff                   # significant only when 100 Hz rows count as independent
    p_sweeps, sweeps = _sweep_test(ev_te, full, new, sigma, ["FY"])
    print("held-out sweeps", sweeps, "p", p_sweeps)
    assert sweeps == 0 or p_sweeps > 0.05


# ----------------------------------------------------------- judged by physics and the data, not our files (#18)
from conftest import SHARED, require_shared  # noqa: E402

_PUBLISHED = ["tir_files/" + p.name for p in sorted(TIR_FILES.glob("*.tir"))] + [
    "reference/mfeval/" + n for n in ("FSAE_Defaults.tir", "MagicFormula52_Parameters.tir",
                                      "MagicFormula61_Parameters.tir", "MagicFormula62_Parameters.tir",
                                      "PacejkaBook_Defaults.tir")] + ["reference/tir/TNO_car205_60R15.tir"]


def _published(name):
    return TIR_FILES / name.split("/", 1)[1] if name.startswith("tir_files/") else require_shared(SHARED / name)


@pytest.mark.parametrize("name", _PUBLISHED)
def test_every_published_tir_passes_verification(name):
    """Issue 18: real files declare "don't care" ranges (TNO's own MF 6.2 example: PRESMIN 0.1 bar, PRESMAX 10 bar,
    where 1 + PPY1 dpi < 0 turns Fy round). Verification covers the domain that matters (a standard programme's
    loads and pressures, the declared slips, speeds to 2 LONGVL), so no published file fails it; what it finds
    beyond, in the physical domain, is a warning naming the range (the MFeval FSAE file's slip stiffness
    PKX1 + PKX2 dfz turns negative above 1.63 FNOMIN: Fx reverses at Fz = FZMAX = 2 FNOMIN)."""
    import warnings as _warnings

    from mftyre.fit.verify import verification

    model = mftyre.load_tir(_published(name))
    with _warnings.catch_warnings():
        _warnings.simplefilter("error", mftyre.InputClippedWarning)   # the checks stay within the .tir ranges
        v = verification(model)
    assert v.problems == [], v.problems
    if name.endswith("FSAE_Defaults.tir"):
        assert any(w.kind == "fx_sign" and "beyond the data" in w and "Fz 50..2000 N" in w for w in v.warnings)


@pytest.mark.parametrize("name", _PUBLISHED)
def test_every_published_value_lies_within_the_fit_bounds_in_an_equivalent_form(name):
    """A fit started from a published file must start from its curves: the MFeval 6.1/6.2 samples have QSX11 =
    -1.76 (bounds 0..100), RVY4 = -97 and RVY6 = -27.5. These parameters are sign-symmetric (with QSX10, -, RVY5),
    so the same tyre in the other sign lies within the bounds; every other value lies within them as it is."""
    from mftyre.fit.core import BOUNDS, sign_in_bounds

    model = mftyre.load_tir(_published(name))
    same = sign_in_bounds(model.params)
    outside = {k: float(same[k]) for k, (lo, hi) in BOUNDS.items()
               if k in PARAMETERS and model.params.version in PARAMETERS[k].versions
               and not lo <= float(same[k]) <= hi}
    assert outside == {}, outside
    # the same tyre: every output equal over slip, camber, load and pressure
    n = 400
    rng = np.random.default_rng(0)
    p0 = model.params
    x = dict(fz=rng.uniform(0.3, 1.8, n) * p0.FNOMIN, kappa=rng.uniform(-0.3, 0.3, n),
             alpha=rng.uniform(-0.2, 0.2, n), gamma=rng.uniform(-0.08, 0.08, n),
             p=rng.uniform(0.8, 1.2, n) * p0.NOMPRES, vx=np.full(n, 20.0))
    a, b = model.evaluate(**x, limits=False), mftyre.MFModel(same).evaluate(**x, limits=False)
    for k in ("fx", "fy", "mx", "my", "mz"):
        np.testing.assert_allclose(getattr(b, k), getattr(a, k), rtol=1e-12, atol=1e-9 * p0.FNOMIN)


def test_refit_of_mx_from_a_published_file_with_negative_qsx11_stays_on_its_curve():
    """Issue 18 (benchmark): the MF 6.1 sample has QSX10 atan(QSX11 Fz/Fz0) gamma with QSX11 = -1.76 < 0, outside
    the fit bounds 0..100. The refit started from QSX11 clipped to 0 (no camber x load term at all) and ran off to
    QSX10 = -2e9, QSX11 = 1e-10, a worse Mx; after camber thrust was added, Mx was 24 % worse on held-out data and
    an unrelated Mx effect (QSX13/QSX14) won. Started from the same tyre in the other sign, the refit stays on it."""
    from mftyre.gaps import Evaluator
    from mftyre.gaps.refit import refit_stages

    truth = mftyre.load_tir(require_shared(SHARED / "reference/mfeval/MagicFormula61_Parameters.tir"))
    data = trailer_programme(truth, points=9, noise=NOISE, seed=1)
    stale = neutralise(truth, "camber_thrust").params      # its Fy lacks camber thrust: Mx refitted around it
    new, res = refit_stages(stale, data, ["mx"], channels=["MX"])
    assert "QSX11" in res["mx"].names
    ev = Evaluator(data, ["MX"])
    err = {k: mftyre.fit.metrics.normalised_rms(ev.predict(m)["MX"], ev.measured["MX"])
           for k, m in (("truth", truth.params), ("new", new))}
    assert abs(new.QSX10) < 10 and abs(new.QSX11) > 0.1, (new.QSX10, new.QSX11)
    assert err["new"] < 1.2 * err["truth"], err


def test_tno_pressure_cornering_stiffness_is_accepted():
    """Issue 18 item 1: with TNO's MF 6.2 file as the truth and PPY1 = PPY2 = 0, the gap finder used to name
    pressure_cornering_stiffness and then reject it because the improved file "fails verification" at 10 bar
    (which the truth itself does). Judged on the data's domain and relative to the given file it is added and the
    held-out Fy error's excess over the truth shrinks by 70 %; the file as given (PPY1 = 0) passes too."""
    tno = mftyre.load_tir(require_shared(SHARED / "reference/tir/TNO_car205_60R15.tir"))
    d = trailer_programme(tno, points=15, noise=NOISE, seed=5, cambers_deg=(0.0,), combined_alpha_deg=())
    d = d.select(d.frame["TEST"].to_numpy() == "pure_lateral")
    rep = find_gaps(d, neutralise(tno, "pressure_cornering_stiffness"))
    assert rep.effect_names == ["pressure_cornering_stiffness"] and not rep.rejected, (rep.message, rep.rejected)
    true = rep.held_out_error(tno)
    assert rep.error_after["FY"] - true["FY"] <= 0.3 * (rep.error_before["FY"] - true["FY"])


def test_no_warning_flood_from_our_own_checks():
    """Issue 18 item 7: on rig data whose lowest pressure lies below the tyre's PRESMIN (the generator's 0.86
    NOMPRES with its jitter, against PRESMIN = 0.845 NOMPRES), the fit printed 24 and the gap finder over a thousand
    InputClippedWarnings from their own verification grids and repeated evaluations. Now the verification stays
    within the .tir ranges and each workflow says once that the data lie outside them."""
    import warnings as _warnings

    from mftyre.fit import fit_tir
    from mftyre.rig import rig_programme

    full = _tyre_a()
    data = rig_programme(full, loads=(0.5, 1.0, 1.5), cambers_deg=(0.0,), longitudinal=False, seed=11)
    assert np.min(data.array("P")) < full.params.PRESMIN
    for run in (lambda: fit_tir(data, compare=False),
                lambda: find_gaps(data, neutralise(full, "pressure_cornering_stiffness"))):
        with _warnings.catch_warnings(record=True) as caught:
            _warnings.simplefilter("always")
            run()
        clipped = [str(w.message) for w in caught if issubclass(w.category, mftyre.InputClippedWarning)]
        assert len(clipped) <= 1, clipped[:3]
        assert all("p outside PRESMIN..PRESMAX" in m for m in clipped)


def _vertical_sweeps(full, seed=1):
    """Load-deflection sweeps (41 points, 0.1-2 FNOMIN) at 0.85, 1 and 1.15 NOMPRES: FZ, RL, RHO only."""
    d = trailer_programme(full, loads=(1.0,), pressures=(0.85, 1.0, 1.15), cambers_deg=(0.0,), points=5,
                          vertical_points=41, noise=NOISE, seed=seed)
    d = d.select(d.frame["TEST"].to_numpy() == "vertical")
    return TyreData(d.frame[["TEST", "SWEEP", "FZ", "SL", "SA", "IA", "VX", "P", "RL", "RHO"]],
                    source="load-deflection")


def test_pressure_vertical_stiffness_is_not_rejected_by_a_collapsed_n_eff():
    """Issue 18 item 2: TNO's MF 6.2 file with PFZ1 = 0, load-deflection sweeps at three pressures. The
    candidate PFZ1 explained most of the held-out chi-square and was rejected (p = 0.02-0.07): the AR(1) count of
    independent residuals came from residuals still dominated by the structure under test (n_eff about 5 of 123
    rows). Point data have independent noise: the honest count is the number of rows; the AR(1) count of the
    residual lacking the effect (about half the rows here) is
    shown beside it. The held-out error's excess over the truth shrinks by more than 90 %."""
    tno = mftyre.load_tir(require_shared(SHARED / "reference/tir/TNO_car205_60R15.tir"))
    rep = find_gaps(_vertical_sweeps(tno), neutralise(tno, "pressure_vertical_stiffness"))
    assert rep.effect_names == ["pressure_vertical_stiffness"], rep.message
    cand = rep.rounds[0][0]
    assert cand.n_eff == cand.n_train and cand.n_eff_residual < 0.6 * cand.n_train
    true = rep.held_out_error(tno)
    assert rep.error_after["FZ"] - true["FZ"] <= 0.1 * (rep.error_given["FZ"] - true["FZ"])
    assert "n_eff" in rep.markdown()


def test_fair_start_never_worsens_the_held_out_error():
    """Issue 18 item 3: trained on two of the three pressures' sweeps, the fair start's vertical refit (without
    PFZ1) raised the held-out FZ error from 9.5 % (the file as given) to 14.2 %. A stage that loses on the held-out
    data keeps the given values, with the reason."""
    full = _tyre_a()
    rep = find_gaps(_vertical_sweeps(full), neutralise(full, "pressure_vertical_stiffness"))
    for c in rep.error_given:
        assert rep.error_before[c] <= rep.error_given[c] * (1 + 1e-9), (c, rep.error_given, rep.error_before)
    assert rep.effect_names == ["pressure_vertical_stiffness"]


def test_friction_decay_with_slip_speed_needs_slip_at_two_speeds():
    """Benchmark (MFeval 6.1/6.2 rig data): the slip-angle sweeps run at one speed, the speed sweep free rolling.
    speed_friction (LMUV) was a candidate because the speeds varied over the whole data, and was added beside the
    hidden effect: at one speed a friction decay with slip speed is a change of the curve's shape. It is now
    untestable unless the slip is swept at two or more speeds."""
    from mftyre.data import TyreData
    from mftyre.gaps.core import _candidates, _prepare
    from mftyre.rig import rig_programme

    full = _tyre_a().with_params(LMUV=0.0)
    kw = dict(loads=(0.6, 1.2), pressures=(1.0,), cambers_deg=(0.0,), longitudinal=False, seed=2)
    one = rig_programme(full, **kw)
    assert np.ptp(one.array("VX")) > 20.0        # a free-rolling speed sweep is in the data
    two = TyreData.concat([one, rig_programme(full, speed=0.5 * full.params.LONGVL, **kw)])
    found = {}
    for name, data in (("one", one), ("two", two)):
        run = _prepare(data, full, 0.25, 0, None, None, 1e-3, None, lambda text: None, 0.0)
        found[name] = _candidates([CATALOGUE["speed_friction"]], run.given, run.train, run.ts)
    cands, untestable = found["one"]
    assert list(untestable) == ["speed_friction"] and "slip swept at one speed" in untestable["speed_friction"] \
        and "slip-angle sweep" not in untestable["speed_friction"], untestable
    cands, untestable = found["two"]
    assert "speed_friction" in cands, untestable


def test_an_effect_scored_with_its_stages_refitted_is_compared_with_them_refitted_without_it():
    """Benchmark (MFeval 6.1 sample, 100 Hz rig run, camber_overturning hidden): when no candidate is significant
    alone, the strongest few are scored with their stages refitted. They were compared with the model before that
    refit, so the refit's own gain counted as theirs, and after camber_overturning an unrelated Mx effect
    (camber_squared_overturning, QSX12 = 0 in the truth) was added on the strength of the Mx stage refitted."""
    from mftyre.rig import rig_programme

    truth = mftyre.load_tir(require_shared(SHARED / "reference/mfeval/MagicFormula61_Parameters.tir"))
    data = rig_programme(truth, loads=(0.5, 1.0, 1.5), longitudinal=False, seed=5)
    rep = find_gaps(data, neutralise(truth, "camber_overturning"), effects=[
        "camber_overturning", "camber_squared_overturning", "lateral_force_overturning_camber"])
    assert rep.effect_names == ["camber_overturning"], [(c.name, c.held_out_gain, c.note) for r in rep.rounds
                                                        for c in r]
    true = rep.held_out_error(truth)["MX"]
    assert rep.error_after["MX"] - true <= 0.3 * (rep.error_before["MX"] - true)


def test_an_effect_made_redundant_by_a_later_one_is_taken_out_again():
    """Forward selection with a backward check (MFeval 6.1 sample, trailer points, camber_overturning hidden): a
    small Mx effect (lateral_force_overturning_camber, QSX13 = QSX14 = 0 in the truth) can win the first round
    while the fair start has bent QSX4-QSX9 towards the missing camber term (it did, while the Mx stage's refit
    crept along a flat valley). Added first and camber_overturning after it, the first no longer passes its test
    with the second in and is taken out again; the Mx gap closes with the second alone."""
    from mftyre.gaps.core import _candidates, _fair_start, _noise, _prepare, _Search

    truth = mftyre.load_tir(require_shared(SHARED / "reference/mfeval/MagicFormula61_Parameters.tir"))
    data = trailer_programme(truth, points=15, noise=NOISE, seed=5)
    run = _prepare(data, neutralise(truth, "camber_overturning"), 0.25, 0, None, None, 1e-3, None,
                   lambda text: None, 0.0)
    start, _, active = _fair_start(run)
    order = ("lateral_force_overturning_camber", "camber_overturning")
    candidates, _ = _candidates([CATALOGUE[n] for n in order], run.given, run.train, run.ts)
    search = _Search(run, start, _noise(run, start), candidates, active)
    for name in order:
        (cand, new), = search.trials([candidates[name]], len(search.rounds) + 1)
        search.rounds.append([cand])
        search.add(cand, new)
    assert [a.name for a in search.added] == list(order)
    search.recheck()
    assert [a.name for a in search.added] == ["camber_overturning"], search.rejected
    assert "then taken out" in search.rejected["lateral_force_overturning_camber"], search.rejected
    mx = {name: float(np.sqrt(np.mean(run.ev_test.residuals(prm, ["MX"])["MX"] ** 2)))
          for name, prm in (("before", start), ("after", search.prm), ("true", truth.params))}
    assert mx["after"] - mx["true"] <= 0.3 * (mx["before"] - mx["true"]), mx
