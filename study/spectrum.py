"""Part 2, ``spectrum``: extreme eigenvalues of B^{-1} A (A of (4.2)) and of
B^{-1} D^2 J_h(xi_h) by Lanczos in the B inner product (claim 7.2, Theorem 4.1); the
rate of Theorem 3.1 predicted from them; cond(M_s) (claim 7.3, (4.6)); the reference
values of docs/method.md section 6 recomputed."""
from __future__ import annotations

import time
from typing import Any, Sequence

import numpy as np

from coupling.solvers import IterationRecord
from study.base import Figures, Part, Table, Tables
from study.common import (
    describe,
    finish_axes,
    fit_log_squared,
    fraction,
    join,
    log,
    log_ticks,
    power_slope,
    series_rows,
    setup_case,
    table_head,
)
from study.pencil import DENSE_MAX, PencilOperators, jacobian_at, stiffness_matrix
from study.sizes import REFERENCE_KAPPA, WIDTH, Sizes
from study.writer import ResultWriter

__all__ = [
    "PART",
    "SPECTRUM_TOL",
    "observed_rate",
    "iterations_to",
    "run",
    "summarize",
    "plot",
    "summary_markdown",
]


def observed_rate(history: Sequence[IterationRecord], low: float, high: float) -> float:
    """Per-step contraction q of the relative B-norm step ||xi_k+1 - xi_k||_B / ||xi_k+1||_B
    over the steps with low < step <= high (least squares on log step; nan with < 5)."""
    steps = np.array([rec.step_norm for rec in history])
    k = np.arange(1, len(steps) + 1)
    window = (steps > low) & (steps <= high)
    if window.sum() < 5:
        return float("nan")
    return float(np.exp(np.polyfit(k[window], np.log(steps[window]), 1)[0]))


def iterations_to(history: Sequence[IterationRecord], tol: float) -> int | None:
    """The first iteration whose relative B-norm step is <= tol (the count of a run
    stopped at tol: the iterates do not depend on tol)."""
    return next((rec.iteration for rec in history if rec.step_norm <= tol), None)


#: The spectrum part solves to this tolerance so that the late, asymptotic rate can be
#: measured; the iteration count at the default 1e-8 is read from the same history.
SPECTRUM_TOL = 1e-13


