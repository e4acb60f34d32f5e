"""The ``exact`` preconditioner: the diagonal blocks of the linear form A of (4.2).

    A(xi, eta) = (grad u, grad w) + < S_h (u|Gamma + phi), w|Gamma + psi >        (4.2)

B_Omega = K + T^T S_h T (K the Laplace stiffness matrix) and M_s = E^T S_h E are
factored directly. The coupling block T^T S_h E is left out so that B keeps the block
structure (3.18) that makes the projection act on phi alone; the two diagonal blocks
of an SPD matrix are spectrally equivalent to it (the constant depends on the angle
between u-traces and gaps in the A norm, not on h). It is the reference against which
the substructuring preconditioner is compared, and costs a sparse factorisation with
a dense n_gamma x n_gamma block: for small problems only.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg

from coupling.preconditioners.base import DenseSignoriniBlock

__all__ = ["ExactPreconditioner"]


class ExactPreconditioner(DenseSignoriniBlock):
    """B = diag(K + T^T S T, E^T S E), factored (same interface as the others).

    Parameters
    ----------
    stiffness
        (N, N) P1 Laplace stiffness matrix K (scipy sparse).
    boundary_dofs
        (n_gamma,) dofs of the boundary nodes in boundary order (T).
    signorini
        (n_s,) boundary positions of the phi unknowns (E).
    steklov_poincare
        Dense S_h (n_gamma x n_gamma).
    """

    def __init__(
        self,
        stiffness: sp.spmatrix,
        boundary_dofs: np.ndarray,
        signorini: np.ndarray,
        steklov_poincare: np.ndarray,
    ):
        n = stiffness.shape[0]
        dofs = np.asarray(boundary_dofs)
        rows, cols = np.meshgrid(dofs, dofs, indexing="ij")
        boundary_block = sp.csr_matrix(
            (steklov_poincare.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n)
        )
        self._omega = (sp.csr_matrix(stiffness) + boundary_block).tocsc()
        self._omega_factor = scipy.sparse.linalg.splu(self._omega)
        self.n_omega = n
        super().__init__(steklov_poincare[np.ix_(signorini, signorini)])

    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        return self._omega_factor.solve(np.asarray(g, dtype=float))

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        return self._omega @ u

    def destroy(self) -> None:
        pass
