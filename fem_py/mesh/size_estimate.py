"""The size of a gmsh mesh of a generated shape, estimated before meshing.

``fem_py.mesh.domain_size`` gives the exact sizes of the structured square and
L-shape and of the box in closed form; a gmsh mesh (the unstructured square and L-shape,
polygons, the disk and the ellipse; the ball in 3D) is only known once made, which takes
time and memory in proportion to its size. :func:`mesh_size_estimate` tells, in O(1)
memory, from the area and the perimeter of Omega and h (from its volume and its surface
area in 3D), whether such a mesh can fit at all; :func:`gmsh_model_size` does the same
for a user's OpenCASCADE model in the current gmsh session, before it is meshed.
"""
from __future__ import annotations

import math
import numpy as np

from fem_py.mesh.build import domain_size
from fem_py.mesh.conic import CONICS, conic_plan
from fem_py.mesh.domain import DomainSize
from fem_py.mesh.shapes import BoundaryCurve, grid_cells_per_side, grid_outline, parse_arcs
from fem_py.spec import GeometrySpec

__all__ = [
    "GMSH_NODES_PER_AREA",
    "GMSH_NODES_PER_VOLUME",
    "gmsh_model_size",
    "mesh_size_estimate",
    "solid_size_estimate",
]

#: P1 nodes of a gmsh mesh of size h per unit area, times h^2: 2 / sqrt(3), the nodes of
#: equilateral triangles of side h (measured 1.20-1.44 on the square, L-shape, disk and
#: ellipse at h = 0.02 .. 0.005, the excess from the boundary, counted apart below)
GMSH_NODES_PER_AREA = 2.0 / math.sqrt(3.0)
#: Interior P1 nodes of a gmsh tetrahedral mesh of size h (``Mesh.MeshSizeMax``) per unit
#: volume, times h^3 (measured 0.56-0.66 on the ball at h = r/5 .. r/28, growing slowly
#: with r/h; the surface nodes are GMSH_NODES_PER_AREA per unit area, measured 1.21-1.36)
GMSH_NODES_PER_VOLUME = 0.55


def mesh_size_estimate(spec: GeometrySpec) -> DomainSize:
    """The sizes of a gmsh mesh of ``build_domain(comm, spec)`` (a generated planar shape)
    estimated before meshing, in O(1) memory, from the area A and the perimeter G of Omega
    and h: dofs about GMSH_NODES_PER_AREA A / h^2 + G / (2 h), boundary dofs G / h,
    Signorini dofs the arcs' length / h, A / d^2 subdomains (0.8-0.95 of the mesh's dofs,
    measured: to refuse a run that cannot fit before its mesh exists). The ball: from its
    volume and its surface area (:func:`solid_size_estimate`). Raises the errors
    ``build_domain`` raises for ``spec``."""
    closed = domain_size(spec)  # the checks of build_domain
    if spec.dim == 3:  # the box in closed form, the ball estimated
        return closed if closed is not None else _ball_size_estimate(spec)
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


def solid_size_estimate(volume: float, area: float, signorini_area: float, h: float) -> DomainSize:
    """The sizes of a gmsh tetrahedral mesh of size h of a body of ``volume`` bounded by a
    surface of ``area`` (``signorini_area`` of it on Gamma_s), in O(1) memory: dofs about
    GMSH_NODES_PER_VOLUME V / h^3 + GMSH_NODES_PER_AREA A / h^2, boundary dofs
    GMSH_NODES_PER_AREA A / h^2, Signorini dofs GMSH_NODES_PER_AREA A_s / h^2 (0.83-0.94
    of the ball's mesh's dofs at h = r/5 .. r/28, measured: an underestimate, so that no
    run that fits is refused)."""
    surface = GMSH_NODES_PER_AREA / h**2
    return DomainSize(
        dofs=int(GMSH_NODES_PER_VOLUME * volume / h**3 + surface * area),
        boundary_dofs=int(surface * area),
        signorini_dofs=int(surface * signorini_area),
        subdomains=0,
        h_min=h,
        h_max=h,
        dim=3,
    )


def _ball_size_estimate(spec: GeometrySpec) -> DomainSize:
    """:func:`solid_size_estimate` of the ball (its faces ``bottom`` and ``top`` are the
    two hemispheres)."""
    r = float(spec.radius)
    area = 4.0 * math.pi * r**2
    names = _names(spec.signorini)
    share = 1.0 if "all" in names else len(set(names) & {"bottom", "top"}) / 2
    return solid_size_estimate(4.0 / 3.0 * math.pi * r**3, area, share * area, float(spec.h))


def _names(signorini) -> list[str]:
    """The Signorini entries of a 3D spec as a list of names."""
    items = [signorini] if isinstance(signorini, (str, int)) else list(signorini)
    return [str(item) for item in items]


def gmsh_model_size(h: float, signorini="all") -> DomainSize | None:
    """The sizes of the mesh of size h (``Mesh.MeshSizeMax``) that ``gmsh.model.mesh.generate``
    would make of the current gmsh model, estimated before meshing from the volumes and
    the areas of its OpenCASCADE entities (:func:`solid_size_estimate`; a planar model
    from its areas and its curves' lengths, as :func:`mesh_size_estimate`).

    Call it on the rank that builds the model, after ``occ.synchronize()`` and the
    physical groups: ``signorini`` names the physical groups of Gamma_s (names or numbers,
    as ``[geometry] signorini``), or ``"all"``. Returns None for a model of the built-in
    kernel (``gmsh.model.geo``), whose areas gmsh does not tell before meshing; pass the
    result to ``coupling.app.sizing.check_memory`` to refuse a mesh that cannot fit.
    """
    import gmsh

    dim = max((d for d, _ in gmsh.model.getEntities()), default=0)
    if dim not in (2, 3):
        return None
    try:
        sizes = [gmsh.model.occ.getMass(dim, tag) for _, tag in gmsh.model.getEntities(dim)]
        faces = {abs(t): gmsh.model.occ.getMass(dim - 1, abs(t)) for _, t in _boundary(gmsh, dim)}
    except Exception:  # noqa: BLE001 - gmsh raises a bare Exception: no OCC entity
        return None
    names = _names(signorini)
    if "all" in names:
        chosen = set(faces)
    else:
        groups = {
            key: tag
            for d, tag in gmsh.model.getPhysicalGroups(dim - 1)
            for key in (str(tag), gmsh.model.getPhysicalName(d, tag))
        }
        chosen = {
            entity
            for name in names
            if name in groups
            for entity in gmsh.model.getEntitiesForPhysicalGroup(dim - 1, groups[name])
        }
    volume, area = float(sum(sizes)), float(sum(faces.values()))
    contact = float(sum(faces.get(tag, 0.0) for tag in chosen))
    if dim == 3:
        return solid_size_estimate(volume, area, contact, h)
    return DomainSize(
        dofs=int(GMSH_NODES_PER_AREA * volume / h**2 + area / (2 * h)),
        boundary_dofs=int(area / h),
        signorini_dofs=int(contact / h),
        subdomains=1,
        h_min=h,
        h_max=h,
    )


def _boundary(gmsh, dim: int) -> list[tuple[int, int]]:
    """The (dim - 1)-entities on the boundary of the model's dim-entities."""
    entities = gmsh.model.getEntities(dim)
    return gmsh.model.getBoundary(entities, combined=True, oriented=False)
