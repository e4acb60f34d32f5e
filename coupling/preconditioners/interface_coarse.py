"""The coarse problem C of the distributed B, solved over the ranks through its interface.

Every subdomain lies whole on one rank. Let H_r be the coarse vertices whose subdomains
are all on rank r, and S the vertices shared by subdomains of two or more ranks. A coarse
vertex couples in C only to the vertices of its own subdomains, so C has no entry between
H_r and H_q for r != q, and

    x_S     = Sigma^{-1} (b_S - sum_r C_{S H_r} C_{H_r H_r}^{-1} b_{H_r}),
    x_{H_r} = C_{H_r H_r}^{-1} (b_{H_r} - C_{H_r S} x_S),
    Sigma   = C_SS - sum_r C_{S H_r} C_{H_r H_r}^{-1} C_{H_r S}.

Rank r factors K_r, the block of C on H_r and S, with S left out of the elimination
(:class:`bem_cpp.sparse.SparseCholesky` with ``n_schur = |S|``): its Schur complement is
K_r / H_r = C_SS - C_{S H_r} C_{H_r H_r}^{-1} C_{H_r S}, so Sigma = sum_r (K_r / H_r) -
(P - 1) C_SS, summed once at set-up (one Allreduce of |S|^2 numbers) and factored densely
on every rank. A solve is then a forward sweep over H_r, one Allreduce of |S| numbers,
a dense solve with Sigma and a backward sweep over H_r: each rank's share of C's factor
and of its solves is about 1/P of the whole, where each rank used to factor and solve
all of C (docs/design/parallel.md, "The coarse problem over the ranks").

The right-hand side is given as each rank's contributions: complete on H_r (only rank
r's skeleton dofs lie on edges at a vertex of H_r) and partial sums on S. The solution
is returned on H_r and S, the coarse vertices of rank r's subdomains.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI

from bem_cpp.sparse import SparseCholesky
from coupling.options import INTERFACE_COARSE_MAX_VERTICES
from coupling.preconditioners.kernels import DenseFactor, SparseFactor, nested_dissection

__all__ = ["InterfaceCoarseFactor", "RedundantCoarseFactor", "coarse_factor", "vertex_rank_range"]


def coarse_factor(
    comm: MPI.Comm, matrix: sp.spmatrix, vertex_ranks: tuple[np.ndarray, np.ndarray]
) -> InterfaceCoarseFactor | RedundantCoarseFactor:
    """C^{-1} for the distributed B: through the interface (:class:`InterfaceCoarseFactor`)
    on two or more ranks with at most ``INTERFACE_COARSE_MAX_VERTICES`` shared vertices,
    else C factored whole on every rank. ``vertex_ranks``: :func:`vertex_rank_range`."""
    lowest, highest = vertex_ranks
    shared = lowest != highest
    if comm.size > 1 and np.count_nonzero(shared) <= INTERFACE_COARSE_MAX_VERTICES:
        return InterfaceCoarseFactor(comm, matrix, ~shared & (lowest == comm.rank), shared)
    return RedundantCoarseFactor(comm, matrix)


def vertex_rank_range(
    edge_vertices: np.ndarray, edge_subdomains: np.ndarray, subdomain_rank: np.ndarray, n_v: int
) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and the highest rank among the subdomains at each coarse vertex.

    Every subdomain at a vertex has two of its coarse edges there, so the subdomains on
    the sides of the vertex's edges are all of them (``edge_subdomains``: -1 outside)."""
    rank_of = np.asarray(subdomain_rank, dtype=np.int64)
    n_ranks = int(rank_of.max(initial=0)) + 1
    present = np.zeros((n_v, n_ranks), dtype=bool)  # a rank's subdomain at the vertex
    for side in range(2):
        inside = edge_subdomains[:, side] >= 0
        rank = rank_of[edge_subdomains[inside, side]]
        for end in range(2):
            present[edge_vertices[inside, end], rank] = True
    lowest = np.argmax(present, axis=1)
    highest = n_ranks - 1 - np.argmax(present[:, ::-1], axis=1)
    return lowest, highest


class InterfaceCoarseFactor:
    """C^{-1} over the ranks of ``comm`` (module docstring); collective set-up and solves.

    Parameters
    ----------
    comm
        The ranks; every one holds the whole ``matrix``.
    matrix
        C (n_v x n_v, SPD), identical on every rank.
    inside
        (n_v,) bool: H_r, the coarse vertices whose subdomains are all on this rank.
    shared
        (n_v,) bool: S, the vertices with subdomains on two or more ranks (the same on
        every rank).
    """

    def __init__(
        self, comm: MPI.Comm, matrix: sp.spmatrix, inside: np.ndarray, shared: np.ndarray
    ) -> None:
        self.comm = comm
        self.n = matrix.shape[0]
        own, interface = np.flatnonzero(inside), np.flatnonzero(shared)
        self._local = np.concatenate([own, interface])
        self._n_inside = own.size
        block = sp.csr_matrix(matrix, dtype=float)[self._local][:, self._local]
        ordering = np.concatenate(
            [nested_dissection(block[: own.size, : own.size]), np.arange(own.size, block.shape[0])]
        )
        self._factor = SparseCholesky(block, ordering, n_schur=interface.size)
        sigma = np.empty((interface.size, interface.size))
        comm.Allreduce(np.ascontiguousarray(self._factor.schur), sigma, op=MPI.SUM)
        sigma -= (comm.size - 1) * block[own.size :, own.size :].toarray()
        self._sigma = DenseFactor(sigma)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x = C^{-1} b on this rank's coarse vertices (H_r and S; zero elsewhere), from
        this rank's contributions ``b`` (n_v,): complete on H_r, partial on S."""
        w = self._factor.eliminate(b[self._local])
        interface = np.ascontiguousarray(w[self._n_inside :])
        total = np.empty_like(interface)
        self.comm.Allreduce(interface, total, op=MPI.SUM)
        w[self._n_inside :] = self._sigma.solve(total)
        x = np.zeros(self.n)
        x[self._local] = self._factor.back_substitute(w)
        return x

    def destroy(self) -> None:
        """Nothing to free (for the interface of the preconditioners' factors)."""


class RedundantCoarseFactor:
    """C^{-1} factored whole on every rank: the contributions summed over the ranks (one
    Allreduce of n_v numbers), then one solve with the whole factor, the same on every rank."""

    def __init__(self, comm: MPI.Comm, matrix: sp.spmatrix) -> None:
        self.comm = comm
        self._factor = SparseFactor(matrix)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x = C^{-1} (sum over the ranks of ``b``) on every coarse vertex."""
        total = np.empty_like(b)
        self.comm.Allreduce(np.ascontiguousarray(b), total, op=MPI.SUM)
        return self._factor.solve(total)

    def destroy(self) -> None:
        self._factor.destroy()
