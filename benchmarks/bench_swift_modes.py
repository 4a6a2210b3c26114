"""SWIFT linear modes: the eigenvalue table of the rigid ring rolling on a flat road (swift.modes), axle height
fixed at the loaded radius, rim free to spin, no slip:

    python benchmarks/bench_swift_modes.py [--tir FILE.tir ...] [--load 4000] [--grid] [--all]

Per file: for each speed the damped natural frequencies [Hz] with their damping ratios, sorted by frequency, and
the slowest decay rate max Re(lambda) [1/s] (negative: every mode damped). ``--grid``: also the worst point of
the scan of tests/test_swift_modes.py (0.5-70 m/s forward and reverse, 2-8 kN) at each of seven pressures over
the declared PRESMIN..PRESMAX, with the MF's cornering-stiffness pressure factor 1 + PPY1 dpi beside it (the TNO
file's turns negative at 5.72 bar: the modes grow there, the MF's Kya having reversed) and the time it took. Default files: the bundled SWIFT sample and the shared TNO file.
``--all``: the README's eigenvalue table: every bundled and shared .tir file with SWIFT data (BELT_MASS), speeds
0.5-70 m/s forward and reverse (``GRID_SPEEDS``), loads 0.25, 0.5, 1, 1.5 FNOMIN and FZMAX, pressures PRESMIN,
INFLPRES, PRESMAX; per file and pressure and load the slowest decay max Re [1/s] (with its speed), the speeds
without a static equilibrium, and where a Magic Formula property of the file has the wrong sign
(:func:`mftyre.inputs.load_factor_edges`, :func:`mftyre.inputs.pressure_factor_edges`) the mark "MF".
"""
from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import mftyre
from mftyre.formula import vertical

ROOT = Path(__file__).resolve().parents[1]
SPEEDS = (0.5, 2.0, 7.0, 15.0, 25.0, 40.0, 70.0, -7.0)
GRID_SPEEDS = [s * v for v in (0.5, 2.0, 4.0, 7.0, 9.0, 15.0, 30.0, 70.0) for s in (1.0, -1.0)]


def main():
    from swift import Flat, SwiftTyre
    from swift.modes import modes, scan

    default = [ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir",
               ROOT.parent / "shared" / "reference" / "tir" / "TNO_car205_60R15.tir"]
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", nargs="+", type=Path, default=[p for p in default if p.exists()])
    ap.add_argument("--load", type=float, default=4000.0, help="vertical load of the table [N]")
    ap.add_argument("--grid", action="store_true", help="also the worst point of the full scan")
    ap.add_argument("--all", action="store_true", help="the scan of every SWIFT file up to FZMAX (README table)")
    args = ap.parse_args()
    if args.all:
        return scan_all()
    for path in args.tir:
        model = mftyre.load_tir(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tyre = SwiftTyre(model, Flat(), axle="height", rim="torque", x_range=(0.0, 3.0))
        prm = model.params
        print(f"\n{path.name}: Fz {args.load:.0f} N, p {prm.INFLPRES / 1e5:.2f} bar; frequency [Hz] (damping ratio)")
        print(f"{'vx [m/s]':>9}  {'max Re [1/s]':>12}  modes")
        for v in SPEEDS:
            m = modes(tyre, v, args.load)
            order = m.frequency.argsort()
            cells = "  ".join(f"{f:5.1f} ({z:.3f})" for f, z in zip(m.frequency[order], m.damping[order]))
            print(f"{v:9.1f}  {m.max_real:12.2f}  {cells}")
        if args.grid:
            import numpy as np

            for p in sorted(set(np.geomspace(prm.PRESMIN, prm.PRESMAX, 7)) | {prm.INFLPRES}):
                t0 = time.perf_counter()
                rows = scan(tyre, GRID_SPEEDS, (2000.0, 5000.0, 8000.0), [p])
                worst = max(rows, key=lambda r: r.max_real)
                dpi = vertical.pressure_increment(prm, p)
                print(f"p {p / 1e5:5.2f} bar (1 + PPY1 dpi = {1 + prm.PPY1 * dpi:6.3f}): {len(rows)} points "
                      f"({time.perf_counter() - t0:.1f} s), slowest decay {worst.max_real:9.2f} 1/s at vx {worst.vx} "
                      f"m/s, Fz {worst.fz:.0f} N")

def swift_files() -> list[Path]:
    """Every bundled and shared .tir file with SWIFT data (a BELT_MASS line)."""
    shared = ROOT.parent / "shared" / "reference"
    paths = sorted((ROOT / "tir_files").glob("*.tir")) + sorted(shared.glob("*/*.tir"))
    return [p for p in paths if any(line.split("=")[0].strip().upper() == "BELT_MASS"
                                    for line in p.read_text(errors="replace").splitlines())]


def scan_all():
    import numpy as np

    from mftyre.errors import ModelInputError
    from mftyre.inputs import load_factor_edges, pressure_factor_edges
    from swift import Flat, SwiftTyre
    from swift.modes import modes

    print("file | p [bar] | Fz [N] | slowest decay max Re [1/s] (at vx [m/s]) | no equilibrium at vx [m/s] | MF")
    for path in swift_files():
        model = mftyre.load_tir(path)
        prm = model.params
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tyre = SwiftTyre(model, Flat(), axle="height", rim="torque", x_range=(0.0, 3.0))
        loads = sorted({f * prm.FNOMIN for f in (0.25, 0.5, 1.0, 1.5) if f * prm.FNOMIN < prm.FZMAX} | {prm.FZMAX})
        t0, worst_valid, points, failed = time.perf_counter(), (-np.inf, None), 0, 0
        for p in sorted({prm.PRESMIN, prm.INFLPRES, prm.PRESMAX}):
            dpi = vertical.pressure_increment(prm, p)
            p_bad = [names for edge, side, names, _ in pressure_factor_edges(prm)
                     if (p >= edge if side > 0 else p <= edge)]
            for fz in loads:
                bad = p_bad + [names for edge, names, _ in load_factor_edges(prm, dpi)
                               if (fz >= edge) != (prm.FNOMIN * prm.LFZO >= edge)]
                rates, none = [], []
                for v in GRID_SPEEDS:
                    points += 1
                    try:
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            rates.append((modes(tyre, v, fz, p).max_real, v))
                    except ModelInputError:
                        none.append(v)
                        failed += 1
                worst = max(rates) if rates else (np.nan, None)
                if not bad and rates and worst[0] > worst_valid[0]:
                    worst_valid = (worst[0], (p, fz, worst[1]))
                print(f"{path.name} | {p / 1e5:.2f} | {fz:.0f} | {worst[0]:.3g} ({worst[1]}) | "
                      f"{' '.join(f'{v:g}' for v in none) or '-'} | {'; '.join(bad) or '-'}")
        p, fz, v = worst_valid[1]
        print(f"== {path.name}: {points} points ({time.perf_counter() - t0:.1f} s), {failed} without equilibrium; "
              f"where the MF's properties keep their sign the slowest decay is {worst_valid[0]:.3g} 1/s "
              f"(p {p / 1e5:.2f} bar, Fz {fz:.0f} N, vx {v} m/s)")


if __name__ == "__main__":
    main()
