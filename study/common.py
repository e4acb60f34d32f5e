"""What the parts share: the study's problems (a manufactured problem, its solver
options and its B, built once) and the small fits and formats of the tables.

The study reads the library and never changes it: a variant is a new
:class:`coupling.options.SolverOptions` (``dataclasses.replace``) passed to
:func:`coupling.solvers.solve` with the case's B, or a new case.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Sequence

import numpy as np

from coupling.manufactured import MANUFACTURED, manufactured_problem
from coupling.options import SolverOptions
from coupling.preconditioners import Preconditioner, build_preconditioner
from coupling.problem import SignoriniProblem
from coupling.solvers import Solution, solve
from fem_py.forms import make_material

__all__ = [
    "Case",
    "setup_case",
    "check_solver_fields",
    "describe",
    "options_columns",
    "log",
    "fraction",
    "fit_log_squared",
    "power_slope",
    "join",
    "series_rows",
    "log_ticks",
    "legend_below",
]


def log(message: str) -> None:
    """A progress line of the study (stdout, flushed)."""
    print(message, flush=True)


def fraction(x: float) -> str:
    """``x`` as a short fraction ("1/8")."""
    f = Fraction(x).limit_denominator(4096)
    return str(f.numerator) if f.denominator == 1 else f"{f.numerator}/{f.denominator}"


def check_solver_fields(options: dict[str, Any]) -> dict[str, Any]:
    """Check that ``options`` are SolverOptions fields (one-line ValueError otherwise)."""
    known = {f.name for f in dataclasses.fields(SolverOptions)}
    unknown = sorted(set(options) - known)
    if unknown:
        raise ValueError(
            f"unknown solver option(s) {unknown} in the study; "
            f"use SolverOptions fields {sorted(known)}"
        )
    return dict(options)


@dataclass
class Case:
    """A problem of the study: the assembled problem, the solver options it is solved
    with, and B (:func:`coupling.preconditioners.build_preconditioner`) built once for
    it. ``setup_seconds`` is the time to assemble the problem and build B."""

    problem: SignoriniProblem
    options: SolverOptions
    preconditioner: Preconditioner
    setup_seconds: float

    def solve(self, options: SolverOptions | None = None) -> tuple[Solution, float]:
        """Solve from xi_0 = 0 with ``options`` (default: the case's) and the case's B;
        returns the solution and the wall time of the solve (step estimate, iteration,
        exterior flux). ``options`` must not change what B depends on."""
        tic = time.perf_counter()
        solution = solve(
            self.problem,
            self.options if options is None else options,
            preconditioner=self.preconditioner,
        )
        return solution, time.perf_counter() - tic

    def release(self) -> None:
        """Destroy B."""
        self.preconditioner.destroy()


def setup_case(
    comm: Any,
    cells: int,
    d_over_h: int,
    *,
    shape: str = "square",
    material: str = "carstensen",
    method: str = "pgpm",
    **options: Any,
) -> Case:
    """The manufactured problem (docs/method.md section 8) on ``cells`` cells per side with
    subdomains of d = ``d_over_h`` h, solved with ``options`` (SolverOptions fields).

    The study is about the paper's claims, so its problems solve with ``pgpm`` (the
    paper's Algorithm 3.1) unless a series names another method."""
    opts = SolverOptions(**check_solver_fields({"method": method, **options}))
    tic = time.perf_counter()
    problem = manufactured_problem(
        comm,
        MANUFACTURED[shape](),
        make_material(material),
        cells=cells,
        d_over_h=d_over_h,
        structured=True,
        flux_space=opts.flux_space,
        jacobian=opts.jacobian,
    )
    preconditioner = build_preconditioner(problem, opts)
    return Case(problem, opts, preconditioner, time.perf_counter() - tic)


def describe(problem: SignoriniProblem) -> dict[str, Any]:
    """The size columns of a row: h, d, d/h, dofs, n_Gamma, n_s."""
    d = problem.domain
    return {
        "h": d.h,
        "d": d.subdomain_size,
        "d_over_h": int(round(d.subdomain_size / d.h)),
        "dofs": problem.V.dofmap.index_map.size_global,
        "n_gamma": problem.boundary.n_gamma,
        "n_s": problem.n_signorini,
    }


def options_columns(options: SolverOptions) -> dict[str, Any]:
    """The solver-option columns of a row."""
    o = options
    return {
        "preconditioner": o.preconditioner,
        "method": o.method,
        "projection": o.projection,
        "edge_form": o.edge_form,
        "flux_space": o.flux_space,
        "omega": o.signorini_weight,
        "tol": o.tol,
        "max_iterations": o.max_iterations,
    }


def fit_log_squared(ratio: Sequence[float], y: Sequence[float]) -> dict[str, float]:
    """Least-squares fit y ~ C (1 + ln r)^2 (Theorem 4.1), and the exponent p of
    y ~ c (1 + ln r)^p (p <= 2 is the claim)."""
    x = (1.0 + np.log(np.asarray(ratio, float))) ** 2
    y = np.asarray(y, float)
    C = float(x @ y / (x @ x))
    p = float(np.polyfit(np.log(np.sqrt(x)), np.log(y), 1)[0]) if len(y) > 1 else float("nan")
    return {"C": C, "max_rel_residual": float(np.max(np.abs(C * x - y) / y)), "exponent": p}


def power_slope(h: Sequence[float], y: Sequence[float]) -> float:
    """p of y ~ c h^-p (least squares in log-log)."""
    if len(y) < 2:
        return float("nan")
    inv_h = np.log(1.0 / np.asarray(h, float))
    return float(np.polyfit(inv_h, np.log(np.asarray(y, float)), 1)[0])


def join(values: Sequence[Any], fmt: str = "{:.2f}") -> str:
    """``values`` formatted and comma-separated ("-" for None)."""
    return ", ".join("-" if v is None else fmt.format(v) for v in values)


def series_rows(rows: Sequence[dict], **match: Any) -> list[dict]:
    """The rows whose columns equal ``match``."""
    return [r for r in rows if all(r.get(k) == v for k, v in match.items())]


def log_ticks(ax: Any, values: Sequence[float]) -> None:
    """Log x axis labelled with the given values (cells or d/h) instead of powers of 10."""
    values = sorted(set(values))
    ax.set_xscale("log")
    ax.set_xticks(values)
    ax.set_xticklabels([f"{v:g}" for v in values])
    ax.minorticks_off()


def table_head(*columns: str) -> list[str]:
    """The header and the rule of a markdown table with ``columns``."""
    return ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]


def finish_axes(ax: Any, xlabel: str, ylabel: str, *, legend_size: int = 8) -> None:
    """Label the axes, draw the grid and the legend (one figure panel done)."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=legend_size)


def legend_below(fig: Any, axes: Any, ncol: int = 3) -> None:
    """One legend for all axes, below the figure (no curve hidden behind it)."""
    handles, labels = {}, []
    for ax in np.ravel(axes):
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in handles:
                handles[lab] = h
                labels.append(lab)
    rows = (len(labels) + ncol - 1) // ncol
    fig.legend(
        [handles[lab] for lab in labels],
        labels,
        loc="lower center",
        ncol=ncol,
        fontsize=7,
        bbox_to_anchor=(0.5, -0.02 - 0.035 * rows),
    )
