"""Uniform refinement of a coarse partition, written down piece by piece (no gmsh).

Every coarse cell (all squares, or all triangles) is refined into n segments per side:
a square into an n x n grid of squares split along the (i,j)-(i+1,j+1) diagonal, a
triangle into n^2 similar triangles. The numbering is global and closed-form, so every
rank can produce any part of the mesh without the rest: the triangles of its own coarse
cells and any contiguous block of node coordinates (the layout ``dolfinx.mesh.create_mesh``
takes as input). Nodes are numbered by kind (*node numbers*)

- ``[0, nv)``: the coarse vertices;
- ``nv + e (n - 1) + k - 1``: the k-th interior node (k = 1 .. n-1) of coarse edge e, edges
  sorted by their (lower, higher) vertex pair, nodes running from the lower vertex;
- ``offset + c m + l``: the l-th of the m interior nodes of coarse cell c;

and the mesh gets them in blocks by coarse cell (*input numbers*, :meth:`input_numbers`):
cell c's block holds the vertices whose lowest cell is c, then the nodes of the edges
whose lowest cell is c, then its interior nodes. Nodes near each other in the mesh are
then near each other in memory, which ``create_mesh`` rewards (measured at 2e6
triangles: 3.5 s against 4.7 s for the node numbers, 3.3 s for ``create_rectangle``'s
row-major order). Both maps are closed-form over the coarse cells, vertices and edges.

The triangles of coarse cell c are rows ``c T .. (c + 1) T - 1`` in a fixed reference order
(T = 2 n^2 for squares, n^2 for triangles).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable

import numpy as np

__all__ = ["Lattice", "StructuredRefinement", "lattice", "refine", "node_count"]


@dataclass(frozen=True)
class Lattice:
    """The reference refinement of one coarse cell with n segments per side.

    Attributes
    ----------
    sides : (k, n+1) int
        Lattice points along side s (from corner s to corner s+1), corners included.
    interior : (m,) int
        Lattice points of the interior nodes, in their numbering order.
    weights : (m, k) float
        Coordinates of the interior nodes as weights of the k corners.
    triangles : (T, 3) int
        Lattice points of the fine triangles (counter-clockwise if the corners are).
    side_triangles : tuple of k int arrays
        The triangles with a facet on side s.
    """

    n: int
    n_points: int
    sides: np.ndarray
    interior: np.ndarray
    weights: np.ndarray
    triangles: np.ndarray
    side_triangles: tuple


def lattice(corners: int, n: int) -> Lattice:
    """The reference refinement of a square (``corners=4``) or triangle (``corners=3``)."""
    if corners not in (3, 4) or n < 1:
        raise ValueError(f"a lattice needs 3 or 4 corners and n >= 1, got {corners} and {n}")
    k = np.arange(n + 1)
    if corners == 4:  # point (j, i) -> j (n+1) + i, corners (0,0), (0,n), (n,n), (n,0)
        p = lambda j, i: np.asarray(j) * (n + 1) + np.asarray(i)  # noqa: E731
        sides = np.stack([p(0, k), p(k, n), p(n, n - k), p(n - k, 0)])
        jj, ii = np.meshgrid(np.arange(1, n), np.arange(1, n), indexing="ij")
        interior = p(jj, ii).ravel()
        s, r = ii.ravel() / n, jj.ravel() / n
        weights = np.stack([(1 - s) * (1 - r), s * (1 - r), s * r, (1 - s) * r], 1)
        j, i = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
        a, b, c, d = p(j, i), p(j, i + 1), p(j + 1, i + 1), p(j + 1, i)
        triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    else:  # point (i, j), i + j <= n -> i (n+1) + j, corners (0,0), (n,0), (0,n)
        p = lambda i, j: np.asarray(i) * (n + 1) + np.asarray(j)  # noqa: E731
        sides = np.stack([p(k, 0), p(n - k, k), p(0, n - k)])
        ij = np.array(
            [(i, j) for i in range(1, n) for j in range(1, n - i)], dtype=np.int64
        ).reshape(-1, 2)
        interior = p(ij[:, 0], ij[:, 1])
        s, r = ij[:, 0] / n, ij[:, 1] / n
        weights = np.stack([1 - s - r, s, r], 1)
        tl = []
        for i in range(n):
            for j in range(n - i):
                tl.append((p(i, j), p(i + 1, j), p(i, j + 1)))
                if i + j < n - 1:
                    tl.append((p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)))
        triangles = np.array(tl, dtype=np.int64)
    on_side = [np.isin(triangles, side).sum(1) == 2 for side in sides]
    return Lattice(
        n=n,
        n_points=(n + 1) ** 2,
        sides=sides.astype(np.int64),
        interior=interior.astype(np.int64),
        weights=weights,
        triangles=triangles.astype(np.int64),
        side_triangles=tuple(np.flatnonzero(m) for m in on_side),
    )


@dataclass(frozen=True)
class _Blocks:
    """The input numbering (blocks by coarse cell, module docstring) over the coarse
    entities: block c is ``[start[c], start[c + 1])``; its owned vertices are
    ``vertices[vertex_start[c]:vertex_start[c + 1]]`` and its owned edges
    ``edges[edge_start[c]:edge_start[c + 1]]``, in increasing order."""

    start: np.ndarray
    vertices: np.ndarray
    vertex_start: np.ndarray
    edges: np.ndarray
    edge_start: np.ndarray
    vertex_input: np.ndarray  # (nv,) the input number of every vertex
    edge_input: np.ndarray  # (ne,) the input number of every edge's node k = 1
    interior_input: np.ndarray  # (nc,) the input number of every cell's interior node 0


def _grouped(owner: np.ndarray, n_groups: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(the indices sorted by their owner, the offsets of each owner's run, the position
    of every index within its owner's run)."""
    order = np.argsort(owner, kind="stable")
    start = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=n_groups))])
    rank = np.empty(len(owner), dtype=np.int64)
    rank[order] = np.arange(len(owner)) - start[owner[order]]
    return order, start, rank


