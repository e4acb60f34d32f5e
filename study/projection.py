"""Part 3, ``projection``: the inexact projection (3.20) with its certified stopping
rule (3.6): inner iterations per step and outer counts for several rho_in and caps,
against the exact projection and against (3.20) stopped by (3.6) with the true optimum
(what (3.6) itself demands).

The projection is instrumented (counted, timed, or replaced by the oracle), so these
runs call :func:`coupling.solvers.pgpm.pgpm` with it directly, exactly as
:func:`coupling.solvers.solve` runs PGPM: the projection of
:func:`coupling.solvers.solution.build_projection`, tau = 1/C0 from Lanczos at xi_0 = 0.
"""
from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from coupling.options import LANCZOS_STEPS
from coupling.solvers import RunResult
from coupling.solvers.lanczos import extremes_at
from coupling.solvers.loop import IterationContext
from coupling.solvers.pgpm import pgpm
from coupling.solvers.projection import ProjectionResult, SignoriniProjection
from coupling.solvers.solution import build_projection
from study.base import Figures, Part, Table, Tables
from study.common import (
    Case,
    describe,
    legend_below,
    log,
    log_ticks,
    power_slope,
    setup_case,
    table_head,
)
from study.sizes import WIDTH, Sizes
from study.writer import ResultWriter

__all__ = [
    "PART",
    "TimedProjection",
    "OracleProjection",
    "run_pgpm",
    "run",
    "summarize",
    "plot",
    "summary_markdown",
]

Projection = Callable[[np.ndarray, np.ndarray], ProjectionResult]


class TimedProjection:
    """Wraps a projection: counts calls (backtracking included) and time."""

    def __init__(self, inner: Projection):
        self.inner, self.calls, self.seconds, self.inner_total = inner, 0, 0.0, 0

    def __call__(self, target: np.ndarray, start: np.ndarray) -> ProjectionResult:
        tic = time.perf_counter()
        out = self.inner(target, start)
        self.seconds += time.perf_counter() - tic
        self.calls += 1
        self.inner_total += out.iterations
        return out

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)


class OracleProjection:
    """(3.20) stopped as soon as (3.6) itself holds, with the true q* = ||P phi~ - phi~||^2
    of the exact projection computed alongside: how many inner steps (3.6) needs
    without a certificate. A measuring device (it needs the exact projection), not a
    method; the iteration is that of coupling/solvers/projection.py with the same theta."""

    def __init__(self, exact: SignoriniProjection, rho_in: float, cap: int):
        self.exact, self.rho_in, self.cap = exact, rho_in, cap

    def __call__(self, target: np.ndarray, start: np.ndarray) -> ProjectionResult:
        M, theta = self.exact.M, self.exact.theta
        best = self.exact(target, start).phi
        q = lambda v: float((v - target) @ (M @ (v - target)))  # noqa: E731
        bound = self.rho_in * q(start) + (1.0 - self.rho_in) * q(best)
        phi = start
        for i in range(1, self.cap + 1):
            phi = np.maximum(0.0, phi - theta * (M @ (phi - target)))
            if q(phi) <= bound:
                return ProjectionResult(phi, i)
        return ProjectionResult(phi, self.cap)

    def __getattr__(self, name: str) -> Any:
        """The rest of the projection's interface (its bounded entries, ``feasible``) is the
        exact projection's."""
        return getattr(self.exact, name)


def run_pgpm(case: Case, projection: Projection) -> tuple[RunResult, np.ndarray, float]:
    """PGPM (Algorithm 3.1) on ``case`` from xi_0 = 0 with ``projection``; returns the
    run, u_h (the Function's array) and the wall time (step estimate and iteration)."""
    from dolfinx import fem

    problem, pc, options = case.problem, case.preconditioner, case.options
    u = fem.Function(problem.V, name="u")
    phi0 = np.zeros(problem.n_signorini)
    tic = time.perf_counter()
    if options.step == "auto":
        tau = 1.0 / extremes_at(problem.functional, pc, u, phi0.size, steps=LANCZOS_STEPS)[1]
    else:
        tau = float(options.step)
    context = IterationContext(
        problem.functional, pc, projection, u, options.tol, options.max_iterations
    )
    run = pgpm(context, phi0, tau=tau)
    return run, u.x.array.copy(), time.perf_counter() - tic


