"""The grading of the subdomains of a locally refined mesh, and the split of the graded
ones (docs/method.md section 6; docs/design/adapt.md, "Subdomains on graded meshes").

Local refinement keeps the coarse partition (``fem_py.mesh.refinement``), so a subdomain at a
singularity gets ever smaller cells inside while its size H stays: the ratio H/h of the
substructuring bound (1 + log(H/h))^2 grows by about log 2 per level, and so do the
iteration counts. :func:`subdomain_grading` measures, per subdomain, its diameter over
its smallest cell; :func:`split_graded_subdomains` cuts every subdomain whose ratio
exceeds a bound into parts (``fem_py.partition.partition_cells`` on its cells only,
halving the part size until every part is below the bound, then merging neighbouring
parts back while their union stays below it), so the parts are graded like the mesh and
H/h stays bounded.

Measures (rank-independent, reduced by MIN / MAX over the ranks): the diameter of a
subdomain is the diagonal of its bounding box (between 1 and sqrt(2) times the true
diameter), the size of a cell its longest edge; for the square subdomains of a
structured mesh the ratio is d/h.

The split is the same for any number of ranks: the cells of a graded subdomain are sent
to one rank (the lowest holding some; with whole subdomains per rank, ``fem_py.mesh.distribute``,
its owner), which orders them canonically (nodes and cells by coordinates) before
splitting; part k of old subdomain s gets the id offset_s + k, offset_s the exclusive
prefix sum of the part counts over the old ids. Refined cells stay on their parent's
rank, so the new subdomains are again whole on one rank.
"""
from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.dofs.p1 import tag_array
from fem_py.partition.cells import cell_adjacency, partition_cells
from fem_py.partition.coarse import compute_coarse_structure

__all__ = ["subdomain_grading", "split_graded_subdomains", "split_cells"]

#: Depth limit of the recursive halving (a part of 4^depth pieces would be far finer
#: than any level refines in one step).
_MAX_DEPTH = 12


def _owned_cells(domain: Any) -> tuple[np.ndarray, np.ndarray]:
    """(corners (n, 3, 2), subdomain ids (n,)) of the owned cells of ``domain``."""
    msh = domain.mesh
    cells = msh.topology.index_map(2)
    n = cells.size_local
    corners = msh.geometry.dofmap.array.reshape(-1, 3)[:n]
    tags = tag_array(domain.cell_tags, n + cells.num_ghosts)[:n].astype(np.int64)
    return msh.geometry.x[:, :2][corners], tags


def _cell_sizes(p: np.ndarray) -> np.ndarray:
    """Longest edge of every triangle p (n, 3, 2)."""
    return np.max(np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2), axis=1)


def _ratio(p: np.ndarray) -> float:
    """Bounding-box diagonal over the smallest longest edge of the triangles p (n, 3, 2)."""
    flat = p.reshape(-1, 2)
    return float(np.linalg.norm(np.ptp(flat, axis=0)) / _cell_sizes(p).min())


def _boxes(p: np.ndarray, label: np.ndarray, n: int) -> tuple:
    """The bounding boxes (lo, hi: (n, 2)) and the smallest cell size (n,) of the parts
    0 .. n-1 of the triangles ``p`` (m, 3, 2) labelled ``label``."""
    lo = np.full((n, 2), np.inf)
    hi = np.full((n, 2), -np.inf)
    h_min = np.full(n, np.inf)
    for k in range(3):
        np.minimum.at(lo, label, p[:, k])
        np.maximum.at(hi, label, p[:, k])
    np.minimum.at(h_min, label, _cell_sizes(p))
    return lo, hi, h_min


def subdomain_grading(domain: Any) -> np.ndarray:
    """Diameter / smallest cell size of every subdomain of ``domain``, (L,) float, the
    same on every rank (collective). Diameter: bounding-box diagonal; cell size: longest
    edge (see the module docstring)."""
    comm = domain.comm
    p, tags = _owned_cells(domain)
    lo, hi, h_min = _boxes(p, tags, int(domain.coarse.n_subdomains))
    for array, op in ((lo, MPI.MIN), (hi, MPI.MAX), (h_min, MPI.MIN)):
        comm.Allreduce(MPI.IN_PLACE, array, op=op)
    return np.linalg.norm(hi - lo, axis=1) / h_min


