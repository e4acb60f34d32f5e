"""Point location in a triangle mesh: the triangle that holds each point, and the P1
interpolation there (vectorised; candidates from a uniform grid of squares, or a k-d tree
of the triangle centroids on strongly graded meshes). The nodes of a uniform refinement
are matched by sorting, for triangles and tetrahedra alike (:func:`interpolate_p1`; the
tetrahedra are located by fem_py.mesh.location3d)."""
from __future__ import annotations

import itertools
import numpy as np
from scipy.spatial import cKDTree

from fem_py.mesh.location3d import locate_in_tetrahedra

__all__ = ["locate", "interpolate_p1", "lattice_weights", "P1Points"]

#: Point location: a grid square holding more triangles than this (a strongly graded
#: mesh, the squares being as large as the largest triangle) switches :func:`locate` to
#: candidates from a k-d tree of the triangle centroids.
LOCATE_MAX_CANDIDATES = 64


def _affine_inverses(corners: np.ndarray) -> np.ndarray:
    """(T, 4): the rows of inverse(b - a, c - a) of every triangle abc (``corners``
    (T, 3, 2)), so that (lambda_1, lambda_2) = inverse (p - a)."""
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    return np.stack([e2[:, 1], -e2[:, 0], -e1[:, 1], e1[:, 0]], axis=1) / det[:, None]


def _barycentric(
    corners: np.ndarray, inverses: np.ndarray, cells: np.ndarray, points: np.ndarray
) -> np.ndarray:
    """Barycentric coordinates (..., 3) of points (..., 2) in the triangles ``cells``
    (...) (:func:`_affine_inverses` of the mesh's ``corners``)."""
    v = points - corners[cells, 0]
    m = inverses[cells]
    l1 = m[..., 0] * v[..., 0] + m[..., 1] * v[..., 1]
    l2 = m[..., 2] * v[..., 0] + m[..., 3] * v[..., 1]
    return np.stack([1.0 - l1 - l2, l1, l2], axis=-1)


def locate(
    x: np.ndarray, triangles: np.ndarray, points: np.ndarray, *, tol: float = 1e-12
) -> tuple[np.ndarray, np.ndarray]:
    """(cell (m,), barycentric coordinates (m, 3)) of each point in the mesh (x (N, 2),
    triangles (T, 3)); cell -1 where no triangle holds the point (within ``tol``
    relative to the triangle in barycentric coordinates).

    The candidates of a point are the triangles registered in its square of a uniform
    grid whose squares are as large as the largest triangle's bounding box (so a triangle
    overlaps at most 2 x 2 squares): a few per point on a quasi-uniform mesh. Where a
    square holds more than LOCATE_MAX_CANDIDATES triangles (strongly graded meshes), the
    triangles whose centroids are nearest to the point are tried instead (k-d tree).
    """
    x = np.asarray(x, dtype=float)[:, :2]
    triangles = np.asarray(triangles, dtype=np.int64)
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    cell = np.full(len(points), -1, dtype=np.int64)
    bary = np.zeros((len(points), 3))
    if len(points) == 0 or len(triangles) == 0:
        return cell, bary
    corners = x[triangles]  # (T, 3, 2)
    inverses = _affine_inverses(corners)
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    size = max(float((hi - lo).max()), 1e-300)
    origin = lo.min(axis=0)
    shape = np.floor((hi.max(axis=0) - origin) / size).astype(np.int64) + 1
    first, last = (np.floor((b - origin) / size).astype(np.int64) for b in (lo, hi))
    squares, owners = [], []
    for dx in (0, 1):
        for dy in (0, 1):
            ok = (first[:, 0] + dx <= last[:, 0]) & (first[:, 1] + dy <= last[:, 1])
            squares.append((first[ok, 0] + dx) * shape[1] + first[ok, 1] + dy)
            owners.append(np.flatnonzero(ok))
    squares, owners = np.concatenate(squares), np.concatenate(owners)
    order = np.argsort(squares, kind="stable")
    owners = owners[order]
    counts = np.bincount(squares, minlength=int(shape.prod()))
    if counts.max() > LOCATE_MAX_CANDIDATES:
        return _locate_nearest(corners, inverses, points, tol)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    with np.errstate(over="ignore", invalid="ignore"):
        ij = np.floor((points - origin) / size)
    todo = np.flatnonzero(((ij >= 0) & (ij < shape)).all(axis=1))  # NaN: outside
    ij = ij[todo].astype(np.int64)
    square = ij[:, 0] * shape[1] + ij[:, 1]
    start, count = starts[square], counts[square]
    for k in range(int(count.max(initial=0))):
        keep = count > k
        todo, start, count = todo[keep], start[keep], count[keep]
        cand = owners[start + k]
        lam = _barycentric(corners, inverses, cand, points[todo])
        hit = (lam >= -tol).all(axis=1)
        cell[todo[hit]] = cand[hit]
        bary[todo[hit]] = lam[hit]
        todo, start, count = todo[~hit], start[~hit], count[~hit]
        if todo.size == 0:
            break
    return cell, bary


