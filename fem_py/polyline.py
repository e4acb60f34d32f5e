"""Arc length along polylines (boundary curves, coarse edges, Signorini arcs)."""
from __future__ import annotations

import numpy as np

__all__ = ["segment_lengths", "arc_length"]


def segment_lengths(points: np.ndarray) -> np.ndarray:
    """Lengths of the segments of polylines: (..., k, dim) -> (..., k - 1)."""
    return np.linalg.norm(np.diff(points, axis=-2), axis=-1)


def arc_length(points: np.ndarray) -> np.ndarray:
    """Cumulative arc length along polylines, starting at 0: (..., k, dim) -> (..., k)."""
    seg = segment_lengths(points)
    return np.concatenate([np.zeros(seg.shape[:-1] + (1,)), np.cumsum(seg, axis=-1)], axis=-1)
