"""What the figures of a body in R^3 are drawn from (:mod:`coupling.io.body_figures`).

From the arrays of fields.npz and the iteration history, :func:`surface_inputs` collects
the surface triangulation of Gamma with u_h, the gap, the pressure and the contact set at
its nodes, and :func:`section` a section of the body by the plane z = z_c through its
centre (the middle of its bounding box): u_h at the pixel centres inside the body
(point location in the tetrahedra) and u_e by the representation formula outside
(docs/method.md section 11). NumPy and bem_cpp only: no matplotlib, no MPI.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from coupling.io.evaluation import exterior_from_fields
from fem_py.mesh.location3d import interpolate_p1_tetrahedra

__all__ = [
    "BODY_PLOT_FILES",
    "BodyFigureInputs",
    "section",
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


def section(fields: dict) -> dict:
    """The section of slice.png: z, the images of u_h and u_e (NaN where they do not apply)
    and their extents, from ``fields`` (module docstring): the point location in the
    tetrahedra and the representation formula, the figures' costly part."""
    nodes = fields["boundary_x"]
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * float((hi - lo)[:2].max())
    g = np.linspace(-2.0, 2.0, SLICE_PIXELS) * half  # the body and its surroundings
    # shifted by a third of a pixel: no pixel centre on a face at a round coordinate
    g = g + (g[1] - g[0]) / 3.0
    X, Y = np.meshgrid(centre[0] + g, centre[1] + g)
    points = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, centre[2])])
    u = interpolate_p1_tetrahedra(fields["x"], fields["cells"], fields["u"], points)
    # outside: u_e by the representation formula (accurate close to Gamma) on the coarser
    # grid of every SLICE_EXTERIOR_STRIDE-th pixel; should a pixel centre lie on Gamma to
    # round-off (refused by the formula), those within a pixel of a boundary node are
    # left out
    k = SLICE_EXTERIOR_STRIDE
    coarse = points.reshape(X.shape + (3,))[::k, ::k].reshape(-1, 3)
    outside = ~np.isfinite(u.reshape(X.shape)[::k, ::k].ravel())
    ue = np.full(len(coarse), np.nan)
    if outside.any():
        try:
            ue[outside] = exterior_from_fields(fields, coarse[outside], SLICE_POTENTIAL_TOL)
        except ValueError:
            outside[outside] = ~_close_to(nodes, coarse[outside], float(g[k] - g[0]))
            ue[outside] = exterior_from_fields(fields, coarse[outside], SLICE_POTENTIAL_TOL)
    return dict(
        z=float(centre[2]),
        u=u.reshape(X.shape),
        u_extent=_extent(centre, g),
        ue=ue.reshape(X[::k, ::k].shape),
        ue_extent=_extent(centre, g[::k]),
    )


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
