"""The P1 space of a distributed mesh (created here only), its dof topology and facet data.

Vertex, geometry-node and dof indices differ in DOLFINx 0.5.2 (they only coincide in
serial by chance), so everything here goes through the P1 dofmap:
``v2dof[c2v[c]] = dofmap[c]``. Facet data are gathered to rank 0 as global P1 dof
pairs with coordinates, which makes the result independent of the partition.
"""
from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np
from dolfinx import fem
from dolfinx import mesh as dmesh

from fem_py.parallel import gather_to_root

__all__ = [
    "p1_space",
    "quiet_jit",
    "P1Topology",
    "p1_topology",
    "FacetData",
    "facet_data",
    "gather_facet_data",
    "tag_array",
]


@contextlib.contextmanager
def quiet_jit() -> Iterator[None]:
    """Silence the INFO lines of cold FFCx/CFFI compiles for the duration of the block.

    distutils raises the root logger to INFO and ffcx installs a root handler, so cold
    compiles print gcc command lines. The handler levels are raised to WARNING and
    restored afterwards (no lasting change of the global logging state).
    """
    handlers = list(logging.getLogger().handlers)
    saved = [h.level for h in handlers]
    try:
        for h in handlers:
            h.setLevel(max(h.level, logging.WARNING))
        yield
    finally:
        for h, lvl in zip(handlers, saved):
            h.setLevel(lvl)


def p1_space(mesh: Any, components: int = 1) -> fem.FunctionSpace:
    """The continuous P1 space V_h(Omega) on ``mesh`` (the single place it is created), or
    with ``components`` = d its vector twin V_h(Omega)^d (elasticity, docs/method.md
    section 12): blocked, the dof of component c at node k is d k + c.

    The dofmap construction is deterministic, so every call on the same mesh gives the
    same global dof numbering (CoarseStructure and BoundaryMap rely on this; checked
    in parallel by tests/test_fem_mpi.py); the vector space's nodes are numbered as the
    scalar space's dofs (tests/test_elastic_forms.py), so that one boundary map serves both.
    """
    with quiet_jit():
        if components == 1:
            return fem.FunctionSpace(mesh, ("Lagrange", 1))
        return fem.VectorFunctionSpace(mesh, ("Lagrange", 1), dim=components)


@dataclass
class P1Topology:
    """Rank-local P1 topology: vertex -> dof maps, facet/cell connectivity, coordinates."""

    v2dof: np.ndarray  # (n_vertices_local,) local dof of each local vertex
    f2v: np.ndarray  # (n_facets_local, 2) local vertices of each facet
    c2v: np.ndarray  # (n_cells_local, 3) local vertices of each cell
    f2c_offsets: np.ndarray  # offsets of facet -> cell adjacency
    f2c_array: np.ndarray  # data of facet -> cell adjacency
    dof_coords: np.ndarray  # (n_dofs_local, 2) coordinates of local dofs (owned then ghost)
    dofmap: np.ndarray  # (n_cells_local, 3) local dofs of each cell
    n_owned_dofs: int
    n_owned_facets: int
    local_to_global: Any  # callable: local dof indices -> global (int64)


def p1_topology(V: fem.FunctionSpace) -> P1Topology:
    """Collect the rank-local P1 topology of ``V`` (creates the needed connectivities)."""
    msh = V.mesh
    top = msh.topology
    tdim = top.dim
    for a, b in ((tdim, 0), (tdim - 1, 0), (tdim - 1, tdim), (tdim, tdim - 1)):
        top.create_connectivity(a, b)
    c2v = top.connectivity(tdim, 0).array.reshape(-1, 3)
    f2v = top.connectivity(tdim - 1, 0).array.reshape(-1, 2)
    f2c = top.connectivity(tdim - 1, tdim)
    dofmap = V.dofmap.list.array.reshape(-1, 3)
    n_vertices = top.index_map(0).size_local + top.index_map(0).num_ghosts
    v2dof = np.full(n_vertices, -1, dtype=np.int32)
    v2dof[c2v[: dofmap.shape[0]].ravel()] = dofmap.ravel()
    im = V.dofmap.index_map

    def l2g(local: np.ndarray) -> np.ndarray:
        local = np.ascontiguousarray(local, dtype=np.int32).ravel()
        return np.asarray(im.local_to_global(local), dtype=np.int64)

    return P1Topology(
        v2dof=v2dof,
        f2v=f2v,
        c2v=c2v,
        f2c_offsets=f2c.offsets,
        f2c_array=f2c.array,
        dof_coords=V.tabulate_dof_coordinates()[:, :2].copy(),
        dofmap=dofmap,
        n_owned_dofs=im.size_local,
        n_owned_facets=top.index_map(tdim - 1).size_local,
        local_to_global=l2g,
    )


