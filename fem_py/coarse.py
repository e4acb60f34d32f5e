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
from mpi4py import MPI

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
    return comm.bcast(result, root=0)


def _coarse_from_skeleton(fd: FacetData, tag_global: np.ndarray, n_dofs: int, n_sub: int) -> CoarseStructure:
    nodes, inv = np.unique(fd.dofs, return_inverse=True)
    inv = inv.reshape(-1, 2)
    nn, nf = len(nodes), len(inv)
    X = np.zeros((nn, 2))
    X[inv[:, 0]] = fd.coords[:, 0]
    X[inv[:, 1]] = fd.coords[:, 1]
    # adjacency lists: node -> incident facets
    inc: list[list[int]] = [[] for _ in range(nn)]
    for f, (a, b) in enumerate(inv.tolist()):
        inc[a].append(f)
        inc[b].append(f)
    deg = np.array([len(x) for x in inc])
    is_vertex = deg != 2
    i2 = np.flatnonzero(deg == 2)
    if len(i2):
        fg = np.array([inc[i] for i in i2.tolist()], dtype=np.int64)
        f, g = fg[:, 0], fg[:, 1]
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
    visited = np.zeros(nf, dtype=bool)
    edges = []
    for v in vidx.tolist():
        for f0 in inc[v]:
            if visited[f0]:
                continue
            chain, facets = [v], []
            cur, f = v, f0
            while True:
                visited[f] = True
                facets.append(f)
                nxt = int(inv[f, 0] if inv[f, 1] == cur else inv[f, 1])
                chain.append(nxt)
                if is_vertex[nxt]:
                    break
                g = inc[nxt][0] if inc[nxt][0] != f else inc[nxt][1]
                cur, f = nxt, g
            edges.append((chain, facets))
    if not visited.all():
        raise RuntimeError(f"{int((~visited).sum())} skeleton facets form closed loops without coarse vertices")
    records = []
    for chain, facets in edges:
        f0 = facets[0]
        ext = bool(fd.exterior[f0])
        tags = fd.tag[facets]
        if ext and not np.all(tags == tags[0]):
            raise RuntimeError("a coarse boundary edge carries two facet tags")
        a, b = vnum[chain[0]], vnum[chain[-1]]
        if ext:
            forward = inv[f0, 0] == chain[0] and inv[f0, 1] == chain[1]  # exterior facets are CCW
            if not forward:
                chain = chain[::-1]
        elif a > b:
            chain = chain[::-1]
        arc = int(tags[0]) - SIGNORINI_TAG0 if ext and tags[0] >= SIGNORINI_TAG0 else -1
        cells = fd.cells[f0]
        sub = (int(cells[0]), -1) if ext else tuple(sorted((int(cells[0]), int(cells[1]))))
        records.append((chain, ext, arc, sub))
    ev = np.array([[vnum[r[0][0]], vnum[r[0][-1]]] for r in records], dtype=np.int64).reshape(-1, 2)
    mid = np.array([K[r[0][len(r[0]) // 2]] for r in records]).reshape(-1, 2)
    eorder = np.lexsort((mid[:, 0], mid[:, 1], ev.max(1), ev.min(1)))
    records = [records[i] for i in eorder]
    ev = ev[eorder]
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
        edge_dofs=tuple(nodes[np.array(r[0])].astype(np.int64) for r in records),
        edge_coords=tuple(X[np.array(r[0])] for r in records),
        edge_on_boundary=np.array([r[1] for r in records], dtype=bool),
        edge_arc=np.array([r[2] for r in records], dtype=np.int64),
        edge_subdomains=np.array([r[3] for r in records], dtype=np.int64).reshape(-1, 2),
        skeleton_dofs=skeleton.astype(np.int64),
        interior_dofs=interior,
        subdomain_of_interior_dof=sub_of_interior.astype(np.int64),
        n_subdomains=int(n_sub),
        n_dofs=int(n_dofs),
        n_skeleton_facets=int(nf),
    )


# ================================================================= entry point
