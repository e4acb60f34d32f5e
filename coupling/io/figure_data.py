"""The arrays the figures are drawn from, at a size independent of the mesh.

:func:`rasterise` evaluates the P1 interpolant of nodal values at the centres of a
:class:`PixelGrid` (pixels outside the mesh masked), so a figure drawn from the image
costs the same at any mesh size; only the pass over the triangles grows with N
(vectorised, docs/design/outputs.md). :func:`coarsen` views an image through pixels
twice as large without a second pass. :class:`FigureInputs` holds everything the
figures of :mod:`coupling.io.figures` need: a few MB, sent as it is to the figure
process (:mod:`coupling.io.figure_worker`). NumPy only: no MPI, no matplotlib.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = [
    "PLOT_FILES",
    "RASTER_PIXELS",
    "FigureInputs",
    "PixelGrid",
    "rasterise",
    "coarsen",
    "plane_square",
]

#: The figures, in the order they are written.
PLOT_FILES = ("u.png", "boundary.png", "whole_plane.png", "history.png")

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


def plane_square(nodes: np.ndarray) -> tuple[np.ndarray, float]:
    """(centre, half side) of the square of whole_plane.png: the box of the boundary
    ``nodes``, twice as wide."""
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    return 0.5 * (lo + hi), float((hi - lo).max())


class FigureInputs(NamedTuple):
    """What the figures are drawn from (:func:`coupling.io.plots.figure_inputs`).

    ``image`` is u_h rasterised on ``grid`` and ``u_range`` its (min, max) over the
    nodes (all three None: not rasterised yet, no u.png or whole_plane.png from these
    inputs, :func:`coupling.io.plots.boundary_figure_inputs`); ``boundary`` the boundary
    arrays of fields.npz (``boundary_x``, ``phi``, ``pressure``, ``dn_ue``,
    ``flux_space``, ``signorini``, ``active``, ``ue``);
    ``exterior_points`` (m, 2) and ``exterior_ue`` (m,) the samples of u_e of
    whole_plane.png (None: not computed yet, no whole_plane.png); ``history`` the
    iteration records as arrays (``iteration``, ``energy``, ``step_norm``, ``contact``;
    empty: no history.png); ``tol`` the solver tolerance drawn in history.png.
    """

    image: np.ma.MaskedArray | None
    grid: PixelGrid | None
    u_range: tuple[float, float] | None
    boundary: dict
    exterior_points: np.ndarray | None
    exterior_ue: np.ndarray | None
    history: dict
    tol: float
