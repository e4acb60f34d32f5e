"""Wall-time measurement: the process clock of a run's timings, and best-of timing for the
benchmarks and the study."""
from __future__ import annotations

import os
import time
from typing import Any, Callable

__all__ = ["best_of", "process_seconds"]


def process_seconds() -> float:
    """Wall seconds since this process started (interpreter start-up and imports
    included; Linux /proc, resolution one clock tick)."""
    with open("/proc/self/stat") as stat:
        # field 22 (starttime, in clock ticks since boot) comes after the ")" of the name
        fields = stat.read().rpartition(")")[2].split()
    started = int(fields[19]) / os.sysconf("SC_CLK_TCK")
    return time.clock_gettime(time.CLOCK_BOOTTIME) - started


def best_of(fn: Callable[[], Any], repeat: int = 5) -> float:
    """Smallest wall time in seconds of ``repeat`` calls of ``fn`` (the call least
    disturbed by other load on a shared machine)."""
    times = []
    for _ in range(repeat):
        tic = time.perf_counter()
        fn()
        times.append(time.perf_counter() - tic)
    return min(times)
