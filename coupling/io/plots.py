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

u_h is drawn as an image: :func:`rasterise` evaluates the P1 interpolant at the
centres of a pixel grid of :data:`RASTER_PIXELS` pixels along its longer side (pixels
outside Omega masked), so drawing costs the same at any mesh size; only the rasteriser's
pass over the triangles grows with N (vectorised, docs/design/outputs.md).

The problem is dimensionless, so the axes carry no units.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, NamedTuple, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.path import Path as PolygonPath  # noqa: E402
from matplotlib.transforms import Bbox  # noqa: E402
from matplotlib.tri import Triangulation  # noqa: E402

from coupling.io.atomic import atomic_write  # noqa: E402
from coupling.io.evaluation import exterior_from_fields  # noqa: E402
from fem_py.polyline import arc_length, closest_on_polygon  # noqa: E402

__all__ = [
    "PLOT_FILES",
    "RASTER_PIXELS",
    "PixelGrid",
    "rasterise",
    "coarsen",
    "write_plots",
    "exterior_samples",
    "ExteriorSamples",
    "true_runs",
]

#: The figures, in the order they are written.
PLOT_FILES = ("u.png", "boundary.png", "whole_plane.png", "history.png")
#: The figures laid out by fig.tight_layout() when they are built: saved as they are
#: (bbox_inches="tight" would draw them once more to find their extent); the others
#: are cropped to the extent "tight" gives (:func:`_tight_extent`).
_LAID_OUT = ("boundary.png", "history.png")

#: The resolution of the figures.
_DPI = 110
#: PNG encoding: zlib level 1 (the same pixels as the default 6 in half the time, files
#: ~25% larger; docs/design/speed.md, "Outputs (helper, 2026-12-02)").
_PNG = {"compress_level": 1}

#: Pixels along the longer side of the images of u_h (about twice the drawn size at 110 dpi).
RASTER_PIXELS = 600

#: Triangle-pixel pairs tested at once by :func:`rasterise` (bounds its scratch memory).
_BATCH = 1 << 16


