"""The coupled functional J_h of docs/method.md section 4, (2.4)-(2.5).

    J_h(u, phi) = G(u) + 1/2 z^T S_h z - b_f^T u - (m_t + s_0)^T z,   z = T u + E phi
    grad_u J    = A(u) + T^T (S_h z - m_t - s_0) - b_f
    grad_phi J  = E^T (S_h z - m_t - s_0)

u lives in a distributed PETSc vector (the DOLFINx P1 layout, owned entries then
ghosts), phi (for elasticity the gap unknowns g, z = T u + E g with the E of
``fem_py.boundary.blocked``) and the boundary block z are small and replicated on every rank, S_h is
dense: replicated in serial, held by rows under MPI (``coupling.distributed.RowBlocks``,
whose product returns the replicated S_h z). The trace T and its transpose
(``fem_py.boundary.BoundaryMap``) are index operations on the owned boundary dofs plus one
Allreduce.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from petsc4py import PETSc

from fem_py.boundary.blocked import GapMap, scalar_gap_map

__all__ = ["CoupledFunctional"]


class CoupledFunctional:
    """J_h(u, phi), its gradient and its Hessian action (docs/method.md (2.4)-(2.5)).

    Parameters
    ----------
    forms
        Interior forms (``fem_py.forms.InteriorForms``): G(u), DG(u, .), D^2 G(u).
    boundary
        ``fem_py.boundary.BoundaryMap``: T, T^T and the positions of the phi unknowns (E).
    steklov_poincare
        Dense S_h (n_gamma x n_gamma): an array, or ``coupling.distributed.RowBlocks``
        under MPI (anything with ``S @ z`` for a replicated vector z).
    load
        b_f (PETSc vector in the layout of u).
    boundary_load
        m_t + s_0 in boundary order (n_gamma,), replicated.
    gap
        E (``fem_py.boundary.blocked.GapMap``): the gap unknowns' directions in the boundary
        vectors; default the scalar equation's, phi at the boundary's ``signorini`` nodes.
    """

    def __init__(
        self,
        forms,
        boundary,
        steklov_poincare: np.ndarray,
        load: PETSc.Vec,
        boundary_load: np.ndarray,
        gap: GapMap | None = None,
    ):
        self.forms = forms
        self.boundary = boundary
        self.gap = scalar_gap_map(boundary) if gap is None else gap
        self.S = steklov_poincare
        self.load = load
        self.boundary_load = np.asarray(boundary_load, dtype=float)
        self.comm = forms.comm

    # -- the boundary block -------------------------------------------------------
    def boundary_block(self, u: PETSc.Vec, phi: np.ndarray) -> np.ndarray:
        """z = T u + E phi."""
        z = self.boundary.gather(u)
        return self.gap.extend(z, phi)

    # -- J_h and its derivatives --------------------------------------------------
    def _boundary_terms(self, u: PETSc.Vec, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """z = T u + E phi and y = S_h z - m_t - s_0 (one S_h product)."""
        z = self.boundary_block(u, phi)
        return z, self.S @ z - self.boundary_load

    def _value(self, u_function, z: np.ndarray, y: np.ndarray) -> float:
        """J_h = G(u) - b_f^T u + 1/2 z^T (y - m_t - s_0)."""
        return (
            self.forms.energy(u_function)
            - u_function.vector.dot(self.load)
            + 0.5 * z @ (y - self.boundary_load)
        )

    def _gradient(self, u_function, y: np.ndarray, grad_u: PETSc.Vec) -> np.ndarray:
        """grad_u J = A(u) - b_f + T^T y into ``grad_u``; returns grad_phi J = E^T y."""
        self.forms.assemble_residual(u_function, grad_u)
        grad_u.axpy(-1.0, self.load)
        self.boundary.scatter_add(y, grad_u, refresh_ghosts=False)
        return self.gap.restrict(y)

    def value(self, u_function, phi: np.ndarray) -> float:
        """J_h(u, phi) (collective)."""
        return self._value(u_function, *self._boundary_terms(u_function.vector, phi))

    def gradient(self, u_function, phi: np.ndarray, grad_u: PETSc.Vec) -> np.ndarray:
        """Fill ``grad_u`` with grad_u J_h and return grad_phi J_h (collective)."""
        return self._gradient(u_function, self._boundary_terms(u_function.vector, phi)[1], grad_u)

    def value_and_gradient(
        self, u_function, phi: np.ndarray, grad_u: PETSc.Vec
    ) -> tuple[float, np.ndarray]:
        """(J_h, grad_phi J_h) with ``grad_u`` filled, sharing one S_h product."""
        z, y = self._boundary_terms(u_function.vector, phi)
        return self._value(u_function, z, y), self._gradient(u_function, y, grad_u)

    def hessian_action(
        self,
        jacobian: Any,
        e_u: PETSc.Vec,
        e_phi: np.ndarray,
        out_u: PETSc.Vec,
        *,
        solver_tol: float | None = None,
    ) -> np.ndarray:
        """(out_u, return) = D^2 J_h (e_u, e_phi), with D^2 G given as the matrix ``jacobian``
        (a ``fem_py.forms.P1Matrix`` or a PETSc Mat: its ``mult``).

        ``solver_tol``: the relative residual of the V solve inside an H-matrix S_h's
        product (``bem_cpp.SteklovPoincareOperator.apply``; None: its own); a dense S_h
        has none and ignores it."""
        z = self.boundary_block(e_u, e_phi)
        y = (
            self.S @ z
            if solver_tol is None or not hasattr(self.S, "apply")
            else self.S.apply(z, solver_tol)
        )
        jacobian.mult(e_u, out_u)
        self.boundary.scatter_add(y, out_u, refresh_ghosts=False)
        return self.gap.restrict(y)
