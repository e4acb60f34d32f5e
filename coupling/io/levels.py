"""The table and figure of the levels of a nested or adaptive run: ``levels.csv`` and
``levels.png`` (the estimator against the dofs, log-log, with the fitted slope)."""
from __future__ import annotations

import csv
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from coupling.io.atomic import atomic_write  # noqa: E402

__all__ = ["LEVEL_FILES", "write_levels", "fitted_slope"]

#: The files this module writes.
LEVEL_FILES = ("levels.csv", "levels.png")

_COLUMNS = (
    "dofs",
    "boundary_dofs",
    "estimator",
    "iterations",
    "cg_iterations",
    "converged",
    "time",
)


def fitted_slope(dofs, values) -> float:
    """The least-squares slope of log(values) against log(dofs) (NaN with < 2 points)."""
    dofs, values = np.asarray(dofs, dtype=float), np.asarray(values, dtype=float)
    keep = (dofs > 0) & (values > 0)
    if keep.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(dofs[keep]), np.log(values[keep]), 1)[0])


def write_levels(out: Path, levels: list[dict], *, plot: bool) -> list[str]:
    """Write levels.csv (one row per level; the columns each level has) and, with ``plot``
    and an estimator per level, levels.png. Returns the names written (rank 0 only)."""
    columns = [c for c in _COLUMNS if all(c in level for level in levels)]
    table = io.StringIO()
    writer = csv.writer(table, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows([[level[c] for c in columns] for level in levels])
    atomic_write(Path(out) / "levels.csv", lambda p: p.write_text(table.getvalue()))
    written = ["levels.csv"]
    if plot and "estimator" in columns:
        dofs = [level["dofs"] for level in levels]
        eta = [level["estimator"] for level in levels]
        fig, ax = plt.subplots(figsize=(6, 4.5))
        ax.loglog(dofs, eta, "o-", label=f"estimator (slope {fitted_slope(dofs, eta):.2f})")
        ax.set_xlabel("dofs")
        ax.set_ylabel(r"$\eta$")
        ax.grid(alpha=0.3, which="both", lw=0.5)
        ax.legend()
        ax.set_title(f"Levels ({len(levels)})")
        fig.tight_layout()
        atomic_write(Path(out) / "levels.png", lambda p: fig.savefig(p, dpi=120, format="png"))
        plt.close(fig)
        written.append("levels.png")
    return written
