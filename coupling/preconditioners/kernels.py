"""Building blocks shared by the substructuring preconditioners (METHOD.md section 6):
factors computed once, the block-diagonal edge forms, the two-level form
B = (I - P R)^T A0 (I - P R) + R^T C R, the coarse matrix C and the arc-length
interpolation Pi along coarse edges.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from petsc4py import PETSc
from threadpoolctl import threadpool_limits

from coupling.preconditioners.edge_forms import edge_form
from fem_py.polyline import arc_length

__all__ = [
    "SparseFactor",
    "DenseFactor",
    "block_diagonal_edge_forms",
    "TwoLevelForm",
    "coarse_matrix",
    "edge_weights",
]


class SparseFactor:
    """Sparse Cholesky factor of an SPD matrix, computed once (PETSc built-in, nested
    dissection; chosen by measurement, docs/design/preconditioners.md). Works on
    ``PETSc.COMM_SELF``: the factor is rank-local.
    """

    def __init__(self, matrix: sp.spmatrix) -> None:
        m = sp.csr_matrix(matrix, dtype=float)
        self.n = m.shape[0]
        self._ksp = None
        self._alive = True
        if self.n == 0:
            return
        self._mat = PETSc.Mat().createAIJ(
            size=m.shape,
            csr=(m.indptr.astype(PETSc.IntType), m.indices.astype(PETSc.IntType), m.data),
            comm=PETSc.COMM_SELF,
        )
        self._mat.setOption(PETSc.Mat.Option.SPD, True)
        self._ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        self._ksp.setOperators(self._mat)
        self._ksp.setType("preonly")
        pc = self._ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("petsc")
        pc.setFactorOrdering("nd")
        self._ksp.setUp()
        self._factor = pc.getFactorMatrix()
        self._rhs, self._sol = self._mat.createVecs()

    def solve(self, b: np.ndarray) -> np.ndarray:
        """A^{-1} b for b of shape (n,) or (n, k)."""
        if not self._alive:
            raise RuntimeError("this factor has been destroyed; build a new preconditioner")
        if self._ksp is None:  # empty matrix
            return np.zeros_like(b, dtype=float)
        if b.ndim == 1:
            self._rhs.array[:] = b
            self._factor.solve(self._rhs, self._sol)
            return self._sol.array.copy()
        out = np.zeros(b.shape, order="F")
        rhs = PETSc.Mat().createDense(
            b.shape, array=np.asfortranarray(b, dtype=float), comm=PETSc.COMM_SELF
        )
        sol = PETSc.Mat().createDense(b.shape, array=out, comm=PETSc.COMM_SELF)
        self._factor.matSolve(rhs, sol)
        rhs.destroy()
        sol.destroy()
        return np.ascontiguousarray(out)

    def destroy(self) -> None:
        """Free the PETSc objects (call on every rank)."""
        if self._ksp is not None:
            for obj in (self._rhs, self._sol, self._ksp, self._mat):
                obj.destroy()
            self._ksp = None
        self._alive = False


class DenseFactor:
    """Dense Cholesky factor of a small SPD matrix (LAPACK), computed once."""

    def __init__(self, matrix: np.ndarray) -> None:
        self._factor = sla.cho_factor(matrix, lower=True) if matrix.size else None

    def solve(self, b: np.ndarray) -> np.ndarray:
        return (
            sla.cho_solve(self._factor, b)
            if self._factor is not None
            else np.zeros_like(b, dtype=float)
        )

    def destroy(self) -> None:
        pass


def block_diagonal_edge_forms(
    groups: Sequence[tuple[np.ndarray, np.ndarray]], n: int, kind: str
) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """All edge forms A^0_gamma and their inverses as two block-diagonal n x n sparse matrices.

    Each group is ``(ix, pts)`` for a batch of edges with equal node counts: ``ix (B, m)``
    the (local) numbers of the interior nodes, ``pts (B, m+2, dim)`` the nodes with both ends.
    """
    rows, cols, vals, ivals = [], [], [], []
    batches: dict[tuple, list] = {}  # one batch per shape: one edge_form call each
    for ix, pts in groups:
        if ix.shape[1]:
            batches.setdefault(pts.shape[1:], []).append((ix, pts))
    # tiny batched LAPACK calls: threads only add overhead (docs/design/preconditioners.md)
    with threadpool_limits(limits=1):
        for batch in batches.values():
            ix = np.concatenate([b[0] for b in batch])
            a0, a0_inv = edge_form(np.concatenate([b[1] for b in batch]), kind)
            rows.append(np.broadcast_to(ix[:, :, None], a0.shape).ravel())
            cols.append(np.broadcast_to(ix[:, None, :], a0.shape).ravel())
            vals.append(a0.ravel())
            ivals.append(a0_inv.ravel())
    if not rows:
        return sp.csr_matrix((n, n)), sp.csr_matrix((n, n))
    r, c = np.concatenate(rows), np.concatenate(cols)
    a0 = sp.csr_matrix((np.concatenate(vals), (r, c)), shape=(n, n))
    a0_inv = sp.csr_matrix((np.concatenate(ivals), (r, c)), shape=(n, n))
    return a0, a0_inv


class TwoLevelForm:
    """The SPD form B = (I - P R)^T A0 (I - P R) + R^T C R on n nodes, with
    B^{-1} = A0^{-1} + P C^{-1} P^T.

    This is the skeleton part B_Sk of B_Omega and the Signorini matrix M_s alike
    (METHOD.md section 6): in the basis {edge-interior hats} U {P e_c} the form is
    block diagonal, diag(A0, C), so B^{-1} needs only the edge inverses and C^{-1}.

    Parameters
    ----------
    a0, a0_inv : (n, n) sparse, block-diagonal edge forms on the edge-interior nodes
        (zero rows and columns at the coarse nodes) and their block inverses.
    interp : (n, n_c) sparse P, coarse values -> node values (unit rows at the coarse nodes).
    coarse_nodes : (n_c,) node number of each coarse unknown (R picks these).
    coarse : (n_c, n_c) SPD; a dense ndarray gets a dense Cholesky factor, a sparse
        matrix a sparse one.
    """

    def __init__(
        self,
        a0: sp.spmatrix,
        a0_inv: sp.spmatrix,
        interp: sp.spmatrix,
        coarse_nodes: np.ndarray,
        coarse: np.ndarray | sp.spmatrix,
    ) -> None:
        n, n_c = interp.shape
        restrict = sp.csr_matrix((np.ones(n_c), (np.arange(n_c), coarse_nodes)), shape=(n_c, n))
        q = (sp.identity(n, format="csr") - interp @ restrict).tocsr()
        self.matrix = (q.T @ a0 @ q + restrict.T @ sp.csr_matrix(coarse) @ restrict).tocsr()
        self.a0_inv = sp.csr_matrix(a0_inv)
        self.interp = sp.csr_matrix(interp)
        self.interp_t = self.interp.T.tocsr()
        self.n = n
        self._coarse = (
            SparseFactor(coarse) if sp.issparse(coarse) else DenseFactor(np.asarray(coarse))
        )

    def matvec(self, v: np.ndarray) -> np.ndarray:
        return self.matrix @ v

    def solve(self, r: np.ndarray) -> np.ndarray:
        return self.a0_inv @ r + self.interp @ self._coarse.solve(self.interp_t @ r)

    def destroy(self) -> None:
        self._coarse.destroy()


def coarse_matrix(coarse: Any, subdomain_size: float) -> sp.csc_matrix:
    """C of METHOD.md section 6: the coarse graph Laplacian + d * sum over the coarse
    vertices on Gamma, sum_{(v_i, v_j)} (u_i - u_j)^2 + d sum_{v on Gamma} u(v)^2."""
    ends = np.asarray(coarse.edge_vertices, dtype=np.int64)
    on_boundary = np.asarray(coarse.vertex_on_boundary, dtype=float)
    n_e, n_v = len(ends), len(on_boundary)
    incidence = sp.csr_matrix(
        (np.tile([1.0, -1.0], n_e), (np.repeat(np.arange(n_e), 2), ends.ravel())), shape=(n_e, n_v)
    )
    return (incidence.T @ incidence + sp.diags(subdomain_size * on_boundary)).tocsc()


def edge_weights(points: np.ndarray) -> np.ndarray:
    """Pi on the interior nodes of coarse edges (batch, n+1, dim): the arc-length position
    t in (0, 1) of every interior node; its value is (1 - t) u(end 0) + t u(end 1)."""
    s = arc_length(points)
    return s[:, 1:-1] / s[:, -1:]
