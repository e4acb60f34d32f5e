"""Part 6, ``adaptivity``: uniform against adaptive refinement on the singular L-shape
(issue 19; docs/design/estimator.md): dofs, energy error, estimator, efficiency index
and fitted rates per level, and how the PGPM and ssn counts move with the local mesh
grading (Theorem 4.1: (1 + ln(d/h))^2 with the local d/h), which the loop bounds by
splitting the graded subdomains (fem_py.mesh.grading; docs/design/adapt.md)."""
from __future__ import annotations

from typing import Any

import numpy as np
from mpi4py import MPI

from coupling.adapt import AdaptOptions, adapt
from coupling.io.levels import fitted_slope, slope_levels
from coupling.manufactured import lshape_corner
from coupling.options import SLOPE_MIN_DOFS, SolverOptions
from coupling.problem import SignoriniProblem
from study.base import Figures, Part, Table, Tables
from study.common import join, log, table_head
from study.sizes import Sizes
from study.writer import ResultWriter
from fem_py.forms import make_material
from fem_py.mesh import GeometrySpec, build_domain, subdomain_grading

__all__ = ["PART", "REFINEMENTS", "METHODS", "run", "summarize", "plot", "summary_markdown"]

#: Doerfler's theta of each refinement: 1 marks every cell (uniform refinement by the
#: same Plaza routine, so the meshes are those of h halved).
REFINEMENTS = {"adaptive": 0.5, "uniform": 1.0}
METHODS = ("ssn", "pgpm")
FIRST_H, SUBDOMAIN = 1 / 16, 1 / 8  # the first mesh and its coarse partition
MAX_STEPS = 40  # refinements; the loop stops at Sizes.adapt_max_dofs first


def _levels(comm: Any, theta: float, method: str, max_dofs: int) -> list[dict]:
    """The rows of one adaptive loop: the corner singularity, linear material, f = 0."""
    exact = lshape_corner()
    material = make_material("linear")

    def build(domain: Any) -> tuple[SignoriniProblem, dict]:
        data = exact.data(domain.mesh, material)
        data["f"] = "0"  # u is harmonic
        problem = SignoriniProblem(
            domain, material, f=data["f"], u0=data["u0"], t0=data["t0"], a=data["a"]
        )
        return problem, data

    domain = build_domain(
        comm, GeometrySpec("lshape", h=FIRST_H, subdomain_size=SUBDOMAIN, structured=True)
    )
    levels = adapt(
        build,
        domain,
        SolverOptions(method=method),
        AdaptOptions(steps=MAX_STEPS, theta=theta, max_dofs=max_dofs),
        exact=exact.u,
    )
    rows = []
    for level in levels:
        r = level.record()
        h_min, h_max = _cell_sizes(level.domain.mesh)
        rows.append(
            {
                **{
                    k: r[k]
                    for k in ("level", "dofs", "boundary_dofs", "cells", "subdomains", "marked")
                },
                "grading": float(subdomain_grading(level.domain).max()),
                "h_min": h_min,
                "d_over_h_min": SUBDOMAIN / h_max,
                "d_over_h_max": SUBDOMAIN / h_min,
                **{
                    k: r[k]
                    for k in (
                        "error",
                        "estimator",
                        "efficiency",
                        "iterations",
                        "gradient_steps",
                        "newton_steps",
                        "cg_iterations",
                        "converged",
                        "time",
                    )
                },
            }
        )
    return rows


def _cell_sizes(mesh: Any) -> tuple[float, float]:
    """The smallest and largest cell diameter (longest edge) of a P1 triangle mesh
    (collective)."""
    n = mesh.topology.index_map(2).size_local
    corners = mesh.geometry.x[mesh.geometry.dofmap.array.reshape(-1, 3)[:n], :2]
    edges = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    return (
        float(mesh.comm.allreduce(edges.min(initial=np.inf), op=MPI.MIN)),
        float(mesh.comm.allreduce(edges.max(initial=0.0), op=MPI.MAX)),
    )


