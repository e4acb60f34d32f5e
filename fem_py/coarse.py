"""The coarse partition of Omega as the fine mesh sees it (METHOD.md section 6).

``compute_coarse_structure`` recovers, from the distributed DOLFINx mesh and its
subdomain cell tags, the skeleton (subdomain boundaries, Gamma included), the coarse
vertices and the coarse edges as chains of fine P1 dofs: the data the substructuring
preconditioner needs. It is computed from the mesh itself, so it is right whatever
mesh generator made the mesh.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from scipy.sparse.csgraph import connected_components

from fem_py.forms import p1_space
from fem_py.meshdata import FacetData, exterior_facets, facet_data, gather_facet_data, p1_topology, tag_array

__all__ = ["CoarseStructure", "compute_coarse_structure", "SIGNORINI_TAG0"]

#: Facet tag of the first Signorini arc (arc k has tag SIGNORINI_TAG0 + k).
SIGNORINI_TAG0 = 100
_COLLINEAR_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class CoarseStructure:
    """The coarse partition as seen by the fine mesh (identical on every rank).

    Dof numbers are global dofs of ``fem_py.forms.p1_space(mesh)``.

    Attributes
    ----------
    vertex_coords : (n_v, 2) float
        Coarse vertices (subdomain corners, arc end points), sorted by (y, x).
    vertex_dofs : (n_v,) int64
    vertex_on_boundary : (n_v,) bool
    edge_vertices : (n_e, 2) int
        Coarse vertex indices of the edge ends. Boundary edges run counter-clockwise along
        Gamma; interior edges from the lower to the higher vertex index.
    edge_dofs : tuple of n_e int64 arrays
        Dofs of the fine nodes along each edge from end 0 to end 1, ends included.
    edge_coords : tuple of n_e (m, 2) float arrays
        Coordinates of those nodes.
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
    edge_dofs: tuple
    edge_coords: tuple
    edge_on_boundary: np.ndarray
    edge_arc: np.ndarray
    edge_subdomains: np.ndarray
    skeleton_dofs: np.ndarray
    interior_dofs: np.ndarray
    subdomain_of_interior_dof: np.ndarray
    n_subdomains: int
    n_dofs: int
    n_skeleton_facets: int

    @property
    def n_vertices(self) -> int:
        return len(self.vertex_coords)

    @property
    def n_edges(self) -> int:
        return len(self.edge_vertices)

    def edge_segments(self) -> np.ndarray:
        """Number of fine segments on each coarse edge."""
        return np.array([len(d) - 1 for d in self.edge_dofs], dtype=np.int64)


def compute_coarse_structure(msh: Any, cell_tags: Any, facet_tags: Any) -> CoarseStructure:
    """Recover the coarse partition from the distributed mesh (collective).

    Skeleton facets are the exterior facets and the facets whose two cells carry
    different subdomain tags. On rank 0 the skeleton graph is built from global P1 dof
    pairs; coarse vertices are the skeleton nodes of degree != 2, or where the two
    skeleton facets are not collinear, or where the exterior facet tag changes (arc
    ends). Chains between coarse vertices are the coarse edges. The result is broadcast.
    """
    comm = msh.comm
    V = p1_space(msh)
    topo = p1_topology(V)
    tdim = msh.topology.dim
    n_cells = msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts
    n_facets = msh.topology.index_map(tdim - 1).size_local + msh.topology.index_map(tdim - 1).num_ghosts
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
    gathered = comm.gather((topo.local_to_global(owned), dof_tag[owned]), root=0)
    n_dofs = V.dofmap.index_map.size_global
    n_sub = comm.allreduce(int(ctag.max(initial=-1)) + 1, op=MPI.MAX)
    result = None
    error = None
    if comm.rank == 0:
        try:
            tag_global = np.full(n_dofs, -1, dtype=np.int32)
            for g, t in gathered:
                tag_global[g] = t
            result = _coarse_from_skeleton(fd, tag_global, n_dofs, n_sub)
        except Exception as err:  # report on every rank instead of deadlocking
            error = f"{type(err).__name__}: {err}"
    error = comm.bcast(error, root=0)
    if error is not None:
        raise RuntimeError(f"coarse structure: {error}")
    if comm.size == 1:
        return result
    return _unpack(comm.bcast(_pack(result) if comm.rank == 0 else None, root=0))


def _pack(coarse: CoarseStructure) -> dict:
    """The fields as a few large arrays (the per-edge tuples concatenated): one pickle of
    ~30 arrays instead of ~2 per coarse edge, which made the broadcast slow (1e5 edges)."""
    fields = {name: getattr(coarse, name) for name in coarse.__dataclass_fields__}
    fields["edge_dofs"] = np.concatenate(coarse.edge_dofs) if coarse.edge_dofs else np.zeros(0, np.int64)
    fields["edge_coords"] = (np.concatenate(coarse.edge_coords) if coarse.edge_coords
                             else np.zeros((0, 2)))
    fields["edge_lengths"] = np.array([len(d) for d in coarse.edge_dofs], dtype=np.int64)
    return fields


