"""The pencil (H, B) of the spectral parts, H = A of (4.2) or D^2 J_h(xi_h), and its
extreme eigenvalues in the B inner product."""
from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from coupling.distributed import dense_matrix, gather_matrix
from coupling.preconditioners import Preconditioner
from coupling.problem import SignoriniProblem

__all__ = ["PencilOperators", "jacobian_at", "stiffness_matrix", "DENSE_MAX"]

#: Largest pencil (u and phi unknowns) solved by a dense eigensolver as a check.
DENSE_MAX = 1200


class PencilOperators:
    """The pencil (H, B) on xi = (u, phi_F), W = [T E_F] (docs/method.md section 4):

        H = K + W^T S_h W,     B = diag(B_Omega, omega M_s restricted to F),

    with K the Laplace stiffness (H = A of (4.2)) or the Jacobian D^2 G(u_h) (H = D^2 J_h
    at xi_h), B = ``preconditioner`` (built for ``problem``) and F the phi unknowns in ``free``
    (all by default; the unknowns off the contact set for the face on which the
    projected iteration moves once the contact set is found).
    """

    def __init__(
        self,
        problem: SignoriniProblem,
        preconditioner: Preconditioner,
        K: sp.csr_matrix,
        free: np.ndarray | None = None,
    ):
        b = problem.boundary
        pc = preconditioner
        n_s = problem.n_signorini
        free = np.ones(n_s, bool) if free is None else np.asarray(free, bool)
        E = b.extension_matrix()[:, np.flatnonzero(free)]
        self.W = sp.hstack([b.trace_matrix(), E]).tocsr()
        self.N = K.shape[0]
        self.n = self.N + int(free.sum())
        self.K = K
        self.S = problem.S
        self.pc = pc
        metric = np.asarray(pc.signorini_metric)[np.ix_(free, free)]
        self.M_s = metric
        self.M_factor = sla.cho_factor(metric) if metric.size else None
        self.matvecs = 0

    def h(self, z: np.ndarray) -> np.ndarray:
        self.matvecs += 1
        out = self.W.T @ (self.S @ (self.W @ z))
        out[: self.N] += self.K @ z[: self.N]
        return out

    def b(self, z: np.ndarray) -> np.ndarray:
        return np.concatenate([self.pc.matvec_omega(z[: self.N]), self.M_s @ z[self.N :]])

    def b_inv(self, z: np.ndarray) -> np.ndarray:
        phi = sla.cho_solve(self.M_factor, z[self.N :]) if self.M_factor else z[self.N :]
        return np.concatenate([self.pc.apply_omega(z[: self.N]), phi])

    def extremes(self, tol: float = 1e-8) -> tuple[float, float]:
        """lambda_min, lambda_max of H x = lambda B x: ARPACK Lanczos in the B inner
        product (mode 2: B^{-1} applied exactly), as tests/test_preconditioner_spectral.py."""
        op = lambda f: spla.LinearOperator((self.n, self.n), matvec=f, dtype=float)  # noqa: E731
        h, b, b_inv = op(self.h), op(self.b), op(self.b_inv)
        ncv = min(40, self.n - 1)
        lam = [
            spla.eigsh(
                h, k=1, M=b, Minv=b_inv, which=w, tol=tol, ncv=ncv, return_eigenvectors=False
            )[0]
            for w in ("SA", "LA")
        ]
        return float(lam[0]), float(lam[1])

    def dense_extremes(self) -> tuple[float, float]:
        """The same by a dense generalized eigensolver (small problems: a check)."""
        W = self.W.toarray()
        H = W.T @ dense_matrix(self.S, "the dense pencil check") @ W
        H[: self.N, : self.N] += self.K.toarray()
        B = sla.block_diag(self.pc.matvec_omega(np.eye(self.N)), self.M_s)
        lam = sla.eigh(0.5 * (H + H.T), 0.5 * (B + B.T), eigvals_only=True)
        return float(lam[0]), float(lam[-1])


def stiffness_matrix(problem: SignoriniProblem) -> sp.csr_matrix:
    """K, the Laplace stiffness matrix of the problem's P1 space, as scipy CSR."""
    stiffness = problem.forms.assemble_stiffness()
    matrix = gather_matrix(stiffness)
    stiffness.destroy()
    return matrix


def jacobian_at(problem: SignoriniProblem, solution: Any) -> sp.csr_matrix:
    """D^2 G(u_h), the Jacobian of the interior form at the computed u_h, as scipy CSR."""
    jac = problem.forms.create_matrix()
    problem.forms.assemble_jacobian(solution.u, jac)
    matrix = gather_matrix(jac)
    jac.destroy()
    return matrix
