"""Arc length along polylines (boundary curves, coarse edges, Signorini arcs)."""
from __future__ import annotations

import numpy as np

__all__ = [
    "segment_lengths",
    "arc_length",
    "closest_on_polygon",
    "inside_polygon",
    "coarsened_polygon",
    "polygon_corners",
    "diameter",
    "CORNER_ANGLE",
]

#: A bend of Gamma by more than this (radians) is a corner: it makes a coarse vertex of a
#: mesh from a file or of a curved shape (``fem_py.partition.coarse``: corners stay coarse vertices,
#: a smooth curve does not fill with them), and a corner in the figures.
CORNER_ANGLE = np.pi / 6


def segment_lengths(points: np.ndarray) -> np.ndarray:
    """Lengths of the segments of polylines: (..., k, dim) -> (..., k - 1)."""
    d = np.diff(points, axis=-2)
    return np.sqrt(np.einsum("...i,...i->...", d, d))


def arc_length(points: np.ndarray) -> np.ndarray:
    """Cumulative arc length along polylines, starting at 0: (..., k, dim) -> (..., k)."""
    seg = segment_lengths(points)
    return np.concatenate([np.zeros(seg.shape[:-1] + (1,)), np.cumsum(seg, axis=-1)], axis=-1)


def polygon_corners(nodes: np.ndarray, min_angle: float = 0.0) -> np.ndarray:
    """Indices of the nodes (k, 2) of a closed polygon where it turns (its corners; the
    other nodes lie on straight sides); with ``min_angle`` > 0 only where it turns by
    more than that (radians: the corners of a curve drawn by a fine polygon)."""
    t = np.diff(np.concatenate([nodes, nodes[:1]]), axis=0)
    t /= np.linalg.norm(t, axis=1)[:, None]
    t_in = np.roll(t, 1, axis=0)
    cross = t_in[:, 0] * t[:, 1] - t_in[:, 1] * t[:, 0]
    if min_angle <= 0.0:
        return np.flatnonzero(np.abs(cross) > 1e-8)
    dot = np.einsum("kd,kd->k", t_in, t)
    return np.flatnonzero(np.abs(np.arctan2(cross, dot)) > min_angle)


def inside_polygon(points: np.ndarray, vertices: np.ndarray, *, block: int = 1 << 20) -> np.ndarray:
    """Whether each point (m, 2) lies inside the closed polygon through ``vertices``
    (k, 2): an odd number of its sides crosses the horizontal ray to the right of the
    point (exact in floating point up to the crossing abscissa; points on a side may
    fall either way). Work in blocks of about ``block`` point-side pairs."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    a = np.asarray(vertices, dtype=float)
    b = np.roll(a, -1, axis=0)
    m = len(points)
    out = np.empty(m, dtype=bool)
    step = max(1, block // max(len(a), 1))
    for lo in range(0, m, step):
        x, y = points[lo : lo + step, :1], points[lo : lo + step, 1:]
        spans = (a[:, 1] > y) != (b[:, 1] > y)  # (b, k): the side spans the ray's height
        with np.errstate(divide="ignore", invalid="ignore"):
            cross = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
        out[lo : lo + step] = np.count_nonzero(spans & (cross > x), axis=1) % 2 == 1
    return out


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


def coarsened_polygon(
    vertices: np.ndarray, spacing: float, keep: list, corner_angle: float, tol: float
) -> np.ndarray:
    """The polygon through a subset of ``vertices`` (k, 2, counter-clockwise) whose sides
    are about ``spacing`` long where the given sides are shorter: a finely drawn curve
    resampled for a mesh of that size.

    Kept always: the corners (vertices where the boundary turns by at least
    ``corner_angle``) and the points ``keep`` (inserted as vertices where they lie inside
    a side, within ``tol``). Between two kept vertices, the stretch is cut into the
    fewest pieces of arc length <= ``spacing``, each ending at the first given vertex at
    or after its even share (so sides are at most ``spacing`` plus one given side). The
    result is inscribed in the given polygon: it departs from it by the sagitta of its
    sides, about spacing^2 / (8 R) on a curve of radius R.
    """
    p = np.asarray(vertices, dtype=float)
    for q in keep:  # the points to keep become vertices
        q = np.asarray(q, dtype=float)
        dist, seg, t = closest_on_polygon(q[None, :], p)
        if dist[0] <= tol and np.linalg.norm(p - q, axis=1).min() > tol:
            p = np.insert(p, seg[0] + 1, q, axis=0)
    before, after = p - np.roll(p, 1, axis=0), np.roll(p, -1, axis=0) - p
    turn = np.abs(
        np.arctan2(
            before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0],
            np.einsum("ij,ij->i", before, after),
        )
    )
    fixed = turn >= corner_angle
    for q in keep:
        fixed[np.linalg.norm(p - np.asarray(q, dtype=float), axis=1) <= tol] = True
    if not fixed.any():
        fixed[0] = True
    start = int(np.flatnonzero(fixed)[0])
    p, fixed = np.roll(p, -start, axis=0), np.roll(fixed, -start)
    s = arc_length(np.vstack([p, p[:1]]))
    chosen = [0]
    for i in range(1, len(p) + 1):
        if i == len(p) or fixed[i]:
            # split the stretch from the last kept vertex to i evenly by arc length
            a, b = chosen[-1], i
            parts = max(1, int(np.ceil((s[b] - s[a]) / spacing - 1e-9)))
            targets = s[a] + (s[b] - s[a]) * np.arange(1, parts) / parts
            inner = np.searchsorted(s[a : b + 1], targets) + a
            chosen += sorted(set(int(j) for j in inner if a < j < b)) + ([i] if i < len(p) else [])
    return p[chosen]


def diameter(P: np.ndarray) -> float:
    """diam of the point set ``P`` (m, 2): the largest distance between two points (for
    many points, between two vertices of their convex hull)."""
    if len(P) > 64:
        from scipy.spatial import ConvexHull

        P = P[ConvexHull(P).vertices]
    d = P[:, None, :] - P[None, :, :]
    return float(np.sqrt((d**2).sum(-1)).max())
