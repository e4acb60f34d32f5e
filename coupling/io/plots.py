"""PNG figures of a solved problem (matplotlib, Agg backend), written on rank 0.

Every figure is drawn from the arrays of fields.npz (:mod:`coupling.io.outputs`) and the
iteration history alone, so it can be redrawn from the outputs of a finished run:

- ``u.png``: u_h over Omega; Gamma_s drawn thick, red where in contact, blue where open.
- ``boundary.png``: the gap phi_h, the flux rho du_h/dn (the contact pressure on
  Gamma_s), the exterior flux du_e/dn and the contact set
  against the arc length s along Gamma (counter-clockwise from ``boundary_x[0]``),
  with Gamma_s shaded and the corners of Omega marked.
- ``whole_plane.png``: u_h in Omega and u_e outside (representation formula,
  METHOD.md section 2) in one colour scale; they differ across Gamma by u0 - phi.
- ``history.png``: the relative B-norm step and the relative energy excess of each
  iteration against the tolerance, and the size of the contact set.

The problem is dimensionless, so the axes carry no units.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.path import Path as PolygonPath  # noqa: E402
from matplotlib.tri import Triangulation  # noqa: E402

import bem_cpp  # noqa: E402
from coupling.io.atomic import atomic_write  # noqa: E402
from fem_py.polyline import arc_length, closest_on_polygon  # noqa: E402

__all__ = ["PLOT_FILES", "write_plots", "true_runs"]

#: The figures, in the order they are written.
PLOT_FILES = ("u.png", "boundary.png", "whole_plane.png", "history.png")

_CONTACT = dict(ls="none", marker="o", ms=3.5, color="tab:red")
_OPEN = dict(ls="none", marker="o", ms=3.5, mfc="white", mec="tab:blue", mew=1.0)


def _closed(a: np.ndarray) -> np.ndarray:
    return np.concatenate([a, a[:1]])


def _signorini_panels(fields: dict) -> np.ndarray:
    """Panel i = [node i, node i+1] lies on Gamma_s when one of its nodes carries phi
    (every arc has interior nodes: d >= 2h)."""
    s = fields["signorini"]
    return s | np.roll(s, -1)


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Maximal runs [i, j) of True in a cyclic boolean array (panels along Gamma)."""
    n = len(mask)
    if mask.all():
        return [(0, n)]
    start = int(np.flatnonzero(~mask)[0])  # begin the scan on a panel off the runs
    runs, i = [], None
    for k in range(start + 1, start + n + 1):
        on = mask[k % n]
        if on and i is None:
            i = k
        elif not on and i is not None:
            runs.append((i, k))
            i = None
    return runs


def _corners(nodes: np.ndarray) -> np.ndarray:
    """Indices of the boundary nodes where Gamma turns (corners of Omega)."""
    t = np.diff(_closed(nodes), axis=0)
    t /= np.linalg.norm(t, axis=1)[:, None]
    t_in = np.roll(t, 1, axis=0)
    return np.flatnonzero(np.abs(t_in[:, 0] * t[:, 1] - t_in[:, 1] * t[:, 0]) > 1e-8)


def _draw_boundary(ax, fields: dict) -> None:
    """Gamma (thin black) and Gamma_s (thick): red where in contact (phi_h = 0 at both
    ends of a panel), blue where the gap is open; the Signorini nodes as dots when
    there are few enough to tell apart."""
    nodes = fields["boundary_x"]
    closed = _closed(nodes)
    ax.plot(closed[:, 0], closed[:, 1], "k-", lw=0.8, zorder=4)
    panels = _signorini_panels(fields)
    if not panels.any():
        return
    shut = fields["phi"] == 0.0
    contact = panels & shut & np.roll(shut, -1)
    segments = np.stack([nodes, np.roll(nodes, -1, axis=0)], axis=1)
    for mask, color, label in (
        (contact, "tab:red", r"$\Gamma_s$ in contact ($\phi_h = 0$)"),
        (panels & ~contact, "tab:blue", r"$\Gamma_s$ open ($\phi_h > 0$)"),
    ):
        ax.add_collection(
            LineCollection(
                segments[mask], colors=color, linewidths=3.0, capstyle="butt", label=label, zorder=5
            )
        )
    sig, active = fields["signorini"], fields["active"]
    if sig.sum() <= 64:
        ax.plot(*nodes[sig & active].T, zorder=6, **_CONTACT)
        ax.plot(*nodes[sig & ~active].T, zorder=6, **_OPEN)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=8, frameon=False)


