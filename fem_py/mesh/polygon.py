"""The polygonal Omegas: the square, the L-shape and a given polygon (docs/method.md sections
1, 4 and 6), meshed with a coarse subdomain partition.

:func:`polygon_domain` makes a coarse partition of Omega into L subdomains of size about
d (coarse squares for the square and the L-shape, coarse triangles of a gmsh mesh of size
d for a polygon), and a fine P1 mesh of size h that resolves every coarse edge (every
fine cell carries its subdomain).

``structured=True`` refines every coarse cell uniformly instead: n = max(2, round(d/h))
segments per coarse edge; a coarse square becomes an n x n grid of squares split into
right triangles along the (i,j)-(i+1,j+1) diagonal, a coarse triangle becomes n^2
similar triangles. These nodes and triangles are written down directly (no gmsh), so
that h-studies at fixed d/h are exact.

Signorini arcs (``signorini``)
------------------------------
A sequence of arcs, each one of

- a pair of boundary points ``((x0, y0), (x1, y1))``: the part of Gamma from the first
  point to the second, going counter-clockwise (Omega on the left);
- a side name. Square: ``bottom, right, top, left``. L-shape, with the square
  [x0, x1] x [y0, y1] of width w centred at ``center`` and its upper-right quarter
  removed (vertices (x0,y0), (x1,y0), (x1,cy), (cx,cy), (cx,y1), (x0,y1), CCW):
  ``bottom`` (x0,y0)-(x1,y0), ``right`` (x1,y0)-(x1,cy), ``notch_bottom`` (x1,cy)-(cx,cy)
  and ``notch_left`` (cx,cy)-(cx,y1) (the bottom and left sides of the removed quarter),
  ``top`` (cx,y1)-(x0,y1), ``left`` (x0,y1)-(x0,y0). Polygon: ``side<i>`` from vertex i to
  vertex i+1 (any shape accepts ``side<i>``);
- ``"all"``: the whole boundary as one closed arc (alone).

Arc end points become coarse vertices (inserted into the coarse mesh when needed; with
``structured=True`` on the square or L-shape they must already be coarse grid vertices),
so every coarse boundary edge lies in Gamma_t or in one arc (docs/method.md section 6).

Modules
-------
``fem_py.mesh.shapes`` (Omega's polygon, Gamma by arc length, the arcs and tags),
``fem_py.mesh.gmsh_mesh`` (gmsh, on rank 0), ``fem_py.mesh.structured`` (the uniform
refinement), ``fem_py.mesh.distribute`` (whole subdomains per rank),
``fem_py.partition.coarse`` (the coarse structure recovered from the distributed mesh);
this module joins them. Polygons with sides < d (resampled at h, or at d when structured,
corners and arc ends kept: ``fem_py.polyline.coarsened_polygon``) go through
``fem_py.mesh.own_mesh`` like users' meshes.

Parallel use: all ranks call with the same spec, validated identically on every rank
before any collective call. Whole subdomains are given to each rank
(:func:`fem_py.mesh.distribute.subdomain_owners`, passed to ``create_mesh`` as its
partitioner). A structured mesh is written down in parallel
(:func:`fem_py.mesh.distribute.distribute_structured`). Otherwise gmsh runs on rank 0
only (an error there is raised on every rank as ``RuntimeError("meshing the domain
failed: ...")``), and the mesh is distributed the way ``gmshio.model_to_mesh`` does it
(:func:`fem_py.mesh.distribute.distribute_mesh`), reading the gmsh arrays per surface
instead of through ``model_to_mesh``'s per-physical-group queries (measurements:
docs/design/fem_py.md). gmsh is initialised and finalised here (do not build a domain
inside a gmsh session of your own).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fem_py.dofs import p1_space
from fem_py.mesh.box import BoxLattice
from fem_py.mesh.distribute import distribute_mesh, distribute_structured
from fem_py.mesh.domain import (
    CORNER_ANGLE,
    Domain,
    DomainSize,
    domain_from_prepared,
    is_positive_number,
    tagged_domain,
)
from fem_py.mesh.gmsh_mesh import mesh_with_gmsh
from fem_py.mesh.own_mesh import polygon_mesh, prepare_mesh
from fem_py.mesh.shapes import (
    SHAPES,
    BoundaryCurve,
    check_polygon,
    checked_center,
    edge_tag,
    grid_cells_per_side,
    grid_counts,
    grid_outline,
    grid_partition,
    insert_boundary_points,
    parse_arcs,
)
from fem_py.mesh.structured import node_count, refine
from fem_py.mesh.structured_coarse import structured_coarse_structure
from fem_py.parallel import broadcast_from_root, run_on_root
from fem_py.polyline import coarsened_polygon, diameter, segment_lengths
from fem_py.spec import GeometrySpec

__all__ = ["polygon_domain", "polygon_size"]


def _given(vertices: Any) -> bool:
    """Whether ``vertices`` were given (None and an empty sequence are not)."""
    if vertices is None:
        return False
    return not (isinstance(vertices, (list, tuple, np.ndarray)) and len(vertices) == 0)


def _validate(spec: GeometrySpec) -> tuple:
    """Scalar and polygon checks (identical on every rank, no communication)."""
    shape, h, subdomain_size, vertices = spec.shape, spec.h, spec.subdomain_size, spec.vertices
    if shape not in SHAPES:
        raise ValueError(f"shape must be one of {SHAPES}, got {shape!r}")
    for name, val in (("h", h), ("subdomain_size", subdomain_size)):
        if not is_positive_number(val):
            raise ValueError(f"{name} must be a positive number, got {val!r}")
    h, d = float(h), float(subdomain_size)
    if d < 2 * h:
        raise ValueError(
            f"subdomain_size d={d:g} is smaller than 2h={2 * h:g}; increase "
            "subdomain_size or decrease h"
        )
    if shape == "polygon":
        if not _given(vertices):
            raise ValueError(
                "shape 'polygon' needs vertices=[(x0, y0), (x1, y1), ...] (counter-clockwise)"
            )
        try:
            P = np.asarray(vertices, dtype=float)
        except (TypeError, ValueError):
            raise ValueError("vertices must be a list of (x, y) pairs") from None
        if P.ndim != 2 or P.shape[1] != 2:
            raise ValueError(f"vertices must be a list of (x, y) pairs, got shape {P.shape}")
        check_polygon(P)
        cx = cy = None
    else:
        if _given(vertices):
            raise ValueError(
                f"vertices are only used by shape 'polygon'; drop them for shape {shape!r}"
            )
        cx, cy = checked_center(spec.center)
        if not is_positive_number(spec.width):
            raise ValueError(f"width must be a positive number, got {spec.width!r}")
        P = None
    return h, d, P, (cx, cy)


@dataclass(frozen=True, eq=False)
class _Plan:
    """What :func:`polygon_domain` knows before any mesh exists: the validated sizes, Omega's
    polygon and boundary curve, the arcs, and (square, L-shape) the coarse grid."""

    h: float
    d: float
    P: np.ndarray
    B: BoundaryCurve
    arcs: tuple
    whole: bool
    ends: list
    cV: Any = None
    ccells: Any = None
    csize: float | None = None


def _plan(spec: GeometrySpec, grid: bool = True) -> _Plan:
    """Validate ``spec`` and lay out its coarse grid (identically on every rank, before any
    collective call); ``grid=False``: the same checks without the coarse cells of the
    square and L-shape (O(1) memory, for sizes)."""
    h, d, P, (cx, cy) = _validate(spec)
    shape, signorini, structured = spec.shape, spec.signorini, spec.structured
    cV = ccells = csize = None
    if shape != "polygon":
        nc = grid_cells_per_side(shape, float(spec.width), d)
        csize = float(spec.width) / nc
        if grid:
            P, cV, ccells, csize = grid_partition(shape, (cx, cy), float(spec.width), d)
        else:
            P = grid_outline(shape, (cx, cy), float(spec.width), nc)
    diam = diameter(P)
    if diam >= 1.0 and not spec.allow_large:
        raise ValueError(
            f"diam(Omega) = {diam:.4g} >= 1: the single-layer operator may not be "
            "elliptic (docs/method.md section 2); shrink the domain, or opt out with "
            "allow_large (geometry.allow_large = true) at your own risk"
        )
    B = BoundaryCurve(P)
    arcs, whole = parse_arcs(signorini, shape, B)
    ends = [] if whole else [np.asarray(p) for a in arcs for p in (a.start, a.end)]
    if shape == "polygon" and float(B.len.min()) < d:  # finely drawn: resampled at d or h
        P = coarsened_polygon(P, d if structured else h, ends, CORNER_ANGLE, B.tol)
        B = BoundaryCurve(P)
        arcs, whole = parse_arcs(signorini, shape, B)
    if shape != "polygon":
        if structured:
            corner = np.array([cx - float(spec.width) / 2, cy - float(spec.width) / 2])
            for q in ends:  # the nearest grid point, in closed form
                off = (q - corner) / csize
                if np.linalg.norm((off - np.round(off)) * csize) > B.tol:
                    raise ValueError(
                        f"signorini: arc end ({q[0]:g}, {q[1]:g}) is not a coarse "
                        "grid vertex, which structured=True requires; move it to a "
                        f"multiple of the coarse size {csize:g} or use "
                        "structured=False"
                    )
        elif grid:  # gmsh meshes the coarse loops; arc ends may lengthen them
            cV, ccells = insert_boundary_points(cV, ccells.tolist(), ends, B.tol)
    return _Plan(h, d, P, B, arcs, whole, ends, cV, ccells, csize)


def polygon_size(spec: GeometrySpec) -> DomainSize | None:
    """The sizes of ``polygon_domain(comm, spec)`` in closed form, without a mesh and in
    O(1) memory (no coarse grid either): for the structured square and L-shape; None where
    only meshing tells (gmsh meshes: see :func:`fem_py.mesh.size_estimate.mesh_size_estimate`).
    Raises the errors ``polygon_domain`` raises for ``spec``.

    The fine nodes number ``fem_py.mesh.structured.node_count`` for n = max(2, round(c/h))
    segments per coarse edge (c the coarse size); every coarse boundary
    edge carries n fine facets; an open arc over k coarse edges has n k - 1 interior
    nodes, a closed one (``"all"``) every boundary node. The facets of the right
    triangles are c/n (legs) and sqrt(2) c/n (diagonals), c the coarse size.
    """
    plan = _plan(spec, grid=False)
    if spec.shape == "polygon" or not spec.structured:
        return None
    n = max(2, int(round(plan.csize / plan.h)))
    n_vertices, n_edges, n_cells, n_boundary = grid_counts(
        spec.shape, round(float(spec.width) / plan.csize)
    )
    n_gamma = n * n_boundary
    if plan.whole:
        n_s = n_gamma
    else:  # arc ends are coarse vertices: an arc covers length / csize coarse edges
        n_s = sum(n * int(round(arc.length / plan.csize)) - 1 for arc in plan.arcs)
    leg = plan.csize / n
    return DomainSize(
        dofs=node_count(n_vertices, n_edges, n_cells, 4, n),
        boundary_dofs=n_gamma,
        signorini_dofs=n_s,
        subdomains=n_cells,
        h_min=leg,
        h_max=math.sqrt(2.0) * leg,
    )


def polygon_domain(comm: Any, spec: GeometrySpec) -> Domain:
    """Mesh the square, the L-shape or the polygon of ``spec`` with a coarse partition
    into subdomains of size about ``spec.subdomain_size`` (collective; see
    ``fem_py.mesh.build_domain``)."""
    plan = _plan(spec)
    shape, structured = spec.shape, spec.structured
    h, d, P, B = plan.h, plan.d, plan.P, plan.B
    arcs, whole, ends = plan.arcs, plan.whole, plan.ends
    cV, ccells, csize = plan.cV, plan.ccells, plan.csize
    if shape == "polygon" and float(B.len.min()) < (0.5 if structured else 1.0) * d:
        return _fine_polygon_domain(comm, plan)

    # gmsh runs on rank 0 (the polygon's coarse mesh, the unstructured fine mesh)
    arrays = None
    if shape == "polygon" or not structured:
        given = None if shape == "polygon" else (cV, ccells)
        meshed = run_on_root(
            comm,
            lambda: mesh_with_gmsh(B, given, ends, d, h, arcs, fine=not structured),
            error_prefix="meshing the domain failed",
        )
        if shape == "polygon":
            cV, ccells = broadcast_from_root(comm, lambda: meshed[:2])
            loops = [c + c[:1] for c in ccells]
            csize = float(np.mean(np.concatenate([segment_lengths(cV[c]) for c in loops])))
        if meshed is not None:
            arrays = meshed[2]
    coarse = h_max = lattice = None
    if structured:  # every rank writes down its own part of the refinement
        n = max(2, int(round((d if shape == "polygon" else csize) / h)))
        if shape != "polygon":  # the diagonal of the grid's right triangles (polygon_size)
            h_max = math.sqrt(2.0) * csize / n
        if shape == "square":  # its nodes: a lattice of nc n cells per side
            cells = int(round(float(spec.width) / csize)) * n
            lattice = BoxLattice(P.min(axis=0), csize / n, cells)  # P[0]: lower left
        ref = refine(cV, ccells, n)
        tags = ref.edge_tags(lambda a, b: edge_tag(cV, a, b, B, arcs))
        msh, ct0, ft = distribute_structured(comm, ref, tags)
        # the coarse structure as the generator knows it, not recovered from the mesh
        coarse = structured_coarse_structure(p1_space(msh), ref, tags)
    else:
        msh, ct0, ft = distribute_mesh(comm, arrays)
    return tagged_domain(
        msh,
        ct0,
        ft,
        coarse=coarse,
        h_max=h_max,
        arcs=arcs,
        h=h,
        subdomain_size=d,
        shape=shape,
        vertices=P.copy(),
        signorini_is_whole_boundary=whole,
        structured=bool(structured),
        coarse_size=float(csize),
        lattice=lattice,
    )


def _fine_polygon_domain(comm: Any, plan: _Plan) -> Domain:
    """A polygon with sides shorter than d/2 (a finely drawn curve): meshed at size h
    and split by the automatic partition (``fem_py.partition.cells``), so that its subdomains
    have size d whatever the vertex spacing (coarse triangles of a gmsh mesh of size d
    would follow the vertex spacing instead)."""
    names = "all" if plan.whole else [f"arc{k}" for k in range(len(plan.arcs))]
    domain = domain_from_prepared(
        comm,
        lambda: prepare_mesh(
            polygon_mesh(plan.B, plan.ends, plan.h, plan.arcs),
            signorini=names,
            subdomain_size=plan.d,
            allow_large=True,
        ),
        plan.d,
        "polygon",
    )
    return dataclasses.replace(domain, h=plan.h)
