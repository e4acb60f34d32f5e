"""The substructuring preconditioner of docs/method.md section 6, distributed by subdomains.

With the mesh partitioned so that every subdomain lies whole on one rank
(``fem_py.mesh.distribute.subdomain_owners``), B_Omega^{-1} g needs no gathering:

1. x_I = A_II^{-1} g_I: the interior dofs of a subdomain are owned by its rank, so
   each rank factors its own block of A_II (its subdomains' Dirichlet problems).
2. r = g_Sk - A_SkI x_I: each rank adds A_IS^T x_I into its local (owned + ghost)
   skeleton entries; one reverse scatter sums them on the owners.
3. v = (A^0)^{-1} r + Pi C^{-1} Pi^T r: every coarse edge is solved on one rank, the
   owner of the subdomain on its first side, which holds all nodes of the edge as
   owned or ghost dofs (a forward scatter brings r there, a reverse scatter takes the
   edge solutions back); C^{-1} Pi^T r is solved over the ranks through C's interface
   Schur complement (:mod:`coupling.preconditioners.interface_coarse`: one Allreduce
   of the interface's numbers).
4. u_I = x_I - A_II^{-1} A_IS v, after a forward scatter of v.

So one application costs two local A_II solves, four neighbour scatters (of skeleton
vectors: steps 2-4 touch no interior value) and one Allreduce of the coarse interface.
B_Omega u (``matvec_omega``) is the same pattern: one forward scatter, one local A_II
solve, one reverse scatter, two Allreduces. The Signorini block (a few hundred to a few
thousand unknowns) is replicated on every rank
(:class:`coupling.preconditioners.signorini.SignoriniBlock`).

The result equals the serial
:class:`coupling.preconditioners.substructuring.SubstructuringPreconditioner` up to
round-off (sums in another order), so the PGPM iterates do not depend on the number of
ranks.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc

from coupling.preconditioners.kernels import (
    SparseFactor,
    fill_reducing_ordering,
    largest_subdomain_interior,
    block_diagonal_edge_forms,
    coarse_matrix,
    edge_weights,
    galerkin_coarse_matrix,
)
from coupling.preconditioners.interface_coarse import coarse_factor, vertex_rank_range
from coupling.preconditioners.signorini import SignoriniArc, SignoriniBlock
from fem_py.partition import as_ragged

__all__ = ["DistributedSubstructuringPreconditioner", "subdomain_ranks"]


def subdomain_ranks(
    comm: MPI.Comm, cell_tags: Any, n_owned_cells: int, n_subdomains: int
) -> np.ndarray | None:
    """The rank owning each subdomain, or None if some subdomain is split between ranks.

    Collective. ``cell_tags`` are the subdomain ids of the cells (dolfinx MeshTags);
    only the first ``n_owned_cells`` (the owned cells) count.
    """
    owned = cell_tags.values[cell_tags.indices < n_owned_cells]
    present = np.zeros(n_subdomains, dtype=np.int32)
    present[np.unique(owned)] = 1
    count = np.zeros_like(present)
    comm.Allreduce(present, count, op=MPI.SUM)
    rank = np.where(present == 1, comm.rank, 0).astype(np.int32)
    owner = np.zeros_like(rank)
    comm.Allreduce(rank, owner, op=MPI.SUM)
    return owner if np.all(count == 1) else None


class _GhostExchange:
    """Owned <-> owned + ghost arrays of a distributed set of dofs (``ghosts``: the global
    numbers of the ghosts, in the order of the local array), through one ghosted PETSc Vec."""

    def __init__(self, comm: MPI.Comm, n_owned: int, n_global: int, ghosts: np.ndarray):
        self._vec = PETSc.Vec().createGhost(
            np.asarray(ghosts, dtype=PETSc.IntType), (n_owned, n_global), comm=comm
        )

    def forward(self, owned: np.ndarray) -> np.ndarray:
        """The owned values and the ghost values from their owners (owned, then ghosts)."""
        self._vec.array[:] = owned
        self._vec.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        with self._vec.localForm() as loc:
            return loc.array_r.copy()

    def reverse_add(self, local: np.ndarray) -> np.ndarray:
        """Owned entries of the sum over ranks of the local contributions (length n_owned)."""
        with self._vec.localForm() as loc:
            loc.array[:] = local
        self._vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return self._vec.array_r.copy()

    def destroy(self) -> None:
        self._vec.destroy()


def _skeleton_exchange(
    comm: MPI.Comm, sk: np.ndarray, n_owned: int, dofs: _GhostExchange
) -> _GhostExchange:
    """The exchange of the skeleton dofs alone: ``sk`` are their local numbers in the P1
    layout ``dofs`` (owned + ghost; the owned ones first), which is destroyed after
    telling the ghosts their owners' skeleton numbers. Collective.

    B's steps 2 to 4 read and write only skeleton values, so their scatters move vectors
    of the skeleton's size (7/16 of the dofs at d = 4h) and no zero-filled P1 arrays."""
    n_sk_owned = int(np.count_nonzero(sk < n_owned))
    offset = comm.exscan(n_sk_owned) or 0  # None on rank 0
    numbers = np.full(n_owned, -1.0)
    numbers[sk[:n_sk_owned]] = offset + np.arange(n_sk_owned)
    ghost_numbers = dofs.forward(numbers)[sk[n_sk_owned:]]
    dofs.destroy()
    if np.any(ghost_numbers < 0):
        raise RuntimeError(  # an invariant of the coarse structure, not a user's input
            "a ghost skeleton dof is not on its owner's skeleton: the coarse structure "
            "differs between ranks"
        )
    return _GhostExchange(
        comm, n_sk_owned, comm.allreduce(n_sk_owned), ghost_numbers.astype(np.int64)
    )


