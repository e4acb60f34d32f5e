"""The supernodal sparse Cholesky factor of bem_cpp (bem/sparse_cholesky.hpp).

A symmetric positive definite matrix is factored as P A P^T = L L^T by the multifrontal
method: columns of L with one row structure (supernodes) are factored together as dense
fronts with LAPACK, which on the nested-dissection ordering of a planar graph puts most
of the work into dense BLAS-3 kernels. The fill-reducing ordering is the caller's.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

import bem_cpp._bem as _bem

__all__ = ["SparseCholesky"]


class SparseCholesky:
    """L L^T = P A P^T of a sparse SPD matrix, computed once.

    Parameters
    ----------
    matrix
        The n x n matrix; scipy.sparse, with both triangles of its symmetric pattern.
    ordering
        ``ordering[i]`` is the row of ``matrix`` that becomes row i (a permutation of
        0..n-1), a fill-reducing one such as nested dissection.
    n_schur
        The last ``n_schur`` rows of ``ordering`` (the set S, in that order) are not
        eliminated sparsely: the other rows H are, and S's block becomes the dense Schur
        complement A_SS - A_SH A_HH^{-1} A_HS (:attr:`schur`). :meth:`solve` solves with
        it; :meth:`eliminate` and :meth:`back_substitute` leave the S block to the caller.

    Raises
    ------
    ValueError
        A matrix that is not square, an ordering that is not a permutation, or
        ``n_schur`` outside 0..n.
    numpy.linalg.LinAlgError
        A matrix that is not positive definite.
    """

    def __init__(self, matrix: sp.spmatrix, ordering: ArrayLike, n_schur: int = 0) -> None:
        m = sp.csr_matrix(matrix, dtype=float)
        if m.shape[0] != m.shape[1]:
            raise ValueError(f"the matrix must be square, got shape {m.shape}")
        self.n = m.shape[0]
        try:
            self._factor = _bem.SparseCholesky(
                self.n,
                m.indptr.astype(np.int64, copy=False),
                m.indices.astype(np.int64, copy=False),
                np.ascontiguousarray(m.data),
                np.asarray(ordering, dtype=np.int64),
                int(n_schur),
            )
        except _bem.NotPositiveDefinite as error:  # malformed input: ValueError as it is
            raise np.linalg.LinAlgError(str(error)) from None

    @property
    def factor_nonzeros(self) -> int:
        """Entries of L held (the supernodes' dense blocks, explicit zeros included)."""
        return int(self._factor.factor_nonzeros)

    @property
    def schur(self) -> NDArray[np.float64]:
        """A_SS - A_SH A_HH^{-1} A_HS, (n_schur, n_schur), S in the ordering's order."""
        return self._factor.schur

    def solve(self, b: ArrayLike) -> NDArray[np.float64]:
        """A^{-1} b for b of shape (n,) or (n, k)."""
        return self._sweep(self._factor.solve, b)

    def eliminate(self, b: ArrayLike) -> NDArray[np.float64]:
        """The forward sweep over H: b_S - A_SH A_HH^{-1} b_H on S, intermediate values on
        H for :meth:`back_substitute`."""
        return self._sweep(self._factor.eliminate, b)

    def back_substitute(self, w: ArrayLike) -> NDArray[np.float64]:
        """x from :meth:`eliminate`'s w with w_S replaced by x_S: x_H = A_HH^{-1} (b_H -
        A_HS x_S), x_S as given."""
        return self._sweep(self._factor.back_substitute, w)

    def _sweep(self, sweep, b: ArrayLike) -> NDArray[np.float64]:
        b = np.asarray(b, dtype=float)
        if b.shape[:1] != (self.n,) or b.ndim > 2:
            raise ValueError(f"b must have shape ({self.n},) or ({self.n}, k), got {b.shape}")
        return sweep(np.asfortranarray(b.reshape(self.n, -1))).reshape(b.shape)