def _figure_u(fields: dict, tri: Triangulation):
    fig, ax = plt.subplots(figsize=(5.6, 5.2))
    im = ax.tripcolor(tri, fields["u"], shading="gouraud", cmap="viridis")
    fig.colorbar(im, ax=ax, shrink=0.85, label="$u_h$")
    _draw_boundary(ax, fields)
    ax.set(aspect="equal", xlabel="$x$", ylabel="$y$", title=r"$u_h$ in $\Omega$")
    return fig


def _figure_boundary(fields: dict):
    nodes = fields["boundary_x"]
    n = len(nodes)
    s = arc_length(_closed(nodes))
    fig, axes = plt.subplots(
        4, 1, figsize=(7.5, 8.5), sharex=True, gridspec_kw=dict(height_ratios=[3, 3, 3, 1.3])
    )
    # a run of Signorini panels may wrap past node 0: shade its pieces on either side
    spans = [
        (s[a], s[b])
        for i, j in true_runs(_signorini_panels(fields))
        for a, b in ((i, min(j, n)), (max(i, n) - n, j - n))
        if b > a
    ]
    for ax in axes:
        for k, span in enumerate(spans):
            ax.axvspan(
                *span, color="tab:orange", alpha=0.15, lw=0, label=r"$\Gamma_s$" if k == 0 else None
            )
        for c in _corners(nodes):
            ax.axvline(s[c], color="0.6", lw=0.6, ls=":")
        ax.grid(alpha=0.3, lw=0.5)
    axes[0].plot(s, _closed(fields["phi"]), ".-", ms=3, lw=1)
    axes[0].set_ylabel(r"gap $\phi_h$")
    axes[1].plot(s, _closed(fields["pressure"]), ".-", ms=3, lw=1, color="tab:purple")
    axes[1].axhline(0.0, color="0.3", lw=0.6)
    axes[1].set_ylabel(r"$\rho\, \partial u_h / \partial n$" "\n(pressure on $\\Gamma_s$)")
    flux = fields["dn_ue"]
    if str(fields["flux_space"]) == "p0":
        axes[2].stairs(flux, s, color="tab:green", lw=1)
    else:
        axes[2].plot(s, _closed(flux), ".-", ms=3, lw=1, color="tab:green")
    axes[2].set_ylabel(r"$\partial u_e / \partial n$")
    sig, active = fields["signorini"], fields["active"]
    axes[3].plot(s[:-1][sig & active], np.ones(np.count_nonzero(sig & active)), **_CONTACT)
    axes[3].plot(s[:-1][sig & ~active], np.zeros(np.count_nonzero(sig & ~active)), **_OPEN)
    axes[3].set(yticks=[0, 1], yticklabels=["open", "contact"], ylim=(-0.5, 1.5))
    x0, y0 = nodes[0]
    axes[3].set_xlabel(
        f"arc length $s$ along $\\Gamma$, counter-clockwise from "
        f"$({x0:.3g}, {y0:.3g})$ (dotted: corners)"
    )
    axes[3].set_xlim(0, s[-1])
    if sig.any():
        axes[0].legend(loc="upper right", fontsize=8)
    fig.suptitle(r"Along $\Gamma$: gap, pressure, exterior flux and contact set")
    fig.tight_layout()
    return fig


