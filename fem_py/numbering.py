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

__all__ = ["input_indices", "gather_by_input"]


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
    parts = comm.gather((np.asarray(input_owned), np.asarray(values)), root=0)
    if comm.rank != 0:
        return None
    first = parts[0][1]
    out = np.empty((n_global,) + first.shape[1:], dtype=first.dtype)
    for index, part in parts:
        out[index] = part
    return out
