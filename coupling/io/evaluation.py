"""u_h and u_e at any points, from the fields of a finished run (``fembem evaluate``).

Each point is located against the mesh of fields.npz (P1 triangles,
:func:`fem_py.mesh.location.locate`) and against Gamma:

- on Gamma (closer than ``ON_GAMMA`` = 1e-11 times the diameter of Gamma's bounding
  box): u = u_h and u_e = the trace u + phi - u0, both linear along the panel;
- ``inside`` Omega (inside the polygon of Gamma's nodes, which bounds the mesh, and not
  on Gamma): u = u_h (linear interpolation in its triangle); u_e does not apply;
- ``outside``: u_e by the representation formula (docs/method.md section 2); u does not
  apply.

Values that do not apply are NaN (empty in the CSV).

An elastic run (given its ``material``) also gets the stress ``sigma`` (m, d, d): inside,
the body's sigma(u_h) of the cell holding the point (u_h is P1: its stress is constant on
a cell; :func:`coupling.io.stress.stress_tensors`); outside, the medium's
sigma(u_e) by the representation formula (``bem_cpp.exterior_stress``); NaN on Gamma,
where the two sides' stresses differ (their tractions are the boundary arrays of
fields.npz).

A body in R^3 (fields with ``x`` (N, 3), ``cells`` and ``boundary_triangles``): points
are x, y, z; on Gamma means within ``ON_GAMMA`` times the diameter of the plane of one of
Gamma's triangles, over it (values linear on the triangle); inside means in one of the
tetrahedra (:mod:`fem_py.mesh.location3d`); outside is the rest, where the representation
formula on Gamma's triangles gives u_e (docs/method.md section 11).
"""
from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

import bem_cpp
from coupling.options import hmatrix_tol
from fem_py.mesh.location import P1Points
from fem_py.mesh.location3d import on_surface
from coupling.io.stress import cell_gradients, stress_tensors
from coupling.io.figure_data import plane_square
from fem_py.polyline import closest_on_polygon, inside_polygon, polygon_corners, segment_lengths

__all__ = [
    "evaluate",
    "exterior_from_fields",
    "exterior_stress_from_fields",
    "ExteriorSamples",
    "exterior_samples",
    "ON_GAMMA",
]

#: points closer to Gamma than this times its bounding-box diameter count as on Gamma
#: (10 times the distance below which the representation formula refuses a point)
ON_GAMMA = 1e-11


def _traces(fields: dict) -> tuple:
    """The boundary data of bem_cpp's potentials in the run of ``fields``: Gamma's nodes and
    the traces u_e and du_e/dn."""
    return fields["boundary_x"], fields["ue"], fields["dn_ue"]


def _kernel(fields: dict, kernel: str | tuple | None = None) -> dict:
    """The keywords of bem_cpp's potentials for the run of ``fields``: its flux space, its
    surface, and for elasticity Kelvin's kernel of the medium and the translation a (d,).
    ``kernel``: the problem's (``SignoriniProblem.kernel``), else read from the fields
    (``exterior``: the medium's E, nu, written by an elastic run)."""
    surface = fields.get("boundary_triangles")
    out = {"flux": str(fields["flux_space"])}
    if surface is not None:
        out["triangles"] = surface
    if kernel is None and "exterior" in fields:
        kernel = ("lame", *map(float, fields["exterior"]))
    if kernel is None or (isinstance(kernel, str) and kernel == "laplace"):
        return dict(out, a=float(fields["a"]))
    return dict(out, kernel=tuple(kernel), a=np.asarray(fields["a"], dtype=float))


def exterior_from_fields(
    fields: dict,
    points: np.ndarray,
    tol: float | None = None,
    kernel: str | tuple | None = None,
) -> np.ndarray:
    """u_e at exterior ``points`` (m, 2) by the representation formula (docs/method.md section
    2) from the boundary arrays of a run's fields (``boundary_x``, ``ue``, ``dn_ue``,
    ``a``, ``flux_space``; in 3D (m, 3) points and ``boundary_triangles``), compressed
    above bem_cpp's measured crossover to the relative accuracy ``tol`` (default: the
    solver's, :func:`coupling.options.hmatrix_tol`); bem_cpp's ValueError for a point
    inside Omega or on Gamma. bem_cpp releases the GIL while it evaluates.

    ``kernel``: the problem's (``SignoriniProblem.kernel``; default: the fields', Kelvin's
    when they hold the medium ``exterior``). For Kelvin's, ``("lame", E, nu)``, the fields
    are those of an elastic run (``ue`` and ``dn_ue`` (n, d), ``a`` (d,)) and u_e is (m, d),
    by direct sums (docs/method.md section 12).
    """
    return bem_cpp.exterior_potential(
        *_traces(fields),
        points,
        compression="auto",
        tol=hmatrix_tol(fields["boundary_x"]) if tol is None else tol,
        **_kernel(fields, kernel),
    )


