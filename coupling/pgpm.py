"""The preconditioned projection-gradient method, Algorithm 3.1 of METHOD.md section 5.

With the block preconditioner B = B_Omega + B_s ((3.18)-(3.22)):

    u_{k+1}   = u_k - tau R_Omega,       B_Omega R_Omega = grad_u J_h(u_k, phi_k)     (3.21)
    phi_{k+1} = P_s(phi_k - tau R_s),    M_s R_s = grad_phi J_h(u_k, phi_k)          (3.22)

stopped when ||xi_{k+1} - xi_k||_B <= tol ||xi_{k+1}||_B. The step tau = 1/C0 with C0
the largest eigenvalue of B^{-1} D^2 J_h(xi_0), estimated by Lanczos in the B inner
product (:func:`estimate_step`).
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

__all__ = ["IterationRecord", "PGPMResult", "estimate_step", "projection_gradient"]


@dataclass(frozen=True)
class IterationRecord:
    """One PGPM step: J_h after it, ||xi_{k+1} - xi_k||_B / ||xi_{k+1}||_B, the number
    of Signorini nodes in contact, the inner projection iterations and tau used."""

    iteration: int
    energy: float
    step_norm: float
    contact: int
    inner: int
    tau: float


@dataclass
class PGPMResult:
    """Outcome of :func:`projection_gradient` (u is left in the Function passed in)."""

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
    (D^2 J_h, B) is returned. It approaches lambda_max from below, quickly for the
    extreme eigenvalue; tau = 1/C0 from it keeps tau below 2/lambda_max (the limit
    of descent) unless the estimate is off by a factor 2, which 20 steps never are.

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
    q_prev_u, q_prev_phi = np.zeros_like(q_u), np.zeros_like(q_phi)
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
        q_prev_u, q_prev_phi, p_prev_u, p_prev_phi = q_u, q_phi, p_u, p_phi
        q_u, q_phi, p_u, p_phi = r_u / beta, r_phi / beta, bu / beta, bphi / beta
    ritz = scipy.linalg.eigvalsh_tridiagonal(np.array(alphas), np.array(betas[:len(alphas) - 1]))
    e_u.destroy(), work.destroy()
    return float(ritz[-1])


def projection_gradient(functional: CoupledFunctional, preconditioner,
                        projection: SignoriniProjection, u_function, phi0: np.ndarray, *,
                        tau: float, tol: float = 1e-8, max_iterations: int = 2000,
                        backtrack: bool = True,
                        monitor: Callable[[IterationRecord], None] | None = None) -> PGPMResult:
    """Run Algorithm 3.1 ((3.3)-(3.4), in the block form (3.21)-(3.22)).

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
        Relative B-norm step tolerance.
    max_iterations
        Iteration cap.
    backtrack
        When J_h would increase (tau too large for the current state), halve tau and
        redo the step; every increase is counted in the result either way.
    monitor
        Called with each :class:`IterationRecord`.
    """
    start = time.perf_counter()
    comm = functional.comm
    u = u_function.vector
    phi = np.maximum(np.asarray(phi0, dtype=float), 0.0)
    grad = u.duplicate()
    energy, grad_phi = functional.value_and_gradient(u_function, phi, grad)
    # B_Omega u is updated by the recurrence B u_{k+1} = B u_k - tau grad_u (exact by (3.21)).
    b_u = preconditioner.matvec_omega(u.array_r.copy())
    history: list[IterationRecord] = []
    increases = 0
    reason = f"reached max_iterations = {max_iterations}"
    converged = False
    k = 0
    for k in range(1, max_iterations + 1):
        g_u = grad.array_r.copy()  # grad is overwritten at every trial point
        r_u = preconditioner.apply_omega(g_u)
        r_phi = preconditioner.apply_signorini(grad_phi)
        u_old = u.array_r.copy()
        while True:
            u.array[:] = u_old - tau * r_u
            u.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            projected = projection(phi - tau * r_phi, phi)
            if comm.size > 1:  # one copy of phi: rank 0's (round-off may differ by rank)
                projected = comm.bcast(projected, root=0)
            new_energy, new_grad_phi = functional.value_and_gradient(u_function,
                                                                     projected.phi, grad)
            increased = new_energy - energy > 1e-13 * (abs(energy) + abs(new_energy))
            if increased:
                increases += 1
            if not (increased and backtrack and tau > 1e-12):
                break
            tau *= 0.5
        d_phi = projected.phi - phi
        phi = projected.phi
        b_u -= tau * g_u
        step2 = tau * tau * _dot(comm, r_u, g_u) + d_phi @ preconditioner.matvec_signorini(d_phi)
        norm2 = _dot(comm, u.array_r, b_u) + phi @ preconditioner.matvec_signorini(phi)
        relative = float(np.sqrt(max(step2, 0.0) / norm2)) if norm2 > 0 else 0.0
        energy, grad_phi = new_energy, new_grad_phi
        record = IterationRecord(k, energy, relative, int(np.count_nonzero(phi <= 0.0)),
                                 projected.iterations, tau)
        history.append(record)
        if monitor is not None:
            monitor(record)
        if relative <= tol:
            converged, reason = True, f"||xi_k+1 - xi_k||_B <= {tol:g} ||xi_k+1||_B"
            break
    grad.destroy()
    return PGPMResult(phi=phi, converged=converged, reason=reason, iterations=k, energy=energy,
                      tau=tau, history=history, energy_increases=increases,
                      solve_time=time.perf_counter() - start)
