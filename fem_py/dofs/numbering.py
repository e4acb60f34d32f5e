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
import scipy.sparse as sp

from fem_py.parallel import gather_to_root

__all__ = [
    "input_indices",
    "input_node_numbers",
    "gather_by_input",
    "gather_p1",
    "gather_p1_and_cells",
    "gather_cells",
]


def input_node_numbers(msh: Any) -> np.ndarray:
    """``msh.geometry.input_global_indices`` (the input index of every local geometry
    node) as a read-only int64 array, kept on ``msh``: the binding builds a Python list
    of them on every access (0.1 s at 10^6 nodes), and the mesh never changes them."""
    numbers = getattr(msh, "_input_node_numbers", None)
    if numbers is None:
        numbers = np.asarray(msh.geometry.input_global_indices, dtype=np.int64)
        numbers.flags.writeable = False
        msh._input_node_numbers = numbers
    return numbers


def input_indices(V: Any) -> np.ndarray:
    """The input index of every local dof of the P1 space ``V`` (owned, then ghosts).

    For P1 on affine triangles the dofs of a cell are its geometry nodes in the same
    local order, so the map is read off the two cell-to-node tables.
    """
    return _input_indices(V, _cell_nodes(V))


def _cell_nodes(V: Any) -> np.ndarray:
    """The input indices of the nodes of every local cell (owned, then ghosts), flat:
    3 per cell in the cell's local order (that of its P1 dofs)."""
    return input_node_numbers(V.mesh)[V.mesh.geometry.dofmap.array]


def _input_indices(V: Any, cell_nodes: np.ndarray) -> np.ndarray:
    index_map = V.dofmap.index_map
    out = np.empty(index_map.size_local + index_map.num_ghosts, dtype=np.int64)
    out[V.dofmap.list.array] = cell_nodes
    return out


def _dof_coordinates(V: Any, gdim: int) -> np.ndarray:
    """The coordinates of the local P1 dofs (owned, then ghosts): the mesh's geometry nodes,
    copies of the input with the same bits on any partition and any machine, not
    ``tabulate_dof_coordinates``, which maps reference points through basix's tabulated
    basis and so rounds in the last bit differently with the machine's BLAS (the box's
    corner at -0.25 came out as -0.24999999999999997 on an AVX-512 machine, unlike the
    boundary nodes)."""
    index_map = V.dofmap.index_map
    out = np.empty((index_map.size_local + index_map.num_ghosts, gdim))
    out[V.dofmap.list.array] = V.mesh.geometry.x[V.mesh.geometry.dofmap.array, :gdim]
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


def _owned_triangles(V: Any, cell_nodes: np.ndarray | None = None) -> np.ndarray:
    """The owned cells of the P1 space ``V`` as node triples (quadruples: tetrahedra) in
    the input numbering (a view of ``cell_nodes``, :func:`_cell_nodes`, computed when not
    given)."""
    tdim = V.mesh.topology.dim
    n_cells = V.mesh.topology.index_map(tdim).size_local
    cell_nodes = _cell_nodes(V) if cell_nodes is None else cell_nodes
    return cell_nodes.reshape(-1, tdim + 1)[:n_cells]


def _joined(parts: list[np.ndarray]) -> np.ndarray:
    """The gathered parts as one array (the part itself on one rank: no copy)."""
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def _cell_order(triangles: np.ndarray) -> np.ndarray:
    """The order of the gathered triangles: by their sorted node numbers a < b < c,
    lexicographically (unique per cell, so the order does not depend on the partition).

    A counting sort by a (the rows of a CSR matrix, one per node, column b N + c and the
    cell's position as its value), then each row's few cells sorted by b N + c
    (``sort_indices``): linear in the cells plus the nodes, where a general sort of 2e6
    triples costs several times more (docs/design/speed.md, "Outputs"). Falls back to
    ``np.lexsort`` when b N + c would overflow int64 or two cells share their nodes, and
    for tetrahedra (by their sorted node numbers, lexicographically).
    """
    if np.shape(triangles)[1] != 3:
        ordered = np.sort(np.asarray(triangles, dtype=np.int64), axis=1)
        return np.lexsort(ordered.T[::-1])
    t0, t1, t2 = np.asarray(triangles, dtype=np.int64).T
    a = np.minimum(np.minimum(t0, t1), t2)
    c = np.maximum(np.maximum(t0, t1), t2)
    n = int(c.max()) + 1 if len(triangles) else 1
    if n < 2**31:  # n^2 < 2^62: the columns b n + c and the matrix shape fit in int64
        column = t0 + t1  # then b = t0 + t1 + t2 - a - c, then b n + c, in place
        column += t2
        column -= a
        column -= c
        column *= n
        column += c
        rows = sp.csr_matrix((np.arange(len(a)), (a, column)), shape=(n, n * n))
        rows.sort_indices()  # (the constructor sums duplicates, which sorts them already)
        if rows.nnz == len(a):  # no two cells with the same nodes (summed into one entry)
            return rows.data
    return np.lexsort((c, t0 + t1 + t2 - a - c, a))


def gather_p1(u) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Gather a P1 Function to rank 0 in the input numbering of the mesh nodes
    (:mod:`fem_py.dofs.numbering`), the same for any number of ranks.

    Returns (x (N, 2), values (N,), triangles (n_cells, 3)) on rank 0, None elsewhere;
    the triangles (counter-clockwise as in the mesh) are sorted by their node numbers.
    On a tetrahedral mesh: x (N, 3) and the tetrahedra (n_cells, 4).
    """
    gathered = gather_p1_and_cells(u, None)
    return None if gathered is None else gathered[:3]


def gather_p1_and_cells(
    u, cell_values: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None] | None:
    """:func:`gather_p1` and, with the triangles, per-cell ``cell_values`` of the owned
    cells (local cell order) in their order (None when not given): the cells sorted once
    for both."""
    V = u.function_space
    comm = V.mesh.comm
    index_map = V.dofmap.index_map
    n_owned, n_global = index_map.size_local, index_map.size_global
    cell_nodes = _cell_nodes(V)
    numbers = _input_indices(V, cell_nodes)[:n_owned]
    gdim = V.mesh.topology.dim
    x = gather_by_input(comm, numbers, _dof_coordinates(V, gdim)[:n_owned], n_global)
    values = gather_by_input(comm, numbers, u.x.array[:n_owned].real, n_global)
    parts = gather_to_root(comm, (_owned_triangles(V, cell_nodes), cell_values))
    if comm.rank != 0:
        return None
    triangles = _joined([t for t, _ in parts])
    order = _cell_order(triangles)
    per_cell = None if cell_values is None else _joined([v for _, v in parts])[order]
    return x, values, triangles[order], per_cell


def gather_cells(V: Any, values: np.ndarray) -> np.ndarray | None:
    """Per-cell ``values`` of the owned cells (local cell order, (n_owned_cells,)) of every
    rank, gathered to rank 0 in the order of the triangles of :func:`gather_p1` (the same
    for any number of ranks); None on the other ranks."""
    comm = V.mesh.comm
    parts = gather_to_root(comm, (_owned_triangles(V), np.asarray(values)))
    if comm.rank != 0:
        return None
    triangles = _joined([t for t, _ in parts])
    return _joined([v for _, v in parts])[_cell_order(triangles)]