def _figure_whole_plane(fields: dict, tri: Triangulation, resolution: int = 121):
    """u_h inside and u_e outside. Outside, u_e is evaluated on a grid and at the boundary
    nodes (its discrete trace ``ue``) and drawn on their Delaunay triangulation, so the
    colour reaches Gamma with no band: exterior_potential integrates the panels near a
    point analytically and is accurate at any distance from Gamma (its docstring);
    grid points closer than h/20 are left out only to avoid slivers."""
    nodes = fields["boundary_x"]
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    centre, half = 0.5 * (lo + hi), (hi - lo).max()
    g = np.linspace(-1, 1, resolution) * half
    X, Y = np.meshgrid(centre[0] + g, centre[1] + g)
    grid = np.column_stack([X.ravel(), Y.ravel()])
    h = np.linalg.norm(np.diff(_closed(nodes), axis=0), axis=1).max()
    outside = ~PolygonPath(nodes).contains_points(grid)
    outside[outside] = closest_on_polygon(grid[outside], nodes[_corners(nodes)])[0] > h / 20
    grid = grid[outside]
    ue_grid = bem_cpp.exterior_potential(
        nodes,
        fields["ue"],
        fields["dn_ue"],
        grid,
        a=float(fields["a"]),
        flux=str(fields["flux_space"]),
    )
    points = np.vstack([grid, nodes])
    ue = np.concatenate([ue_grid, fields["ue"]])
    ext = Triangulation(points[:, 0], points[:, 1])
    # Omega is covered by the triangles of boundary nodes alone whose centroid is inside;
    # a triangle with a grid vertex is exterior even where it cuts a corner of Omega
    # (u_h is drawn over it)
    on_gamma = np.all(ext.triangles >= len(grid), axis=1)
    centroids = points[ext.triangles].mean(axis=1)
    ext.set_mask(on_gamma & PolygonPath(nodes).contains_points(centroids))

    u = fields["u"]
    vmin, vmax = min(ue.min(), u.min()), max(ue.max(), u.max())
    levels = np.linspace(vmin, vmax, 17)[1:-1]
    fig, ax = plt.subplots(figsize=(6.2, 5.6))
    for z, (t, v) in enumerate(((ext, ue), (tri, u))):  # Omega's layers over the exterior's
        im = ax.tripcolor(
            t, v, shading="gouraud", cmap="viridis", vmin=vmin, vmax=vmax, zorder=2 * z
        )
        ax.tricontour(
            t,
            v,
            levels=levels,
            colors="white",
            linewidths=0.5,
            alpha=0.6,
            linestyles="solid",
            zorder=2 * z + 1,
        )
    fig.colorbar(im, ax=ax, shrink=0.85, label=r"$u_h$ in $\Omega$, $u_e$ outside")
    _draw_boundary(ax, fields)
    ax.set(
        aspect="equal", xlabel="$x$", ylabel="$y$", xlim=(X.min(), X.max()), ylim=(Y.min(), Y.max())
    )
    ax.set_title(
        r"Whole plane: $u_h$ in $\Omega$, $u_e$ (representation formula) outside;"
        "\n"
        r"across $\Gamma$ they differ by $u_0 - \phi_h$",
        fontsize=10,
    )
    return fig


def _figure_history(history: Sequence, tol: float):
    it = np.array([r.iteration for r in history])
    energy = np.array([r.energy for r in history])
    step = np.array([r.step_norm for r in history])
    contact = np.array([r.contact for r in history])
    fig, axes = plt.subplots(
        2, 1, figsize=(6.5, 5.5), sharex=True, gridspec_kw=dict(height_ratios=[3, 1.3])
    )
    ax = axes[0]
    ax.semilogy(it, step, label=r"$\Vert\xi_{k+1} - \xi_k\Vert_B \,/\, \Vert\xi_{k+1}\Vert_B$")
    best = energy.min()  # J* below: the lowest energy reached
    keep = energy > best
    ax.semilogy(
        it[keep],
        (energy[keep] - best) / max(abs(best), 1e-300),
        label=r"$(J_h(\xi_k) - J^*) \,/\, |J^*|$,  $J^*$: lowest $J_h$ reached",
    )
    ax.axhline(tol, color="0.4", ls="--", lw=0.8, label=f"tol = {tol:g}")
    ax.set_ylabel("relative size")
    ax.grid(alpha=0.3, lw=0.5, which="both")
    ax.legend(fontsize=8)
    ax.set_title(f"Convergence ({len(history)} iterations)")
    axes[1].step(it, contact, where="post", color="tab:red")
    axes[1].set(xlabel="iteration $k$", ylabel="contact nodes")
    axes[1].grid(alpha=0.3, lw=0.5)
    fig.tight_layout()
    return fig


def write_plots(out: Path, fields: dict, history: Sequence, *, tol: float) -> list[str]:
    """Write the figures of :data:`PLOT_FILES` into ``out`` and return their names.

    Parameters
    ----------
    fields
        The arrays of fields.npz (:func:`coupling.outputs.write_outputs`).
    history
        The PGPM iteration records (``iteration``, ``energy``, ``step_norm``,
        ``contact``); no history.png when empty.
    tol
        The PGPM tolerance, drawn in history.png.
    """
    tri = Triangulation(fields["x"][:, 0], fields["x"][:, 1], fields["triangles"])
    figures = {
        "u.png": lambda: _figure_u(fields, tri),
        "boundary.png": lambda: _figure_boundary(fields),
        "whole_plane.png": lambda: _figure_whole_plane(fields, tri),
        "history.png": lambda: _figure_history(history, tol) if len(history) else None,
    }
    written = []
    for name in PLOT_FILES:
        fig = figures[name]()
        if fig is None:
            continue
        atomic_write(
            Path(out) / name, lambda p: fig.savefig(p, dpi=110, bbox_inches="tight", format="png")
        )
        plt.close(fig)
        written.append(name)
    return written