def run(comm: Any, sizes: Sizes) -> list[Table]:
    """Extreme eigenvalues of B^{-1} A and B^{-1} D^2 J_h(xi_h) (claim 7.2), the rate of
    Theorem 3.1 predicted from them, cond(M_s) (claim 7.3) and the reference kappa."""
    k, r0 = sizes.d_subdomains, sizes.spectrum_ratio
    points = [(f"d/h = {r0}", c, r0, c in sizes.spectrum_cells) for c in sizes.cond_cells]
    points += [
        (f"d = {fraction(WIDTH / k)}", c, c // k, c in sizes.spectrum_d_cells)
        for c in sizes.cond_cells
    ]
    spectrum, rates, cond = [], [], []
    for series, cells, r, eigen in points:
        if series.startswith("d =") and r < 4:
            continue
        case = setup_case(comm, cells, r, tol=SPECTRUM_TOL, max_iterations=20_000)
        problem, pc = case.problem, case.preconditioner
        info = describe(problem)
        metric = np.asarray(pc.signorini_metric)
        lam = np.linalg.eigvalsh(metric / case.options.signorini_weight)
        cond.append(
            {
                "series": series,
                "cells": cells,
                **info,
                "lambda_min": lam[0],
                "lambda_max": lam[-1],
                "cond": lam[-1] / lam[0],
                "cond_times_h": lam[-1] / lam[0] * info["h"],
                "cond_h_over_log2": lam[-1]
                / lam[0]
                * info["h"]
                / (1 + np.log(info["d_over_h"]) ** 2),
            }
        )
        if not eigen:
            case.release()
            continue
        K = stiffness_matrix(problem)
        result, _ = case.solve()  # case.options.tol = SPECTRUM_TOL
        D2G = jacobian_at(problem, result)
        free = result.phi > 0
        extremes = {}
        for operator, matrix, mask in (
            ("A (4.2)", K, None),
            ("D2J_h(xi_h)", D2G, None),
            ("D2J_h(xi_h), free face", D2G, free),
        ):
            tic = time.perf_counter()
            pencil = PencilOperators(problem, pc, matrix, mask)
            lo, hi = pencil.extremes()
            row = {
                "series": series,
                "cells": cells,
                **info,
                "operator": operator,
                "size": pencil.n,
                "lambda_min": lo,
                "lambda_max": hi,
                "kappa": hi / lo,
                "kappa_over_log2": hi / lo / (1 + np.log(r) ** 2),
                "kappa_over_1_plus_log_sq": hi / lo / (1 + np.log(r)) ** 2,
                "matvecs": pencil.matvecs,
                "seconds": time.perf_counter() - tic,
            }
            if pencil.n <= DENSE_MAX:
                dlo, dhi = pencil.dense_extremes()
                row["dense_check"] = max(abs(dlo - lo) / dlo, abs(dhi - hi) / dhi)
            spectrum.append(row)
            extremes[operator] = (lo, hi)
        tau = result.tau
        q = {op: max(abs(1 - tau * lo), abs(1 - tau * hi)) for op, (lo, hi) in extremes.items()}
        lo_f, hi_f = extremes["D2J_h(xi_h), free face"]
        rates.append(
            {
                "series": series,
                "cells": cells,
                **info,
                "iterations_1e-8": iterations_to(result.history, 1e-8),
                "iterations_1e-13": result.iterations,
                "converged": result.converged,
                "C0_estimate": result.C0,
                "tau": tau,
                "kappa_D2J": extremes["D2J_h(xi_h)"][1] / extremes["D2J_h(xi_h)"][0],
                "kappa_face": hi_f / lo_f,
                "contact_nodes": int(result.contact.sum()),
                "q_predicted_full": q["D2J_h(xi_h)"],
                "q_predicted_face": q["D2J_h(xi_h), free face"],
                "q_observed_early": observed_rate(result.history, 1e-8, 1e-3),
                "q_observed_late": observed_rate(result.history, 1e-13, 1e-10),
            }
        )
        log(
            f"[spectrum] {series}: cells {cells} -> kappa(A) "
            f"{extremes['A (4.2)'][1] / extremes['A (4.2)'][0]:.2f}, kappa(D2J) "
            f"{rates[-1]['kappa_D2J']:.2f}, face {rates[-1]['kappa_face']:.2f}, "
            f"cond(M_s) {cond[-1]['cond']:.1f}, q early {rates[-1]['q_observed_early']:.4f}, "
            f"late {rates[-1]['q_observed_late']:.4f}, "
            f"predicted {rates[-1]['q_predicted_face']:.4f}"
        )
        case.release()

    reference = []
    for cells, r in sizes.reference:
        case = setup_case(comm, cells, r, flux_space="p0", signorini_weight=1.0)
        pencil = PencilOperators(case.problem, case.preconditioner, stiffness_matrix(case.problem))
        lo, hi = pencil.extremes()
        ref = REFERENCE_KAPPA.get((cells, r))
        reference.append(
            {
                "cells": cells,
                "d_over_h": r,
                "d": WIDTH * r / cells,
                "lambda_min": lo,
                "lambda_max": hi,
                "kappa": hi / lo,
                "kappa_reference": ref,
                "rel_difference": None if ref is None else (hi / lo - ref) / ref,
            }
        )
        log(
            f"[spectrum] reference cells {cells}, d/h {r}: kappa {hi / lo:.2f} "
            f"(docs/method.md: {ref})"
        )
        case.release()

    return [
        Table(
            "spectrum",
            "Extreme eigenvalues of B^-1 A and B^-1 D^2 J_h (Lanczos)",
            "A of (4.2) = Laplace stiffness + S_h term on (u, phi); D^2 J_h(xi_h) = Jacobian "
            "of the interior form at the computed solution + S_h term; `free face`: the "
            "pencil restricted to u and the phi unknowns off the computed contact set (the "
            "space on which the projected iteration moves once the contact set is found). "
            "B = B_Omega + omega M_s, omega = 1/4, P1 flux, edge form `paper`. ARPACK "
            "Lanczos in the B inner product (B^-1 exact), tol 1e-8; `dense_check` = "
            "relative difference to a dense generalized eigensolver where the size allows.",
            spectrum,
            [
                "series",
                "cells",
                "d_over_h",
                "operator",
                "lambda_min",
                "lambda_max",
                "kappa",
                "kappa_over_log2",
                "dense_check",
            ],
        ),
        Table(
            "rates",
            "Observed PGPM contraction against the rate predicted by the spectrum",
            f"The same runs continued to tol = {SPECTRUM_TOL:g} (the iterates do not "
            "depend on tol; `iterations_1e-8` is the count of the default tolerance). "
            "q = per-step contraction of the relative B-norm step, fitted over the steps "
            "in (1e-8, 1e-3] (`early`) and (1e-13, 1e-10] (`late`); predicted for the "
            "iteration linearised at xi_h with the tau used (Theorem 3.1): "
            "max(|1 - tau lambda_min|, |1 - tau lambda_max|) of B^-1 D^2 J_h on the whole "
            "space and on the free face.",
            rates,
            [
                "series",
                "cells",
                "d_over_h",
                "iterations_1e-8",
                "tau",
                "kappa_D2J",
                "kappa_face",
                "q_predicted_full",
                "q_predicted_face",
                "q_observed_early",
                "q_observed_late",
            ],
        ),
        Table(
            "cond_ms",
            "cond(M_s), the matrix of B_s (Theorem 4.2, (4.6))",
            "Eigenvalues of M_s (dense, all of them) on the Signorini arc (bottom side); "
            "(4.6) bounds cond(M_s) by C h^-1 (1 + ln^2(d/h)).",
            cond,
            [
                "series",
                "cells",
                "h",
                "d_over_h",
                "n_s",
                "lambda_min",
                "lambda_max",
                "cond",
                "cond_times_h",
                "cond_h_over_log2",
            ],
        ),
        Table(
            "reference",
            "kappa of (A, B) against the reference values of docs/method.md section 6",
            "As the reference implementation: P0 flux, omega = 1, edge form `paper`, "
            "square of width 0.5; `kappa_reference` is the value quoted in docs/method.md "
            "section 6 (input, not measured here).",
            reference,
            [
                "cells",
                "d_over_h",
                "d",
                "lambda_min",
                "lambda_max",
                "kappa",
                "kappa_reference",
                "rel_difference",
            ],
        ),
    ]


def summarize(tables: Tables) -> dict[str, Any]:
    """kappa per series and operator with its fit at fixed d, cond(M_s) with its
    exponent, the observed and predicted rates, and the comparison with the reference."""
    out: dict[str, Any] = {"kappa": [], "cond": [], "rates": []}
    spectrum, cond, rates = tables["spectrum"], tables["cond_ms"], tables["rates"]
    for series in dict.fromkeys(r["series"] for r in spectrum):
        for operator in dict.fromkeys(r["operator"] for r in spectrum):
            s = series_rows(spectrum, series=series, operator=operator)
            kappa = [r["kappa"] for r in s]
            entry = {
                "series": series,
                "operator": operator,
                "fixed_d": series.startswith("d ="),
                "cells": [r["cells"] for r in s],
                "d_over_h": [r["d_over_h"] for r in s],
                "kappa": kappa,
                "lambda_min": [r["lambda_min"] for r in s],
                "lambda_max": [r["lambda_max"] for r in s],
                "max_over_min": max(kappa) / min(kappa),
            }
            if entry["fixed_d"]:
                entry["fit"] = fit_log_squared(entry["d_over_h"], kappa)
                x = 1 + np.log(np.array(entry["d_over_h"], float)) ** 2
                entry["ratio_to_1_plus_log2"] = list(np.array(kappa) / x)
            out["kappa"].append(entry)
    for series in dict.fromkeys(r["series"] for r in cond):
        s = series_rows(cond, series=series)
        c, h = [r["cond"] for r in s], [r["h"] for r in s]
        out["cond"].append(
            {
                "series": series,
                "cells": [r["cells"] for r in s],
                "cond": c,
                "d_over_h": [r["d_over_h"] for r in s],
                "slope": power_slope(h, c),
                "local_slopes": list(np.diff(np.log(c)) / np.diff(np.log(1 / np.array(h)))),
                "cond_times_h": [r["cond_times_h"] for r in s],
                "cond_h_over_log2": [r["cond_h_over_log2"] for r in s],
            }
        )
    for series in dict.fromkeys(r["series"] for r in rates):
        s = series_rows(rates, series=series)
        out["rates"].append(
            {
                "series": series,
                **{
                    key: [r[key] for r in s]
                    for key in (
                        "cells",
                        "d_over_h",
                        "iterations_1e-8",
                        "q_observed_early",
                        "q_observed_late",
                        "q_predicted_face",
                        "q_predicted_full",
                        "kappa_face",
                        "kappa_D2J",
                        "tau",
                    )
                },
            }
        )
    ref = [r for r in tables.get("reference", []) if r.get("kappa_reference")]
    if ref:
        out["reference"] = {
            "cells": [r["cells"] for r in ref],
            "d_over_h": [r["d_over_h"] for r in ref],
            "kappa": [r["kappa"] for r in ref],
            "kappa_reference": [r["kappa_reference"] for r in ref],
            "max_abs_rel_difference": max(abs(r["rel_difference"]) for r in ref),
        }
    return out


def plot(tables: Tables, writer: ResultWriter) -> Figures:
    """kappa against h and d/h, cond(M_s) against 1/h, predicted and observed rates."""
    summary = summarize(tables)
    fig, axes = writer.subplots(1, 2, figsize=(11, 4.2))
    for s in summary["kappa"]:
        ax = axes[1] if s["fixed_d"] else axes[0]
        ax.semilogx(
            s["d_over_h"] if s["fixed_d"] else s["cells"], s["kappa"], "o-", label=s["operator"]
        )
        if s["fixed_d"] and s["operator"] == "A (4.2)":
            r = np.geomspace(min(s["d_over_h"]), max(s["d_over_h"]), 100)
            ax.semilogx(
                r,
                s["fit"]["C"] * (1 + np.log(r)) ** 2,
                "k--",
                lw=0.8,
                label=f"{s['fit']['C']:.3g} (1 + ln(d/h))^2 (fit to A)",
            )
    fixed = [s for s in summary["kappa"] if not s["fixed_d"]]
    axes[0].set_xlabel(
        "cells per side (h = 0.5/cells), " + (fixed[0]["series"] if fixed else "d/h fixed")
    )
    fixed_d = [s for s in summary["kappa"] if s["fixed_d"]]
    axes[1].set_xlabel("d/h, " + (fixed_d[0]["series"] if fixed_d else "d fixed"))
    log_ticks(axes[0], [c for s in fixed for c in s["cells"]])
    log_ticks(axes[1], [r for s in fixed_d for r in s["d_over_h"]])
    for ax in axes:
        ax.set_ylabel("kappa = lambda_max / lambda_min")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Spectral condition of B^-1 A and B^-1 D^2 J_h")
    files = [
        writer.figure(
            fig,
            "spectrum_kappa",
            "kappa of B^-1 A and B^-1 D^2 J_h(xi_h): fixed d/h (left), fixed d (right)",
        )
    ]
    fig, ax = writer.subplots(figsize=(6.5, 4.5))
    for s in summary["cond"]:
        ax.loglog(np.array(s["cells"]) / WIDTH, s["cond"], "o-", label=f"cond(M_s), {s['series']}")
    if summary["cond"]:
        s = summary["cond"][0]
        inv_h = np.array(s["cells"]) / WIDTH
        ax.loglog(inv_h, s["cond"][0] * inv_h / inv_h[0], "k:", lw=0.8, label="slope 1 (h^-1)")
    ax.set_xlabel("1/h")
    ax.set_ylabel("cond(M_s)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    files.append(writer.figure(fig, "spectrum_cond_ms", "cond(M_s) against 1/h"))
    fig, ax = writer.subplots(figsize=(6.5, 4.5))
    for r in summary["rates"]:
        x = np.array(r["cells"], float)
        (line,) = ax.semilogx(
            x, r["q_predicted_face"], "o-", label=f"predicted (face), {r['series']}"
        )
        ax.semilogx(
            x,
            r["q_observed_late"],
            "s--",
            color=line.get_color(),
            label=f"observed late, {r['series']}",
        )
        ax.semilogx(
            x,
            r["q_observed_early"],
            "^:",
            color=line.get_color(),
            label=f"observed early, {r['series']}",
        )
    log_ticks(ax, [c for r in summary["rates"] for c in r["cells"]])
    finish_axes(ax, "cells per side", "per-step contraction q", legend_size=7)
    caption = "PGPM contraction per step: predicted from the spectrum against observed"
    return files + [writer.figure(fig, "spectrum_rates", caption)]


def summary_markdown(summary: dict[str, Any]) -> str:
    """kappa and its fit per series, cond(M_s) and its exponents, the reference check."""
    lines = table_head("series", "operator", "kappa", "max/min", "fit C (1 + ln(d/h))^2")
    for s in summary["kappa"]:
        fit = (
            f"C = {s['fit']['C']:.3g}, free exponent {s['fit']['exponent']:.2f}"
            if "fit" in s
            else ""
        )
        lines.append(
            f"| {s['series']} | {s['operator']} | {join(s['kappa'])} | "
            f"{s['max_over_min']:.2f} | {fit} |"
        )
    lines += [""] + table_head(
        "cond(M_s), series",
        "cond",
        "fitted p of h^-p",
        "local slopes",
        "cond h / (1 + ln^2(d/h))",
    )
    for s in summary["cond"]:
        lines.append(
            f"| {s['series']} | {join(s['cond'], '{:.1f}')} | {s['slope']:.2f} | "
            f"{join(s['local_slopes'])} | {join(s['cond_h_over_log2'], '{:.3g}')} |"
        )
    if "reference" in summary:
        lines += [
            "",
            "Largest relative difference to the docs/method.md reference kappa: "
            f"{summary['reference']['max_abs_rel_difference']:.2e}.",
        ]
    return "\n".join(lines)


PART = Part(
    "spectrum",
    "Part 2: C0/c0 and cond(M_s)",
    "Claims 7.2 and 7.3: kappa = C0/c0 of B^-1 A and of B^-1 D^2 J_h grows like "
    "1 + ln^2(d/h) (Theorem 4.1); cond(M_s) = O(h^-1 (1 + ln^2(d/h))) (Theorem 4.2).",
    run,
    summarize,
    plot,
    summary_markdown,
)
