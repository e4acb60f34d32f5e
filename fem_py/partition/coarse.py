"""The coarse partition of Omega as the fine mesh sees it (docs/method.md section 6).

``compute_coarse_structure`` recovers, from the distributed DOLFINx mesh and its
subdomain cell tags, the skeleton (subdomain boundaries, Gamma included), the coarse
vertices and the coarse edges as chains of fine P1 dofs: the data the substructuring
preconditioner needs. It is computed from the mesh itself, so it is right whatever
mesh generator made the mesh.

The chains are stored as :class:`fem_py.partition.ragged.Ragged` arrays (one flat array
and offsets). The result is computed on rank 0 and broadcast (``fem_py.parallel``). This
module imports DOLFINx lazily (in :func:`compute_coarse_structure`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from scipy.sparse.csgraph import connected_components

from fem_py.parallel import broadcast_from_root, gather_to_root, run_on_root
from fem_py.partition.chains import mark_closed_chains, walk_chains
from fem_py.partition.ragged import Ragged, as_ragged
from fem_py.tags import SIGNORINI_TAG0

if TYPE_CHECKING:
    from fem_py.dofs.p1 import FacetData

__all__ = ["CoarseStructure", "compute_coarse_structure"]

_COLLINEAR_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class CoarseStructure:
    """The coarse partition as seen by the fine mesh (identical on every rank).

    Dof numbers are global dofs of ``fem_py.dofs.p1_space(mesh)``.

    Attributes
    ----------
    vertex_coords : (n_v, 2) float
        Coarse vertices (subdomain corners, arc end points), sorted by (y, x).
    vertex_dofs : (n_v,) int64
    vertex_on_boundary : (n_v,) bool
    edge_vertices : (n_e, 2) int
        Coarse vertex indices of the edge ends. Boundary edges run counter-clockwise along
        Gamma; interior edges from the lower to the higher vertex index.
    edge_dofs : Ragged of n_e int64 rows
        Dofs of the fine nodes along each edge from end 0 to end 1, ends included
        (``edge_dofs[k]`` is an (m_k,) array). A sequence of arrays given here is
        converted with :func:`as_ragged`.
    edge_coords : Ragged of n_e (m_k, 2) float rows
        Coordinates of those nodes (same offsets as ``edge_dofs``).
    edge_on_boundary : (n_e,) bool
    edge_arc : (n_e,) int
        k if the edge lies in the k-th Signorini arc, -1 otherwise.
    edge_subdomains : (n_e, 2) int
        Subdomain ids on both sides (-1 for the exterior side of a boundary edge).
    skeleton_dofs : sorted int64
        Dofs on the union of the subdomain boundaries (Gamma included).
    interior_dofs : sorted int64
        All other dofs.
    subdomain_of_interior_dof : int, aligned with ``interior_dofs``
    n_subdomains : int
    n_dofs : int
        Global number of P1 dofs.
    n_skeleton_facets : int
        Number of fine facets on the skeleton.
    """

    vertex_coords: np.ndarray
    vertex_dofs: np.ndarray
    vertex_on_boundary: np.ndarray
    edge_vertices: np.ndarray
    edge_dofs: Ragged
    edge_coords: Ragged
    edge_on_boundary: np.ndarray
    edge_arc: np.ndarray
    edge_subdomains: np.ndarray
    skeleton_dofs: np.ndarray
    interior_dofs: np.ndarray
    subdomain_of_interior_dof: np.ndarray
    n_subdomains: int
    n_dofs: int
    n_skeleton_facets: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "edge_dofs", as_ragged(self.edge_dofs, dtype=np.int64))
        object.__setattr__(
            self, "edge_coords", as_ragged(self.edge_coords, dtype=np.float64, item_shape=(2,))
        )

    @property
    def n_vertices(self) -> int:
        return len(self.vertex_coords)

    @property
    def n_edges(self) -> int:
        return len(self.edge_vertices)

    def edge_segments(self) -> np.ndarray:
        """Number of fine segments on each coarse edge, (n_e,) int64."""
        return self.edge_dofs.lengths - 1


def compute_coarse_structure(
    msh: Any, cell_tags: Any, facet_tags: Any, corner_angle: float | None = None
) -> CoarseStructure:
    """Recover the coarse partition from the distributed mesh (collective).

    Skeleton facets are the exterior facets and the facets whose two cells carry
    different subdomain tags. On rank 0 the skeleton graph is built from global P1 dof
    pairs; coarse vertices are the skeleton nodes of degree != 2, or where the two
    skeleton facets are not collinear, or where the exterior facet tag changes (arc
    ends). Chains between coarse vertices are the coarse edges. The result is broadcast.

    ``corner_angle`` (radians) is for curved coarse edges (subdomains of an automatic
    partition, ``fem_py.partition``, curved boundaries): a bend makes a coarse vertex
    only on Gamma and only where it turns by more than ``corner_angle``; interfaces
    between subdomains may zigzag, their chains are ordered by walking them, and a
    closed chain without a coarse vertex gets two. None: the straight edges above.
    """
    from fem_py.dofs.p1 import p1_space
    from fem_py.dofs.p1 import (
        exterior_facets,
        facet_data,
        gather_facet_data,
        p1_topology,
        tag_array,
    )

    comm = msh.comm
    V = p1_space(msh)
    topo = p1_topology(V)
    tdim = msh.topology.dim
    n_cells = msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts
    n_facets = (
        msh.topology.index_map(tdim - 1).size_local + msh.topology.index_map(tdim - 1).num_ghosts
    )
    ctag = tag_array(cell_tags, n_cells)
    ftag = tag_array(facet_tags, n_facets, default=0)
    ext = exterior_facets(msh)
    ncell = np.diff(topo.f2c_offsets)
    two = np.flatnonzero(ncell == 2)
    c0 = topo.f2c_array[topo.f2c_offsets[two]]
    c1 = topo.f2c_array[topo.f2c_offsets[two] + 1]
    iface = two[(ctag[c0] != ctag[c1]) & (ctag[c0] >= 0) & (ctag[c1] >= 0)]
    parts = [facet_data(topo, ext, ftag, ctag, True), facet_data(topo, iface, ftag, ctag, False)]
    fd = gather_facet_data(comm, parts)
    # subdomain of every owned dof (any cell containing it; unique for interior dofs)
    dof_tag = np.full(topo.dof_coords.shape[0], -1, dtype=np.int32)
    dof_tag[topo.dofmap.ravel()] = np.repeat(ctag[: topo.dofmap.shape[0]], 3)
    owned = np.arange(topo.n_owned_dofs)
    gathered = gather_to_root(comm, (topo.local_to_global(owned), dof_tag[owned]))
    n_dofs = V.dofmap.index_map.size_global
    n_sub = comm.allreduce(int(ctag.max(initial=-1)) + 1, op=MPI.MAX)

    def on_root() -> CoarseStructure:
        tag_global = np.full(n_dofs, -1, dtype=np.int32)
        for g, t in gathered:
            tag_global[g] = t
        return _coarse_from_skeleton(fd, tag_global, n_dofs, n_sub, corner_angle)

    if comm.size == 1:
        return run_on_root(comm, on_root, error_prefix="coarse structure")
    return _unpack(
        broadcast_from_root(comm, lambda: _pack(on_root()), error_prefix="coarse structure")
    )


def _pack(coarse: CoarseStructure) -> dict:
    """The fields as a few large arrays (the ragged rows as flat arrays + offsets): one
    pickle of ~30 arrays, whatever the number of coarse edges."""
    fields = {name: getattr(coarse, name) for name in coarse.__dataclass_fields__}
    fields["edge_dofs"] = coarse.edge_dofs.flat
    fields["edge_coords"] = coarse.edge_coords.flat
    fields["edge_offsets"] = coarse.edge_dofs.offsets
    return fields


def _unpack(fields: dict) -> CoarseStructure:
    offsets = fields.pop("edge_offsets")
    fields["edge_dofs"] = Ragged(fields["edge_dofs"], offsets)
    fields["edge_coords"] = Ragged(fields["edge_coords"], offsets)
    return CoarseStructure(**fields)


def _coarse_from_skeleton(
    fd: FacetData,
    tag_global: np.ndarray,
    n_dofs: int,
    n_sub: int,
    corner_angle: float | None = None,
) -> CoarseStructure:
    # skeleton nodes = the dofs on skeleton facets, sorted (a mark array of n_dofs
    # instead of np.unique: no sort)
    on_skeleton = np.zeros(n_dofs, dtype=bool)
    on_skeleton[fd.dofs.ravel()] = True
    nodes = np.flatnonzero(on_skeleton)
    node_of_dof = np.full(n_dofs, -1, dtype=np.intp)
    node_of_dof[nodes] = np.arange(len(nodes))
    inv = node_of_dof[fd.dofs]
    nn, nf = len(nodes), len(inv)
    X = np.zeros((nn, 2))
    X[inv[:, 0]] = fd.coords[:, 0]
    X[inv[:, 1]] = fd.coords[:, 1]
    # incident facets of every node, in increasing facet order
    end_node = inv.ravel()
    by_node = np.argsort(end_node, kind="stable")
    incident = by_node // 2
    deg = np.bincount(end_node, minlength=nn)
    first = np.concatenate([[0], np.cumsum(deg)[:-1]])
    is_vertex = deg != 2
    i2 = np.flatnonzero(deg == 2)
    f, g = incident[first[i2]], incident[first[i2] + 1]
    if len(i2):
        a = np.where(inv[f, 1] == i2, inv[f, 0], inv[f, 1])
        b = np.where(inv[g, 1] == i2, inv[g, 0], inv[g, 1])
        Xi = X.take(i2, axis=0)  # take: faster than X[i2] for (n, 2) rows (docs/design/fem_py.md)
        u, w = Xi - X.take(a, axis=0), X.take(b, axis=0) - Xi
        cross = np.abs(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0])
        if corner_angle is None:
            bent = (
                cross > _COLLINEAR_TOL * np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1)
            ) | ((u * w).sum(1) <= 0)
        else:  # corners of Gamma only
            turn = np.arctan2(cross, (u * w).sum(1))
            bent = fd.exterior[f] & fd.exterior[g] & (turn > corner_angle)
        tag_change = (fd.exterior[f] != fd.exterior[g]) | (
            fd.exterior[f] & (fd.tag[f] != fd.tag[g])
        )
        is_vertex[i2[bent | tag_change]] = True
    if corner_angle is not None:
        mark_closed_chains(inv, incident, first, i2, f, g, is_vertex)
    vidx = np.flatnonzero(is_vertex)
    # sort keys rounded far above round-off, so that coordinate noise (gmsh leaves ~1e-18
    # instead of 0) cannot reorder vertices between runs
    scale = float(max(np.ptp(X[:, 0]), np.ptp(X[:, 1])))
    K = np.round(X / scale, 9)
    order = np.lexsort((K[vidx, 0], K[vidx, 1]))  # sort by y, then x
    vidx = vidx[order]
    vnum = -np.ones(nn, dtype=np.int64)
    vnum[vidx] = np.arange(len(vidx))
    # coarse edges: the facets joined at the non-vertex nodes (connected components)
    join = ~is_vertex[i2]
    graph = sp.csr_matrix((np.ones(int(join.sum())), (f[join], g[join])), shape=(nf, nf))
    n_edges, comp = connected_components(graph, directed=False)
    comp2 = np.repeat(comp, 2)
    vertex_end = is_vertex[inv].ravel()  # (2 nf,)
    end_comp, end_nodes = comp2[vertex_end], end_node[vertex_end]
    ends_per_edge = np.bincount(end_comp, minlength=n_edges)
    if np.any(ends_per_edge != 2):
        raise RuntimeError(
            f"{int(np.count_nonzero(ends_per_edge != 2))} chains of skeleton facets do "
            "not run between two coarse vertices (closed loops without coarse vertices)"
        )
    pair = np.argsort(end_comp, kind="stable").reshape(-1, 2)
    e0, e1 = end_nodes[pair[:, 0]], end_nodes[pair[:, 1]]
    # a coarse edge is straight (a bend makes a coarse vertex): order its nodes by position
    first_facet = _first_index(comp, n_edges)
    ext = fd.exterior[first_facet]
    along = X[e1] - X[e0]
    facet_dir = X[inv[first_facet, 1]] - X[inv[first_facet, 0]]
    reverse = np.where(ext, (facet_dir * along).sum(1) < 0, vnum[e0] > vnum[e1])
    start, stop = np.where(reverse, e1, e0), np.where(reverse, e0, e1)
    # the (edge, node) pairs sorted by edge then node, as one int64 key (nn * n_edges < 2^63):
    # a non-vertex node lies on one edge only (that of its two facets), plus the edge ends
    inner = i2[join]
    key = np.unique(
        np.concatenate(
            [
                comp[f[join]].astype(np.int64) * nn + inner,
                end_comp.astype(np.int64) * nn + end_nodes,
            ]
        )
    )
    c, nd = np.divmod(key, nn)
    chord = (X[stop] - X[start]).take(c, axis=0)
    offset = X.take(nd, axis=0) - X[start].take(c, axis=0)
    position = offset[:, 0] * chord[:, 0] + offset[:, 1] * chord[:, 1]
    length = np.bincount(c, minlength=n_edges)
    offsets = np.concatenate([[0], np.cumsum(length)])
    if corner_angle is None:
        chain_nodes = _sort_rows(Ragged(nd, offsets), position)
    else:  # curved chains: walk them from their start
        start, stop, rows = walk_chains(
            inv, incident, first, is_vertex, comp, fd.exterior, start, stop, vnum
        )
        chain_nodes = as_ragged(rows, dtype=np.int64)
        offsets, length = chain_nodes.offsets, chain_nodes.lengths
    if np.any(fd.exterior & (fd.tag != fd.tag[first_facet][comp])):
        raise RuntimeError("a coarse boundary edge carries two facet tags")
    ftag = fd.tag[first_facet]
    arc = np.where(ext & (ftag >= SIGNORINI_TAG0), ftag - SIGNORINI_TAG0, -1)
    cells = fd.cells[first_facet]
    sub = np.where(
        ext[:, None], np.stack([cells[:, 0], np.full(n_edges, -1)], 1), np.sort(cells, axis=1)
    )
    ev = np.stack([vnum[start], vnum[stop]], 1)
    mid = K[chain_nodes.flat[offsets[:-1] + length // 2]]
    eorder = np.lexsort((mid[:, 0], mid[:, 1], ev.max(1), ev.min(1)))
    ev = ev[eorder]
    chains = chain_nodes.take(eorder)
    interior = np.flatnonzero(~on_skeleton).astype(np.int64, copy=False)
    sub_of_interior = tag_global[interior]
    if (sub_of_interior < 0).any():
        raise RuntimeError("some interior dofs have no subdomain tag")
    on_bnd = np.zeros(nn, dtype=bool)
    on_bnd[inv[fd.exterior].ravel()] = True
    return CoarseStructure(
        vertex_coords=X[vidx],
        vertex_dofs=nodes[vidx].astype(np.int64),
        vertex_on_boundary=on_bnd[vidx],
        edge_vertices=ev,
        edge_dofs=Ragged(nodes[chains.flat].astype(np.int64, copy=False), chains.offsets),
        edge_coords=Ragged(X.take(chains.flat, axis=0), chains.offsets),
        edge_on_boundary=ext[eorder].astype(bool),
        edge_arc=arc[eorder].astype(np.int64),
        edge_subdomains=sub[eorder].astype(np.int64).reshape(-1, 2),
        skeleton_dofs=nodes.astype(np.int64),
        interior_dofs=interior,
        subdomain_of_interior_dof=sub_of_interior.astype(np.int64),
        n_subdomains=int(n_sub),
        n_dofs=int(n_dofs),
        n_skeleton_facets=int(nf),
    )


def _first_index(labels: np.ndarray, n: int) -> np.ndarray:
    """The first index of each label 0..n-1 in ``labels`` (each label present).

    ``connected_components`` numbers the components in order of first appearance, so
    the first indices are where the running maximum rises; that is checked, with
    ``np.minimum.at`` as the general fallback.
    """
    rise = np.flatnonzero(np.diff(np.maximum.accumulate(labels), prepend=-1) > 0)
    if len(rise) == n and np.array_equal(labels[rise], np.arange(n)):
        return rise
    first = np.full(n, len(labels))
    np.minimum.at(first, labels, np.arange(len(labels)))
    return first


def _sort_rows(rows: Ragged, key: np.ndarray) -> Ragged:
    """Each row of ``rows`` stably sorted by ``key`` (aligned with ``rows.flat``).

    Equals ``flat[np.lexsort((key, row_of_entry))]``: one batched argsort per row length.
    """
    flat = rows.flat.copy()
    for length, group in rows.length_groups():
        start = rows.offsets[group][:, None]
        index = start + np.arange(length)
        flat[index] = rows.flat[start + np.argsort(key[index], axis=1, kind="stable")]
    return Ragged(flat, rows.offsets)


# ================================================================= entry point