def tag_array(tags: Any, n: int, default: int = -1) -> np.ndarray:
    """Dense int array of MeshTags values over ``n`` local entities (``default`` if untagged)."""
    out = np.full(n, default, dtype=np.int32)
    if tags is not None:
        out[tags.indices] = tags.values
    return out


@dataclass
class FacetData:
    """Facets as global P1 dof pairs. Exterior facets are oriented with Omega on the left
    (counter-clockwise along Gamma); interior facets have sorted dofs."""

    dofs: np.ndarray  # (n, 2) int64 global dofs
    coords: np.ndarray  # (n, 2, 2) coordinates of the two end points
    tag: np.ndarray  # (n,) facet tag (0 where untagged)
    cells: np.ndarray  # (n, 2) cell tags on both sides (-1 for the exterior side)
    exterior: np.ndarray  # (n,) bool


def facet_data(
    topo: P1Topology,
    facets: np.ndarray,
    facet_tag: np.ndarray,
    cell_tag: np.ndarray,
    exterior: bool,
) -> FacetData:
    """Data of the given local ``facets`` (all exterior, or all interior with two local cells)."""
    facets = np.asarray(facets, dtype=np.int64)
    v = topo.f2v[facets]
    first = topo.f2c_array[topo.f2c_offsets[facets]]
    if exterior:
        opposite = topo.c2v[first].sum(axis=1) - v.sum(axis=1)
        p = topo.dof_coords[topo.v2dof[v]]
        q = topo.dof_coords[topo.v2dof[opposite]]
        e = p[:, 1] - p[:, 0]
        r = q - p[:, 0]
        flip = (e[:, 0] * r[:, 1] - e[:, 1] * r[:, 0]) < 0  # third vertex on the right: reverse
        v = np.where(flip[:, None], v[:, ::-1], v)
        cells = np.stack([cell_tag[first], np.full(len(facets), -1, np.int32)], axis=1)
    else:
        second = topo.f2c_array[topo.f2c_offsets[facets] + 1]
        cells = np.stack([cell_tag[first], cell_tag[second]], axis=1)
    local = topo.v2dof[v]
    dofs = topo.local_to_global(local.ravel()).reshape(-1, 2)
    coords = topo.dof_coords[local]
    if not exterior:
        order = np.argsort(dofs, axis=1)
        dofs = np.take_along_axis(dofs, order, axis=1)
        coords = np.take_along_axis(coords, order[:, :, None], axis=1)
    return FacetData(
        dofs=dofs,
        coords=coords,
        tag=facet_tag[facets].astype(np.int32),
        cells=cells,
        exterior=np.full(len(facets), exterior),
    )


def gather_facet_data(comm: Any, parts: list[FacetData]) -> FacetData | None:
    """Concatenate the local parts, gather them on rank 0 and drop duplicate facets there
    (an interior facet is seen by every rank holding both its cells). None off rank 0."""
    fields = ("dofs", "coords", "tag", "cells", "exterior")
    local = {f: np.concatenate([getattr(p, f) for p in parts]) for f in fields}
    gathered = gather_to_root(comm, local)
    if comm.rank != 0:
        return None
    allp = {f: np.concatenate([g[f] for g in gathered]) for f in fields}
    pair = np.sort(allp["dofs"], axis=1).astype(np.int64)
    key = pair[:, 0] * (int(pair.max(initial=0)) + 1) + pair[:, 1]  # one int64 per facet
    _, first = np.unique(key, return_index=True)
    first = np.sort(first)
    return FacetData(**{f: allp[f][first] for f in fields})


def exterior_facets(msh: Any) -> np.ndarray:
    """Owned exterior facets (``dolfinx.mesh.exterior_facet_indices``)."""
    msh.topology.create_connectivity(msh.topology.dim - 1, msh.topology.dim)
    return np.asarray(dmesh.exterior_facet_indices(msh.topology), dtype=np.int64)
