"""Meshes of Omega with a coarse subdomain partition (METHOD.md sections 1, 4 and 6).

``build_domain`` makes a polygon Omega (square, L-shape or a given polygon), a coarse
partition of Omega into L subdomains of size about d (coarse squares for the square and
the L-shape, coarse triangles of a gmsh mesh of size d for a polygon), and a fine P1
mesh of size h that resolves every coarse edge (every fine cell carries its subdomain).

``structured=True`` refines every coarse cell uniformly instead: n = max(2, round(d/h))
segments per coarse edge; a coarse square becomes an n x n grid of squares split into
right triangles along the (i,j)-(i+1,j+1) diagonal, a coarse triangle becomes n^2
similar triangles. These nodes and triangles are written down directly (no gmsh), so
that h-studies at fixed d/h are exact.

Tags
----
- cell tags: subdomain id 0 .. L-1 (``Domain.cell_tags``, dim 2);
- facet tags (dim 1, exterior facets): 1 on Gamma_t, 100 + k on the k-th Signorini arc.

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
so every coarse boundary edge lies in Gamma_t or in one arc (METHOD.md section 6).

Modules
-------
``fem_py.shapes`` (Omega's polygon, Gamma by arc length, the arcs and tags),
``fem_py.gmsh_mesh`` (gmsh, on rank 0), ``fem_py.structured`` (the uniform refinement),
``fem_py.distribute`` (whole subdomains per rank), ``fem_py.coarse`` (the coarse
structure recovered from the distributed mesh); this module joins them. Users' meshes,
the disk, ellipse, polygons with sides < d (resampled at h, or at d when structured, corners and
arc ends kept: ``fem_py.polyline.coarsened_polygon``) go through ``fem_py.own_mesh``.

Parallel use: all ranks call ``build_domain`` with the same arguments. Arguments are
validated identically on every rank before any collective call. Whole subdomains are
given to each rank (:func:`fem_py.distribute.subdomain_owners`, passed to
``create_mesh`` as its partitioner). A structured mesh is written down in parallel
(:func:`fem_py.distribute.distribute_structured`). Otherwise gmsh runs on rank 0 only
(an error there is raised on every rank as ``RuntimeError("meshing the domain failed:
...")``), and the mesh is distributed the way ``gmshio.model_to_mesh`` does it
(:func:`fem_py.distribute.distribute_mesh`), reading the gmsh arrays per surface
instead of through ``model_to_mesh``'s per-physical-group queries (measurements:
docs/design/fem_py.md). ``build_domain`` initialises and finalises gmsh itself (do not
call it inside a gmsh session of your own).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from mpi4py import MPI

from fem_py.coarse import SIGNORINI_TAG0, CoarseStructure, compute_coarse_structure
from fem_py.conic import CONICS, conic_domain, conic_plan
from fem_py.distribute import distribute_mesh, distribute_structured, subdomain_owners
from fem_py.gmsh_mesh import mesh_with_gmsh
from fem_py.parallel import broadcast_from_root, run_on_root
from fem_py.polyline import CORNER_ANGLE, coarsened_polygon, segment_lengths
from fem_py.shapes import (
    GAMMA_T_TAG,
    SHAPES,
    Arc,
    BoundaryCurve,
    check_polygon,
    checked_center,
    diameter,
    edge_tag,
    grid_cells_per_side,
    grid_counts,
    grid_outline,
    grid_partition,
    insert_boundary_points,
    parse_arcs,
)
from fem_py.structured import node_count, refine

__all__ = [
    "Arc",
    "CoarseStructure",
    "Domain",
    "DomainSize",
    "build_domain",
    "domain_size",
    "domain_from_file",
    "domain_from_mesh",
    "domain_from_prepared",
    "compute_coarse_structure",
    "GAMMA_T_TAG",
    "SIGNORINI_TAG0",
    "SHAPES",
    "subdomain_owners",
]


@dataclass(frozen=True, eq=False)
class Domain:
    """A meshed Omega with its coarse partition (see the module docstring).

    Attributes
    ----------
    mesh, cell_tags, facet_tags
        DOLFINx mesh; subdomain id of each cell (dim 2); 1 / 100+k on exterior facets.
    coarse : CoarseStructure
    arcs : tuple of Arc
    h, subdomain_size
        The requested fine and coarse sizes.
    shape : str
    vertices : (m, 2) float
        Polygon vertices of Omega, counter-clockwise (the first one is a corner).
    signorini_is_whole_boundary : bool
    structured : bool
    coarse_size : float
        Actual coarse size (coarse square side, or mean coarse edge length for a polygon).
    h_max : float
        Longest fine facet.
    partition : "grid" (a generated coarse grid) or "cells" (groups of a mesh's cells)
    """

    mesh: Any
    cell_tags: Any
    facet_tags: Any
    coarse: CoarseStructure
    arcs: tuple
    h: float
    subdomain_size: float
    shape: str
    vertices: np.ndarray
    signorini_is_whole_boundary: bool
    structured: bool
    coarse_size: float
    h_max: float
    partition: str = "grid"

    @property
    def comm(self) -> Any:
        return self.mesh.comm

    @property
    def diameter(self) -> float:
        return diameter(self.vertices)


def _is_positive_number(val: Any) -> bool:
    return (
        not isinstance(val, bool)
        and isinstance(val, (int, float, np.floating, np.integer))
        and math.isfinite(val)
        and val > 0
    )


def _validate(shape, h, subdomain_size, center, width, vertices):
    """Scalar and polygon checks (identical on every rank, no communication)."""
    if shape not in SHAPES:
        raise ValueError(f"shape must be one of {SHAPES}, got {shape!r}")
    for name, val in (("h", h), ("subdomain_size", subdomain_size)):
        if not _is_positive_number(val):
            raise ValueError(f"{name} must be a positive number, got {val!r}")
    h, d = float(h), float(subdomain_size)
    if d < 2 * h:
        raise ValueError(
            f"subdomain_size d={d:g} is smaller than 2h={2 * h:g}; increase "
            "subdomain_size or decrease h"
        )
    if shape == "polygon":
        if vertices is None:
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
        if vertices is not None:
            raise ValueError(
                f"vertices are only used by shape 'polygon'; drop them for shape {shape!r}"
            )
        cx, cy = checked_center(center)
        if not _is_positive_number(width):
            raise ValueError(f"width must be a positive number, got {width!r}")
        P = None
    return h, d, P, (cx, cy)


@dataclass(frozen=True, eq=False)
class _Plan:
    """What ``build_domain`` knows before any mesh exists: the validated sizes, Omega's
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


def _plan(
    shape, h, subdomain_size, center, width, vertices, signorini, structured, allow_large, grid=True
) -> _Plan:
    """Validate the arguments of :func:`build_domain` and lay out its coarse grid
    (identically on every rank, before any collective call); ``grid=False``: the same
    checks without the coarse cells of the square and L-shape (O(1) memory, for sizes)."""
    h, d, P, (cx, cy) = _validate(shape, h, subdomain_size, center, width, vertices)
    cV = ccells = csize = None
    if shape != "polygon":
        nc = grid_cells_per_side(shape, float(width), d)
        csize = float(width) / nc
        if grid:
            P, cV, ccells, csize = grid_partition(shape, (cx, cy), float(width), d)
        else:
            P = grid_outline(shape, (cx, cy), float(width), nc)
    diam = diameter(P)
    if diam >= 1.0 and not allow_large:
        raise ValueError(
            f"diam(Omega) = {diam:.4g} >= 1: the single-layer operator may not be "
            "elliptic (METHOD.md section 2); shrink the domain, or opt out with "
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
            corner = np.array([cx - float(width) / 2, cy - float(width) / 2])
            for q in ends:  # the nearest grid point, in closed form
                off = (q - corner) / csize
                if np.linalg.norm((off - np.round(off)) * csize) > B.tol:
                    raise ValueError(
                        f"signorini: arc end ({q[0]:g}, {q[1]:g}) is not a coarse "
                        "grid vertex, which structured=True requires; move it to a "
                        f"multiple of the coarse size {csize:g} or use "
                        "structured=False"
                    )
        elif grid:
            cV, ccells = insert_boundary_points(cV, ccells, ends, B.tol)
    return _Plan(h, d, P, B, arcs, whole, ends, cV, ccells, csize)


@dataclass(frozen=True)
class DomainSize:
    """The sizes of a domain (and of its P1 problem) as ``build_domain`` will make it.

    Attributes
    ----------
    dofs, boundary_dofs, signorini_dofs
        P1 nodes in Omega, on Gamma, and carrying a phi unknown.
    subdomains
        Coarse cells L.
    h_min, h_max
        The shortest and the longest fine facet.
    """

    dofs: int
    boundary_dofs: int
    signorini_dofs: int
    subdomains: int
    h_min: float
    h_max: float


def domain_size(
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
) -> DomainSize | None:
    """The sizes of ``build_domain(comm, shape, ...)`` (same arguments) in closed form,
    without a mesh and in O(1) memory (no coarse grid either): for the structured square
    and L-shape; None where only meshing tells (gmsh meshes: see
    :func:`fem_py.mesh_size.mesh_size_estimate`). Raises the errors ``build_domain``
    raises for the arguments.

    The fine nodes number ``fem_py.structured.node_count`` for n = max(2, round(c/h))
    segments per coarse edge (c the coarse size); every coarse boundary
    edge carries n fine facets; an open arc over k coarse edges has n k - 1 interior
    nodes, a closed one (``"all"``) every boundary node. The facets of the right
    triangles are c/n (legs) and sqrt(2) c/n (diagonals), c the coarse size.
    """
    if shape in CONICS:
        conic_plan(shape, h, subdomain_size, center, radius, semi_axes, signorini, allow_large)
        return None
    plan = _plan(
        shape,
        h,
        subdomain_size,
        center,
        width,
        vertices,
        signorini,
        structured,
        allow_large,
        grid=False,
    )
    if shape == "polygon" or not structured:
        return None
    n = max(2, int(round(plan.csize / plan.h)))
    n_vertices, n_edges, n_cells, n_boundary = grid_counts(shape, round(width / plan.csize))
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


def build_domain(
    comm: Any,
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
) -> Domain:
    """Mesh Omega with a coarse partition into subdomains of size about ``subdomain_size``.

    Parameters
    ----------
    comm
        MPI communicator (all its ranks call with the same arguments).
    shape
        ``"square"`` (``center``, ``width``), ``"lshape"`` (``center``, ``width``: the square
        of that width minus its upper-right quarter), ``"polygon"`` (``vertices``, CCW) or
        ``"disk"`` / ``"ellipse"`` (``center``, ``radius`` / ``semi_axes`` (a, b): gmsh, size
        h, automatic subdomains ``fem_py.partition``, arcs as point pairs on the curve).
    h
        Fine mesh size (structured: h = coarse edge / round(d/h)).
    subdomain_size
        Coarse size d >= 2h.
    signorini
        Signorini arcs (module docstring); () for none.
    structured
        Uniform refinement of the coarse cells instead of an unstructured gmsh mesh.
    allow_large
        Allow diam(Omega) >= 1 (then V is not guaranteed elliptic, METHOD.md section 2).

    Returns
    -------
    Domain

    Raises
    ------
    ValueError
        Invalid parameters (raised identically on every rank before any collective).
    RuntimeError
        gmsh failed on rank 0 (``"meshing the domain failed: <type>: <message>"``, on
        every rank).
    """
    if shape in CONICS:
        args = (center, radius, semi_axes, signorini, allow_large)
        return conic_domain(comm, shape, h, subdomain_size, *args)
    plan = _plan(
        shape, h, subdomain_size, center, width, vertices, signorini, structured, allow_large
    )
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
    if structured:  # every rank writes down its own part of the refinement
        n = max(2, int(round((d if shape == "polygon" else csize) / h)))
        msh, ct0, ft = distribute_structured(
            comm, refine(cV, ccells, n), lambda a, b: edge_tag(cV, a, b, B, arcs)
        )
    else:
        msh, ct0, ft = distribute_mesh(comm, arrays)
    coarse = compute_coarse_structure(msh, ct0, ft)
    h_max = _max_facet_length(msh)
    return Domain(
        mesh=msh,
        cell_tags=ct0,
        facet_tags=ft,
        coarse=coarse,
        arcs=arcs,
        h=h,
        subdomain_size=d,
        shape=shape,
        vertices=P.copy(),
        signorini_is_whole_boundary=whole,
        structured=bool(structured),
        coarse_size=float(csize),
        h_max=h_max,
    )


def domain_from_file(
    comm: Any,
    path: str,
    *,
    subdomain_size: float,
    signorini: Any = (),
    subdomains: str = "auto",
    allow_large: bool = False,
) -> Domain:
    """The :class:`Domain` of a gmsh mesh file (MSH 2.2 or 4.1, 2D linear triangles).

    Rank 0 reads and checks the file (``fem_py.own_mesh``) and partitions it (``subdomains
    = "auto"``: subdomains of size about ``subdomain_size``; ``"physical"``: the
    physical surface groups); the mesh is then distributed by whole subdomains.
    ``signorini`` names physical curve groups (or ``"all"``). Collective; a bad file or
    argument raises the same one-line ``ValueError`` on every rank before the mesh is
    distributed.
    """
    from fem_py.own_mesh import prepare_mesh, read_msh

    d = _check_size(subdomain_size)
    return domain_from_prepared(
        comm,
        lambda: prepare_mesh(
            read_msh(path),
            signorini=signorini,
            subdomain_size=d,
            subdomains=subdomains,
            allow_large=allow_large,
        ),
        d,
        "mesh",
    )


def domain_from_mesh(
    mesh: Any,
    facet_tags: Any,
    signorini: Any = (),
    subdomain_size: float | None = None,
    cell_tags: Any = None,
    names: dict[str, int] | None = None,
    allow_large: bool = False,
) -> Domain:
    """The :class:`Domain` of a DOLFINx triangle mesh (collective, on ``mesh.comm``).

    ``facet_tags`` mark boundary parts; ``signorini`` lists the tags (or names, through
    ``names``: name -> tag) of Gamma_s, or ``"all"``. Subdomains: ``cell_tags`` (one
    subdomain per tag value) when given, else the automatic partition of size
    ``subdomain_size``. The mesh is gathered on rank 0 and distributed anew by whole
    subdomains, so the returned ``Domain.mesh`` is a new mesh.
    """
    from fem_py.own_mesh import gather_mesh, prepare_mesh

    if subdomain_size is None and cell_tags is None:
        raise ValueError("subdomain_size: give subdomain_size (or cell_tags as subdomains)")
    d = _check_size(subdomain_size) if subdomain_size is not None else 1.0
    gathered = gather_mesh(mesh, facet_tags, cell_tags, names)
    comm = mesh.comm
    return domain_from_prepared(
        comm,
        lambda: prepare_mesh(
            gathered,
            signorini=[str(s) for s in signorini] if not isinstance(signorini, str) else signorini,
            subdomain_size=d,
            subdomains="auto" if cell_tags is None else "physical",
            allow_large=allow_large,
        ),
        d,
        "mesh",
    )


def _fine_polygon_domain(comm: Any, plan: _Plan) -> Domain:
    """A polygon with sides shorter than d/2 (a finely drawn curve): meshed at size h
    and split by the automatic partition (``fem_py.partition``), so that its subdomains
    have size d whatever the vertex spacing (coarse triangles of a gmsh mesh of size d
    would follow the vertex spacing instead)."""
    from fem_py.own_mesh import polygon_mesh, prepare_mesh

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


def _check_size(d: Any) -> float:
    if not _is_positive_number(d):
        raise ValueError(f"subdomain_size must be a positive number, got {d!r}")
    return float(d)


def domain_from_prepared(comm: Any, prepare: Any, d: float, shape: str) -> Domain:
    """``prepare()`` (a ``fem_py.own_mesh.PreparedMesh``) on rank 0, its errors raised on
    every rank; the mesh distributed by whole subdomains, its coarse edges curved."""
    prepared = run_on_root(comm, prepare)
    meta = broadcast_from_root(
        comm, lambda: (prepared.polygon, prepared.arcs, prepared.whole, prepared.subdomain_size)
    )
    polygon, arcs, whole, d = meta
    msh, ct0, ft = distribute_mesh(comm, prepared.arrays if comm.rank == 0 else None)
    coarse = compute_coarse_structure(msh, ct0, ft, corner_angle=CORNER_ANGLE)
    h_max = _max_facet_length(msh)
    return Domain(
        mesh=msh,
        cell_tags=ct0,
        facet_tags=ft,
        coarse=coarse,
        arcs=arcs,
        h=h_max,
        subdomain_size=d,
        shape=shape,
        vertices=np.asarray(polygon, dtype=float),
        signorini_is_whole_boundary=bool(whole),
        structured=False,
        coarse_size=d,
        h_max=h_max,
        partition="cells",
    )


def _max_facet_length(msh: Any) -> float:
    """The longest fine facet: the longest side of the local triangles, maximised over ranks."""
    x = msh.geometry.x[:, :2]
    corners = msh.geometry.dofmap.array.reshape(-1, 3)
    # take: faster than x[...] for (n, 2) rows (measurements: docs/design/fem_py.md)
    p = [x.take(corners[:, k], axis=0) for k in range(3)]
    loc = max(
        float(np.einsum("ij,ij->i", d, d).max(initial=0.0))
        for d in (p[1] - p[0], p[2] - p[1], p[0] - p[2])
    )
    return math.sqrt(msh.comm.allreduce(loc, op=MPI.MAX))