class DistributedSubstructuringPreconditioner(SignoriniBlock):
    """B = B_Omega + omega B_s of docs/method.md section 6 on a subdomain-aligned partition.

    Parameters
    ----------
    comm
        Communicator of the mesh.
    stiffness
        This rank's cells' share of the P1 Laplace matrix A on its local dofs, local
        column numbers (scipy CSR, ``InteriorForms.stiffness_local``; columns past the
        local dofs, which only other ranks' cells reach, are allowed). A row whose cells
        are all on this rank, as every subdomain interior dof's are, is complete there.
    index_map
        The dof index map of the P1 space (owned range, ghosts).
    coarse
        ``fem_py.partition.coarse.CoarseStructure`` (replicated, global dof numbers).
    subdomain_rank
        (L,) owner rank of each subdomain (:func:`subdomain_ranks`).
    subdomain_size, signorini_arcs, edge_form, signorini_weight, coarse_space
        As for :class:`coupling.preconditioners.substructuring.SubstructuringPreconditioner`.

    ``apply_omega`` and ``matvec_omega`` act on the owned entries of u.
    """

    def __init__(
        self,
        comm: MPI.Comm,
        stiffness: sp.csr_matrix,
        index_map: Any,
        coarse: Any,
        subdomain_rank: np.ndarray,
        subdomain_size: float,
        signorini_arcs: Sequence[SignoriniArc],
        *,
        edge_form: str,
        signorini_weight: float,
        coarse_space: str,
    ) -> None:
        self._init_signorini(signorini_arcs, subdomain_size, edge_form, signorini_weight)
        self.comm = comm
        r0, r1 = index_map.local_range
        n_owned, ghosts = r1 - r0, np.asarray(index_map.ghosts, dtype=np.int64)
        self.n_omega = n_owned
        n_local = n_owned + ghosts.size
        to_local = _global_to_local(r0, r1, ghosts)

        # skeleton (owned + ghost) and owned interior dofs, in local numbering
        local_global = np.concatenate([np.arange(r0, r1), ghosts])
        skeleton = np.asarray(coarse.skeleton_dofs, dtype=np.int64)
        on_skeleton = np.isin(local_global, skeleton, assume_unique=True)
        self._sk = np.flatnonzero(on_skeleton)  # the owned ones first (local numbering)
        self._sk_owned = self._sk < n_owned
        self._exchange = _skeleton_exchange(
            comm, self._sk, n_owned, _GhostExchange(comm, n_owned, index_map.size_global, ghosts)
        )
        self._int = np.flatnonzero(~on_skeleton[:n_owned])
        sk_pos = np.full(n_local, -1, dtype=np.int64)
        sk_pos[self._sk] = np.arange(self._sk.size)

        # A_II (rank-local by the partition) and A_IS, from the owned interior rows of this
        # rank's share of A (complete there): a code per local column, its interior
        # position i >= 0 or -2 - its skeleton position, -1 for the others (ghost interior
        # dofs, columns past the local dofs); no copy of the rows is cut first
        n_i, n_sk = self._int.size, self._sk.size
        code = np.full(max(stiffness.shape[1], n_local), -1, dtype=np.int32)
        code[self._int] = np.arange(n_i)
        code[self._sk] = -2 - np.arange(n_sk)
        column = code[stiffness.indices]
        interior_row = np.zeros(stiffness.shape[0], dtype=bool)
        interior_row[self._int] = True
        on_interior_row = np.repeat(interior_row, np.diff(stiffness.indptr))
        if np.any(on_interior_row & (column == -1)):
            raise RuntimeError(  # an invariant of the distributed mesh, not a user's input
                "a subdomain interior dof couples to a dof owned by another rank: "
                "the mesh is not partitioned by subdomains (use fem_py.mesh.build_domain)"
            )
        keep = on_interior_row & (column >= 0)
        self._a_ii = _column_block(stiffness, self._int, keep, column[keep], n_i)
        keep = on_interior_row & (column < -1)
        self._a_is = _column_block(stiffness, self._int, keep, -2 - column[keep], n_sk)
        self._interior_factor = SparseFactor(
            self._a_ii, fill_reducing_ordering(self._a_ii, largest_subdomain_interior(coarse))
        )

        # the skeleton: edge forms of the edges this rank solves, Pi on all local skeleton dofs
        subdomains = np.asarray(coarse.edge_subdomains, dtype=np.int64)
        side = np.where(subdomains[:, 0] >= 0, subdomains[:, 0], subdomains[:, 1])
        rank_of = np.asarray(subdomain_rank)
        mine = rank_of[side] == comm.rank
        # the edges of this rank's subdomains: every local skeleton dof that B reads lies on
        # one (an owned dof is in an owned cell); the others' interpolation is never used
        near = ((subdomains >= 0) & (rank_of[np.maximum(subdomains, 0)] == comm.rank)).any(axis=1)
        ends = np.asarray(coarse.edge_vertices, dtype=np.int64)
        vertex_local = to_local(np.asarray(coarse.vertex_dofs, dtype=np.int64))
        vertex_sk = np.where(vertex_local >= 0, sk_pos[vertex_local], -1)
        n_v = len(vertex_sk)
        has = vertex_sk >= 0
        p_rows, p_cols, p_vals = [vertex_sk[has]], [np.flatnonzero(has)], [np.ones(int(has.sum()))]
        groups = []
        edge_dofs = as_ragged(coarse.edge_dofs, dtype=np.int64)
        edge_coords = as_ragged(coarse.edge_coords, dtype=float, item_shape=(2,))
        for length, group in edge_dofs.length_groups():
            group = group[near[group]]
            if group.size == 0:
                continue
            inner_global = edge_dofs.rows(group)[:, 1:-1]
            local = to_local(inner_global)
            inner = np.where(local >= 0, sk_pos[np.maximum(local, 0)], -1)
            pts = edge_coords.rows(group)
            t = edge_weights(pts)
            for end, weight in ((0, 1.0 - t), (1, t)):
                present = inner >= 0
                p_rows.append(inner[present])
                p_cols.append(np.broadcast_to(ends[group, end][:, None], inner.shape)[present])
                p_vals.append(weight[present])
            own = mine[group]
            if np.any(inner[own] < 0):
                raise RuntimeError(
                    "a coarse edge is not local to the rank owning its subdomain; "
                    "the mesh is not partitioned by subdomains"
                )
            groups.append((inner[own], pts[own]))
        self._interp = sp.csr_matrix(
            (np.concatenate(p_vals), (np.concatenate(p_rows), np.concatenate(p_cols))),
            shape=(n_sk, n_v),
        )
        self._owned_sk = self._sk[self._sk_owned]  # local numbers of the owned skeleton dofs
        self._interp_owned = self._interp[self._sk_owned].tocsr()
        self._interp_owned_t = self._interp_owned.T.tocsr()
        self._interp_t = self._interp.T.tocsr()
        self._a0, self._a0_inv = block_diagonal_edge_forms(groups, n_sk, edge_form)
        self._vertex_owned = np.flatnonzero(
            has & (vertex_local < n_owned)
        )  # coarse vertices owned here
        self._vertex_owned_dof = vertex_local[self._vertex_owned]
        if coarse_space == "galerkin":
            self._coarse_matrix = galerkin_coarse_matrix(
                coarse, self.subdomain_size, lambda e: self._schur_of(stiffness, e)
            )
        elif coarse_space == "graph":
            self._coarse_matrix = coarse_matrix(coarse, self.subdomain_size)
        else:
            raise ValueError(f"coarse_space must be 'graph' or 'galerkin', got {coarse_space!r}")
        self._coarse = coarse_factor(
            comm, self._coarse_matrix, vertex_rank_range(ends, subdomains, rank_of, n_v)
        )

    def _schur_of(self, stiffness: sp.csr_matrix, e: np.ndarray) -> np.ndarray:
        """Pi^T S Pi e for coarse vertex values e (n_v, K), collective: the discrete
        harmonic extension u of Pi e (local Dirichlet solves), then Pi^T (A u) on the
        owned skeleton rows, each rank's cells' share of A u summed on the owners."""
        out = np.zeros(e.shape)
        u = np.zeros(stiffness.shape[1])  # 0 past the local dofs: no local cell reaches them
        skeleton_rows = stiffness[self._sk]
        for k in range(e.shape[1]):
            p = self._interp @ e[:, k]  # Pi e on the local skeleton (owned and ghost)
            u[self._int] = -self._interior_factor.solve(self._a_is @ p)
            u[self._sk] = p
            out[:, k] = self._interp_owned_t @ self._exchange.reverse_add(skeleton_rows @ u)
        return self._sum(out)

    def _sum(self, v: np.ndarray) -> np.ndarray:
        out = np.empty_like(v)
        self.comm.Allreduce(np.ascontiguousarray(v), out, op=MPI.SUM)
        return out

    def _owned(self, v: np.ndarray, name: str) -> np.ndarray:
        """``v`` as floats, refused unless it holds the owned entries."""
        v = np.asarray(v, dtype=float)
        if v.shape != (self.n_omega,):
            raise ValueError(
                f"{name} must have shape ({self.n_omega},), the owned entries, got {v.shape}"
            )
        return v

    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        """u = B_Omega^{-1} g on the owned entries: the four steps of the module docstring."""
        g = self._owned(g, "g")
        x_i = self._interior_factor.solve(g[self._int])
        r_owned = g[self._owned_sk] - self._exchange.reverse_add(self._a_is.T @ x_i)
        r_sk = self._exchange.forward(r_owned)
        c = self._coarse.solve(self._interp_owned_t @ r_owned)
        v_owned = self._exchange.reverse_add(self._a0_inv @ r_sk) + self._interp_owned @ c
        v_sk = self._exchange.forward(v_owned)
        u = np.empty(self.n_omega)
        u[self._int] = x_i - self._interior_factor.solve(self._a_is @ v_sk)
        u[self._owned_sk] = v_owned
        return u

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        """B_Omega u on the owned entries (docs/method.md section 6, B_Sk = Q^T A^0 Q + R^T C R)."""
        u = self._owned(u, "u")
        u_sk = self._exchange.forward(u[self._owned_sk])
        u_i = u[self._int]
        y = self._a_is @ u_sk
        coarse_u = np.zeros(self._coarse_matrix.shape[0])
        coarse_u[self._vertex_owned] = u[self._vertex_owned_dof]
        coarse_u = self._sum(coarse_u)  # R u
        a_sk = self._a0 @ (u_sk - self._interp @ coarse_u)  # A^0 Q u on the edges of this rank
        coarse_term = self._coarse_matrix @ coarse_u - self._sum(
            self._interp_t @ a_sk
        )  # C R u - Pi^T A^0 Q u
        out = np.empty(self.n_omega)
        out[self._owned_sk] = self._exchange.reverse_add(
            self._a_is.T @ (u_i + self._interior_factor.solve(y)) + a_sk
        )
        out[self._int] = self._a_ii @ u_i + y
        out[self._vertex_owned_dof] += coarse_term[self._vertex_owned]
        return out

    def destroy(self) -> None:
        """Free the PETSc objects (call on every rank)."""
        self._interior_factor.destroy()
        self._coarse.destroy()
        self._exchange.destroy()


