"""The preconditioned projection-gradient method, Algorithm 3.1 of METHOD.md section 5.

With the block preconditioner B = B_Omega + B_s ((3.18)-(3.22)):

    u_{k+1}   = u_k - tau R_Omega,       B_Omega R_Omega = grad_u J_h(u_k, phi_k)     (3.21)
    phi_{k+1} = P_s(phi_k - tau R_s),    M_s R_s = grad_phi J_h(u_k, phi_k)          (3.22)

stopped when ||xi_{k+1} - xi_k||_B <= tol ||xi_{k+1}||_B. The step tau = 1/C0 with C0
the largest eigenvalue of B^{-1} D^2 J_h(xi_0), estimated by Lanczos in the B inner
product (:func:`estimate_step`; :func:`estimate_extremes` also returns the smallest Ritz
value, from which the accelerated variant sets its momentum).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.linalg
from mpi4py import MPI
from petsc4py import PETSc

from coupling.functional import CoupledFunctional
from coupling.projection import SignoriniProjection

__all__ = ["IterationRecord", "RunResult", "estimate_extremes", "estimate_step",
           "projection_gradient"]


@dataclass(frozen=True)
class IterationRecord:
    """One PGPM step: J_h after it, the step norm of the stopping rule
    ||xi_{k+1} - y_k||_B / ||xi_{k+1}||_B (y_k = xi_k for PGPM, the extrapolated point for
    APGPM), the number of Signorini nodes in contact, the inner projection iterations
    and tau used."""

    iteration: int
    energy: float
    step_norm: float
    contact: int
    inner: int
    tau: float


@dataclass
class RunResult:
    """Outcome of an iterative solve (u is left in the Function passed in)."""

    phi: np.ndarray
    converged: bool
    reason: str
    iterations: int
    energy: float
    tau: float
    history: list[IterationRecord] = field(default_factory=list)
    energy_increases: int = 0
    solve_time: float = 0.0


def _dot(comm: MPI.Comm, a: np.ndarray, b: np.ndarray) -> float:
    return comm.allreduce(float(a @ b), op=MPI.SUM)


def estimate_step(functional: CoupledFunctional, preconditioner, jacobian: PETSc.Mat,
                  n_phi: int, *, steps: int = 20, seed: int = 0) -> float:
    """Estimate C0 = lambda_max(B^{-1} D^2 J_h(xi_0)) by Lanczos in the B inner product.

    The largest Ritz value of a ``steps``-step Lanczos recurrence for the pencil
    (D^2 J_h, B) is returned (:func:`estimate_extremes`). It approaches lambda_max from
    below, quickly for the extreme eigenvalue; tau = 1/C0 from it keeps tau below
    2/lambda_max (the limit of descent) unless the estimate is off by a factor 2, which
    20 steps never are.
    """
    return estimate_extremes(functional, preconditioner, jacobian, n_phi, steps=steps,
                             seed=seed)[1]


def estimate_extremes(functional: CoupledFunctional, preconditioner, jacobian: PETSc.Mat,
                      n_phi: int, *, steps: int = 20, seed: int = 0) -> tuple[float, float]:
    """The smallest and the largest Ritz value of a ``steps``-step Lanczos recurrence for
    the pencil (D^2 J_h(xi), B) (METHOD.md (3.5); D^2 G(xi) given as ``jacobian``).

    They bracket the spectrum from inside: the smallest Ritz value is an upper bound of
    lambda_min(B^{-1} D^2 J_h(xi)), the largest a lower bound of lambda_max (C0).

    The recurrence keeps p_j = B q_j so that only B^{-1} is needed:
    r = B^{-1} H q_j - alpha q_j - beta q_{j-1},  B r = H q_j - alpha p_j - beta p_{j-1}.
    """
    comm = functional.comm
    work = jacobian.createVecRight()
    r0, r1 = work.getOwnershipRange()
    # the same start vector for any number of ranks (iterates independent of P)
    rng = np.random.default_rng(seed)
    p_u = rng.standard_normal(work.getSize())[r0:r1]
    p_phi = rng.standard_normal(n_phi)
    q_u, q_phi = preconditioner.apply_omega(p_u), preconditioner.apply_signorini(p_phi)
    norm = np.sqrt(_dot(comm, q_u, p_u) + q_phi @ p_phi)
    q_u, q_phi, p_u, p_phi = q_u / norm, q_phi / norm, p_u / norm, p_phi / norm
    p_prev_u, p_prev_phi = np.zeros_like(p_u), np.zeros_like(p_phi)
    alphas, betas, beta = [], [], 0.0
    e_u = jacobian.createVecRight()
    for _ in range(steps):
        e_u.array[:] = q_u
        h_phi = functional.hessian_action(jacobian, e_u, q_phi, work)
        h_u = work.array_r.copy()
        alpha = _dot(comm, q_u, h_u) + q_phi @ h_phi
        bu = h_u - alpha * p_u - beta * p_prev_u
        bphi = h_phi - alpha * p_phi - beta * p_prev_phi
        r_u = preconditioner.apply_omega(bu)
        r_phi = preconditioner.apply_signorini(bphi)
        alphas.append(alpha)
        beta = np.sqrt(max(_dot(comm, r_u, bu) + r_phi @ bphi, 0.0))
        if beta < 1e-12 * abs(alpha):
            break
        betas.append(beta)
        p_prev_u, p_prev_phi = p_u, p_phi
        q_u, q_phi, p_u, p_phi = r_u / beta, r_phi / beta, bu / beta, bphi / beta
    ritz = scipy.linalg.eigvalsh_tridiagonal(np.array(alphas), np.array(betas[:len(alphas) - 1]))
    e_u.destroy(), work.destroy()
    return float(ritz[0]), float(ritz[-1])


def _set_owned(u_function, owned: np.ndarray) -> None:
    """Copy owned values into the dolfinx Function and refresh its ghosts."""
    u = u_function.vector
    u.array[:] = owned
    u.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)


#: APGPM divides the Lanczos estimate of lambda_min(B^{-1} D^2 J_h(xi_0)) by this factor:
#: the smallest Ritz value lies above lambda_min, and D^2 J_h changes along the iteration
#: (measured on the square, carstensen material: 0.39 at xi_0, 0.31 at xi_h). Too small
#: a mu only slows the momentum by sqrt(factor); too large a mu loses the acceleration
#: (measured there: factors 1.5 to 3 need 49-59 iterations to tol 1e-8, factor 1 up to 65).
MU_SAFETY = 2.0


def _momentum(tau: float, mu: float) -> float:
    """beta = (1 - sqrt(q)) / (1 + sqrt(q)), q = tau mu / MU_SAFETY = 1/kappa (Nesterov's
    constant momentum for a mu-strongly convex function with 1/tau-Lipschitz gradient)."""
    root = np.sqrt(min(max(tau * mu / MU_SAFETY, 0.0), 1.0))
    return float((1.0 - root) / (1.0 + root))


def _lambda_min_at(functional: CoupledFunctional, preconditioner, u_function,
                   n_phi: int) -> float:
    """The smallest Ritz value of :func:`estimate_extremes` at the current u."""
    jacobian = functional.forms.create_matrix()
    functional.forms.assemble_jacobian(u_function, jacobian)
    low = estimate_extremes(functional, preconditioner, jacobian, n_phi)[0]
    jacobian.destroy()
    return low


def projection_gradient(functional: CoupledFunctional, preconditioner,
                        projection: SignoriniProjection, u_function, phi0: np.ndarray, *,
                        tau: float, tol: float = 1e-8, max_iterations: int = 2000,
                        accelerated: bool = False, backtrack: bool = True,
                        strong_convexity: float | None = None,
                        monitor: Callable[[IterationRecord], None] | None = None) -> RunResult:
    """Run Algorithm 3.1 ((3.3)-(3.4), in the block form (3.21)-(3.22)), or its
    accelerated variant.

    PGPM (``accelerated=False``): xi_{k+1} = P(xi_k - tau B^{-1} DJ_h(xi_k)), stopped when
    ||xi_{k+1} - xi_k||_B <= tol ||xi_{k+1}||_B.

    APGPM (``accelerated=True``, our extension): the same step taken from the
    extrapolated point y_k = xi_k + beta (xi_k - xi_{k-1}), all in the B metric, with
    Nesterov's constant momentum for strongly convex functions,
    beta = (1 - sqrt(q)) / (1 + sqrt(q)), q = tau mu / 2 (1/q bounds the condition number
    of (3.5) seen by the step tau; mu = ``strong_convexity``, see :data:`MU_SAFETY`).
    Two restarts (O'Donoghue and Candes 2015): if J_h(xi_{k+1}) > J_h(xi_k) the step is
    discarded and a plain PGPM step is taken from xi_k instead (so J_h decreases
    monotonically, as for PGPM); if the gradient-mapping test
    (y_k - xi_{k+1})^T B (xi_{k+1} - xi_k) > 0 fails (the momentum points uphill), the
    next step is a plain one. Either way the momentum resumes the step after.
    The count scales like sqrt(kappa) instead of kappa.

    Both methods stop on the gradient mapping at the point the step is taken from,
    ||xi_{k+1} - y_k||_B <= tol ||xi_{k+1}||_B (y_k = xi_k for PGPM, so its rule is the
    one above). For tau <= 1/C0 and J_h c0-strongly convex in the B metric (3.5), the
    prox-gradient inequality J_h(xi) - J_h(xi_{k+1}) >= <G, xi - y_k>_B + tau/2 ||G||_B^2
    + c0/2 ||xi - y_k||_B^2, G = (y_k - xi_{k+1})/tau (Beck 2017, First-Order Methods in
    Optimization, Thm 10.16) at xi = xi_h gives, for either method,
    ||xi_{k+1} - xi_h||_B <= (1 + 2 / (tau c0)) ||xi_{k+1} - y_k||_B: the same
    a-posteriori error bound at the same tol. The difference of consecutive APGPM
    iterates also contains the momentum beta (xi_k - xi_{k-1}) and is not an optimality
    measure.

    Parameters
    ----------
    functional
        J_h.
    preconditioner
        B: ``apply_omega`` (B_Omega^{-1}), ``matvec_omega`` (B_Omega), ``apply_signorini``
        (M_s^{-1}) and ``matvec_signorini`` (M_s), on owned entries.
    projection
        P_s in the M_s metric.
    u_function
        dolfinx Function holding u_0 on entry and u_h on exit.
    phi0
        phi_0 >= 0.
    tau
        Step length (1/C0).
    tol
        Stop when ||xi_{k+1} - y_k||_B <= tol ||xi_{k+1}||_B.
    max_iterations
        Iteration cap.
    accelerated
        APGPM instead of PGPM.
    backtrack
        When a plain step would increase J_h (tau too large for the current state),
        halve tau and redo it; every increase is counted in the result either way.
    strong_convexity
        APGPM only: an estimate of mu = lambda_min(B^{-1} D^2 J_h), e.g. the smallest Ritz
        value of :func:`estimate_extremes` computed with C0. Default: that value at xi_0,
        from 20 Lanczos steps here (pass it to save them).
    monitor
        Called with each :class:`IterationRecord`.
    """
    if strong_convexity is not None and not strong_convexity > 0.0:
        raise ValueError(f"strong_convexity must be > 0 (lambda_min of B^-1 D^2 J_h), "
                         f"got {strong_convexity}; pass None to estimate it")
    start = time.perf_counter()
    comm = functional.comm
    mu = 0.0
    if accelerated:
        mu = (strong_convexity if strong_convexity is not None else
              _lambda_min_at(functional, preconditioner, u_function, np.asarray(phi0).size))
    grad = u_function.vector.duplicate()
    u_k = u_function.vector.array_r.copy()
    phi_k = np.maximum(np.asarray(phi0, dtype=float), 0.0)
    energy, g_phi = functional.value_and_gradient(u_function, phi_k, grad)
    g_u, gradient_at_xi_k = grad.array_r.copy(), True
    # B_Omega u is carried along by B u_{k+1} = B y_k - tau grad_u J(y_k), exact by (3.21),
    # so the B norms cost no extra solve.
    b_u = preconditioner.matvec_omega(u_k)
    u_prev, phi_prev, b_prev, momentum = u_k, phi_k, b_u, False
    history: list[IterationRecord] = []
    increases = 0
    reason = f"reached max_iterations = {max_iterations}"
    converged = False
    k = 0
    for k in range(1, max_iterations + 1):
        beta = _momentum(tau, mu) if accelerated and momentum else 0.0
        restarted = False
        while True:
            y_u, y_phi, b_y = (u_k + beta * (u_k - u_prev), phi_k + beta * (phi_k - phi_prev),
                               b_u + beta * (b_u - b_prev))
            if beta > 0.0 or not gradient_at_xi_k:
                _set_owned(u_function, y_u)
                g_phi = functional.gradient(u_function, y_phi, grad)
                g_u, gradient_at_xi_k = grad.array_r.copy(), beta == 0.0
            r_u = preconditioner.apply_omega(g_u)
            r_phi = preconditioner.apply_signorini(g_phi)
            _set_owned(u_function, y_u - tau * r_u)
            projected = projection(y_phi - tau * r_phi, phi_k)
            if comm.size > 1:  # one copy of phi: rank 0's (round-off may differ by rank)
                projected = comm.bcast(projected, root=0)
            if accelerated:
                new_energy = functional.value(u_function, projected.phi)
            else:
                new_energy, new_g_phi = functional.value_and_gradient(u_function,
                                                                      projected.phi, grad)
            increased = new_energy - energy > 1e-13 * (abs(energy) + abs(new_energy))
            increases += int(increased)
            if increased and beta > 0.0:  # function restart: a plain step from xi_k
                beta, restarted = 0.0, True
            elif increased and backtrack and tau > 1e-12:
                tau *= 0.5
            else:
                break
        u_new = u_function.vector.array_r.copy()
        b_new = b_y - tau * g_u
        d_u, d_phi = u_new - u_k, projected.phi - phi_k
        m_d_phi = preconditioner.matvec_signorini(d_phi)
        norm2 = _dot(comm, u_new, b_new) + projected.phi @ preconditioner.matvec_signorini(
            projected.phi)
        if accelerated:
            # gradient mapping xi_{k+1} - y_k; B (u_{k+1} - y_u) = -tau grad_u J(y_k)
            m_phi = projected.phi - y_phi
            step2 = _dot(comm, u_new - y_u, b_new - b_y) + m_phi @ (
                preconditioner.matvec_signorini(m_phi))
            # gradient restart: momentum that points uphill in the B metric is dropped
            uphill = (_dot(comm, y_u - u_new, b_new - b_u) - m_phi @ m_d_phi) > 0.0
            momentum = not (uphill or restarted)
            gradient_at_xi_k = False
        else:
            step2 = _dot(comm, d_u, b_new - b_u) + d_phi @ m_d_phi
            g_u, g_phi = grad.array_r.copy(), new_g_phi
        u_prev, phi_prev, b_prev = u_k, phi_k, b_u
        u_k, phi_k, b_u, energy = u_new, projected.phi, b_new, new_energy
        relative = float(np.sqrt(max(step2, 0.0) / norm2)) if norm2 > 0 else 0.0
        record = IterationRecord(k, energy, relative, int(np.count_nonzero(phi_k <= 0.0)),
                                 projected.iterations, tau)
        history.append(record)
        if monitor is not None:
            monitor(record)
        if relative <= tol:
            rule = "y_k" if accelerated else "xi_k"
            converged, reason = True, f"||xi_k+1 - {rule}||_B <= {tol:g} ||xi_k+1||_B"
            break
    grad.destroy()
    return RunResult(phi=phi_k, converged=converged, reason=reason, iterations=k,
                      energy=energy, tau=tau, history=history, energy_increases=increases,
                      solve_time=time.perf_counter() - start)