def exterior_stress_from_fields(fields: dict, points: np.ndarray) -> np.ndarray:
    """The stress sigma(u_e) (m, d, d) of the exterior medium at exterior ``points`` from
    the fields of an elastic run (``bem_cpp.exterior_stress``, docs/method.md section 12)."""
    return bem_cpp.exterior_stress(*_traces(fields), points, **_kernel(fields))


class ExteriorSamples(NamedTuple):
    """u_e at the points of the whole-plane grid outside Omega (:func:`exterior_samples`)."""

    points: np.ndarray  # (m, 2)
    ue: np.ndarray  # (m,), or (m, 2) for an elastic run


def exterior_samples(
    fields: dict, resolution: int = 121, kernel: str | tuple = "laplace"
) -> ExteriorSamples:
    """u_e (the representation formula, docs/method.md section 2) on the ``resolution`` x
    ``resolution`` grid of whole_plane.png, at its points outside Omega farther than
    h/20 from Gamma, from the boundary arrays of ``fields`` (``boundary_x``, ``ue``,
    ``dn_ue``, ``a``, ``flux_space``; ``kernel``: that of
    :func:`coupling.io.evaluation.exterior_from_fields`, Kelvin's for an elastic run,
    whose u_e is (m, 2)). bem_cpp releases the GIL while it evaluates, so
    :mod:`coupling.io.outputs` runs this in a thread."""
    from matplotlib.path import Path as PolygonPath

    nodes = fields["boundary_x"]
    centre, half = plane_square(nodes)
    g = np.linspace(-1, 1, resolution) * half
    X, Y = np.meshgrid(centre[0] + g, centre[1] + g)
    grid = np.column_stack([X.ravel(), Y.ravel()])
    h = segment_lengths(np.concatenate([nodes, nodes[:1]])).max()
    # Gamma is the polygon of its corners (the other nodes lie on its sides): tested
    # against it, not against all n nodes (O(n) per point); points on Gamma, on either
    # side of the test, are dropped with the others closer than h/20
    corners = nodes[polygon_corners(nodes)]
    outside = ~PolygonPath(corners).contains_points(grid)
    outside[outside] = closest_on_polygon(grid[outside], corners)[0] > h / 20
    grid = grid[outside]
    return ExteriorSamples(grid, exterior_from_fields(fields, grid, kernel=kernel))


def evaluate(fields: dict, points: np.ndarray, material: Any = None) -> dict[str, np.ndarray]:
    """``where`` ("inside", "boundary" or "outside"), ``u`` and ``ue`` at ``points`` (m, 2)
    ((m, 3) for a body in R^3); with the elastic run's ``material`` also ``sigma``
    (m, d, d) (module docstring).

    ``fields`` is the content of fields.npz (:func:`coupling.io.outputs.load_fields`).
    """
    d = fields["x"].shape[1]
    points = np.asarray(points, dtype=float).reshape(-1, d)
    values, located, of = (_evaluate_in_body if d == 3 else _evaluate_in_plane)(fields, points)
    if material is not None:
        cell = np.full(len(points), -1, dtype=np.int64)
        cell[of] = located.cells()
        values["sigma"] = _stress(fields, points, values["where"], cell, material)
    return values


