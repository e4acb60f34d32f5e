"""Point location in a triangle mesh: the triangle that holds each point, and the P1
interpolation there (vectorised; candidates from a k-d tree of the triangle centroids)."""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["locate", "interpolate_p1"]


def _barycentric(
    x: np.ndarray, triangles: np.ndarray, cells: np.ndarray, points: np.ndarray
) -> np.ndarray:
    """Barycentric coordinates (..., 3) of points (..., 2) in the triangles ``cells``."""
    a, b, c = (x[triangles[cells, i]] for i in range(3))
    v0, v1, v2 = b - a, c - a, points - a
    det = v0[..., 0] * v1[..., 1] - v0[..., 1] * v1[..., 0]
    l1 = (v2[..., 0] * v1[..., 1] - v2[..., 1] * v1[..., 0]) / det
    l2 = (v0[..., 0] * v2[..., 1] - v0[..., 1] * v2[..., 0]) / det
    return np.stack([1.0 - l1 - l2, l1, l2], axis=-1)


def locate(
    x: np.ndarray, triangles: np.ndarray, points: np.ndarray, *, tol: float = 1e-12
) -> tuple[np.ndarray, np.ndarray]:
    """(cell (m,), barycentric coordinates (m, 3)) of each point in the mesh (x (N, 2),
    triangles (T, 3)); cell -1 where no triangle holds the point (within ``tol``
    relative to the triangle in barycentric coordinates).

    The candidates of a point are the triangles whose centroids are nearest to it: 8,
    then 32, then 128 of them for the points not found yet, which suffices for the
    shape-regular meshes of this project.
    """
    x = np.asarray(x, dtype=float)[:, :2]
    triangles = np.asarray(triangles, dtype=np.int64)
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    cell = np.full(len(points), -1, dtype=np.int64)
    bary = np.zeros((len(points), 3))
    if len(points) == 0 or len(triangles) == 0:
        return cell, bary
    tree = cKDTree(x[triangles].mean(axis=1))
    todo = np.arange(len(points))
    for k in (8, 32, 128):
        k = min(k, len(triangles))
        _, cand = tree.query(points[todo], k=k)
        cand = cand.reshape(len(todo), k)
        lam = _barycentric(x, triangles, cand, points[todo][:, None, :])
        inside = (lam >= -tol).all(axis=2)
        hit = inside.any(axis=1)
        first = inside.argmax(axis=1)
        rows = np.flatnonzero(hit)
        cell[todo[rows]] = cand[rows, first[rows]]
        bary[todo[rows]] = lam[rows, first[rows]]
        todo = todo[~hit]
        if todo.size == 0 or k == len(triangles):
            break
    return cell, bary


def interpolate_p1(
    x: np.ndarray, triangles: np.ndarray, values: np.ndarray, points: np.ndarray
) -> np.ndarray:
    """The P1 function of nodal ``values`` at ``points``; NaN outside the mesh."""
    cell, bary = locate(x, triangles, points)
    out = np.full(len(cell), np.nan)
    found = cell >= 0
    out[found] = np.einsum(
        "ij,ij->i", bary[found], np.asarray(values)[np.asarray(triangles)[cell[found]]]
    )
    return out
