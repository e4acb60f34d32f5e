"""The peer benchmark's table of runs (markdown) and its figure (time against N)."""
from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

from bench.peers.solvers import PROBLEMS, SEQUENCED_KEPT, SOLVERS
from bench.peers.targets import index_records


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
