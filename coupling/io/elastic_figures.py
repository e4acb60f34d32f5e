"""The PNG figures of an elastic run, drawn with matplotlib (Agg) from a
:class:`coupling.io.elastic_figure_data.ElasticFigureInputs`:

- ``deformed.png``: the deformed body, the displacement magnified by the factor in the
  title (the largest displacement about a tenth of the body's size), coloured by the von
  Mises stress of sigma(u_h), the undeformed outline thin and dashed. 2D: constant on each
  triangle (the P1 gradient and the material), Gamma_s drawn on the deformed outline, red
  where in contact, white where open; 3D: the deformed surface from two opposite
  viewpoints, each surface triangle coloured by the stress of its tetrahedron, the edges
  of the undeformed surface thin and grey.
- ``signorini.png``: 2D, along the arc length of each Signorini arc, the contact
  pressure p = -n.sigma(u_h) n (compression positive) and the opening phi_h = j_h.n,
  the contact set shaded, both scales set by the nodes that carry a gap unknown (the
  arc's end nodes, bonded, drawn grey); 3D, the Signorini faces seen along their normal,
  the opening and the pressure (:func:`coupling.io.body_figures.figure_signorini`).
- ``exterior.png``: |u_e| and the von Mises stress of sigma(u_e), the medium's
  displacement and stress by the representation formula with Kelvin's kernel, on the
  square twice the body's box (2D; arrows of u_e) or on a section (3D, ``[output]
  slice``, by default z = z_c), the body blank, the stress blank within a sample spacing
  of Gamma.
- ``history.png``: the convergence history, as for a scalar run.

The problem is dimensionless, so the axes carry no units. Planar figures import neither
MPI nor the mesh libraries; a body's import :mod:`coupling.io.body_figures` (the figure
process of a 3D run has it imported already).
"""
from __future__ import annotations

from typing import Collection

import matplotlib
import matplotlib.patches

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.path import Path as PolygonPath  # noqa: E402

from coupling.io.elastic_figure_data import (  # noqa: E402
    ELASTIC_PLOT_FILES,
    EXTERIOR_SAMPLES_2D,
    ElasticFigureInputs,
)
from coupling.io.figure_data import PixelGrid, plane_square, rasterise  # noqa: E402
from coupling.io.gamma_drawing import (  # noqa: E402
    draw_boundary,
    exterior_triangulation,
    frame_plane,
    signorini_panels,
    true_runs,
)
from coupling.io.history_figure import figure_history  # noqa: E402
from coupling.io.png import draw_pngs  # noqa: E402
from fem_py.polyline import arc_length  # noqa: E402

__all__ = ["render_elastic"]

#: The colour map of the stress and of |u_e|.
_CMAP = "viridis"
#: Surface edges turning by more than this (degrees) are the undeformed outline of a body.
_FEATURE_ANGLE = 30.0
#: Pixels along the side of exterior.png's square (2D).
_EXTERIOR_PIXELS = 400
#: exterior.png draws u_e as an arrow at every this-th sample along each axis (2D).
_ARROW_STRIDE = 8
#: The shading of the contact set in signorini.png.
_SHADE = dict(color="tab:red", alpha=0.12, lw=0)


def _title_factor(inputs: ElasticFigureInputs) -> str:
    """The magnification and the largest displacement, for a title."""
    largest = inputs.deformed["largest"]
    return f"displacement drawn $\\times${inputs.factor:g} (largest $|u_h|$ = {largest:.3g})"


def _stress_norm(inputs: ElasticFigureInputs):
    lo, hi = inputs.deformed["range"]
    return plt.Normalize(lo, hi if hi > lo else lo + 1.0)


