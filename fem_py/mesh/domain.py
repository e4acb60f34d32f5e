"""The :class:`Domain`: a distributed mesh of Omega with its coarse subdomain partition
(docs/method.md sections 1, 4 and 6), and the domains of a user's mesh.

Tags
----
- cell tags: subdomain id 0 .. L-1 (``Domain.cell_tags``, dim 2);
- facet tags (dim 1, exterior facets): ``fem_py.tags``: 1 on Gamma_t, 100 + k on the k-th
  Signorini arc.

:func:`domain_from_file` (a gmsh mesh file) and :func:`domain_from_mesh` (a DOLFINx mesh
and its tags) prepare the mesh on rank 0 (``fem_py.mesh.own_mesh``: checks, Signorini
tags, the automatic partition ``fem_py.partition.cells`` or the given subdomains);
:func:`domain_from_prepared` distributes such a prepared mesh by whole subdomains
(``fem_py.mesh.distribute``) and recovers its coarse structure
(``fem_py.partition.coarse``), its coarse edges curved (``CORNER_ANGLE``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from mpi4py import MPI

from fem_py.mesh.distribute import distribute_mesh
from fem_py.mesh.own_mesh import gather_mesh, prepare_mesh, read_msh
from fem_py.parallel import broadcast_from_root, run_on_root
from fem_py.partition.coarse import CoarseStructure, compute_coarse_structure
from fem_py.polyline import CORNER_ANGLE, diameter
from fem_py.spec import GeometrySpec

__all__ = [
    "CORNER_ANGLE",
    "Domain",
    "DomainSize",
    "check_size",
    "domain_from_file",
    "domain_from_mesh",
    "domain_from_prepared",
    "is_positive_number",
    "max_facet_length",
    "tagged_domain",
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
    lattice : fem_py.mesh.box.BoxLattice or None
        The structured square's vertex lattice (its nodes are lower + spacing (i, j),
        0 <= i, j <= n), for the geometric multigrid of the amg preconditioner; ``None``
        for every other domain (``fem_py.mesh.solid.SolidDomain.lattice``: the box's).
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
    lattice: Any = None

    #: Omega's dimension (``fem_py.mesh.solid.SolidDomain.dim`` is 3).
    dim = 2

    @property
    def comm(self) -> Any:
        return self.mesh.comm

    @property
    def diameter(self) -> float:
        return diameter(self.vertices)


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
    dim
        2 (a planar domain) or 3 (a body).
    components
        Unknowns per node: 1 (the P1 counts above); d once the counts are those of the
        elastic equation (``coupling.app.sizing.equation_size``: dofs and boundary_dofs d
        per node).
    """

    dofs: int
    boundary_dofs: int
    signorini_dofs: int
    subdomains: int
    h_min: float
    h_max: float
    dim: int = 2
    components: int = 1


def is_positive_number(val: Any) -> bool:
    return (
        not isinstance(val, bool)
        and isinstance(val, (int, float, np.floating, np.integer))
        and math.isfinite(val)
        and val > 0
    )


def check_size(d: Any) -> float:
    if not is_positive_number(d):
        raise ValueError(f"subdomain_size must be a positive number, got {d!r}")
    return float(d)


def domain_from_file(comm: Any, spec: GeometrySpec) -> Domain:
    """The :class:`Domain` of the gmsh mesh file ``spec.mesh`` (MSH 2.2 or 4.1, 2D linear
    triangles; ``build_domain`` of a spec with ``mesh``).

    Rank 0 reads and checks the file (``fem_py.mesh.own_mesh``) and partitions it
    (``spec.subdomains = "auto"``: subdomains of size about ``spec.subdomain_size``;
    ``"physical"``: the physical surface groups); the mesh is then distributed by whole
    subdomains. ``spec.signorini`` names physical curve groups (or ``"all"``). Collective;
    a bad file or argument raises the same one-line ``ValueError`` on every rank before
    the mesh is distributed.
    """
    d = check_size(spec.subdomain_size)
    return domain_from_prepared(
        comm,
        lambda: prepare_mesh(
            read_msh(spec.mesh),
            signorini=spec.signorini,
            subdomain_size=d,
            subdomains=spec.subdomains,
            allow_large=spec.allow_large,
        ),
        d,
        "mesh",
    )


def domain_from_mesh(
    mesh: Any,
    facet_tags: Any,
    signorini: Any = GeometrySpec.signorini,
    subdomain_size: float | None = None,
    cell_tags: Any = None,
    names: dict[str, int] | None = None,
    allow_large: bool = GeometrySpec.allow_large,
) -> Domain:
    """The :class:`Domain` of a DOLFINx triangle mesh (collective, on ``mesh.comm``).

    ``facet_tags`` mark boundary parts; ``signorini`` lists the tags (or names, through
    ``names``: name -> tag) of Gamma_s, or ``"all"``. Subdomains: ``cell_tags`` (one
    subdomain per tag value) when given, else the automatic partition of size
    ``subdomain_size``. The mesh is gathered on rank 0 and distributed anew by whole
    subdomains, so the returned ``Domain.mesh`` is a new mesh.
    """
    if subdomain_size is None and cell_tags is None:
        raise ValueError("subdomain_size: give subdomain_size (or cell_tags as subdomains)")
    d = check_size(subdomain_size) if subdomain_size is not None else 1.0
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


def domain_from_prepared(comm: Any, prepare: Any, d: float, shape: str) -> Domain:
    """``prepare()`` (a ``fem_py.mesh.own_mesh.PreparedMesh``) on rank 0, its errors raised on
    every rank; the mesh distributed by whole subdomains, its coarse edges curved."""
    prepared = run_on_root(comm, prepare)
    meta = broadcast_from_root(
        comm, lambda: (prepared.polygon, prepared.arcs, prepared.whole, prepared.subdomain_size)
    )
    polygon, arcs, whole, d = meta
    msh, ct0, ft = distribute_mesh(comm, prepared.arrays if comm.rank == 0 else None)
    return tagged_domain(
        msh,
        ct0,
        ft,
        corner_angle=CORNER_ANGLE,
        arcs=arcs,
        subdomain_size=d,
        shape=shape,
        vertices=np.asarray(polygon, dtype=float),
        signorini_is_whole_boundary=bool(whole),
        structured=False,
        coarse_size=d,
        partition="cells",
    )


def tagged_domain(
    mesh: Any,
    cell_tags: Any,
    facet_tags: Any,
    corner_angle: float | None = None,
    coarse: CoarseStructure | None = None,
    h_max: float | None = None,
    **fields: Any,
) -> Domain:
    """The :class:`Domain` of a distributed mesh and its tags (collective): its coarse
    structure ``coarse``, or recovered from the mesh (``corner_angle``:
    ``compute_coarse_structure``), and its longest facet ``h_max``, or measured;
    ``fields``: the other fields of the domain (``h`` defaults to the longest facet)."""
    if coarse is None:
        coarse = compute_coarse_structure(mesh, cell_tags, facet_tags, corner_angle=corner_angle)
    if h_max is None:
        h_max = max_facet_length(mesh)
    return Domain(
        mesh=mesh,
        cell_tags=cell_tags,
        facet_tags=facet_tags,
        coarse=coarse,
        h_max=h_max,
        **{"h": h_max, **fields},
    )


def max_facet_length(msh: Any) -> float:
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
