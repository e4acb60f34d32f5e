"""Part 5, ``variants``: the edge forms ``paper`` and ``sqrt-laplacian`` (iterations and
kappa); the ``ufl`` and ``handwritten`` Jacobians (assembly time, iterates)."""
from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse.linalg as spla

from coupling.distributed import gather_matrix
from study.base import Figures, Part, Table, Tables
from study.common import (
    describe,
    fraction,
    join,
    legend_below,
    log,
    log_ticks,
    series_rows,
    setup_case,
    table_head,
)
from study.pencil import PencilOperators, stiffness_matrix
from study.sizes import WIDTH, Sizes
from study.writer import ResultWriter
from coupling.timing import best_of

__all__ = ["PART", "run", "summarize", "plot", "summary_markdown"]


def run(comm: Any, sizes: Sizes) -> list[Table]:
    """Edge forms (paper vs sqrt-laplacian) and Jacobians (ufl vs handwritten)."""
    k = sizes.d_subdomains
    edge_rows = []
    points = [("d/h = 4", c, 4) for c in sizes.edge_cells]
    points += [(f"d = {fraction(WIDTH / k)}", c, c // k) for c in sizes.edge_d_cells]
    for series, cells, r in points:
        for form in ("paper", "sqrt-laplacian"):
            case = setup_case(comm, cells, r, edge_form=form)
            result, seconds = case.solve()
            row = {"series": series, "edge_form": form, "cells": cells, **describe(case.problem)}
            row.update(iterations=result.iterations, converged=result.converged, solve_s=seconds)
            if cells <= sizes.edge_kappa_max_cells:
                lo, hi = PencilOperators(
                    case.problem, case.preconditioner, stiffness_matrix(case.problem)
                ).extremes()
                row.update(lambda_min=lo, lambda_max=hi, kappa=hi / lo)
            edge_rows.append(row)
            log(
                f"[variants] edge form {form}, {series}, cells {cells}: "
                f"{result.iterations} its, kappa {row.get('kappa', float('nan')):.2f}"
            )
            case.release()

    jac_rows, histories = [], []
    for cells in sizes.jacobian_cells:
        runs = {}
        for kind in ("ufl", "handwritten"):
            case = setup_case(comm, cells, 4, jacobian=kind)
            result, seconds = case.solve()
            runs[kind] = (case, result, seconds)
        case, result, _ = runs["ufl"]
        problem = case.problem
        forms = problem.forms
        mats = {kind: forms.create_matrix() for kind in ("ufl", "handwritten")}
        timing = {}
        for kind, mat in mats.items():
            forms.assemble_jacobian(result.u, mat, kind)  # compile (JIT) outside the timing
            timing[kind] = best_of(lambda: forms.assemble_jacobian(result.u, mat, kind))
        residual = forms.create_vector()
        t_residual = best_of(lambda: forms.assemble_residual(result.u, residual))
        residual.destroy()
        J_ufl, J_hw = (gather_matrix(mats[kind]) for kind in ("ufl", "handwritten"))
        for mat in mats.values():
            mat.destroy()
        h_ufl, h_hw = runs["ufl"][1].history, runs["handwritten"][1].history
        n = min(len(h_ufl), len(h_hw))
        energy_diff = max(
            abs(a.energy - b.energy) / abs(a.energy) for a, b in zip(h_ufl[:n], h_hw[:n])
        )
        step_diff = max(
            abs(a.step_norm - b.step_norm) / a.step_norm for a, b in zip(h_ufl[:n], h_hw[:n])
        )
        u_ufl, u_hw = runs["ufl"][1].u.x.array, runs["handwritten"][1].u.x.array
        jac_rows.append(
            {
                "cells": cells,
                **describe(problem),
                "assemble_ufl_s": timing["ufl"],
                "assemble_handwritten_s": timing["handwritten"],
                "ratio_handwritten_to_ufl": timing["handwritten"] / timing["ufl"],
                "assemble_residual_s": t_residual,
                "matrix_rel_diff": float(spla.norm(J_ufl - J_hw) / spla.norm(J_ufl)),
                "C0_ufl": runs["ufl"][1].C0,
                "C0_handwritten": runs["handwritten"][1].C0,
                "iterations_ufl": len(h_ufl),
                "iterations_handwritten": len(h_hw),
                "max_rel_energy_diff": energy_diff,
                "max_rel_step_diff": step_diff,
                "u_rel_diff": float(np.linalg.norm(u_ufl - u_hw) / np.linalg.norm(u_ufl)),
                "phi_rel_diff": float(
                    np.linalg.norm(runs["ufl"][1].phi - runs["handwritten"][1].phi)
                    / np.linalg.norm(runs["ufl"][1].phi)
                ),
                "solve_ufl_s": runs["ufl"][2],
                "solve_handwritten_s": runs["handwritten"][2],
            }
        )
        for kind, (_, res, _) in runs.items():
            histories += [
                {
                    "cells": cells,
                    "jacobian": kind,
                    "iteration": rec.iteration,
                    "energy": rec.energy,
                    "step_norm": rec.step_norm,
                    "contact": rec.contact,
                    "tau": rec.tau,
                }
                for rec in res.history
            ]
        log(
            f"[variants] jacobians cells {cells}: assembly ufl {1e3 * timing['ufl']:.1f} ms, "
            f"handwritten {1e3 * timing['handwritten']:.1f} ms; iterations {len(h_ufl)} / "
            f"{len(h_hw)}; max rel energy diff {energy_diff:.1e}"
        )
        for run_case, _, _ in runs.values():
            run_case.release()
    return [
        Table(
            "edge_forms",
            "Edge forms A^0_gamma: `paper` (5.1) against `sqrt-laplacian`",
            "Square, carstensen, tol 1e-8; kappa of (A, B) (A of (4.2)) by Lanczos up to "
            "the size stated in the part's sizes.",
            edge_rows,
            [
                "series",
                "cells",
                "d_over_h",
                "edge_form",
                "iterations",
                "kappa",
                "lambda_min",
                "lambda_max",
                "solve_s",
            ],
        ),
        Table(
            "jacobians",
            "Jacobians `ufl` against `handwritten`",
            "Assembly time of D^2 G(u_h) (best of 5, after a warm-up), the relative "
            "Frobenius difference of the two matrices at u_h, and the two PGPM runs: the "
            "Jacobian enters PGPM only through the Lanczos estimate of C0 (tau = 1/C0), "
            "so the iterates agree to round-off when the matrices do. "
            "`max_rel_*_diff`: largest relative difference of J_h and of the step norm "
            "over the common iterations.",
            jac_rows,
            [
                "cells",
                "dofs",
                "assemble_ufl_s",
                "assemble_handwritten_s",
                "assemble_residual_s",
                "matrix_rel_diff",
                "C0_ufl",
                "C0_handwritten",
                "iterations_ufl",
                "iterations_handwritten",
                "max_rel_energy_diff",
                "max_rel_step_diff",
                "u_rel_diff",
            ],
        ),
        Table(
            "jacobian_histories",
            "Iteration histories of the two Jacobian runs",
            "Every PGPM step of both runs (CSV only).",
            histories,
            [],
        ),
    ]


def summarize(tables: Tables) -> dict[str, Any]:
    """Iterations and kappa per edge form and series; the Jacobian rows as they are."""
    edge = tables["edge_forms"]
    out: dict[str, Any] = {"edge": [], "jacobians": tables["jacobians"]}
    for series in dict.fromkeys(r["series"] for r in edge):
        for form in ("paper", "sqrt-laplacian"):
            s = series_rows(edge, series=series, edge_form=form)
            out["edge"].append(
                {
                    "series": series,
                    "edge_form": form,
                    "cells": [r["cells"] for r in s],
                    "d_over_h": [r["d_over_h"] for r in s],
                    "iterations": [r["iterations"] for r in s],
                    "kappa": [r.get("kappa") for r in s],
                }
            )
    return out


def plot(tables: Tables, writer: ResultWriter) -> Figures:
    """Edge forms: iterations and kappa; the histories of the two Jacobian runs."""
    summary = summarize(tables)
    fig, axes = writer.subplots(1, 2, figsize=(11, 4.2))
    for s in summary["edge"]:
        style = "o-" if s["edge_form"] == "paper" else "s--"
        label = f"{s['edge_form']}, {s['series']}"
        axes[0].semilogx(s["cells"], s["iterations"], style, label=label)
        kap = [(c, k) for c, k in zip(s["cells"], s["kappa"]) if k is not None]
        if kap:
            axes[1].semilogx(*zip(*kap), style, label=label)
    axes[0].set_ylabel("PGPM iterations")
    axes[1].set_ylabel("kappa of (A, B)")
    for ax in axes:
        log_ticks(ax, [c for s in summary["edge"] for c in s["cells"]])
        ax.set_xlabel("cells per side")
        ax.grid(True, which="both", alpha=0.3)
    legend_below(fig, axes, ncol=2)
    files = [
        writer.figure(fig, "variants_edge_forms", "Edge forms: iterations (left) and kappa (right)")
    ]
    hist = tables["jacobian_histories"]
    if hist:
        cells = max(r["cells"] for r in hist)
        fig, axes = writer.subplots(1, 2, figsize=(11, 4.2))
        steps = {}
        for kind, style in (("ufl", "-"), ("handwritten", "--")):
            s = series_rows(hist, cells=cells, jacobian=kind)
            steps[kind] = np.array([r["step_norm"] for r in s])
            axes[0].semilogy([r["iteration"] for r in s], steps[kind], style, label=kind)
        n = min(len(v) for v in steps.values())
        diff = np.abs(steps["ufl"][:n] - steps["handwritten"][:n]) / steps["ufl"][:n]
        axes[1].semilogy(np.arange(1, n + 1), np.maximum(diff, 1e-17), ".", ms=3)
        axes[0].set_ylabel("relative B-norm step")
        axes[1].set_ylabel("|difference| / ufl value (1e-17 = identical)")
        for ax in axes:
            ax.set_xlabel("PGPM iteration")
            ax.grid(True, which="both", alpha=0.3)
        axes[0].legend()
        fig.suptitle(f"Iteration histories, ufl and handwritten Jacobians, cells = {cells}")
        files.append(
            writer.figure(
                fig, "variants_jacobian_histories", "Iteration histories with the two Jacobians"
            )
        )
    return files


def summary_markdown(summary: dict[str, Any]) -> str:
    """Iterations and kappa of the edge forms."""
    lines = table_head("series", "edge form", "cells", "iterations", "kappa")
    for s in summary["edge"]:
        kappa = join([k for k in s["kappa"] if k is not None])
        lines.append(
            f"| {s['series']} | {s['edge_form']} | {join(s['cells'], '{}')} | "
            f"{join(s['iterations'], '{}')} | {kappa} |"
        )
    return "\n".join(lines)


PART = Part(
    "variants",
    "Part 5: edge forms and Jacobians",
    "The two edge forms A^0_gamma of docs/method.md section 6 and the two Jacobians of "
    "fem_py/forms/interior.py.",
    run,
    summarize,
    plot,
    summary_markdown,
)
