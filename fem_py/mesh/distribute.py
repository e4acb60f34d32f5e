"""Distribute a triangle mesh over the ranks by whole subdomains (docs/method.md section 6).

Every rank gets whole subdomains (:func:`subdomain_owners`), so the local Dirichlet
problems of the substructuring preconditioner are rank-local; cells are ghosted in
DOLFINx's shared-facet mode. Two inputs:

- :func:`distribute_mesh`: a mesh held whole on rank 0 (the gmsh arrays of
  ``fem_py.mesh.gmsh_mesh``), distributed the way ``gmshio.model_to_mesh`` does it
  (``create_mesh`` with :func:`subdomain_owners` as its partitioner,
  ``distribute_entity_data``, ``meshtags_from_entities``);
- :func:`distribute_structured`: a structured refinement (``fem_py.mesh.structured``),
  written down in parallel: each rank makes the triangles of its own coarse cells and a
  block of the node coordinates, the mesh is made from them where they are
  (``fem_py.mesh.placed``, without ``create_mesh``), and the tags follow from the
  closed-form numbering.

With fewer subdomains than ranks, DOLFINx's graph partitioner is used instead (the
preconditioner then runs on rank 0, ``coupling.distributed``).
"""
from __future__ import annotations

from typing import Any

import numpy as np
from dolfinx import mesh as dmesh

from fem_py.dofs import input_node_numbers
from fem_py.mesh.placed import mesh_of_placed_cells, p1_domain
from fem_py.mesh.structured import StructuredRefinement
from fem_py.parallel import broadcast_from_root, gather_to_root

__all__ = [
    "destinations",
    "distribute_mesh",
    "distribute_structured",
    "structured_cells",
    "subdomain_owners",
    "reghost",
]

#: (mesh, cell tags "subdomains" (dim 2), facet tags "boundary" (dim 1)).
TaggedMesh = tuple[Any, Any, Any]


