"""The shapes of Omega and the description of its boundary (docs/method.md sections 1, 4, 6).

Omega is a polygon: the square, the L-shape (the square minus its upper-right
quarter) or a given simple counter-clockwise polygon (:func:`check_polygon`). Its
boundary Gamma is parametrised by arc length from the first vertex, counter-clockwise
(:class:`BoundaryCurve`). On Gamma lie the Signorini arcs (:class:`Arc`, parsed by
:func:`parse_arcs` from the ``signorini`` argument of ``fem_py.mesh.build_domain``),
and every coarse boundary edge carries the facet tag of the part of Gamma it lies in
(:func:`edge_tag`): ``GAMMA_T_TAG`` on Gamma_t, ``SIGNORINI_TAG0 + k`` on arc k.

The coarse cells of the square and the L-shape are squares of a uniform grid
(:func:`grid_partition`); arc end points are inserted into them as extra coarse
vertices (:func:`insert_boundary_points`). The coarse triangles of a polygon come from
gmsh (``fem_py.mesh.gmsh_mesh``).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from fem_py.polyline import arc_length, diameter, segment_lengths
from fem_py.tags import GAMMA_T_TAG, SIGNORINI_TAG0

__all__ = [
    "Arc",
    "BoundaryCurve",
    "SHAPES",
    "SQUARE_SIDES",
    "LSHAPE_SIDES",
    "check_polygon",
    "checked_center",
    "edge_tag",
    "grid_cells_per_side",
    "grid_counts",
    "grid_outline",
    "grid_partition",
    "insert_boundary_points",
    "parse_arcs",
]

SHAPES = ("square", "lshape", "polygon")
SQUARE_SIDES = ("bottom", "right", "top", "left")
LSHAPE_SIDES = ("bottom", "right", "notch_bottom", "notch_left", "top", "left")


@dataclass(frozen=True)
class Arc:
    """A Signorini arc: the part of Gamma from ``start`` to ``end`` counter-clockwise.

    ``s0``/``length`` are the arc-length position of ``start`` (measured from the first
    polygon vertex, counter-clockwise) and the arc length; ``whole`` marks Gamma_s = Gamma
    (then start = end = the first polygon vertex and length = |Gamma|).
    """

    start: tuple[float, float]
    end: tuple[float, float]
    s0: float
    length: float
    whole: bool = False
    name: str = ""


# ======================================================================= polygons


def checked_center(center: Any) -> tuple[float, float]:
    """``center`` as a pair of finite numbers; else a one-line ``ValueError`` naming it."""
    try:
        cx, cy = (float(c) for c in center)
    except (TypeError, ValueError):
        raise ValueError(f"center must be a pair (x, y), got {center!r}") from None
    if not (np.isfinite(cx) and np.isfinite(cy)):
        raise ValueError(f"center must be finite, got {center!r}")
    return cx, cy


def _signed_area(P: np.ndarray) -> float:
    x, y = P[:, 0], P[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _segments_intersect(p1, p2, q1, q2, tol) -> bool:
    """Closed segments p1p2 and q1q2 intersect (touching counts)."""

    def orient(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return 0 if abs(v) <= tol else (1 if v > 0 else -1)

    def on_seg(a, b, c):
        return (
            min(a[0], b[0]) - tol <= c[0] <= max(a[0], b[0]) + tol
            and min(a[1], b[1]) - tol <= c[1] <= max(a[1], b[1]) + tol
        )

    o1, o2 = orient(p1, p2, q1), orient(p1, p2, q2)
    o3, o4 = orient(q1, q2, p1), orient(q1, q2, p2)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return (
        (o1 == 0 and on_seg(p1, p2, q1))
        or (o2 == 0 and on_seg(p1, p2, q2))
        or (o3 == 0 and on_seg(q1, q2, p1))
        or (o4 == 0 and on_seg(q1, q2, p2))
    )


def check_polygon(P: np.ndarray) -> None:
    """Check that ``P`` (m, 2) is a simple counter-clockwise polygon.

    Raises
    ------
    ValueError
        Fewer than 3 vertices, non-finite coordinates, coinciding or repeated vertices,
        sides that fold back or intersect, or a clockwise orientation.
    """
    m = len(P)
    if m < 3:
        raise ValueError(f"vertices: a polygon needs at least 3 vertices, got {m}")
    if not np.all(np.isfinite(P)):
        raise ValueError("vertices: coordinates must be finite numbers")
    scale = diameter(P)
    if scale == 0.0:
        raise ValueError("vertices: all vertices coincide; give a non-degenerate polygon")
    tol = 1e-12 * scale**2
    short = np.flatnonzero(segment_lengths(np.vstack([P, P[:1]])) <= 1e-12 * scale)
    if short.size:
        i = int(short[0])
        raise ValueError(f"vertices: vertex {i} repeats vertex {(i + 1) % m}; remove duplicates")
    for i in range(m):
        for j in range(i + 1, m):
            adjacent = j == i + 1 or (i == 0 and j == m - 1)
            a1, a2, b1, b2 = P[i], P[(i + 1) % m], P[j], P[(j + 1) % m]
            if adjacent:
                # adjacent sides meet at one vertex only: reject a fold-back (collinear overlap)
                shared = a2 if j == i + 1 else a1
                u = (a1 if j == i + 1 else a2) - shared
                w = (b2 if j == i + 1 else b1) - shared
                cross = u[0] * w[1] - u[1] * w[0]
                if abs(cross) <= tol and float(np.dot(u, w)) > 0:
                    raise ValueError(
                        f"vertices: sides {i} and {j} fold back onto each other; "
                        "the polygon must be simple"
                    )
                continue
            if _segments_intersect(a1, a2, b1, b2, tol):
                raise ValueError(
                    f"vertices: sides {i} and {j} intersect; the polygon must be "
                    "simple (non-self-intersecting)"
                )
    if _signed_area(P) <= 0:
        raise ValueError("vertices: the polygon is clockwise; list the vertices counter-clockwise")


class BoundaryCurve:
    """Arc-length parametrisation of the polygon boundary (counter-clockwise).

    Parameters
    ----------
    P : (m, 2) float
        Polygon vertices, counter-clockwise.

    Attributes
    ----------
    P, m
        The vertices and their number.
    seg, len : (m, 2) float, (m,) float
        Side i from vertex i to vertex i+1 (mod m) and its length.
    S : (m + 1,) float
        Arc-length position of every vertex, the first one again at the end (S[m] = L).
    L : float
        |Gamma|.
    tol : float
        Geometric tolerance, 1e-8 diam(Omega).
    """

    def __init__(self, P: np.ndarray):
        closed = np.vstack([P, P[:1]])
        self.P = P
        self.m = len(P)
        self.seg = np.diff(closed, axis=0)
        self.len = segment_lengths(closed)
        self.S = arc_length(closed)
        self.L = float(self.S[-1])
        self.tol = 1e-8 * diameter(P)

    def locate(self, q: np.ndarray) -> tuple[float, float, np.ndarray]:
        """(distance to Gamma, arc-length position, projected point)."""
        r = q[None, :] - self.P
        tau = np.clip((r * self.seg).sum(1) / self.len**2, 0.0, 1.0)
        proj = self.P + tau[:, None] * self.seg
        dist = np.linalg.norm(proj - q[None, :], axis=1)
        i = int(np.argmin(dist))
        return float(dist[i]), float(self.S[i] + tau[i] * self.len[i]) % self.L, proj[i]

    def point(self, s: float) -> np.ndarray:
        """The point of Gamma at arc-length position ``s`` (mod L)."""
        s = s % self.L
        i = min(int(np.searchsorted(self.S, s, side="right")) - 1, self.m - 1)
        return self.P[i] + (s - self.S[i]) / self.len[i] * self.seg[i]

    def inside(self, s: float | np.ndarray, arc: Arc) -> Any:
        """s lies strictly inside the arc (away from its ends by more than tol)."""
        if arc.whole:
            return np.ones_like(np.asarray(s), dtype=bool)
        r = (np.asarray(s) - arc.s0) % self.L
        return (r > self.tol) & (r < arc.length - self.tol)


# ================================================================ Signorini arcs
def _side_names(shape: str, m: int) -> dict[str, int]:
    names = {f"side{i}": i for i in range(m)}
    if shape == "square":
        names.update({n: i for i, n in enumerate(SQUARE_SIDES)})
    elif shape == "lshape":
        names.update({n: i for i, n in enumerate(LSHAPE_SIDES)})
    return names


def parse_arcs(signorini: Any, shape: str, boundary: BoundaryCurve) -> tuple[tuple[Arc, ...], bool]:
    """The Signorini arcs of ``signorini`` (the grammar of the ``fem_py.mesh`` module
    docstring) on the boundary of a ``shape``.

    Point pairs are snapped onto a polygon vertex within ``boundary.tol``.

    Returns
    -------
    arcs : tuple of Arc
    whole : bool
        Gamma_s = Gamma (``"all"``: one closed arc).

    Raises
    ------
    ValueError
        An unknown side, a point off Gamma, an arc of zero length, overlapping arcs, or
        ``"all"`` combined with other arcs.
    """
    B = boundary
    if isinstance(signorini, str):
        signorini = (signorini,)
    try:
        items = list(signorini)
    except TypeError:
        raise ValueError(
            "signorini must be a sequence of arcs (point pairs or side names), 'all' or ()"
        ) from None
    if any(isinstance(a, str) and a == "all" for a in items):
        if len(items) != 1:
            raise ValueError(
                "signorini: 'all' (the whole boundary) cannot be combined with other arcs"
            )
        first = tuple(map(float, B.P[0]))
        return (Arc(first, first, 0.0, B.L, True, "all"),), True
    sides = _side_names(shape, B.m)
    arcs: list[Arc] = []
    for k, a in enumerate(items):
        if isinstance(a, str):
            if a not in sides:
                named = [n for n in sides if not re.fullmatch(r"side\d+", n)]
                raise ValueError(
                    f"signorini arc {k}: unknown side {a!r}; use one of "
                    f"{', '.join(named + ['side<i>'])}, 'all' or a pair of points"
                )
            i = sides[a]
            arcs.append(
                Arc(
                    tuple(map(float, B.P[i])),
                    tuple(map(float, B.P[(i + 1) % B.m])),
                    float(B.S[i]),
                    float(B.len[i]),
                    False,
                    a,
                )
            )
            continue
        try:
            pts = np.asarray(a, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(
                f"signorini arc {k}: expected ((x0, y0), (x1, y1)) or a side name, got {a!r}"
            ) from None
        if pts.shape != (2, 2) or not np.all(np.isfinite(pts)):
            raise ValueError(
                f"signorini arc {k}: expected ((x0, y0), (x1, y1)) or a side name, got {a!r}"
            )
        ends = []
        for q in pts:
            dist, s, proj = B.locate(q)
            if dist > B.tol:
                raise ValueError(
                    f"signorini arc {k}: point ({q[0]:g}, {q[1]:g}) is not on the "
                    f"boundary (distance {dist:.3g}); give points on Gamma"
                )
            # snap onto a polygon vertex when within tolerance
            dv = np.linalg.norm(B.P - proj, axis=1)
            if dv.min() <= B.tol:
                proj = B.P[int(np.argmin(dv))]
                s = float(B.S[int(np.argmin(dv))]) % B.L
            ends.append((s, proj))
        length = (ends[1][0] - ends[0][0]) % B.L
        if length <= B.tol or length >= B.L - B.tol:
            raise ValueError(
                f"signorini arc {k}: its end equals its start; give two different "
                "points (or 'all' for the whole boundary)"
            )
        arcs.append(
            Arc(
                tuple(map(float, ends[0][1])),
                tuple(map(float, ends[1][1])),
                ends[0][0],
                length,
                False,
                f"arc{k}",
            )
        )
    for i in range(len(arcs)):
        for j in range(i + 1, len(arcs)):
            a, b = arcs[i], arcs[j]
            if (
                B.inside(b.s0, a)
                or B.inside(a.s0, b)
                or abs(((a.s0 - b.s0 + B.L / 2) % B.L) - B.L / 2) <= B.tol
            ):
                raise ValueError(
                    f"signorini arcs {i} and {j} overlap; arcs may only touch at end points"
                )
    return tuple(arcs), False


def edge_tag(V: np.ndarray, a: int, b: int, boundary: BoundaryCurve, arcs: tuple[Arc, ...]) -> int:
    """Facet tag of the coarse boundary edge from vertex ``a`` to ``b`` of ``V``:
    ``SIGNORINI_TAG0 + k`` if its midpoint lies inside arc k, else ``GAMMA_T_TAG``."""
    _, s, _ = boundary.locate(0.5 * (V[a] + V[b]))
    for k, arc in enumerate(arcs):
        if boundary.inside(s, arc):
            return SIGNORINI_TAG0 + k
    return GAMMA_T_TAG


# =================================================== coarse cells of the built-in shapes
def grid_partition(
    shape: str, center: Sequence[float], width: float, d: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Coarse squares of the square / L-shape.

    Parameters
    ----------
    shape
        ``"square"`` or ``"lshape"``.
    center, width
        The square [cx - w/2, cx + w/2] x [cy - w/2, cy + w/2] (for the L-shape, minus
        its upper-right quarter).
    d
        Requested coarse size: n_c = round(width / d) squares per side (at least 1; for
        the L-shape an even number, at least 2).

    Returns
    -------
    P : (m, 2) float
        The polygon of Omega, counter-clockwise from the lower-left corner.
    vertices : (n_v, 2) float
        Coarse vertices, numbered in the order they first appear in ``cells``.
    cells : (m, 4) int64
        Coarse squares row by row (y, then x), corners counter-clockwise.
    size : float
        The coarse square side width / n_c.
    """
    cx, cy = float(center[0]), float(center[1])
    x0, x1, y0, y1 = cx - width / 2, cx + width / 2, cy - width / 2, cy + width / 2
    nc = grid_cells_per_side(shape, width, d)
    xs, ys = np.linspace(x0, x1, nc + 1), np.linspace(y0, y1, nc + 1)
    half = nc // 2
    keep = np.ones((nc, nc), dtype=bool)  # keep[j, i]: coarse square i (x), j (y)
    if shape == "lshape":
        keep[half:, half:] = False
    # squares row by row (j, then i), corners counter-clockwise; vertices numbered in
    # the order they first appear
    jj, ii = np.nonzero(keep)
    corner = (
        np.stack([jj, jj, jj + 1, jj + 1], 1) * (nc + 1) + np.stack([ii, ii + 1, ii + 1, ii], 1)
    ).ravel()
    grid_point, first = np.unique(corner, return_index=True)
    grid_point = grid_point[np.argsort(first)]
    vid = np.empty((nc + 1) ** 2, dtype=np.int64)
    vid[grid_point] = np.arange(len(grid_point))
    verts = np.stack([xs[grid_point % (nc + 1)], ys[grid_point // (nc + 1)]], 1)
    P = grid_outline(shape, center, width, nc)
    return P, verts, vid[corner].reshape(-1, 4), width / nc


def grid_cells_per_side(shape: str, width: float, d: float) -> int:
    """n_c of :func:`grid_partition`: round(width / d) coarse squares per side, at least
    1 (for the L-shape an even number, at least 2)."""
    if shape == "square":
        return max(1, int(round(width / d)))
    return max(2, 2 * int(round(width / (2 * d))))


def grid_outline(shape: str, center: Sequence[float], width: float, nc: int) -> np.ndarray:
    """The polygon P of :func:`grid_partition` (the square, or the L-shape whose notch
    corner is the grid point nc / 2, nc / 2), without the grid."""
    cx, cy = float(center[0]), float(center[1])
    x0, x1, y0, y1 = cx - width / 2, cx + width / 2, cy - width / 2, cy + width / 2
    if shape == "square":
        return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    xm, ym = np.linspace(x0, x1, nc + 1)[nc // 2], np.linspace(y0, y1, nc + 1)[nc // 2]
    return np.array([[x0, y0], [x1, y0], [x1, ym], [xm, ym], [xm, y1], [x0, y1]])


def grid_counts(shape: str, nc: int) -> tuple[int, int, int, int]:
    """(vertices, edges, cells, boundary edges) of :func:`grid_partition` with ``nc``
    squares per side, in closed form (O(1) memory): the square has (nc + 1)^2 vertices,
    2 nc (nc + 1) edges, nc^2 cells; the L-shape loses the h^2 squares, h^2 vertices
    and 2 h^2 edges of the open upper-right quarter (h = nc / 2); both have 4 nc
    boundary edges."""
    cut = (nc // 2) ** 2 if shape == "lshape" else 0
    return (nc + 1) ** 2 - cut, 2 * nc * (nc + 1) - 2 * cut, nc * nc - cut, 4 * nc


def insert_boundary_points(
    V: np.ndarray, cells: list[list[int]], points: list[np.ndarray], tol: float
) -> tuple[np.ndarray, list[list[int]]]:
    """Insert points lying on coarse boundary edges into the cells owning those edges.

    A point within ``tol`` of a coarse vertex is that vertex; the others are appended to
    ``V`` and inserted, in order along the edge, into every cell loop with that edge.
    Returns the new (vertices, cells).
    """
    V = [np.asarray(v, dtype=float) for v in V]
    new = []
    for q in points:
        dv = np.linalg.norm(np.asarray(V) - q, axis=1)
        if dv.min() <= tol:
            continue
        if any(np.linalg.norm(V[n] - q) <= tol for n in new):
            continue
        new.append(len(V))
        V.append(np.asarray(q, dtype=float))
    if not new:
        return np.asarray(V), cells
    out = []
    for c in cells:
        loop = []
        for a, b in zip(c, c[1:] + c[:1]):
            loop.append(a)
            pa, pb = V[a], V[b]
            e = pb - pa
            ins = []
            for n in new:
                r = V[n] - pa
                t = float(np.dot(r, e) / np.dot(e, e))
                if 0 < t < 1 and abs(e[0] * r[1] - e[1] * r[0]) <= tol * np.linalg.norm(e):
                    ins.append((t, n))
            loop.extend(n for _, n in sorted(ins))
        out.append(loop)
    return np.asarray(V), out