def run(comm: Any, sizes: Sizes) -> list[Table]:
    """Inexact projection (3.20) with the certified rule (3.6) against the exact one,
    and (3.20) stopped by (3.6) with the true optimum (``oracle``)."""
    rows = []
    configs = (
        [("exact", None, None, max(sizes.projection_cells))]
        + [("inexact", rho, cap, top) for rho, cap, top in sizes.projection_configs]
        + [("oracle", rho, 100_000, top) for rho, top in sizes.oracle_rho]
    )
    for cells in sizes.projection_cells:
        reference = None
        for projection, rho, cap, top in configs:
            if cells > top:
                continue
            options = {
                "projection": "exact" if projection == "oracle" else projection,
                "max_iterations": 20_000,
            }
            if projection == "inexact":
                options.update(projection_tol=rho, projection_max_iterations=cap)
            case = setup_case(comm, cells, 4, **options)
            p_s = build_projection(case.preconditioner, case.options)
            timed = TimedProjection(
                OracleProjection(p_s, rho, cap) if projection == "oracle" else p_s
            )
            lam = np.linalg.eigvalsh(np.asarray(case.preconditioner.signorini_metric))
            result, u, seconds = run_pgpm(case, timed)
            inner = np.array([rec.projection_iterations for rec in result.history])
            phi = result.phi.copy()
            if reference is None:
                reference = (u, phi)
            row = {
                "cells": cells,
                **describe(case.problem),
                "projection": projection,
                "rho_in": rho,
                "cap": cap,
                "outer_iterations": result.iterations,
                "converged": result.converged,
                "inner_total": int(inner.sum()),
                "inner_per_step": float(inner.mean()),
                "inner_max": int(inner.max()),
                "steps_at_cap": int(np.count_nonzero(inner == cap)) if cap else 0,
                "projection_calls": timed.calls,
                "projection_s": timed.seconds,
                "solve_s": seconds,
                "cond_ms": lam[-1] / lam[0],
                "u_rel_diff_to_exact": float(
                    np.linalg.norm(u - reference[0]) / np.linalg.norm(reference[0])
                ),
                "phi_rel_diff_to_exact": float(
                    np.linalg.norm(phi - reference[1]) / max(np.linalg.norm(reference[1]), 1e-300)
                ),
            }
            rows.append(row)
            log(
                f"[projection] cells {cells} {projection} rho_in {rho} cap {cap}: outer "
                f"{result.iterations}, inner {row['inner_total']} "
                f"({row['inner_per_step']:.1f}/step), {seconds:.1f} s"
            )
            case.release()
    return [
        Table(
            "projection",
            "Inexact projection (3.20) against the exact projection",
            "Square, carstensen, d/h = 4, tol 1e-8. `inexact`: projected iteration "
            "(3.20) with theta = 1/lambda_max(M_s), stopped when (3.6) is certified "
            "with rho = `rho_in` (dual lower bound, see coupling/solvers/projection.py) "
            "or at `cap` inner steps. Inner steps cost one product with the dense M_s each; "
            "`exact`: primal-dual active set (its `inner` are active-set iterations, "
            "each a dense solve). `oracle`: (3.20) stopped as soon as (3.6) holds with "
            "the true optimum (computed by the exact projection; a measurement of what "
            "(3.6) itself demands, not a method). `*_rel_diff_to_exact`: final iterate "
            "against the run with the exact projection.",
            rows,
            [
                "cells",
                "n_s",
                "projection",
                "rho_in",
                "cap",
                "outer_iterations",
                "converged",
                "inner_per_step",
                "inner_total",
                "steps_at_cap",
                "projection_s",
                "solve_s",
                "u_rel_diff_to_exact",
            ],
        )
    ]


