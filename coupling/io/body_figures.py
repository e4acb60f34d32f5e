"""The PNG figures of a body in R^3, drawn with matplotlib (Agg) from a
:class:`coupling.io.body_figure_data.BodyFigureInputs`:

- ``signorini.png``: the Signorini faces flattened onto their best plane (principal axes;
  the real coordinates when the plane is across a coordinate axis): the gap phi_h >= 0 with
  the contact set outlined, and the contact pressure sigma = rho du_h/dn <= 0 beside it, each
  coloured from the nodes with a gap unknown on a map that ends at 0 (a value of the
  wrong sign takes the colour beyond that end); the rim where a Signorini face meets
  another face, whose nodes carry no gap unknown, in grey;
- ``surface.png``: u_h on Gamma from two opposite viewpoints;
- ``slice.png``: a section by a coordinate plane (``[output] slice``; by default through
  the Signorini part): u_h inside and u_e outside in one colour scale, the section of
  Gamma outlined;
- ``history.png``: the convergence history, as for a planar run.
"""
from __future__ import annotations

from typing import Collection

import matplotlib
import matplotlib.patches

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import collections as mcollections  # noqa: E402
from mpl_toolkits.mplot3d import proj3d  # noqa: E402

from coupling.io.body_figure_data import BODY_PLOT_FILES, BodyFigureInputs  # noqa: E402
from coupling.io.history_figure import figure_history  # noqa: E402
from coupling.io.png import draw_pngs  # noqa: E402

__all__ = ["render_body"]


#: A pressure above 0 by less than this share of the largest |pressure| on the Signorini
#: nodes is drawn as 0 (less than a colour level of 256: the solver's round-off, not a
#: broken sign condition)
_SIGN_SLACK = 1e-3
#: The colour of the rim of the Signorini faces (triangles at a node without a gap
#: unknown: where a Signorini face meets another face) and of a broken sign condition
_RIM_COLOUR, _WRONG_SIGN_COLOUR = "0.85", "tab:cyan"
#: A plane whose normal is this close to a coordinate axis (cos 0.8 degrees) is drawn in
#: the other two coordinates (a hemisphere of the ball's mesh is not exactly symmetric)
_ALIGNED = 1.0 - 1e-4


def figure_signorini(inputs: BodyFigureInputs, elastic: bool = False):
    """signorini.png (module docstring); ``elastic``: the fields of an elastic run, the gap
    being the opening jump.n and the pressure drawn as p = -n.sigma n >= 0 (compression
    positive), on a map that starts at 0."""
    f, tri = inputs.fields, inputs.triangles
    gap = f["signorini"]  # the nodes with a gap unknown
    touching = tri[gap[tri].any(axis=1)]
    inner = touching[gap[touching].all(axis=1)]  # the triangles of the gap unknowns
    rim = touching[~gap[touching].all(axis=1)]
    if not len(inner):
        return None
    used = np.unique(touching)  # numbered 0 .. len(used) - 1 below
    inner, rim = np.searchsorted(used, inner), np.searchsorted(used, rim)
    f = {key: f[key][used] for key in ("phi", "pressure", "active", "signorini")}
    gap, points = f["signorini"], inputs.nodes[used]
    normal = np.linalg.svd(points - points.mean(axis=0), full_matrices=False)[2][2]
    axes, names, seen = _plane_axes(normal)
    x, y = (points @ axes.T).T  # real coordinates along the plane's axes
    sign = -1.0 if elastic else 1.0  # the elastic pressure drawn compression positive
    phi, sigma = f["phi"][gap], sign * f["pressure"][gap]
    slack = _SIGN_SLACK * max(float(np.abs(sigma).max()), np.finfo(float).tiny)
    pressure = sign * f["pressure"]
    pressure = np.where((sign * pressure > 0) & (sign * pressure <= slack), 0.0, pressure)
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"wspace": 0.4})
    panels = (
        # the gap phi_h >= 0 on a map starting at 0, the pressure <= 0 on one ending at 0
        # (elastic: p >= 0 on one starting at 0): a value of the wrong sign would take the
        # colour beyond the scale's end
        (left, f["phi"], (0.0, max(float(phi.max()), slack)), "viridis", "min", r"$\phi_h < 0$"),
        (
            (right, pressure, (0.0, max(float(sigma.max()), slack)), "magma", "min", "$p < 0$")
            if elastic
            else (
                right,
                pressure,
                (min(float(sigma.min()), -slack), 0.0),
                "magma",
                "max",
                r"$\sigma > 0$",
            )
        ),
    )
    for ax, values, (lo, hi), cmap, end, wrong in panels:
        over = {"min": "under", "max": "over"}[end]
        colours = plt.get_cmap(cmap).with_extremes(**{over: _WRONG_SIGN_COLOUR})
        shown = ax.tripcolor(x, y, inner, values, shading="gouraud", cmap=colours, vmin=lo, vmax=hi)
        bar = fig.colorbar(shown, ax=ax, shrink=0.85, extend=end)
        bar.set_label(f"{_WRONG_SIGN_COLOUR[4:]}: {wrong}, the wrong sign", fontsize=8)
        if len(rim):
            ax.tripcolor(x, y, rim, facecolors=np.zeros(len(rim)), cmap=_grey(), vmin=0, vmax=1)
        ax.set(aspect="equal", xlabel=names[0], ylabel=names[1])
    if elastic:
        left.set_title(r"opening $\phi_h = j_h \cdot n \geq 0$")
        right.set_title(r"contact pressure $p = -n \cdot \sigma(u_h)\, n \geq 0$")
    else:
        left.set_title(r"gap $\phi_h \geq 0$")
        right.set_title(r"pressure $\sigma = \rho\,\partial u_h/\partial n \leq 0$")
    on = f["active"]
    if 0 < on[gap].sum() < gap.sum():
        for ax in (left, right):
            ax.tricontour(x, y, inner, on.astype(float), levels=[0.5], colors="tab:red")
    left.plot(x[on], y[on], ".", color="tab:red", ms=2)
    handles = [
        plt.Line2D([], [], color="tab:red", marker=".", label="contact set (nodes, outline)"),
        matplotlib.patches.Patch(color=_RIM_COLOUR, label="rim: nodes without a gap unknown"),
    ]
    fig.legend(handles=handles[: 1 + bool(len(rim))], loc="lower center", ncol=2, fontsize=9)
    counts = f"{int(on.sum())} of {int(gap.sum())}"
    fig.suptitle(f"Signorini faces, seen {seen}: {counts} nodes in contact")
    return fig


