"""Spectral estimates in the B inner product (docs/method.md (3.5)): the step tau = 1/C0 of
the gradient methods, and the smallest Ritz value from which APGPM sets its momentum.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg

from coupling.solvers.records import global_dot
from fem_py.dofs import input_indices

__all__ = ["estimate_extremes", "extremes_at"]


def estimate_extremes(
    functional, preconditioner, jacobian: Any, n_phi: int, *, steps: int, seed: int = 0
) -> tuple[float, float]:
    """The smallest and the largest Ritz value of a ``steps``-step Lanczos recurrence for
    the pencil (D^2 J_h(xi), B) (docs/method.md (3.5); D^2 G(xi) given as ``jacobian``).

    They bracket the spectrum from inside: the smallest Ritz value is an upper bound of
    lambda_min(B^{-1} D^2 J_h(xi)), the largest a lower bound of lambda_max (C0). The
    largest approaches lambda_max from below, quickly for the extreme eigenvalue; tau =
    1/C0 from it keeps tau below 2/lambda_max (the limit of descent) unless the estimate
    is off by a factor 2, which 20 steps never are.

    The recurrence keeps p_j = B q_j so that only B^{-1} is needed:
    r = B^{-1} H q_j - alpha q_j - beta q_{j-1},  B r = H q_j - alpha p_j - beta p_{j-1}.
    """
    comm = functional.comm
    work = functional.forms.create_vector()
    # the same start vector for any number of ranks: drawn in the input numbering
    V = functional.forms.V
    rng = np.random.default_rng(seed)
    bs, nodes = V.dofmap.index_map_bs, input_indices(V)[: V.dofmap.index_map.size_local]
    p_u = rng.standard_normal(work.getSize())[(bs * nodes[:, None] + np.arange(bs)).ravel()]
    p_phi = rng.standard_normal(n_phi)
    q_u, q_phi = preconditioner.apply_omega(p_u), preconditioner.apply_signorini(p_phi)
    norm = np.sqrt(global_dot(comm, q_u, p_u) + q_phi @ p_phi)
    q_u, q_phi, p_u, p_phi = q_u / norm, q_phi / norm, p_u / norm, p_phi / norm
    p_prev_u, p_prev_phi = np.zeros_like(p_u), np.zeros_like(p_phi)
    alphas, betas, beta = [], [], 0.0
    e_u = functional.forms.create_vector()
    for _ in range(steps):
        e_u.array[:] = q_u
        h_phi = functional.hessian_action(jacobian, e_u, q_phi, work)
        h_u = work.array_r.copy()
        alpha = global_dot(comm, q_u, h_u) + q_phi @ h_phi
        bu = h_u - alpha * p_u - beta * p_prev_u
        bphi = h_phi - alpha * p_phi - beta * p_prev_phi
        r_u = preconditioner.apply_omega(bu)
        r_phi = preconditioner.apply_signorini(bphi)
        alphas.append(alpha)
        beta = np.sqrt(max(global_dot(comm, r_u, bu) + r_phi @ bphi, 0.0))
        if beta < 1e-12 * abs(alpha):
            break
        betas.append(beta)
        p_prev_u, p_prev_phi = p_u, p_phi
        q_u, q_phi, p_u, p_phi = r_u / beta, r_phi / beta, bu / beta, bphi / beta
    ritz = scipy.linalg.eigvalsh_tridiagonal(np.array(alphas), np.array(betas[: len(alphas) - 1]))
    e_u.destroy(), work.destroy()
    return float(ritz[0]), float(ritz[-1])


def extremes_at(
    functional,
    preconditioner,
    u_function,
    n_phi: int,
    *,
    steps: int,
    matrix: Any = None,
) -> tuple[float, float]:
    """:func:`estimate_extremes` with D^2 G assembled at the current u, into ``matrix``
    (the caller's P1 matrix: a ``fem_py.forms.P1Matrix`` or a PETSc Mat) or into a new
    P1Matrix."""
    jacobian = functional.forms.create_p1_matrix() if matrix is None else matrix
    functional.forms.assemble_jacobian(u_function, jacobian)
    try:
        return estimate_extremes(functional, preconditioner, jacobian, n_phi, steps=steps)
    finally:
        if matrix is None:
            jacobian.destroy()
