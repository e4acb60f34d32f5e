"""A geometric multigrid for B_Omega on a vertex lattice: the box's or the structured
square's (docs/method.md section 11, "Preconditioning"; docs/design/three_dimensions.md,
"A geometric multigrid on the box"; docs/design/elasticity.md, "Speed against a linear
elasticity solve").

The P1 nodes are the lattice points lower + spacing (i, j[, k]), 0 <= i, j, k <= n
(``fem_py.mesh.box.BoxLattice``; its dimension, 2 or 3, is the one of this code path).
Halving n while it is even gives the coarser lattices n/2, n/4, ..., m (the coarsest, at
most ``LATTICE_MG_COARSEST`` cells per side). From each lattice to the next finer one the
prolongation P is bilinear (2D) or trilinear (3D) interpolation (a fine point's value is
the mean of the coarse points around it: 1, 2, 4 or 8 of them, weights 1, 1/2, 1/4, 1/8);
for d components per node (elasticity: dof = node d + component, DOLFINx's blocked
numbering) it is that P Kronecker I_d, a matrix of block size d. The interpolation is
exact on (multi)linear fields, so the coarse spaces keep the rigid motions. The coarse
operators are Galerkin's, A_c = P^T A P, so that no coarser mesh is built. The V-cycle
smooths by ``LATTICE_MG_SMOOTHING_STEPS`` Chebyshev steps with Jacobi's diagonal on
[f g, g], g the Gershgorin bound max_i sum_j |a_ij| / a_ii >= lambda_max(D^{-1} A) and
f = ``LATTICE_MG_EIGENVALUE_FRACTION``, and solves the coarsest level by a Cholesky factor
on every rank. For the scalar box g = 2 on every level. For elasticity g is larger than
lambda_max (measured by power iteration: 1.00 lambda_max on the finest level of the Hencky
square, 1.5 on its Galerkin levels; 1.5-1.7 on every level of the linear elastic box,
E = 2.5, nu = 0.25), so the smoothers damp less of the spectrum: one cycle's spectrum
against B_Omega is [0.40, 1] at 16^3 cubes and [0.55, 1] on the square at 32^2 cells
(the scalar box: [0.85, 1]). Kept: the bound is exact and rank-independent, and the
alternatives save little there (CG to 1e-10 on the 16^3 box: 15 cycles; 12 with a power
estimate of lambda_max times 1.1 on [0.53, 1], 12 with a third Chebyshev step, [0.55, 1],
each cycle half as dear again).

Everything in it is independent of the number of ranks (up to the order of floating-point
sums): the coarse lattices are numbered lexicographically and split into contiguous ranges,
Jacobi and Chebyshev with fixed bounds are pointwise, g is a maximum, the coarsest solve is
redundant. So one V-cycle is a fixed symmetric positive definite operator, the same on any
number of ranks, and may precondition the Newton steps' CG directly
(``MultigridPreconditioner.cycle_omega``), which GAMG (its aggregates follow the
partition) may not.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from coupling.options import (
    LATTICE_MG_COARSEST,
    LATTICE_MG_EIGENVALUE_FRACTION,
    LATTICE_MG_SMOOTHING_STEPS,
)

__all__ = [
    "lattice_levels",
    "multilinear_prolongation",
    "gershgorin_bound",
    "lattice_multigrid_options",
    "LatticeHierarchy",
]


def lattice_levels(n: int, coarsest: int = LATTICE_MG_COARSEST) -> list[int] | None:
    """Cells (cubes) per side of the lattices from the finest ``n`` down: halved while even
    and above 4; ``None`` when that leaves no coarser lattice or a coarsest one of more than
    ``coarsest`` cells per side (its Cholesky factor would cost too much)."""
    levels = [int(n)]
    while levels[-1] % 2 == 0 and levels[-1] > 4:
        levels.append(levels[-1] // 2)
    if len(levels) < 2 or levels[-1] > coarsest:
        return None
    return levels


def _owned_range(comm: MPI.Comm, size: int) -> tuple[int, int]:
    """The contiguous range of lexicographic lattice nodes rank ``comm.rank`` owns."""
    return size * comm.rank // comm.size, size * (comm.rank + 1) // comm.size


def _lexicographic_points(start: int, stop: int, m: int, dim: int) -> np.ndarray:
    """The lattice indices (k, dim) of the lexicographic numbers start..stop-1 on the
    ``dim``-dimensional lattice of ``m`` cells per side (the first index fastest)."""
    g = np.arange(start, stop, dtype=np.int64)
    side = m + 1
    return np.stack([(g // side**axis) % side for axis in range(dim)], axis=1)


def multilinear_prolongation(
    comm: MPI.Comm, fine_points: np.ndarray, fine_size: int, m: int, block_size: int = 1
) -> PETSc.Mat:
    """P from the lattice of ``m`` cells per side to the one of 2m (collective): bilinear
    (``fine_points`` of 2 columns) or trilinear (3) interpolation, Kronecker the identity of
    ``block_size`` components (dof = node * block_size + component, DOLFINx's blocked
    numbering; the matrix carries that block size).

    Parameters
    ----------
    fine_points
        (k, dim) lattice indices (of the 2m lattice) of this rank's nodes, in the order of
        its rows (blocks of ``block_size`` rows) of the fine operator.
    fine_size
        The fine level's global number of rows (nodes times ``block_size``).
    m
        The coarse lattice; its nodes are numbered lexicographically, split into
        contiguous ranges over the ranks, their ``block_size`` components consecutive.
    block_size
        Components per node: 1 for the scalar problem, d for elasticity.
    """
    fine_points = np.asarray(fine_points, dtype=np.int64)
    k, dim = fine_points.shape
    side, bs = m + 1, int(block_size)
    strides = side ** np.arange(dim, dtype=np.int64)
    odd = fine_points % 2 == 1
    lower = fine_points // 2
    columns, weights = [], []
    for corner in np.ndindex(*(2,) * dim):
        step = np.asarray(corner)
        # a corner above an even coordinate is the same point: weight 0, dropped below
        weight = np.prod(np.where(odd, 0.5, np.where(step == 0, 1.0, 0.0)), axis=1)
        columns.append((lower + step * odd) @ strides)
        weights.append(weight)
    columns_array, weights_array = np.stack(columns, axis=1), np.stack(weights, axis=1)
    kept = weights_array > 0
    order = np.argsort(np.where(kept, columns_array, np.iinfo(np.int64).max), axis=1)
    columns_array = np.take_along_axis(columns_array, order, axis=1)
    weights_array = np.take_along_axis(weights_array, order, axis=1)
    kept = np.take_along_axis(kept, order, axis=1)
    # Kronecker I_bs: row node * bs + c has the node's columns * bs + c, the same weights
    component = np.arange(bs, dtype=np.int64)[None, :, None]
    columns_array = columns_array[:, None, :] * bs + component  # (k, bs, corners)
    weights_array = np.broadcast_to(weights_array[:, None, :], columns_array.shape)
    kept = np.broadcast_to(kept[:, None, :], columns_array.shape)
    counts = np.repeat(kept[:, 0, :].sum(axis=1), bs)
    indptr = np.concatenate([[0], np.cumsum(counts)]).astype(PETSc.IntType)
    nodes = side**dim
    start, stop = _owned_range(comm, nodes)
    prolongation = PETSc.Mat().createAIJ(
        size=((k * bs, fine_size), ((stop - start) * bs, nodes * bs)),
        bsize=bs,
        csr=(indptr, columns_array[kept].astype(PETSc.IntType), weights_array[kept]),
        comm=comm,
    )
    prolongation.assemble()
    return prolongation


def gershgorin_bound(matrix: PETSc.Mat) -> float:
    """max_i sum_j |a_ij| / a_ii over every rank's rows (collective): an upper bound of
    lambda_max(D^{-1} A), independent of the partition."""
    indptr, _, values = matrix.getValuesCSR()
    diagonal = matrix.getDiagonal()
    local = 0.0
    if indptr[-1] > 0:
        sums = np.add.reduceat(np.abs(values), indptr[:-1])
        local = float(np.max(sums / diagonal.array))
    diagonal.destroy()
    return matrix.getComm().tompi4py().allreduce(local, op=MPI.MAX)


class LatticeHierarchy:
    """The prolongations and Galerkin operators of the lattices below B_Omega (collective).

    Parameters
    ----------
    matrix
        B_Omega on the finest lattice, rows in the P1 space's owned order (``block_size``
        rows per node, node-major).
    owned_points
        (n_owned, dim) lattice indices of the owned nodes (dim 2: the square's lattice,
        3: the box's).
    levels
        Cells per side, finest first (:func:`lattice_levels`).
    block_size
        Components per node (1: the scalar problem, d: elasticity).

    Attributes
    ----------
    prolongations : list of Mat
        From each lattice to the next finer one, coarsest first (PCMG's order).
    operators : list of Mat
        The Galerkin operators, coarsest first; the finest is ``matrix`` (not owned).
    """

    def __init__(
        self,
        matrix: PETSc.Mat,
        owned_points: np.ndarray,
        levels: Sequence[int],
        block_size: int = 1,
    ):
        comm = matrix.getComm().tompi4py()
        dim = np.asarray(owned_points).shape[1]
        prolongations, operators = [], [matrix]
        points, size = owned_points, matrix.getSize()[0]
        for m in levels[1:]:
            p = multilinear_prolongation(comm, points, size, m, block_size)
            prolongations.append(p)
            operators.append(operators[-1].PtAP(p))
            start, stop = _owned_range(comm, (m + 1) ** dim)
            points = _lexicographic_points(start, stop, m, dim)
            size = (m + 1) ** dim * block_size
        self.prolongations = prolongations[::-1]
        self.operators = operators[::-1]

    def configure(self, pc: PETSc.PC) -> dict:
        """Make ``pc`` the V-cycle of the module docstring on these levels; returns the PETSc
        options (without the KSP's prefix) its set-up must read."""
        pc.setType(PETSc.PC.Type.MG)
        pc.setMGLevels(len(self.operators))
        for level, p in enumerate(self.prolongations, start=1):
            pc.setMGInterpolation(level, p)
        bounds = {}
        for level, operator in enumerate(self.operators):
            if level == 0:
                pc.getMGCoarseSolve().setOperators(operator)
                continue
            pc.getMGSmoother(level).setOperators(operator)
            bounds[level] = gershgorin_bound(operator)
        return lattice_multigrid_options(bounds)

    def destroy(self) -> None:
        for obj in (*self.prolongations, *self.operators[:-1]):
            obj.destroy()


def lattice_multigrid_options(bounds: dict[int, float]) -> dict:
    """PCMG's options for the smoothers and the coarsest solve of the module docstring;
    ``bounds`` level -> Gershgorin bound g of that level (Chebyshev on [f g, g])."""
    options = {
        "pc_mg_galerkin": "none",  # the operators are given
        "mg_levels_ksp_type": "chebyshev",
        "mg_levels_pc_type": "jacobi",
        "mg_levels_ksp_max_it": LATTICE_MG_SMOOTHING_STEPS,
        "mg_coarse_ksp_type": "preonly",
        "mg_coarse_pc_type": "redundant",
        "mg_coarse_redundant_pc_type": "cholesky",
    }
    for level, g in bounds.items():
        options[
            f"mg_levels_{level}_ksp_chebyshev_eigenvalues"
        ] = f"{LATTICE_MG_EIGENVALUE_FRACTION * g!r},{g!r}"
    return options
