"""Serial pieces under MPI: a preconditioner gathered on rank 0, and S_h computed there once
and kept by rows.

The u block of the PGPM lives in a distributed PETSc vector whose owned entries are
the contiguous global range [r0, r1) of each rank, in rank order. A preconditioner
built from global (gathered) matrices is set up on rank 0 only; each application
gathers the owned entries of the residual there (one Gatherv), applies B^{-1} and
returns each rank its slice (one Scatterv). The small Signorini block is replicated:
rank 0 applies it and broadcasts. With one rank the wrapper is not used.

This keeps every iterate independent of the number of ranks. It is not the
distributed substructuring preconditioner (whole subdomains per rank): the work of B
stays on rank 0.
"""
from __future__ import annotations

import os
import time
from typing import Callable

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc
from threadpoolctl import threadpool_limits

__all__ = ["RootPreconditioner", "RowBlocks", "gather_matrix", "gather_rows", "computed_on_root",
           "threads_per_rank"]


def threads_per_rank(comm: MPI.Comm) -> int:
    """BLAS/OpenMP threads for each rank: the cores of the node shared by its ranks.

    An application running under mpirun (the ``fembem`` command, the benchmarks) limits
    the thread pools to this, ``threadpoolctl.threadpool_limits(threads_per_rank(comm))``,
    so that P ranks on P cores do not run P threads each (measured on 2 cores: the
    batched 3 x 3 edge-form inverses took 0.9 s instead of 0.05 s with 2 x 2 threads).
    """
    node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    ranks_here = node.size
    node.Free()
    return max(1, len(os.sched_getaffinity(0)) // ranks_here)


def _on_root(comm: MPI.Comm, compute: Callable[[], np.ndarray]) -> tuple[np.ndarray | None, tuple]:
    """(result on rank 0 / None elsewhere, its shape on every rank): rank 0 computes with
    as many threads as it may use cores (see :func:`threads_per_rank`) while the other
    ranks sleep in a polled non-blocking barrier instead of spinning in MPI. An exception
    on rank 0 is raised on every rank."""
    result, error = None, None
    if comm.rank == 0:
        try:
            with threadpool_limits(limits=len(os.sched_getaffinity(0))):  # all cores, for now
                result = np.ascontiguousarray(compute(), dtype=float)
        except Exception as err:  # noqa: BLE001 - re-raised on every rank below
            error = err
    barrier = comm.Ibarrier()
    while not barrier.Test():
        time.sleep(0.002)
    error, shape = comm.bcast((error, None if error is not None or comm.rank != 0 else result.shape),
                              root=0)
    if error is not None:
        raise error
    return result, shape


def computed_on_root(comm: MPI.Comm, compute: Callable[[], np.ndarray]) -> np.ndarray:
    """A dense array computed once, on rank 0 (:func:`_on_root`), and broadcast to every rank."""
    if comm.size == 1:
        return compute()
    result, shape = _on_root(comm, compute)
    if comm.rank != 0:
        result = np.empty(shape)
    comm.Bcast(result, root=0)
    return result


class RowBlocks:
    """A dense square matrix held by rows across ``comm``: rank r keeps the contiguous
    block of rows [r n / P, (r + 1) n / P) (S_h under MPI).

    ``A @ z`` for a replicated vector z is the replicated product A z: every rank
    multiplies its rows and one Allgatherv joins the pieces. The memory per rank is
    n^2 / P, and the P products read disjoint rows, which matters because a dense
    product is memory-bound (n = 4000 on 2 cores, one measurement: 10.5 ms with every
    rank multiplying the whole matrix, 3.5 ms by rows, 6.4 ms in serial; on a day with
    more bandwidth per core, 3.9 ms by rows and 4.0-4.7 ms in serial).
    """

    def __init__(self, comm: MPI.Comm, block: np.ndarray, n: int):
        self._counts, self._offsets = _row_blocks(comm.size, n)
        if block.shape != (self._counts[comm.rank], n):
            raise ValueError(f"rank {comm.rank} must hold rows {self._offsets[comm.rank]} .. "
                             f"{self._offsets[comm.rank] + self._counts[comm.rank] - 1} of the {n} x {n} "
                             f"matrix, got a block of shape {block.shape}")
        self.comm, self.block, self.shape = comm, block, (n, n)

    @classmethod
    def from_root(cls, comm: MPI.Comm, compute: Callable[[], np.ndarray]) -> "RowBlocks":
        """The square matrix ``compute()`` evaluated on rank 0 (:func:`_on_root`), scattered by rows."""
        full, (n, _) = _on_root(comm, compute)
        counts, offsets = _row_blocks(comm.size, n)
        block = np.empty((counts[comm.rank], n))
        comm.Scatterv([full, counts * n, offsets * n, MPI.DOUBLE], block, root=0)
        return cls(comm, block, n)

    def __matmul__(self, z: np.ndarray) -> np.ndarray:
        z = np.asarray(z, dtype=float)
        if z.ndim != 1 or z.shape[0] != self.shape[1]:
            raise ValueError(f"RowBlocks @ z needs a vector of length {self.shape[1]}, got shape {z.shape}")
        y = np.empty(self.shape[0])
        self.comm.Allgatherv(np.ascontiguousarray(self.block @ z), [y, self._counts, self._offsets, MPI.DOUBLE])
        return y

    def full(self) -> np.ndarray:
        """The whole matrix on every rank (collective; for reference solvers and checks)."""
        n = self.shape[1]
        out = np.empty(self.shape)
        self.comm.Allgatherv(np.ascontiguousarray(self.block), [out, self._counts * n, self._offsets * n, MPI.DOUBLE])
        return out


def _row_blocks(ranks: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(counts, offsets) of the contiguous row blocks [r n / P, (r + 1) n / P) of ``ranks`` ranks."""
    bounds = np.arange(ranks + 1) * n // ranks
    return np.diff(bounds), bounds[:-1]


def gather_rows(comm: MPI.Comm, owned: np.ndarray) -> np.ndarray | None:
    """The owned rows of every rank stacked in rank order on rank 0 (None elsewhere)."""
    parts = comm.gather(np.ascontiguousarray(owned), root=0)
    return np.concatenate(parts) if comm.rank == 0 else None


def gather_matrix(matrix: PETSc.Mat) -> sp.csr_matrix | None:
    """A distributed PETSc AIJ matrix as one scipy CSR matrix on rank 0 (None elsewhere)."""
    comm = matrix.comm.tompi4py()
    r0, r1 = matrix.getOwnershipRange()
    indptr, indices, data = matrix.getValuesCSR()
    local = sp.csr_matrix((data, indices, indptr), shape=(r1 - r0, matrix.getSize()[1]))
    parts = comm.gather(local, root=0)
    return sp.vstack(parts).tocsr() if comm.rank == 0 else None


class RootPreconditioner:
    """A preconditioner set up on rank 0 and applied to distributed owned arrays.

    Parameters
    ----------
    comm
        Communicator of the mesh.
    n_owned
        Number of u entries owned by this rank.
    build
        Called on rank 0 only; returns the serial preconditioner (the interface of
        :class:`coupling.preconditioner.Preconditioner`) for the gathered problem.
    """

    def __init__(self, comm: MPI.Comm, n_owned: int, build: Callable[[], object]):
        self.comm = comm
        self._counts = np.array(comm.allgather(n_owned))
        self._offsets = np.concatenate([[0], np.cumsum(self._counts)[:-1]])
        error, self._inner = None, None
        if comm.rank == 0:
            try:
                self._inner = build()
            except ValueError as err:  # raise on every rank, not only on the root
                error = str(err)
        error = comm.bcast(error, root=0)
        if error is not None:
            raise ValueError(error)
        metric, lam = (self._inner.signorini_metric, self._inner.lambda_max_signorini) \
            if comm.rank == 0 else (None, None)
        self.signorini_metric = comm.bcast(metric, root=0)
        self.lambda_max_signorini = comm.bcast(lam, root=0)
        self.n_signorini = self.signorini_metric.shape[0]

    def _root_apply(self, method: str, owned: np.ndarray) -> np.ndarray:
        full = np.empty(int(self._counts.sum())) if self.comm.rank == 0 else None
        self.comm.Gatherv(np.ascontiguousarray(owned, dtype=float),
                          [full, self._counts, self._offsets, MPI.DOUBLE], root=0)
        result = getattr(self._inner, method)(full) if self.comm.rank == 0 else None
        out = np.empty(self._counts[self.comm.rank])
        self.comm.Scatterv([result, self._counts, self._offsets, MPI.DOUBLE], out, root=0)
        return out

    def _root_signorini(self, method: str, phi: np.ndarray) -> np.ndarray:
        result = getattr(self._inner, method)(phi) if self.comm.rank == 0 else None
        return self.comm.bcast(result, root=0)

    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        return self._root_apply("apply_omega", g)

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        return self._root_apply("matvec_omega", u)

    def apply_signorini(self, g: np.ndarray) -> np.ndarray:
        return self._root_signorini("apply_signorini", g)

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray:
        return self.signorini_metric @ phi

    def destroy(self) -> None:
        if self._inner is not None:
            self._inner.destroy()
