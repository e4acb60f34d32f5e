"""Part 4, ``errors``: discretisation errors on the manufactured solutions of docs/method.md
section 8 and their observed orders (claim 7.5), linear and carstensen material, square
and L-shape, P1 flux (and P0 flux for comparison)."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from coupling.manufactured import MANUFACTURED, solution_errors
from study.base import Figures, Part, Table, Tables
from study.common import describe, log, power_slope, setup_case
from study.sizes import Sizes
from study.writer import ResultWriter

__all__ = ["PART", "ERROR_KEYS", "ERROR_CASES", "run", "summarize", "plot", "summary_markdown"]

ERROR_KEYS = ("energy", "nodal_u", "gap", "ue_gamma", "ue_exterior")
#: (shape, material, flux space) of the error study: both shapes and materials with the
#: default P1 flux, and the linear material with the discontinuous P0 flux, which can
#: follow the jump of du_e/dn at the corners of Gamma.
ERROR_CASES = (
    ("square", "linear", "p1"),
    ("square", "carstensen", "p1"),
    ("lshape", "linear", "p1"),
    ("lshape", "carstensen", "p1"),
    ("square", "linear", "p0"),
    ("lshape", "linear", "p0"),
)


def run(comm: Any, sizes: Sizes, *, tol: float = 1e-10) -> list[Table]:
    """Errors against the manufactured solutions (docs/method.md section 8, claim 7.5) with
    observed orders log(e_coarse/e_fine)/log(h_coarse/h_fine); tol 1e-10 so that the
    algebraic error stays far below the discretisation error."""
    rows = []
    for shape, material, flux in ERROR_CASES:
        previous = None
        for cells in sizes.error_cells:
            case = setup_case(
                comm,
                cells,
                4,
                shape=shape,
                material=material,
                tol=tol,
                max_iterations=20_000,
                flux_space=flux,
            )
            problem = case.problem
            result, seconds = case.solve()
            solution = MANUFACTURED[shape]()
            errors = solution_errors(problem, solution, result)
            # every node whose contact state differs from the exact one, the size of
            # the wrong quantity there (phi_h where g* = 0, g* where phi_h = 0) and its
            # distance to the nearest switch point of the exact contact set
            b = problem.boundary
            s_nodes = b.nodes[b.signorini]
            exact_gap = solution.exact_gap(s_nodes)
            wrong = (exact_gap <= 0.0) != result.contact
            flip = np.flatnonzero(
                (np.diff((exact_gap <= 0.0).astype(int)) != 0) & (np.diff(b.arc_of_signorini) == 0)
            )
            switches = 0.5 * (s_nodes[flip] + s_nodes[flip + 1])
            switch_distance = max(
                (float(np.min(np.linalg.norm(switches - p, axis=1))) for p in s_nodes[wrong]),
                default=0.0,
            )
            # where the largest gap and nodal errors sit: distance to the nearest
            # corner of Gamma in mesh sizes
            corners = np.asarray(problem.domain.vertices, float)
            x = problem.V.tabulate_dof_coordinates()[:, :2]
            nodal = np.abs(result.u.x.array - solution.exact_u()(x[:, 0], x[:, 1]))
            at = {
                "gap": b.nodes[b.signorini][np.argmax(np.abs(result.phi - exact_gap))],
                "nodal_u": x[np.argmax(nodal)],
            }
            distance = {
                f"{key}_max_corner_distance_h": float(
                    np.min(np.linalg.norm(corners - point, axis=1)) / problem.domain.h
                )
                for key, point in at.items()
            }
            row = {
                "shape": shape,
                "material": material,
                "flux_space": flux,
                "cells": cells,
                **describe(problem),
                "iterations": result.iterations,
                "converged": result.converged,
                "solve_s": seconds,
                **errors,
                "mismatch_all": int(wrong.sum()),
                "mismatch_max_gap_error": float(
                    np.abs(result.phi - exact_gap)[wrong].max(initial=0.0)
                ),
                "mismatch_switch_distance_h": switch_distance / problem.domain.h,
                **distance,
            }
            for key in ERROR_KEYS:
                row[f"order_{key}"] = (
                    None
                    if previous is None
                    else math.log(previous[key] / errors[key]) / math.log(previous["h"] / row["h"])
                )
            rows.append(row)
            previous = row
            log(
                f"[errors] {shape} {material} {flux} cells {cells}: "
                f"energy {errors['energy']:.3e}, "
                f"nodal {errors['nodal_u']:.3e}, gap {errors['gap']:.3e}, "
                f"u_e ext {errors['ue_exterior']:.3e} ({result.iterations} its)"
            )
            case.release()
    return [
        Table(
            "errors",
            "Discretisation errors and observed orders",
            "Manufactured solutions with a known contact set (coupling/manufactured.py): "
            "`energy` = |u_h - u|_1, `nodal_u` = max nodal error of u_h, `gap` = max "
            "error of phi_h at the Signorini nodes, `ue_gamma` = max error of u_e on "
            "Gamma, `ue_exterior` = max error of u_e at 8 points on the circle of "
            "radius 0.6, `contact_mismatch` = Signorini nodes with the wrong contact "
            "state away from the switch points (solution_errors), `mismatch_all` with "
            "them, `mismatch_max_gap_error` = largest |phi_h - g*| at those nodes (the "
            "size of the wrong quantity), `mismatch_switch_distance_h` = largest "
            "distance of such a node to a switch point of the exact contact set in "
            "mesh sizes h, "
            "`*_max_corner_distance_h` = distance of the node with the largest gap "
            "(nodal u) error to the nearest corner of Gamma, in mesh sizes h. "
            "d/h = 4, PGPM tol 1e-10. `order_*` against the previous row.",
            rows,
            [
                "shape",
                "material",
                "flux_space",
                "cells",
                "energy",
                "order_energy",
                "nodal_u",
                "order_nodal_u",
                "gap",
                "order_gap",
                "ue_gamma",
                "order_ue_gamma",
                "ue_exterior",
                "order_ue_exterior",
                "contact_mismatch",
                "mismatch_all",
                "mismatch_switch_distance_h",
                "gap_max_corner_distance_h",
                "nodal_u_max_corner_distance_h",
            ],
        )
    ]


def error_case(row: dict) -> str:
    """The label of a row's case: shape, material and (P0) flux space."""
    flux = row.get("flux_space") or "p1"
    return f"{row['shape']}, {row['material']}" + (", P0 flux" if flux == "p0" else "")


