"""Semismooth Newton (primal-dual active set) for the discrete problem (2.3): our extension.

Optimality system of min J_h(u, phi) over phi >= 0 (METHOD.md sections 4-5), written
with the natural residual of one PGPM step in the metric M_s of B_s ((3.19), (3.22)):

    grad_u J = 0,   phi = P_s(phi - tau M_s^{-1} grad_phi J)

(P_s the M_s-orthogonal projection onto {phi >= 0}, tau = 1/C0; at the minimiser this
is (2.5)). At each outer step the Signorini nodes split into the predicted active set
A = {P_s(phi - tau M_s^{-1} grad_phi J) = 0} (the gap is closed: phi_A = 0) and the
inactive set I (grad_phi J_I = 0). The Newton step solves, with H = D^2 J_h at the iterate,

    H_[(u,I),(u,I)] (du, dphi_I) = -(grad_u J, grad_phi J_I) - H_[(u,I),A] dphi_A,
    dphi_A = -phi_A,

by preconditioned CG: H is applied as a product (the interior Jacobian, assembled once
per step, plus S_h on the boundary block), the preconditioner is the
substructuring B restricted to the inactive set (B_Omega^{-1} for u, M_s[I, I]^{-1} for
phi_I). The CG tolerance follows the Newton residual r = (||grad_u J||_{B_Omega^{-1}}^2
+ ||phi - P_s(phi - tau M_s^{-1} grad_phi J)||_{M_s}^2 / tau^2)^{1/2} (inexact Newton,
forcing term min(0.1, (r_k / r_0)^p), p = 1/2 from a cold start and p = 1 from a given
iterate (``forcing_exponent``), kept above c tol ||xi_k||_B / (tau r_k) with
c = OVERSOLVE_SAFEGUARD: no step is solved more accurately than the stopping rule needs,
the safeguard of Kelley, Iterative Methods for Linear and Nonlinear Equations, 1995,
section 6.3). tau r is the B-norm of the PGPM step from the iterate ((3.19) with the
exact projection), so the iteration stops as soon as that step meets the PGPM rule
||step||_B <= tol ||xi||_B with the active set unchanged: the answer is one that PGPM
would accept, without the confirming Newton step the rule on the Newton step itself
would take. After a Newton step of relative B-norm at most SSN_JACOBIAN_REUSE_STEP the
next step keeps the Jacobian (D^2 G is Lipschitz in u, so the stale Jacobian perturbs
the step by a relative O(that norm), about the CG tolerance of such a late step).
Globalisation: backtracking on J_h along the projected path (u + a du, max(0, phi + a
dphi)); a step that does not decrease J_h after 30 halvings is replaced by a PGPM step.
A few PGPM steps start the iteration.

The active set is predicted in the metric M_s, by the M_s projection of
phi - tau M_s^{-1} grad_phi J (the active set of a PGPM step), not by the
componentwise rule A = {phi - c grad_phi J <= 0}, whose edge retreats by a bounded
number of nodes per step and so needs O(1/h) steps (docs/design/solvers.md). At the
solution the prediction is exact, {phi = 0} (phi is the fixed point of the PGPM step),
so the local convergence of the active-set Newton method is kept.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.linalg
from mpi4py import MPI

from coupling.functional import CoupledFunctional
from coupling.options import OVERSOLVE_SAFEGUARD, SSN_JACOBIAN_REUSE_STEP
from coupling.solvers.pgpm import energy_increased, pgpm
from coupling.solvers.projection import SignoriniProjection
from coupling.solvers.records import (
    History,
    Monitor,
    RunResult,
    b_norm2,
    global_dot,
    relative_step,
    set_owned,
)

__all__ = ["semismooth_newton"]


def _pcg(
    apply_h: Callable,
    apply_b_inv: Callable,
    rhs: tuple[np.ndarray, np.ndarray],
    comm: MPI.Comm,
    *,
    rtol: float,
    max_iterations: int,
):
    """Preconditioned CG on the pair (u owned entries, phi_I replicated).

    The vectors are updated in place through one work buffer per part (x += alpha p as
    w = alpha p, x += w): the same floating-point operations as x + alpha p, without
    new arrays of 10^6 entries every iteration; p starts as a copy of z, so that no
    in-place update can reach an array apply_b_inv returned or was given)."""
    dot = lambda a, b: global_dot(comm, a[0], b[0]) + a[1] @ b[1]  # noqa: E731
    x = (np.zeros_like(rhs[0]), np.zeros_like(rhs[1]))
    r = (rhs[0].copy(), rhs[1].copy())
    work = (np.empty_like(rhs[0]), np.empty_like(rhs[1]))
    z = apply_b_inv(r)
    p = (z[0].copy(), z[1].copy())
    rz = dot(r, z)
    stop = rtol * np.sqrt(max(rz, 0.0))
    for it in range(1, max_iterations + 1):
        hp = apply_h(p)
        alpha = rz / dot(p, hp)
        for k in (0, 1):
            np.add(x[k], np.multiply(alpha, p[k], out=work[k]), out=x[k])
            np.subtract(r[k], np.multiply(alpha, hp[k], out=work[k]), out=r[k])
        z = apply_b_inv(r)
        rz_new = dot(r, z)
        if np.sqrt(max(rz_new, 0.0)) <= stop:
            return x, it
        beta = rz_new / rz
        for k in (0, 1):
            np.add(z[k], np.multiply(beta, p[k], out=p[k]), out=p[k])
        rz = rz_new
    return x, max_iterations


def _predict(preconditioner, predictor, comm, g_u, g_phi, phi, tau):
    """The active-set prediction P_s(phi - tau M_s^{-1} grad_phi J) and the Newton residual
    r = (||grad_u J||^2_{B_Omega^{-1}} + ||phi - prediction||^2_{M_s} / tau^2)^{1/2}."""
    predicted = predictor(phi - tau * preconditioner.apply_signorini(g_phi), phi).phi
    if comm.size > 1:  # one copy of the replicated unknowns
        predicted = comm.bcast(predicted, root=0)
    natural = phi - predicted  # tau times the projected B_s-gradient
    residual = np.sqrt(
        global_dot(comm, g_u, preconditioner.apply_omega(g_u))
        + natural @ preconditioner.matvec_signorini(natural) / tau**2
    )
    return predicted, residual


def zero_residual(functional, preconditioner, u_function, n_phi: int, tau: float) -> float:
    """The Newton residual r at xi = (0, 0): the scale of the problem's residuals (for
    ``residual_scale``; ``u_function`` is left as it was)."""
    comm = functional.comm
    saved = u_function.vector.array_r.copy()
    set_owned(u_function, np.zeros_like(saved))
    grad = u_function.vector.duplicate()
    phi = np.zeros(n_phi)
    g_phi = functional.gradient(u_function, phi, grad)
    predictor = SignoriniProjection.exact(preconditioner.signorini_metric)
    _, residual = _predict(preconditioner, predictor, comm, grad.array_r.copy(), g_phi, phi, tau)
    grad.destroy()
    set_owned(u_function, saved)
    return float(residual)


def semismooth_newton(
    functional: CoupledFunctional,
    preconditioner,
    projection: SignoriniProjection,
    forms,
    u_function,
    phi0: np.ndarray,
    *,
    tau: float,
    tol: float,
    max_iterations: int,
    start_steps: int,
    cg_max_iterations: int,
    forcing_exponent: float,
    residual_scale: float | None = None,
    monitor: Monitor | None = None,
    matrix=None,
) -> RunResult:
    """Semismooth Newton on the optimality system, started by ``start_steps`` PGPM steps.

    The active set is predicted by a PGPM step in the M_s metric with the exact
    projection (module docstring). Stops when that PGPM step from the Newton iterate xi_k
    meets the rule of the PGPM, ||step||_B = tau r_k <= tol ||xi_k||_B, with the active
    set unchanged by the last Newton step, or when a Newton step itself has
    ||xi_{k+1} - xi_k||_B <= tol ||xi_{k+1}||_B with an unchanged active set, or after
    ``max_iterations`` outer steps in all (the PGPM steps included). The records of the
    Newton steps hold their CG iterations and the length taken along the Newton direction.

    The CG tolerance of a step is min(0.1, (r / r_0)^p) times the residual r (module
    docstring), p = ``forcing_exponent``, r_0 the residual of the first Newton step, or
    ``residual_scale`` when given: from a start already close to the solution (nested
    iteration) r_0 of the problem's own scale (:func:`zero_residual`) keeps the steps
    from being limited to a contraction of 0.1 each.

    ``matrix`` (optional, the caller's, from ``forms.create_matrix()``) holds the
    Jacobians of the Newton steps; by default a new Mat is created and destroyed here.
    """
    comm = functional.comm
    history = History(monitor)
    warm = pgpm(
        functional,
        preconditioner,
        projection,
        u_function,
        phi0,
        tau=tau,
        tol=tol,
        max_iterations=min(start_steps, max_iterations),
        monitor=monitor,
    )
    history.extend(warm.history)
    if warm.converged or warm.iterations >= max_iterations:
        return warm
    phi = warm.phi
    grad = u_function.vector.duplicate()
    jacobian = forms.create_matrix() if matrix is None else matrix
    e_u, h_u = jacobian.createVecRight(), jacobian.createVecRight()
    energy, g_phi = functional.value_and_gradient(u_function, phi, grad)
    # the exact M_s-projection predicts the active set (an inexact one would blur it); the
    # solver's own projection serves when it is exact (one factor of M_s and of its inverse)
    predictor = (
        projection
        if projection.method == "exact"
        else SignoriniProjection.exact(preconditioner.signorini_metric)
    )
    residual0 = residual_scale
    increases = warm.energy_increases
    active = np.zeros(phi.size, dtype=bool)
    b_u = None  # B_Omega u_k, updated by the steps
    norm2 = relative = None  # ||xi_k||_B^2 and ||xi_k - xi_k-1||_B / ||xi_k||_B after a Newton step
    stop_measure = None  # ||PGPM step at xi_k||_B / ||xi_k||_B when that test stops the run
    reason, converged, k = f"reached max_iterations = {max_iterations}", False, warm.iterations
    for k in range(warm.iterations + 1, max_iterations + 1):
        g_u = grad.array_r.copy()
        predicted, residual = _predict(preconditioner, predictor, comm, g_u, g_phi, phi, tau)
        new_active = predicted <= 0.0
        active_changed = not np.array_equal(new_active, active)
        if norm2 is not None and not active_changed and tau * residual <= tol * np.sqrt(norm2):
            # the PGPM step from xi_k (B-norm tau r) meets the PGPM rule: no further step
            converged, k = True, k - 1
            stop_measure = tau * residual / np.sqrt(norm2)
            reason = f"||PGPM step at xi_k||_B <= {tol:g} ||xi_k||_B, active set settled"
            break
        active, free = new_active, ~new_active
        residual0 = residual if residual0 is None else residual0
        if relative is None or relative > SSN_JACOBIAN_REUSE_STEP:
            forms.assemble_jacobian(u_function, jacobian)
        metric_free = preconditioner.signorini_metric[np.ix_(free, free)]
        factor = scipy.linalg.cho_factor(metric_free) if free.any() else None

        def hessian(e_u_owned: np.ndarray, e_phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            e_u.array[:] = e_u_owned
            h_phi = functional.hessian_action(jacobian, e_u, e_phi, h_u)
            return h_u.array_r.copy(), h_phi

        def apply_h(p):
            e_phi = np.zeros(phi.size)
            e_phi[free] = p[1]
            h_u_owned, h_phi = hessian(p[0], e_phi)
            return h_u_owned, h_phi[free]

        def apply_b_inv(r):
            return (
                preconditioner.apply_omega(r[0]),
                scipy.linalg.cho_solve(factor, r[1]) if factor is not None else r[1],
            )

        d_phi = np.zeros(phi.size)
        d_phi[active] = -phi[active]
        h_a_u, h_a_phi = hessian(np.zeros_like(g_u), d_phi)
        rhs = (-g_u - h_a_u, -g_phi[free] - h_a_phi[free])
        forcing = min(0.1, (residual / residual0) ** forcing_exponent)
        if norm2 is not None:  # no more accuracy than the stopping rule asks for
            forcing = max(forcing, OVERSOLVE_SAFEGUARD * tol * np.sqrt(norm2) / (tau * residual))
        (d_u, d_phi_free), cg_its = _pcg(
            apply_h, apply_b_inv, rhs, comm, rtol=forcing, max_iterations=cg_max_iterations
        )
        d_phi[free] = d_phi_free
        if comm.size > 1:  # one copy of the replicated unknowns
            d_phi = comm.bcast(d_phi, root=0)

        u_old = u_function.vector.array_r.copy()
        step = 1.0
        for _ in range(30):
            set_owned(u_function, u_old + step * d_u)
            trial_phi = np.maximum(0.0, phi + step * d_phi)
            trial_energy, trial_g_phi = functional.value_and_gradient(u_function, trial_phi, grad)
            if not energy_increased(energy, trial_energy):
                break
            increases += 1
            step *= 0.5
        else:  # no decrease along the Newton path: fall back to one PGPM step
            set_owned(u_function, u_old)
            run = pgpm(
                functional,
                preconditioner,
                projection,
                u_function,
                phi,
                tau=tau,
                tol=0.0,
                max_iterations=1,
            )
            trial_phi, trial_energy = run.phi, run.energy
            trial_g_phi = functional.gradient(u_function, trial_phi, grad)
            step = 0.0
        d_u_taken = u_function.vector.array_r - u_old
        d_phi_taken = trial_phi - phi
        b_d_u = preconditioner.matvec_omega(d_u_taken)
        step2 = b_norm2(
            comm, d_u_taken, b_d_u, d_phi_taken, preconditioner.matvec_signorini(d_phi_taken)
        )
        # B_Omega u_k+1 = B_Omega u_k + B_Omega du: one product per step for both norms
        b_u = preconditioner.matvec_omega(u_old) + b_d_u if b_u is None else b_u + b_d_u
        u_now = u_function.vector.array_r
        norm2 = b_norm2(comm, u_now, b_u, trial_phi, preconditioner.matvec_signorini(trial_phi))
        phi, energy, g_phi = trial_phi, trial_energy, trial_g_phi
        relative = relative_step(step2, norm2)
        history.step(k, energy, relative, phi, tau, cg_iterations=cg_its, line_search=step)
        if relative <= tol and not active_changed:
            converged = True
            reason = f"||xi_k+1 - xi_k||_B <= {tol:g} ||xi_k+1||_B, active set settled"
            break
    for obj in (grad, e_u, h_u) + ((jacobian,) if matrix is None else ()):
        obj.destroy()
    return history.result(
        phi,
        converged=converged,
        reason=reason,
        iterations=k,
        energy=energy,
        tau=tau,
        energy_increases=increases,
        stop_measure=stop_measure,
    )
