"""The size of a gmsh mesh of a generated shape, estimated before meshing.

``fem_py.geometry.domain_size`` gives the exact sizes of the structured square and
L-shape in closed form; a gmsh mesh (the unstructured square and L-shape, polygons, the
disk and the ellipse) is only known once made, which takes time and memory in
proportion to its size. :func:`mesh_size_estimate` tells, in O(1) memory, from the area
and the perimeter of Omega and h, whether such a mesh can fit at all.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from fem_py.conic import CONICS, conic_plan
from fem_py.geometry import DomainSize, domain_size
from fem_py.shapes import BoundaryCurve, grid_cells_per_side, grid_outline, parse_arcs

__all__ = ["GMSH_NODES_PER_AREA", "mesh_size_estimate"]

#: P1 nodes of a gmsh mesh of size h per unit area, times h^2: 2 / sqrt(3), the nodes of
#: equilateral triangles of side h (measured 1.20-1.44 on the square, L-shape, disk and
#: ellipse at h = 0.02 .. 0.005, the excess from the boundary, counted apart below)
GMSH_NODES_PER_AREA = 2.0 / math.sqrt(3.0)


def mesh_size_estimate(
    shape: str,
    *,
    h: float,
    subdomain_size: float,
    center: Sequence[float] = (0.0, 0.0),
    width: float = 0.5,
    vertices: Sequence[Sequence[float]] | None = None,
    signorini: Any = (),
    structured: bool = False,
    allow_large: bool = False,
    radius: float = 0.25,
    semi_axes: Sequence[float] | None = None,
) -> DomainSize:
    """The sizes of a gmsh mesh of ``build_domain(comm, shape, ...)`` estimated before
    meshing, in O(1) memory, from the area A and the perimeter G of Omega and h: dofs
    about GMSH_NODES_PER_AREA A / h^2 + G / (2 h), boundary dofs G / h, Signorini dofs
    the arcs' length / h, A / d^2 subdomains (0.8-0.95 of the mesh's dofs, measured: to
    refuse a run that cannot fit before its mesh exists). Raises the errors
    ``build_domain`` raises for the arguments."""
    kwargs = dict(
        h=h,
        subdomain_size=subdomain_size,
        center=center,
        width=width,
        vertices=vertices,
        signorini=signorini,
        structured=structured,
        allow_large=allow_large,
        radius=radius,
        semi_axes=semi_axes,
    )
    domain_size(shape, **kwargs)  # the checks of build_domain
    h, d = float(h), float(subdomain_size)
    if shape in CONICS:
        _, _, _, (a, b), arcs = conic_plan(
            shape, h, d, center, radius, semi_axes, signorini, allow_large
        )
        area = math.pi * a * b
        gamma = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))  # Ramanujan
        if arcs == "all":
            contact = gamma
        else:  # an arc's share of the parameter angle, a fair share of the length
            contact = sum(((t1 - t0) % (2 * math.pi)) / (2 * math.pi) for t0, t1 in arcs) * gamma
    else:
        if shape == "polygon":
            P = np.asarray(vertices, dtype=float)
        else:
            P = grid_outline(shape, center, width, grid_cells_per_side(shape, width, d))
        x, y = P[:, 0], P[:, 1]
        area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
        B = BoundaryCurve(P)
        arcs, whole = parse_arcs(signorini, shape, B)
        gamma = float(B.len.sum())
        contact = gamma if whole else sum(arc.length for arc in arcs)
    return DomainSize(
        dofs=int(GMSH_NODES_PER_AREA * area / h**2 + gamma / (2 * h)),
        boundary_dofs=int(gamma / h),
        signorini_dofs=int(contact / h),
        subdomains=max(1, int(area / d**2)),
        h_min=h,
        h_max=h,
    )
