"""Doerfler marking (docs/method.md section 10): the smallest set M of cells with
sum_M eta_T^2 >= theta sum_T eta_T^2, 0 < theta <= 1 (Doerfler, SINUM 33, 1996)."""
from __future__ import annotations

from typing import Any

import numpy as np

from fem_py.parallel import gather_to_root

__all__ = ["doerfler_marking", "TIE_TOLERANCE"]

#: indicators within this relative distance of the threshold count as tied with it: the
#: solves stop at a relative tolerance (1e-8 by default), so indicators of cells that are
#: equal in exact arithmetic (a symmetric mesh) differ by round-off that depends on the
#: number of ranks; marking them all keeps the marking the same on any number of ranks
TIE_TOLERANCE = 1e-6


def doerfler_marking(comm: Any, indicators: np.ndarray, theta: float) -> np.ndarray:
    """Mask of the owned cells in M for the owned eta_T^2 ``indicators`` (collective).

    The indicators of all ranks are sorted on rank 0; the threshold is the k-th largest
    value, k the smallest count whose sum reaches theta times the total, and every cell
    at or above it is marked (cells tied with the threshold, to ``TIE_TOLERANCE``
    relative, are all marked).
    """
    if not 0.0 < theta <= 1.0:
        raise ValueError(f"theta must lie in (0, 1], got {theta!r}")
    indicators = np.asarray(indicators, dtype=float)
    gathered = gather_to_root(comm, indicators)
    threshold = None
    if comm.rank == 0:
        values = np.sort(np.concatenate(gathered))[::-1]
        cumulative = np.cumsum(values)
        if cumulative.size == 0 or cumulative[-1] <= 0.0:
            threshold = np.inf  # nothing to refine
        else:
            k = int(np.searchsorted(cumulative, theta * cumulative[-1] * (1 - 1e-14)))
            threshold = float(values[min(k, values.size - 1)])
    threshold = comm.bcast(threshold, root=0)
    return indicators >= threshold * (1.0 - TIE_TOLERANCE)