def run(comm: Any, sizes: Sizes) -> list[Table]:
    """Adaptive (theta = 0.5) and uniform (theta = 1) loops from h = 1/16 (d = 1/8, 12
    subdomains), each solved by ssn and by pgpm from the transferred iterate, up to
    ``sizes.adapt_max_dofs`` dofs."""
    rows = []
    for refinement, theta in REFINEMENTS.items():
        for method in METHODS:
            for r in _levels(comm, theta, method, sizes.adapt_max_dofs):
                rows.append({"refinement": refinement, "method": method, **r})
                log(
                    f"[adaptivity] {refinement} {method} level {r['level']}: {r['dofs']} dofs, "
                    f"error {r['error']:.3e}, eta {r['estimator']:.3e}, "
                    f"{r['iterations']} its ({r['cg_iterations']} CG)"
                )
    return [
        Table(
            "adaptivity",
            "Uniform against adaptive refinement on the singular L-shape",
            "u = r^(2/3) sin(2 theta/3) at the re-entrant corner of the L-shape "
            "(coupling.manufactured.lshape_corner), linear material, f = 0, no contact; "
            f"first mesh h = 1/{round(1 / FIRST_H)}, subdomains d = 1/{round(1 / SUBDOMAIN)} "
            "on the first mesh, split where the refinement grades them (`subdomains`, "
            "`grading`: the largest diameter / smallest cell of a subdomain, at most "
            "2 d/h); `adaptive`: Doerfler theta = 0.5, `uniform`: theta = 1 "
            "(every cell refined). Each level starts from the previous level's solution "
            "(tol 1e-8). `error` = |u - u_h|_1, `estimator` = eta (docs/design/"
            "estimator.md), `efficiency` = eta / error, `d_over_h_min`/`max`: d over the "
            "largest / smallest cell diameter (the local d/h of Theorem 4.1); `iterations`: "
            "outer steps of the method (ssn: PGPM warm-up `gradient_steps` and Newton "
            "steps with their `cg_iterations`).",
            rows,
            [
                "refinement",
                "method",
                "level",
                "dofs",
                "error",
                "estimator",
                "efficiency",
                "d_over_h_max",
                "subdomains",
                "grading",
                "iterations",
                "newton_steps",
                "cg_iterations",
            ],
        )
    ]


def _series(rows: list[dict]) -> dict[tuple[str, str], list[dict]]:
    out: dict[tuple[str, str], list[dict]] = {}
    for r in rows:
        out.setdefault((r["refinement"], r["method"]), []).append(r)
    return out


def summarize(tables: Tables) -> dict[str, Any]:
    """Per refinement and method: the fitted rates of error and estimator (levels with N
    >= SLOPE_MIN_DOFS, or all), the efficiency band, the counts per level; and, for each
    uniform level after the first, the fewest adaptive dofs with an error at least as
    small, as a fraction of the uniform dofs."""
    series = _series(tables["adaptivity"])
    out: dict[str, Any] = {"series": {}, "min_dofs": SLOPE_MIN_DOFS}
    for (refinement, method), s in series.items():
        dofs = [r["dofs"] for r in s]
        index = [r["efficiency"] for r in s]
        out["series"][f"{refinement}, {method}"] = {
            "refinement": refinement,
            "method": method,
            "dofs": dofs,
            "error_slope": fitted_slope(dofs, [r["error"] for r in s]),
            "estimator_slope": fitted_slope(dofs, [r["estimator"] for r in s]),
            "efficiency_min": min(index),
            "efficiency_max": max(index),
            "efficiency_band": max(index) / min(index),
            "iterations": [r["iterations"] for r in s],
            "cg_iterations": [r["cg_iterations"] for r in s],
            "d_over_h_max": [r["d_over_h_max"] for r in s],
            "subdomains": [r["subdomains"] for r in s],
            "grading": [r["grading"] for r in s],
            "converged": all(r["converged"] for r in s),
        }
    adaptive, uniform = series.get(("adaptive", "ssn"), []), series.get(("uniform", "ssn"), [])
    out["dofs_fraction"] = [
        {
            "uniform_dofs": u["dofs"],
            "uniform_error": u["error"],
            "adaptive_dofs": min((a["dofs"] for a in adaptive if a["error"] <= u["error"]),
                                 default=None),  # fmt: skip
        }
        for u in uniform[1:]
    ]
    for item in out["dofs_fraction"]:
        a = item["adaptive_dofs"]
        item["fraction"] = None if a is None else a / item["uniform_dofs"]
    return out