def _grey():
    """A colour map of one colour: the rim's."""
    from matplotlib.colors import ListedColormap

    return ListedColormap([_RIM_COLOUR])


def _plane_axes(normal: np.ndarray) -> tuple[np.ndarray, tuple[str, str], str]:
    """Two orthonormal axes (2, 3) of the plane of ``normal``, their names and the
    direction the plane is seen from. A plane across a coordinate axis (the box's faces,
    the ball's hemispheres) takes the other two coordinate axes in their order, so that
    the figure shows the real coordinates; another plane the coordinate axis closest to
    it, projected, and the axis across both."""
    normal = normal / np.linalg.norm(normal)
    k = int(np.argmax(np.abs(normal)))
    if abs(normal[k]) > _ALIGNED:
        i, j = (m for m in range(3) if m != k)
        return np.eye(3)[[i, j]], ("xyz"[i], "xyz"[j]), f"along {'xyz'[k]}"
    k = int(np.argmin(np.abs(normal)))
    first = np.eye(3)[k] - normal[k] * normal
    first /= np.linalg.norm(first)
    second = np.cross(normal, first)
    names = tuple("along ({:.2f}, {:.2f}, {:.2f})".format(*a) for a in (first, second))
    return (
        np.stack([first, second]),
        names,
        "along their normal ({:.2f}, {:.2f}, {:.2f})".format(*normal),
    )


class GouraudSurface(mcollections.Collection):
    """Triangles in a 3D axes with a colour per corner, drawn farthest first in one call
    of the renderer's Gouraud triangles: what mplot3d's Poly3DCollection does (project,
    sort by mean depth, draw) with one numpy pass instead of a Path per polygon (3 s for
    the 49,152 triangles of a 64^3 box, against 0.1 s)."""

    def __init__(self, corners: np.ndarray, colours: np.ndarray):
        super().__init__()
        self._paths = []  # no polygons: draw() below is the drawing
        self._corners, self._colours = corners, colours  # (t, 3, 3), (t, 3, 4)
        self._projected = (np.empty((0, 3, 2)), np.empty((0, 3, 4)))

    def do_3d_projection(self) -> float:
        """Project onto the axes' view and sort by depth; returns the nearest depth (the
        artists' own order, as Poly3DCollection's)."""
        x, y, z = proj3d.proj_transform(*self._corners.reshape(-1, 3).T, self.axes.M)
        depth = z.reshape(-1, 3).mean(axis=1)
        far_first = np.argsort(-depth, kind="stable")
        flat = np.stack([x, y], axis=-1).reshape(-1, 3, 2)
        self._projected = (flat[far_first], self._colours[far_first])
        return float(depth.min()) if len(depth) else np.nan

    def draw(self, renderer) -> None:
        if not self.get_visible() or not len(self._projected[0]):
            return
        gc = renderer.new_gc()
        self._set_gc_clip(gc)
        renderer.draw_gouraud_triangles(gc, *self._projected, self.axes.transData.frozen())
        gc.restore()


