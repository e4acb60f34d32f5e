"""The input numbering of a P1 space: node numbers that do not depend on the partition.

DOLFINx renumbers the dofs (and, under MPI, distributes them by ranks), so the global
dof numbers depend on the number of ranks. The index of each node in the input of the
mesh (``mesh.geometry.input_global_indices``: the generator's or the mesh file's node
numbers) does not. Vectors that start an iteration and arrays written for the user are
defined in this numbering, so that results do not depend on the number of ranks.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from fem_py.parallel import gather_to_root

__all__ = ["input_indices", "gather_by_input", "gather_p1", "gather_cells"]


def input_indices(V: Any) -> np.ndarray:
    """The input index of every local dof of the P1 space ``V`` (owned, then ghosts).

    For P1 on affine triangles the dofs of a cell are its geometry nodes in the same
    local order, so the map is read off the two cell-to-node tables.
    """
    mesh = V.mesh
    index_map = V.dofmap.index_map
    out = np.empty(index_map.size_local + index_map.num_ghosts, dtype=np.int64)
    nodes = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    out[V.dofmap.list.array] = nodes[mesh.geometry.dofmap.array]
    return out


def gather_by_input(
    comm: Any, input_owned: np.ndarray, values: np.ndarray, n_global: int
) -> np.ndarray | None:
    """Owned ``values`` (n_owned, ...) of every rank, placed at their input indices on
    rank 0 (an array of ``n_global`` rows there; None elsewhere)."""
    parts = gather_to_root(comm, (np.asarray(input_owned), np.asarray(values)))
    if comm.rank != 0:
        return None
    first = parts[0][1]
    out = np.empty((n_global,) + first.shape[1:], dtype=first.dtype)
    for index, part in parts:
        out[index] = part
    return out


def _owned_triangles(V: Any) -> np.ndarray:
    """The owned cells of the P1 space ``V`` as node triples in the input numbering."""
    n_cells = V.mesh.topology.index_map(V.mesh.topology.dim).size_local
    return input_indices(V)[V.dofmap.list.array.reshape(-1, 3)[:n_cells]]


def _cell_order(triangles: np.ndarray) -> np.ndarray:
    """The order of the gathered triangles: by their sorted node numbers (unique per
    cell, so the order does not depend on the partition)."""
    key = np.sort(triangles, axis=1)
    return np.lexsort(key.T[::-1])


def gather_p1(u) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Gather a P1 Function to rank 0 in the input numbering of the mesh nodes
    (:mod:`fem_py.numbering`), the same for any number of ranks.

    Returns (x (N, 2), values (N,), triangles (n_cells, 3)) on rank 0, None elsewhere;
    the triangles (counter-clockwise as in the mesh) are sorted by their node numbers.
    """
    V = u.function_space
    comm = V.mesh.comm
    index_map = V.dofmap.index_map
    n_owned, n_global = index_map.size_local, index_map.size_global
    numbers = input_indices(V)
    x = gather_by_input(
        comm, numbers[:n_owned], V.tabulate_dof_coordinates()[:n_owned, :2], n_global
    )
    values = gather_by_input(comm, numbers[:n_owned], u.x.array[:n_owned].real, n_global)
    parts = gather_to_root(comm, _owned_triangles(V))
    if comm.rank != 0:
        return None
    triangles = np.concatenate(parts)
    return x, values, triangles[_cell_order(triangles)]


def gather_cells(V: Any, values: np.ndarray) -> np.ndarray | None:
    """Per-cell ``values`` of the owned cells (local cell order, (n_owned_cells,)) of every
    rank, gathered to rank 0 in the order of the triangles of :func:`gather_p1` (the same
    for any number of ranks); None on the other ranks."""
    comm = V.mesh.comm
    parts = gather_to_root(comm, (_owned_triangles(V), np.asarray(values)))
    if comm.rank != 0:
        return None
    triangles = np.concatenate([t for t, _ in parts])
    return np.concatenate([v for _, v in parts])[_cell_order(triangles)]
