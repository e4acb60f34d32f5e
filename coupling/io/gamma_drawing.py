"""Gamma and its Signorini part drawn on the axes of a planar figure, the scalar run's
(:mod:`coupling.io.figures`) and the elastic run's (:mod:`coupling.io.elastic_figures`):
the contact and open runs of Gamma_s, the Signorini nodes' markers, and the triangulation
of the exterior samples up to Gamma."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")  # before anything of pyplot is imported: no display

import numpy as np  # noqa: E402
from matplotlib import patheffects  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.path import Path as PolygonPath  # noqa: E402
from matplotlib.transforms import ScaledTranslation  # noqa: E402
from matplotlib.tri import Triangulation  # noqa: E402

__all__ = [
    "CONTACT_MARKER",
    "OPEN_MARKER",
    "closed",
    "signorini_panels",
    "true_runs",
    "draw_boundary",
    "exterior_triangulation",
]

#: the markers of the Signorini nodes in contact and open
CONTACT_MARKER = dict(ls="none", marker="o", ms=3.5, color="tab:red")
OPEN_MARKER = dict(ls="none", marker="o", ms=3.5, mfc="white", mec="tab:blue", mew=1.0)

#: the open part of Gamma_s over u_h: white on a black edge, far from every colour of
#: the colormap (blue would vanish in viridis' blues)
_OPEN_LINE = "white"
_OPEN_EDGE = [patheffects.Stroke(linewidth=5.0, foreground="black"), patheffects.Normal()]
#: inches between the bottom of the axes and the legend under them (tick labels and the
#: x label take about 0.4)
_LEGEND_DROP = 0.5


def closed(a: np.ndarray) -> np.ndarray:
    """The closed polyline (or values) of Gamma: the first entry repeated last."""
    return np.concatenate([a, a[:1]])


def signorini_panels(fields: dict) -> np.ndarray:
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


def frame_plane(ax, lo, hi) -> None:
    """A figure of the plane: equal aspect, the axes named x and y, the view [lo, hi] (the
    lower left and upper right corners)."""
    ax.set(aspect="equal", xlabel="$x$", ylabel="$y$", xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]))


def draw_boundary(ax, fields: dict) -> None:
    """Gamma (thin black) and Gamma_s (thick): red where in contact (phi_h = 0 at both
    ends of a panel), white on a black edge where the gap is open; each run of panels one
    line, so no stroke of the edge ends between its panels (drawn panel by panel, the
    open part looked like a dashed band), and drawn over the axes' frame, which Gamma_s
    may lie on; the Signorini nodes as dots when there are few enough to tell apart."""
    nodes = fields["boundary_x"]
    loop = closed(nodes)
    ax.plot(loop[:, 0], loop[:, 1], "k-", lw=0.8, zorder=4, clip_on=False)
    panels = signorini_panels(fields)
    if not panels.any():
        return
    shut = fields["phi"] == 0.0
    contact = panels & shut & np.roll(shut, -1)
    n = len(nodes)
    handles = []
    for mask, color, label in (
        (contact, "tab:red", r"$\Gamma_s$ in contact ($\phi_h = 0$)"),
        (panels & ~contact, _OPEN_LINE, r"$\Gamma_s$ open ($\phi_h > 0$)"),
    ):
        effects = _OPEN_EDGE if color == _OPEN_LINE else None
        lines = [nodes[np.arange(i, j + 1) % n] for i, j in true_runs(mask)]
        ax.add_collection(
            LineCollection(
                lines,
                colors=color,
                linewidths=3.0,
                capstyle="butt",
                joinstyle="round",
                label=label,
                zorder=5,
                path_effects=effects,
                clip_on=False,
            )
        )
        handles.append(Line2D([], [], color=color, lw=3.0, label=label, path_effects=effects))
    sig, active = fields["signorini"], fields["active"]
    if sig.sum() <= 64:
        ax.plot(*nodes[sig & active].T, zorder=6, **CONTACT_MARKER)
        ax.plot(*nodes[sig & ~active].T, zorder=6, **OPEN_MARKER)
    # below the tick labels and the x label, whatever the height of the axes (Omega's shape)
    below = ax.transAxes + ScaledTranslation(0.0, -_LEGEND_DROP, ax.figure.dpi_scale_trans)
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, 0.0),
        bbox_transform=below,
        ncol=2,
        fontsize=8,
        frameon=False,
    )


def exterior_triangulation(samples: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points (the exterior ``samples`` (m, 2), then the boundary ``nodes`` (n, 2)) and
    the triangles (k, 3) of their Delaunay triangulation outside Omega, on which values
    at the samples and the trace on Gamma are interpolated up to Gamma with no band.
    Omega is covered by the triangles of boundary nodes alone whose centroid is inside
    (left out); a triangle with a sample vertex is exterior even where it cuts a corner of
    Omega (what is drawn inside Omega covers it)."""
    points = np.vstack([samples, nodes])
    ext = Triangulation(points[:, 0], points[:, 1])
    interior = np.all(ext.triangles >= len(samples), axis=1)
    centroids = points[ext.triangles[interior]].mean(axis=1)
    interior[interior] = PolygonPath(nodes).contains_points(centroids)
    return points, ext.triangles[~interior]