def summarize(tables: Tables) -> dict[str, Any]:
    """Per case: successive and fitted orders of every error, and the contact-set
    mismatch and corner-distance columns."""
    rows = tables["errors"]
    out: dict[str, Any] = {}
    for case in dict.fromkeys(error_case(r) for r in rows):
        s = [r for r in rows if error_case(r) == case]
        h = [r["h"] for r in s]
        out[case] = {
            key: {
                "orders": [r[f"order_{key}"] for r in s[1:]],
                "fitted": power_slope(h, [r[key] for r in s]),
                "finest": s[-1][key],
            }
            for key in ERROR_KEYS
        }
        for key in (
            "cells",
            "contact_mismatch",
            "mismatch_all",
            "mismatch_max_gap_error",
            "mismatch_switch_distance_h",
            "gap_max_corner_distance_h",
            "nodal_u_max_corner_distance_h",
        ):
            out[case][key] = [r.get(key) for r in s]
    return out


def plot(tables: Tables, writer: ResultWriter) -> Figures:
    """The errors of every case against h, with O(h) and O(h^2) guides."""
    rows = tables["errors"]
    cases = list(dict.fromkeys(error_case(r) for r in rows))
    ncol = 2
    nrow = (len(cases) + ncol - 1) // ncol
    fig, axes = writer.subplots(
        nrow, ncol, figsize=(11, 4 * nrow), sharey=True, squeeze=False, constrained_layout=True
    )
    for ax, case in zip(axes.ravel(), cases):
        s = [r for r in rows if error_case(r) == case]
        h = np.array([r["h"] for r in s])
        for key in ERROR_KEYS:
            ax.loglog(h, [r[key] for r in s], "o-", label=key)
        for p, style in ((1, "k--"), (2, "k:")):
            ax.loglog(
                h,
                s[-1]["energy" if p == 1 else "ue_exterior"] * (h / h[-1]) ** p,
                style,
                lw=0.8,
                label=f"O(h^{p})",
            )
        ax.set_title(case)
        ax.set_xlabel("h")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes.ravel()[len(cases) :]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel("error")
    return [writer.figure(fig, "errors", "Discretisation errors against h")]


def summary_markdown(summary: dict[str, Any]) -> str:
    """Successive and fitted orders per case, and the contact mismatch."""
    lines = [
        "| case | "
        + " | ".join(f"order {k} (successive; fitted)" for k in ERROR_KEYS)
        + " | contact mismatch |",
        "|---|" + "---|" * (len(ERROR_KEYS) + 1),
    ]
    for case, s in summary.items():
        cells = [
            f"{', '.join(f'{o:.2f}' for o in s[k]['orders'])}; {s[k]['fitted']:.2f}"
            for k in ERROR_KEYS
        ]
        lines.append(
            f"| {case} | "
            + " | ".join(cells)
            + f" | {', '.join(str(m) for m in s['contact_mismatch'])} |"
        )
    return "\n".join(lines)


PART = Part(
    "errors",
    "Part 4: discretisation errors on manufactured solutions",
    "Claim 7.5: with smooth data the energy-norm error is O(h); nodal errors of P1 are "
    "expected O(h^2) where the solution is smooth.",
    run,
    summarize,
    plot,
    summary_markdown,
)
