"""Reading measured data: mftyre's CSV and TYDEX readers against plain ``pandas.read_csv`` of the same file,
side by side in one run (wall time, best of ``--repeat``; peak memory traced by tracemalloc).

    python benchmarks/bench_data.py [--rows 100000 1000000] [--repeat 3]

The files: every canonical channel (16 columns) plus SWEEP, random values written with 17 significant digits;
the TYDEX file has the same samples in a ``**MEASURDATA`` block. The baseline for TYDEX is pandas reading that
block alone (whitespace separated, rows after the header skipped). Target: mftyre <= 2x plain pandas.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import tracemalloc
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import best_time  # noqa: E402

from mftyre.data import CHANNELS, TyreData, read_csv, read_tydex, write_tydex  # noqa: E402


def _frame(rows: int) -> pd.DataFrame:
    rng = np.random.default_rng(1)
    frame = pd.DataFrame({ch: rng.normal(size=rows) for ch in CHANNELS})
    frame["FZ"] = rng.uniform(1000.0, 8000.0, rows)
    frame["P"] = rng.uniform(1.8e5, 2.6e5, rows)
    frame["VX"] = rng.uniform(5.0, 30.0, rows)
    frame["SWEEP"] = np.arange(rows) // 100
    return frame


def _files(rows: int, folder: Path) -> tuple[Path, Path, int]:
    frame = _frame(rows)
    csv = folder / f"data_{rows}.csv"
    frame.to_csv(csv, index=False, float_format="%.17g")
    tdx = folder / f"data_{rows}.tdx"
    write_tydex(TyreData(frame.iloc[:1].copy(), tyre="bench", source="bench"), tdx)  # the header blocks
    head = tdx.read_text().split("**MEASURDATA")[0] + "**MEASURDATA\n"
    with open(tdx, "w", encoding="utf-8") as fh:
        fh.write(head)
        frame[[c for c in CHANNELS] + ["SWEEP"]].to_csv(fh, sep=" ", header=False, index=False,
                                                        float_format="%.17g")
        fh.write("**END\n")
    return csv, tdx, head.count("\n")


def _peak_mb(fn) -> float:
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"{'file':<6} {'rows':>9} {'mftyre s':>9} {'pandas s':>9} {'ratio':>6} {'mftyre MB':>10} "
          f"{'pandas MB':>10} {'ratio':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for rows in args.rows:
            csv, tdx, head_lines = _files(rows, Path(tmp))
            repeat = args.repeat if rows <= 200_000 else 1
            cases = {
                "CSV": (lambda: read_csv(csv), lambda: pd.read_csv(csv)),
                "TYDEX": (lambda: read_tydex(tdx),
                          lambda: pd.read_csv(tdx, sep=r"\s+", header=None, skiprows=head_lines, nrows=rows)),
            }
            for kind, (ours, plain) in cases.items():
                t_ours, t_plain = best_time(ours, repeat), best_time(plain, repeat)
                m_ours, m_plain = _peak_mb(ours), _peak_mb(plain)
                print(f"{kind:<6} {rows:>9} {t_ours:>9.3f} {t_plain:>9.3f} {t_ours / t_plain:>6.2f} "
                      f"{m_ours:>10.0f} {m_plain:>10.0f} {m_ours / m_plain:>6.2f}", flush=True)


if __name__ == "__main__":
    main()
