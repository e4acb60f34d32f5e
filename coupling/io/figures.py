"""The PNG figures of a solved problem, drawn with matplotlib (Agg) from plain arrays.

- ``u.png``: u_h over Omega; Gamma_s drawn thick, red where in contact, white (black
  edged) where open.
- ``boundary.png``: the gap phi_h, the flux rho du_h/dn (the contact pressure on
  Gamma_s), the exterior flux du_e/dn and the contact set
  against the arc length s along Gamma (counter-clockwise from ``boundary_x[0]``),
  with Gamma_s shaded and the corners of Omega marked.
- ``whole_plane.png``: u_h in Omega and u_e outside (representation formula,
  docs/method.md section 2) in one colour scale; they differ across Gamma by u0 - phi.
- ``history.png``: the relative B-norm step and the relative energy excess of each
  iteration against the tolerance, and the size of the contact set.

:func:`render` turns a :class:`FigureInputs` (an image of u_h, the boundary arrays of
fields.npz, samples of u_e and the iteration history: a few MB at any mesh size) into
PNG bytes. It needs neither MPI nor the mesh, so it runs in this process or in the
figure process of :mod:`coupling.io.figure_worker`, with the same bytes.

The problem is dimensionless, so the axes carry no units.
"""
from __future__ import annotations

from typing import Callable, Collection

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.transforms import Bbox  # noqa: E402

from coupling.io.elastic_figure_data import ElasticFigureInputs  # noqa: E402
from coupling.io.figure_data import (  # noqa: E402
    PLOT_FILES,
    FigureInputs,
    PixelGrid,
    coarsen,
    plane_square,
    rasterise,
)
from coupling.io.gamma_drawing import (  # noqa: E402
    CONTACT_MARKER,
    OPEN_MARKER,
    closed,
    draw_boundary,
    exterior_triangulation,
    frame_plane,
    signorini_panels,
    true_runs,
)
from coupling.io.history_figure import figure_history  # noqa: E402
from coupling.io.png import draw_pngs  # noqa: E402
from fem_py.polyline import CORNER_ANGLE, arc_length, polygon_corners  # noqa: E402

__all__ = ["exterior_triangulation", "render", "true_runs", "warm_up"]

#: The figures laid out by fig.tight_layout() when they are built: saved as they are
#: (bbox_inches="tight" would draw them once more to find their extent); the others
#: are cropped to the extent "tight" gives (:func:`_tight_extent`).
_LAID_OUT = ("boundary.png", "history.png")


#: the share of |Gamma| on either side of a corner whose pressure is left out of the
#: pressure axis' range: the flux is singular at corners, and its P1 spikes (a few
#: nodes wide on a locally refined mesh) would flatten the rest
_CORNER_SHARE = 0.03


def _pressure_range(
    pressure: np.ndarray, s: np.ndarray, corners: np.ndarray
) -> tuple[float, float]:
    """y-limits of the pressure axis: the range of the pressure at the nodes (arc length
    ``s``, the closing node last) farther than ``_CORNER_SHARE`` |Gamma| from every
    corner and not next to one, with 0 and a 5 % margin; the spikes at corners run off
    the axis instead of flattening the rest."""
    n, length = len(pressure), s[-1]
    gap = np.abs(s[:n, None] - s[np.asarray(corners, dtype=np.int64)][None, :])
    gap = np.minimum(gap, length - gap).min(axis=1, initial=np.inf)
    near = gap <= _CORNER_SHARE * length
    for k in (-1, 0, 1):
        near[(np.asarray(corners, dtype=np.int64) + k) % n] = True
    values = pressure[~near] if (~near).any() else pressure
    lo, hi = min(float(values.min()), 0.0), max(float(values.max()), 0.0)
    pad = 0.05 * (hi - lo) if hi > lo else 1.0
    return lo - pad, hi + pad


def _image(ax, image: np.ma.MaskedArray, grid: PixelGrid, **kwargs):
    """``image`` drawn over the area of ``grid``; masked pixels are transparent."""
    return ax.imshow(
        image, origin="lower", extent=grid.extent, cmap="viridis", interpolation="nearest", **kwargs
    )


def _figure_u(fields: dict, image: np.ma.MaskedArray, grid: PixelGrid):
    fig, ax = plt.subplots(figsize=(5.6, 5.2))
    im = _image(ax, image, grid)
    fig.colorbar(im, ax=ax, shrink=0.85, label="$u_h$")
    draw_boundary(ax, fields)
    ax.set(aspect="equal", xlabel="$x$", ylabel="$y$", title=r"$u_h$ in $\Omega$")
    return fig


