"""The project's own methods (``pgpm``, ``apgpm``, ``ssn``) as a baseline: the same
problem, a wall-time budget on J_h, the result in the form of the PETSc baselines."""
from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from bench.peers.baselines.budget import (
    Budget,
    BudgetedFunctional,
    BudgetExceeded,
    PeerResult,
    require_serial,
)
from coupling.options import SolverOptions
from coupling.preconditioners import Preconditioner, build_preconditioner
from coupling.problem import SignoriniProblem
from coupling.solvers import RunResult
from coupling.solvers.solution import iterate, iteration_context, step_length

__all__ = ["solve_project", "run_method"]


def run_method(
    problem: SignoriniProblem,
    functional: Any,
    preconditioner: Preconditioner,
    options: SolverOptions,
    u_function: Any,
) -> tuple[RunResult, float, float, float]:
    """``options.method`` from xi_0 = (0, 0) on ``functional`` (J_h, or J_h wrapped),
    with the projection, the step estimate and the iteration of
    :func:`coupling.solvers.solve` (so the iterates are the same).

    Returns the run (u_h is left in ``u_function``), C0, and the wall times of the step
    estimate and of the iteration in seconds.
    """
    phi0 = np.zeros(problem.n_signorini)
    tic = time.perf_counter()
    tau, C0, lambda_min = step_length(functional, preconditioner, u_function, phi0.size, options)
    step_estimate = time.perf_counter() - tic
    context = iteration_context(functional, problem.forms, preconditioner, u_function, options)
    tic = time.perf_counter()
    run = iterate(context, options, phi0, tau=tau, lambda_min=lambda_min)
    return run, C0, step_estimate, time.perf_counter() - tic


def solve_project(
    problem: SignoriniProblem,
    method: str = "pgpm",
    *,
    preconditioner: str = "substructuring",
    budget: float | None = None,
    **options: Any,
) -> PeerResult:
    """Run one of the project's methods (``pgpm``, ``apgpm``, ``ssn``) on ``problem``
    with a freshly built ``preconditioner`` and the result in the form of the peers.

    ``setup`` is the preconditioner build plus the step estimate (tau = 1/C0),
    ``solve`` the iteration; ``options`` override further
    :class:`coupling.options.SolverOptions` fields (e.g. ``tol``, ``max_iterations``).
    ``linear_iterations`` is the number of CG iterations of ``ssn`` (0 otherwise).
    The budget is checked at every evaluation of J_h (a
    :class:`~bench.peers.baselines.budget.BudgetedFunctional` handed to the method; the
    problem is not changed).
    """
    from dolfinx import fem

    require_serial(problem.comm)
    base = SolverOptions(flux_space=problem.flux_space, jacobian=problem.jacobian)
    opts = dataclasses.replace(base, method=method, preconditioner=preconditioner, **options)
    tic = time.perf_counter()
    pc = build_preconditioner(problem, opts)
    build = time.perf_counter() - tic
    try:
        clock = Budget(budget)
        functional = BudgetedFunctional(problem.functional, clock)
        u = fem.Function(problem.V, name="u")
        tic = time.perf_counter()
        try:
            run, C0, step_estimate, seconds = run_method(problem, functional, pc, opts, u)
        except BudgetExceeded as err:
            u_last, phi = functional.last
            return PeerResult(
                u=u_last,
                phi=phi,
                converged=False,
                reason=str(err),
                iterations=-1,
                linear_iterations=0,
                setup=build,
                solve=time.perf_counter() - tic,
            )
    finally:
        pc.destroy()
    n_u = problem.V.dofmap.index_map.size_local
    return PeerResult(
        u=u.x.array[:n_u].copy(),
        phi=run.phi.copy(),
        converged=run.converged,
        reason=run.reason,
        iterations=run.iterations,
        linear_iterations=int(sum(r.cg_iterations for r in run.history)),
        setup=build + step_estimate,
        solve=seconds,
        details={"tau": run.tau, "C0": C0, "energy_increases": run.energy_increases},
    )
