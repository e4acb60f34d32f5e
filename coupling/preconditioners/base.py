"""The interface of the block preconditioner B = B_Omega + B_s of the iterations
(docs/method.md (3.18)-(3.22)), and B = identity (Remark 2.1).
"""
from __future__ import annotations

from typing import Callable, Protocol

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from bem_cpp.dense import SingleMatrix, release_free_heap

__all__ = [
    "Preconditioner",
    "IdentityPreconditioner",
    "DenseSignoriniBlock",
    "check_length",
    "cholesky_of",
    "dense_metric",
    "largest_eigenvalue",
    "omega_cycle",
    "solve_with_cholesky",
]

#: Up to this size the largest eigenvalue of M_s comes from LAPACK, above it from Lanczos.
DENSE_EIGENVALUE_SIZE = 400


class Preconditioner(Protocol):
    """Interface of the block-diagonal preconditioner B = B_Omega + B_s used by the PGPM "
    "(3.21)-(3.22)."""

    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        ...  # B_Omega^{-1} g

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        ...  # B_Omega u

    def apply_signorini(self, g: np.ndarray) -> np.ndarray:
        ...  # M_s^{-1} g

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray:
        ...  # M_s phi

    @property
    def lambda_max_signorini(self) -> float:
        ...  # largest eigenvalue of M_s, for theta in (3.20)

    @property
    def signorini_metric(self) -> np.ndarray:
        ...  # M_s, dense (the metric of the projection (3.19))

    def destroy(self) -> None:
        ...  # free solver objects (PETSc) on every rank


def omega_cycle(preconditioner: Preconditioner) -> Callable[[np.ndarray], np.ndarray]:
    """The preconditioner's fixed approximation of B_Omega^{-1} for preconditioning a Krylov
    solve (the Newton steps' CG): its ``cycle_omega`` where it has one (one multigrid cycle,
    the same on any number of ranks), else ``apply_omega``."""
    return getattr(preconditioner, "cycle_omega", preconditioner.apply_omega)


class IdentityPreconditioner:
    """B = Euclidean inner product on R^N x R^{n_s} (plain projection-gradient, Remark 2.1).

    Parameters
    ----------
    n_omega : number N of fine nodes (length of u).
    n_signorini : number n_s of phi unknowns.
    """

    def __init__(self, n_omega: int, n_signorini: int) -> None:
        if n_omega < 1 or n_signorini < 0:
            raise ValueError(
                f"need n_omega >= 1 and n_signorini >= 0, got {n_omega}, {n_signorini}"
            )
        self.n_omega = int(n_omega)
        self.n_signorini = int(n_signorini)

    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        return check_length(g, self.n_omega, "g").copy()

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        return check_length(u, self.n_omega, "u").copy()

    def apply_signorini(self, g: np.ndarray) -> np.ndarray:
        return check_length(g, self.n_signorini, "g").copy()

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray:
        return check_length(phi, self.n_signorini, "phi").copy()

    @property
    def lambda_max_signorini(self) -> float:
        return 1.0

    @property
    def signorini_metric(self) -> np.ndarray:
        return np.eye(self.n_signorini)

    def destroy(self) -> None:
        pass


class DenseSignoriniBlock:
    """A Signorini block B_s given by its dense SPD matrix M_s (n_s x n_s), Cholesky-factored
    on first use:
    ``apply_signorini`` (M_s^{-1}), ``matvec_signorini``, ``lambda_max_signorini`` (computed
    on first use: only the inexact projection reads it) and ``signorini_metric`` of the
    interface, for preconditioners to inherit."""

    def __init__(self, metric: np.ndarray | SingleMatrix):
        self.signorini_metric = dense_metric(metric)
        self.n_signorini = self.signorini_metric.shape[0]
        self._lambda_max: float | None = None
        self._signorini_factor = None
        self._signorini_inverse: np.ndarray | None = None

    @property
    def signorini_factor(self) -> tuple[np.ndarray, bool] | None:
        """M_s's Cholesky factor (``scipy.linalg.cho_factor``'s), computed on first use (n_s^3/3
        flops and a second n_s^2 array, which a Newton step from an iterate with active nodes
        never needs: :meth:`coupling.solvers.projection.SignoriniProjection.step`), for the
        projection to share; None without Signorini unknowns, or once
        :attr:`signorini_inverse` has replaced it."""
        if self._signorini_factor is None and self._signorini_inverse is None and self.n_signorini:
            self._signorini_factor = cholesky_of(self.signorini_metric)
        return self._signorini_factor

    @property
    def signorini_inverse(self) -> np.ndarray:
        """M_s^{-1}, computed on first use from the factor, which it replaces (one n_s x n_s
        array instead of two; ``apply_signorini`` then multiplies by it, the flops of the
        two triangular solves): for the exact projection to share."""
        if self._signorini_inverse is None:
            self._signorini_inverse = (
                inverse_from_cholesky(self.signorini_factor)
                if self.n_signorini
                else np.zeros((0, 0))
            )
            self._signorini_factor = None
            release_free_heap()  # the factor's pages, which the C library may keep
        return self._signorini_inverse

    @property
    def lambda_max_signorini(self) -> float:
        if self._lambda_max is None:
            self._lambda_max = (
                largest_eigenvalue(self.signorini_metric) if self.n_signorini else 1.0
            )
        return self._lambda_max

    def apply_signorini(self, g: np.ndarray) -> np.ndarray:
        if not self.n_signorini:
            return np.zeros(0)
        if self._signorini_inverse is not None:
            return self._signorini_inverse @ g
        return solve_with_cholesky(self.signorini_factor, g)

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray:
        return self.signorini_metric @ phi