class PixelGrid(NamedTuple):
    """Square pixels of side ``size``, ``nx`` by ``ny``, the first one's lower-left corner
    at ``origin``; pixel (i, j) (row i, column j) has its centre at
    origin + size * (j + 1/2, i + 1/2)."""

    origin: tuple[float, float]
    size: float
    nx: int
    ny: int

    @classmethod
    def covering(cls, lo: np.ndarray, hi: np.ndarray, pixels: int = RASTER_PIXELS) -> PixelGrid:
        """The grid over the box [lo, hi] with ``pixels`` pixels along its longer side."""
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        size = float((hi - lo).max()) / pixels
        nx, ny = (max(int(np.ceil(w / size - 1e-9)), 1) for w in hi - lo)
        return cls((float(lo[0]), float(lo[1])), size, nx, ny)

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """The x (nx,) and y (ny,) coordinates of the pixel centres."""
        x0, y0 = self.origin
        return (
            x0 + (np.arange(self.nx) + 0.5) * self.size,
            y0 + (np.arange(self.ny) + 0.5) * self.size,
        )

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(left, right, bottom, top), as ``imshow`` takes it."""
        x0, y0 = self.origin
        return (x0, x0 + self.nx * self.size, y0, y0 + self.ny * self.size)


def rasterise(
    x: np.ndarray, triangles: np.ndarray, values: np.ndarray, grid: PixelGrid
) -> np.ma.MaskedArray:
    """The P1 interpolant of ``values`` at the pixel centres of ``grid``.

    Each triangle is tested against the pixel centres in its bounding box (barycentric
    coordinates, all >= 0 up to round-off); a centre on an edge shared by two triangles
    takes the value of either, equal up to round-off. Vectorised over batches of
    triangle-pixel pairs: the time is linear in the triangles plus the pixels, and the
    scratch memory is bounded by the batch size.

    The bounding boxes come from the nodes: in pixel-centre units a triangle's box holds
    the centres from the smallest ceiling to the largest floor of its nodes' coordinates
    (ceil and floor are monotone), so each node's four (clipped to the grid) are
    computed once and packed into 8 bytes, and the pass over the triangles is three
    integer gathers and a minimum and maximum per triangle.

    Parameters
    ----------
    x : (N, 2) array
        Node coordinates.
    triangles : (n_cells, 3) int array
        Node indices of each triangle, either orientation.
    values : (N,) array
        Nodal values.

    Returns
    -------
    (ny, nx) masked array
        Row i holds the pixel centres at height y0 + size (i + 1/2); pixels whose centre
        lies in no triangle (outside Omega) are masked.
    """
    image = np.full(grid.ny * grid.nx, np.nan)
    values = np.asarray(values, float)
    # node coordinates in pixel-centre units: the centre of pixel (i, j) is the point (j, i)
    q = (np.asarray(x, float)[:, :2] - np.asarray(grid.origin)) / grid.size - 0.5
    boxes = _node_boxes(q, grid.nx, grid.ny)
    chunk = 1 << 16  # triangles per pass over their bounding boxes
    for start in range(0, len(triangles), chunk):
        t = triangles[start : start + chunk]
        b0, b1, b2 = (boxes.unpack(boxes.packed[t[:, k]]) for k in range(3))
        low = np.minimum(np.minimum(b0, b1), b2)  # columns 0, 1: first centre (j, i)
        high = np.maximum(np.maximum(b0, b1), b2)  # columns 2, 3: last centre (j, i)
        # most triangles far below the pixel size hold no centre
        hit = np.flatnonzero((high[:, 2] >= low[:, 0]) & (high[:, 3] >= low[:, 1]))
        t, first = t[hit], low[hit, :2].astype(np.int64)
        width = high[hit, 2:] - first + 1
        counts = width[:, 0] * width[:, 1]
        ends = np.cumsum(counts)
        # batches of whole triangles with at most _BATCH pairs (or a single triangle)
        cuts = [0]
        while cuts[-1] < len(t):
            begun = ends[cuts[-1] - 1] if cuts[-1] else 0
            cuts.append(max(int(np.searchsorted(ends, begun + _BATCH, "right")), cuts[-1] + 1))
        for a, b in zip(cuts[:-1], cuts[1:]):
            _fill(image, grid.nx, q, values, t[a:b], first[a:b], width[a:b], counts[a:b])
    return np.ma.masked_invalid(image.reshape(grid.ny, grid.nx))


class _NodeBoxes(NamedTuple):
    """Per node (ceil q_x, ceil q_y, floor q_x, floor q_y) in pixel-centre units, clipped
    to [0, n] and [-1, n - 1]; ``packed`` holds the four of a node in one element, which
    :meth:`unpack` turns back into an (m, 4) integer array."""

    packed: np.ndarray
    dtype: np.dtype

    def unpack(self, packed: np.ndarray) -> np.ndarray:
        return packed.view(self.dtype).reshape(-1, 4)


def _node_boxes(q: np.ndarray, nx: int, ny: int) -> _NodeBoxes:
    """The clipped ceilings and floors of the node coordinates ``q`` (N, 2) on an nx by
    ny grid, four int16 per node in one int64 (int32 in 16 bytes for larger grids)."""
    dtype = np.dtype(np.int16 if max(nx, ny) < 2**15 - 1 else np.int32)
    floor = np.floor(q)
    ceil = floor + (q != floor)
    boxes = np.empty((len(q), 4), dtype=dtype)
    boxes[:, :2] = np.minimum(np.maximum(ceil, 0), [nx, ny])
    boxes[:, 2:] = np.minimum(np.maximum(floor, -1), [nx - 1, ny - 1])
    element = np.dtype(np.int64) if dtype.itemsize == 2 else np.dtype((np.void, 16))
    return _NodeBoxes(boxes.view(element).ravel(), dtype)


def coarsen(
    image: np.ma.MaskedArray, grid: PixelGrid, lo: np.ndarray, hi: np.ndarray
) -> tuple[PixelGrid, np.ma.MaskedArray]:
    """``image`` on ``grid`` seen through pixels twice as large covering the box [lo, hi]
    (which must contain ``grid``'s area), each centred on every other centre of ``grid``:
    the same values, no second pass over the triangles. Pixels off ``grid`` are masked.

    Returns the coarse grid and its (ny, nx) image.
    """
    o, s = np.asarray(grid.origin), grid.size
    m = np.ceil((o - s / 2 - np.asarray(lo)) / (2 * s) - 1e-9).astype(int)
    origin = o - s / 2 - 2 * s * m
    n = np.maximum(np.ceil((np.asarray(hi) - origin) / (2 * s) - 1e-9).astype(int), 1)
    coarse = PixelGrid((float(origin[0]), float(origin[1])), 2 * s, int(n[0]), int(n[1]))
    out = np.ma.masked_all((coarse.ny, coarse.nx))
    # coarse pixel (r, c) is centred on the centre of pixel (2 (r - m_y), 2 (c - m_x))
    cols, rows = (mk + np.arange((nk + 1) // 2) for mk, nk in zip(m, (grid.nx, grid.ny)))
    cols, rows = cols[(cols >= 0) & (cols < coarse.nx)], rows[(rows >= 0) & (rows < coarse.ny)]
    out[np.ix_(rows, cols)] = image[np.ix_(2 * (rows - m[1]), 2 * (cols - m[0]))]
    return coarse, out


def _fill(image, nx, q, values, t, first, width, counts) -> None:
    """Write the values at the pixel centres inside the triangles ``t`` (m, 3) into the
    flat ``image`` (a batch of :func:`rasterise`; ``q``: the nodes in pixel-centre
    units, ``first`` the first centre (j, i) of each bounding box, ``width`` its
    columns and rows, ``counts`` = their product)."""
    p0 = q[t[:, 0]]
    e1, e2 = q[t[:, 1]] - p0, q[t[:, 2]] - p0
    with np.errstate(divide="ignore", invalid="ignore"):  # degenerate triangles: NaN, dropped
        det = 1.0 / (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    # per triangle: p0 and the rows of [e1 e2]^-1, so (l1, l2) = rows (centre - p0)
    rows = np.column_stack([p0, e2[:, 1] * det, -e2[:, 0] * det, -e1[:, 1] * det, e1[:, 0] * det])
    if len(counts) == counts.sum():  # one centre per box (triangles below the pixel size)
        k, j, i = None, first[:, 0], first[:, 1]
    else:
        k = np.repeat(np.arange(len(counts)), counts)
        local = np.arange(len(k)) - np.repeat(np.cumsum(counts) - counts, counts)
        w = width[k, 0]
        j = first[k, 0] + local % w
        i = first[k, 1] + local // w
        rows = rows[k]
    dx, dy = j - rows[:, 0], i - rows[:, 1]
    l1 = rows[:, 2] * dx + rows[:, 3] * dy
    l2 = rows[:, 4] * dx + rows[:, 5] * dy
    tol = -1e-12
    inside = np.flatnonzero((l1 >= tol) & (l2 >= tol) & (1.0 - l1 - l2 >= tol))
    t = t[inside] if k is None else t[k[inside]]
    l1, l2, v0 = l1[inside], l2[inside], values[t[:, 0]]
    value = v0 + l1 * (values[t[:, 1]] - v0) + l2 * (values[t[:, 2]] - v0)
    image[i[inside] * nx + j[inside]] = value


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


def _image(ax, image: np.ma.MaskedArray, grid: PixelGrid, **kwargs):
    """``image`` drawn over the area of ``grid``; masked pixels are transparent."""
    return ax.imshow(
        image, origin="lower", extent=grid.extent, cmap="viridis", interpolation="nearest", **kwargs
    )


def _figure_u(fields: dict, image: np.ma.MaskedArray, grid: PixelGrid):
    fig, ax = plt.subplots(figsize=(5.6, 5.2))
    im = _image(ax, image, grid)
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


class ExteriorSamples(NamedTuple):
    """u_e at the points of the whole-plane grid outside Omega (:func:`exterior_samples`)."""

    points: np.ndarray  # (m, 2)
    ue: np.ndarray  # (m,)


def _plane_square(nodes: np.ndarray) -> tuple[np.ndarray, float]:
    """(centre, half side) of the square of whole_plane.png: Omega's box, twice as wide."""
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    return 0.5 * (lo + hi), float((hi - lo).max())


def exterior_samples(fields: dict, resolution: int = 121) -> ExteriorSamples:
    """u_e (the representation formula, METHOD.md section 2) on the ``resolution`` x
    ``resolution`` grid of whole_plane.png, at its points outside Omega farther than
    h/20 from Gamma, from the boundary arrays of ``fields`` (``boundary_x``, ``ue``,
    ``dn_ue``, ``a``, ``flux_space``). bem_cpp releases the GIL while it evaluates, so
    :func:`coupling.io.outputs.write_outputs` runs this in a thread."""
    nodes = fields["boundary_x"]
    centre, half = _plane_square(nodes)
    g = np.linspace(-1, 1, resolution) * half
    X, Y = np.meshgrid(centre[0] + g, centre[1] + g)
    grid = np.column_stack([X.ravel(), Y.ravel()])
    h = np.linalg.norm(np.diff(_closed(nodes), axis=0), axis=1).max()
    # Gamma is the polygon of its corners (the other nodes lie on its sides): tested
    # against it, not against all n nodes (O(n) per point); points on Gamma, on either
    # side of the test, are dropped with the others closer than h/20
    corners = nodes[_corners(nodes)]
    outside = ~PolygonPath(corners).contains_points(grid)
    outside[outside] = closest_on_polygon(grid[outside], corners)[0] > h / 20
    grid = grid[outside]
    return ExteriorSamples(grid, exterior_from_fields(fields, grid))


def _figure_whole_plane(
    fields: dict, image: np.ma.MaskedArray, u_grid: PixelGrid, samples: ExteriorSamples
):
    """u_h inside and u_e outside, rasterised on one pixel grid. Outside, u_e is
    evaluated on a coarse grid (``samples``, :func:`exterior_samples`) and at the boundary
    nodes (its discrete trace ``ue``) and interpolated linearly on their Delaunay
    triangulation, so the colour reaches Gamma with no band: exterior_potential
    integrates the panels near a point analytically and is accurate at any distance from
    Gamma (its docstring); grid points closer than h/20 are left out only to avoid
    slivers. u_h (``image`` on ``u_grid``, coarsened to the plane's pixels) covers every
    pixel whose centre is in Omega."""
    nodes = fields["boundary_x"]
    centre, half = _plane_square(nodes)
    grid = samples.points
    points = np.vstack([grid, nodes])
    ue = np.concatenate([samples.ue, fields["ue"]])
    ext = Triangulation(points[:, 0], points[:, 1])
    # Omega is covered by the triangles of boundary nodes alone whose centroid is inside;
    # a triangle with a grid vertex is exterior even where it cuts a corner of Omega
    # (u_h is drawn over it)
    interior = np.all(ext.triangles >= len(grid), axis=1)
    centroids = points[ext.triangles[interior]].mean(axis=1)
    interior[interior] = PolygonPath(nodes).contains_points(centroids)
    exterior = ext.triangles[~interior]

    pixels, inner = coarsen(image, u_grid, centre - half, centre + half)
    outer = np.ma.masked_where(~inner.mask, rasterise(points, exterior, ue, pixels))
    u = fields["u"]
    vmin, vmax = min(ue.min(), u.min()), max(ue.max(), u.max())
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
    _draw_boundary(ax, fields)
    ax.set(
        aspect="equal",
        xlabel="$x$",
        ylabel="$y$",
        xlim=(centre[0] - half, centre[0] + half),
        ylim=(centre[1] - half, centre[1] + half),
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


def _tight_extent(fig) -> Bbox:
    """The extent (inches) that ``savefig(bbox_inches="tight")`` crops ``fig`` to: its
    tight bounding box, padded by ``savefig.pad_inches``, found with the renderer of the
    figure itself. Given to ``savefig`` it saves the same PNG without the layout draw
    that ``"tight"`` makes first (the figure is built at the saving dpi, :data:`_DPI`)."""
    box = fig.get_tightbbox(fig.canvas.get_renderer())
    return box.padded(plt.rcParams["savefig.pad_inches"])


def write_plots(
    out: Path,
    fields: dict,
    history: Sequence,
    *,
    tol: float,
    exterior: Callable[[], ExteriorSamples] | None = None,
) -> list[str]:
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
    exterior
        Returns the samples of u_e of whole_plane.png (:func:`exterior_samples` of
        ``fields``, e.g. computed meanwhile in a thread); default: computed here.
    """
    if exterior is None:
        exterior = lambda: exterior_samples(fields)  # noqa: E731
    x = fields["x"]
    grid = PixelGrid.covering(x.min(axis=0), x.max(axis=0))
    image = rasterise(x, fields["triangles"], fields["u"], grid)  # for both figures of u_h
    figures = {
        "u.png": lambda: _figure_u(fields, image, grid),
        "boundary.png": lambda: _figure_boundary(fields),
        "whole_plane.png": lambda: _figure_whole_plane(fields, image, grid, exterior()),
        "history.png": lambda: _figure_history(history, tol) if len(history) else None,
    }
    written = []
    for name in PLOT_FILES:
        with plt.rc_context({"figure.dpi": _DPI}):
            fig = figures[name]()
        if fig is None:
            continue
        bbox = None if name in _LAID_OUT else _tight_extent(fig)  # no second layout draw
        atomic_write(
            Path(out) / name,
            lambda p: fig.savefig(p, dpi=_DPI, bbox_inches=bbox, format="png", pil_kwargs=_PNG),
        )
        plt.close(fig)
        written.append(name)
    return written
