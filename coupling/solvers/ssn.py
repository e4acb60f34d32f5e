"""Semismooth Newton (primal-dual active set) for the discrete problem (2.3): our extension.

Optimality system of min J_h(u, phi) over phi >= 0 (docs/method.md sections 4-5), written
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
phi_I; on the box one V-cycle of the amg preconditioner's geometric multigrid stands for
B_Omega^{-1}: a fixed operator, the same on any number of ranks). The CG tolerance
follows the Newton residual r = (||grad_u J||_{B_Omega^{-1}}^2
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

Inside a Newton step's CG the V solve of each product with an H-matrix S_h runs only as
accurately as the step needs: to SSN_INNER_TOL_FACTOR times the CG's rtol at the first
iteration, instead of to the operator's own tolerance (kept for the gradients and norms
that decide convergence), and looser as the CG's residual falls, by the factor it has
fallen, up to SSN_INNER_TOL_FACTOR: a product's error enters the computed solution
weighted by the residual at its iteration, so the late products, at a residual near
rtol, need only a few digits (relaxed inexact Krylov methods: Simoncini and Szyld, SIAM
J. Sci. Comput. 25, 2003; van den Eshof and Sleijpen, SIAM J. Matrix Anal. Appl. 26,
2004). The products then differ from the exact ones by far less than the step's own
tolerance, which leaves the CG's iterations as they were. Where the amg preconditioner
has GAMG (domains other than the box and the structured square) its inner CG + GAMG
keeps its own tolerance inside the CG as well: GAMG's hierarchy depends on the number of
ranks, and only a solve far below the step's accuracy keeps the iterates independent of
it.

The active set is predicted in the metric M_s, by the M_s projection of
phi - tau M_s^{-1} grad_phi J (the active set of a PGPM step), not by the
componentwise rule A = {phi - c grad_phi J <= 0}, whose edge retreats by a bounded
number of nodes per step and so needs O(1/h) steps (docs/design/solvers.md). At the
solution the prediction is exact, {phi = 0} (phi is the fixed point of the PGPM step),
so the local convergence of the active-set Newton method is kept.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, NamedTuple

import numpy as np
from mpi4py import MPI

from coupling.options import (
    OVERSOLVE_SAFEGUARD,
    SSN_INNER_TOL_FACTOR,
    SSN_JACOBIAN_REUSE_STEP,
)
from coupling.preconditioners.base import omega_cycle
from coupling.solvers.loop import IterationContext, Loop
from coupling.solvers.pgpm import energy_increased, pgpm
from coupling.solvers.projection import SignoriniProjection
from coupling.solvers.records import RunResult, b_norm2, global_dot, set_owned

__all__ = [
    "NewtonSettings",
    "Hessian",
    "Trial",
    "semismooth_newton",
    "newton_direction",
    "line_search",
    "forcing_term",
    "zero_residual",
]


@dataclass(frozen=True)
class NewtonSettings:
    """The settings of an ssn run beside its :class:`~coupling.solvers.loop.IterationContext`
    (their values: ``coupling.options``, SSN_*).

    Attributes
    ----------
    start_steps
        PGPM steps before the first Newton step.
    cg_max_iterations
        CG iterations per Newton step at most.
    forcing_exponent
        p of the forcing term min(0.1, (r / r_0)^p) (:func:`forcing_term`).
    residual_scale
        r_0; None: the residual of the first Newton step.
    """

    start_steps: int
    cg_max_iterations: int
    forcing_exponent: float
    residual_scale: float | None = None


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
    in-place update can reach an array apply_b_inv returned or was given). ``rhs`` is
    overwritten: its arrays hold the residual. ``apply_h(p, slack)`` is given
    slack = ||r_0|| / ||r_k|| (B^{-1}-norms, >= 1 as the residual falls): the factor by
    which the product may be less accurate than at the start (relaxed inexact Krylov
    products, module docstring)."""
    dot = lambda a, b: global_dot(comm, a[0], b[0]) + a[1] @ b[1]  # noqa: E731
    x = (np.zeros_like(rhs[0]), np.zeros_like(rhs[1]))
    r = rhs
    work = (np.empty_like(rhs[0]), np.empty_like(rhs[1]))
    z = apply_b_inv(r)
    p = (z[0].copy(), z[1].copy())
    rz = rz0 = dot(r, z)
    stop = rtol * np.sqrt(max(rz, 0.0))
    for it in range(1, max_iterations + 1):
        hp = apply_h(p, np.sqrt(rz0 / rz) if rz > 0 else 1.0)
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
    predicted = predictor.step(phi, g_phi, tau).phi  # exact: no solve with M_s
    if comm.size > 1:  # one copy of the replicated unknowns
        predicted = comm.bcast(predicted, root=0)
    natural = phi - predicted  # tau times the projected B_s-gradient
    residual = np.sqrt(
        global_dot(comm, g_u, preconditioner.apply_omega(g_u))
        + natural @ preconditioner.matvec_signorini(natural) / tau**2
    )
    return predicted, residual


