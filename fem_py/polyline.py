"""Arc length along polylines (boundary curves, coarse edges, Signorini arcs)."""
from __future__ import annotations

import numpy as np

__all__ = ["segment_lengths", "arc_length", "closest_on_polygon"]


def segment_lengths(points: np.ndarray) -> np.ndarray:
    """Lengths of the segments of polylines: (..., k, dim) -> (..., k - 1)."""
    return np.linalg.norm(np.diff(points, axis=-2), axis=-1)


def arc_length(points: np.ndarray) -> np.ndarray:
    """Cumulative arc length along polylines, starting at 0: (..., k, dim) -> (..., k)."""
    seg = segment_lengths(points)
    return np.concatenate([np.zeros(seg.shape[:-1] + (1,)), np.cumsum(seg, axis=-1)], axis=-1)


def closest_on_polygon(
    points: np.ndarray, vertices: np.ndarray, *, block: int = 1 << 20
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The closest point of the closed polygon through ``vertices`` (k, 2) to each point.

    Returns (distance (m,), segment (m,), t (m,)): the closest point lies on segment
    i = [vertices[i], vertices[i + 1 mod k]] at vertices[i] + t (vertices[i+1] - vertices[i]),
    t in [0, 1]. Work in blocks of about ``block`` point-segment pairs.
    """
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    a = np.asarray(vertices, dtype=float)
    ab = np.roll(a, -1, axis=0) - a
    ab2 = np.einsum("kj,kj->k", ab, ab)
    m = len(points)
    dist, seg, par = np.empty(m), np.empty(m, dtype=np.int64), np.empty(m)
    step = max(1, block // max(len(a), 1))
    for lo in range(0, m, step):
        rel = points[lo : lo + step, None, :] - a  # (b, k, 2)
        t = np.clip(np.einsum("mkj,kj->mk", rel, ab) / ab2, 0.0, 1.0)
        d = np.linalg.norm(rel - t[..., None] * ab, axis=2)
        best = d.argmin(axis=1)
        rows = np.arange(len(best))
        dist[lo : lo + step], seg[lo : lo + step] = d[rows, best], best
        par[lo : lo + step] = t[rows, best]
    return dist, seg, par
