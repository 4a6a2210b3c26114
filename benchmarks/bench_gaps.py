"""Hidden-effect benchmark of the gap finder on tyres we did not write (issue 18).

    python benchmarks/bench_gaps.py [--truths tno,mf61,mf62,book] [--programmes trailer,rig,drive_brake,deflection]

Truths: TNO's public MF 6.2 example (``../shared/reference/tir/TNO_car205_60R15.tir``) and the MFeval sample files
(``../shared/reference/mfeval``: MagicFormula61/62_Parameters, PacejkaBook_Defaults). For each truth and test
programme, every catalogue effect the programme can test and the truth has switched on is removed in turn
(its switches at their neutral values, :func:`mftyre.gaps.neutralise`), and the gap finder is handed that file
and data generated from the truth. Programmes, as labs run them:

* ``trailer``: point data (:func:`mftyre.data.trailer_programme`, 15 points per sweep, 3 loads x 3 pressures x 3
  cambers, realistic noise);
* ``rig``: 100 Hz slip-angle sweeps (:func:`mftyre.rig.rig_programme`, AR(1) noise, hysteresis, drift, load
  scatter; 3 loads x 3 pressures x 3 cambers, no slip-ratio sweeps);
* ``drive_brake``: one-sided: slip-ratio sweeps at alpha 0, -3, -6 deg, one pressure, camber 0;
* ``deflection``: 8 load-deflection points (2 pressures x 4 loads, 1 % load noise).

A case passes when the hidden effect is named, nothing unrelated is added, and the held-out error's excess over
the truth's shrinks by at least 70 % on the effect's primary channel; a control (nothing hidden) passes when
nothing is added. A nuisance of the measurement the finder names (the rig's friction drift over the test day,
:mod:`mftyre.gaps.drift`) is shown in brackets: it is no effect of the tyre. Prints one row per case and the pass count. Nothing here is tuned to a case: the cases are
every testable effect of the catalogue.
"""
from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

import mftyre  # noqa: E402
from mftyre.data import TyreData, trailer_programme  # noqa: E402
from mftyre.gaps import CATALOGUE, find_gaps, neutralise  # noqa: E402
from mftyre.gaps.catalogue import effect_state  # noqa: E402
from mftyre.rig import rig_programme  # noqa: E402

SHARED = Path(__file__).resolve().parents[2] / "shared" / "reference"
TRUTHS = {"tno": SHARED / "tir" / "TNO_car205_60R15.tir", "mf61": SHARED / "mfeval" / "MagicFormula61_Parameters.tir",
          "mf62": SHARED / "mfeval" / "MagicFormula62_Parameters.tir",
          "book": SHARED / "mfeval" / "PacejkaBook_Defaults.tir"}
#: per programme, the catalogue effects its conditions can show (load, pressure, camber, slip sweeps it holds)
EFFECTS = {
    "trailer": ("pressure_cornering_stiffness", "pressure_slip_stiffness", "pressure_friction_y", "pressure_trail",
                "camber_thrust", "camber_overturning", "camber_trail", "load_friction_y", "load_slip_stiffness",
                "pressure_vertical_stiffness", "pressure_rolling_resistance"),
    "rig": ("pressure_cornering_stiffness", "camber_thrust", "camber_overturning", "load_friction_y"),
    "drive_brake": ("load_friction_x", "load_slip_stiffness", "combined_fx"),
    "deflection": ("pressure_vertical_stiffness", "vertical_hardening"),
}


def programme(name: str, truth, seed: int = 5) -> TyreData:
    if name == "trailer":
        return trailer_programme(truth, points=15, noise=1.0, seed=seed)
    if name == "rig":
        return rig_programme(truth, loads=(0.5, 1.0, 1.5), longitudinal=False, seed=seed)
    if name == "drive_brake":
        d = trailer_programme(truth, points=21, noise=1.0, seed=seed, pressures=(1.0,), cambers_deg=(0.0,),
                              combined_alpha_deg=(-3.0, -6.0))
        test = d.frame["TEST"].to_numpy()
        return d.select((test == "pure_longitudinal") | (test == "combined") | (test == "free_rolling"))
    if name == "deflection":
        p = truth.params
        fz = np.tile(np.array([0.45, 0.75, 1.05, 1.35]) * p.FNOMIN, 2)
        pressure = np.repeat([0.8 * p.NOMPRES, 1.2 * p.NOMPRES], 4)
        rl, rho = truth.loaded_radius(fz, p=pressure, omega=1.0 / p.UNLOADED_RADIUS)
        noisy = fz * (1.0 + 0.01 * np.random.default_rng(seed).normal(size=fz.size))
        return TyreData(pd.DataFrame(dict(TEST="vertical", SWEEP=np.repeat([0, 1], 4), FZ=noisy, SL=0.0, SA=0.0,
                                          IA=0.0, VX=1.0, P=pressure, RL=rl, RHO=rho)), source="8 points")
    raise ValueError(name)


def run_case(truth, data, hidden):
    rep = find_gaps(data, neutralise(truth, *hidden) if hidden else truth)
    named = set(rep.effect_names)
    if not hidden:
        return not named, rep, float("nan")
    channel = CATALOGUE[hidden[0]].channels[0]
    true = rep.held_out_error(truth)[channel]
    before, after = rep.error_before[channel] - true, rep.error_after[channel] - true
    shrink = (before - after) / before if before > 0 else float("nan")
    ok = named == set(hidden) and before > 0 and shrink >= 0.7
    return ok, rep, shrink


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--truths", default=",".join(TRUTHS))
    ap.add_argument("--programmes", default=",".join(EFFECTS))
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    rows, t0 = [], time.perf_counter()
    for tname in args.truths.split(","):
        if not TRUTHS[tname].exists():
            print(f"skipped {tname}: {TRUTHS[tname]} not found (../shared beside the project)")
            continue
        truth = mftyre.load_tir(TRUTHS[tname])
        for pname in args.programmes.split(","):
            data = programme(pname, truth)
            cases = [()] + [(e,) for e in EFFECTS[pname] if effect_state(CATALOGUE[e], truth.params) == "active"]
            for hidden in cases:
                t1 = time.process_time()
                try:
                    ok, rep, shrink = run_case(truth, data, hidden)
                    added = (",".join(rep.effect_names) or "-") + "".join(f" [{a.name}]" for a in rep.nuisances)
                except Exception as exc:   # a crash is a failed case, reported
                    ok, added, shrink = False, f"error: {type(exc).__name__}: {exc}"[:60], float("nan")
                rows.append((tname, pname, hidden[0] if hidden else "(control)", added, shrink, ok,
                             time.process_time() - t1))
                r = rows[-1]
                print(f"{r[0]:5} {r[1]:11} {r[2]:30} added {r[3]:45} shrink {100 * r[4]:6.0f} %  "
                      f"{'PASS' if r[5] else 'fail'}  {r[6]:5.1f} s cpu", flush=True)
    n_ok = sum(r[5] for r in rows)
    hidden_rows = [r for r in rows if r[2] != "(control)"]
    print(f"\npassed {n_ok} of {len(rows)} cases ({sum(r[5] for r in hidden_rows)} of {len(hidden_rows)} hidden "
          f"effects, {n_ok - sum(r[5] for r in hidden_rows)} of {len(rows) - len(hidden_rows)} controls) in "
          f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
