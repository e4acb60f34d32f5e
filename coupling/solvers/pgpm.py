"""The preconditioned projection-gradient method, Algorithm 3.1 of docs/method.md section 5.

With the block preconditioner B = B_Omega + B_s ((3.18)-(3.22)):

    u_{k+1}   = u_k - tau R_Omega,       B_Omega R_Omega = grad_u J_h(u_k, phi_k)     (3.21)
    phi_{k+1} = P_s(phi_k - tau R_s),    M_s R_s = grad_phi J_h(u_k, phi_k)          (3.22)

stopped when ||xi_{k+1} - xi_k||_B <= tol ||xi_{k+1}||_B. The step tau = 1/C0 with C0
the largest eigenvalue of B^{-1} D^2 J_h(xi_0), estimated by Lanczos in the B inner
product (:mod:`coupling.solvers.lanczos`).
"""
from __future__ import annotations

import numpy as np

from coupling.solvers.loop import IterationContext, Loop
from coupling.solvers.records import RunResult, b_norm2, set_owned

__all__ = ["pgpm", "energy_increased"]


def energy_increased(old: float, new: float) -> bool:
    """J_h went up by more than round-off (13 digits relative)."""
    return new - old > 1e-13 * (abs(old) + abs(new))


def pgpm(context: IterationContext, phi0: np.ndarray, *, tau: float) -> RunResult:
    """Run Algorithm 3.1 ((3.3)-(3.4), in the block form (3.21)-(3.22)).

    xi_{k+1} = P(xi_k - tau B^{-1} DJ_h(xi_k)), stopped when
    ||xi_{k+1} - xi_k||_B <= tol ||xi_{k+1}||_B. B_Omega u is carried along by
    B u_{k+1} = B u_k - tau grad_u J(xi_k), exact by (3.21), so the B norms cost no
    extra solve. For tau <= 1/C0 and J_h c0-strongly convex in the B metric (3.5), the
    prox-gradient inequality (Beck 2017, First-Order Methods in Optimization, Thm 10.16)
    gives ||xi_{k+1} - xi_h||_B <= (1 + 2 / (tau c0)) ||xi_{k+1} - xi_k||_B.

    Parameters
    ----------
    context
        J_h, B, P_s, the Function u (u_0 on entry, u_h on exit), ``tol``,
        ``max_iterations``, the monitor and ``backtrack``: when a step would increase
        J_h (tau too large for the current state), halve tau and redo it; every increase
        is counted in the result either way.
    phi0
        phi_0 (negative entries are set to 0).
    tau
        Step length (1/C0).
    """
    functional, preconditioner, projection = (
        context.functional,
        context.preconditioner,
        context.projection,
    )
    comm, u_function = context.comm, context.u
    grad = u_function.vector.duplicate()
    u_k = u_function.vector.array_r.copy()
    phi_k = projection.feasible(np.asarray(phi0, dtype=float))
    energy, g_phi = functional.value_and_gradient(u_function, phi_k, grad)
    g_u = grad.array_r.copy()
    b_u = preconditioner.matvec_omega(u_k)
    loop = Loop(context, "||xi_k+1 - xi_k||_B <= {tol:g} ||xi_k+1||_B")
    for k in loop.steps():
        r_u = preconditioner.apply_omega(g_u)
        r_phi = preconditioner.apply_signorini(g_phi)
        while True:
            set_owned(u_function, u_k - tau * r_u)
            projected = projection(phi_k - tau * r_phi, phi_k)
            if comm.size > 1:  # one copy of phi: rank 0's (round-off may differ by rank)
                projected = comm.bcast(projected, root=0)
            new_energy, new_g_phi = functional.value_and_gradient(u_function, projected.phi, grad)
            increased = energy_increased(energy, new_energy)
            loop.increases += int(increased)
            if not (increased and context.backtrack and tau > 1e-12):
                break
            tau *= 0.5
        u_new = u_function.vector.array_r.copy()
        b_new = b_u - tau * g_u
        d_u, d_phi = u_new - u_k, projected.phi - phi_k
        m_d_phi = preconditioner.matvec_signorini(d_phi)
        norm2 = b_norm2(
            comm, u_new, b_new, projected.phi, preconditioner.matvec_signorini(projected.phi)
        )
        step2 = b_norm2(comm, d_u, b_new - b_u, d_phi, m_d_phi)
        g_u, g_phi = grad.array_r.copy(), new_g_phi
        u_k, phi_k, b_u, energy = u_new, projected.phi, b_new, new_energy
        loop.end_step(
            k, energy, step2, norm2, phi_k, tau, projection_iterations=projected.iterations
        )
    return loop.result(phi_k, energy, tau, release=(grad,))
