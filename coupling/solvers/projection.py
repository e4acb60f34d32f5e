"""The B_s-orthogonal projection onto K = {phi >= 0}: docs/method.md (3.19), (3.20) and (3.6).

    P_s(phi~) = argmin_{psi >= 0} (psi - phi~)^T M_s (psi - phi~)

``inexact`` is the paper's projected iteration (3.20)::

    phi^{i+1} = max(0, phi^i - theta M_s (phi^i - phi~)),   phi^0 = phi_k,

with theta = 1 / lambda_max(M_s) (inside (0, 2/lambda_max)), stopped as soon as the
accuracy condition (3.6) is certified, or at a cap. With q(psi) = ||psi - phi~||^2_{M_s}
(3.6) reads q(phi^i) <= rho_in q(phi_k) + (1 - rho_in) q*, q* = q(P phi~) unknown. Weak
duality gives, for any lambda >= 0, q* >= -lambda^T phi~ - lambda^T M_s^{-1} lambda / 4;
with lambda = max(0, 2 M_s (phi^i - phi~)) this lower bound tends to q* as phi^i
converges, and using it in place of q* makes the test sufficient for (3.6). Theorem 3.1
then keeps the outer rate independent of h. (A rule on the size of the inner step is
not sufficient: docs/design/solvers.md.)
``exact`` solves the small dense QP to round-off by a primal-dual active-set
(semismooth Newton) iteration warm-started from the previous active set, with the
Lawson-Hanson NNLS method on the Cholesky factor as a fallback should it cycle.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable, NamedTuple, Protocol

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp

from bem_cpp.sparse import SparseCholesky
from coupling.options import METRIC_SPARSE_ROW_NONZEROS
from coupling.preconditioners.base import (
    cholesky_of,
    dense_metric,
    inverse_from_cholesky,
    largest_eigenvalue,
    solve_with_cholesky,
)

__all__ = ["SignoriniProjection", "ProjectionResult", "BlockFactor", "DenseBlockFactor"]


class BlockFactor(Protocol):
    """A factor of a principal block M_II of M_s (:meth:`SignoriniProjection.free_factor`)."""

    def solve(self, b: np.ndarray) -> np.ndarray:
        """M_II^{-1} b."""


class _InverseBlock(NamedTuple):
    """M_II^{-1} through M^{-1} (the projection's :meth:`SignoriniProjection._solve_free`)."""

    projection: "SignoriniProjection"
    free: np.ndarray

    def solve(self, b: np.ndarray) -> np.ndarray:
        full = np.zeros(self.free.size)
        full[self.free] = b
        return self.projection._solve_free(full, self.free)[self.free]


class DenseBlockFactor(NamedTuple):
    """A dense Cholesky factor, as ``scipy.linalg.cho_factor`` gives it."""

    factor: tuple[np.ndarray, bool]

    def solve(self, b: np.ndarray) -> np.ndarray:
        return solve_with_cholesky(self.factor, b)


@dataclass(frozen=True)
class ProjectionResult:
    """The projected vector and the inner iterations it took."""

    phi: np.ndarray
    iterations: int


class SignoriniProjection:
    """P_s, the M_s-orthogonal projection onto {phi >= 0}.

    Parameters
    ----------
    metric
        M_s, the dense SPD matrix of B_s (n_s x n_s).
    method
        ``"inexact"`` (3.20) or ``"exact"``.
    rho_in
        Relative stopping tolerance of (3.20), in [0, 1).
    max_iterations
        Cap on the inner iterations of (3.20).
    lambda_max
        Largest eigenvalue of M_s, or a function returning it (called, or computed from
        M_s when not given, on first use by ``inexact``).
    factor
        A function returning M_s's Cholesky factor as ``scipy.linalg.cho_factor`` gives it,
        called on first use, when the caller has one (the preconditioner's: not factored
        twice); the factor is read, never written. Without it (and without ``inverse``) the
        projection factors M_s itself when it first needs to solve with it.
    inverse
        A function returning M_s^{-1}, when the caller computes it once for both (the
        preconditioner's, :class:`coupling.preconditioners.base.DenseSignoriniBlock`);
        else the exact projection computes its own from the factor when it first needs it.
    bounded
        (n_s,) bool: the entries constrained to be >= 0; the others are free (the
        tangential slips of elasticity, ``fem_py.boundary.blocked``). Default: all.
    """

    def __init__(
        self,
        metric: np.ndarray,
        method: str,
        *,
        rho_in: float,
        max_iterations: int,
        lambda_max: float | Callable[[], float] | None = None,
        factor: Callable[[], tuple[np.ndarray, bool]] | None = None,
        inverse: Callable[[], np.ndarray] | None = None,
        bounded: np.ndarray | None = None,
    ):
        if method not in ("inexact", "exact"):
            raise ValueError(f'projection must be "inexact" or "exact", got {method!r}')
        self.M = dense_metric(metric)
        self.method = method
        self.rho_in = rho_in
        self.max_iterations = max_iterations
        n = self.M.shape[0]
        self.bounded = np.ones(n, dtype=bool) if bounded is None else np.asarray(bounded, bool)
        self._lambda_max = lambda_max
        self._theta: float | None = None if n > 0 else 0.0
        if factor is None and inverse is None:
            factor = lambda: cholesky_of(self.M)  # noqa: E731
        # M's Cholesky factor, from _factor_of on first use (the exact projection of an
        # iterate with active nodes never needs it)
        self._factor_of = factor
        self._factor: tuple[np.ndarray, bool] | None = None
        self._free: tuple[np.ndarray, BlockFactor] | None = None  # I, M_II's factor
        self._kept_active: tuple[np.ndarray, tuple[np.ndarray, bool]] | None = None  # I, W_AA's
        self._active: np.ndarray | None = None  # of the last exact projection
        self._inverse: np.ndarray | None = None  # M^{-1}, for the exact projection
        self._factorised_flops = 0.0  # of the M_II factorisations done instead of buying W
        self._inverse_of = inverse or (lambda: inverse_from_cholesky(self._cholesky()))

    @classmethod
    def exact(cls, metric: np.ndarray, bounded: np.ndarray | None = None) -> "SignoriniProjection":
        """The exact projection (it has no tolerance or cap)."""
        return cls(metric, "exact", rho_in=0.0, max_iterations=0, bounded=bounded)

    def feasible(self, phi: np.ndarray) -> np.ndarray:
        """phi with its bounded entries clipped at 0: the pointwise projection onto K in the
        Euclidean metric (a new array)."""
        return np.where(self.bounded, np.maximum(phi, 0.0), phi)

    def in_contact(self, phi: np.ndarray) -> np.ndarray:
        """The bounded entries of phi that are 0 (the discrete contact set), one per entry
        of ``phi[bounded]``."""
        return phi[self.bounded] <= 0.0

    def as_exact(self) -> "SignoriniProjection":
        """The exact projection in the same metric: this one when it is exact, else one that
        shares its Cholesky factor of M_s and M_s^{-1} (nothing factored or inverted twice)."""
        if self.method == "exact":
            return self
        return SignoriniProjection(
            self.M,
            "exact",
            rho_in=0.0,
            max_iterations=0,
            factor=self._cholesky if self._factor_of is not None else None,
            inverse=self._inverse_matrix,
            bounded=self.bounded,
        )

    @property
    def theta(self) -> float:
        """The step 1 / lambda_max(M_s) of (3.20), computed on first use (only ``inexact``
        needs it)."""
        if self._theta is None:
            lam = self._lambda_max() if callable(self._lambda_max) else self._lambda_max
            if lam is None:
                lam = largest_eigenvalue(self.M)
            self._theta = 1.0 / float(lam)
        return self._theta

    def norm(self, v: np.ndarray) -> float:
        """||v||_{M_s}."""
        return float(np.sqrt(max(v @ (self.M @ v), 0.0)))

    def __call__(self, target: np.ndarray, start: np.ndarray) -> ProjectionResult:
        """Project ``target`` (phi~), starting from ``start`` (phi_k, feasible)."""
        if target.size == 0:
            return ProjectionResult(target.copy(), 0)
        if self.method == "exact":
            return self._exact(self.M @ target)
        return self._projected_iteration(target, start)

    def step(
        self,
        phi: np.ndarray,
        gradient: np.ndarray,
        tau: float,
        solve: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> ProjectionResult:
        """P_s(phi - tau M_s^{-1} gradient), the projected gradient step (3.19) from the
        feasible ``phi``. The exact projection reads the target only through
        M_s (phi - tau M_s^{-1} gradient) = M_s phi - tau gradient, so it solves nothing
        with M_s; the inexact one forms the target with ``solve`` (M_s^{-1}, the
        preconditioner's; default: its own)."""
        if phi.size == 0:
            return ProjectionResult(phi.copy(), 0)
        if self.method == "exact":
            return self._exact(self.M @ phi - tau * gradient)
        return self._projected_iteration(phi - tau * (solve or self._solve)(gradient), phi)

    def free_factor(self, free: np.ndarray) -> BlockFactor:
        """A Cholesky factor of M_II (I = ``free``, boolean). Where M_s is sparse but for a
        few dense rows (the two-level form's coarse nodes: ``METRIC_SPARSE_ROW_NONZEROS``),
        the other rows of I are eliminated sparsely and the dense ones through their
        dense Schur complement (:class:`bem_cpp.sparse.SparseCholesky`); else M_II is
        factored densely. The last one is kept: the exact projection's last free set is
        the prediction that a Newton step solves on, and the next prediction often keeps
        it (:func:`coupling.solvers.ssn.newton_direction`). Once the exact projection has
        bought W = M^{-1} (:meth:`_solve_free`) and fewer than half the nodes are active,
        M_II^{-1} is applied through W and W_AA's factor instead: the same block inverse,
        without a second dense n_s x n_s array."""
        if _kept_for(self._free, free):
            return self._free[1]
        self._free = None  # the old factor goes before the new one is made
        n_active = int(np.count_nonzero(~free))
        if self._inverse is not None and self._sparse is None and n_active < free.size - n_active:
            # W = M^{-1} is bought: M_II^{-1} through it and W_AA's factor, as the exact
            # projection solves (no second n_s^2 array: 0.27 GB at 48^3 elastic cubes)
            return _InverseBlock(self, free.copy())
        if self._sparse is None:
            factor: BlockFactor = DenseBlockFactor(_principal_cholesky(self.M, free))
        else:
            matrix, dense_row = self._sparse
            rows = np.flatnonzero(free)
            dense = dense_row[rows]
            factor = SparseCholesky(
                matrix[rows][:, rows],
                np.concatenate([np.flatnonzero(~dense), np.flatnonzero(dense)]),
                int(np.count_nonzero(dense)),
            )
        self._free = (free.copy(), factor)
        return factor

    @functools.cached_property
    def _sparse(self) -> tuple[sp.csr_matrix, np.ndarray] | None:
        """M as a sparse matrix and its dense rows, or None (:func:`_sparse_structure`),
        made on first use: the inexact projection never factors a block of M."""
        return _sparse_structure(self.M)

    def destroy(self) -> None:
        """Drop the kept factors of M_II and W_AA (n_s^2 and n_s^2 / 4 arrays at most)."""
        self._free = self._kept_active = None

    def _active_factor(self, free: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, bool]:
        """The Cholesky factor of W_AA (A: the nodes not ``free``). The last one is kept: an
        exact projection starts from the last one's active set (:meth:`_exact`)."""
        if _kept_for(self._kept_active, free):
            return self._kept_active[1]
        self._kept_active = None
        factor = _principal_cholesky(W, ~free)
        self._kept_active = (free.copy(), factor)
        return factor

    def _cholesky(self) -> tuple[np.ndarray, bool]:
        """M's Cholesky factor, made (or read from the caller's) on first use."""
        if self._factor is None:
            self._factor = self._factor_of()
        return self._factor

    def _solve(self, v: np.ndarray) -> np.ndarray:
        """M^{-1} v: through M^{-1} once it is there (or when it is all the caller gave),
        else the factor."""
        if self._inverse is not None or self._factor_of is None:
            return self._inverse_matrix() @ v
        return solve_with_cholesky(self._cholesky(), v)

    def _projected_iteration(self, target: np.ndarray, start: np.ndarray) -> ProjectionResult:
        """(3.20) from phi_k = ``start`` until (3.6) is certified by the dual bound."""
        M_target = self.M @ target
        residual = self.M @ start - M_target  # M_s (phi^i - phi~), one product per step
        q_start = (start - target) @ residual
        phi = start
        for i in range(1, self.max_iterations + 1):
            phi = self.feasible(phi - self.theta * residual)
            residual = self.M @ phi - M_target
            lam = np.where(self.bounded, np.maximum(0.0, 2.0 * residual), 0.0)
            m_inv_lam = self._solve(lam)
            q_lower = -lam @ target - 0.25 * lam @ m_inv_lam
            if (phi - target) @ residual <= (
                self.rho_in * q_start + (1.0 - self.rho_in) * max(q_lower, 0.0)
            ):
                return ProjectionResult(phi, i)
        return ProjectionResult(phi, self.max_iterations)

    def _inverse_matrix(self) -> np.ndarray:
        """W = M^{-1}: the caller's (``inverse``) or from the factor, computed once; the
        exact projection then drops its reference to the factor (W replaces it)."""
        if self._inverse is None:
            self._inverse = self._inverse_of()
            if self.method == "exact":
                self._factor = self._free = None
        return self._inverse

    def _solve_free(self, b: np.ndarray, free: np.ndarray) -> np.ndarray:
        """psi with psi_A = 0 and M_II psi_I = b_I (I = ``free``, A the rest).

        With few active nodes, through W = M^{-1} and the block-inverse identity
        (M_II)^{-1} = W_II - W_IA W_AA^{-1} W_AI: y = W (b on I, 0 on A),
        psi = y - W_:A W_AA^{-1} y_A (so psi_A = 0 exactly). This costs n^2 + |A|^3/3
        flops instead of |I|^3/3 for a factorisation of M_II, once W is there; W itself
        costs about n^3 (LAPACK's potri from the factor: 2.6 times the Cholesky's time,
        90 s at n = 16,129). So W is bought only once the factorisations of M_II done
        instead would have cost as much (rent or buy: at most twice the cheaper of the
        two whatever the number of calls); with no active node the factor of M solves.
        The last factors of M_II and of W_AA are kept (:meth:`free_factor`,
        :meth:`_active_factor`): the same free set again costs no factorisation.
        """
        n, n_active = b.size, int(np.count_nonzero(~free))
        n_free = n - n_active
        if n_active == n:
            return np.zeros(n)
        bought = self._inverse is not None
        if not bought and n_active == 0:
            return self._solve(b)
        kept = _kept_for(self._free, free)
        # W would serve (few active nodes) but is not bought yet: rent, i.e. factor M_II,
        # while the rents paid stay below W's price (a sparse M_s's factors are cheap:
        # always rented)
        rent = (
            not bought
            and n_active < n_free
            and (
                kept
                or self._sparse is not None
                or self._factorised_flops + n_free**3 / 3 <= float(n) ** 3
            )
        )
        if rent and not kept:
            self._factorised_flops += n_free**3 / 3
        if rent or n_active >= n_free:  # M_II's factor
            psi = np.zeros(n)
            psi[free] = self.free_factor(free).solve(b[free])
            return psi
        W = self._inverse_matrix()
        y = W @ np.where(free, b, 0.0)
        if n_active == 0:
            return y
        active = np.flatnonzero(~free)
        z = solve_with_cholesky(self._active_factor(free, W), y[active])
        psi = y - W[:, active] @ z
        psi[active] = 0.0
        return psi

    def _exact(self, b: np.ndarray) -> ProjectionResult:
        """Primal-dual active set on min 1/2 psi^T M psi - b^T psi over psi >= 0 (b = M phi~):
        psi_A = 0, M_II psi_I = b_I, lam = M psi - b, from the last projection's active set
        (the first one from {b <= 0}, exact for a diagonal M)."""
        M, n, bounded = self.M, b.size, self.bounded
        c = float(np.mean(M.diagonal()))
        active = self._active.copy() if self._active is not None else (b <= 0.0) & bounded
        for iteration in range(1, 4 * n + 10):
            free = ~active
            psi = self._solve_free(b, free)
            lam = M @ psi - b
            lam[free] = 0.0
            new_active = (lam - c * psi > 0) & bounded
            if np.array_equal(new_active, active):
                self._active = active
                return ProjectionResult(self.feasible(psi), iteration)
            active = new_active
        # The active-set iteration cycled (possible for matrices that are not M-matrices):
        # min ||L^T psi - L^{-1} b|| over psi >= 0, M = L L^T, a free entry the difference
        # of two nonnegative ones
        L = scipy.linalg.cholesky(np.asarray(M), lower=True)
        free_columns = L.T[:, ~bounded]
        split, _ = scipy.optimize.nnls(
            np.hstack([L.T, -free_columns]),
            scipy.linalg.solve_triangular(L, b, lower=True),
            maxiter=50 * n,
        )
        psi = split[:n]
        psi[~bounded] -= split[n:]
        self._active = (psi <= 0) & bounded
        return ProjectionResult(psi, iteration)


def _kept_for(kept: tuple[np.ndarray, object] | None, free: np.ndarray) -> bool:
    """Whether ``kept`` (a free set and the factor made for it, or None) is for ``free``."""
    return kept is not None and np.array_equal(kept[0], free)


def _sparse_structure(M: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray] | None:
    """M as a sparse matrix and its dense rows (more than ``METRIC_SPARSE_ROW_NONZEROS``
    nonzeros or a quarter of the row), when those are at most half of them; None for a
    dense M."""
    limit = min(METRIC_SPARSE_ROW_NONZEROS, M.shape[0] // 4)
    dense_row = np.count_nonzero(M, axis=1) > limit
    if np.count_nonzero(dense_row) > M.shape[0] // 2:
        return None
    return sp.csr_matrix(M), dense_row


def _principal_cholesky(matrix: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, bool]:
    """The Cholesky factor of the principal block of the symmetric ``matrix`` on ``rows``
    (boolean), as ``scipy.linalg.cho_factor`` gives it: factored in place through the
    transpose of the block's copy, a Fortran-ordered view (LAPACK would copy the
    C-ordered array)."""
    block = matrix[np.ix_(rows, rows)]
    return scipy.linalg.cho_factor(block.T, lower=True, overwrite_a=True)
