"""Meshes of Omega with a coarse subdomain partition (METHOD.md sections 1, 4 and 6).

``build_domain`` makes a polygon Omega (square, L-shape or a given polygon), a coarse
partition of Omega into L subdomains of size about d (coarse squares for the square and
the L-shape, coarse triangles of a gmsh mesh of size d for a polygon), and a fine P1
mesh of size h that resolves every coarse edge. Each coarse cell is its own gmsh plane
surface, sharing the coarse edges with its neighbours, with its own physical group, so
the fine mesh is conforming and every fine cell carries its subdomain id.

``structured=True`` refines every coarse cell uniformly instead: n = max(2, round(d/h))
segments per coarse edge; a coarse square becomes an n x n grid of squares split into
right triangles along the (i,j)-(i+1,j+1) diagonal, a coarse triangle becomes n^2
similar triangles. These nodes and triangles are written down directly (no gmsh), so
that h-studies at fixed d/h are exact.

Tags
----
- cell tags: subdomain id 0 .. L-1 (``Domain.cell_tags``, dim 2);
- facet tags (dim 1, exterior facets): 1 on Gamma_t, 100 + k on the k-th Signorini arc.

Signorini arcs (``signorini``)
------------------------------
A sequence of arcs, each one of

- a pair of boundary points ``((x0, y0), (x1, y1))``: the part of Gamma from the first
  point to the second, going counter-clockwise (Omega on the left);
- a side name. Square: ``bottom, right, top, left``. L-shape, with the square
  [x0, x1] x [y0, y1] of width w centred at ``center`` and its upper-right quarter
  removed (vertices (x0,y0), (x1,y0), (x1,cy), (cx,cy), (cx,y1), (x0,y1), CCW):
  ``bottom`` (x0,y0)-(x1,y0), ``right`` (x1,y0)-(x1,cy), ``notch_bottom`` (x1,cy)-(cx,cy)
  and ``notch_left`` (cx,cy)-(cx,y1) (the bottom and left sides of the removed quarter),
  ``top`` (cx,y1)-(x0,y1), ``left`` (x0,y1)-(x0,y0). Polygon: ``side<i>`` from vertex i to
  vertex i+1 (any shape accepts ``side<i>``);
- ``"all"``: the whole boundary as one closed arc (alone).

Arc end points become coarse vertices (inserted into the coarse mesh when needed; with
``structured=True`` on the square or L-shape they must already be coarse grid vertices),
so every coarse boundary edge lies in Gamma_t or in one arc (METHOD.md section 6).

Parallel use: all ranks call ``build_domain`` with the same arguments. Arguments are
validated identically on every rank before any collective call. Whole subdomains are
given to each rank (:func:`subdomain_owners`, passed to ``create_mesh`` as its
partitioner). A structured mesh is written down in parallel (``fem_py.structured``):
each rank makes the triangles of its own coarse cells and a block of the node
coordinates, and the tags follow from the closed-form numbering. Otherwise gmsh runs on
rank 0 only, and the mesh is distributed the way ``gmshio.model_to_mesh`` does it
(``create_mesh`` + ``distribute_entity_data`` + ``meshtags_from_entities``, see
``_distribute_mesh``), reading the gmsh arrays per surface because
``model_to_mesh``'s per-physical-group queries cost 20 s for 3000 subdomains.
``build_domain`` initialises and finalises gmsh itself (do not call it inside a gmsh
session of your own).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.coarse import SIGNORINI_TAG0, CoarseStructure, compute_coarse_structure
from fem_py.structured import StructuredRefinement, refine

__all__ = ["Arc", "CoarseStructure", "Domain", "build_domain", "compute_coarse_structure",
           "GAMMA_T_TAG", "SIGNORINI_TAG0", "SHAPES"]

GAMMA_T_TAG = 1
SHAPES = ("square", "lshape", "polygon")
SQUARE_SIDES = ("bottom", "right", "top", "left")
LSHAPE_SIDES = ("bottom", "right", "notch_bottom", "notch_left", "top", "left")


# ============================================================================ data
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


@dataclass(frozen=True, eq=False)
class Domain:
    """A meshed Omega with its coarse partition (see the module docstring).

    Attributes
    ----------
    mesh, cell_tags, facet_tags
        DOLFINx mesh; subdomain id of each cell (dim 2); 1 / 100+k on exterior facets.
    coarse : CoarseStructure
    arcs : tuple of Arc
    h, subdomain_size
        The requested fine and coarse sizes.
    shape : str
    vertices : (m, 2) float
        Polygon vertices of Omega, counter-clockwise (the first one is a corner).
    signorini_is_whole_boundary : bool
    structured : bool
    coarse_size : float
        Actual coarse size (coarse square side, or mean coarse edge length for a polygon).
    h_max : float
        Longest fine facet.
    """

    mesh: Any
    cell_tags: Any
    facet_tags: Any
    coarse: CoarseStructure
    arcs: tuple
    h: float
    subdomain_size: float
    shape: str
    vertices: np.ndarray
    signorini_is_whole_boundary: bool
    structured: bool
    coarse_size: float
    h_max: float

    @property
    def comm(self) -> Any:
        return self.mesh.comm

    @property
    def diameter(self) -> float:
        return _diameter(self.vertices)


# ======================================================================= helpers
def _diameter(P: np.ndarray) -> float:
    d = P[:, None, :] - P[None, :, :]
    return float(np.sqrt((d**2).sum(-1)).max())


def _signed_area(P: np.ndarray) -> float:
    x, y = P[:, 0], P[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _segments_intersect(p1, p2, q1, q2, tol) -> bool:
    """Closed segments p1p2 and q1q2 intersect (touching counts)."""
    def orient(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return 0 if abs(v) <= tol else (1 if v > 0 else -1)

    def on_seg(a, b, c):
        return min(a[0], b[0]) - tol <= c[0] <= max(a[0], b[0]) + tol and \
            min(a[1], b[1]) - tol <= c[1] <= max(a[1], b[1]) + tol

    o1, o2, o3, o4 = orient(p1, p2, q1), orient(p1, p2, q2), orient(q1, q2, p1), orient(q1, q2, p2)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return (o1 == 0 and on_seg(p1, p2, q1)) or (o2 == 0 and on_seg(p1, p2, q2)) \
        or (o3 == 0 and on_seg(q1, q2, p1)) or (o4 == 0 and on_seg(q1, q2, p2))


def _check_polygon(P: np.ndarray) -> None:
    m = len(P)
    if m < 3:
        raise ValueError(f"vertices: a polygon needs at least 3 vertices, got {m}")
    if not np.all(np.isfinite(P)):
        raise ValueError("vertices: coordinates must be finite numbers")
    scale = _diameter(P)
    if scale == 0.0:
        raise ValueError("vertices: all vertices coincide; give a non-degenerate polygon")
    tol = 1e-12 * scale**2
    for i in range(m):
        if np.linalg.norm(P[(i + 1) % m] - P[i]) <= 1e-12 * scale:
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
                    raise ValueError(f"vertices: sides {i} and {j} fold back onto each other; "
                                     "the polygon must be simple")
                continue
            if _segments_intersect(a1, a2, b1, b2, tol):
                raise ValueError(f"vertices: sides {i} and {j} intersect; the polygon must be simple "
                                 "(non-self-intersecting)")
    if _signed_area(P) <= 0:
        raise ValueError("vertices: the polygon is clockwise; list the vertices counter-clockwise")


class _Boundary:
    """Arc-length parametrisation of the polygon boundary (counter-clockwise)."""

    def __init__(self, P: np.ndarray):
        self.P = P
        self.m = len(P)
        self.seg = np.roll(P, -1, axis=0) - P
        self.len = np.linalg.norm(self.seg, axis=1)
        self.S = np.concatenate([[0.0], np.cumsum(self.len)])
        self.L = float(self.S[-1])
        self.tol = 1e-8 * _diameter(P)

    def locate(self, q: np.ndarray) -> tuple[float, float, np.ndarray]:
        """(distance to Gamma, arc-length position, projected point)."""
        r = q[None, :] - self.P
        tau = np.clip((r * self.seg).sum(1) / self.len**2, 0.0, 1.0)
        proj = self.P + tau[:, None] * self.seg
        dist = np.linalg.norm(proj - q[None, :], axis=1)
        i = int(np.argmin(dist))
        return float(dist[i]), float(self.S[i] + tau[i] * self.len[i]) % self.L, proj[i]

    def point(self, s: float) -> np.ndarray:
        s = s % self.L
        i = min(int(np.searchsorted(self.S, s, side="right")) - 1, self.m - 1)
        return self.P[i] + (s - self.S[i]) / self.len[i] * self.seg[i]

    def inside(self, s: float | np.ndarray, arc: Arc) -> Any:
        """s lies strictly inside the arc (away from its ends by more than tol)."""
        if arc.whole:
            return np.ones_like(np.asarray(s), dtype=bool)
        r = (np.asarray(s) - arc.s0) % self.L
        return (r > self.tol) & (r < arc.length - self.tol)


def _side_names(shape: str, m: int) -> dict[str, int]:
    names = {f"side{i}": i for i in range(m)}
    if shape == "square":
        names.update({n: i for i, n in enumerate(SQUARE_SIDES)})
    elif shape == "lshape":
        names.update({n: i for i, n in enumerate(LSHAPE_SIDES)})
    return names


def _parse_arcs(signorini: Any, shape: str, B: _Boundary) -> tuple[tuple[Arc, ...], bool]:
    if isinstance(signorini, str):
        signorini = (signorini,)
    try:
        items = list(signorini)
    except TypeError:
        raise ValueError("signorini must be a sequence of arcs (point pairs or side names), 'all' or ()") from None
    if any(isinstance(a, str) and a == "all" for a in items):
        if len(items) != 1:
            raise ValueError("signorini: 'all' (the whole boundary) cannot be combined with other arcs")
        return (Arc(tuple(map(float, B.P[0])), tuple(map(float, B.P[0])), 0.0, B.L, True, "all"),), True
    sides = _side_names(shape, B.m)
    arcs: list[Arc] = []
    for k, a in enumerate(items):
        if isinstance(a, str):
            if a not in sides:
                named = [n for n in sides if not re.fullmatch(r"side\d+", n)]
                raise ValueError(f"signorini arc {k}: unknown side {a!r}; use one of "
                                 f"{', '.join(named + ['side<i>'])}, 'all' or a pair of points")
            i = sides[a]
            arcs.append(Arc(tuple(map(float, B.P[i])), tuple(map(float, B.P[(i + 1) % B.m])),
                            float(B.S[i]), float(B.len[i]), False, a))
            continue
        try:
            pts = np.asarray(a, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"signorini arc {k}: expected ((x0, y0), (x1, y1)) or a side name, got {a!r}") from None
        if pts.shape != (2, 2) or not np.all(np.isfinite(pts)):
            raise ValueError(f"signorini arc {k}: expected ((x0, y0), (x1, y1)) or a side name, got {a!r}")
        ends = []
        for q in pts:
            dist, s, proj = B.locate(q)
            if dist > B.tol:
                raise ValueError(f"signorini arc {k}: point ({q[0]:g}, {q[1]:g}) is not on the boundary "
                                 f"(distance {dist:.3g}); give points on Gamma")
            # snap onto a polygon vertex when within tolerance
            dv = np.linalg.norm(B.P - proj, axis=1)
            if dv.min() <= B.tol:
                proj = B.P[int(np.argmin(dv))]
                s = float(B.S[int(np.argmin(dv))]) % B.L
            ends.append((s, proj))
        length = (ends[1][0] - ends[0][0]) % B.L
        if length <= B.tol or length >= B.L - B.tol:
            raise ValueError(f"signorini arc {k}: its end equals its start; give two different points "
                             "(or 'all' for the whole boundary)")
        arcs.append(Arc(tuple(map(float, ends[0][1])), tuple(map(float, ends[1][1])), ends[0][0], length,
                        False, f"arc{k}"))
    for i in range(len(arcs)):
        for j in range(i + 1, len(arcs)):
            a, b = arcs[i], arcs[j]
            if B.inside(b.s0, a) or B.inside(a.s0, b) or abs(((a.s0 - b.s0 + B.L / 2) % B.L) - B.L / 2) <= B.tol:
                raise ValueError(f"signorini arcs {i} and {j} overlap; arcs may only touch at end points")
    return tuple(arcs), False


# ============================================================ coarse partitions
def _grid_partition(shape: str, center: Sequence[float], width: float, d: float):
    """Coarse squares of the square / L-shape: (polygon, coarse vertices, cells, n_c)."""
    cx, cy = float(center[0]), float(center[1])
    x0, x1, y0, y1 = cx - width / 2, cx + width / 2, cy - width / 2, cy + width / 2
    if shape == "square":
        nc = max(1, int(round(width / d)))
    else:
        nc = max(2, 2 * int(round(width / (2 * d))))
    xs, ys = np.linspace(x0, x1, nc + 1), np.linspace(y0, y1, nc + 1)
    half = nc // 2
    keep = np.ones((nc, nc), dtype=bool)  # keep[j, i]: coarse square i (x), j (y)
    if shape == "lshape":
        keep[half:, half:] = False
    # squares row by row (j, then i), corners counter-clockwise; vertices numbered in
    # the order they first appear
    jj, ii = np.nonzero(keep)
    corner = (np.stack([jj, jj, jj + 1, jj + 1], 1) * (nc + 1) + np.stack([ii, ii + 1, ii + 1, ii], 1)).ravel()
    grid_point, first = np.unique(corner, return_index=True)
    grid_point = grid_point[np.argsort(first)]
    vid = np.empty((nc + 1) ** 2, dtype=np.int64)
    vid[grid_point] = np.arange(len(grid_point))
    verts = np.stack([xs[grid_point % (nc + 1)], ys[grid_point // (nc + 1)]], 1)
    cells = vid[corner].reshape(-1, 4).tolist()
    if shape == "square":
        P = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    else:
        xm, ym = xs[half], ys[half]
        P = np.array([[x0, y0], [x1, y0], [x1, ym], [xm, ym], [xm, y1], [x0, y1]])
    return P, np.array(verts, dtype=float), cells, width / nc


def _insert_boundary_points(V: np.ndarray, cells: list[list[int]], points: list[np.ndarray], tol: float):
    """Insert points lying on coarse boundary edges into the cells owning those edges."""
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


def _polygon_partition_gmsh(P: np.ndarray, extra: list[np.ndarray], d: float, tol: float):
    """Coarse triangles: a gmsh mesh of size d of the polygon with ``extra`` boundary points."""
    import gmsh

    B = _Boundary(P)
    pts = [(float(B.S[i]), P[i]) for i in range(len(P))]
    for q in extra:
        _, s, proj = B.locate(q)
        if min(np.linalg.norm(P - proj, axis=1)) > tol:
            pts.append((s, proj))
    pts.sort(key=lambda x: x[0])
    geo = gmsh.model.geo
    ptags = [geo.addPoint(float(p[0]), float(p[1]), 0.0, d) for _, p in pts]
    lines = [geo.addLine(ptags[i], ptags[(i + 1) % len(ptags)]) for i in range(len(ptags))]
    loop = geo.addCurveLoop(lines)
    surf = geo.addPlaneSurface([loop])
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, [surf], 1)
    gmsh.model.mesh.generate(2)
    tags, x, _ = gmsh.model.mesh.getNodes()
    x = x.reshape(-1, 3)[:, :2]
    order = np.argsort(tags)
    tags, x = tags[order], x[order]
    _, elem_nodes = gmsh.model.mesh.getElementsByType(2)
    tri = np.searchsorted(tags, elem_nodes.reshape(-1, 3))
    used = np.unique(tri)
    remap = -np.ones(len(tags), dtype=np.int64)
    remap[used] = np.arange(len(used))
    V = x[used]
    tri = remap[tri]
    a, b, c = V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]]
    neg = ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]) < 0
    tri[neg] = tri[neg][:, [0, 2, 1]]
    return V, [list(map(int, t)) for t in tri]


# ============================================================== fine gmsh model
def _edge_key(a: int, b: int) -> tuple[int, int]:
    return (a, b) if a < b else (b, a)


def _boundary_edges(cells: list[list[int]]) -> dict[tuple[int, int], int]:
    count: dict[tuple[int, int], int] = {}
    for c in cells:
        for a, b in zip(c, c[1:] + c[:1]):
            k = _edge_key(a, b)
            count[k] = count.get(k, 0) + 1
    return count


def _edge_tag(V: np.ndarray, a: int, b: int, B: _Boundary, arcs: tuple[Arc, ...]) -> int:
    _, s, _ = B.locate(0.5 * (V[a] + V[b]))
    for k, arc in enumerate(arcs):
        if B.inside(s, arc):
            return SIGNORINI_TAG0 + k
    return GAMMA_T_TAG


def _build_fine_geo(V: np.ndarray, cells: list[list[int]], h: float, B: _Boundary, arcs: tuple[Arc, ...]):
    """Unstructured fine mesh: one gmsh plane surface per coarse cell (its own physical
    group), coarse lines shared between neighbours, mesh size h.

    Returns the mesh as arrays (x, cells, cell subdomain ids, boundary facets, facet tags).
    The arrays are read per surface and per line rather than through
    ``gmshio.extract_topology_and_markers``, whose per-physical-group queries are
    quadratic in the number of groups (7 s for 3000 subdomains).
    """
    import gmsh

    geo = gmsh.model.geo
    ptags = [geo.addPoint(float(x), float(y), 0.0, h) for x, y in V]
    count = _boundary_edges(cells)
    line_of: dict[tuple[int, int], int] = {}
    for (a, b) in sorted(count):
        line_of[(a, b)] = geo.addLine(ptags[a], ptags[b])
    surfs = []
    for c in cells:
        loop = []
        for a, b in zip(c, c[1:] + c[:1]):
            tag = line_of[_edge_key(a, b)]
            loop.append(tag if a < b else -tag)
        surfs.append(geo.addPlaneSurface([geo.addCurveLoop(loop)]))
    geo.synchronize()
    for i, s in enumerate(surfs):  # every surface needs a physical group (else dolfinx segfaults)
        gmsh.model.addPhysicalGroup(2, [s], i + 1)
    groups: dict[int, list[int]] = {}
    for (a, b), n in count.items():
        if n == 1:
            groups.setdefault(_edge_tag(V, a, b, B, arcs), []).append(line_of[(a, b)])
    for tag, lines in sorted(groups.items()):
        gmsh.model.addPhysicalGroup(1, lines, tag)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.model.mesh.generate(2)

    node_tags, xyz, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(node_tags)
    node_tags = node_tags[order]
    x = xyz.reshape(-1, 3)[order, :2]
    tri, tri_id = [], []
    for i, s in enumerate(surfs):
        _, enodes = gmsh.model.mesh.getElementsByType(2, s)
        tri.append(enodes)
        tri_id.append(np.full(len(enodes) // 3, i, dtype=np.int32))
    seg, seg_tag = [], []
    for tag, lines in sorted(groups.items()):
        for line in lines:
            _, enodes = gmsh.model.mesh.getElementsByType(1, line)
            seg.append(enodes)
            seg_tag.append(np.full(len(enodes) // 2, tag, dtype=np.int32))
    cells_arr = np.searchsorted(node_tags, np.concatenate(tri)).reshape(-1, 3)
    facets_arr = np.searchsorted(node_tags, np.concatenate(seg)).reshape(-1, 2)
    return x, cells_arr, np.concatenate(tri_id), facets_arr, np.concatenate(seg_tag)


def subdomain_owners(x: np.ndarray, cells: np.ndarray, subdomain: np.ndarray, nparts: int) -> np.ndarray:
    """The rank of every cell such that each subdomain lies whole on one rank.

    Recursive coordinate bisection of the subdomain centroids, weighted by the cell
    count: a group of subdomains for ``k`` ranks is cut across its longer extent at
    the weighted position k//2 : k - k//2. The partition is deterministic (the same
    for every run), and the local Dirichlet problems of METHOD.md section 6 become
    rank-local.

    Parameters
    ----------
    x : (n_nodes, 2) node coordinates; cells : (n_cells, 3) node numbers;
    subdomain : (n_cells,) subdomain id of each cell (0 .. L-1); nparts : number of ranks.
    """
    subdomain = np.asarray(subdomain, dtype=np.int64)
    n_sub = int(subdomain.max(initial=-1)) + 1
    weight = np.bincount(subdomain, minlength=n_sub).astype(float)
    centre = x[cells].mean(axis=1)
    centroid = np.stack([np.bincount(subdomain, centre[:, i], minlength=n_sub) for i in range(2)], 1)
    centroid /= np.maximum(weight, 1.0)[:, None]
    part = np.zeros(n_sub, dtype=np.int32)

    def bisect(ids: np.ndarray, first: int, count: int) -> None:
        if count == 1 or ids.size < 2:
            part[ids] = first
            return
        c = centroid[ids]
        axis = int(np.argmax(np.ptp(c, axis=0)))
        order = ids[np.lexsort((c[:, 1 - axis], c[:, axis]))]
        left = count // 2
        cum = np.cumsum(weight[order])  # cum[k]: weight of order[:k + 1]
        cut = 1 + int(np.argmin(np.abs(cum[:-1] - cum[-1] * left / count)))
        bisect(order[:cut], first, left)
        bisect(order[cut:], first + left, count - left)

    bisect(np.arange(n_sub), 0, nparts)
    return part[subdomain]


def _destinations(owner: np.ndarray, links: np.ndarray):
    """DOLFINx partitioner output: per local cell its owner, then the ranks ghosting it
    (``links``: unique (cell, rank) rows)."""
    from dolfinx import cpp

    n = len(owner)
    cell = np.concatenate([np.arange(n), links[:, 0]])
    rank = np.concatenate([owner, links[:, 1]])
    order = np.lexsort((np.arange(cell.size) >= n, cell))  # per cell: the owner first
    offsets = np.concatenate([[0], np.cumsum(np.bincount(cell, minlength=n))])
    return cpp.graph.AdjacencyList_int32(rank[order].astype(np.int32), offsets.astype(np.int32))


def _owner_and_ghosts(cells: np.ndarray, owner: np.ndarray):
    """Rows of (owner, ranks ghosting the cell) for DOLFINx's shared-facet ghost mode:
    a cell is ghosted on the owners of its facet neighbours. Only cells with two nodes
    touched by several ranks can have a neighbour elsewhere, so only their facets are
    matched."""
    nparts = int(owner.max(initial=0)) + 1
    n_nodes = int(cells.max(initial=0)) + 1
    ranks_at = sum((np.bincount(cells[owner == r].ravel(), minlength=n_nodes) > 0).astype(np.int8)
                   for r in range(nparts))
    near = np.flatnonzero((ranks_at[cells] > 1).sum(1) >= 2)
    facets = np.sort(cells[near][:, [[1, 2], [2, 0], [0, 1]]].reshape(-1, 2), axis=1)
    code = facets[:, 0] * n_nodes + facets[:, 1]
    order = np.argsort(code)
    same = np.flatnonzero(code[order][1:] == code[order][:-1])  # a facet seen from both cells
    a, b = near[order[same] // 3], near[order[same + 1] // 3]
    cut = owner[a] != owner[b]
    a, b = a[cut], b[cut]
    links = np.unique(np.stack([np.concatenate([a, b]), owner[np.concatenate([b, a])]], 1), axis=0)
    return _destinations(owner, links.reshape(-1, 2))


def _tagged_mesh(msh: Any, cell_values: np.ndarray, facets: np.ndarray, facet_values: np.ndarray):
    """(mesh, cell tags, facet tags): ``cell_values`` for the local cells (owned, then
    ghosts), ``facets`` (input node numbers) and their values on any rank."""
    from dolfinx import cpp

    ct = dmesh.meshtags(msh, 2, np.arange(_n_local_cells(msh), dtype=np.int32),
                        np.asarray(cell_values, dtype=np.int32))
    ents, vals = cpp.io.distribute_entity_data(msh._mesh, 1, np.asarray(facets, dtype=np.int64).reshape(-1, 2),
                                               np.asarray(facet_values, dtype=np.int32))
    msh.topology.create_connectivity(1, 2)
    ft = dmesh.meshtags_from_entities(msh, 1, cpp.graph.AdjacencyList_int32(ents), vals.astype(np.int32))
    ct.name, ft.name = "subdomains", "boundary"
    return msh, ct, ft


def _ufl_triangle_mesh() -> Any:
    """The UFL domain of a P1 triangle mesh in 2D (``gmshio.ufl_mesh(2, 2)`` without
    importing gmsh, 0.3 s, where no gmsh is needed)."""
    import ufl

    cell = ufl.Cell("triangle", geometric_dimension=2)
    return ufl.Mesh(ufl.VectorElement(ufl.FiniteElement("Lagrange", cell, 1, variant="equispaced")))


def _n_local_cells(msh: Any) -> int:
    """Number of local cells, owned and ghosts."""
    cells = msh.topology.index_map(2)
    return cells.size_local + cells.num_ghosts


def _local_cells(msh: Any) -> np.ndarray:
    """Input (global) index of every local cell, owned then ghosts."""
    return np.asarray(msh.topology.original_cell_index[:_n_local_cells(msh)], dtype=np.int64)


def _distribute_mesh(comm: Any, arrays: tuple | None):
    """Distribute a triangle mesh held on rank 0 (what ``gmshio.model_to_mesh`` does, with
    the arrays already extracted), whole subdomains per rank (:func:`subdomain_owners`):
    returns (mesh, cell tags, facet tags)."""
    from dolfinx import cpp

    if comm.rank == 0:
        x, cells, cell_values, facets, facet_values = arrays
    else:
        x, cells = np.zeros((0, 2)), np.zeros((0, 3), dtype=np.int64)
        cell_values = np.zeros(0, dtype=np.int32)
        facets, facet_values = np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int32)
    cells = np.asarray(cells, dtype=np.int64)
    x = np.ascontiguousarray(x, dtype=np.float64)

    def partitioner(comm_, nparts, tdim, local_cells, ghost_mode):
        if len(cells) == 0:
            return cpp.graph.AdjacencyList_int32(np.zeros(0, np.int32), np.zeros(1, np.int32))
        return _owner_and_ghosts(cells, subdomain_owners(x, cells, cell_values, nparts))

    # whole subdomains per rank when there are enough subdomains, else DOLFINx's graph
    # partitioner (the preconditioner then runs on rank 0, coupling.distributed)
    n_sub = comm.bcast(int(np.max(cell_values, initial=-1)) + 1 if comm.rank == 0 else None, root=0)
    by_subdomain = n_sub >= comm.size  # also in serial: no graph partitioner for one part
    msh = dmesh.create_mesh(comm, cells, x, _ufl_triangle_mesh(),
                            **({"partitioner": partitioner} if by_subdomain else {}))
    # cell tags by the input index of every local cell (all cells were input on rank 0)
    wanted = comm.gather(_local_cells(msh), root=0)
    values = comm.scatter([np.asarray(cell_values, dtype=np.int32)[w] for w in wanted]
                          if comm.rank == 0 else None, root=0)
    return _tagged_mesh(msh, values, facets, facet_values)


def _distribute_structured(comm: Any, ref: StructuredRefinement, boundary_tag: Callable[[int, int], int]):
    """Create the structured mesh in parallel: every rank writes down the triangles of its
    own coarse cells (:func:`subdomain_owners` of the coarse cells) and an even block of
    the node coordinates, so no rank holds the whole mesh. ``boundary_tag(a, b)`` is the
    facet tag of the coarse boundary edge a-b. Returns (mesh, cell tags, facet tags)."""
    nc, T = len(ref.cells), ref.triangles_per_cell
    rank_of_cell = (subdomain_owners(ref.V, ref.cells, np.arange(nc), comm.size) if comm.size > 1
                    else np.zeros(nc, dtype=np.int32))
    mine = np.flatnonzero(rank_of_cell == comm.rank)
    cells = ref.triangles(mine)
    N = ref.n_nodes
    x = ref.coordinates(comm.rank * N // comm.size, (comm.rank + 1) * N // comm.size)

    def partitioner(comm_, nparts, tdim, local_cells, ghost_mode):
        return _destinations(np.full(len(cells), comm.rank, dtype=np.int64),
                             ref.ghost_ranks(mine, rank_of_cell, comm.rank))

    # whole subdomains per rank when there are enough subdomains, else DOLFINx's graph
    # partitioner (the preconditioner then runs on rank 0, coupling.distributed)
    by_subdomain = nc >= comm.size  # also in serial: no graph partitioner for one part
    msh = dmesh.create_mesh(comm, cells, x, _ufl_triangle_mesh(),
                            **({"partitioner": partitioner} if by_subdomain else {}))
    # input cells are numbered rank after rank, each rank's coarse cells in increasing order
    by_rank = np.argsort(rank_of_cell, kind="stable")
    ct = dmesh.meshtags(msh, 2, np.arange(_n_local_cells(msh), dtype=np.int32),
                        by_rank[_local_cells(msh) // T].astype(np.int32))
    # facet tags from the input numbers of the facet nodes: the coarse edge under each facet
    tag_of_edge = np.full(len(ref.edges), -1, dtype=np.int32)
    for e in np.flatnonzero(ref.edge_cells[:, 1] < 0):
        tag_of_edge[e] = boundary_tag(int(ref.edges[e, 0]), int(ref.edges[e, 1]))
    msh.topology.create_connectivity(1, 0)
    msh.topology.create_connectivity(1, 2)
    node_of_vertex = np.empty(msh.topology.index_map(0).size_local + msh.topology.index_map(0).num_ghosts,
                              dtype=np.int64)
    node_of_vertex[msh.topology.connectivity(2, 0).array] = msh.geometry.dofmap.array
    ends = np.asarray(msh.geometry.input_global_indices, dtype=np.int64)[node_of_vertex[msh.topology.connectivity(1, 0).array]].reshape(-1, 2)
    edge = ref.edge_of_segments(ends[:, 0], ends[:, 1])
    tags = np.where(edge >= 0, tag_of_edge[np.maximum(edge, 0)], -1)
    facets = np.flatnonzero(tags >= 0).astype(np.int32)
    ft = dmesh.meshtags(msh, 1, facets, tags[facets])
    ct.name, ft.name = "subdomains", "boundary"
    return msh, ct, ft


def _validate(shape, h, subdomain_size, center, width, vertices):
    """Scalar and polygon checks (identical on every rank, no communication)."""
    if shape not in SHAPES:
        raise ValueError(f"shape must be one of {SHAPES}, got {shape!r}")
    for name, val in (("h", h), ("subdomain_size", subdomain_size)):
        if isinstance(val, bool) or not isinstance(val, (int, float, np.floating, np.integer)) \
                or not math.isfinite(val) or val <= 0:
            raise ValueError(f"{name} must be a positive number, got {val!r}")
    h, d = float(h), float(subdomain_size)
    if d < 2 * h:
        raise ValueError(f"subdomain_size d={d:g} is smaller than 2h={2 * h:g}; increase subdomain_size "
                         "or decrease h")
    if shape == "polygon":
        if vertices is None:
            raise ValueError("shape 'polygon' needs vertices=[(x0, y0), (x1, y1), ...] (counter-clockwise)")
        try:
            P = np.asarray(vertices, dtype=float)
        except (TypeError, ValueError):
            raise ValueError("vertices must be a list of (x, y) pairs") from None
        if P.ndim != 2 or P.shape[1] != 2:
            raise ValueError(f"vertices must be a list of (x, y) pairs, got shape {P.shape}")
        _check_polygon(P)
        cx = cy = None
    else:
        if vertices is not None:
            raise ValueError(f"vertices are only used by shape 'polygon'; drop them for shape {shape!r}")
        try:
            cx, cy = (float(c) for c in center)
        except (TypeError, ValueError):
            raise ValueError(f"center must be a pair (x, y), got {center!r}") from None
        if not (math.isfinite(cx) and math.isfinite(cy)):
            raise ValueError(f"center must be finite, got {center!r}")
        if isinstance(width, bool) or not isinstance(width, (int, float, np.floating, np.integer)) \
                or not math.isfinite(width) or width <= 0:
            raise ValueError(f"width must be a positive number, got {width!r}")
        P = None
    return h, d, P, (cx, cy)


def build_domain(comm: Any, shape: str, *, h: float, subdomain_size: float,
                 center: Sequence[float] = (0.0, 0.0), width: float = 0.5,
                 vertices: Sequence[Sequence[float]] | None = None, signorini: Any = (),
                 structured: bool = False, allow_large: bool = False) -> Domain:
    """Mesh Omega with a coarse partition into subdomains of size about ``subdomain_size``.

    Parameters
    ----------
    comm
        MPI communicator (all its ranks call with the same arguments).
    shape
        ``"square"`` (``center``, ``width``), ``"lshape"`` (``center``, ``width``: the square
        of that width minus its upper-right quarter) or ``"polygon"`` (``vertices``, CCW).
    h
        Fine mesh size (structured: h = coarse edge / round(d/h)).
    subdomain_size
        Coarse size d >= 2h.
    signorini
        Signorini arcs (module docstring); () for none.
    structured
        Uniform refinement of the coarse cells instead of an unstructured gmsh mesh.
    allow_large
        Allow diam(Omega) >= 1 (then V is not guaranteed elliptic, METHOD.md section 2).

    Returns
    -------
    Domain

    Raises
    ------
    ValueError
        Invalid parameters (raised identically on every rank before any collective).
    """
    h, d, P, (cx, cy) = _validate(shape, h, subdomain_size, center, width, vertices)
    if shape != "polygon":
        P, cV, ccells, csize = _grid_partition(shape, (cx, cy), float(width), d)
    diam = _diameter(P)
    if diam >= 1.0 and not allow_large:
        raise ValueError(f"diam(Omega) = {diam:.4g} >= 1: the single-layer operator may not be elliptic "
                         "(METHOD.md section 2); shrink the domain, or opt out with allow_large "
                         "(geometry.allow_large = true) at your own risk")
    B = _Boundary(P)
    arcs, whole = _parse_arcs(signorini, shape, B)
    ends = [] if whole else [np.asarray(p) for a in arcs for p in (a.start, a.end)]
    if shape != "polygon":
        if structured:
            for q in ends:
                if np.linalg.norm(cV - q, axis=1).min() > B.tol:
                    raise ValueError(f"signorini: arc end ({q[0]:g}, {q[1]:g}) is not a coarse grid vertex, "
                                     "which structured=True requires; move it to a multiple of the coarse "
                                     f"size {csize:g} or use structured=False")
        else:
            cV, ccells = _insert_boundary_points(cV, ccells, ends, B.tol)

    # ---- gmsh runs on rank 0 (the polygon's coarse mesh, the unstructured fine mesh);
    # errors are broadcast so no rank waits forever.
    error, arrays = None, None
    if comm.rank == 0 and (shape == "polygon" or not structured):
        try:
            import gmsh

            gmsh.initialize(readConfigFiles=False)
            gmsh.option.setNumber("General.Terminal", 0)
            try:
                if shape == "polygon":
                    gmsh.model.add("fembem_coarse")
                    cV, ccells = _polygon_partition_gmsh(P, ends, d, B.tol)
                    gmsh.model.remove()
                if not structured:
                    gmsh.model.add("fembem_domain")
                    arrays = _build_fine_geo(cV, ccells, h, B, arcs)
            finally:
                gmsh.finalize()
        except Exception as err:
            error = f"{type(err).__name__}: {err}"
    error = comm.bcast(error, root=0)
    if error is not None:
        raise RuntimeError(f"meshing the domain failed: {error}")
    if shape == "polygon":
        cV, ccells = comm.bcast((cV, ccells) if comm.rank == 0 else None, root=0)
        csize = float(np.mean([np.linalg.norm(cV[a] - cV[b]) for c in ccells for a, b in zip(c, c[1:] + c[:1])]))
    if structured:  # every rank writes down its own part of the refinement
        n = max(2, int(round((d if shape == "polygon" else csize) / h)))
        msh, ct0, ft = _distribute_structured(comm, refine(cV, ccells, n),
                                              lambda a, b: _edge_tag(cV, a, b, B, arcs))
    else:
        msh, ct0, ft = _distribute_mesh(comm, arrays)
    coarse = compute_coarse_structure(msh, ct0, ft)
    h_max = _max_facet_length(msh)
    return Domain(mesh=msh, cell_tags=ct0, facet_tags=ft, coarse=coarse, arcs=arcs, h=h, subdomain_size=d,
                  shape=shape, vertices=P.copy(), signorini_is_whole_boundary=whole, structured=bool(structured),
                  coarse_size=float(csize), h_max=h_max)


def _max_facet_length(msh: Any) -> float:
    """The longest fine facet: the longest side of the local triangles, maximised over ranks."""
    x = msh.geometry.x[:, :2]
    corners = msh.geometry.dofmap.array.reshape(-1, 3)
    p = [x.take(corners[:, k], axis=0) for k in range(3)]  # take: much faster than x[...] for (n, 2) rows
    loc = max(float(np.einsum("ij,ij->i", d, d).max(initial=0.0)) for d in (p[1] - p[0], p[2] - p[1], p[0] - p[2]))
    return math.sqrt(msh.comm.allreduce(loc, op=MPI.MAX))
