"""A solve of an assembled problem: :func:`solve` and the :class:`Solution` it returns.

The way dolfinx separates ``NewtonSolver`` from the problem it solves: the problem
(:class:`coupling.problem.SignoriniProblem`) is read, never changed; the preconditioner
is built here unless one is passed in; progress goes to the caller's monitor.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from coupling.options import (
    LANCZOS_STEPS,
    SSN_LANCZOS_STEPS,
    SSN_CG_MAX_ITERATIONS,
    SSN_FORCING_EXPONENT,
    SSN_START_STEPS,
    SSN_WARM_FORCING_EXPONENT,
    SSN_WARM_START_STEPS,
    SolverOptions,
)
from coupling.preconditioners import Preconditioner, build_preconditioner, create_matrix
from coupling.preconditioners.base import DenseSignoriniBlock
from coupling.solvers.apgpm import apgpm
from coupling.solvers.lanczos import extremes_at
from coupling.solvers.loop import IterationContext
from coupling.solvers.pgpm import pgpm
from coupling.solvers.projection import SignoriniProjection
from coupling.solvers.records import IterationRecord, Monitor, RunResult, set_owned
from coupling.solvers.ssn import NewtonSettings, semismooth_newton, zero_residual

__all__ = [
    "Solution",
    "solve",
    "build_projection",
    "iteration_context",
    "step_length",
    "iterate",
]


@dataclass
class Solution:
    """What :func:`solve` returns.

    Attributes
    ----------
    u
        u_h (dolfinx Function on the P1 space of the problem).
    phi
        phi_h at the Signorini nodes (n_s,), the gap u_e + u0 - u there.
    contact
        (n_s,) bool, phi_h == 0: the discrete contact set.
    boundary_u, ue, flux
        u_h on Gamma, u_e = u + phi - u0 on Gamma (boundary order), and the
        coefficients of the exterior normal derivative psi_h (flux space; None when
        :func:`solve` was asked not to compute it).
    converged, reason, iterations, energy, history, energy_increases, stop_measure
        The outcome of the iteration (:class:`coupling.solvers.records.RunResult`).
    tau, C0
        The step length at the end and the estimate C0 = 1/tau_0 it started from.
    residual_scale
        The scale of ssn's residuals from a given iterate (None for a cold start or
        another method): passed on to the next finer level.
    timings
        Seconds per stage of the solve: ``preconditioner`` (when built here),
        ``step_estimate``, ``solve``, ``exterior_flux``.
    """

    u: Any
    phi: np.ndarray
    contact: np.ndarray
    boundary_u: np.ndarray
    ue: np.ndarray
    flux: np.ndarray | None
    converged: bool
    reason: str
    iterations: int
    energy: float
    tau: float
    C0: float
    history: list[IterationRecord]
    energy_increases: int
    timings: dict[str, float]
    residual_scale: float | None = None
    stop_measure: float | None = None


def build_projection(
    preconditioner: Preconditioner, options: SolverOptions, bounded: np.ndarray | None = None
) -> SignoriniProjection:
    """P_s of ``options`` in the metric M_s of ``preconditioner`` (3.19)-(3.20), sharing
    its Cholesky factor of M_s and M_s^{-1} when it has them (a dense M_s's), each made when
    first needed; lambda_max(M_s) is computed only when the inexact projection first
    needs it."""
    # the class, not the object: hasattr on the object would evaluate the property, i.e.
    # compute M_s^{-1} (n_s^3 flops) whether or not the projection ever reads it
    dense = isinstance(preconditioner, DenseSignoriniBlock)
    return SignoriniProjection(
        preconditioner.signorini_metric,
        options.projection,
        rho_in=options.projection_tol,
        max_iterations=options.projection_max_iterations,
        lambda_max=lambda: preconditioner.lambda_max_signorini,
        factor=(lambda: preconditioner.signorini_factor) if dense else None,
        inverse=(lambda: preconditioner.signorini_inverse) if dense else None,
        bounded=bounded,
    )


def iteration_context(
    functional: Any,
    forms: Any,
    preconditioner: Preconditioner,
    u: Any,
    options: SolverOptions,
    *,
    monitor: Monitor | None = None,
    matrix: Any = None,
) -> IterationContext:
    """The :class:`~coupling.solvers.loop.IterationContext` of ``options`` (its ``tol``,
    ``max_iterations`` and projection, :func:`build_projection`) on J_h = ``functional``
    (the problem's, or one that wraps it, as the baselines' budget does) from the
    iterate in ``u``; ``matrix``: a P1 Mat of the caller's for the Jacobians."""
    gap = getattr(functional, "gap", None)  # a wrapper of J_h (the baselines') has none
    projection = build_projection(preconditioner, options, None if gap is None else gap.bounded)
    stop = dict(tol=options.tol, max_iterations=options.max_iterations)
    extra = dict(monitor=monitor, forms=forms, matrix=matrix)
    return IterationContext(functional, preconditioner, projection, u, **stop, **extra)


def step_length(
    functional: Any,
    preconditioner: Preconditioner,
    u: Any,
    n_phi: int,
    options: SolverOptions,
    *,
    matrix: Any = None,
) -> tuple[float, float, float | None]:
    """(tau, C0, lambda_min): tau = 1/C0 with C0 from Lanczos at the iterate u
    (``options.step = "auto"``: LANCZOS_STEPS steps, SSN_LANCZOS_STEPS for ssn; lambda_min,
    the momentum of apgpm, from the same run),
    or the given step (lambda_min None). ``matrix``: a P1 Mat of the caller's to
    assemble D^2 G into (default: a new one)."""
    if options.step == "auto":
        steps = SSN_LANCZOS_STEPS if options.method == "ssn" else LANCZOS_STEPS
        lambda_min, C0 = extremes_at(
            functional, preconditioner, u, n_phi, steps=steps, matrix=matrix
        )
        return 1.0 / C0, C0, lambda_min
    tau = float(options.step)
    return tau, 1.0 / tau, None


def iterate(
    context: IterationContext,
    options: SolverOptions,
    phi0: np.ndarray,
    *,
    tau: float,
    lambda_min: float | None,
    warm_start: bool = False,
    residual_scale: float | None = None,
) -> RunResult:
    """The iteration of ``options.method`` in ``context`` (:func:`iteration_context`)
    from (context.u, phi0); u_h is left in ``context.u``.
    ``warm_start``: (u, phi0) is a given iterate (nested iteration, adaptivity), from which
    ssn takes Newton steps at once, with CG tolerances relative to ``residual_scale``
    (:func:`coupling.solvers.ssn.zero_residual`; None: the first step's residual) and the
    quadratic forcing (``SSN_WARM_FORCING_EXPONENT``)."""
    if options.method == "ssn":
        newton = NewtonSettings(
            start_steps=SSN_WARM_START_STEPS if warm_start else SSN_START_STEPS,
            cg_max_iterations=SSN_CG_MAX_ITERATIONS,
            forcing_exponent=SSN_WARM_FORCING_EXPONENT if warm_start else SSN_FORCING_EXPONENT,
            residual_scale=residual_scale,
        )
        return semismooth_newton(context, phi0, tau=tau, newton=newton)
    if options.method == "apgpm":
        if lambda_min is None:  # a given step: lambda_min at the start, as C0 would be
            lambda_min = extremes_at(
                context.functional,
                context.preconditioner,
                context.u,
                phi0.size,
                steps=LANCZOS_STEPS,
                matrix=context.matrix,
            )[0]
        return apgpm(context, phi0, tau=tau, strong_convexity=lambda_min)
    return pgpm(context, phi0, tau=tau)


def solve(
    problem: Any,
    options: SolverOptions,
    *,
    initial: tuple[np.ndarray, np.ndarray] | None = None,
    preconditioner: Preconditioner | None = None,
    matrix: Any = None,
    residual_scale: float | None = None,
    monitor: Monitor | None = None,
    exterior_flux: bool = True,
) -> Solution:
    """Solve the discrete problem (2.3) with ``options.method`` (collective).

    ``ssn`` (default): semismooth Newton (:mod:`coupling.solvers.ssn`); ``pgpm``: the
    paper's Algorithm 3.1 (:mod:`coupling.solvers.pgpm`); ``apgpm``: its accelerated
    variant (:mod:`coupling.solvers.apgpm`). The step tau = 1/C0 comes from Lanczos at
    the initial iterate (``options.step = "auto"``) or is given.

    Parameters
    ----------
    problem
        The assembled :class:`coupling.problem.SignoriniProblem` (read only).
    options
        :class:`coupling.options.SolverOptions`; ``flux_space`` and ``jacobian`` were
        used to assemble the problem and are not read here.
    initial
        (u, phi): the owned entries of u (or a dolfinx Function on ``problem.V``) and
        phi (n_s,), the iterate to start from; default xi_0 = (0, 0).
    preconditioner
        A B built by :func:`coupling.preconditioners.build_preconditioner` for this
        problem, to reuse it (the caller destroys it); default: built for
        ``options.preconditioner`` here and destroyed at the end.
    matrix
        A P1 matrix of the caller's (:func:`coupling.preconditioners.create_matrix`, the
        one a given ``preconditioner`` was built with) for the stiffness of B when built
        here and the Jacobians of the step estimate and the iteration (each assembled over
        the last); default a new one, whose sparsity pattern costs about one assembly.
    residual_scale
        From an ``initial`` iterate, ssn's scale of the residuals (the residual at
        xi = (0, 0), :func:`coupling.solvers.ssn.zero_residual`): that of a coarser level's
        problem, whose residuals have the same scale (their dual norms approximate the
        same functional's); default computed here (one gradient and one projection).
        The solution reports the scale it used.
    monitor
        Called with every :class:`coupling.solvers.records.IterationRecord`.
    exterior_flux
        Whether to compute the flux psi_h of u_e (one solve with the boundary operator;
        False for a coarser level of nested iteration, which only passes on (u, phi)):
        the solution's ``flux`` is then None.
    """
    from dolfinx import fem

    timings: dict[str, float] = {}
    owned = preconditioner is None
    # one P1 matrix for the stiffness of B, the Jacobian of the step estimate and those of
    # the iteration (each assembled over the last): creating one costs about one assembly
    own_matrix = matrix is None
    if owned:
        tic = time.perf_counter()
        if own_matrix:
            matrix = create_matrix(problem, options)
        preconditioner = build_preconditioner(problem, options, matrix=matrix)
        timings["preconditioner"] = time.perf_counter() - tic
    try:
        pc = preconditioner
        u = fem.Function(problem.V, name="u")
        phi0 = np.zeros(problem.n_signorini)
        if initial is not None:
            u_start, phi_start = initial
            n_owned = problem.V.dofmap.index_map.size_local * problem.components
            u_values = (
                u_start.x.array[:n_owned]
                if hasattr(u_start, "x")
                else np.asarray(u_start, dtype=float)
            )
            phi0 = np.asarray(phi_start, dtype=float).copy()
            if u_values.shape != (n_owned,) or phi0.shape != (problem.n_signorini,):
                raise ValueError(
                    f"initial (u, phi) must have shapes ({n_owned},) (the owned "
                    f"entries) and ({problem.n_signorini},), got "
                    f"{u_values.shape} and {phi0.shape}"
                )
            set_owned(u, u_values)
        tic = time.perf_counter()
        if matrix is None and (options.step == "auto" or options.method != "pgpm"):
            matrix = problem.forms.create_p1_matrix()
        tau, C0, lambda_min = step_length(
            problem.functional, pc, u, phi0.size, options, matrix=matrix
        )
        timings["step_estimate"] = time.perf_counter() - tic
        context = iteration_context(
            problem.functional, problem.forms, pc, u, options, monitor=monitor, matrix=matrix
        )
        tic = time.perf_counter()
        if initial is not None and options.method == "ssn" and residual_scale is None:
            residual_scale = zero_residual(context, phi0.size, tau)
        run = iterate(
            context,
            options,
            phi0,
            tau=tau,
            lambda_min=lambda_min,
            warm_start=initial is not None,
            residual_scale=residual_scale,
        )
        timings["solve"] = time.perf_counter() - tic
    finally:
        if owned:
            preconditioner.destroy()
        if own_matrix and matrix is not None:
            matrix.destroy()

    boundary_u = problem.boundary.gather(u.vector)
    ue = problem.gap.extend(boundary_u.copy(), run.phi) - problem.u0
    flux = None
    if exterior_flux:
        tic = time.perf_counter()
        flux = problem.exterior_flux(ue)
        timings["exterior_flux"] = time.perf_counter() - tic
    return Solution(
        u=u,
        contact=run.phi[problem.gap.bounded] <= 0.0,
        boundary_u=boundary_u,
        ue=ue,
        flux=flux,
        C0=C0,
        timings=timings,
        residual_scale=residual_scale,
        **{f.name: getattr(run, f.name) for f in dataclasses.fields(RunResult)},
    )
