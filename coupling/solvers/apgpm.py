"""The accelerated projection-gradient method (APGPM, our extension of Algorithm 3.1).

The PGPM step of docs/method.md (3.21)-(3.22) taken from the extrapolated point
y_k = xi_k + beta (xi_k - xi_{k-1}), all in the B metric, with Nesterov's constant
momentum for strongly convex functions,

    beta = (1 - sqrt(q)) / (1 + sqrt(q)),   q = tau mu / MU_SAFETY,

(1/q bounds the condition number of (3.5) seen by the step tau; mu an estimate of
lambda_min(B^{-1} D^2 J_h)). Two restarts (O'Donoghue and Candes 2015): if
J_h(xi_{k+1}) > J_h(xi_k) the step is discarded and a plain PGPM step is taken from
xi_k instead (so J_h decreases monotonically, as for PGPM); if the gradient-mapping test
(y_k - xi_{k+1})^T B (xi_{k+1} - xi_k) > 0 fails (the momentum points uphill), the next
step is a plain one. Either way the momentum resumes the step after. The count scales
like sqrt(kappa) instead of kappa.

The method stops on the gradient mapping at the point the step is taken from,
||xi_{k+1} - y_k||_B <= tol ||xi_{k+1}||_B. By the prox-gradient inequality (Beck 2017,
Thm 10.16) this gives ||xi_{k+1} - xi_h||_B <= (1 + 2 / (tau c0)) ||xi_{k+1} - y_k||_B,
the a-posteriori bound of PGPM at the same tol. (The difference of consecutive APGPM
iterates also contains the momentum beta (xi_k - xi_{k-1}) and is not an optimality
measure.)
"""
from __future__ import annotations

import numpy as np

from coupling.solvers.loop import IterationContext, Loop
from coupling.solvers.pgpm import energy_increased
from coupling.solvers.records import RunResult, b_norm2, global_dot, set_owned

__all__ = ["apgpm", "MU_SAFETY", "momentum"]

#: The Lanczos estimate of lambda_min(B^{-1} D^2 J_h(xi_0)) is divided by this factor: the
#: smallest Ritz value lies above lambda_min, and D^2 J_h changes along the iteration. Too
#: small a mu only slows the momentum by sqrt(factor); too large a mu loses the
#: acceleration (measurements: docs/design/solvers.md).
MU_SAFETY = 2.0


def momentum(tau: float, mu: float) -> float:
    """beta = (1 - sqrt(q)) / (1 + sqrt(q)), q = tau mu / MU_SAFETY = 1/kappa (Nesterov's
    constant momentum for a mu-strongly convex function with 1/tau-Lipschitz gradient)."""
    root = np.sqrt(min(max(tau * mu / MU_SAFETY, 0.0), 1.0))
    return float((1.0 - root) / (1.0 + root))


def apgpm(
    context: IterationContext, phi0: np.ndarray, *, tau: float, strong_convexity: float
) -> RunResult:
    """Run APGPM (module docstring) from (context.u, phi0).

    Parameters
    ----------
    context, phi0, tau
        As for :func:`coupling.solvers.pgpm.pgpm`; the stopping rule is
        ||xi_{k+1} - y_k||_B <= tol ||xi_{k+1}||_B.
    strong_convexity
        mu, an estimate of lambda_min(B^{-1} D^2 J_h): the smallest Ritz value of
        :func:`coupling.solvers.lanczos.estimate_extremes`, computed with C0.
    """
    if not strong_convexity > 0.0:
        raise ValueError(
            f"strong_convexity must be > 0 (lambda_min of B^-1 D^2 J_h), " f"got {strong_convexity}"
        )
    functional, preconditioner, projection = (
        context.functional,
        context.preconditioner,
        context.projection,
    )
    comm, u_function = context.comm, context.u
    mu = strong_convexity
    grad = u_function.vector.duplicate()
    u_k = u_function.vector.array_r.copy()
    phi_k = projection.feasible(np.asarray(phi0, dtype=float))
    energy, g_phi = functional.value_and_gradient(u_function, phi_k, grad)
    g_u, gradient_at_xi_k = grad.array_r.copy(), True
    b_u = preconditioner.matvec_omega(u_k)  # carried along, as in PGPM
    u_prev, phi_prev, b_prev, with_momentum = u_k, phi_k, b_u, False
    loop = Loop(context, "||xi_k+1 - y_k||_B <= {tol:g} ||xi_k+1||_B")
    for k in loop.steps():
        beta = momentum(tau, mu) if with_momentum else 0.0
        restarted = False
        while True:
            y_u, y_phi, b_y = (
                u_k + beta * (u_k - u_prev),
                phi_k + beta * (phi_k - phi_prev),
                b_u + beta * (b_u - b_prev),
            )
            if beta > 0.0 or not gradient_at_xi_k:
                set_owned(u_function, y_u)
                g_phi = functional.gradient(u_function, y_phi, grad)
                g_u, gradient_at_xi_k = grad.array_r.copy(), beta == 0.0
            r_u = preconditioner.apply_omega(g_u)
            r_phi = preconditioner.apply_signorini(g_phi)
            set_owned(u_function, y_u - tau * r_u)
            projected = projection(y_phi - tau * r_phi, phi_k)
            if comm.size > 1:  # one copy of phi: rank 0's (round-off may differ by rank)
                projected = comm.bcast(projected, root=0)
            new_energy = functional.value(u_function, projected.phi)
            increased = energy_increased(energy, new_energy)
            loop.increases += int(increased)
            if increased and beta > 0.0:  # function restart: a plain step from xi_k
                beta, restarted = 0.0, True
            elif increased and context.backtrack and tau > 1e-12:
                tau *= 0.5
            else:
                break
        u_new = u_function.vector.array_r.copy()
        b_new = b_y - tau * g_u
        d_phi = projected.phi - phi_k
        m_d_phi = preconditioner.matvec_signorini(d_phi)
        norm2 = b_norm2(
            comm, u_new, b_new, projected.phi, preconditioner.matvec_signorini(projected.phi)
        )
        # gradient mapping xi_{k+1} - y_k; B (u_{k+1} - y_u) = -tau grad_u J(y_k)
        m_phi = projected.phi - y_phi
        step2 = b_norm2(
            comm, u_new - y_u, b_new - b_y, m_phi, preconditioner.matvec_signorini(m_phi)
        )
        # gradient restart: momentum that points uphill in the B metric is dropped
        uphill = (global_dot(comm, y_u - u_new, b_new - b_u) - m_phi @ m_d_phi) > 0.0
        with_momentum = not (uphill or restarted)
        gradient_at_xi_k = False
        u_prev, phi_prev, b_prev = u_k, phi_k, b_u
        u_k, phi_k, b_u, energy = u_new, projected.phi, b_new, new_energy
        loop.end_step(
            k, energy, step2, norm2, phi_k, tau, projection_iterations=projected.iterations
        )
    return loop.result(phi_k, energy, tau, release=(grad,))
