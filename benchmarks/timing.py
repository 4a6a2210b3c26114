"""The one timing rule of the benchmarks: the best of ``repeat`` runs (least disturbed by a shared machine).

The clock is wall time; ``cpu=True`` uses the calling thread's CPU time instead, which a busy shared machine
disturbs far less (the time a run waits for a core is not counted). Use it only for single-threaded work.
"""
from __future__ import annotations

import time


def best_time(fn, repeat: int, cpu: bool = False) -> float:
    """Shortest time [s] of ``repeat`` calls of ``fn()``: wall time, or this thread's CPU time with ``cpu``."""
    clock = time.thread_time if cpu else time.perf_counter
    best = float("inf")
    for _ in range(repeat):
        t0 = clock()
        fn()
        best = min(best, clock() - t0)
    return best
