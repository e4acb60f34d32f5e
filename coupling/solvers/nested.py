"""Nested iteration: solve on a hierarchy of meshes, coarse to fine, each level started
from the previous level's solution (issue 18; full multigrid's outer loop).

The fine problem (2.3) is solved by the method of ``options`` started from the coarse
solution prolonged to the fine mesh: u_h by P1 interpolation (a point location of the
fine nodes in the coarse mesh), the gap phi_h by linear interpolation along Gamma (0 on
Gamma_t). Since the iteration counts of the substructuring-preconditioned methods do not
grow with refinement at fixed d/h, a prolonged start that is within the discretisation
error leaves only a few steps on the fine mesh. The step tau = 1/C0 of the coarse level
is kept (C0 is bounded independently of h, Theorem 4.1), so the fine level needs no
Lanczos estimate.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np
from scipy.spatial import cKDTree

from coupling.options import SolverOptions
from coupling.solvers.records import Monitor
from coupling.solvers.solution import Solution, solve
from fem_py.dofs import gather_p1
from fem_py.mesh.location import P1Points
from fem_py.mesh.location3d import on_surface
from fem_py.polyline import closest_on_polygon

__all__ = ["LevelRecord", "prolong", "solve_nested"]


@dataclass(frozen=True)
class LevelRecord:
    """One level of a nested solve: its size, the iterations and CG iterations taken
    there, and the wall time of the level (assembly, prolongation and solve)."""

    dofs: int
    boundary_dofs: int
    iterations: int
    cg_iterations: int
    converged: bool
    time: float


def prolong(coarse: Any, coarse_solution: Solution, fine: Any) -> tuple[np.ndarray, np.ndarray]:
    """(u on the owned fine dofs, the gaps of the fine Signorini nodes) from a coarse
    solution (collective: every rank evaluates the gathered coarse field at its own nodes).
    For elasticity every component of u and of the jump is carried over, and the fine gaps
    are the jump's components in the fine nodes' frames (``GapMap.restrict``)."""
    comm = fine.comm
    gathered = gather_p1(coarse_solution.u)
    x, values, cells = comm.bcast(gathered, root=0) if comm.size > 1 else gathered
    n_owned = fine.V.dofmap.index_map.size_local
    dim, d = x.shape[1], fine.components
    values = values.reshape(len(x), d)
    points = fine.V.tabulate_dof_coordinates()[:n_owned, :dim]
    # an n-fold uniform refinement has n^dim times the cells: its nodes are matched by
    # sorting
    fine_cells = fine.V.mesh.topology.index_map(dim).size_global
    divisions = max(1, round((fine_cells / len(cells)) ** (1.0 / dim)))
    located = P1Points(x, cells, points, divisions=divisions)  # once for the d components
    u = np.stack([located.interpolate(values[:, k]) for k in range(d)], axis=1)
    lost = np.isnan(u).any(axis=1)  # on the coarse boundary up to round-off (or outside a
    if lost.any():  # coarse curved surface): the nearest coarse node
        u[lost] = values[cKDTree(x).query(points[lost])[1]]
    b_coarse, b_fine = coarse.boundary, fine.boundary
    jump = coarse.gap.extend(np.zeros(b_coarse.n_gamma), coarse_solution.phi)
    jump = jump.reshape(-1, d)  # (n, d): the jump at every coarse node of Gamma
    coarse_nodes = b_coarse.nodes
    targets = b_fine.nodes[b_fine.signorini]
    if dim == 3:
        at_targets = np.stack(
            [_surface_gap(b_coarse, jump[:, k], targets) for k in range(d)], axis=1
        )
    else:
        _, seg, t = closest_on_polygon(targets, coarse_nodes)
        nxt = (seg + 1) % len(coarse_nodes)
        at_targets = (1.0 - t)[:, None] * jump[seg] + t[:, None] * jump[nxt]
    fine_jump = np.zeros((len(b_fine.nodes), d))
    fine_jump[b_fine.signorini] = at_targets
    gaps = fine.gap.restrict(fine_jump.ravel())
    return u.ravel(), np.where(fine.gap.bounded, np.maximum(gaps, 0.0), gaps)


def _surface_gap(coarse_boundary: Any, gap: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The coarse gap (P1 on the coarse surface) at fine boundary ``points``: linear on the
    coarse triangle under a point (flat faces: the fine nodes lie on them), else (a curved
    surface, the fine nodes off the coarse facets) the value of the nearest coarse node."""
    nodes, triangles = coarse_boundary.nodes, coarse_boundary.triangles
    diameter = float(np.linalg.norm(nodes.max(axis=0) - nodes.min(axis=0)))
    triangle, bary = on_surface(nodes, triangles, points, 1e-10 * diameter)
    found = triangle >= 0
    out = np.empty(len(points))
    out[found] = np.einsum("ij,ij->i", bary[found], gap[triangles[triangle[found]]])
    if (~found).any():
        out[~found] = gap[cKDTree(nodes).query(points[~found])[1]]
    return out


def solve_nested(
    problem: Any,
    coarser: Sequence[Callable[[], Any]],
    options: SolverOptions,
    *,
    monitor: Monitor | None = None,
    level_monitor: Callable[[LevelRecord], None] | None = None,
) -> tuple[Solution, list[LevelRecord]]:
    """Solve ``problem`` by nested iteration over the coarser levels ``coarser`` (problem
    builders, coarsest first; each is called when its level starts, so their assembly is
    part of the solve) and return (the solution of ``problem``, one record per level,
    coarsest first).

    The coarsest level is solved with ``options`` from xi_0 = (0, 0); each next one,
    ``problem`` last, from the prolonged solution (:func:`prolong`) with the step tau and
    (once a level has one) ssn's residual scale of the level before. The solution's
    timings hold its own stages plus ``coarse_levels`` (assembly and solves of the
    coarser levels) and ``prolongation`` (onto ``problem``).
    """
    levels: list[LevelRecord] = []
    previous = previous_solution = None
    tic = time.perf_counter()
    for build in [*coarser, lambda: problem]:
        start = time.perf_counter()
        level = build()
        if level is problem:
            coarse_time = start - tic
        if previous is None:
            level_options, initial, scale = options, None, None
        else:
            level_options = dataclasses.replace(options, step=previous_solution.tau)
            initial = prolong(previous, previous_solution, level)
            scale = previous_solution.residual_scale
            previous = previous_solution = None  # the coarser level's memory goes now
        prolonged = time.perf_counter()
        solution = solve(
            level,
            level_options,
            initial=initial,
            residual_scale=scale,
            monitor=monitor if level is problem else None,
            exterior_flux=level is problem,  # a coarser level passes on (u, phi) alone
        )
        levels.append(
            LevelRecord(
                dofs=level.n_dofs,
                boundary_dofs=int(level.boundary.n_gamma),
                iterations=solution.iterations,
                cg_iterations=int(sum(r.cg_iterations for r in solution.history)),
                converged=solution.converged,
                time=time.perf_counter() - start,
            )
        )
        if level_monitor is not None:
            level_monitor(levels[-1])
        previous, previous_solution = level, solution
    solution.timings = {
        "coarse_levels": coarse_time,
        "prolongation": prolonged - start,
        **solution.timings,
    }
    return solution, levels