def _contact_fields(boundary: dict, nodes: np.ndarray) -> dict:
    """The arrays :func:`coupling.io.figures.draw_boundary` draws Gamma_s from, at
    ``nodes``: the contact set as phi = 0 (the opening is phi_h = j_h.n, 0 up to round-off
    at a node in contact)."""
    sig, active = boundary["signorini"], boundary["active"]
    return dict(
        boundary_x=nodes,
        phi=np.where(sig & ~active, 1.0, 0.0),
        signorini=sig,
        active=active,
    )


def _figure_deformed_plane(inputs: ElasticFigureInputs):
    d, b = inputs.deformed, inputs.boundary
    nodes, grid = b["boundary_x"], d["grid"]
    moved = nodes + inputs.factor * b["boundary_u"]
    fig, ax = plt.subplots(figsize=(6.4, 5.6))
    shown = ax.imshow(
        d["image"],
        origin="lower",
        extent=grid.extent,
        cmap=_CMAP,
        norm=_stress_norm(inputs),
        interpolation="nearest",
    )
    fig.colorbar(shown, ax=ax, shrink=0.85, label=r"von Mises stress of $\sigma(u_h)$")
    closed = np.vstack([nodes, nodes[:1]])
    ax.plot(*closed.T, color="0.35", lw=0.7, ls="--", zorder=3)
    draw_boundary(ax, _contact_fields(b, moved))
    lo = np.minimum(moved.min(axis=0), nodes.min(axis=0))
    hi = np.maximum(moved.max(axis=0), nodes.max(axis=0))
    pad = 0.04 * float((hi - lo).max())
    frame_plane(ax, lo - pad, hi + pad)
    ax.set_title(
        f"Deformed body, {_title_factor(inputs)}\n"
        "(dashed: undeformed outline), coloured by the von Mises stress",
        fontsize=10,
    )
    return fig