def _unpack(fields: dict) -> CoarseStructure:
    cut = np.cumsum(fields.pop("edge_lengths"))[:-1]
    fields["edge_dofs"] = tuple(np.split(fields["edge_dofs"], cut))
    fields["edge_coords"] = tuple(np.split(fields["edge_coords"], cut))
    return CoarseStructure(**fields)


def _coarse_from_skeleton(fd: FacetData, tag_global: np.ndarray, n_dofs: int, n_sub: int) -> CoarseStructure:
    nodes, inv = np.unique(fd.dofs, return_inverse=True)
    inv = inv.reshape(-1, 2)
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
        u, w = X[i2] - X[a], X[b] - X[i2]
        cross = np.abs(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0])
        bent = (cross > _COLLINEAR_TOL * np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1)) \
            | ((u * w).sum(1) <= 0)
        tag_change = (fd.exterior[f] != fd.exterior[g]) | (fd.exterior[f] & (fd.tag[f] != fd.tag[g]))
        is_vertex[i2[bent | tag_change]] = True
    vidx = np.flatnonzero(is_vertex)
    # sort keys rounded far above round-off, so that coordinate noise (gmsh leaves ~1e-18
    # instead of 0) cannot reorder vertices between runs
    scale = float(np.ptp(X, axis=0).max())
    K = np.round(X / scale, 9)
    order = np.lexsort((K[vidx, 0], K[vidx, 1]))  # sort by y, then x
    vidx = vidx[order]
    vnum = -np.ones(nn, dtype=np.int64)
    vnum[vidx] = np.arange(len(vidx))
    # coarse edges: the facets joined at the non-vertex nodes (connected components)
    join = ~is_vertex[i2]
    graph = sp.csr_matrix((np.ones(int(join.sum())), (f[join], g[join])), shape=(nf, nf))
    n_edges, comp = connected_components(graph, directed=False)
    vertex_end = is_vertex[inv]  # (nf, 2)
    ends_per_edge = np.bincount(np.repeat(comp, 2)[vertex_end.ravel()], minlength=n_edges)
    if np.any(ends_per_edge != 2):
        raise RuntimeError(f"{int(np.count_nonzero(ends_per_edge != 2))} chains of skeleton facets do "
                           "not run between two coarse vertices (closed loops without coarse vertices)")
    end_comp, end_nodes = np.repeat(comp, 2)[vertex_end.ravel()], end_node[vertex_end.ravel()]
    pair = np.argsort(end_comp, kind="stable").reshape(-1, 2)
    e0, e1 = end_nodes[pair[:, 0]], end_nodes[pair[:, 1]]
    # a coarse edge is straight (a bend makes a coarse vertex): order its nodes by position
    first_facet = np.full(n_edges, nf)
    np.minimum.at(first_facet, comp, np.arange(nf))
    ext = fd.exterior[first_facet]
    along = X[e1] - X[e0]
    facet_dir = X[inv[first_facet, 1]] - X[inv[first_facet, 0]]
    reverse = np.where(ext, (facet_dir * along).sum(1) < 0, vnum[e0] > vnum[e1])
    start, stop = np.where(reverse, e1, e0), np.where(reverse, e0, e1)
    node_comp = np.unique(np.stack([np.repeat(comp, 2), end_node], 1), axis=0)  # (edge, node)
    c, nd = node_comp[:, 0], node_comp[:, 1]
    position = ((X[nd] - X[start[c]]) * (X[stop[c]] - X[start[c]])).sum(1)
    chain_nodes = nd[np.lexsort((position, c))]
    length = np.bincount(c, minlength=n_edges)
    offsets = np.concatenate([[0], np.cumsum(length)])
    if np.any(fd.exterior & (fd.tag != fd.tag[first_facet][comp])):
        raise RuntimeError("a coarse boundary edge carries two facet tags")
    ftag = fd.tag[first_facet]
    arc = np.where(ext & (ftag >= SIGNORINI_TAG0), ftag - SIGNORINI_TAG0, -1)
    cells = fd.cells[first_facet]
    sub = np.where(ext[:, None], np.stack([cells[:, 0], np.full(n_edges, -1)], 1), np.sort(cells, axis=1))
    ev = np.stack([vnum[start], vnum[stop]], 1)
    mid = K[chain_nodes[offsets[:-1] + length // 2]]
    eorder = np.lexsort((mid[:, 0], mid[:, 1], ev.max(1), ev.min(1)))
    ev = ev[eorder]
    chains = [chain_nodes[offsets[k]:offsets[k + 1]] for k in eorder.tolist()]
    skeleton = np.sort(nodes)
    interior = np.setdiff1d(np.arange(n_dofs, dtype=np.int64), skeleton)
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
        edge_dofs=tuple(nodes[ch].astype(np.int64) for ch in chains),
        edge_coords=tuple(X[ch] for ch in chains),
        edge_on_boundary=ext[eorder].astype(bool),
        edge_arc=arc[eorder].astype(np.int64),
        edge_subdomains=sub[eorder].astype(np.int64).reshape(-1, 2),
        skeleton_dofs=skeleton.astype(np.int64),
        interior_dofs=interior,
        subdomain_of_interior_dof=sub_of_interior.astype(np.int64),
        n_subdomains=int(n_sub),
        n_dofs=int(n_dofs),
        n_skeleton_facets=int(nf),
    )


# ================================================================= entry point
