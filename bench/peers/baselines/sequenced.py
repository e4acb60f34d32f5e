"""SNES ``vinewtonrsls`` with grid sequencing: solved on the coarsest mesh of a hierarchy
from x_0 = 0, its solution prolonged to the next finer mesh as the initial iterate, and
so on to the finest (PETSc's ``-snes_grid_sequence``, done here on the project's own
hierarchy and prolongation, :func:`coupling.solvers.nested.prolong`)."""
from __future__ import annotations

import time
from types import SimpleNamespace
from typing import Callable, Sequence

import numpy as np

from bench.peers.baselines.budget import PeerResult, require_serial
from bench.peers.baselines.linear import KRYLOV_RTOL
from bench.peers.baselines.snes import solve_snes_vi
from coupling.problem import SignoriniProblem
from coupling.solvers.nested import prolong

__all__ = ["solve_snes_vi_sequenced"]


def solve_snes_vi_sequenced(
    problem: SignoriniProblem,
    coarser: Sequence[Callable[[], SignoriniProblem]],
    *,
    linear_solver: str = "substructuring",
    rtol: float = 1e-12,
    budget: float | None = None,
    krylov_rtol: float = KRYLOV_RTOL,
) -> PeerResult:
    """Solve the optimality system of (2.3) on ``problem`` by SNES VI with grid sequencing.

    Every level is solved by :func:`bench.peers.baselines.snes.solve_snes_vi` with the
    linear solver ``linear_solver`` and its cold stopping test ||F(x)|| <= rtol ||F(0)||
    (PETSc's VI norm); each level after the coarsest starts from the previous level's
    solution prolonged by :func:`coupling.solvers.nested.prolong` (u_h by P1
    interpolation, the gap linearly along Gamma, clipped at 0).

    Parameters
    ----------
    problem
        The finest level, a serial :class:`coupling.problem.SignoriniProblem` (its
        assembly is not part of the times, as for the other peers).
    coarser
        Builders of the coarser levels, coarsest first; each is called when its level
        starts, so that its assembly (mesh, forms, S_h, loads) counts in ``solve``.
    linear_solver, rtol, krylov_rtol
        As in :func:`~bench.peers.baselines.snes.solve_snes_vi`, on every level.
    budget
        Wall-time budget in seconds for all levels together.

    Returns
    -------
    PeerResult
        The finest level's solution; ``setup`` is the finest level's own set-up, ``solve``
        everything else (the coarser levels with their assembly, the prolongations and
        the finest solve); ``iterations`` and ``linear_iterations`` are the finest
        level's, ``details["levels"]`` lists every level (dofs, Newton steps, Krylov
        iterations, converged, wall time), coarsest first. A level that does not
        converge ends the run with its result.
    """
    require_serial(problem.comm)
    tic = time.perf_counter()
    levels: list[dict] = []
    previous = previous_result = None
    for build in [*coarser, lambda: problem]:
        start = time.perf_counter()
        level = build()
        initial = None
        if previous is not None:
            u_coarse = _function(previous, previous_result.u)
            initial = prolong(previous, SimpleNamespace(u=u_coarse, phi=previous_result.phi), level)
        remaining = None if budget is None else max(budget - (time.perf_counter() - tic), 0.0)
        result = solve_snes_vi(
            level,
            linear_solver=linear_solver,
            rtol=rtol,
            budget=remaining,
            krylov_rtol=krylov_rtol,
            initial=initial,
        )
        levels.append(
            {
                "dofs": int(level.V.dofmap.index_map.size_global),
                "iterations": result.iterations,
                "linear_iterations": result.linear_iterations,
                "converged": bool(result.converged),
                "time": time.perf_counter() - start,
            }
        )
        if not result.converged or level is problem:
            break
        previous, previous_result = level, result
    total = time.perf_counter() - tic
    fine_setup = result.setup if level is problem else 0.0
    u, phi = result.u, result.phi
    if level is not problem:  # a coarser level failed: no iterate on the finest mesh
        u = np.zeros(problem.V.dofmap.index_map.size_local)
        phi = np.zeros(problem.n_signorini)
    return PeerResult(
        u=u,
        phi=phi,
        converged=bool(result.converged and level is problem),
        reason=result.reason if level is problem else f"level {len(levels)}: {result.reason}",
        iterations=result.iterations,
        linear_iterations=result.linear_iterations,
        setup=fine_setup,
        solve=total - fine_setup,
        evaluations=result.evaluations,
        details={**result.details, "levels": levels},
    )


def _function(problem: SignoriniProblem, values) -> object:
    """A P1 Function of ``problem`` with the (serial) nodal ``values``."""
    from dolfinx import fem

    u = fem.Function(problem.V)
    u.x.array[:] = values
    return u