def _figure_boundary(fields: dict):
    nodes = fields["boundary_x"]
    n = len(nodes)
    s = arc_length(closed(nodes))
    fig, axes = plt.subplots(
        4, 1, figsize=(7.5, 8.5), sharex=True, gridspec_kw=dict(height_ratios=[3, 3, 3, 1.3])
    )
    # a run of Signorini panels may wrap past node 0: shade its pieces on either side
    spans = [
        (s[a], s[b])
        for i, j in true_runs(signorini_panels(fields))
        for a, b in ((i, min(j, n)), (max(i, n) - n, j - n))
        if b > a
    ]
    for ax in axes:
        for k, span in enumerate(spans):
            ax.axvspan(
                *span, color="tab:orange", alpha=0.15, lw=0, label=r"$\Gamma_s$" if k == 0 else None
            )
        for c in polygon_corners(nodes, CORNER_ANGLE):  # not every node of a curve
            ax.axvline(s[c], color="0.6", lw=0.6, ls=":")
        ax.grid(alpha=0.3, lw=0.5)
    axes[0].plot(s, closed(fields["phi"]), ".-", ms=3, lw=1)
    axes[0].set_ylabel(r"gap $\phi_h$")
    axes[1].plot(s, closed(fields["pressure"]), ".-", ms=3, lw=1, color="tab:purple")
    axes[1].axhline(0.0, color="0.3", lw=0.6)
    axes[1].set_ylim(_pressure_range(fields["pressure"], s, polygon_corners(nodes, CORNER_ANGLE)))
    axes[1].set_ylabel(r"$\rho\, \partial u_h / \partial n$" "\n(pressure on $\\Gamma_s$)")
    flux = fields["dn_ue"]
    if str(fields["flux_space"]) == "p0":
        axes[2].stairs(flux, s, color="tab:green", lw=1)
    else:
        axes[2].plot(s, closed(flux), ".-", ms=3, lw=1, color="tab:green")
    axes[2].set_ylabel(r"$\partial u_e / \partial n$")
    sig, active = fields["signorini"], fields["active"]
    axes[3].plot(s[:-1][sig & active], np.ones(np.count_nonzero(sig & active)), **CONTACT_MARKER)
    axes[3].plot(s[:-1][sig & ~active], np.zeros(np.count_nonzero(sig & ~active)), **OPEN_MARKER)
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


def _figure_whole_plane(inputs: FigureInputs):
    """u_h inside and u_e outside, rasterised on one pixel grid. Outside, u_e is
    evaluated on a coarse grid (the exterior samples of ``inputs``,
    :func:`coupling.io.plots.exterior_samples`) and at the boundary
    nodes (its discrete trace ``ue``) and interpolated linearly on their Delaunay
    triangulation, so the colour reaches Gamma with no band: exterior_potential
    integrates the panels near a point analytically and is accurate at any distance from
    Gamma (its docstring); grid points closer than h/20 are left out only to avoid
    slivers. u_h (the image of ``inputs``, coarsened to the plane's pixels) covers every
    pixel whose centre is in Omega."""
    fields = inputs.boundary
    nodes = fields["boundary_x"]
    centre, half = plane_square(nodes)
    points, exterior = exterior_triangulation(inputs.exterior_points, nodes)
    ue = np.concatenate([inputs.exterior_ue, fields["ue"]])

    pixels, inner = coarsen(inputs.image, inputs.grid, centre - half, centre + half)
    outer = np.ma.masked_where(~inner.mask, rasterise(points, exterior, ue, pixels))
    vmin, vmax = min(ue.min(), inputs.u_range[0]), max(ue.max(), inputs.u_range[1])
    levels = np.linspace(vmin, vmax, 17)[1:-1]
    fig, ax = plt.subplots(figsize=(6.2, 5.6))
    im = _image(ax, np.ma.where(inner.mask, outer, inner), pixels, vmin=vmin, vmax=vmax)
    xc, yc = pixels.centres()
    for image in (outer, inner):  # each side's own contours: u_h and u_e jump across Gamma
        if image.count() and np.ptp(image) > 0:
            ax.contour(
                xc,
                yc,
                image,
                levels=levels,
                colors="white",
                linewidths=0.5,
                alpha=0.6,
                linestyles="solid",
                zorder=1,
            )
    fig.colorbar(im, ax=ax, shrink=0.85, label=r"$u_h$ in $\Omega$, $u_e$ outside")
    draw_boundary(ax, fields)
    frame_plane(ax, centre - half, centre + half)
    ax.set_title(
        r"Whole plane: $u_h$ in $\Omega$, $u_e$ (representation formula) outside;"
        "\n"
        r"across $\Gamma$ they differ by $u_0 - \phi_h$",
        fontsize=10,
    )
    return fig


