"""A DOLFINx mesh from cells already on the rank that owns them (collective).

The structured meshes (``fem_py.mesh.distribute.distribute_structured`` in 2D,
``fem_py.mesh.box`` in 3D) write each rank's own cells on that rank and know, from their
closed form, which cells each neighbouring rank must ghost (DOLFINx's shared-facet mode).
``dolfinx.mesh.create_mesh`` would still call a partitioner, send every cell to its rank
(itself), build the dual graph and reorder the cells before it makes the topology, which
costs more than the two steps that remain (measured in docs/design/parallel.md, "The
tenth session"). :func:`mesh_of_placed_cells` calls those two steps,
``dolfinx::mesh::create_topology`` and ``create_geometry``, through the module
``fem_py.mesh._placed_cells`` (fem_py/mesh/cpp/, built by ``make build``), after one
exchange of the ghost cells between neighbours.

The cells keep the order they are given in, owned then ghosts; their input numbers
(``topology.original_cell_index``) are those ``create_mesh`` gives: the cells numbered
rank after rank, each rank's in the order given.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from dolfinx import mesh as dmesh

import fem_py.mesh._placed_cells as _placed_cells

__all__ = ["mesh_of_placed_cells", "p1_domain"]


def mesh_of_placed_cells(
    comm: Any, cell: str, cells: np.ndarray, x: np.ndarray, links: np.ndarray
) -> dmesh.Mesh:
    """The P1 mesh of the cells owned by each rank, ghosted as ``links`` says (collective).

    Parameters
    ----------
    comm
        The communicator of the mesh.
    cell
        "triangle" or "tetrahedron".
    cells
        (n, k) input node numbers of the cells this rank owns.
    x
        (m, gdim) this rank's block of the input nodes' coordinates: the nodes are numbered
        block after block, rank after rank (as ``create_mesh`` takes them).
    links
        (g, 2) unique rows (owned cell, rank): the other ranks on which each owned cell is a
        ghost (every rank owning a cell across one of its facets).

    Returns
    -------
    dolfinx.mesh.Mesh
        The cells in the order given, owned then the ghosts (by owner, then by their input
        number).
    """
    cells = np.ascontiguousarray(cells, dtype=np.int64)
    links = np.asarray(links, dtype=np.int64).reshape(-1, 2)
    offset = comm.exscan(len(cells)) or 0  # None on rank 0
    # send each rank the cells it ghosts, with their input numbers
    links = links[np.lexsort((links[:, 0], links[:, 1]))]
    bounds = np.searchsorted(links[:, 1], np.arange(comm.size + 1))
    outgoing = [
        (cells[links[a:b, 0]], offset + links[a:b, 0]) for a, b in zip(bounds[:-1], bounds[1:])
    ]
    incoming = comm.alltoall(outgoing)
    ghost_cells = [c for c, _ in incoming]
    ghost_numbers = [g for _, g in incoming]
    owners = [np.full(len(g), r, dtype=np.int32) for r, g in enumerate(ghost_numbers)]
    cpp_mesh = _placed_cells.mesh_of_placed_cells(
        comm,
        cell,
        np.concatenate([cells, *ghost_cells]),
        np.ascontiguousarray(x, dtype=np.float64),
        np.concatenate([offset + np.arange(len(cells), dtype=np.int64), *ghost_numbers]),
        np.concatenate(owners),
    )
    return dmesh.Mesh(cpp_mesh, p1_domain(cell))


def p1_domain(cell: str) -> Any:
    """The UFL domain of a P1 mesh of ``cell`` ("triangle" in 2D, "tetrahedron" in 3D;
    ``gmshio.ufl_mesh`` without importing gmsh where no gmsh is needed; measurements:
    docs/design/fem_py.md)."""
    import ufl

    c = ufl.Cell(cell, geometric_dimension=3 if cell == "tetrahedron" else 2)
    return ufl.Mesh(ufl.VectorElement(ufl.FiniteElement("Lagrange", c, 1, variant="equispaced")))