def _stress(
    fields: dict, points: np.ndarray, where: np.ndarray, cell: np.ndarray, material: Any
) -> np.ndarray:
    """sigma (m, d, d) at ``points``: the body's inside (``cell`` (m,), the cell of the
    mesh that holds each point, -1 none), the medium's outside, NaN on Gamma."""
    x, u = np.asarray(fields["x"], dtype=float), _columns(fields["u"])
    d = x.shape[1]
    sigma = np.full((len(points), d, d), np.nan)
    inside = np.flatnonzero((where == "inside") & (cell >= 0))
    if inside.size:
        cells = fields["cells"] if d == 3 else fields["triangles"]
        gradients = cell_gradients(x, cells[cell[inside]], u)
        sigma[inside] = stress_tensors(gradients, material)[:, :d, :d]
    outside = where == "outside"
    if outside.any():
        sigma[outside] = exterior_stress_from_fields(fields, points[outside])
    return sigma


def _evaluate_in_plane(fields: dict, points: np.ndarray) -> tuple[dict, P1Points, np.ndarray]:
    """:func:`evaluate` for the fields of a planar run, without the stress; with the
    location in the mesh of the points it interpolated u_h at, and their indices."""
    nodes = fields["boundary_x"]
    diameter = float(np.linalg.norm(nodes.max(axis=0) - nodes.min(axis=0)))
    dist, seg, t = closest_on_polygon(points, nodes)
    on = dist <= ON_GAMMA * diameter
    # inside by Gamma itself: the mesh's point location snaps points to nodes within
    # 2^-30 of its extent, which would take a point just outside for one inside
    inside = inside_polygon(points, nodes) & ~on
    outside = ~inside & ~on
    values = _columns(fields["u"])
    located = P1Points(fields["x"], fields["triangles"], points[inside])
    u_h = [located.interpolate(c) for c in values.T]
    u, ue = _empty(len(points), fields)
    u[inside] = np.stack(u_h, axis=1)
    nxt = (seg[on] + 1) % len(nodes)
    weight = t[on][:, None]
    for out, key in ((u, "boundary_u"), (ue, "ue")):
        trace = _columns(fields[key])
        out[on] = (1.0 - weight) * trace[seg[on]] + weight * trace[nxt]
    if outside.any():
        ue[outside] = _columns(exterior_from_fields(fields, points[outside]))
    where = np.where(inside, "inside", np.where(on, "boundary", "outside"))
    return {"where": where, "u": _squeezed(u), "ue": _squeezed(ue)}, located, np.flatnonzero(inside)


def _columns(values: np.ndarray) -> np.ndarray:
    """Nodal values as (n, k) columns: k = 1 for a scalar, d for a displacement."""
    values = np.asarray(values, dtype=float)
    return values.reshape(len(values), -1)


def _empty(m: int, fields: dict) -> tuple[np.ndarray, np.ndarray]:
    """(u, ue) at m points, NaN where they do not apply: (m, 1), or (m, d) for elasticity."""
    k = _columns(fields["u"]).shape[1]
    return np.full((m, k), np.nan), np.full((m, k), np.nan)


def _squeezed(values: np.ndarray) -> np.ndarray:
    """(m,) for a scalar, (m, d) for a displacement."""
    return values[:, 0] if values.shape[1] == 1 else values


def _evaluate_in_body(fields: dict, points: np.ndarray) -> tuple[dict, P1Points, np.ndarray]:
    """:func:`evaluate` for the fields of a body in R^3 (module docstring), without the
    stress; with the location in the mesh of the points (all) and their indices."""
    nodes, surface = fields["boundary_x"], fields["boundary_triangles"]
    diameter = float(np.linalg.norm(nodes.max(axis=0) - nodes.min(axis=0)))
    triangle, bary = on_surface(nodes, surface, points, ON_GAMMA * diameter)
    on = triangle >= 0
    values = _columns(fields["u"])
    located = P1Points(fields["x"], fields["cells"], points)
    u = np.stack([located.interpolate(c) for c in values.T], axis=1)
    inside = np.isfinite(u).all(axis=1) & ~on
    outside = ~inside & ~on
    u[outside] = np.nan
    ue = np.full(u.shape, np.nan)
    corners = surface[triangle[on]]
    for out, key in ((u, "boundary_u"), (ue, "ue")):
        out[on] = np.einsum("ij,ijk->ik", bary[on], _columns(fields[key])[corners])
    if outside.any():
        ue[outside] = _columns(exterior_from_fields(fields, points[outside]))
    where = np.where(inside, "inside", np.where(on, "boundary", "outside"))
    return {"where": where, "u": _squeezed(u), "ue": _squeezed(ue)}, located, np.arange(len(points))