def _locate_nearest(
    corners: np.ndarray, inverses: np.ndarray, points: np.ndarray, tol: float
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`locate` with the candidates from a k-d tree of the triangle centroids: the
    8, then 32, then 128 nearest for the points not found yet."""
    cell = np.full(len(points), -1, dtype=np.int64)
    bary = np.zeros((len(points), 3))
    n_triangles = len(corners)
    tree = cKDTree(corners.mean(axis=1))
    todo = np.arange(len(points))
    for k in (8, 32, 128):
        k = min(k, n_triangles)
        _, cand = tree.query(points[todo], k=k)
        cand = np.minimum(cand.reshape(len(todo), k), n_triangles - 1)  # n: no neighbour
        lam = _barycentric(corners, inverses, cand, points[todo][:, None, :])
        inside = (lam >= -tol).all(axis=2)
        hit = inside.any(axis=1)
        first = inside.argmax(axis=1)
        rows = np.flatnonzero(hit)
        cell[todo[rows]] = cand[rows, first[rows]]
        bary[todo[rows]] = lam[rows, first[rows]]
        todo = todo[~hit]
        if todo.size == 0 or k == n_triangles:
            break
    return cell, bary


def _grid_keys(coords: np.ndarray, origin: np.ndarray, quantum: float) -> np.ndarray:
    """One int64 per point (coordinates (m, d), d = 2 or 3): its coordinates rounded to
    multiples of ``quantum``, -1 for the points outside [0, GRID_LEVELS[d]] quanta from
    ``origin`` (none of the mesh's)."""
    d = coords.shape[1]
    levels = GRID_LEVELS[d]
    with np.errstate(over="ignore", invalid="ignore"):
        k = coords - origin
        k /= quantum
        np.rint(k, out=k)
    inside = ((k >= 0) & (k <= levels)).all(axis=1)
    k[~inside] = 0  # whole arrays below, no selections: the outside keys set to -1 last
    ki = k.astype(np.int64)
    keys = ki[:, 0].copy()
    for axis in range(1, d):
        keys *= levels + 1
        keys += ki[:, axis]
    keys[~inside] = -1
    return keys


#: Quanta per side of the matching grid, by dimension: the keys fit in an int64.
GRID_LEVELS = {2: 2**30, 3: 2**20}


def lattice_weights(divisions: int, corners: int = 3) -> np.ndarray:
    """(k, corners) barycentric weights (i, j, ...) / n, summing to 1 (n = ``divisions``),
    of the lattice points of a triangle (``corners`` = 3) or tetrahedron (4) that are not
    its corners: the nodes that n-fold uniform refinement adds in (and on the sides of)
    each cell (for n = 2 the edge midpoints)."""
    n = divisions
    w = [c for c in itertools.product(range(n + 1), repeat=corners) if sum(c) == n]
    return np.array([c for c in w if max(c) < n], dtype=float).reshape(-1, corners) / n


def _lattice_match(
    x: np.ndarray, cells: np.ndarray, points: np.ndarray, weights: np.ndarray
) -> np.ndarray:
    """(m,): for each point that coincides, up to 1 / GRID_LEVELS of the mesh's extent,
    with a node or a lattice point of a cell (triangles or tetrahedra; ``weights`` of
    :func:`lattice_weights`), its index in the nodes followed by the cells' lattice points
    (:func:`_lattice_values`); -1 for the others: every node of an n-fold uniform
    refinement of the mesh, by sorting instead of a point location."""
    d = x.shape[1]
    coords = x
    if len(weights):  # not for divisions = 1: the nodes alone (no cells' corners gathered)
        coords = np.concatenate([x, np.matmul(weights, x[cells]).reshape(-1, d)])
    origin = x.min(axis=0)
    quantum = max(float(np.ptp(x, axis=0).max()), 1e-300) / GRID_LEVELS[d]
    keys = _grid_keys(coords, origin, quantum)
    order = np.argsort(keys, kind="stable")
    keys = keys[order]
    wanted = _grid_keys(points, origin, quantum)
    # searched in increasing order (a binary search for each point in turn would jump
    # across the sorted keys: 2-3x the time of sorting the points first, at 10^6 points)
    by_key = np.argsort(wanted)
    at = np.empty(len(wanted), dtype=np.int64)
    at[by_key] = np.minimum(np.searchsorted(keys, wanted[by_key]), len(keys) - 1)
    matched = (keys[at] == wanted) & (wanted >= 0)
    return np.where(matched, order[at], -1)


def _lattice_values(values: np.ndarray, cells: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The P1 function of nodal ``values`` at the nodes, then at the cells' lattice points
    (the same weights of the corner values), as :func:`_lattice_match` numbers them."""
    if not len(weights):
        return values
    return np.concatenate([values, (values[cells] @ weights.T).ravel()])


class P1Points:
    """Points located once in a mesh of triangles or tetrahedra, for the P1 interpolation
    of any number of functions on it (:func:`interpolate_p1` of one) and the cells that
    hold them.

    The mesh: triangles (``cells`` (T, 3), nodes ``x`` (N, 2), or (N, 3) with z left
    out, points (m, 2)) or tetrahedra (``cells`` (T, 4), x (N, 3), points (m, 3)).
    Points at nodes and at the lattice points of the ``divisions``-fold uniform refinement
    (all nodes of such a refinement: nested iteration; 2 gives the edge midpoints; by
    default 2 on triangles, 1 on tetrahedra) are matched by sorting; the others are
    located (:func:`locate`, :func:`fem_py.mesh.location3d.locate_in_tetrahedra`)."""

    def __init__(
        self, x: np.ndarray, cells: np.ndarray, points: np.ndarray, *, divisions: int | None = None
    ):
        cells = np.asarray(cells, dtype=np.int64)
        self._tetrahedra = cells.ndim == 2 and cells.shape[1] == 4
        d = 3 if self._tetrahedra else 2
        self._x, self._cells = np.asarray(x, dtype=float)[:, :d], cells
        self._points = np.asarray(points, dtype=float).reshape(-1, d)
        self._empty = len(self._x) == 0 or len(cells) == 0
        m = len(self._points)
        self._lattice, self._weights = np.full(m, -1, dtype=np.int64), np.zeros((0, d + 1))
        self._rest = np.arange(m)
        self._cell, self._bary = np.full(m, -1, dtype=np.int64), np.zeros((m, d + 1))
        if self._empty:
            return
        if divisions is None:
            divisions = 1 if self._tetrahedra else 2
        self._weights = lattice_weights(max(int(divisions), 1), cells.shape[1])
        self._lattice = _lattice_match(self._x, cells, self._points, self._weights)
        self._rest = np.flatnonzero(self._lattice < 0)
        self._cell, self._bary = self._locate(self._points[self._rest])

    def _locate(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return (locate_in_tetrahedra if self._tetrahedra else locate)(self._x, self._cells, points)

    def interpolate(self, values: np.ndarray) -> np.ndarray:
        """(m,): the P1 function of nodal ``values`` (N,) at the points; NaN outside the
        mesh."""
        out = np.full(len(self._points), np.nan)
        if self._empty:
            return out
        values = np.asarray(values, dtype=float)
        matched = self._lattice >= 0
        out[matched] = _lattice_values(values, self._cells, self._weights)[self._lattice[matched]]
        found = self._cell >= 0
        corners = values[self._cells[self._cell[found]]]
        out[self._rest[found]] = np.einsum("ij,ij->i", self._bary[found], corners)
        return out

    def cells(self) -> np.ndarray:
        """(m,): the cell that holds each point, -1 outside the mesh: as located, and for
        the points matched by sorting (a node, a point on a side) the cell :func:`locate`
        (or ``locate_in_tetrahedra``) gives, located now."""
        cell = np.full(len(self._points), -1, dtype=np.int64)
        if self._empty:
            return cell
        cell[self._rest] = self._cell
        matched = np.flatnonzero(self._lattice >= 0)
        cell[matched] = self._locate(self._points[matched])[0]
        return cell


def interpolate_p1(
    x: np.ndarray,
    cells: np.ndarray,
    values: np.ndarray,
    points: np.ndarray,
    *,
    divisions: int | None = None,
) -> np.ndarray:
    """The P1 function of nodal ``values`` at ``points``; NaN outside the mesh
    (:class:`P1Points`, the mesh and ``divisions`` as there; for several functions at the
    same points, locate them once with :class:`P1Points`)."""
    return P1Points(x, cells, points, divisions=divisions).interpolate(values)
