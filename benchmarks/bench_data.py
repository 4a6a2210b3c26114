"""Reading measured data: mftyre's CSV and TYDEX readers against plain ``pandas.read_csv`` of the same file,
side by side in one run (wall time, best of ``--repeat``; growth of the peak resident memory of a fresh process
reading the file once).

    python benchmarks/bench_data.py [--rows 100000 1000000] [--repeat 3]

The files: every canonical channel (16 columns) plus SWEEP, random values written with 17 significant digits;
the TYDEX file has the same samples in a ``**MEASURDATA`` block. The baseline for TYDEX is pandas reading that
block alone (whitespace separated, rows after the header skipped). Target: mftyre <= 2x plain pandas.
"""
from __future__ import annotations

import argparse
import sys
import subprocess
import tempfile
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


_RSS_CODE = """
import sys
import pandas as pd
from mftyre.data import read_csv, read_tydex
kind, reader, path, skip, rows = sys.argv[1:6]
import os
before = int(open("/proc/self/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1024  # current, kB
if reader == "mftyre":
    (read_csv if kind == "CSV" else read_tydex)(path)
elif kind == "CSV":
    pd.read_csv(path)
else:
    pd.read_csv(path, sep=r"\\s+", header=None, skiprows=int(skip), nrows=int(rows))
peak = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM"))  # kB
print((peak - before) / 1024)
"""


def _rss_mb(kind: str, reader: str, path: Path, skip: int, rows: int) -> float:
    """Peak resident memory [MB] of a fresh process reading the file, less its resident memory after the imports:
    every allocation counted, C included (Linux: /proc/self/statm and VmHWM; ru_maxrss would carry this
    process's peak across exec)."""
    out = subprocess.run([sys.executable, "-c", _RSS_CODE, kind, reader, str(path), str(skip), str(rows)],
                         capture_output=True, text=True, check=True)
    return float(out.stdout)


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
                path = csv if kind == "CSV" else tdx
                m_ours, m_plain = (_rss_mb(kind, who, path, head_lines, rows) for who in ("mftyre", "pandas"))
                print(f"{kind:<6} {rows:>9} {t_ours:>9.3f} {t_plain:>9.3f} {t_ours / t_plain:>6.2f} "
                      f"{m_ours:>10.0f} {m_plain:>10.0f} {m_ours / m_plain:>6.2f}", flush=True)


if __name__ == "__main__":
    main()
