"""The size of a gmsh mesh of a generated shape, estimated before meshing.

``fem_py.mesh.domain_size`` gives the exact sizes of the structured square and
L-shape in closed form; a gmsh mesh (the unstructured square and L-shape, polygons, the
disk and the ellipse) is only known once made, which takes time and memory in
proportion to its size. :func:`mesh_size_estimate` tells, in O(1) memory, from the area
and the perimeter of Omega and h, whether such a mesh can fit at all.
"""
from __future__ import annotations

import math
import numpy as np

from fem_py.mesh.build import domain_size
from fem_py.mesh.conic import CONICS, conic_plan
from fem_py.mesh.domain import DomainSize
from fem_py.mesh.shapes import BoundaryCurve, grid_cells_per_side, grid_outline, parse_arcs
from fem_py.spec import GeometrySpec

__all__ = ["GMSH_NODES_PER_AREA", "mesh_size_estimate"]

#: P1 nodes of a gmsh mesh of size h per unit area, times h^2: 2 / sqrt(3), the nodes of
#: equilateral triangles of side h (measured 1.20-1.44 on the square, L-shape, disk and
#: ellipse at h = 0.02 .. 0.005, the excess from the boundary, counted apart below)
GMSH_NODES_PER_AREA = 2.0 / math.sqrt(3.0)


def mesh_size_estimate(spec: GeometrySpec) -> DomainSize:
    """The sizes of a gmsh mesh of ``build_domain(comm, spec)`` (a generated planar shape)
    estimated before meshing, in O(1) memory, from the area A and the perimeter G of Omega
    and h: dofs about GMSH_NODES_PER_AREA A / h^2 + G / (2 h), boundary dofs G / h,
    Signorini dofs the arcs' length / h, A / d^2 subdomains (0.8-0.95 of the mesh's dofs,
    measured: to refuse a run that cannot fit before its mesh exists). Raises the errors
    ``build_domain`` raises for ``spec``."""
    domain_size(spec)  # the checks of build_domain
    shape, h, d = spec.shape, float(spec.h), float(spec.subdomain_size)
    if shape in CONICS:
        _, _, _, (a, b), arcs = conic_plan(spec)
        area = math.pi * a * b
        gamma = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))  # Ramanujan
        if arcs == "all":
            contact = gamma
        else:  # an arc's share of the parameter angle, a fair share of the length
            contact = sum(((t1 - t0) % (2 * math.pi)) / (2 * math.pi) for t0, t1 in arcs) * gamma
    else:
        if shape == "polygon":
            P = np.asarray(spec.vertices, dtype=float)
        else:
            width = float(spec.width)
            P = grid_outline(shape, spec.center, width, grid_cells_per_side(shape, width, d))
        x, y = P[:, 0], P[:, 1]
        area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
        B = BoundaryCurve(P)
        arcs, whole = parse_arcs(spec.signorini, shape, B)
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