def subdomain_owners(
    x: np.ndarray, cells: np.ndarray, subdomain: np.ndarray, nparts: int
) -> np.ndarray:
    """The rank of every cell such that each subdomain lies whole on one rank.

    Recursive coordinate bisection of the subdomain centroids, weighted by the cell
    count: a group of subdomains for ``k`` ranks is cut across its longer extent at
    the weighted position k//2 : k - k//2. The partition is deterministic (the same
    for every run), and the local Dirichlet problems of docs/method.md section 6 become
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
    centroid = np.stack(
        [np.bincount(subdomain, centre[:, i], minlength=n_sub) for i in range(2)], 1
    )
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


def destinations(owner: np.ndarray, links: np.ndarray) -> Any:
    """DOLFINx partitioner output: per local cell its owner, then the ranks ghosting it
    (``links``: unique (cell, rank) rows), those of a cell in the order of ``links``.

    Written by offsets, without a sort of every cell and link (docs/design/speed.md, "The
    mesh on one rank")."""
    from dolfinx import cpp

    n = len(owner)
    links = np.asarray(links, dtype=np.int64).reshape(-1, 2)
    if not len(links):  # one rank per cell (every cell on one rank)
        return cpp.graph.AdjacencyList_int32(
            np.asarray(owner, dtype=np.int32), np.arange(n + 1, dtype=np.int32)
        )
    counts = np.bincount(links[:, 0], minlength=n) + 1
    offsets = np.zeros(n + 1, dtype=np.int32)
    np.cumsum(counts, out=offsets[1:])
    ranks = np.empty(offsets[-1], dtype=np.int32)
    ranks[offsets[:-1]] = owner
    order = np.argsort(links[:, 0], kind="stable")
    cell = links[order, 0]
    # the k-th link of a cell goes k + 1 places after its owner
    k = np.arange(len(cell)) - np.searchsorted(cell, cell, side="left")
    ranks[offsets[cell] + 1 + k] = links[order, 1]
    return cpp.graph.AdjacencyList_int32(ranks, offsets)


def _owner_and_ghosts(cells: np.ndarray, owner: np.ndarray) -> Any:
    """Rows of (owner, ranks ghosting the cell) for DOLFINx's shared-facet ghost mode:
    a cell is ghosted on the owners of its facet neighbours. Only cells with two nodes
    touched by several ranks can have a neighbour elsewhere, so only their facets are
    matched."""
    nparts = int(owner.max(initial=0)) + 1
    n_nodes = int(cells.max(initial=0)) + 1
    ranks_at = sum(
        (np.bincount(cells[owner == r].ravel(), minlength=n_nodes) > 0).astype(np.int8)
        for r in range(nparts)
    )
    near = np.flatnonzero((ranks_at[cells] > 1).sum(1) >= 2)
    facets = np.sort(cells[near][:, [[1, 2], [2, 0], [0, 1]]].reshape(-1, 2), axis=1)
    code = facets[:, 0] * n_nodes + facets[:, 1]
    order = np.argsort(code)
    same = np.flatnonzero(code[order][1:] == code[order][:-1])  # a facet seen from both cells
    a, b = near[order[same] // 3], near[order[same + 1] // 3]
    cut = owner[a] != owner[b]
    a, b = a[cut], b[cut]
    links = np.unique(np.stack([np.concatenate([a, b]), owner[np.concatenate([b, a])]], 1), axis=0)
    return destinations(owner, links.reshape(-1, 2))


def _tagged_mesh(
    msh: Any, cell_values: np.ndarray, facets: np.ndarray, facet_values: np.ndarray
) -> TaggedMesh:
    """(mesh, cell tags, facet tags): ``cell_values`` for the local cells (owned, then
    ghosts), ``facets`` (input node numbers) and their values on any rank."""
    from dolfinx import cpp

    ct = dmesh.meshtags(
        msh,
        2,
        np.arange(_n_local_cells(msh), dtype=np.int32),
        np.asarray(cell_values, dtype=np.int32),
    )
    ents, vals = cpp.io.distribute_entity_data(
        msh._mesh,
        1,
        np.asarray(facets, dtype=np.int64).reshape(-1, 2),
        np.asarray(facet_values, dtype=np.int32),
    )
    msh.topology.create_connectivity(1, 2)
    ft = dmesh.meshtags_from_entities(
        msh, 1, cpp.graph.AdjacencyList_int32(ents), vals.astype(np.int32)
    )
    ct.name, ft.name = "subdomains", "boundary"
    return msh, ct, ft


def _n_local_cells(msh: Any) -> int:
    """Number of local cells, owned and ghosts."""
    cells = msh.topology.index_map(2)
    return cells.size_local + cells.num_ghosts


def _local_cells(msh: Any) -> np.ndarray:
    """Input (global) index of every local cell, owned then ghosts."""
    return np.asarray(msh.topology.original_cell_index[: _n_local_cells(msh)], dtype=np.int64)


def distribute_mesh(comm: Any, arrays: tuple | None) -> TaggedMesh:
    """Distribute a triangle mesh held on rank 0, whole subdomains per rank (collective).

    Parameters
    ----------
    comm
        The communicator of the mesh.
    arrays
        On rank 0, (x (n, 2), cells (n_c, 3), subdomain id of every cell 0 .. L-1,
        boundary facets (n_f, 2) as node numbers, facet tags) (``fem_py.mesh.gmsh_mesh``);
        ignored on the other ranks.

    Returns
    -------
    (mesh, cell tags, facet tags)
    """
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
    n_sub = broadcast_from_root(comm, lambda: int(np.max(cell_values, initial=-1)) + 1)
    by_subdomain = n_sub >= comm.size  # also in serial: no graph partitioner for one part
    msh = dmesh.create_mesh(
        comm,
        cells,
        x,
        p1_domain("triangle"),
        **({"partitioner": partitioner} if by_subdomain else {}),
    )
    # cell tags by the input index of every local cell (all cells were input on rank 0)
    wanted = gather_to_root(comm, _local_cells(msh))
    values = comm.scatter(
        [np.asarray(cell_values, dtype=np.int32)[w] for w in wanted] if comm.rank == 0 else None,
        root=0,
    )
    return _tagged_mesh(msh, values, facets, facet_values)


def structured_cells(
    comm: Any, ref: StructuredRefinement
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """This rank's part of the structured mesh, written down where it is owned: the rank of
    every coarse cell (:func:`subdomain_owners`), the triangles of this rank's coarse cells
    (input node numbers), this rank's even block of the node coordinates, and the (triangle,
    rank) rows of the ranks ghosting its triangles (the inputs of
    ``fem_py.mesh.placed.mesh_of_placed_cells``; no communication)."""
    nc = len(ref.cells)
    rank_of_cell = (
        subdomain_owners(ref.V, ref.cells, np.arange(nc), comm.size)
        if comm.size > 1
        else np.zeros(nc, dtype=np.int32)
    )
    mine = np.flatnonzero(rank_of_cell == comm.rank)
    N = ref.n_nodes
    x = ref.coordinates(comm.rank * N // comm.size, (comm.rank + 1) * N // comm.size)
    return rank_of_cell, ref.triangles(mine), x, ref.ghost_ranks(mine, rank_of_cell, comm.rank)


def distribute_structured(
    comm: Any, ref: StructuredRefinement, edge_tags: np.ndarray
) -> TaggedMesh:
    """Create the structured mesh in parallel (collective).

    Every rank writes down the triangles of its own coarse cells (:func:`subdomain_owners`
    of the coarse cells) and an even block of the node coordinates, so no rank holds the
    whole mesh.

    Parameters
    ----------
    comm
        The communicator of the mesh.
    ref
        The refinement of the coarse cells (the same on every rank).
    edge_tags
        The facet tag of every coarse edge, -1 inside (``ref.edge_tags``).

    Returns
    -------
    (mesh, cell tags, facet tags)
    """
    nc, T = len(ref.cells), ref.triangles_per_cell
    rank_of_cell, cells, x, links = structured_cells(comm, ref)
    # whole subdomains per rank when there are enough subdomains, made where they are
    # (fem_py.mesh.placed), else DOLFINx's graph partitioner (the preconditioner then runs
    # on rank 0, coupling.distributed)
    if nc >= comm.size:
        msh = mesh_of_placed_cells(comm, "triangle", cells, x, links)
    else:
        msh = dmesh.create_mesh(comm, cells, x, p1_domain("triangle"))
    # input cells are numbered rank after rank, each rank's coarse cells in increasing order
    by_rank = np.argsort(rank_of_cell, kind="stable")
    ct = dmesh.meshtags(
        msh,
        2,
        np.arange(_n_local_cells(msh), dtype=np.int32),
        by_rank[_local_cells(msh) // T].astype(np.int32),
    )
    # facet tags from the node numbers of the facet ends: the coarse edge under each facet.
    # Only coarse boundary edges are tagged, and their facets have one local cell (so do
    # the outer facets of ghost cells, which the edges' tags then leave out)
    topology = msh.topology
    topology.create_connectivity(1, 0)
    topology.create_connectivity(1, 2)
    vertices = topology.index_map(0)
    node_of_vertex = np.empty(vertices.size_local + vertices.num_ghosts, dtype=np.int64)
    node_of_vertex[topology.connectivity(2, 0).array] = msh.geometry.dofmap.array
    one_cell = np.flatnonzero(np.diff(topology.connectivity(1, 2).offsets) == 1)
    facet_vertices = topology.connectivity(1, 0).array.reshape(-1, 2)[one_cell]
    ends = ref.node_numbers(input_node_numbers(msh)[node_of_vertex[facet_vertices.ravel()]])
    ends = ends.reshape(-1, 2)
    edge = ref.edge_of_segments(ends[:, 0], ends[:, 1])
    tags = np.where(edge >= 0, edge_tags[np.maximum(edge, 0)], -1)
    tagged = tags >= 0
    ft = dmesh.meshtags(msh, 1, one_cell[tagged].astype(np.int32), tags[tagged])
    ct.name, ft.name = "subdomains", "boundary"
    return msh, ct, ft


def reghost(msh: Any) -> Any:
    """``msh`` (refined by DOLFINx without redistribution) created again from its owned
    cells, each owned by the same rank and ghosted once on every other rank owning one of
    its facet neighbours (DOLFINx's shared-facet mode; collective). In serial ``msh``.
    Triangles or tetrahedra (facets: edges or triangles).

    DOLFINx 0.5.2's ``refine(..., redistribute=False)`` ghosts a cell once per facet it
    shares with another rank, so a cell with two such facets arrives twice, and the
    vertices around it get wrong owners (``fem_py.refinement``)."""
    comm = msh.comm
    if comm.size == 1:
        return msh
    topology = msh.topology
    tdim = topology.dim
    k = tdim + 1  # vertices and facets of a simplex
    topology.create_connectivity(tdim, 0)
    topology.create_connectivity(tdim - 1, tdim)
    topology.create_connectivity(tdim, tdim - 1)
    cells, vertices = topology.index_map(tdim), topology.index_map(0)
    n_own = cells.size_local
    c2v = topology.connectivity(tdim, 0).array.reshape(-1, k)
    node_of_vertex = np.empty(vertices.size_local + vertices.num_ghosts, dtype=np.int64)
    node_of_vertex[c2v] = msh.geometry.dofmap.array.reshape(-1, k)
    x = msh.geometry.x[node_of_vertex[: vertices.size_local], :tdim]
    own = c2v[:n_own]
    glob = vertices.local_to_global(own.ravel().astype(np.int32)).reshape(-1, k)
    # the other ranks ghosting each owned cell: owners of the ghost cells across its facets
    owner = np.concatenate([np.full(n_own, comm.rank), np.asarray(cells.owners)])
    f2c = topology.connectivity(tdim - 1, tdim)
    c2f = topology.connectivity(tdim, tdim - 1).array.reshape(-1, k)[:n_own]
    # every (owned cell, cell across one of its facets) pair, itself included (a facet may
    # have more than two cells here: the doubled ghosts)
    facet = c2f.ravel()
    count = np.diff(f2c.offsets)[facet]
    start = np.repeat(f2c.offsets[facet] - np.cumsum(count) + count, count)
    other = f2c.array[start + np.arange(count.sum())]
    cell = np.repeat(np.repeat(np.arange(n_own), k), count)
    away = owner[other] != comm.rank
    links = np.unique(np.stack([cell[away], owner[other][away]], axis=1), axis=0)
    name = "tetrahedron" if tdim == 3 else "triangle"
    return mesh_of_placed_cells(comm, name, glob, x, links)
