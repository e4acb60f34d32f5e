"""J_h on x = (u, phi) in one sequential PETSc Vec, and its Hessian H(x) (docs/method.md
(4.1)) as one SeqAIJ matrix: the sparse P1 matrix D^2G plus the dense block
P^T S_h P on the boundary and Signorini unknowns (z = T u + E phi = P x)."""
from __future__ import annotations

from typing import Any, Callable

import numpy as np
from petsc4py import PETSc

from bench.peers.baselines.budget import Budget, PeerResult, require_serial
from coupling.distributed import dense_matrix
from coupling.problem import SignoriniProblem

__all__ = ["Evaluator", "CoupledHessian"]


class Evaluator:
    """J_h, its gradient and its Hessian on x = (u, phi) in one sequential PETSc Vec;
    every evaluation checks ``budget``."""

    def __init__(self, problem: SignoriniProblem, budget: Budget):
        from dolfinx import fem

        require_serial(problem.comm)
        self.problem = problem
        self.functional = problem.functional
        self.budget = budget
        self.u = fem.Function(problem.V)
        self.n_u = problem.V.dofmap.index_map.size_local
        if self.u.x.array.size != self.n_u:
            raise ValueError("the P1 space has ghost entries; the PETSc peers are serial")
        self.n_s = problem.n_signorini
        self.grad_u = problem.forms.create_vector()
        self.evaluations = 0

    @property
    def size(self) -> int:
        return self.n_u + self.n_s

    def create_vec(self) -> PETSc.Vec:
        x = PETSc.Vec().createSeq(self.size, comm=PETSc.COMM_SELF)
        x.set(0.0)
        return x

    def bounds(self) -> tuple[PETSc.Vec, PETSc.Vec]:
        """u free, phi >= 0."""
        lower, upper = self.create_vec(), self.create_vec()
        lower.array[: self.n_u] = PETSc.NINFINITY
        lower.array[self.n_u :] = 0.0
        upper.set(PETSc.INFINITY)
        return lower, upper

    def state(self, x: PETSc.Vec) -> np.ndarray:
        """Check the budget, put the u part of ``x`` into :attr:`u`, return phi."""
        self.budget.check()
        values = x.array_r
        self.u.x.array[:] = values[: self.n_u]
        return values[self.n_u :].copy()

    def objective(self, x: PETSc.Vec) -> float:
        self.evaluations += 1
        return self.functional.value(self.u, self.state(x))

    def gradient(self, x: PETSc.Vec, g: PETSc.Vec) -> None:
        self.evaluations += 1
        g_phi = self.functional.gradient(self.u, self.state(x), self.grad_u)
        g.array[: self.n_u] = self.grad_u.array_r
        g.array[self.n_u :] = g_phi

    def objective_gradient(self, x: PETSc.Vec, g: PETSc.Vec) -> float:
        self.evaluations += 1
        value, g_phi = self.functional.value_and_gradient(self.u, self.state(x), self.grad_u)
        g.array[: self.n_u] = self.grad_u.array_r
        g.array[self.n_u :] = g_phi
        return value

    def split(self, x: PETSc.Vec) -> tuple[np.ndarray, np.ndarray]:
        """(u, phi) of ``x``, copied."""
        values = x.array_r
        return values[: self.n_u].copy(), values[self.n_u :].copy()

    def run(
        self, solver: Any, solve: Callable[[], Any], describe: Callable[[int], str], x, **fields
    ) -> PeerResult:
        """Run ``solve()`` (the SNES or TAO ``solver`` on ``x``) within the budget; the
        result at ``x``, with the further ``fields`` of :class:`PeerResult`."""
        converged, reason, seconds = self.budget.run(solve, solver.getConvergedReason, describe)
        outcome = dict(converged=converged, reason=reason, iterations=solver.getIterationNumber())
        u, phi = self.split(x)
        return PeerResult(u, phi, **outcome, solve=seconds, evaluations=self.evaluations, **fields)

    def destroy(self) -> None:
        self.grad_u.destroy()


