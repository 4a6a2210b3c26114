"""The one timing rule of the benchmarks: the best of ``repeat`` wall-clock runs (least disturbed by a shared
machine)."""
from __future__ import annotations

import time


def best_time(fn, repeat: int) -> float:
    """Shortest wall time [s] of ``repeat`` calls of ``fn()``."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best
