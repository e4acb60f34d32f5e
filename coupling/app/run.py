"""The solve of one configuration, plain, nested (``[solver] nested``) or adaptive
(``[adapt] steps > 0``), the a posteriori estimator of its result (adaptive runs, or when
``[output]`` asks) and, when the configuration gives the exact solution (``[data]
exact``), its energy error."""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from coupling.app.config import ConfigError
from coupling.app.from_config import coarser_configs, domain_from_config, problem_on_domain
from coupling.options import RunConfig

__all__ = ["Run", "run_solver"]


@dataclass
class Run:
    """What the outputs of a run need: the (finest) problem and its solution, the stage
    timings, one record per level (nested or adaptive runs), the global estimator, the
    per-cell eta_T^2 of the owned cells of the final mesh (``indicators``, in the local
    cell order; triangles, or tetrahedra for a body in R^3) and the energy
    error |u_h - u|_1 (None without ``[data] exact``). A plain or nested solve has an
    estimator only with ``[output] estimator`` or ``indicators``."""

    problem: Any
    solution: Any
    timings: dict[str, float]
    levels: list[dict] | None
    estimator: float | None
    indicators: np.ndarray | None
    error: float | None = None


def _level_builder(comm: Any, config: RunConfig):
    """A builder of the problem of one coarser level (called when the level starts)."""
    return lambda: problem_on_domain(domain_from_config(comm, config), config)[0]


def run_solver(
    comm: Any,
    config: RunConfig,
    domain: Any,
    problem: Any,
    timings: dict[str, float],
    monitor: Any = None,
    after_solve: Callable[[Any, Any, list[dict] | None], None] | None = None,
) -> Run:
    """Solve the assembled ``problem`` on ``domain`` as ``config`` asks (collective): with
    ``config.solver``, adaptively as ``config.adapt`` says or nested over coarser levels of
    ``config.geometry``, the estimator (when ``config.output`` asks) on the data ``config.data``.

        ``timings`` are the set-up stages so far; the run adds ``solve`` (and the stages of
        :func:`coupling.solvers.solve`), ``coarse_levels`` and ``prolongation`` for a nested
        solve, ``adaptive_loop`` (every level: assembly, solves, estimates, errors,
        refinement) for an adaptive one, and ``estimator``. ``after_solve(problem,
        solution, levels)``, when given, is called with the final problem, its solution and
        the records of the levels (nested or adaptive; None for a plain solve) as soon as
        they are known: before the estimator of a plain or nested solve, after the
        adaptive loop (e.g. :meth:`coupling.io.outputs.RunOutputs.start`, whose work then
        runs beside the estimator); its time is in none of the stages.
    """
    from coupling.adapt import adapt, estimate
    from coupling.manufactured import energy_error
    from coupling.solvers import solve
    from coupling.solvers.nested import solve_nested

    data, settings, options = config.data, config.adapt, config.solver
    exact = data.exact
    if settings.steps > 0:
        dofs = problem.n_dofs
        if dofs > settings.max_dofs:
            raise ConfigError(
                f"adapt.max_dofs = {settings.max_dofs} is below the starting "
                f"mesh's {dofs} dofs; raise it or coarsen the mesh (geometry.h)"
            )
        first = [problem]
        loads = {"f": data.f, "t0": data.t0}  # the estimator's data on every level

        def build(level_domain: Any) -> tuple[Any, dict]:
            if first:  # the starting level is the problem assembled already
                return first.pop(), loads
            return problem_on_domain(level_domain, config)[0], loads

        tic = time.perf_counter()
        levels = adapt(
            build,
            domain,
            options,
            settings,
            monitor=monitor,
            on_level=monitor.adapt_level if monitor is not None else None,
            exact=exact,
        )
        last, records = levels[-1], [level.record() for level in levels]
        if after_solve is not None:
            after_solve(last.problem, last.solution, records)
        return Run(
            last.problem,
            last.solution,
            {**timings, "adaptive_loop": time.perf_counter() - tic},
            records,
            float(last.estimate.total),
            last.estimate.cells,
            last.error,
        )
    records = None
    dofs = problem.n_dofs
    levels = coarser_configs(config, dofs) if options.nested else []
    coarser = [_level_builder(comm, c) for c in levels]
    if coarser:  # a nested solve needs a coarser level (none for small or imported meshes)
        solution, nested = solve_nested(
            problem,
            coarser,
            options,
            monitor=monitor,
            level_monitor=monitor.level if monitor is not None else None,
        )
        records = [dataclasses.asdict(r) for r in nested]
    else:
        solution = solve(problem, options, monitor=monitor)
    if after_solve is not None:
        after_solve(problem, solution, records)
    error = energy_error(problem, solution.u, exact) if exact else None
    stages = {**timings, **solution.timings}
    # the residual estimator (docs/design/estimator.md, 2D and 3D), off unless asked
    if not config.output.estimates:
        return Run(problem, solution, stages, records, None, None, error)
    tic = time.perf_counter()
    est = estimate(problem, solution, f=data.f, t0=data.t0)
    stages["estimator"] = time.perf_counter() - tic
    return Run(problem, solution, stages, records, float(est.total), est.cells, error)