def _figure_surface(inputs: BodyFigureInputs):
    nodes, tri, u = inputs.nodes, inputs.triangles, inputs.fields["u"]
    norm = plt.Normalize(float(u.min()), float(u.max()))
    colours = plt.get_cmap("viridis")(norm(u))[tri]  # (t, 3, 4): a colour per corner
    fig = plt.figure(figsize=(11, 5))
    surface_views(fig, nodes[tri], colours, nodes.min(axis=0), nodes.max(axis=0))
    mappable = plt.cm.ScalarMappable(norm=norm, cmap="viridis")
    fig.colorbar(mappable, ax=fig.axes, shrink=0.7, label=r"$u_h$ on $\Gamma$")
    return fig


def surface_views(fig, corners: np.ndarray, colours: np.ndarray, lo, hi) -> list:
    """A closed surface (triangles ``corners`` (t, 3, 3), a colour per corner ``colours``
    (t, 3, 4)) in the box [lo, hi], seen from above and from below side by side in
    ``fig``: the two 3D axes (the triangles facing away from the eye are hidden behind the
    others, so only those facing it are drawn: half the triangles to sort and fill)."""
    outward = outward_normals(corners)
    # a flat side keeps a thousandth of the box's largest side
    aspect = np.maximum(hi - lo, 1e-3 * float((hi - lo).max()))
    axes = []
    for k, (elev, azim) in enumerate(((25, -60), (-25, 120))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        e, a = np.radians(elev), np.radians(azim)
        eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
        front = outward @ eye > 0.0
        ax.add_collection(GouraudSurface(corners[front], colours[front]), autolim=False)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]))
        ax.set(xlabel="$x$", ylabel="$y$", zlabel="$z$")
        ax.set_box_aspect(aspect)
        ax.view_init(elev=elev, azim=azim)
        ax.set_title(f"seen from elevation {elev}, azimuth {azim}", fontsize=9)
        axes.append(ax)
    return axes


def outward_normals(corners: np.ndarray) -> np.ndarray:
    """The normals (t, 3) of a closed surface's triangles ``corners`` (t, 3, 3), turned
    outward: the orientation whose enclosed (signed) volume is positive."""
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    centre = corners.reshape(-1, 3).mean(axis=0)
    volume = np.einsum("ij,ij->", corners[:, 0] - centre, normals) / 6.0
    return normals if volume > 0 else -normals


def _figure_slice(inputs: BodyFigureInputs):
    s = inputs.section
    u, ue = np.ma.masked_invalid(s["u"]), np.ma.masked_invalid(s["ue"])
    both = np.concatenate([u.compressed(), ue.compressed()])
    if not len(both):
        return None
    kwargs = dict(origin="lower", vmin=both.min(), vmax=both.max(), cmap="viridis")
    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    # u_e beneath, its pixels inside the body filled from their nearest outside: u_h's
    # pixels cover them, and no band of neither is left along Gamma between u_h's fine
    # pixels and u_e's coarser ones
    ax.imshow(filled_image(s["ue"]), extent=s["ue_extent"], interpolation="bilinear", **kwargs)
    shown = ax.imshow(u, extent=s["u_extent"], **kwargs)
    # the section of Gamma itself (the triangles cut by the plane), not the pixels' edge
    ax.add_collection(mcollections.LineCollection(s["outline"], colors="white", linewidths=1.0))
    fig.colorbar(shown, ax=ax, label=r"$u_h$ inside, $u_e$ outside")
    first, second = s["names"]
    title = f"section {s['axis']} = {s['value']:.4g}"
    if not u.count():
        title += " (the plane misses the body)"
    ax.set(xlabel=f"${first}$", ylabel=f"${second}$", title=title)
    return fig


def filled_image(image: np.ndarray) -> np.ndarray:
    """``image`` with each NaN pixel given its nearest finite pixel's value (all NaN:
    unchanged)."""
    from scipy.ndimage import distance_transform_edt

    missing = ~np.isfinite(image)
    if missing.all() or not missing.any():
        return image
    nearest = distance_transform_edt(missing, return_distances=False, return_indices=True)
    return image[tuple(nearest)]


def render_body(inputs: BodyFigureInputs, skip: Collection[str] = ()) -> dict[str, bytes]:
    """The PNG files of :data:`BODY_PLOT_FILES` drawn from ``inputs``, as {name: bytes},
    but those named in ``skip`` (no signorini.png without Signorini nodes, no slice.png
    without the section, no history.png without history)."""
    figures = {
        "signorini.png": lambda: figure_signorini(inputs),
        "surface.png": lambda: _figure_surface(inputs),
        "slice.png": lambda: None if inputs.section is None else _figure_slice(inputs),
        "history.png": lambda: (
            figure_history(inputs.history, inputs.tol) if len(inputs.history["iteration"]) else None
        ),
    }
    return draw_pngs(figures, BODY_PLOT_FILES, skip)