def zero_residual(context: IterationContext, n_phi: int, tau: float) -> float:
    """The Newton residual r at xi = (0, 0): the scale of the problem's residuals (for
    ``residual_scale``; the context's ``u`` is left as it was)."""
    functional, preconditioner, u_function = context.functional, context.preconditioner, context.u
    comm = functional.comm
    saved = u_function.vector.array_r.copy()
    set_owned(u_function, np.zeros_like(saved))
    grad = u_function.vector.duplicate()
    phi = np.zeros(n_phi)
    g_phi = functional.gradient(u_function, phi, grad)
    predictor = context.projection.as_exact()
    _, residual = _predict(preconditioner, predictor, comm, grad.array_r.copy(), g_phi, phi, tau)
    grad.destroy()
    set_owned(u_function, saved)
    return float(residual)


class Hessian:
    """D^2 J_h at the iterate as a product: the interior Jacobian, assembled into a P1
    matrix (the context's, or a new ``fem_py.forms.P1Matrix``), plus S_h on the boundary
    block."""

    def __init__(self, context: IterationContext):
        self.functional, self.forms = context.functional, context.forms
        self.owns_matrix = context.matrix is None
        self.matrix = context.forms.create_p1_matrix() if self.owns_matrix else context.matrix
        self.e_u, self.h_u = self.forms.create_vector(), self.forms.create_vector()

    def assemble(self, u_function) -> None:
        """Assemble the interior Jacobian at u."""
        self.forms.assemble_jacobian(u_function, self.matrix)

    def __call__(
        self, e_u_owned: np.ndarray, e_phi: np.ndarray, solver_tol: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """D^2 J_h (e_u, e_phi): (owned entries of the u part, the phi part); ``solver_tol``:
        that of the V solve in an H-matrix S_h's product (None: the operator's own)."""
        self.e_u.array[:] = e_u_owned
        h_phi = self.functional.hessian_action(
            self.matrix, self.e_u, e_phi, self.h_u, solver_tol=solver_tol
        )
        return self.h_u.array_r.copy(), h_phi

    def destroy(self) -> None:
        for obj in (self.e_u, self.h_u) + ((self.matrix,) if self.owns_matrix else ()):
            obj.destroy()


def forcing_term(
    residual: float,
    residual0: float,
    exponent: float,
    *,
    tol: float,
    norm2: float | None,
    tau: float,
) -> float:
    """The CG tolerance of a Newton step: min(0.1, (r / r_0)^p), kept above
    OVERSOLVE_SAFEGUARD tol ||xi_k||_B / (tau r) once ||xi_k||_B^2 = ``norm2`` is known
    (no more accuracy than the stopping rule asks for; module docstring)."""
    forcing = min(0.1, (residual / residual0) ** exponent)
    if norm2 is not None:
        forcing = max(forcing, OVERSOLVE_SAFEGUARD * tol * np.sqrt(norm2) / (tau * residual))
    return forcing


def newton_direction(
    context: IterationContext,
    hessian: Hessian,
    phi: np.ndarray,
    active: np.ndarray,
    gradient: tuple[np.ndarray, np.ndarray],
    *,
    rtol: float,
    cg_max_iterations: int,
    projection: SignoriniProjection | None = None,
) -> tuple[np.ndarray, np.ndarray, int]:
    """The Newton direction of the active-set system (module docstring): dphi_A = -phi_A,
    and (du, dphi_I) from H_[(u,I),(u,I)] (du, dphi_I) = -(grad_u J, grad_phi J_I)
    - H_[(u,I),A] dphi_A by CG to ``rtol``, preconditioned by B_Omega^{-1} (one multigrid
    cycle where the preconditioner has a rank-independent one, ``omega_cycle``) and
    M_s[I, I]^{-1}. ``gradient`` = (grad_u J owned, grad_phi J) at the iterate; returns
    (du owned, dphi, the CG iterations). M_s[I, I]'s Cholesky factor is ``projection``'s
    (default: the context's), the exact projection's that predicted the active set: it
    factored M_s[I, I] on the same I already (n_s^3/3 flops at most, 50 s at 128^3 cubes)."""
    preconditioner, comm = context.preconditioner, context.comm
    g_u, g_phi = gradient
    free = ~active
    factor = (projection or context.projection).free_factor(free) if free.any() else None

    inner = SSN_INNER_TOL_FACTOR * rtol  # S_h's V solves (module docstring)
    precondition_u = omega_cycle(preconditioner)

    def apply_h(p, slack):
        e_phi = np.zeros(phi.size)
        e_phi[free] = p[1]
        h_u_owned, h_phi = hessian(p[0], e_phi, min(SSN_INNER_TOL_FACTOR, inner * slack))
        return h_u_owned, h_phi[free]

    def apply_b_inv(r):
        return (
            precondition_u(r[0]),
            factor.solve(r[1]) if factor is not None else r[1],
        )

    d_phi = np.zeros(phi.size)
    d_phi[active] = -phi[active]
    h_a_u, h_a_phi = hessian(np.zeros_like(g_u), d_phi, inner)
    rhs = (np.subtract(-g_u, h_a_u, out=h_a_u), -g_phi[free] - h_a_phi[free])
    (d_u, d_phi_free), cg_its = _pcg(
        apply_h, apply_b_inv, rhs, comm, rtol=rtol, max_iterations=cg_max_iterations
    )
    d_phi[free] = d_phi_free
    if comm.size > 1:  # one copy of the replicated unknowns
        d_phi = comm.bcast(d_phi, root=0)
    return d_u, d_phi, cg_its


class Trial(NamedTuple):
    """Where the line search ends: phi, J_h and grad_phi J_h there (u is in the context's
    Function), the length taken along the Newton direction (0: a PGPM step instead) and
    the energy increases met on the way."""

    phi: np.ndarray
    energy: float
    g_phi: np.ndarray
    step: float
    increases: int


def line_search(
    context: IterationContext,
    grad,
    u_old: np.ndarray,
    phi: np.ndarray,
    energy: float,
    direction: tuple[np.ndarray, np.ndarray],
    *,
    tau: float,
) -> Trial:
    """Backtracking on J_h along the projected path (u + a du, max(0, phi + a dphi)),
    a = 1, 1/2, ...: the first a that does not increase J_h (``energy`` at (u_old, phi));
    after 30 halvings one PGPM step (step length tau) from (u_old, phi) instead. The
    trial's u is left in ``context.u``, grad_u J_h there in ``grad``."""
    functional, u_function = context.functional, context.u
    d_u, d_phi = direction
    increases = 0
    step = 1.0
    for _ in range(30):
        set_owned(u_function, u_old + step * d_u)
        trial_phi = context.projection.feasible(phi + step * d_phi)
        trial_energy, trial_g_phi = functional.value_and_gradient(u_function, trial_phi, grad)
        if not energy_increased(energy, trial_energy):
            break
        increases += 1
        step *= 0.5
    else:  # no decrease along the Newton path: fall back to one PGPM step
        set_owned(u_function, u_old)
        run = pgpm(replace(context, tol=0.0, max_iterations=1, monitor=None), phi, tau=tau)
        trial_phi, trial_energy = run.phi, run.energy
        trial_g_phi = functional.gradient(u_function, trial_phi, grad)
        step = 0.0
    return Trial(trial_phi, trial_energy, trial_g_phi, step, increases)


def semismooth_newton(
    context: IterationContext, phi0: np.ndarray, *, tau: float, newton: NewtonSettings
) -> RunResult:
    """Semismooth Newton on the optimality system, started by ``newton.start_steps`` PGPM
    steps.

    The active set is predicted by a PGPM step in the M_s metric with the exact
    projection (module docstring). Stops when that PGPM step from the Newton iterate xi_k
    meets the rule of the PGPM, ||step||_B = tau r_k <= tol ||xi_k||_B, with the active
    set unchanged by the last Newton step, or when a Newton step itself has
    ||xi_{k+1} - xi_k||_B <= tol ||xi_{k+1}||_B with an unchanged active set, or after
    ``max_iterations`` outer steps in all (the PGPM steps included). The records of the
    Newton steps hold their CG iterations and the length taken along the Newton direction.
    Each step: the direction (:func:`newton_direction`, CG tolerance
    :func:`forcing_term`), then the line search (:func:`line_search`).

    The CG tolerance of a step is min(0.1, (r / r_0)^p) times the residual r (module
    docstring), p = ``newton.forcing_exponent``, r_0 the residual of the first Newton
    step, or ``newton.residual_scale`` when given: from a start already close to the
    solution (nested iteration) r_0 of the problem's own scale (:func:`zero_residual`)
    keeps the steps from being limited to a contraction of 0.1 each.

    ``context.forms`` assembles the Jacobians of the Newton steps, into ``context.matrix``
    when given (else into a new Mat, destroyed here).
    """
    functional, preconditioner, projection = (
        context.functional,
        context.preconditioner,
        context.projection,
    )
    comm, u_function, tol = context.comm, context.u, context.tol
    if newton.start_steps > 0 or context.max_iterations == 0:
        start = replace(context, max_iterations=min(newton.start_steps, context.max_iterations))
        warm = pgpm(start, phi0, tau=tau)
        if warm.converged or warm.iterations >= context.max_iterations:
            return warm
        phi, first, history, increases = (
            warm.phi,
            warm.iterations + 1,
            warm.history,
            warm.energy_increases,
        )
    else:  # Newton from xi_0 itself (a warm start): no PGPM run of no steps, whose set-up
        # would evaluate J_h and its gradient at xi_0 once more than below
        phi, first, history, increases = projection.feasible(np.asarray(phi0, float)), 1, [], 0
    grad = u_function.vector.duplicate()
    hessian = Hessian(context)
    energy, g_phi = functional.value_and_gradient(u_function, phi, grad)
    # the exact M_s-projection predicts the active set (an inexact one would blur it), in
    # the solver's projection's metric with its factor of M_s and its inverse
    predictor = projection.as_exact()
    residual0 = newton.residual_scale
    active = np.zeros(phi.size, dtype=bool)
    b_u = None  # B_Omega u_k, updated by the steps
    norm2 = relative = None  # ||xi_k||_B^2 and ||xi_k - xi_k-1||_B / ||xi_k||_B after a Newton step
    loop = Loop(
        context,
        "||xi_k+1 - xi_k||_B <= {tol:g} ||xi_k+1||_B, active set settled",
        first=first,
        history=history,
        increases=increases,
    )
    for k in loop.steps():
        g_u = grad.array_r.copy()
        predicted, residual = _predict(preconditioner, predictor, comm, g_u, g_phi, phi, tau)
        new_active = (predicted <= 0.0) & projection.bounded
        active_changed = not np.array_equal(new_active, active)
        if norm2 is not None and not active_changed and tau * residual <= tol * np.sqrt(norm2):
            # the PGPM step from xi_k (B-norm tau r) meets the PGPM rule: no further step
            loop.stop(
                "||PGPM step at xi_k||_B <= {tol:g} ||xi_k||_B, active set settled",
                k - 1,
                measure=tau * residual / np.sqrt(norm2),
            )
            continue
        active = new_active
        residual0 = residual if residual0 is None else residual0
        if relative is None or relative > SSN_JACOBIAN_REUSE_STEP:
            hessian.assemble(u_function)
        rtol = forcing_term(
            residual, residual0, newton.forcing_exponent, tol=tol, norm2=norm2, tau=tau
        )
        d_u, d_phi, cg_its = newton_direction(
            context,
            hessian,
            phi,
            active,
            (g_u, g_phi),
            rtol=rtol,
            cg_max_iterations=newton.cg_max_iterations,
            projection=predictor,
        )
        u_old = u_function.vector.array_r.copy()
        trial = line_search(context, grad, u_old, phi, energy, (d_u, d_phi), tau=tau)
        loop.increases += trial.increases
        d_u_taken = u_function.vector.array_r - u_old
        d_phi_taken = trial.phi - phi
        b_d_u = preconditioner.matvec_omega(d_u_taken)
        step2 = b_norm2(
            comm, d_u_taken, b_d_u, d_phi_taken, preconditioner.matvec_signorini(d_phi_taken)
        )
        # B_Omega u_k+1 = B_Omega u_k + B_Omega du: one product per step for both norms
        b_u = preconditioner.matvec_omega(u_old) + b_d_u if b_u is None else b_u + b_d_u
        u_now = u_function.vector.array_r
        norm2 = b_norm2(comm, u_now, b_u, trial.phi, preconditioner.matvec_signorini(trial.phi))
        phi, energy, g_phi = trial.phi, trial.energy, trial.g_phi
        # this step's vectors go before the next step's CG allocates its own (the peak)
        del d_u, u_old, d_u_taken, b_d_u, u_now
        relative = loop.end_step(
            k,
            energy,
            step2,
            norm2,
            phi,
            tau,
            settled=not active_changed,
            cg_iterations=cg_its,
            line_search=trial.step,
        )
    return loop.result(phi, energy, tau, release=(grad, hessian, predictor))