def _tight_extent(fig) -> Bbox:
    """The extent (inches) that ``savefig(bbox_inches="tight")`` crops ``fig`` to: its
    tight bounding box, padded by ``savefig.pad_inches``, found with the renderer of the
    figure itself. Given to ``savefig`` it saves the same PNG without the layout draw
    that ``"tight"`` makes first (the figure is built at the saving dpi,
    :data:`coupling.io.png.DPI`)."""
    box = fig.get_tightbbox(fig.canvas.get_renderer())
    return box.padded(plt.rcParams["savefig.pad_inches"])


def render(inputs: FigureInputs, skip: Collection[str] = ()) -> dict[str, bytes]:
    """The PNG files of :data:`PLOT_FILES` drawn from ``inputs``, as {name: bytes} in
    that order (no history.png without history); those of
    :func:`coupling.io.body_figures.render_body` for the inputs of a body in R^3, of
    :func:`coupling.io.elastic_figures.render_elastic` for those of an elastic run; but
    those named in ``skip``."""
    if isinstance(inputs, ElasticFigureInputs):  # an elastic run's (2D or 3D)
        from coupling.io.elastic_figures import render_elastic

        return render_elastic(inputs, skip)
    if not isinstance(inputs, FigureInputs):  # a body's (BodyFigureInputs): its modules
        # import the mesh libraries, and with them MPI, which planar figures never need
        from coupling.io.body_figures import render_body

        return render_body(inputs, skip)
    figures = {
        "u.png": lambda: (
            None if inputs.image is None else _figure_u(inputs.boundary, inputs.image, inputs.grid)
        ),
        "boundary.png": lambda: _figure_boundary(inputs.boundary),
        "whole_plane.png": lambda: (
            None
            if inputs.exterior_points is None or inputs.image is None
            else _figure_whole_plane(inputs)
        ),
        "history.png": lambda: (
            figure_history(inputs.history, inputs.tol) if len(inputs.history["iteration"]) else None
        ),
    }
    # no second layout draw: the laid-out figures as they are, the others to their extent
    pngs = draw_pngs(
        figures,
        PLOT_FILES,
        skip,
        bbox=lambda name, fig: None if name in _LAID_OUT else _tight_extent(fig),
    )
    return pngs


def warm_up(stop: Callable[[], bool] = lambda: False) -> None:
    """Draw and discard the figures of a small square (:func:`_warm_up_inputs`), one by one
    until ``stop()`` is true (the run's inputs have come: a short run does not wait for
    the warm-up): matplotlib loads its fonts, builds its parsers and lays out the figures'
    mathtext strings on the first draw, which the figure process does while the run
    computes."""
    inputs = _warm_up_inputs()
    for name in PLOT_FILES:
        if stop():
            return
        render(inputs, skip=[n for n in PLOT_FILES if n != name])


def _warm_up_inputs() -> FigureInputs:
    """Figure inputs of the unit square with 8 boundary nodes, two of them in contact on
    its lower side, u = x + y, two iterations and the exterior samples of one ring."""
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    nodes = np.repeat(corners, 2, axis=0)
    nodes[1::2] = 0.5 * (corners + np.roll(corners, -1, axis=0))
    n = len(nodes)
    signorini = np.zeros(n, bool)
    signorini[1] = True
    grid = PixelGrid.covering(corners[0], corners[2], pixels=8)
    image = rasterise(corners, np.array([[0, 1, 2], [0, 2, 3]]), corners.sum(axis=1), grid)
    ring = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    outside = 0.5 + 1.5 * np.column_stack([np.cos(ring), np.sin(ring)])
    history = dict(
        iteration=np.array([1.0, 2.0]),
        energy=np.array([-1.0, -1.5]),
        step_norm=np.array([0.1, 0.01]),
        contact=np.array([1.0, 1.0]),
        stop=np.array([]),
    )
    return FigureInputs(
        image=image,
        grid=grid,
        u_range=(0.0, 2.0),
        boundary=dict(
            boundary_x=nodes,
            phi=np.where(signorini, 0.0, 0.1),
            pressure=np.linspace(-1.0, 1.0, n),
            dn_ue=np.linspace(1.0, -1.0, n),
            flux_space=np.array("p1"),
            signorini=signorini,
            active=signorini.copy(),
            ue=nodes.sum(axis=1),
        ),
        exterior_points=outside,
        exterior_ue=1.0 / np.linalg.norm(outside - 0.5, axis=1),
        history=history,
        tol=1e-8,
    )
