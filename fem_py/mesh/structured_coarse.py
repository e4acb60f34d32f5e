"""The coarse structure of a structured mesh, written down from its generator.

A :class:`fem_py.mesh.structured.StructuredRefinement` knows its coarse partition in
closed form: the coarse cells are the subdomains, the coarse vertices are nodes
``0 .. nv-1`` and the fine nodes of coarse edge e are ``nv + e (n - 1) + k - 1`` (node
numbers, ``fem_py.mesh.structured``; the mesh's input numbers map to them).
:func:`structured_coarse_structure` turns that into the
:class:`fem_py.partition.coarse.CoarseStructure` the substructuring preconditioner needs,
equal field by field to what ``compute_coarse_structure`` recovers from the distributed
mesh (the same orders and orientations; tests/test_fem_structured.py), without the
skeleton search, the facet gathers and the rank-0 work of the recovery: every rank maps
its owned dofs to nodes, and the ranks exchange only those pairs.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from fem_py.dofs.numbering import input_indices
from fem_py.mesh.structured import StructuredRefinement
from fem_py.parallel import allgather_arrays
from fem_py.partition.coarse import CoarseStructure
from fem_py.partition.ragged import Ragged
from fem_py.tags import SIGNORINI_TAG0

__all__ = ["structured_coarse_structure"]


def structured_coarse_structure(
    V: Any, ref: StructuredRefinement, edge_tags: np.ndarray
) -> CoarseStructure:
    """The coarse structure of the mesh of ``V`` made by ``ref``
    (``fem_py.mesh.distribute.distribute_structured``; collective).

    Parameters
    ----------
    V
        The P1 space of the mesh (``fem_py.dofs.p1_space``).
    ref
        The refinement that made the mesh: subdomain c is coarse cell c.
    edge_tags
        The facet tag of every coarse edge, -1 inside (``ref.edge_tags``).
    """
    comm = V.mesh.comm
    nv, n = len(ref.V), ref.n
    n_edges, n_cells = len(ref.edges), len(ref.cells)
    n_skeleton = nv + n_edges * (n - 1)  # the nodes on coarse vertices and edges
    interior_per_cell = len(ref.lattice.interior)

    # the node of every dof, in dof order (the ranks own consecutive ranges of dofs, in
    # rank order): the skeleton and interior dofs, sorted, and the dof of each skeleton node
    index_map = V.dofmap.index_map
    n_owned = index_map.size_local
    (node_of_dof,) = allgather_arrays(comm, (ref.node_numbers(input_indices(V)[:n_owned]),))
    on_skeleton_dof = node_of_dof < n_skeleton
    skeleton_dofs = np.flatnonzero(on_skeleton_dof)
    interior_dofs = np.flatnonzero(~on_skeleton_dof)
    dof_of_node = np.empty(n_skeleton, dtype=np.int64)
    dof_of_node[node_of_dof[skeleton_dofs]] = skeleton_dofs
    interior_subdomain = (node_of_dof[interior_dofs] - n_skeleton) // max(interior_per_cell, 1)

    # coarse vertices sorted by (y, x), keys rounded as compute_coarse_structure's
    X = ref.node_coordinates(np.arange(n_skeleton))
    scale = float(np.ptp(ref.V, axis=0).max())
    K = np.round(X / scale, 9)
    vertex_order = np.lexsort((K[:nv, 0], K[:nv, 1]))
    vnum = np.empty(nv, dtype=np.int64)
    vnum[vertex_order] = np.arange(nv)

    # edges: a boundary edge along its cell's counter-clockwise side, an interior one
    # from the lower to the higher vertex number
    on_boundary = ref.edge_cells[:, 1] < 0
    a, b = ref.edges[:, 0].copy(), ref.edges[:, 1].copy()
    k = ref.cells.shape[1]
    cell, side = (i.ravel() for i in np.indices(ref.cell_edges.shape))  # every side
    edge = ref.cell_edges[cell, side]
    along = ref.cells[cell, side]  # the side's start, counter-clockwise around its cell
    boundary_side = on_boundary[edge]
    a[edge[boundary_side]] = along[boundary_side]
    b[edge[boundary_side]] = ref.cells[cell, (side + 1) % k][boundary_side]
    interior = ~on_boundary
    swap = interior & (vnum[a] > vnum[b])
    a[swap], b[swap] = b[swap], a[swap]
    chains = ref.edge_nodes(a, b)  # (n_edges, n + 1) node numbers from a to b
    ev = np.stack([vnum[a], vnum[b]], 1)
    mid = K[chains[:, (n + 1) // 2]]
    edge_order = np.lexsort((mid[:, 0], mid[:, 1], ev.max(1), ev.min(1)))
    chains = chains[edge_order]

    arc = np.where(on_boundary & (edge_tags >= SIGNORINI_TAG0), edge_tags - SIGNORINI_TAG0, -1)
    cells = ref.edge_cells
    sub = np.where(on_boundary[:, None], cells, np.sort(cells, axis=1))
    vertex_on_boundary = np.zeros(nv, dtype=bool)
    vertex_on_boundary[ref.edges[on_boundary].ravel()] = True
    offsets = np.arange(n_edges + 1, dtype=np.int64) * (n + 1)
    return CoarseStructure(
        vertex_coords=X[vertex_order],
        vertex_dofs=dof_of_node[vertex_order],
        vertex_on_boundary=vertex_on_boundary[vertex_order],
        edge_vertices=ev[edge_order],
        edge_dofs=Ragged(dof_of_node[chains.ravel()], offsets),
        edge_coords=Ragged(X[chains.ravel()], offsets),
        edge_on_boundary=on_boundary[edge_order],
        edge_arc=arc[edge_order].astype(np.int64),
        edge_subdomains=sub[edge_order].astype(np.int64),
        skeleton_dofs=skeleton_dofs,
        interior_dofs=interior_dofs,
        subdomain_of_interior_dof=interior_subdomain,
        n_subdomains=int(n_cells),
        n_dofs=int(index_map.size_global),
        n_skeleton_facets=int(n_edges * n),
    )
