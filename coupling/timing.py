"""Wall-time measurement for the benchmarks and the study."""
from __future__ import annotations

import time
from typing import Any, Callable

__all__ = ["best_of"]


def best_of(fn: Callable[[], Any], repeat: int = 5) -> float:
    """Smallest wall time in seconds of ``repeat`` calls of ``fn`` (the call least
    disturbed by other load on a shared machine)."""
    times = []
    for _ in range(repeat):
        tic = time.perf_counter()
        fn()
        times.append(time.perf_counter() - tic)
    return min(times)
