"""What the figures of a body in R^3 are drawn from (:mod:`coupling.io.body_figures`).

From the arrays of fields.npz and the iteration history, :func:`surface_inputs` collects
the surface triangulation of Gamma with u_h, the gap, the pressure and the contact set at
its nodes, and :func:`section` a section of the body by a coordinate plane (``[output]
slice``: ``"x = c"``, ``"y = c"``, ``"z = c"``, or ``"auto"``, the plane through the
Signorini part that crosses it along its longest extent, :func:`slice_plane`): u_h at the
pixel centres inside the body (point location in the tetrahedra), u_e by the
representation formula outside (docs/method.md section 11), and the section of Gamma
itself, the triangles cut by the plane, as the outline. NumPy and bem_cpp only: no
matplotlib, no MPI.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from coupling.io.evaluation import exterior_from_fields
from coupling.options import parse_slice
from fem_py.mesh import interpolate_p1

__all__ = [
    "BODY_PLOT_FILES",
    "BodyFigureInputs",
    "section",
    "slice_plane",
    "surface_inputs",
    "SLICE_PIXELS",
]

#: The figures of a body, in the order they are written.
BODY_PLOT_FILES = ("signorini.png", "surface.png", "slice.png", "history.png")
#: Pixels along each side of the section's image of u_h.
SLICE_PIXELS = 121
#: u_e is evaluated at every SLICE_EXTERIOR_STRIDE-th pixel in each direction (u_e is
#: smooth outside): the representation formula costs points times triangles as direct
#: sums (measured at 35,937 dofs: 19 s for every pixel), less compressed (bem_cpp's
#: crossover), and a quarter of the pixels a quarter of either.
SLICE_EXTERIOR_STRIDE = 2
#: Relative accuracy of the section's u_e (the compressed representation formula): a
#: colour map resolves about 1/256 of the range, and at 1e-4 the image moves by 2e-5 of
#: it (64^3 box: 2.4 s instead of 5.1 s at the solver's 1e-6; at 1e-2 the compressed
#: solid angle takes exterior points for interior ones; docs/design/three_dimensions.md)
SLICE_POTENTIAL_TOL = 1e-4


class BodyFigureInputs(NamedTuple):
    """The arrays of the figures of a body (a few MB plus Gamma's triangulation)."""

    nodes: np.ndarray  # (n, 3) boundary nodes
    triangles: np.ndarray  # (m, 3) rows of nodes
    fields: dict  # boundary arrays (n,): u, phi, pressure, active, signorini
    section: dict | None  # z, u_h and u_e images (NaN where not), their extents (x0, x1, y0, y1)
    history: dict
    tol: float


def surface_inputs(fields: dict, history: dict, *, tol: float) -> BodyFigureInputs:
    """The inputs of the figures drawn on Gamma and of the history (``section`` None: no
    slice.png from them), at once: the surface arrays of ``fields`` as they are."""
    boundary = dict(
        u=fields["boundary_u"],
        phi=fields["phi"],
        pressure=fields["pressure"],
        active=fields["active"],
        signorini=fields["signorini"],
    )
    nodes, triangles = fields["boundary_x"], fields["boundary_triangles"]
    return BodyFigureInputs(nodes, triangles, boundary, None, history, float(tol))


def slice_plane(fields: dict, text: str = "auto") -> tuple[int, float]:
    """The plane of slice.png as (the axis across it, its coordinate): ``[output] slice``
    as given, or for ``"auto"`` the plane through the centroid of the Signorini nodes
    across the axis along which they extend least among the two that span their face (so
    it cuts the Signorini part along its longest extent, and an L-shaped bracket's foot
    through the foot); without Signorini nodes the plane z = z_c through the middle of
    the bounding box."""
    given = parse_slice(text)
    if given is not None:
        return given
    nodes, on = fields["boundary_x"], fields["signorini"]
    if not on.any():
        return 2, float(0.5 * (nodes[:, 2].min() + nodes[:, 2].max()))
    part = nodes[on]
    spread = np.ptp(part, axis=0)
    across = int(np.argmin(spread))  # the face's normal, for a flat part
    k = min((a for a in range(3) if a != across), key=lambda a: (spread[a], -a))
    return k, float(part[:, k].mean())


def section(fields: dict, plane: str = "auto") -> dict:
    """The section of slice.png by the plane ``plane`` (``[output] slice``,
    :func:`slice_plane`): the axis across it and its coordinate, the names of the two
    in-plane axes, the images of u_h and u_e (NaN where they do not apply) and their
    extents, and the section of Gamma (``outline``, (m, 2, 2) segments in the plane's
    coordinates), from ``fields`` (module docstring): the point location in the
    tetrahedra and the representation formula, the figures' costly part."""
    nodes = fields["boundary_x"]
    k, value = slice_plane(fields, plane)
    i, j = (a for a in range(3) if a != k)
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * float(max(hi[i] - lo[i], hi[j] - lo[j]))
    centre = centre[[i, j]]
    g = np.linspace(-2.0, 2.0, SLICE_PIXELS) * half  # the body and its surroundings
    # shifted by a third of a pixel: no pixel centre on a face at a round coordinate
    g = g + (g[1] - g[0]) / 3.0
    X, Y = np.meshgrid(centre[0] + g, centre[1] + g)
    points = np.empty((X.size, 3))
    points[:, i], points[:, j], points[:, k] = X.ravel(), Y.ravel(), value
    u = interpolate_p1(fields["x"], fields["cells"], fields["u"], points)
    # outside: u_e by the representation formula (accurate close to Gamma) on the coarser
    # grid of every SLICE_EXTERIOR_STRIDE-th pixel; should a pixel centre lie on Gamma to
    # round-off (refused by the formula), those within a pixel of a boundary node are
    # left out
    s = SLICE_EXTERIOR_STRIDE
    coarse = points.reshape(X.shape + (3,))[::s, ::s].reshape(-1, 3)
    outside = ~np.isfinite(u.reshape(X.shape)[::s, ::s].ravel())
    ue = np.full(len(coarse), np.nan)
    if outside.any():
        try:
            ue[outside] = exterior_from_fields(fields, coarse[outside], SLICE_POTENTIAL_TOL)
        except ValueError:
            outside[outside] = ~_close_to(nodes, coarse[outside], float(g[s] - g[0]))
            ue[outside] = exterior_from_fields(fields, coarse[outside], SLICE_POTENTIAL_TOL)
    return dict(
        axis="xyz"[k],
        value=value,
        names=("xyz"[i], "xyz"[j]),
        u=u.reshape(X.shape),
        u_extent=_extent(centre, g),
        ue=ue.reshape(X[::s, ::s].shape),
        ue_extent=_extent(centre, g[::s]),
        outline=plane_section(nodes, fields["boundary_triangles"], k, value)[:, :, [i, j]],
    )


def plane_section(nodes: np.ndarray, triangles: np.ndarray, k: int, value: float) -> np.ndarray:
    """The segments (m, 2, 3) where the triangles cross the plane x_k = value: the section
    of the surface, exact for flat triangles (a triangle lying in the plane, or touching
    it at a corner only, gives none; one with an edge in the plane gives that edge)."""
    d = nodes[triangles][:, :, k] - value  # (t, 3) signed distances of the corners
    below, above = (d < 0).sum(axis=1), (d > 0).sum(axis=1)
    crossing = (below > 0) & (above > 0) | (((below > 0) | (above > 0)) & ((d == 0).sum(1) == 2))
    segments = []
    for tri, dist in zip(triangles[crossing], d[crossing]):
        ends = [nodes[tri[a]] for a in range(3) if dist[a] == 0]
        for a, b in ((0, 1), (1, 2), (2, 0)):
            if dist[a] * dist[b] < 0:
                t = dist[a] / (dist[a] - dist[b])
                ends.append(nodes[tri[a]] + t * (nodes[tri[b]] - nodes[tri[a]]))
        if len(ends) == 2:
            segments.append(ends)
    return np.asarray(segments, dtype=float).reshape(-1, 2, 3)


def _extent(centre: np.ndarray, g: np.ndarray) -> tuple[float, float, float, float]:
    """imshow's extent of the pixels centred at centre + (g_j, g_i): half a pixel beyond."""
    half = 0.5 * float(g[1] - g[0])
    lo, hi = float(g[0]) - half, float(g[-1]) + half
    return (centre[0] + lo, centre[0] + hi, centre[1] + lo, centre[1] + hi)


def _close_to(nodes: np.ndarray, points: np.ndarray, distance: float) -> np.ndarray:
    """Whether each point lies within ``distance`` of a boundary node (a pixel next to
    Gamma on the section, with the pixel at least as large as the triangles)."""
    from scipy.spatial import cKDTree

    if not len(points):
        return np.zeros(0, bool)
    return cKDTree(nodes).query(points, distance_upper_bound=distance)[0] < np.inf
