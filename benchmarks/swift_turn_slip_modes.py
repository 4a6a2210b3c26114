"""SWIFT turn slip from the contact patch's yaw rate: the linearised ring's worst eigenvalue with and without it,
beside the sign of the MF's own turn-slip moment, on every bundled and shared SWIFT file:

    python benchmarks/swift_turn_slip_modes.py [--tir FILE.tir ...] [--loads 2000 4000 8000]

Per file and load: max Re(lambda) [1/s] of the ring (swift.modes: flat road, axle height fixed at the loaded radius,
rim free to spin, INFLPRES) over 0.5-70 m/s forward and reverse, with ``turn_slip`` off and on (the speed, the
frequency of that mode; speeds without a static equilibrium are listed), and dMz/dphit, dMzr/dphit [N m per
1/m] of MFModel.evaluate(turn_slip=True) at zero slip (:func:`swift.ring.turn_slip_moment_slopes`): positive = the MF moment pushes the patch along its yaw rate, the case
:class:`mftyre.errors.TurnSlipWarning` names. Loads: 0.5, 1, 2 FNOMIN (2, 4, 8 kN on the 205/60 R15 files).
"""
from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

import mftyre

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "reference"
SPEEDS = [s * v for v in (0.5, 1.0, 2.0, 4.0, 7.0, 9.0, 15.0, 30.0, 70.0) for s in (1.0, -1.0)]


def default_files():
    bundled = sorted((ROOT / "tir_files").glob("*.tir"))
    shared = [SHARED / "tir" / "TNO_car205_60R15.tir"] + sorted((SHARED / "mfeval").glob("*.tir"))
    return [p for p in bundled + shared if p.exists() and "BELT_MASS" in p.read_text(errors="replace")]


def worst(tyre, fz):
    from swift.modes import modes

    from mftyre.errors import ModelInputError

    rows, missing = [], []
    for v in SPEEDS:
        try:
            rows.append(modes(tyre, v, fz))
        except ModelInputError:  # no static equilibrium (agricultural tyres at 70 m/s): listed, not hidden
            missing.append(v)
    row = max(rows, key=lambda r: r.max_real)
    ev = row.eigenvalues[np.argmax(row.eigenvalues.real)]
    return row.max_real, row.vx, abs(ev.imag) / (2 * np.pi), missing


def main():
    from swift import Flat, SwiftTyre
    from swift.ring import turn_slip_moment_slopes

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", nargs="+", type=Path, default=default_files())
    ap.add_argument("--loads", nargs="+", type=float, default=None, help="vertical loads [N]")
    args = ap.parse_args()
    print(f"{'file':34s} {'Fz':>6s} {'dMz/dphit':>10s} {'dMzr/dphit':>10s} | {'off: max Re':>11s} {'at m/s':>7s} "
          f"{'Hz':>5s} | {'on: max Re':>10s} {'at m/s':>7s} {'Hz':>5s}")
    for path in args.tir:
        t0 = time.process_time()
        model = mftyre.load_tir(path)
        fnom = model.params.FNOMIN
        loads = args.loads or [0.5 * fnom, fnom, 2 * fnom]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tyres = [SwiftTyre(model, Flat(), axle="height", rim="torque", x_range=(0.0, 3.0), compiled=False,
                               turn_slip=on) for on in (False, True)]
        slopes = turn_slip_moment_slopes(model, loads)
        for fz, (_, slope, residual) in zip(loads, slopes):
            off, on = worst(tyres[0], fz), worst(tyres[1], fz)
            print(f"{path.name:34s} {fz:6.0f} {slope:+10.1f} {residual:+10.1f} | {off[0]:+11.3g} {off[1]:+7.1f} "
                  f"{off[2]:5.0f} | {on[0]:+10.3g} {on[1]:+7.1f} {on[2]:5.0f}" + ("  GROWS" if on[0] > 0 else "")
                  + (f"  (no equilibrium at {off[3]} m/s)" if off[3] else ""))
        print(f"{'':34s} ({time.process_time() - t0:.1f} s CPU)", flush=True)


if __name__ == "__main__":
    main()