def _canonical(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangles p (n, 3, 2) as a canonical mesh: (x, cells, order) with the nodes sorted
    by (rounded) coordinates, each cell's nodes increasing, and the cells sorted by their
    node numbers; cell i of the mesh is p[order[i]]. The result depends on the set of
    triangles only, not on their order."""
    flat = p.reshape(-1, 2)
    scale = float(np.max(np.ptp(flat, axis=0)))
    key = np.round((flat - flat.min(0)) / scale, 10)
    _, first, node = np.unique(key, axis=0, return_index=True, return_inverse=True)
    cells = np.sort(node.reshape(-1, 3), axis=1)
    order = np.lexsort((cells[:, 2], cells[:, 1], cells[:, 0]))
    return flat[first], cells[order], order


def split_cells(x: np.ndarray, cells: np.ndarray, max_ratio: float) -> np.ndarray:
    """Parts 0 .. m-1 of the triangles ``cells`` (node coordinates ``x``), each part of
    ratio (bounding-box diagonal / smallest longest edge) at most ``max_ratio`` where
    possible: a part above it is cut by ``partition_cells`` at half its size (sqrt of
    its area / 2, about four pieces), recursively; then neighbouring pieces are merged
    while their union stays within ``max_ratio`` (:func:`_merge_pieces`). Every part is
    connected and none is enclosed by one other part (``partition_cells``, and merges
    that would enclose one are skipped)."""
    x = np.asarray(x, dtype=float)[:, :2]
    cells = np.asarray(cells, dtype=np.int64)
    label = np.zeros(len(cells), dtype=np.int64)

    def split(idx: np.ndarray, depth: int, first: int) -> int:
        p = x[cells[idx]]
        if depth >= _MAX_DEPTH or len(idx) < 2 or _ratio(p) <= max_ratio:
            label[idx] = first
            return first + 1
        e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
        pieces = partition_cells(x, cells[idx], 0.5 * np.sqrt(area))
        if pieces.max() == 0:  # cells too coarse to cut further
            label[idx] = first
            return first + 1
        for k in range(int(pieces.max()) + 1):
            first = split(idx[pieces == k], depth + 1, first)
        return first

    split(np.arange(len(cells)), 0, 0)
    return _merge_pieces(x, cells, label, max_ratio)


def _merge_pieces(
    x: np.ndarray, cells: np.ndarray, label: np.ndarray, max_ratio: float
) -> np.ndarray:
    """Merge neighbouring pieces while their union stays within ``max_ratio``: the piece
    of smallest ratio first, into the neighbour it shares most facets with, unless that
    leaves a piece enclosed by a single other one (touching neither the outside nor a
    second piece); one merge at a time, until none is possible. Halving leaves pieces of
    a few coarse cells far from the fine end. The pieces' bounding boxes, smallest cells
    and shared facet counts (a dense matrix: a few dozen pieces) are updated in place."""
    a, b, outside = cell_adjacency(cells)
    p = x[cells]
    n = int(label.max()) + 1
    lo, hi, h_min = _boxes(p, label, n)
    cut = label[a] != label[b]
    shared = np.zeros((n, n), dtype=np.int64)
    np.add.at(shared, (label[a][cut], label[b][cut]), 1)
    shared += shared.T
    on_outside = np.bincount(label, outside, minlength=n) > 0
    while True:
        pair = _merge_pair(lo, hi, h_min, shared, on_outside, max_ratio)
        if pair is None:
            return label
        keep, gone = pair
        lo[keep] = np.minimum(lo[keep], lo[gone])
        hi[keep] = np.maximum(hi[keep], hi[gone])
        h_min[keep] = min(h_min[keep], h_min[gone])
        on_outside[keep] |= on_outside[gone]
        shared[keep] += shared[gone]
        shared[:, keep] += shared[:, gone]
        shared[keep, keep] = 0
        lo, hi, h_min, on_outside = (
            np.delete(v, gone, axis=0) for v in (lo, hi, h_min, on_outside)
        )
        shared = np.delete(np.delete(shared, gone, axis=0), gone, axis=1)
        label = np.where(label == gone, keep, label)
        label = np.where(label > gone, label - 1, label)


def _merge_pair(
    lo: np.ndarray,
    hi: np.ndarray,
    h_min: np.ndarray,
    shared: np.ndarray,
    on_outside: np.ndarray,
    max_ratio: float,
) -> tuple[int, int] | None:
    """The next merge of :func:`_merge_pieces` as (kept id, removed id), or None."""
    n = len(h_min)
    ratio = np.linalg.norm(hi - lo, axis=1) / h_min
    for u in np.lexsort((np.arange(n), ratio)):
        nbrs = np.flatnonzero(shared[u])
        for v in nbrs[np.lexsort((nbrs, -shared[u, nbrs]))]:
            union = np.linalg.norm(np.maximum(hi[u], hi[v]) - np.minimum(lo[u], lo[v]))
            if union / min(h_min[u], h_min[v]) > max_ratio:
                continue
            if _encloses(shared, on_outside, u, v):
                continue
            return int(min(u, v)), int(max(u, v))
    return None


def _encloses(shared: np.ndarray, on_outside: np.ndarray, u: int, v: int) -> bool:
    """Whether merging pieces u and v leaves a neighbour enclosed by the union alone."""
    for z in set(np.flatnonzero(shared[u] + shared[v]).tolist()) - {u, v}:
        others = set(np.flatnonzero(shared[z]).tolist()) - {u, v}
        if not others and not on_outside[z]:
            return True
    return False


def split_graded_subdomains(domain: Any, max_ratio: float, corner_angle: float) -> Any:
    """``domain`` with every subdomain of :func:`subdomain_grading` above ``max_ratio``
    split by :func:`split_cells` (collective).

    Returns ``domain`` itself when no subdomain is above the bound, else a new Domain
    with the new cell tags (ids 0 .. L'-1, see the module docstring), the coarse
    structure recomputed with ``corner_angle`` (the interfaces of the parts zigzag along
    the cells: ``compute_coarse_structure``) and ``partition = "cells"``.
    """
    comm = domain.comm
    graded = subdomain_grading(domain) > max_ratio
    if not graded.any():
        return domain
    n_sub = len(graded)
    p, tags = _owned_cells(domain)
    present = np.full(n_sub, comm.size, dtype=np.int64)
    present[np.unique(tags)] = comm.rank
    comm.Allreduce(MPI.IN_PLACE, present, op=MPI.MIN)
    holder = present  # the lowest rank holding cells of s
    mine = np.flatnonzero(graded[tags])
    dest = holder[tags[mine]]
    sends = [mine[dest == r] for r in range(comm.size)]
    received = comm.alltoall([(tags[c], p[c]) for c in sends])

    parts = np.zeros(n_sub, dtype=np.int64)
    labels_in = [np.zeros(len(t), dtype=np.int64) for t, _ in received]
    for s in np.flatnonzero(graded & (holder == comm.rank)):
        pieces = [(r, np.flatnonzero(t == s)) for r, (t, _) in enumerate(received)]
        tri = np.concatenate([received[r][1][i] for r, i in pieces])
        x, cells, order = _canonical(tri)
        label = np.empty(len(tri), dtype=np.int64)
        label[order] = split_cells(x, cells, max_ratio)
        parts[s] = int(label.max()) + 1
        start = 0
        for r, i in pieces:
            labels_in[r][i] = label[start : start + len(i)]
            start += len(i)
    comm.Allreduce(MPI.IN_PLACE, parts, op=MPI.SUM)
    parts[~graded] = 1
    offset = np.concatenate([[0], np.cumsum(parts)[:-1]])
    new = offset[tags]
    for r, lab in enumerate(comm.alltoall(labels_in)):
        new[sends[r]] += lab
    ct = _with_ghosts(domain.mesh, new)
    return dataclasses.replace(
        domain,
        cell_tags=ct,
        coarse=compute_coarse_structure(domain.mesh, ct, domain.facet_tags, corner_angle),
        partition="cells",
    )


def _with_ghosts(msh: Any, owned: np.ndarray) -> Any:
    """Cell tags of every local cell (owned, then ghosts) from the values ``owned`` of the
    owned cells, the ghosts' values from their owners (a DG0 scatter)."""
    V0 = fem.FunctionSpace(msh, ("DG", 0))
    n = msh.topology.index_map(2).size_local
    n_all = n + msh.topology.index_map(2).num_ghosts
    dof = V0.dofmap.list.array.reshape(-1)[:n_all]
    f = fem.Function(V0)
    f.x.array[dof[:n]] = owned
    f.x.scatter_forward()
    values = np.rint(f.x.array[dof]).astype(np.int32)
    ct = dmesh.meshtags(msh, 2, np.arange(n_all, dtype=np.int32), values)
    ct.name = "subdomains"
    return ct
