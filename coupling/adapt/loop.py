"""The adaptive loop solve -> estimate -> mark -> refine (docs/method.md section 10).

Each level is a new :class:`coupling.problem.SignoriniProblem` on the refined
:class:`fem_py.mesh.Domain` (built by the caller's ``problem_builder``), solved by
:func:`coupling.solvers.solve` from the previous solution transferred to it
(:mod:`coupling.adapt.transfer`), estimated (:mod:`coupling.adapt.estimator`) and
marked by Doerfler's rule (:mod:`coupling.adapt.marking`); the marked cells are
refined (:func:`fem_py.mesh.refinement.refine_domain`) and, in 2D, the subdomains the
refinement has graded are split (:func:`fem_py.mesh.grading.split_graded_subdomains`, bound
``coupling.options.GRADING_SPLIT_FACTOR``), so that H/h stays bounded. The same loop
refines a body in R^3 (a :class:`fem_py.mesh.SolidDomain`: tetrahedra, S_h rebuilt on the
refined surface by the problem builder; no subdomains to split).
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

from coupling.adapt.estimator import Estimate, estimate
from coupling.adapt.marking import doerfler_marking
from coupling.adapt.transfer import transfer_iterate
from coupling.manufactured import energy_error
from coupling.options import GRADING_SPLIT_FACTOR, AdaptOptions, SolverOptions
from coupling.solvers import solve
from fem_py.mesh import CORNER_ANGLE, refine_domain, split_graded_subdomains, subdomain_grading

__all__ = ["AdaptOptions", "Level", "adapt"]


@dataclass
class Level:
    """One level of the loop. :meth:`record` gives the JSON fields (dofs, boundary_dofs,
    signorini_dofs, cells, subdomains, estimator, terms, iterations, gradient_steps, newton_steps,
    cg_iterations, converged, time; with an exact solution also error and efficiency);
    ``problem``, ``solution``, ``estimate`` and ``domain`` are the objects themselves."""

    level: int
    domain: Any
    problem: Any
    solution: Any
    estimate: Estimate
    time: float
    marked: int = 0
    error: float | None = None

    def record(self) -> dict[str, Any]:
        sol, p = self.solution, self.problem
        history = sol.history
        newton = [r for r in history if r.line_search is not None]
        tdim = p.V.mesh.topology.dim
        cells = p.V.mesh.topology.index_map(tdim).size_global
        coarse = getattr(self.domain, "coarse", None)  # a body has no subdomains
        return {
            "level": self.level,
            "dofs": p.n_dofs,
            "boundary_dofs": int(p.boundary.n_gamma),
            "signorini_dofs": int(p.n_signorini),
            "cells": int(cells),
            "subdomains": int(coarse.n_subdomains) if coarse is not None else 0,
            "estimator": self.estimate.total,
            "terms": dict(self.estimate.terms),
            "iterations": int(sol.iterations),
            "gradient_steps": len(history) - len(newton),
            "newton_steps": len(newton),
            "cg_iterations": int(sum(r.cg_iterations for r in history)),
            "converged": bool(sol.converged),
            "contact_nodes": int(sol.contact.sum()),
            "marked": self.marked,
            "time": self.time,
            **(
                {}
                if self.error is None
                else {"error": self.error, "efficiency": self.estimate.total / self.error}
            ),
        }


def adapt(
    problem_builder: Callable[[Any], tuple[Any, dict[str, Any]]],
    domain: Any,
    options: SolverOptions,
    adapt_options: AdaptOptions,
    *,
    monitor: Any = None,
    on_level: Callable[[Level], None] | None = None,
    exact: str = "",
    split: bool = True,
) -> list[Level]:
    """Run the adaptive loop from ``domain`` (collective); return the levels.

    Parameters
    ----------
    problem_builder
        ``problem_builder(domain) -> (problem, data)``: the SignoriniProblem on a domain
        and the data it was built with, ``{"f": ..., "t0": ...}`` (text, numbers or UFL
        on domain.mesh) for the estimator.
    domain
        The first (coarsest) :class:`fem_py.mesh.Domain`.
    options, adapt_options
        The ``[solver]`` and ``[adapt]`` sections. ``steps`` refinements give up to
        steps + 1 levels; the loop stops before a level of more than ``max_dofs`` dofs.
    monitor
        Passed to every solve.
    on_level
        Called with each finished :class:`Level` (e.g. to print or measure it).
    exact
        The exact interior solution u (an expression in x, y), when known: each level
        then records the energy error |u_h - u|_1 and the efficiency index eta / error.
    split
        Split the subdomains whose diameter / smallest cell exceeds GRADING_SPLIT_FACTOR
        times the largest such ratio of the first mesh after every refinement (False:
        keep the first partition, every subdomain graded inside).
    """
    levels: list[Level] = []
    split = split and domain.dim == 2  # a body (3D) has no coarse partition
    max_ratio = GRADING_SPLIT_FACTOR * float(subdomain_grading(domain).max()) if split else 0.0
    start = None
    previous = None
    for k in range(adapt_options.steps + 1):
        # P1 dofs = mesh vertices: checked before S_h of the level is assembled
        if k > 0 and domain.mesh.topology.index_map(0).size_global > adapt_options.max_dofs:
            break
        tic = time.perf_counter()
        problem, data = problem_builder(domain)
        if previous is not None:
            start = transfer_iterate(previous.problem, previous.solution, problem)
        scale = previous.solution.residual_scale if previous is not None else None
        solution = solve(problem, options, initial=start, residual_scale=scale, monitor=monitor)
        est = estimate(problem, solution, f=data.get("f", "0"), t0=data.get("t0", "0"))
        level = Level(k, domain, problem, solution, est, time.perf_counter() - tic)
        if exact:
            level.error = energy_error(problem, solution.u, exact)
        levels.append(level)
        if k < adapt_options.steps:
            marked = doerfler_marking(domain.comm, est.cells, adapt_options.theta)
            level.marked = int(domain.comm.allreduce(int(marked.sum())))
            domain = refine_domain(domain, marked.nonzero()[0])
            if split:
                domain = split_graded_subdomains(domain, max_ratio, CORNER_ANGLE)
        if on_level is not None:
            on_level(level)
        previous = level
    return levels