class CoupledHessian:
    """The Hessian H(x) of J_h (module docstring) as one SeqAIJ matrix.

    Set-up, O(nnz): the pattern of D^2G (the P1 pattern of DOLFINx) and the dense block
    P^T S_h P on the sorted indices ``idx`` of P = [T, E] (boundary dofs and phi). A row
    outside ``idx`` is the D^2G row; a row in ``idx`` is ``idx`` merged with the few
    D^2G columns outside it, so every position is known without a global sort. The
    matrix shares its CSR arrays with numpy (``MatCreateSeqAIJWithArrays``): the dense
    values are written once, and :meth:`assemble` costs one DOLFINx Jacobian assembly
    plus one vector update at the D^2G positions. S_h is symmetrised, (S_h + S_h^T)/2,
    the Hessian of 1/2 z^T S_h z whatever the round-off asymmetry of S_h.

    Parameters
    ----------
    problem
        A :class:`coupling.problem.SignoriniProblem` on one rank.
    """

    def __init__(self, problem: SignoriniProblem):
        from dolfinx import fem

        require_serial(problem.comm)
        s_h = dense_matrix(problem.S, "the assembled Hessian of the SNES VI / TAO Newton peers")
        self.forms = problem.forms
        b = problem.boundary
        n_u = problem.V.dofmap.index_map.size_local
        n_s = problem.n_signorini
        n = n_u + n_s
        self.n = n
        self._jacobian = self.forms.create_matrix()
        self.forms.assemble_jacobian(fem.Function(problem.V), self._jacobian)
        k_indptr, k_indices, _ = self._jacobian.getValuesCSR()  # sorted columns per row
        k_indptr = k_indptr.astype(np.int64)
        k_indices = k_indices.astype(np.int64)
        k_len = np.diff(k_indptr)
        k_rows = np.repeat(np.arange(n_u), k_len)
        # the dense block: block index p <-> unknown idx[p] <-> boundary position inv[p]
        idx = np.concatenate([b.dofs, n_u + np.arange(n_s)]).astype(np.int64)
        inv = np.concatenate([np.arange(b.n_gamma), b.signorini]).astype(np.int64)
        order = np.argsort(idx)
        idx, inv = idx[order], inv[order]
        m = idx.size
        in_block = np.zeros(n, dtype=bool)
        in_block[idx] = True
        # D^2G entries of block rows whose column is outside the block: "extra" columns
        in_block_row = in_block[k_rows]
        extra = in_block_row & ~in_block[k_indices]
        row_len = np.zeros(n, dtype=np.int64)
        row_len[:n_u] = k_len
        row_len[idx] = m + np.bincount(k_rows[extra], minlength=n)[idx]
        indptr = np.concatenate([[0], np.cumsum(row_len)])
        nnz = int(indptr[-1])
        # position of every D^2G entry: its rank in the row (outside the block: the
        # D^2G row itself; in a block row: block columns before it + extras before it)
        rank = np.arange(k_indices.size) - k_indptr[k_rows]
        extras_before = np.cumsum(extra) - extra
        extras_before -= np.concatenate([[0], np.cumsum(extra)])[k_indptr[:-1]][k_rows]
        merged_rank = np.searchsorted(idx, k_indices) + extras_before
        k_pos = indptr[k_rows] + np.where(in_block_row, merged_rank, rank)
        indices = np.empty(nnz, dtype=PETSc.IntType)
        values = np.zeros(nnz)
        indices[k_pos] = k_indices
        s_sym = 0.5 * (s_h + s_h.T)
        extra_cols = k_indices[extra]
        extra_ptr = np.concatenate([[0], np.cumsum(np.bincount(k_rows[extra], minlength=n))])
        for p, row in enumerate(idx):
            cols = extra_cols[extra_ptr[row] : extra_ptr[row + 1]]
            pos = indptr[row] + np.arange(m) + np.searchsorted(cols, idx)
            indices[pos] = idx
            values[pos] = s_sym[inv[p], inv]
        self._k_pos = k_pos
        self._k_base = values[k_pos].copy()  # the dense part at the D^2G positions
        self._indptr = indptr.astype(PETSc.IntType)
        self._indices = indices
        self._values = values
        self.matrix = PETSc.Mat().createAIJWithArrays(
            (n, n), (self._indptr, self._indices, self._values), comm=PETSc.COMM_SELF
        )
        self.matrix.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        self.matrix.assemble()
        self.nnz = nnz

    def assemble(self, u: Any) -> PETSc.Mat:
        """H at the state ``u`` (dolfinx Function) into :attr:`matrix`; returns it."""
        self.forms.assemble_jacobian(u, self._jacobian)
        _, _, k_values = self._jacobian.getValuesCSR()
        self._values[self._k_pos] = self._k_base + k_values
        self.matrix.assemble()  # marks the shared arrays as changed (state increase)
        return self.matrix

    def destroy(self) -> None:
        self._jacobian.destroy()
        self.matrix.destroy()