def plot(tables: Tables, writer: ResultWriter) -> Figures:
    """Left: error and estimator against the dofs (ssn levels), slopes in the legend;
    right: the outer counts of pgpm and ssn per level against the dofs."""
    series = _series(tables["adaptivity"])
    fig, (left, right) = writer.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True)
    colours = {"adaptive": "C0", "uniform": "C1"}
    for (refinement, method), s in series.items():
        dofs = [r["dofs"] for r in s]
        if method == "ssn":
            for key, style in (("error", "s-"), ("estimator", "o--")):
                values = [r[key] for r in s]
                left.loglog(
                    dofs,
                    values,
                    style,
                    color=colours[refinement],
                    label=f"{refinement} {key} (slope {fitted_slope(dofs, values):.2f})",
                )
        right.semilogx(
            dofs,
            [r["iterations"] for r in s],
            "o-" if method == "pgpm" else "s--",
            color=colours[refinement],
            label=f"{refinement}, {method}",
        )
    left.set_xlabel("dofs N")
    left.set_ylabel(r"$|u - u_h|_1$, $\eta$")
    adaptive = [r["dofs"] for r in series.get(("adaptive", "ssn"), [])]
    where = "all levels" if slope_levels(adaptive).all() else f"N >= {SLOPE_MIN_DOFS}"
    left.set_title(f"Singular L-shape (slopes fitted over {where})")
    right.set_xlabel("dofs N")
    right.set_ylabel("outer iterations per level")
    right.set_title("PGPM and ssn counts per level (from the transferred iterate)")
    for ax in (left, right):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    return [writer.figure(fig, "adaptivity", "Uniform against adaptive refinement")]


def summary_markdown(summary: dict[str, Any]) -> str:
    """Rates, efficiency band and counts per series; the dofs the adaptive loop needs for
    the error of each uniform level."""
    lines = table_head(
        "series",
        "levels (dofs)",
        "error slope",
        "eta slope",
        "eta / error",
        "outer iterations per level",
        "CG per level",
    )
    for name, s in summary["series"].items():
        lines.append(
            f"| {name} | {len(s['dofs'])} ({s['dofs'][0]} .. {s['dofs'][-1]}) | "
            f"{s['error_slope']:.2f} | {s['estimator_slope']:.2f} | "
            f"{s['efficiency_min']:.2f} .. {s['efficiency_max']:.2f} | "
            f"{join(s['iterations'], '{}')} | {join(s['cg_iterations'], '{}')} |"
        )
    lines += [""] + table_head(
        "uniform dofs", "uniform error", "fewest adaptive dofs with that error", "fraction"
    )
    for item in summary["dofs_fraction"]:
        a, f = item["adaptive_dofs"], item["fraction"]
        lines.append(
            f"| {item['uniform_dofs']} | {item['uniform_error']:.3e} | "
            f"{'not reached' if a is None else a} | {'-' if f is None else f'{f:.2f}'} |"
        )
    return "\n".join(lines)


PART = Part(
    "adaptivity",
    "Part 6: adaptive refinement on the singular L-shape",
    "Issue 19's targets: adaptive error and estimator slope at most -0.45 over the levels "
    "with N >= 1000 (uniform: -1/3), the uniform error reached with at most half the "
    "dofs, the efficiency index within a band of max/min <= 3; and how the counts of "
    "PGPM and ssn move with the local grading (bounded by splitting graded subdomains).",
    run,
    summarize,
    plot,
    summary_markdown,
)
