"""The peer benchmark's report: the markdown tables, the plot, ``results.md`` with its
text sections and the table printed at the end of a run.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

from bench.peers.solvers import (
    BY_NAME,
    NEWTON_TOL,
    PROBLEMS,
    SEQUENCED_KEPT,
    SOLVERS,
    TOL_PHI,
    TOL_U,
)
from bench.peers.targets import TIE, index_records


def _fmt(value, spec: str = ".2f", missing: str = "-") -> str:
    return missing if value is None else format(value, spec)


def markdown_table(
    result: dict[str, Any], problem: str, names: Sequence[str] | None = None
) -> list[str]:
    table, poisson = index_records(result["records"])
    lines = [
        "| N | solver | status | its | lin. its | setup [s] | solve [s] | total [s] "
        "| / (a) | / (e) | peak [MB] | +peak [MB] | du | dphi |",
        "|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for cells in result["sizes"]:
        a = table.get((problem, cells, "pgpm"))
        e = poisson.get(cells)
        for solver in SOLVERS:
            if names is not None and solver.name not in names:
                continue
            key = ("poisson" if solver.kind == "poisson" else problem, cells, solver.name)
            r = table.get(key)
            if r is None:
                continue
            total = r.get("total")
            ratio_a = total / a["total"] if total and a and a.get("total") else None
            ratio_e = total / e["total"] if total and e and e.get("total") else None
            dofs = r.get("dofs") or (a or {}).get("dofs")
            status = (
                r["status"]
                if r["status"] in ("ok", "inaccurate")
                else (f"{r['status']}: {r.get('reason', '')}")
            )
            its = r.get("iterations")
            its = _fmt(its if its is not None and its >= 0 else None, "d")
            lin = _fmt(r.get("linear_iterations") or None, "d")
            levels = (r.get("details") or {}).get("levels")
            if levels:  # grid-sequenced: per level, coarsest first
                its = " / ".join(str(lv["iterations"]) for lv in levels)
                if any(lv["linear_iterations"] for lv in levels):
                    lin = " / ".join(str(lv["linear_iterations"]) for lv in levels)
            lines.append(
                f"| {_fmt(dofs, 'd')} | {solver.group}: {solver.label} | {status} "
                f"| {its} | {lin} "
                f"| {_fmt(r.get('setup'))} | {_fmt(r.get('solve'))} | {_fmt(total)} "
                f"| {_fmt(ratio_a)} | {_fmt(ratio_e, '.1f')} | {_fmt(r.get('peak_mb'), '.0f')} "
                f"| {_fmt(r.get('delta_mb'), '.0f')} | {_fmt(r.get('du'), '.1e')} "
                f"| {_fmt(r.get('dphi'), '.1e')} |"
            )
    return lines


#: The solvers of the main tables and the plot: all but the SNES VI linear-solver
#: candidates (cold and grid-sequenced) that were not kept.
MAIN = tuple(
    s.name
    for s in SOLVERS
    if (not s.selection or s.name in ("snes-substructuring", "snes-mumps-cholesky"))
    and (not s.sequenced_selection or s.name in SEQUENCED_KEPT)
)


def plot(result: dict[str, Any], path: Path) -> None:
    """Set-up + solve time against N, log-log, one panel per problem (failed solves as x)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    table, _ = index_records(result["records"])
    problems = [p for p in PROBLEMS if any(k[0] == p for k in table)]
    fig, axes = plt.subplots(1, len(problems), figsize=(6.5 * len(problems), 5), squeeze=False)
    markers = dict(a="o", b="s", c="^", d="v", e="D")
    handles = {}
    for ax, problem in zip(axes[0], problems):
        for i, solver in enumerate(s for s in SOLVERS if s.name in MAIN):
            rows = [
                table.get(("poisson" if solver.kind == "poisson" else problem, c, solver.name))
                for c in result["sizes"]
            ]
            rows = [r for r in rows if r and r.get("total")]
            if not rows:
                continue
            color = "black" if solver.kind == "poisson" else plt.cm.tab10(i % 10)
            style = dict(
                marker=markers[solver.group],
                color=color,
                linestyle="--" if solver.kind == "poisson" else "-",
                linewidth=2.5 if solver.name == "pgpm" else 1.2,
            )
            ok = [r for r in rows if r["status"] == "ok"]
            if ok:
                ax.loglog([r["dofs"] for r in ok], [r["total"] for r in ok], **style)
            bad = [r for r in rows if r["status"] != "ok"]
            if bad:
                ax.loglog(
                    [r["dofs"] for r in bad],
                    [r["total"] for r in bad],
                    "x",
                    color=style["color"],
                    markersize=10,
                    markeredgewidth=2,
                )
            handles.setdefault(
                solver.name, Line2D([], [], label=f"{solver.group}: {solver.label}", **style)
            )
        ax.set_xlabel("N (dofs of u)")
        ax.set_ylabel("set-up + solve [s]")
        ax.set_title(PROBLEMS[problem]["label"])
        ax.grid(True, which="both", alpha=0.3)
    fig.legend(handles=list(handles.values()), fontsize=8, loc="center right")
    fig.suptitle("Peer benchmark: wall time vs N (x: not converged within the budget or failed)")
    fig.tight_layout(rect=(0, 0, 0.8, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)


def report(result: dict[str, Any], command: str) -> str:
    m = result["machine"]
    v = m["versions"]
    table, poisson = index_records(result["records"])
    setups = {(r["problem"], r["cells"]): r for r in result["records"] if r["type"] == "setup"}
    out = [
        "# Peer benchmark: PGPM against PETSc's VI and bound-constrained solvers",
        "",
        f"Generated by `{command}` on {m['date']} in {result['wall_time'] / 60:.1f} min "
        "(do not edit by hand; rerun to update"
        + (
            f"; text and tables rewritten on {result['regenerated']} from this run's "
            "records, `python -m bench.peers --report-from bench/results.json`"
            if result.get("regenerated")
            else ""
        )
        + ").",
        "",
        f"- Machine: {m['cpu']}, {m['cores']} cores (shared with other jobs; load average "
        f"{m['load']:.1f} at the start), {m['platform']}; one process, {m['threads']}.",
        f"- Versions: petsc4py {v.get('petsc4py')} (PETSc {v.get('PETSc')}), dolfinx "
        f"{v.get('dolfinx')}, numpy {v.get('numpy')}, scipy {v.get('scipy')}, python "
        f"{v.get('python')}; git commit {m['commit']}.",
        f"- Budget per solve: {result['budget']:g} s (120 s for BLMVM and BQNLS, 60 s for PGPM "
        "+ identity), checked at every evaluation of J_h or its derivatives. A solver that "
        "fails or runs out of budget is reported with its reason and not run on finer "
        "meshes; nor is one whose time on the previous mesh, scaled linearly with N (no "
        "solver here scales better), exceeds its budget (status `skipped`, with the reason).",
        "",
        "## What is measured",
        "",
        "The same discrete problem (2.3) - minimise J_h(u, phi) over phi >= 0 - on the square "
        "[-1/4, 1/4]^2 (structured mesh, `cells` squares per side, each split in two; "
        "subdomains of d = 4h; Signorini arc = bottom side; carstensen material rho(t) = "
        "2 + 1/(1+t)), for two data sets: `manufactured` (`square_contact`, exact solution "
        "known) and `load` (f = 2, t0 = -1, u0 = 0.1 x, a = 0; no exact solution, contact on "
        "most of the arc). All solvers start from x = 0.",
        "",
        "- (a) PGPM + substructuring preconditioner, the paper's method with the "
        "project's default options (tol = 1e-8 on ||xi_k+1 - xi_k||_B / ||xi_k+1||_B, exact "
        "projection, tau = 1/C0 from 20 Lanczos steps).",
        "- (b) PGPM + identity (Euclidean metric; smallest mesh and manufactured data "
        "only: its count grows like h^-2, Remark 2.1), APGPM and SSN with the "
        "substructuring preconditioner, same tol.",
        "- (c) PETSc SNES `vinewtonrsls` (reduced-space active-set Newton, `bt` line search "
        "on ||F||) on F = grad J_h with phi >= 0, Jacobian = the Hessian "
        "[[D^2G + T^T S T, T^T S E], [E^T S T, E^T S E]] assembled as one SeqAIJ matrix "
        "(the P1 pattern plus the dense boundary/Signorini block, pattern built once, "
        f"values refreshed in place). snes_rtol = {NEWTON_TOL:g}. Linear solvers: see the "
        "selection below; the CG-based ones stop at rtol 1e-6 (fastest of 1e-8, 1e-6, 1e-4 "
        "and Eisenstat-Walker, measured on SNES VI + CG/B at N = 6.2e4). Grid-sequenced "
        "(issue 18; PETSc's `-snes_grid_sequence` done on the project's hierarchy): solved "
        "on the coarsest level of a hierarchy of the same square (h doubled per level, "
        "`coupling.app.from_config.coarser_configs`) from x = 0, the solution prolonged "
        "to the next finer level (`coupling.solvers.nested.prolong`: P1 interpolation of "
        "u, linear interpolation of the gap along Gamma) as its initial iterate, and so "
        "on to the finest; every level stops at the cold test ||F|| <= snes_rtol "
        "||F(0)|| (PETSc's VI norm), and its time counts the coarser levels' assembly "
        "(mesh, forms, S_h, loads). `its` and `lin. its` of these rows are per level, "
        "coarsest first.",
        "- (d) PETSc TAO: `blmvm` and `bqnls` (J_h and gradient only) and `bnls`, `bntr` "
        f"(Hessian as in (c), STCG with a MUMPS Cholesky factor). gttol = {NEWTON_TOL:g} "
        "for BNLS/BNTR.",
        "- (e) yardstick: one linear solve on the same mesh, -Laplace w = 1 with w = 0 on "
        "Gamma, P1 stiffness, CG + GAMG to rtol 1e-8 (set-up = assembly + GAMG set-up).",
        "",
        f"Same accuracy: every solution is compared with PGPM's, du = ||u - u_a|| / ||u_a|| "
        f"and dphi = ||phi - phi_a|| / ||phi_a|| (Euclidean norms of the nodal vectors); "
        f"status `ok` means converged by the solver's own test and du <= {TOL_U:g}, "
        f"dphi <= {TOL_PHI:g}. PGPM's own error is what the Newton solvers (converged to "
        "round-off) show as du, dphi: about 1e-8 in u and 1e-6 in phi, so phi sets the "
        "tolerance. BLMVM and BQNLS cannot reach it by their own gradient test (they stall "
        "near 1e-6 in u, the objective's round-off level for their line search); they are "
        "stopped as soon as their iterate passes this accuracy test against PGPM's "
        "solution (an oracle: the most favourable stopping rule they could have). On a mesh "
        "where PGPM is skipped, the solutions are compared with SSN's instead (a Newton "
        "method, converged past its tol), and `/ (a)` is left empty.",
        "",
        "Times are wall-clock seconds: `setup` is the solver's own set-up (for (a)-(b) "
        "building B and the step estimate; for (c)-(d) the Hessian pattern and, for CG + "
        "substructuring, building B; PETSc's factorisations happen inside `solve`), `solve` "
        "the iteration, `total` = setup + solve. Not included, because all solvers share "
        "it: mesh, forms, S_h and loads (listed below). `/ (a)` and `/ (e)` are ratios of "
        "`total` to PGPM's and to the Poisson solve's, measured in the same run. `peak` is "
        "the process's peak resident memory during the solve (it includes the mesh and "
        "S_h), `+peak` its increase over the resident memory before the solver started "
        "(Linux VmHWM reset by /proc/self/clear_refs). `its` = outer iterations (PGPM "
        "steps, Newton steps, TAO iterations), `lin. its` = Krylov iterations summed.",
        "",
    ]
    # shared set-up
    out += [
        "### Shared set-up (not in the solver times)",
        "",
        "| N | problem | mesh [s] | forms + S_h + loads [s] | S_h [s] | n_Gamma | n_s |",
        "|---:|---|---:|---:|---:|---:|---:|",
    ]
    for (problem, cells), s in sorted(setups.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        out.append(
            f"| {s['dofs']} | {problem} | {s['mesh']:.1f} | {s['shared']:.1f} "
            f"| {s['timings'].get('steklov_poincare', 0.0):.1f} | {s['n_gamma']} "
            f"| {s['n_signorini']} |"
        )
    out.append("")
    # linear solver selection
    selection = [s.name for s in SOLVERS if s.selection]
    out += [
        "## Linear solver for SNES VI",
        "",
        "All candidates on the manufactured problem up to N = 6.2e4 (PETSc's LU only at "
        "1e4); the finer meshes run the two kept for the main tables:",
        "",
    ]
    out += markdown_table(result, "manufactured", names=selection)
    out += ["", *_selection_text(result), ""]
    out += _sequenced_section(result)
    # main tables
    main = MAIN
    for problem in PROBLEMS:
        if not any(k[0] == problem for k in table):
            continue
        out += [f"## Results: {PROBLEMS[problem]['label']}", ""]
        out += markdown_table(result, problem, names=main)
        out.append("")
    out += ["![time vs N](peers.png)", "", "## Targets", ""]
    out += _targets_text(result)
    out += ["", *_profile_text(result), "", *_discussion(result)]
    crashes = [r for r in result["records"] if r["type"] == "crash"]
    if crashes:
        out += ["", "## Worker failures", ""]
        out += [f"- cells = {r['cells']}: {r['reason']}" for r in crashes]
    return "\n".join(out) + "\n"


def _selection_text(result) -> list[str]:
    table, _ = index_records(result["records"])
    lines = []
    for cells in result["sizes"]:
        rows = [
            (n, table[("manufactured", cells, n)])
            for n in (s.name for s in SOLVERS if s.selection)
            if ("manufactured", cells, n) in table
        ]
        ok = sorted((r["total"], n) for n, r in rows if r["status"] == "ok")
        if len(rows) > 2 and ok:
            order = ", ".join(f"{BY_NAME[n].label.split(', ', 1)[1]} {t:.2f} s" for t, n in ok)
            lines.append(f"- N = {rows[0][1]['dofs']}: {order}.")

    def pick(name):
        return [
            table[k]
            for k in sorted(table, key=lambda k: k[1])
            if k[0] == "manufactured" and k[2] == name and table[k]["status"] == "ok"
        ]

    def per_step(rows):
        return ", ".join(f"{r['linear_iterations'] / max(r['iterations'], 1):.0f}" for r in rows)

    def speed(slow, fast):
        pairs = [
            (a["total"] / b["total"])
            for a in pick(slow)
            for b in pick(fast)
            if a["cells"] == b["cells"]
        ]
        if not pairs:
            return "-"
        lo, hi = f"{min(pairs):.1f}", f"{max(pairs):.1f}"
        return f"{lo}x" if lo == hi else f"{lo}-{hi}x"

    sub, amg, gamg = pick("snes-substructuring"), pick("snes-hypre"), pick("snes-gamg")
    lines += [
        "",
        "Choice: CG preconditioned by the project's substructuring preconditioner B "
        "restricted to the inactive set (PCSHELL: B_Omega^-1 on u, (omega M_s)[I, I]^-1 on "
        "the free phi; the inactive set from `SNES.getVIInactiveSet()` in the PC set-up) "
        "is the fastest wherever all candidates ran. Its CG count per Newton step stays "
        f"nearly constant as h -> 0 ({per_step(sub)} for N = "
        + ", ".join(str(r["dofs"]) for r in sub)
        + "; at fixed d/h, B is spectrally equivalent to "
        "the Hessian uniformly in h, Theorem 4.1) and it never factors "
        "the dense block. MUMPS is the best black-box choice and is kept as the second "
        "SNES peer: Cholesky is "
        f"{speed('snes-mumps', 'snes-mumps-cholesky')} faster than LU, and the AMD "
        "ordering (ICNTL(7) = 0) "
        f"{speed('snes-mumps-cholesky-auto', 'snes-mumps-cholesky')} faster than this "
        "build's default (PORD; METIS and SCOTCH are absent); the factor still pays for "
        "the dense n_Gamma x n_Gamma block at every Newton step. BoomerAMG needs "
        f"{per_step(amg)} CG iterations per Newton step and GAMG {per_step(gamg)}, but "
        "both are slower overall than CG + B ("
        f"{speed('snes-hypre', 'snes-substructuring')} and "
        f"{speed('snes-gamg', 'snes-substructuring')}): the AMG hierarchy is rebuilt for "
        "every reduced Newton system, on a matrix with n_Gamma-long dense rows (GAMG must "
        "be rebuilt: PETSc 3.18's GAMG cannot be set up again when SNES VI changes the size "
        "of the reduced system). PETSc's own LU "
        "(nested dissection) is "
        f"{speed('snes-petsc-lu', 'snes-mumps')} slower than MUMPS LU.",
    ]
    return lines


def _sequenced_section(result) -> list[str]:
    """The grid-sequenced SNES VI candidates, next to the cold SNES VI with CG + B."""
    table, _ = index_records(result["records"])
    names = [s.name for s in SOLVERS if s.sequenced_selection]
    if not any(k[2] in names for k in table):
        return []
    out = [
        "## Linear solver and hierarchy for the grid-sequenced SNES VI",
        "",
        "The candidates on the manufactured problem up to N = 6.2e4, next to the cold SNES "
        "VI with CG + substructuring; the finer meshes run the ones kept for the main "
        "tables (" + ", ".join(BY_NAME[n].label for n in SEQUENCED_KEPT) + "). The "
        "`nested` hierarchy is that of `[solver] nested = true` (h doubled with the "
        "subdomains of d = 4h kept, so one coarser level with d = 2h; B needs d/h >= 2); "
        "`to 1e3 dofs` doubles h down to about 10^3 dofs on 2 x 2 subdomains (for the "
        "black-box linear solvers, which do not use them).",
        "",
    ]
    out += markdown_table(result, "manufactured", names=["snes-substructuring", *names])
    out.append("")
    for cells in result["sizes"]:
        rows = [
            (table[k]["total"], n, table[k])
            for n in names
            if (k := ("manufactured", cells, n)) in table and table[k]["status"] == "ok"
        ]
        if len(rows) > 1:
            rows.sort(key=lambda row: row[0])
            levels = [lv["dofs"] for lv in rows[0][2]["details"]["levels"]]
            lines = ", ".join(
                f"{BY_NAME[n].label.removeprefix('SNES VI ')} {t:.2f} s" for t, n, _ in rows
            )
            out.append(
                f"- N = {rows[0][2]['dofs']}: {lines} (fastest on levels of "
                + ", ".join(map(str, levels))
                + " dofs)."
            )
    out.append("")
    return out


def _targets_text(result) -> list[str]:
    t = result["targets"]
    lines = []
    rows = t["pgpm"]["faster_than_peers"]
    if rows:
        met = all(r["met"] for r in rows)
        lines.append(
            f"1. (a) faster than every PETSc peer (c, d) at N >= 2.5e5: "
            f"**{'met' if met else 'not met'}**."
        )
        for r in rows:
            if r["met"]:
                detail = "faster than all"
            else:
                detail = "slower than " + ", ".join(r["faster_peers"])
            if r["tie"]:
                detail += (
                    f" (the fastest peer, {r['best_peer'][0]}, within {100 * TIE:.0f}%: "
                    "a tie on this shared machine)"
                )
            lines.append(f"   - {r['problem']}, N = {r['dofs']}: PGPM {r['time']:.1f} s, {detail}.")
    else:
        lines.append(
            "1. (a) faster than every peer at N >= 2.5e5: not measured (no size "
            ">= 2.5e5 in this run)."
        )
    rows = t["pgpm"]["within_10x_poisson"]
    if rows:
        met = all(r["met"] for r in rows)
        lines.append(
            f"2. (a) within 10x of the Poisson solve (e): **{'met' if met else 'not met'}** "
            "(ratios "
            + ", ".join(f"{r['problem']} N={r['dofs']}: {r['ratio']:.1f}" for r in rows)
            + ")."
        )
    rows = t.get("ssn_vs_sequenced", [])
    if rows:
        met = all(r["met"] for r in rows)
        lines.append(
            "3. (b) SSN, the default method, faster than the grid-sequenced SNES VI peer at "
            f"N >= 2.5e5 (issue 18): **{'met' if met else 'not met'}**."
        )
        for r in rows:
            best = r["best_peer"]
            peer = (
                f"fastest grid-sequenced peer {best[0]} {best[1]:.1f} s ({best[1] / r['time']:.2f}x"
                " SSN's time)"
                if best
                else "no grid-sequenced peer converged"
            )
            tie = " (within 10%: a tie on this shared machine)" if r["tie"] else ""
            lines.append(
                f"   - {r['problem']}, N = {r['dofs']}: SSN {r['time']:.1f} s, {peer}{tie}."
            )
    else:
        lines.append(
            "3. (b) SSN faster than the grid-sequenced SNES VI peer at N >= 2.5e5: not "
            "measured (no size >= 2.5e5 in this run)."
        )
    for method, label in (("apgpm", "APGPM"), ("ssn", "SSN")):
        other = t.get(method)
        if not other:
            continue
        fast, within = other["faster_than_peers"], other["within_10x_poisson"]
        parts = []
        if fast:
            parts.append(
                "faster than every PETSc peer at N >= 2.5e5 in "
                f"{sum(r['met'] for r in fast)} of {len(fast)} cases"
            )
        if within:
            big = [r for r in within if r["dofs"] >= 2.5e5]
            parts.append(
                "within 10x of the Poisson solve in "
                f"{sum(r['met'] for r in within)} of {len(within)} cases (ratio "
                f"{min(r['ratio'] for r in within):.1f}-{max(r['ratio'] for r in within):.1f}"
                + (f"; {max(r['ratio'] for r in big):.1f} at most for N >= 2.5e5" if big else "")
                + ")"
            )
        if parts:
            lines.append(
                f"- For comparison, the project's {label} (b) with the same "
                f"preconditioner: {'; '.join(parts)}."
            )
    return lines


#: Profile entries that are not parts of a PGPM iteration: the measured total, and the
#: B_Omega product of earlier runs (PGPM carries B_Omega u along without a product).
_NOT_IN_ITERATION = ("one PGPM iteration (measured)", "B_Omega u (norm of the step)")


def _profile_text(result) -> list[str]:
    profiled = [r for r in result["records"] if r.get("profile")]
    if not profiled:
        return []
    lines = ["## Where the time goes", ""]
    for r in profiled:
        prof = r["profile"]
        unit = prof["residual assembly DG(u)"]
        lines += [
            f"PGPM, {r['problem']}, N = {r['dofs']}: {r['iterations']} iterations, "
            f"{1e3 * prof['one PGPM iteration (measured)']:.1f} ms each (best of 5 per "
            "part, at the final iterate):",
            "",
            "| part | ms | / residual assembly |",
            "|---|---:|---:|",
        ]
        for name, t in prof.items():
            if name not in _NOT_IN_ITERATION[1:]:
                lines.append(f"| {name} | {1e3 * t:.2f} | {t / unit:.2f} |")
        lines.append("")
    table, poisson = index_records(result["records"])
    for r in profiled:
        snes = table.get((r["problem"], r["cells"], "snes-substructuring"))
        if snes and snes.get("details") and snes["status"] == "ok":
            d = snes["details"]
            rest = (
                snes["solve"]
                - d["time_function"]
                - d["time_jacobian"]
                - d["time_pc_apply"]
                - d["time_pc_setup"]
            )
            lines.append(
                f"SNES VI + CG/B, {r['problem']}, N = {r['dofs']}: {snes['iterations']} Newton "
                f"steps, {snes['linear_iterations']} CG iterations; of {snes['solve']:.1f} s: "
                f"residuals {d['time_function']:.1f} s, Hessian assembly "
                f"{d['time_jacobian']:.1f} s, B^-1 applications {d['time_pc_apply']:.1f} s "
                f"({d['pc_applications']}), PETSc itself (submatrix of the inactive set, "
                f"Hessian products, vector work) {rest:.1f} s."
            )
    return lines


def _discussion(result) -> list[str]:
    """What the numbers say and what would close the gaps (computed from the run)."""
    table, poisson = index_records(result["records"])
    pgpm = [r for r in table.values() if r["solver"] == "pgpm" and r["status"] == "ok"]
    profiled = [r for r in result["records"] if r.get("profile") and r["solver"] == "pgpm"]
    if not pgpm or not profiled:
        return []
    its = [r["iterations"] for r in pgpm]
    r = max(profiled, key=lambda q: q["dofs"])
    prof = r["profile"]
    e = poisson.get(r["cells"])
    t_iter = prof["one PGPM iteration (measured)"]
    t_res, t_energy = prof["residual assembly DG(u)"], prof["energy assembly G(u)"]
    listed = sum(v for k, v in prof.items() if k not in _NOT_IN_ITERATION)
    lines = [
        "## Reading the numbers, and what would close the gaps",
        "",
        f"- PGPM's iteration count is h-independent, as the paper claims: {min(its)}-"
        f"{max(its)} iterations from N = {min(q['dofs'] for q in pgpm)} to "
        f"{max(q['dofs'] for q in pgpm)} on both problems. The PETSc peers without a good "
        "preconditioner do not have this: "
        "BLMVM and BQNLS need thousands of iterations already at N = 1e4, and PGPM with the "
        "identity metric does not converge within its budget at N = 1e4.",
        f"- One PGPM iteration costs {t_iter / t_res:.1f} residual assemblies at N = "
        f"{r['dofs']} ({1e3 * t_iter:.0f} ms): the residual DG(u) ({1e3 * t_res:.0f} ms) and "
        f"the energy G(u) ({1e3 * t_energy:.0f} ms) dominate; B^-1, the dense S_h product and "
        "the exact projection together are below one residual assembly, and "
        f"{1e3 * max(t_iter - listed, 0.0):.0f} ms are vector operations in Python. So "
        "the substructuring preconditioner is cheap; the cost is the ~170 nonlinear "
        "evaluations of J_h and its gradient.",
    ]
    increases = sum(q.get("details", {}).get("energy_increases", 0) for q in pgpm)
    if e and e.get("total"):
        units = e["total"] / t_res
        lean = r["setup"] + r["iterations"] * (t_iter - t_energy)
        lines.append(
            f"- The Poisson yardstick at this size costs {e['total']:.1f} s, about {units:.0f} "
            f"residual assemblies (assembly, GAMG set-up and {e['iterations']} CG iterations). "
            f"Ten of them are {10 * units:.0f} residual assemblies, while PGPM needs "
            f"{r['iterations'] * t_iter / t_res:.0f}: with a count of ~170 no iteration "
            "costing a residual assembly or more can meet the 10x target. Dropping the "
            "energy assembly from the step (J_h is only needed for the monotonicity check "
            f"that triggers backtracking, which fired {increases} times in this run: "
            "evaluate it every k steps or test descent with the gradient already computed) "
            "would bring this run to about "
            f"{lean:.0f} s, {lean / e['total']:.1f}x the Poisson solve. Fusing the energy "
            "into the residual kernel (one pass over the cells computes rho(|grad u|) once) "
            "is the alternative if J_h must be evaluated at every step."
        )
    big = max(q["cells"] for q in pgpm)
    at_big = {
        (q["problem"], q["solver"]): q
        for q in table.values()
        if q["cells"] == big and q.get("status") == "ok"
    }
    snes = [
        (p, at_big[p, "snes-substructuring"]["total"] / at_big[p, "pgpm"]["total"])
        for p in PROBLEMS
        if (p, "snes-substructuring") in at_big and (p, "pgpm") in at_big
    ]
    mem = [
        (at_big[p, "snes-substructuring"]["delta_mb"], at_big[p, "pgpm"]["delta_mb"])
        for p, _ in snes
    ]
    shrink = []
    for p in PROBLEMS:
        ratios = [
            (q["dofs"], q["total"] / table[p, q["cells"], "pgpm"]["total"])
            for q in sorted(table.values(), key=lambda q: q["cells"])
            if q["problem"] == p
            and q["solver"] == "snes-substructuring"
            and q.get("status") == "ok"
            and q["dofs"] >= 2.5e5
            and table.get((p, q["cells"], "pgpm"), {}).get("status") == "ok"
        ]
        if ratios:
            shrink.append(f"{p} " + ", ".join(f"{x:.2f} (N = {d})" for d, x in ratios))
    sub = [
        q
        for q in table.values()
        if q["solver"] == "snes-substructuring" and q.get("status") == "ok"
    ]
    newton = [q["iterations"] for q in sub]
    cg = [q["linear_iterations"] / max(q["iterations"], 1) for q in sub]
    fast = [
        q["total"] / table[q["problem"], q["cells"], "pgpm"]["total"]
        for q in table.values()
        if q["solver"] in ("apgpm", "ssn")
        and q.get("status") == "ok"
        and table.get((q["problem"], q["cells"], "pgpm"), {}).get("status") == "ok"
    ]
    mumps = [
        q["total"] / at_big[q["problem"], "pgpm"]["total"]
        for (p, n), q in at_big.items()
        if n in ("snes-mumps-cholesky", "tao-bnls", "tao-bntr") and (p, "pgpm") in at_big
    ]
    if snes:
        lines.append(
            "- Against SNES VI + CG/B the gap is the iteration count, not the preconditioner: "
            f"Newton needs {min(newton)}-{max(newton)} outer steps, each one Hessian assembly "
            f"and {min(cg):.0f}-{max(cg):.0f} CG iterations of a sparse product and one B^-1, "
            "instead of ~170 "
            "nonlinear evaluations. SNES pays for the dense S_h block as "
            f"{(r['n_gamma'] + r['n_signorini']) ** 2:.1e} AIJ entries at N = {r['dofs']} "
            "(every CG product and the inactive-set submatrix of every Newton step go "
            "through them; memory increase "
            + ", ".join(f"{a:.0f} MB vs PGPM's {b:.0f} MB" for a, b in mem)
            + "). SNES / PGPM time: "
            + "; ".join(shrink)
            + "."
        )
    if fast:
        lines.append(
            "- The project's own answers are in the tables: APGPM (Nesterov momentum in the "
            "B metric with restarts, ~55 iterations) and SSN (semismooth Newton with "
            "B-preconditioned CG on the inactive set, the dense block applied as a dense "
            "product, 11-12 outer steps; the default method) take "
            f"{min(fast):.2f}-{max(fast):.2f} of PGPM's time at every size; Targets above "
            "lists where they beat every PETSc peer and stay within 10x of the Poisson "
            "solve. PGPM (the paper's method) needs the cheaper iteration above to get near "
            "the 10x line."
        )
    if mumps:
        lines.append(
            "- MUMPS-based peers (SNES VI and TAO BNLS/BNTR) factor the reduced Hessian with "
            "its dense n_Gamma x n_Gamma block at every Newton step: "
            f"{min(mumps):.1f}-{max(mumps):.1f}x PGPM's time at N = {r['dofs']}, with the "
            "largest memory peaks. The first-order TAO methods (BLMVM, BQNLS) do not reach "
            "PGPM's accuracy by their own test and run out of budget early (tables)."
        )
    lines += [
        f"- Timing noise: the machine was shared (load average {result['machine']['load']:.1f} "
        "at the start on 2 cores). Two full runs of the same PGPM code during development "
        "differed by 2-5% at N = 1e6 and up to 16% at N = 2.5e5 (more for sub-second "
        f"solves), so differences within {100 * TIE:.0f}% of the fastest peer are marked "
        "as ties.",
    ]
    return lines


def print_table(result: dict[str, Any]) -> None:
    for problem in PROBLEMS:
        print(f"\n## {PROBLEMS[problem]['label']}\n")
        print("\n".join(markdown_table(result, problem)))
    print()
    print("\n".join(_targets_text(result)))
