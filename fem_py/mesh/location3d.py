"""Point location for a body in R^3: the tetrahedron that holds each point (for the P1
interpolation of fem_py.mesh.location.interpolate_p1), and the points that lie on a
triangulated surface (with their barycentric coordinates there). Candidates come from a
k-d tree of the cells' centroids: a point inside a cell is within the cell's largest
centroid-to-vertex distance of its centroid, so every cell that may hold it is among
those within the mesh's largest such distance."""
from __future__ import annotations

import itertools

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["locate_in_tetrahedra", "on_surface"]


def _candidates(corners: np.ndarray, points: np.ndarray) -> list[list[int]]:
    """For each point, the cells (``corners`` (T, k, 3)) whose centroid lies within the
    largest centroid-to-vertex distance of the mesh (with a 1e-9 relative margin)."""
    centroids = corners.mean(axis=1)
    reach = float(np.linalg.norm(corners - centroids[:, None], axis=2).max())
    return cKDTree(centroids).query_ball_point(points, reach * (1 + 1e-9) + 1e-300)


#: Cells whose corners are gathered at a time when the cells meeting a box are sought (the
#: corners of all cells at once: 1.2 GB at 128^3 cubes).
_CELLS_PER_CHUNK = 1 << 18


def _cells_meeting_box(
    x: np.ndarray, tets: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray:
    """The cells (indices into ``tets``) whose bounding boxes meet the box [lo, hi], found
    a chunk of cells at a time and one coordinate at a time, the box's thinnest (relative
    to the mesh's extent) first: for a section's plane that first test, on one coordinate
    of the four corners, leaves the few cells along the plane for the others."""
    extent = np.maximum(x.max(axis=0) - x.min(axis=0), np.finfo(float).tiny)
    axes = np.argsort((hi - lo) / extent, kind="stable")
    coordinates = [np.ascontiguousarray(x[:, a]) for a in range(x.shape[1])]
    kept = []
    for start in range(0, len(tets), _CELLS_PER_CHUNK):
        cells = np.arange(start, min(start + _CELLS_PER_CHUNK, len(tets)))
        for a in axes:
            c0, c1, c2, c3 = coordinates[a][tets[cells]].T  # the corners' coordinate a
            top = np.maximum(np.maximum(c0, c1), np.maximum(c2, c3))
            bottom = np.minimum(np.minimum(c0, c1), np.minimum(c2, c3))
            cells = cells[(top >= lo[a]) & (bottom <= hi[a])]
        kept.append(cells)
    return np.concatenate(kept) if kept else np.zeros(0, dtype=np.int64)


def locate_in_tetrahedra(
    x: np.ndarray, tetrahedra: np.ndarray, points: np.ndarray, *, tol: float = 1e-12
) -> tuple[np.ndarray, np.ndarray]:
    """(cell (m,), barycentric coordinates (m, 4)) of each point in the mesh (x (N, 3),
    tetrahedra (T, 4)); cell -1 where no tetrahedron holds the point (within ``tol`` in
    barycentric coordinates)."""
    x, tets = np.asarray(x, dtype=float), np.asarray(tetrahedra, dtype=np.int64)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    cell = np.full(len(points), -1, dtype=np.int64)
    bary = np.zeros((len(points), 4))
    if len(points) == 0 or len(tets) == 0:
        return cell, bary
    # points outside the mesh's bounding box (with a margin) are in no cell, and only the
    # cells that meet the bounding box of the others can hold them (a section of the body:
    # the cells along its plane)
    lo, hi = x.min(axis=0), x.max(axis=0)
    margin = 1e-9 * float((hi - lo).max())
    inside = np.flatnonzero(((points >= lo - margin) & (points <= hi + margin)).all(axis=1))
    if len(inside) == 0:
        return cell, bary
    p_lo, p_hi = points[inside].min(axis=0) - margin, points[inside].max(axis=0) + margin
    kept = _cells_meeting_box(x, tets, p_lo, p_hi)
    if len(kept) == 0:  # e.g. points in the notch or hole of a body: in no cell's box
        return cell, bary
    corners = x[tets[kept]]  # (kept, 4, 3)
    candidates = _candidates(corners, points[inside])
    # the inverse Jacobians of the candidate cells only
    used = np.unique(np.fromiter(itertools.chain.from_iterable(candidates), dtype=np.int64))
    position = np.full(len(corners), -1, dtype=np.int64)
    position[used] = np.arange(len(used))
    edges = corners[used, 1:] - corners[used, :1]
    inverses = np.linalg.inv(np.transpose(edges, (0, 2, 1)))
    for i, near in zip(inside, candidates):
        if not near:
            continue
        near = np.asarray(near)
        lam = np.einsum("tij,tj->ti", inverses[position[near]], points[i] - corners[near, 0])
        lam = np.column_stack([1.0 - lam.sum(axis=1), lam])
        best = int(np.argmax(lam.min(axis=1)))
        if lam[best].min() >= -tol:
            cell[i], bary[i] = kept[near[best]], lam[best]
    return cell, bary


def on_surface(
    nodes: np.ndarray, triangles: np.ndarray, points: np.ndarray, distance: float
) -> tuple[np.ndarray, np.ndarray]:
    """(triangle (m,), barycentric coordinates (m, 3)) of the points (m, 3) closer than
    ``distance`` to the surface (``nodes`` (n, 3), ``triangles`` (t, 3)), at the foot of
    the perpendicular on the triangle, and triangle -1 for the others. ``distance`` is
    meant to be tiny (points given on the surface up to round-off)."""
    nodes, tris = np.asarray(nodes, dtype=float), np.asarray(triangles, dtype=np.int64)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    which = np.full(len(points), -1, dtype=np.int64)
    bary = np.zeros((len(points), 3))
    if len(points) == 0:
        return which, bary
    corners = nodes[tris]  # (t, 3, 3)
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    normal = np.cross(e1, e2)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    # the in-plane coordinates (l1, l2) of a point: the Gram system of e1, e2
    g11, g12, g22 = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    det = g11 * g22 - g12 * g12
    slack = 1e-9  # barycentric: a point on an edge belongs to both triangles
    for i, near in enumerate(_candidates(corners, points)):
        if not near:
            continue
        near = np.asarray(near)
        v = points[i] - corners[near, 0]
        height = np.abs((v * normal[near]).sum(axis=1))
        b1, b2 = (v * e1[near]).sum(axis=1), (v * e2[near]).sum(axis=1)
        l1 = (g22[near] * b1 - g12[near] * b2) / det[near]
        l2 = (g11[near] * b2 - g12[near] * b1) / det[near]
        lam = np.column_stack([1.0 - l1 - l2, l1, l2])
        hit = (height <= distance) & (lam.min(axis=1) >= -slack)
        if hit.any():
            k = int(np.flatnonzero(hit)[np.argmin(height[hit])])
            which[i] = near[k]
            clipped = np.clip(lam[k], 0.0, None)
            bary[i] = clipped / clipped.sum()
    return which, bary