def _column_block(
    matrix: sp.csr_matrix, rows: np.ndarray, keep: np.ndarray, columns: np.ndarray, n_columns: int
) -> sp.csr_matrix:
    """The block of the CSR ``matrix`` on the (increasing) ``rows``: its stored entries
    ``keep`` (one flag per entry, none outside ``rows``), renumbered to the ``columns``
    (one per kept entry), built directly in CSR (no matrix of triplets, no copy of the
    rows, no array of the matrix's size but the flags)."""
    per_row = np.zeros(matrix.shape[0], dtype=np.int64)
    starts, ends = matrix.indptr[:-1], matrix.indptr[1:]
    filled = np.flatnonzero(ends > starts)
    if keep.size:
        per_row[filled] = np.add.reduceat(keep.view(np.uint8), starts[filled], dtype=np.int64)
    indptr = np.zeros(len(rows) + 1, dtype=np.int64)
    np.cumsum(per_row[rows], out=indptr[1:])
    block = sp.csr_matrix((matrix.data[keep], columns, indptr), shape=(len(rows), n_columns))
    block.sort_indices()
    return block


def _global_to_local(r0: int, r1: int, ghosts: np.ndarray):
    """A vectorised map of global dof numbers to local ones (owned, then ghosts; -1 if absent)."""
    order = np.argsort(ghosts)
    sorted_ghosts = ghosts[order]
    n_owned = r1 - r0

    def to_local(g: np.ndarray) -> np.ndarray:
        out = np.subtract(g, r0, dtype=np.int64)  # a new array: the owned ones' local numbers
        other = np.flatnonzero((out < 0) | (out >= n_owned))
        if len(other) == 0:
            return out
        wanted = out.ravel()[other] + r0  # look up only the entries owned elsewhere, a few
        local = np.full(len(other), -1, dtype=np.int64)
        if len(ghosts):
            at = np.minimum(np.searchsorted(sorted_ghosts, wanted), len(ghosts) - 1)
            found = sorted_ghosts[at] == wanted
            local[found] = n_owned + order[at[found]]
        out.ravel()[other] = local
        return out

    return to_local
