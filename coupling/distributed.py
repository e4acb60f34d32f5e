"""Dense and sparse matrices across ranks: S_h kept by rows or replicated, matrices and
rows gathered.

The u block of the iterations lives in a distributed PETSc vector whose owned entries
are the contiguous global range [r0, r1) of each rank, in rank order. S_h
(:func:`steklov_poincare`) is either dense, computed once on rank 0 and held by rows
(:class:`RowBlocks`), or the H-matrix operator of bem_cpp, distributed by rows (each rank
holds the blocks of its rows; ``bem_cpp.steklov_poincare(..., comm=comm)``); the Signorini
unknowns are replicated.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc

import bem_cpp
from coupling.options import CHOICES, HMATRIX_CROSSOVER, HMATRIX_CROSSOVER_3D, hmatrix_tol
from fem_py.parallel import gather_to_root, run_on_root

__all__ = [
    "RowBlocks",
    "boundary_operator_kind",
    "hmatrix_crossover",
    "steklov_poincare",
    "dense_matrix",
    "gather_matrix",
    "gather_owned_rows",
    "gather_rows",
]


class RowBlocks:
    """A dense square matrix held by rows across ``comm``: rank r keeps the contiguous
    block of rows [r n / P, (r + 1) n / P) (S_h under MPI).

    ``A @ z`` for a replicated vector z is the replicated product A z: every rank
    multiplies its rows and one Allgatherv joins the pieces. The memory per rank is
    n^2 / P, and the P products read disjoint rows, which matters because a dense
    product is memory-bound (measurements: docs/design/parallel.md).
    """

    def __init__(self, comm: MPI.Comm, block: np.ndarray, n: int):
        self._counts, self._offsets = _row_blocks(comm.size, n)
        if block.shape != (self._counts[comm.rank], n):
            raise ValueError(
                f"rank {comm.rank} must hold rows {self._offsets[comm.rank]} .. "
                f"{self._offsets[comm.rank] + self._counts[comm.rank] - 1} of the {n} x {n} "
                f"matrix, got a block of shape {block.shape}"
            )
        self.comm, self.block, self.shape = comm, block, (n, n)

    @classmethod
    def from_root(cls, comm: MPI.Comm, compute: Callable[[], np.ndarray]) -> "RowBlocks":
        """The square matrix ``compute()`` evaluated on rank 0 with every core
        (:func:`fem_py.parallel.run_on_root`), scattered by rows."""
        full = run_on_root(
            comm, lambda: np.ascontiguousarray(compute(), dtype=float), all_cores=True
        )
        n = comm.bcast(full.shape[0] if comm.rank == 0 else None, root=0)
        counts, offsets = _row_blocks(comm.size, n)
        block = np.empty((counts[comm.rank], n))
        comm.Scatterv([full, counts * n, offsets * n, MPI.DOUBLE], block, root=0)
        return cls(comm, block, n)

    def __matmul__(self, z: np.ndarray) -> np.ndarray:
        z = np.asarray(z, dtype=float)
        if z.ndim != 1 or z.shape[0] != self.shape[1]:
            raise ValueError(
                f"RowBlocks @ z needs a vector of length {self.shape[1]}, got shape {z.shape}"
            )
        y = np.empty(self.shape[0])
        self.comm.Allgatherv(
            np.ascontiguousarray(self.block @ z), [y, self._counts, self._offsets, MPI.DOUBLE]
        )
        return y

    def full(self) -> np.ndarray:
        """The whole matrix on every rank (collective; for reference solvers and checks)."""
        n = self.shape[1]
        out = np.empty(self.shape)
        self.comm.Allgatherv(
            np.ascontiguousarray(self.block), [out, self._counts * n, self._offsets * n, MPI.DOUBLE]
        )
        return out


def boundary_operator_kind(
    choice: str, n: int, dim: int = 2, *, kernel: str | tuple = "laplace"
) -> str:
    """``"dense"`` or ``"hmatrix"``: the S_h of ``[solver] boundary_operator = choice`` for
    n boundary nodes of a ``dim``-dimensional body (``"auto"``: the H-matrix from
    :data:`coupling.options.HMATRIX_CROSSOVER` boundary dofs on, in 3D from
    :data:`coupling.options.HMATRIX_CROSSOVER_3D`; with Kelvin's ``kernel`` from bem_cpp's
    measured crossovers of the Lame S_h, ``HMATRIX_LAME_AUTO_NODES`` nodes of a polygon and
    ``HMATRIX_SURFACE_AUTO_DOFS`` vertices of a surface)."""
    allowed = CHOICES["solver", "boundary_operator"]
    if choice not in allowed:
        raise ValueError(f"boundary_operator must be one of {allowed}, got {choice!r}")
    if choice == "auto":
        return "hmatrix" if n >= hmatrix_crossover(dim, kernel) else "dense"
    return choice


def hmatrix_crossover(dim: int, kernel: str | tuple = "laplace") -> int:
    """The boundary nodes from which ``boundary_operator = "auto"`` takes the H-matrix S_h
    (:func:`boundary_operator_kind`)."""
    if kernel == "laplace":
        return HMATRIX_CROSSOVER_3D if dim == 3 else HMATRIX_CROSSOVER
    defaults = bem_cpp.defaults
    return defaults.HMATRIX_SURFACE_AUTO_DOFS if dim == 3 else defaults.HMATRIX_LAME_AUTO_NODES


def steklov_poincare(
    comm: MPI.Comm,
    nodes: np.ndarray,
    flux: str,
    choice: str,
    triangles: np.ndarray | None = None,
    *,
    kernel: str | tuple = "laplace",
) -> Any:
    """S_h of the boundary ``nodes`` (replicated, (n, 2)) for ``[solver] boundary_operator
    = choice`` (collective); in 3D ``nodes`` (n, 3) are the vertices of the surface
    ``triangles`` (m, 3) (docs/method.md section 11, the same S_h formula); with Kelvin's
    ``kernel`` (``("lame", E, nu)``, docs/method.md section 12) the elastic S_h on the
    node-major boundary vectors (d n).

    Dense: the matrix (serial) or :class:`RowBlocks` (computed on rank 0 with every core,
    held by rows). H-matrix: ``bem_cpp.SteklovPoincareOperator`` to the relative accuracy
    :func:`coupling.options.hmatrix_tol`; under MPI distributed over ``comm``: each rank
    holds the blocks of its own rows of V_h, V0_h and K_h (3D: V_h, W_h, K_h; ``S.nbytes``
    is this rank's),
    ``S @ z`` and ``S.flux(v)`` are collective (K x: local rows and one Allgatherv; V x,
    V0 x, K^T y: partial sums and one Allreduce, or Reduce_scatter and Allgatherv on more
    than 2 ranks) and return the same bits on every rank, and the CG of the V_h solves
    takes the serial iteration count (``S.last_iterations``; docs/design/hmatrix.md,
    "Under MPI"). Each has ``S @ z`` for a replicated z and ``S.shape``.
    """
    nodes = np.asarray(nodes, dtype=float)
    surface = {} if triangles is None else {"triangles": np.asarray(triangles)}
    if boundary_operator_kind(choice, *nodes.shape, kernel=kernel) == "hmatrix":
        return bem_cpp.steklov_poincare(
            nodes,
            flux=flux,
            compression="hmatrix",
            tol=hmatrix_tol(nodes),
            comm=comm if comm.size > 1 else None,
            kernel=kernel,
            **surface,
        )

    def dense() -> np.ndarray:
        return bem_cpp.steklov_poincare(nodes, flux=flux, kernel=kernel, **surface)

    return dense() if comm.size == 1 else RowBlocks.from_root(comm, dense)


def dense_matrix(operator: Any, what: str) -> np.ndarray:
    """The dense S_h on every rank for ``what`` (collective for :class:`RowBlocks`).

    Raises
    ------
    ValueError
        One line naming ``what`` if ``operator`` is the H-matrix operator (never formed).
    """
    if isinstance(operator, np.ndarray):
        return operator
    if isinstance(operator, RowBlocks):
        return operator.full()
    raise ValueError(
        f"{what} needs the dense S_h, but S_h is the H-matrix operator (n = "
        f'{operator.shape[0]} boundary dofs); set [solver] boundary_operator = "dense"'
    )


def _row_blocks(ranks: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(counts, offsets) of the contiguous row blocks [r n / P, (r + 1) n / P) of ``ranks`` "
    "ranks."""
    bounds = np.arange(ranks + 1) * n // ranks
    return np.diff(bounds), bounds[:-1]


def gather_rows(comm: MPI.Comm, owned: np.ndarray) -> np.ndarray | None:
    """The owned rows of every rank stacked in rank order on rank 0 (None elsewhere)."""
    parts = gather_to_root(comm, np.ascontiguousarray(owned))
    return np.concatenate(parts) if comm.rank == 0 else None


def gather_matrix(matrix: PETSc.Mat) -> sp.csr_matrix | None:
    """A distributed PETSc AIJ matrix as one scipy CSR matrix on rank 0 (None elsewhere)."""
    r0, r1 = matrix.getOwnershipRange()
    indptr, indices, data = matrix.getValuesCSR()
    local = sp.csr_matrix((data, indices, indptr), shape=(r1 - r0, matrix.getSize()[1]))
    return gather_owned_rows(matrix.comm.tompi4py(), local)


def gather_owned_rows(comm: MPI.Comm, owned: sp.csr_matrix) -> sp.csr_matrix | None:
    """Every rank's owned rows (global column numbers, ranks' rows in order) stacked into
    one scipy CSR matrix on rank 0 (None elsewhere)."""
    parts = gather_to_root(comm, owned)
    if comm.rank != 0:
        return None
    return parts[0] if len(parts) == 1 else sp.vstack(parts).tocsr()