def summarize(tables: Tables) -> dict[str, Any]:
    """Per configuration: outer and inner counts against cells and their exponents."""
    rows = tables["projection"]
    out: dict[str, Any] = {"configs": {}}
    for r in rows:
        key = {
            "exact": "exact",
            "inexact": f"certified, rho_in {r['rho_in']}, cap {r['cap']}",
            "oracle": f"oracle, rho_in {r['rho_in']}",
        }[r["projection"]]
        entry = out["configs"].setdefault(
            key,
            {
                "cells": [],
                "outer": [],
                "inner_per_step": [],
                "inner_total": [],
                "solve_s": [],
                "u_rel_diff": [],
                "converged": True,
            },
        )
        entry["cells"].append(r["cells"])
        entry["outer"].append(r["outer_iterations"])
        entry["inner_per_step"].append(r["inner_per_step"])
        entry["inner_total"].append(r["inner_total"])
        entry["solve_s"].append(r["solve_s"])
        entry["u_rel_diff"].append(r["u_rel_diff_to_exact"])
        entry["converged"] &= bool(r["converged"])
    for entry in out["configs"].values():
        h = WIDTH / np.array(entry["cells"], float)
        entry["outer_slope"] = power_slope(h, entry["outer"])
        entry["inner_slope"] = power_slope(h, entry["inner_per_step"])
    return out


def plot(tables: Tables, writer: ResultWriter) -> Figures:
    """Outer iterations and inner iterations per step against cells."""
    summary = summarize(tables)
    fig, axes = writer.subplots(1, 2, figsize=(11, 4.2))
    for key, s in summary["configs"].items():
        style = "k-o" if key == "exact" else "o--"
        axes[0].loglog(s["cells"], s["outer"], style, label=key)
        if key != "exact":
            axes[1].loglog(s["cells"], s["inner_per_step"], "o--", label=key)
    axes[0].set_ylabel("outer PGPM iterations")
    axes[1].set_ylabel("inner iterations of (3.20) per outer step")
    cells = [c for s in summary["configs"].values() for c in s["cells"]]
    for ax in axes:
        log_ticks(ax, cells)
        ax.set_xlabel("cells per side (d/h = 4)")
        ax.grid(True, which="both", alpha=0.3)
    legend_below(fig, axes)
    fig.suptitle("Inexact projection: outer count and inner work")
    return [
        writer.figure(
            fig,
            "projection",
            "Outer iterations (left) and inner iterations per step (right) of the inexact "
            "projection for several rho_in and caps, against the exact projection",
        )
    ]


def summary_markdown(summary: dict[str, Any]) -> str:
    """Outer and inner counts per configuration with their fitted exponents."""
    lines = table_head(
        "configuration",
        "outer iterations",
        "inner per step",
        "total inner",
        "fitted p (outer ~ h^-p)",
        "fitted p (inner/step ~ h^-p)",
    )
    for key, s in summary["configs"].items():
        lines.append(
            f"| {key} | {', '.join(str(x) for x in s['outer'])} | "
            f"{', '.join(f'{x:.1f}' for x in s['inner_per_step'])} | "
            f"{', '.join(str(x) for x in s['inner_total'])} | {s['outer_slope']:.2f} | "
            f"{s['inner_slope']:.2f} |"
        )
    return "\n".join(lines)


PART = Part(
    "projection",
    "Part 3: inexact projection (3.20) against the exact projection",
    "Theorem 3.1 allows an inexact projection satisfying (3.6); the iteration (3.20) "
    "converges at a rate set by cond(M_s) (Theorem 4.2).",
    run,
    summarize,
    plot,
    summary_markdown,
)