def _feature_edges(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The edges (k, 2, 3) of a closed surface where it turns by more than
    :data:`_FEATURE_ANGLE` (a box's edges; none on a smooth ball)."""
    normals = np.cross(
        nodes[triangles[:, 1]] - nodes[triangles[:, 0]],
        nodes[triangles[:, 2]] - nodes[triangles[:, 0]],
    )
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    owner = np.tile(np.arange(len(triangles)), 3)
    edges = np.sort(edges, axis=1)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    edges, owner = edges[order], owner[order]
    # on a closed surface each edge is shared by two triangles: consecutive after sorting
    pair = np.flatnonzero(np.all(edges[1:] == edges[:-1], axis=1))
    cos = np.einsum("ij,ij->i", normals[owner[pair]], normals[owner[pair + 1]])
    sharp = pair[cos < np.cos(np.radians(_FEATURE_ANGLE))]
    return nodes[edges[sharp]]


def _figure_deformed_body(inputs: ElasticFigureInputs):
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    from coupling.io.body_figures import surface_views

    d, b = inputs.deformed, inputs.boundary
    corners, nodes = d["corners"], b["boundary_x"]
    norm = _stress_norm(inputs)
    colours = np.repeat(plt.get_cmap(_CMAP)(norm(d["stress"]))[:, None, :], 3, axis=1)
    outline = _feature_edges(nodes, b["boundary_triangles"])
    both = np.vstack([corners.reshape(-1, 3), nodes])
    fig = plt.figure(figsize=(11, 5.2))
    for ax in surface_views(fig, corners, colours, both.min(axis=0), both.max(axis=0)):
        if len(outline):
            ax.add_collection3d(Line3DCollection(outline, colors="0.3", linewidths=0.6))
    mappable = plt.cm.ScalarMappable(norm=norm, cmap=_CMAP)
    fig.colorbar(
        mappable,
        ax=fig.axes,
        shrink=0.7,
        label=r"von Mises stress of $\sigma(u_h)$",
    )
    fig.suptitle(
        f"Deformed body, {_title_factor(inputs)}, coloured by the von Mises stress\n"
        "of the tetrahedron under each surface triangle; grey lines: the undeformed edges",
        fontsize=11,
    )
    return fig


def _range(values: np.ndarray, scale: float) -> tuple[float, float]:
    """Axis limits holding ``values`` and 0, with a 5 % margin; [-0.05, 1] ``scale`` when
    all are 0 (an arc wholly in contact has no opening)."""
    lo = min(float(values.min(initial=0.0)), 0.0)
    hi = max(float(values.max(initial=0.0)), 0.0)
    if not hi > lo:
        lo, hi = 0.0, scale
    pad = 0.05 * (hi - lo)
    return lo - pad, hi + pad


def _contact_spans(s: np.ndarray, on: np.ndarray, inner: np.ndarray) -> list[tuple[float, float]]:
    """The stretches of arc length of the contact set: each node in contact (``on``, at
    ``s``) owns the arc from the midpoint before it to the midpoint after it, consecutive
    ones merged; an arc's end node (bonded: not ``inner``) next to one in contact joins
    it (the jump is 0 at both)."""
    shut = on.copy()
    shut[1:] |= ~inner[1:] & on[:-1]
    shut[:-1] |= ~inner[:-1] & on[1:]
    middle = np.concatenate([s[:1], 0.5 * (s[1:] + s[:-1]), s[-1:]])
    return [(middle[i], middle[j]) for i, j in _runs(shut)]


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Maximal runs [i, j) of True in a (not cyclic) boolean array."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def _figure_signorini_plane(inputs: ElasticFigureInputs):
    b = inputs.boundary
    nodes, sig, active = b["boundary_x"], b["signorini"], b["active"]
    runs = true_runs(signorini_panels(b))
    if not sig.any() or not runs:
        return None
    n = len(nodes)
    pressure, opening = -b["pressure"], b["phi"]
    cols = len(runs)
    fig, axes = plt.subplots(
        2, cols, figsize=(max(7.0, 4.2 * cols), 6.2), sharex="col", squeeze=False
    )
    # a scale for values all 0: a thousandth of the body's size, of its largest stress
    size = float(np.ptp(nodes, axis=0).max())
    limits = (
        _range(pressure[sig], max(inputs.deformed["range"][1], np.finfo(float).tiny)),
        _range(opening[sig], 1e-3 * size),
    )
    for col, (i, j) in enumerate(runs):
        idx = np.arange(i, j + 1) % n
        s = arc_length(nodes[idx])
        on, inner = active[idx] & sig[idx], sig[idx]
        for row, (values, label) in enumerate(
            (
                (pressure, "contact pressure\n" r"$p = -n \cdot \sigma(u_h)\, n$"),
                (opening, "opening\n" r"$\phi_h = j_h \cdot n$"),
            )
        ):
            ax = axes[row, col]
            for a, c in _contact_spans(s, on, inner):
                ax.axvspan(a, c, **_SHADE)
            v = values[idx]
            ax.plot(s, v, "-", lw=1, color="tab:purple" if row == 0 else "tab:blue", zorder=2)
            ax.plot(s[inner & ~on], v[inner & ~on], "o", ms=3.5, mfc="white", mec="tab:blue")
            ax.plot(s[on], v[on], "o", ms=3.5, color="tab:red")
            ax.plot(s[~inner], v[~inner], "s", ms=3.5, color="0.6")
            ax.axhline(0.0, color="0.3", lw=0.6)
            ax.set_ylim(limits[row])
            ax.grid(alpha=0.3, lw=0.5)
            if col == 0:
                ax.set_ylabel(label)
        x0, y0 = nodes[idx[0]]
        axes[0, col].set_title(
            f"arc {col + 1}: {int(on.sum())} of {int(inner.sum())} nodes in contact", fontsize=10
        )
        axes[1, col].set_xlabel(f"arc length $s$ from $({x0:.3g}, {y0:.3g})$")
        axes[1, col].set_xlim(s[0], s[-1])
    handles = [
        plt.Line2D([], [], ls="none", marker="o", ms=5, color="tab:red", label="in contact"),
        plt.Line2D([], [], ls="none", marker="o", ms=5, mfc="white", mec="tab:blue", label="open"),
        plt.Line2D(
            [], [], ls="none", marker="s", ms=5, color="0.6", label="arc end (bonded, no gap)"
        ),
        matplotlib.patches.Patch(label="contact set", **_SHADE),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle(
        r"Along $\Gamma_s$: contact pressure (compression $> 0$) and opening;"
        "\nscales set by the nodes with a gap unknown",
        fontsize=11,
    )
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


def _figure_signorini_body(inputs: ElasticFigureInputs):
    from coupling.io.body_figure_data import BodyFigureInputs
    from coupling.io.body_figures import figure_signorini

    b = inputs.boundary
    body = BodyFigureInputs(
        b["boundary_x"],
        b["boundary_triangles"],
        {k: b[k] for k in ("phi", "pressure", "active", "signorini")},
        None,
        inputs.history,
        inputs.tol,
    )
    return figure_signorini(body, elastic=True)


def _stress_scale(stress: np.ndarray) -> tuple[float, float, str]:
    """(vmin, vmax, extend) of the medium's stress: up to its 99th percentile, so that the
    peaks at the body's corners (a singularity of the stress) leave the rest readable."""
    finite = stress[np.isfinite(stress)]
    if not len(finite):
        return 0.0, 1.0, "neither"
    top = float(np.percentile(finite, 99.0))
    top = top if top > 0.0 else max(float(finite.max()), 1.0)
    return 0.0, top, "max" if finite.max() > top else "neither"


#: The second panel of exterior.png: its label and title.
_STRESS_LABEL = r"von Mises stress of $\sigma(u_e)$"


def _figure_exterior_plane(inputs: ElasticFigureInputs):
    b, ex = inputs.boundary, inputs.exterior
    nodes = b["boundary_x"]
    centre, half = plane_square(nodes)
    points, triangles = exterior_triangulation(ex["points"], nodes)
    grid = PixelGrid.covering(centre - half, centre + half, pixels=_EXTERIOR_PIXELS)
    xc, yc = grid.centres()
    X, Y = np.meshgrid(xc, yc)
    body = PolygonPath(nodes).contains_points(np.column_stack([X.ravel(), Y.ravel()]))
    body = body.reshape(grid.ny, grid.nx)

    def image(values: np.ndarray) -> np.ma.MaskedArray:  # at the samples, then the nodes
        shown = rasterise(points, triangles, values, grid)
        return np.ma.masked_where(body | np.ma.getmaskarray(shown) | ~np.isfinite(shown), shown)

    size = np.linalg.norm(np.vstack([ex["ue"], b["ue"]]), axis=1)
    # the stress is not known on Gamma: the triangles at a boundary node are left blank
    stress = np.concatenate([ex["stress"], np.full(len(nodes), np.nan)])
    lo, hi, extend = _stress_scale(ex["stress"])
    fig, (left, right) = plt.subplots(1, 2, figsize=(12.8, 5.6), gridspec_kw={"wspace": 0.35})
    for ax, values, label, scale in (
        (left, size, r"$|u_e|$", {}),
        (right, stress, _STRESS_LABEL, dict(vmin=lo, vmax=hi)),
    ):
        shown = ax.imshow(
            image(values),
            origin="lower",
            extent=grid.extent,
            cmap=_CMAP,
            interpolation="nearest",
            **scale,
        )
        bar = dict(extend=extend) if scale else {}
        fig.colorbar(shown, ax=ax, shrink=0.85, label=label, **bar)
        ax.fill(*nodes.T, color="white", zorder=2)
        draw_boundary(ax, _contact_fields(b, nodes))
        frame_plane(ax, centre - half, centre + half)
    # the direction of u_e: arrows at every _ARROW_STRIDE-th sample of the grid
    step = 2.0 * half / (EXTERIOR_SAMPLES_2D - 1)
    lattice = np.rint((ex["points"] - (centre - half)) / step).astype(np.int64)
    some = np.all(lattice % _ARROW_STRIDE == _ARROW_STRIDE // 2, axis=1)
    if some.any():
        left.quiver(
            *ex["points"][some].T,
            *ex["ue"][some].T,
            color="white",
            alpha=0.8,
            width=0.004,
            zorder=3,
        )
    left.set_title(r"$|u_e|$; arrows: the direction and relative size of $u_e$", fontsize=10)
    right.set_title(
        _STRESS_LABEL + " (plane strain;\nblank within a sample spacing of $\\Gamma$)",
        fontsize=10,
    )
    fig.suptitle(
        "Exterior medium by the representation formula (Kelvin's kernel); "
        "the body blank, undeformed",
        fontsize=11,
    )
    return fig


def _figure_exterior_body(inputs: ElasticFigureInputs):
    from coupling.io.body_figures import filled_image

    ex = inputs.exterior
    size = np.linalg.norm(ex["ue"], axis=2)  # NaN inside the body and next to a node
    if not np.isfinite(size).any():
        return None
    # the samples left out next to a boundary node take their nearest neighbour's value
    size = np.where(ex["inside"], np.nan, filled_image(size))
    stress = ex["stress"]  # NaN inside and within a sample spacing of Gamma
    lo, hi, extend = _stress_scale(stress)
    fig, (left, right) = plt.subplots(1, 2, figsize=(12.8, 5.4), gridspec_kw={"wspace": 0.35})
    for ax, values, extent, label, scale in (
        (left, size, ex["extent"], r"$|u_e|$", {}),
        (right, stress, ex["stress_extent"], _STRESS_LABEL, dict(vmin=lo, vmax=hi)),
    ):
        shown = ax.imshow(
            np.ma.masked_invalid(values),
            origin="lower",
            extent=extent,
            cmap=_CMAP,
            interpolation="nearest",
            **scale,
        )
        ax.add_collection(LineCollection(ex["outline"], colors="black", linewidths=1.0))
        bar = dict(extend=extend) if scale else {}
        fig.colorbar(shown, ax=ax, shrink=0.85, label=label, **bar)
        first, second = ex["names"]
        ax.set(aspect="equal", xlabel=f"${first}$", ylabel=f"${second}$")
        ax.set_xlim(ex["extent"][:2])
        ax.set_ylim(ex["extent"][2:])
    left.set_title(r"$|u_e|$", fontsize=10)
    right.set_title(
        _STRESS_LABEL + " (every other sample;\nblank within a sample spacing of $\\Gamma$)",
        fontsize=10,
    )
    title = f"Exterior medium on the section {ex['axis']} = {ex['value']:.4g}, "
    title += (
        "by the representation formula (Kelvin's kernel); the body blank"
        if ex["inside"].any()
        else "(the plane misses the body)"
    )
    fig.suptitle(title, fontsize=11)
    return fig


def render_elastic(inputs: ElasticFigureInputs, skip: Collection[str] = ()) -> dict[str, bytes]:
    """The PNG files of :data:`ELASTIC_PLOT_FILES` drawn from ``inputs``, as {name: bytes}
    in that order, but those named in ``skip`` (no signorini.png without Signorini nodes,
    no exterior.png without its samples, no history.png without history)."""
    plane = inputs.dim == 2
    figures = {
        "deformed.png": _figure_deformed_plane if plane else _figure_deformed_body,
        "signorini.png": _figure_signorini_plane if plane else _figure_signorini_body,
        "exterior.png": lambda i: (
            None
            if i.exterior is None
            else (_figure_exterior_plane if plane else _figure_exterior_body)(i)
        ),
        "history.png": lambda i: (
            figure_history(i.history, i.tol) if len(i.history["iteration"]) else None
        ),
    }
    builders = {name: (lambda draw=draw: draw(inputs)) for name, draw in figures.items()}
    return draw_pngs(builders, ELASTIC_PLOT_FILES, skip)
