"""The PNG figures of a body in R^3, drawn with matplotlib (Agg) from a
:class:`coupling.io.body_figure_data.BodyFigureInputs`:

- ``signorini.png``: the Signorini faces seen from outside, flattened onto their best
  plane (principal axes): the gap phi_h coloured with the contact set outlined (phi_h = 0
  nodes), and the contact pressure rho du_h/dn beside it;
- ``surface.png``: u_h on Gamma from two opposite viewpoints;
- ``slice.png``: the section z = z_c: u_h inside and u_e outside in one colour scale;
- ``history.png``: the convergence history, as for a planar run.
"""
from __future__ import annotations

import io
from typing import Collection

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import collections as mcollections  # noqa: E402
from mpl_toolkits.mplot3d import proj3d  # noqa: E402

from coupling.io.body_figure_data import BODY_PLOT_FILES, BodyFigureInputs  # noqa: E402
from coupling.io.history_figure import figure_history  # noqa: E402

__all__ = ["render_body"]

_DPI = 110
_PNG = {"compress_level": 1}


def _figure_signorini(inputs: BodyFigureInputs):
    f, tri = inputs.fields, inputs.triangles
    patch = tri[f["signorini"][tri].any(axis=1)]  # triangles at a phi unknown
    if not len(patch):
        return None
    used = np.unique(patch)
    points = inputs.nodes[used]
    centred = points - points.mean(axis=0)
    axes, names = _plane_axes(np.linalg.svd(centred, full_matrices=False)[2][2])
    flat = np.zeros((len(inputs.nodes), 2))
    flat[used] = centred @ axes.T
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.6))
    for ax, key, title, cmap in (
        (left, "phi", r"gap $\phi_h$ (contact set outlined)", "viridis"),
        (right, "pressure", r"pressure $\rho\,\partial u_h/\partial n$ on $\Gamma_s$", "magma"),
    ):
        shown = ax.tripcolor(flat[:, 0], flat[:, 1], patch, f[key], shading="gouraud", cmap=cmap)
        fig.colorbar(shown, ax=ax, shrink=0.85)
        ax.set(aspect="equal", title=title, xlabel=names[0], ylabel=names[1])
    contact = f["active"].astype(float)
    if 0 < contact[used].sum() < len(used):
        left.tricontour(flat[:, 0], flat[:, 1], patch, contact, levels=[0.5], colors="tab:red")
    on = f["active"]
    left.plot(flat[on, 0], flat[on, 1], ".", color="tab:red", ms=2, label="in contact")
    left.legend(fontsize=8, loc="upper right")
    counts = f"{int(on.sum())} of {int(f['signorini'].sum())}"
    fig.suptitle(f"Signorini faces, seen along their normal: {counts} nodes in contact")
    return fig


def _plane_axes(normal: np.ndarray) -> tuple[np.ndarray, tuple[str, str]]:
    """Two orthonormal axes of the plane of ``normal`` (2, 3), the first along the
    coordinate axis closest to the plane, and their names (the coordinate's, when the
    axis is one: the box's faces)."""
    normal = normal / np.linalg.norm(normal)
    k = int(np.argmin(np.abs(normal)))
    first = np.eye(3)[k] - normal[k] * normal
    first /= np.linalg.norm(first)
    second = np.cross(normal, first)
    names = []
    for axis in (first, second):
        j = int(np.argmax(np.abs(axis)))
        exact = abs(abs(axis[j]) - 1.0) < 1e-9
        names.append(("-" if axis[j] < 0 else "") + "xyz"[j] if exact else "in the plane")
    return np.stack([first, second]), (names[0], names[1])


class _GouraudSurface(mcollections.Collection):
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
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    corners = nodes[tri]
    outward = _outward_normals(corners)
    fig = plt.figure(figsize=(11, 5))
    for k, (elev, azim) in enumerate(((25, -60), (-25, 120))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        # the triangles facing away from the eye are hidden behind the others (a closed
        # surface): only those facing it are drawn (half the triangles to sort and fill)
        e, a = np.radians(elev), np.radians(azim)
        eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
        front = outward @ eye > 0.0
        ax.add_collection(_GouraudSurface(corners[front], colours[front]), autolim=False)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]))
        ax.set(xlabel="$x$", ylabel="$y$", zlabel="$z$")
        ax.set_box_aspect(hi - lo)
        ax.view_init(elev=elev, azim=azim)
        ax.set_title(f"seen from elevation {elev}, azimuth {azim}", fontsize=9)
    mappable = plt.cm.ScalarMappable(norm=norm, cmap="viridis")
    fig.colorbar(mappable, ax=fig.axes, shrink=0.7, label=r"$u_h$ on $\Gamma$")
    return fig


def _outward_normals(corners: np.ndarray) -> np.ndarray:
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
    ax.imshow(ue, extent=s["ue_extent"], interpolation="bilinear", **kwargs)
    shown = ax.imshow(u, extent=s["u_extent"], **kwargs)
    if u.count():  # the section of Gamma: the edge of the pixels inside
        inside = np.isfinite(s["u"]).astype(float)
        ax.contour(inside, levels=[0.5], colors="white", linewidths=1.0, extent=s["u_extent"])
    fig.colorbar(shown, ax=ax, label=r"$u_h$ inside, $u_e$ outside")
    ax.set(xlabel="$x$", ylabel="$y$", title=f"section z = {s['z']:.4g}")
    return fig


def render_body(inputs: BodyFigureInputs, skip: Collection[str] = ()) -> dict[str, bytes]:
    """The PNG files of :data:`BODY_PLOT_FILES` drawn from ``inputs``, as {name: bytes},
    but those named in ``skip`` (no signorini.png without Signorini nodes, no slice.png
    without the section, no history.png without history)."""
    figures = {
        "signorini.png": lambda: _figure_signorini(inputs),
        "surface.png": lambda: _figure_surface(inputs),
        "slice.png": lambda: None if inputs.section is None else _figure_slice(inputs),
        "history.png": lambda: (
            figure_history(inputs.history, inputs.tol) if len(inputs.history["iteration"]) else None
        ),
    }
    pngs = {}
    for name in (n for n in BODY_PLOT_FILES if n not in skip):
        with plt.rc_context({"figure.dpi": _DPI}):
            fig = figures[name]()
        if fig is None:
            continue
        buffer = io.BytesIO()
        fig.savefig(buffer, dpi=_DPI, bbox_inches="tight", format="png", pil_kwargs=_PNG)
        plt.close(fig)
        pngs[name] = buffer.getvalue()
    return pngs