@dataclass(frozen=True, eq=False)
class StructuredRefinement:
    """The refinement of coarse cells ``cells`` of vertices ``V`` (see the module docstring).

    Attributes
    ----------
    edges : (ne, 2) int
        Coarse edges as sorted vertex pairs, in numbering order.
    cell_edges : (nc, k) int
        The edge of side s (corner s to s+1) of every coarse cell.
    edge_cells : (ne, 2) int
        The coarse cells on both sides of every edge (-1 for none: a boundary edge).
    """

    V: np.ndarray
    cells: np.ndarray
    n: int
    lattice: Lattice
    edges: np.ndarray
    cell_edges: np.ndarray
    edge_cells: np.ndarray

    @property
    def n_nodes(self) -> int:
        return node_count(
            len(self.V), len(self.edges), len(self.cells), self.cells.shape[1], self.n
        )

    @property
    def triangles_per_cell(self) -> int:
        return len(self.lattice.triangles)

    @property
    def _offset(self) -> int:
        return len(self.V) + len(self.edges) * (self.n - 1)

    @cached_property
    def _blocks(self) -> _Blocks:
        nc, k, n = len(self.cells), self.cells.shape[1], self.n
        m = len(self.lattice.interior)
        vertex_owner = np.full(len(self.V), nc, dtype=np.int64)
        np.minimum.at(vertex_owner, self.cells.ravel(), np.repeat(np.arange(nc), k))
        vertices, vertex_start, vertex_rank = _grouped(vertex_owner, nc)
        edge_owner = self.edge_cells[:, 0]  # the lower of the two cells
        edges, edge_start, edge_rank = _grouped(edge_owner, nc)
        own_v, own_e = np.diff(vertex_start), np.diff(edge_start)
        start = np.concatenate([[0], np.cumsum(own_v + own_e * (n - 1) + m)])
        return _Blocks(
            start=start,
            vertices=vertices,
            vertex_start=vertex_start,
            edges=edges,
            edge_start=edge_start,
            vertex_input=start[vertex_owner] + vertex_rank,
            edge_input=start[edge_owner] + own_v[edge_owner] + edge_rank * (n - 1),
            interior_input=start[:-1] + own_v + own_e * (n - 1),
        )

    def input_numbers(self, g: np.ndarray) -> np.ndarray:
        """The input numbers of the nodes numbered ``g`` (module docstring)."""
        g = np.asarray(g, dtype=np.int64)
        blocks, nv, n, offset = self._blocks, len(self.V), self.n, self._offset
        m = max(len(self.lattice.interior), 1)
        out = np.empty_like(g)
        vertex, inside = g < nv, g >= offset
        on_edge = ~vertex & ~inside
        out[vertex] = blocks.vertex_input[g[vertex]]
        e, k = np.divmod(g[on_edge] - nv, n - 1)
        out[on_edge] = blocks.edge_input[e] + k
        c, local = np.divmod(g[inside] - offset, m)
        out[inside] = blocks.interior_input[c] + local
        return out

    def node_numbers(self, i: np.ndarray) -> np.ndarray:
        """The node numbers of the nodes with input numbers ``i`` (inverse of
        :meth:`input_numbers`)."""
        i = np.asarray(i, dtype=np.int64)
        blocks, nv, n, offset = self._blocks, len(self.V), self.n, self._offset
        m = len(self.lattice.interior)
        c = np.searchsorted(blocks.start, i, side="right") - 1
        r = i - blocks.start[c]
        own_v = blocks.vertex_start[c + 1] - blocks.vertex_start[c]
        own_e = blocks.edge_start[c + 1] - blocks.edge_start[c]
        out = np.empty_like(i)
        vertex = r < own_v
        out[vertex] = blocks.vertices[blocks.vertex_start[c[vertex]] + r[vertex]]
        inside = r >= own_v + own_e * (n - 1)
        out[inside] = offset + c[inside] * m + (r - own_v - own_e * (n - 1))[inside]
        on_edge = ~vertex & ~inside
        e, k = np.divmod((r - own_v)[on_edge], n - 1)
        out[on_edge] = nv + blocks.edges[blocks.edge_start[c[on_edge]] + e] * (n - 1) + k
        return out

    def edge_tags(self, boundary_tag: Callable[[int, int], int]) -> np.ndarray:
        """(ne,) int32: ``boundary_tag(a, b)`` of every coarse boundary edge a-b, -1 for the
        interior edges."""
        tags = np.full(len(self.edges), -1, dtype=np.int32)
        for e in np.flatnonzero(self.edge_cells[:, 1] < 0):
            tags[e] = boundary_tag(int(self.edges[e, 0]), int(self.edges[e, 1]))
        return tags

    def edge_nodes(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(len(a), n+1) node numbers at k/n along the coarse edges a -> b, k = 0..n."""
        a, b = np.atleast_1d(np.asarray(a, dtype=np.int64)), np.atleast_1d(
            np.asarray(b, dtype=np.int64)
        )
        nv, n = len(self.V), self.n
        codes = self.edges[:, 0] * nv + self.edges[:, 1]
        e = np.searchsorted(codes, np.minimum(a, b) * nv + np.maximum(a, b))
        k = np.arange(n + 1)
        ids = nv + e[:, None] * (n - 1) + np.where((a < b)[:, None], k, n - k) - 1
        ids[:, 0], ids[:, n] = a, b
        return ids

    def triangles(self, ids: np.ndarray) -> np.ndarray:
        """(len(ids) T, 3) input numbers of the triangles of coarse cells ``ids``, cell by
        cell."""
        ids = np.asarray(ids, dtype=np.int64)
        lat, q = self.lattice, self.cells[ids]
        k = q.shape[1]
        node = np.zeros((len(ids), lat.n_points), dtype=np.int64)  # a triangle uses fewer
        for s in range(k):
            node[:, lat.sides[s]] = self.edge_nodes(q[:, s], q[:, (s + 1) % k])
        m = len(lat.interior)
        node[:, lat.interior] = self._offset + ids[:, None] * m + np.arange(m)
        return self.input_numbers(node)[:, lat.triangles].reshape(-1, 3)

    def coordinates(self, lo: int, hi: int) -> np.ndarray:
        """(hi - lo, 2) coordinates of the nodes of input numbers lo .. hi-1."""
        return self.node_coordinates(self.node_numbers(np.arange(lo, hi, dtype=np.int64)))

    def node_coordinates(self, g: np.ndarray) -> np.ndarray:
        """(len(g), 2) coordinates of the nodes numbered ``g``."""
        V, n, lat = self.V, self.n, self.lattice
        nv, offset, m = len(V), self._offset, len(lat.interior)
        g = np.asarray(g, dtype=np.int64)
        X = np.empty((len(g), 2))
        vert = g < nv
        X[vert] = V[g[vert]]
        on_edge = (g >= nv) & (g < offset)
        e, k = np.divmod(g[on_edge] - nv, n - 1)
        a, b = V[self.edges[e, 0]], V[self.edges[e, 1]]
        X[on_edge] = a + ((k + 1) / n)[:, None] * (b - a)
        inside = g >= offset
        c, node = np.divmod(g[inside] - offset, max(m, 1))
        corners = V[self.cells[c]]  # (len, k, 2)
        w = lat.weights[node]
        if self.cells.shape[1] == 4:
            X[inside] = (
                w[:, 0:1] * corners[:, 0]
                + w[:, 1:2] * corners[:, 1]
                + w[:, 2:3] * corners[:, 2]
                + w[:, 3:4] * corners[:, 3]
            )
        else:
            c0 = corners[:, 0]
            X[inside] = c0 + w[:, 1:2] * (corners[:, 1] - c0) + w[:, 2:3] * (corners[:, 2] - c0)
        return X

    def edge_of_segments(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The coarse edge on which the fine segment a-b lies (node numbers), or -1."""
        a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
        nv, n = len(self.V), self.n

        def edge(g: np.ndarray) -> np.ndarray:
            return np.where((g >= nv) & (g < self._offset), (g - nv) // max(n - 1, 1), -1)

        ea, eb = edge(a), edge(b)
        e = np.maximum(ea, eb)  # every fine segment on a coarse edge has an interior node of it
        ends = self.edges[np.maximum(e, 0)]
        on_a = (ea == e) | (a == ends[:, 0]) | (a == ends[:, 1])
        on_b = (eb == e) | (b == ends[:, 0]) | (b == ends[:, 1])
        return np.where((e >= 0) & on_a & on_b, e, -1)

    def ghost_ranks(self, ids: np.ndarray, rank_of_cell: np.ndarray, rank: int) -> np.ndarray:
        """(g, 2) rows (triangle, rank): the local triangles (numbered as in
        :meth:`triangles`) with a facet on a coarse edge whose other cell lies on another
        rank, and that rank (DOLFINx's shared-facet ghosts)."""
        ids = np.asarray(ids, dtype=np.int64)
        T = self.triangles_per_cell
        rows = []
        for s, tris in enumerate(self.lattice.side_triangles):
            pair = self.edge_cells[self.cell_edges[ids, s]]
            other = np.where(pair[:, 0] == ids, pair[:, 1], pair[:, 0])
            far = np.flatnonzero((other >= 0) & (rank_of_cell[np.maximum(other, 0)] != rank))
            tri = (far[:, None] * T + tris[None, :]).ravel()
            rows.append(np.stack([tri, np.repeat(rank_of_cell[other[far]], len(tris))], 1))
        return np.unique(np.concatenate(rows), axis=0)  # one (possibly empty) block per side


def node_count(n_vertices: int, n_edges: int, n_cells: int, corners: int, n: int) -> int:
    """The fine nodes of the refinement (the numbering of the module docstring) without
    building it: nv + ne (n - 1) + nc m, m = (n - 1)^2 interior nodes per square,
    (n - 1)(n - 2)/2 per triangle."""
    interior = (n - 1) ** 2 if corners == 4 else (n - 1) * (n - 2) // 2
    return n_vertices + n_edges * (n - 1) + n_cells * interior


def refine(V: np.ndarray, cells: np.ndarray, n: int) -> StructuredRefinement:
    """The uniform refinement of the coarse cells (rows of ``cells``, counter-clockwise
    vertex numbers into ``V``), with ``n`` >= 2 segments per coarse edge."""
    cells = np.asarray(cells, dtype=np.int64)
    if cells.ndim != 2 or cells.shape[1] not in (3, 4):
        raise ValueError("coarse cells must be all triangles or all quadrilaterals")
    if n < 2:
        raise ValueError(f"a structured refinement needs n >= 2 segments per coarse edge, got {n}")
    nc, k = cells.shape
    a, b = cells, np.roll(cells, -1, axis=1)
    lo, hi = np.minimum(a, b).ravel(), np.maximum(a, b).ravel()
    nv = len(V)
    codes, inverse = np.unique(lo * nv + hi, return_inverse=True)
    edges = np.stack(np.divmod(codes, nv), 1)
    cell_edges = inverse.reshape(nc, k)
    edge_cells = np.full((len(edges), 2), -1, dtype=np.int64)
    order = np.argsort(inverse, kind="stable")
    e, cell = inverse[order], order // k
    first = np.concatenate([[True], e[1:] != e[:-1]])
    if np.any(np.bincount(e) > 2):
        raise ValueError("a coarse edge is shared by more than two coarse cells")
    edge_cells[e[first], 0] = cell[first]
    edge_cells[e[~first], 1] = cell[~first]
    if nv and np.bincount(cells.ravel(), minlength=nv).min() == 0:
        raise ValueError("every coarse vertex must be a corner of a coarse cell")
    return StructuredRefinement(
        V=np.asarray(V, dtype=float),
        cells=cells,
        n=int(n),
        lattice=lattice(k, int(n)),
        edges=edges,
        cell_edges=cell_edges,
        edge_cells=edge_cells,
    )
