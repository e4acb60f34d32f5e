"""The table and figure of the levels of a run with levels.

An adaptive run (``[adapt] steps > 0``) writes ``adapt.csv`` (one row per level: dofs,
the estimator eta and, when the exact solution is known (``[data] exact``), the energy
error and the efficiency index eta / error, solver counts, time) and ``adapt.png`` (eta
and the error against the dofs, log-log, with the fitted slopes in the legend). A nested
solve (``[solver] nested``) writes ``levels.csv`` (its levels' dofs, iteration counts
and times; its coarse levels are not estimated, so there is no figure).
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from coupling.io.atomic import atomic_write
from coupling.options import SLOPE_MIN_DOFS

__all__ = ["LEVEL_FILES", "write_levels", "fitted_slope", "slope_levels"]

#: The files this module writes (nested: levels.csv; adaptive: adapt.csv, adapt.png).
LEVEL_FILES = ("levels.csv", "adapt.csv", "adapt.png", "mesh.png")

_COLUMNS = (
    "level",
    "dofs",
    "boundary_dofs",
    "signorini_dofs",
    "cells",
    "subdomains",
    "marked",
    "estimator",
    "error",
    "efficiency",
    "iterations",
    "gradient_steps",
    "newton_steps",
    "cg_iterations",
    "contact_nodes",
    "converged",
    "time",
)


def slope_levels(dofs) -> np.ndarray:
    """The levels a fitted rate uses (bool mask): N >= coupling.options.SLOPE_MIN_DOFS,
    or every level when fewer than two are that large."""
    dofs = np.asarray(dofs, dtype=float)
    large = dofs >= SLOPE_MIN_DOFS
    return large if large.sum() >= 2 else np.ones(dofs.shape, bool)


def fitted_slope(dofs, values) -> float:
    """The least-squares slope of log(values) against log(dofs) over :func:`slope_levels`
    (NaN with fewer than 2 positive points)."""
    dofs, values = np.asarray(dofs, dtype=float), np.asarray(values, dtype=float)
    keep = slope_levels(dofs) & (dofs > 0) & (values > 0)
    if keep.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(dofs[keep]), np.log(values[keep]), 1)[0])


def _plot(path: Path, levels: list[dict]) -> None:
    """eta (and the error) against the dofs, log-log, slopes in the legend."""
    import matplotlib

    matplotlib.use("Agg")  # files only; imported here, as a plain or nested run draws nothing
    import matplotlib.pyplot as plt

    dofs = [level["dofs"] for level in levels]
    fit = slope_levels(dofs)
    where = f"N >= {SLOPE_MIN_DOFS}" if not fit.all() else "all levels"
    fig, ax = plt.subplots(figsize=(6, 4.5))
    series = [("estimator", r"estimator $\eta$", "o-")]
    if all("error" in level for level in levels):
        series.append(("error", r"error $|u - u_h|_1$", "s-"))
    for key, label, style in series:
        values = [level[key] for level in levels]
        ax.loglog(dofs, values, style, label=f"{label} (slope {fitted_slope(dofs, values):.2f})")
    ax.set_xlabel("dofs N")
    ax.set_ylabel(", ".join(key for key, _, _ in series))  # what is drawn
    ax.grid(alpha=0.3, which="both", lw=0.5)
    ax.legend(title=f"slopes fitted over {where}", fontsize=9, title_fontsize=8)
    ax.set_title(f"Adaptive refinement ({len(levels)} levels)")
    fig.tight_layout()
    atomic_write(path, lambda p: fig.savefig(p, dpi=120, format="png"))
    plt.close(fig)


def _surface_triangles(tetrahedra: np.ndarray) -> np.ndarray:
    """The boundary triangles of a tetrahedral mesh: the faces in one cell only."""
    faces = tetrahedra[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]].reshape(-1, 3)
    key = np.sort(faces, axis=1)
    _, first, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[first[count == 1]]


def _plot_mesh(path: Path, x: np.ndarray, cells: np.ndarray) -> None:
    """The final mesh of an adaptive run: every edge once, thin, rasterised; of a body
    (tetrahedra) its surface triangles, opaque with their edges, in an oblique 3D view."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    body = cells.shape[1] == 4
    triangles = _surface_triangles(cells) if body else cells
    edges = np.sort(triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    edges = np.unique(edges, axis=0)
    lw = float(np.clip(40.0 / np.sqrt(len(triangles)), 0.05, 0.8))
    if body:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        fig = plt.figure(figsize=(6, 6))
        ax = fig.add_subplot(projection="3d")
        faces = Poly3DCollection(
            x[triangles], facecolors="0.9", edgecolors="k", linewidths=lw, rasterized=True
        )
        ax.add_collection3d(faces)
        lo, hi = x.min(axis=0), x.max(axis=0)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]))
        ax.set_box_aspect(hi - lo)
        ax.set(xlabel="$x$", ylabel="$y$", zlabel="$z$")
        ax.set_title(f"Adapted mesh ({len(cells)} cells, {len(x)} nodes; its surface)")
    else:
        fig, ax = plt.subplots(figsize=(6, 6))
        ax.add_collection(LineCollection(x[edges][:, :, :2], colors="k", linewidths=lw))
        ax.autoscale()
        ax.set(aspect="equal", xlabel="$x$", ylabel="$y$")
        ax.set_title(f"Adapted mesh ({len(triangles)} cells, {len(x)} nodes)")
    fig.tight_layout()
    atomic_write(path, lambda p: fig.savefig(p, dpi=150, format="png"))
    plt.close(fig)


def write_levels(
    out: Path,
    levels: list[dict],
    *,
    adaptive: bool,
    plot: bool,
    mesh: tuple[np.ndarray, np.ndarray] | None = None,
) -> list[str]:
    """Write the levels' table (one row per level; the columns every level has):
    adapt.csv and, with ``plot``, adapt.png and mesh.png (``mesh``: the final mesh's
    node coordinates and triangles, or tetrahedra for a body) for an adaptive run,
    levels.csv for a nested one.
    Returns the names written (rank 0 only)."""
    columns = [c for c in _COLUMNS if all(c in level for level in levels)]
    table = io.StringIO()
    writer = csv.writer(table, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows([[level[c] for c in columns] for level in levels])
    name = "adapt.csv" if adaptive else "levels.csv"
    atomic_write(Path(out) / name, lambda p: p.write_text(table.getvalue()))
    written = [name]
    if adaptive and plot:
        _plot(Path(out) / "adapt.png", levels)
        written.append("adapt.png")
        if mesh is not None:
            _plot_mesh(Path(out) / "mesh.png", *mesh)
            written.append("mesh.png")
    return written