def dense_metric(metric: np.ndarray | SingleMatrix) -> np.ndarray | SingleMatrix:
    """A dense symmetric M_s as held: a :class:`bem_cpp.dense.SingleMatrix` as it is (single
    precision, applied in double); an array as float64 in C order, a Fortran-ordered one
    (Eigen's, from bem_cpp) as its transpose, a view of the same bytes, not copied (n_s^2
    doubles: 2.1 GB at 128^3 cubes)."""
    if isinstance(metric, SingleMatrix):
        return metric
    metric = np.asarray(metric, dtype=float)
    if metric.flags.f_contiguous and not metric.flags.c_contiguous:
        return metric.T
    return np.ascontiguousarray(metric)


def cholesky_of(metric: np.ndarray | SingleMatrix) -> tuple[np.ndarray, bool]:
    """The Cholesky factor (``scipy.linalg.cho_factor``'s) of a dense SPD M: of a float64
    copy factored in place for a :class:`bem_cpp.dense.SingleMatrix` (through its
    transpose, a Fortran-ordered view of the symmetric copy, which LAPACK takes as it is:
    the C-ordered copy would be copied once more), else of a copy."""
    if isinstance(metric, SingleMatrix):
        return scipy.linalg.cho_factor(metric.to_dense().T, lower=True, overwrite_a=True)
    return scipy.linalg.cho_factor(metric)


def solve_with_cholesky(factor: tuple[np.ndarray, bool], b: np.ndarray) -> np.ndarray:
    """M^{-1} b from M's Cholesky factor (``scipy.linalg.cho_factor``'s, as
    :func:`cholesky_of` gives it), without scipy's finiteness check of the factor: the
    factor came from a checked M, and the check reads all n^2 entries at every solve (2.1 s
    in 210 solves at n_s = 16,129)."""
    return scipy.linalg.cho_solve(factor, b, check_finite=False)


def inverse_from_cholesky(factor: tuple[np.ndarray, bool], block: int = 512) -> np.ndarray:
    """M^{-1} (n x n) from M's Cholesky factor (``scipy.linalg.cho_factor``'s (c, lower)),
    in one n x n array: LAPACK's potri on a copy of the factor, then the other triangle
    filled a block of columns at a time (no identity right-hand side, no triangle-index
    arrays: the n x n temporaries of ``cho_solve(factor, eye(n))``)."""
    c, lower = factor
    inverse, info = scipy.linalg.lapack.dpotri(c, lower=lower, overwrite_c=False)
    if info != 0:
        raise np.linalg.LinAlgError(f"potri failed (info {info}): M_s is not positive definite")
    n = inverse.shape[0]
    for j in range(0, n, block):  # copy the computed triangle into the other one
        k = min(j + block, n)
        if lower:  # rows below the block hold (M^{-1})[k:, j:k]; mirror it to [j:k, k:]
            inverse[j:k, k:] = inverse[k:, j:k].T
        else:
            inverse[k:, j:k] = inverse[j:k, k:].T
        d = inverse[j:k, j:k]
        d[...] = np.tril(d) + np.tril(d, -1).T if lower else np.triu(d) + np.triu(d, 1).T
    return inverse


def largest_eigenvalue(matrix) -> float:
    """The largest eigenvalue of a symmetric matrix (dense or scipy sparse): LAPACK up to
    DENSE_EIGENVALUE_SIZE rows, else Lanczos (ARPACK, relative tolerance 1e-10), started
    from a fixed pseudo-random vector: every rank computes the same number, and the start
    has a component along the top eigenvector (a symmetric start such as the ones vector
    can miss it on a symmetric mesh)."""
    n = matrix.shape[0]
    if n <= DENSE_EIGENVALUE_SIZE:
        dense = matrix.toarray() if hasattr(matrix, "toarray") else np.asarray(matrix)
        return float(scipy.linalg.eigvalsh(dense, subset_by_index=[n - 1, n - 1])[0])
    top = scipy.sparse.linalg.eigsh(
        matrix,
        k=1,
        which="LA",
        return_eigenvectors=False,
        tol=1e-10,
        v0=np.random.default_rng(0).standard_normal(n),
    )
    return float(top[0])


def check_length(v: np.ndarray, n: int, name: str) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    if v.ndim not in (1, 2) or v.shape[0] != n:
        raise ValueError(f"{name} must have shape ({n},) or ({n}, k), got {v.shape}")
    return v
