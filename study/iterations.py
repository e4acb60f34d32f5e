"""Part 1, ``iterations``: PGPM iterations to tol = 1e-8 against h at fixed d/h and
against d/h at fixed d (claims 7.1 and 7.4; Theorems 3.1 and 4.1), for the
``substructuring``, ``identity`` and ``exact`` preconditioners, and the other solver
methods of :data:`METHODS` (``apgpm``, ``ssn``)."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from coupling.solvers import Solution
from study.base import Figures, Part, Table, Tables
from study.common import (
    Case,
    check_solver_fields,
    describe,
    finish_axes,
    fit_log_squared,
    fraction,
    log,
    log_ticks,
    options_columns,
    power_slope,
    setup_case,
    table_head,
)
from study.pencil import DENSE_MAX, PencilOperators, jacobian_at
from study.sizes import WIDTH, Sizes
from study.writer import ResultWriter

__all__ = [
    "PART",
    "METHODS",
    "Series",
    "iteration_series",
    "run",
    "summarize",
    "plot",
    "summary_markdown",
]

#: Solver methods of the ``iterations`` part, as SolverOptions fields, run on every
#: point of the substructuring series: the paper's PGPM first (the claims are checked
#: on it), then our extensions. Another variant is studied by adding its fields here.
METHODS: tuple[dict[str, Any], ...] = ({"method": "pgpm"}, {"method": "apgpm"}, {"method": "ssn"})


@dataclass(frozen=True)
class Series:
    """One line of the iterations part: a label, what varies ("h" or "d/h"), the
    solver options, the (cells, d/h) points and the solver methods run on each."""

    label: str
    varies: str
    options: dict
    points: tuple[tuple[int, int], ...]
    methods: tuple[dict, ...] = ({},)


def iteration_series(sizes: Sizes, methods: Sequence[dict] = METHODS) -> list[Series]:
    """The series of the iterations part; every entry of ``methods`` (SolverOptions
    fields) is run on every point of the substructuring series."""
    k = sizes.d_subdomains
    sub = {"preconditioner": "substructuring"}
    out = [
        Series(f"substructuring, d/h = {r}", "h", sub, tuple((c, r) for c in cells), tuple(methods))
        for r, cells in sizes.ratio_series
    ]
    out.append(
        Series(
            f"substructuring, d = {fraction(WIDTH / k)}",
            "d/h",
            sub,
            tuple((c, c // k) for c in sizes.d_cells),
            tuple(methods),
        )
    )
    out.append(
        Series(
            "identity (Euclidean B)",
            "h",
            {"preconditioner": "identity", "max_iterations": 400_000},
            tuple((c, 2) for c in sizes.identity_cells),
        )
    )
    out.append(
        Series(
            "exact (diagonal blocks of A)",
            "h",
            {"preconditioner": "exact"},
            tuple((c, 4) for c in sizes.exact_cells),
        )
    )
    return out


def run(comm: Any, sizes: Sizes, methods: Sequence[dict] = METHODS) -> list[Table]:
    """Iterations to tol (default 1e-8) on the square, carstensen material.

    Claims 7.1 and 7.4: bounded at fixed d/h, at most C (1 + ln(d/h))^2 at fixed d,
    ~ h^-2 for the Euclidean B (Remark 2.1). Each problem is set up once and solved
    with every method of its series (the method is a solver option only: the
    preconditioner and the projection do not depend on it).
    """
    rows = []
    for series in iteration_series(sizes, methods):
        for cells, r in series.points:
            case = setup_case(comm, cells, r, **series.options)
            setup = case.setup_seconds
            for method in series.methods:
                options = dataclasses.replace(case.options, **check_solver_fields(method))
                result, seconds = case.solve(options)
                row = {
                    "series": series.label,
                    "varies": series.varies,
                    "cells": cells,
                    **describe(case.problem),
                    **options_columns(options),
                    "iterations": result.iterations,
                    "converged": result.converged,
                    "inner_total": inner_total(result),
                    "C0": result.C0,
                    "tau": result.tau,
                    "energy_increases": result.energy_increases,
                    "contact_nodes": int(result.contact.sum()),
                    "setup_s": setup,
                    "solve_s": seconds,
                    "s_per_iteration": result.timings["solve"] / max(result.iterations, 1),
                }
                if options.preconditioner == "identity":
                    row.update(euclidean_condition(case, result, options.tol))
                rows.append(row)
                log(
                    f"[iterations] {series.label}, {row['method']}: cells {cells}, "
                    f"{row['dofs']} dofs -> {result.iterations} its ("
                    f"{'converged' if result.converged else 'NOT converged'}),"
                    f" setup {setup:.1f} s, solve {seconds:.1f} s"
                )
            case.release()
    return [
        Table(
            "iterations",
            "Iterations to the tolerance",
            "Square of width 0.5, Signorini arc = bottom side, material `carstensen`, "
            "manufactured data (docs/method.md section 8), xi_0 = 0, stopping rule "
            "||xi_k+1 - y_k||_B <= tol ||xi_k+1||_B (y_k = xi_k except for apgpm). "
            "`method`: `pgpm` is the paper's Algorithm 3.1; `apgpm` (Nesterov's "
            "constant momentum in the B metric from the Lanczos estimate of lambda_min, "
            "with restarts; y_k its extrapolated point) and `ssn` (semismooth Newton "
            "with B-preconditioned CG, the active set predicted by one exact PGPM "
            "step; `iterations` include its 5 PGPM warm steps, `inner_total` is its "
            "CG iterations) are our extensions. "
            "`identity` uses d/h = 2 (d is unused by it), `exact` d/h = 4. For "
            "`identity`: `kappa_euclidean` = cond(D^2 J_h(xi_h)) in the Euclidean "
            "metric (dense), `iterations_model` = ln(tau lambda_min / tol) / "
            "-ln(1 - tau lambda_min), the steps the slowest mode needs until its step "
            "falls below tol.",
            rows,
            [
                "series",
                "method",
                "cells",
                "h",
                "d_over_h",
                "dofs",
                "iterations",
                "converged",
                "inner_total",
                "C0",
                "kappa_euclidean",
                "iterations_model",
                "s_per_iteration",
                "solve_s",
            ],
        )
    ]


def inner_total(result: Solution) -> int:
    """The inner iterations of a run: those of the projection in the gradient steps and
    the CG iterations of the Newton steps (ssn)."""
    return int(sum(rec.projection_iterations + rec.cg_iterations for rec in result.history))


def euclidean_condition(case: Case, result: Solution, tol: float) -> dict[str, float]:
    """Remark 2.1: cond(D^2 J_h(xi_h)) in the Euclidean metric (dense, small sizes), and
    the iteration count it implies. The slowest mode contracts by 1 - tau lambda_min per
    step and its step is tau lambda_min times its error, so the run stops after about
    ln(tau lambda_min / tol) / -ln(1 - tau lambda_min) steps."""
    problem = case.problem
    pencil = PencilOperators(problem, case.preconditioner, jacobian_at(problem, result))
    if pencil.n > DENSE_MAX:
        return {}
    lo, hi = pencil.dense_extremes()
    t = result.tau * lo
    return {
        "kappa_euclidean": hi / lo,
        "tau_lambda_min": t,
        "iterations_model": math.log(t / tol) / -math.log1p(-t),
    }


def summarize(tables: Tables) -> dict[str, Any]:
    """Per series and method: the counts, their spread, and the fit of the series (the
    exponent of 1/h at fixed d/h, C (1 + ln(d/h))^2 at fixed d)."""
    rows = tables["iterations"]
    out: dict[str, Any] = {"series": {}}
    for label, method in dict.fromkeys((r["series"], r.get("method") or "pgpm") for r in rows):
        s = [r for r in rows if r["series"] == label and (r.get("method") or "pgpm") == method]
        its = [r["iterations"] for r in s]
        entry = {
            "method": method,
            "cells": [r["cells"] for r in s],
            "d_over_h": [r["d_over_h"] for r in s],
            "h": [r["h"] for r in s],
            "inner_total": [r.get("inner_total") for r in s],
            "solve_s": [r["solve_s"] for r in s],
            "iterations": its,
            "dofs": [r["dofs"] for r in s],
            "converged": all(r["converged"] for r in s),
            "max_over_min": max(its) / min(its),
            "varies": s[0]["varies"],
            "preconditioner": s[0]["preconditioner"],
        }
        if s[0]["varies"] == "d/h":
            entry["fit"] = fit_log_squared(entry["d_over_h"], its)
        else:
            h = [r["h"] for r in s]
            entry["slope"] = power_slope(h, its)
            entry["local_slopes"] = list(np.diff(np.log(its)) / np.diff(np.log(1 / np.array(h))))
            kappa = [r.get("kappa_euclidean") for r in s]
            if all(k is not None for k in kappa) and all(r.get("iterations_model") for r in s):
                entry.update(
                    kappa_euclidean=kappa,
                    kappa_slope=power_slope(h, kappa),
                    iterations_model=[r["iterations_model"] for r in s],
                )
        out["series"][label if method == "pgpm" else f"{label}, {method}"] = entry
    return out


METHOD_STYLE = {"pgpm": "o-", "apgpm": "s--", "ssn": "^:"}


def plot(tables: Tables, writer: ResultWriter) -> Figures:
    """Iterations against 1/h (fixed d/h) and against d/h (fixed d) with the fit."""
    summary = summarize(tables)
    fig, ax = writer.subplots(figsize=(6.5, 4.5))
    for label, s in summary["series"].items():
        if s["varies"] != "h":
            continue
        ax.loglog(
            1.0 / np.array(s["h"]),
            s["iterations"],
            METHOD_STYLE.get(s["method"], "o-"),
            label=label
            if s["method"] in label or s["preconditioner"] != "substructuring"
            else f"{label}, pgpm",
        )
    ax.set_xlabel("1/h")
    ax.set_ylabel("iterations to tol")
    ax.set_title("Iterations against h (fixed d/h)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    files = [
        writer.figure(
            fig,
            "iterations_h",
            "Iterations against 1/h at fixed d/h "
            "(substructuring; pgpm, apgpm, ssn), and PGPM with the identity and exact "
            "preconditioners",
        )
    ]
    fig, ax = writer.subplots(figsize=(6.5, 4.5))
    for label, s in summary["series"].items():
        if s["varies"] != "d/h":
            continue
        r = np.array(s["d_over_h"], float)
        (line,) = ax.semilogx(
            r,
            s["iterations"],
            METHOD_STYLE.get(s["method"], "o")[0],
            label=f"{label if s['method'] in label else label + ', pgpm'} " "(measured)",
        )
        rr = np.geomspace(r.min(), r.max(), 100)
        ax.semilogx(
            rr,
            s["fit"]["C"] * (1 + np.log(rr)) ** 2,
            "--",
            color=line.get_color(),
            label=f"{s['fit']['C']:.3g} (1 + ln(d/h))^2",
        )
    log_ticks(
        ax, [r for s in summary["series"].values() if s["varies"] == "d/h" for r in s["d_over_h"]]
    )
    ax.set_title("Iterations against d/h (fixed d)")
    finish_axes(ax, "d/h", "iterations to tol")
    caption = "Iterations against d/h at fixed d with the fitted C (1 + ln(d/h))^2"
    return files + [writer.figure(fig, "iterations_ratio", caption)]


def summary_markdown(summary: dict[str, Any]) -> str:
    """The counts of every series and their fit."""
    lines = table_head("series", "iterations", "max/min", "fit")
    for label, s in summary["series"].items():
        if "fit" in s:
            f = s["fit"]
            fit = (
                f"C (1 + ln(d/h))^2 with C = {f['C']:.3g} (largest relative residual "
                f"{f['max_rel_residual']:.2f}); exponent of (1 + ln(d/h)): {f['exponent']:.2f}"
            )
        else:
            fit = f"iterations ~ h^-p with p = {s['slope']:.2f}"
        lines.append(
            f"| {label} | {', '.join(str(i) for i in s['iterations'])} | "
            f"{s['max_over_min']:.2f} | {fit} |"
        )
    return "\n".join(lines)


PART = Part(
    "iterations",
    "Part 1: PGPM iterations against h and d/h",
    "Claims 7.1 and 7.4 of docs/method.md: with the substructuring preconditioner the count "
    "is bounded as h -> 0 at fixed d/h and grows at most like (1 + ln(d/h))^2 at fixed "
    "d (Theorems 3.1 and 4.1); with B = identity it grows like h^-2 (Remark 2.1).",
    run,
    summarize,
    plot,
    summary_markdown,
)
