"""The builders of a :class:`fem_py.mesh.domain.Domain` from a
:class:`fem_py.spec.GeometrySpec`: :func:`build_domain` (collective) and
:func:`domain_size` (its sizes in closed form, without a mesh).

The one dispatch on the spec: by Omega's dimension (``spec.dim``; the planar builders are
the only ones so far: a three-dimensional Omega, its tetrahedral shapes and surface
triangulations, gets its own entry of ``_BUILDERS``), then by its source: a mesh file
(``fem_py.mesh.domain.domain_from_file``), the disk or the ellipse
(``fem_py.mesh.conic``), the square, the L-shape or a polygon (``fem_py.mesh.polygon``).
"""
from __future__ import annotations

from typing import Any, Callable

from fem_py.mesh.conic import CONICS, conic_domain, conic_plan
from fem_py.mesh.domain import Domain, DomainSize, domain_from_file
from fem_py.mesh.polygon import polygon_domain, polygon_size
from fem_py.spec import GeometrySpec

__all__ = ["build_domain", "domain_size"]


def _planar_domain(comm: Any, spec: GeometrySpec) -> Domain:
    if spec.mesh:
        return domain_from_file(comm, spec)
    if spec.shape in CONICS:
        return conic_domain(comm, spec)
    return polygon_domain(comm, spec)


def _planar_size(spec: GeometrySpec) -> DomainSize | None:
    if spec.mesh:  # only reading the file tells
        return None
    if spec.shape in CONICS:
        conic_plan(spec)  # the checks of conic_domain
        return None
    return polygon_size(spec)


#: Omega's dimension -> (the builder of its domain, the closed-form sizes).
_BUILDERS: dict[int, tuple[Callable[..., Domain], Callable[..., DomainSize | None]]] = {
    2: (_planar_domain, _planar_size),
}


def build_domain(comm: Any, spec: GeometrySpec) -> Domain:
    """Mesh Omega with a coarse partition into subdomains of size about
    ``spec.subdomain_size`` (docs/method.md sections 1, 4 and 6).

    Parameters
    ----------
    comm
        MPI communicator (all its ranks call with the same spec).
    spec
        Omega, its mesh sizes, its Signorini arcs (:class:`fem_py.spec.GeometrySpec`).

    Returns
    -------
    Domain

    Raises
    ------
    ValueError
        Invalid spec, the message starting with the field at fault (raised identically on
        every rank before any collective call).
    RuntimeError
        gmsh failed on rank 0 (``"meshing the domain failed: <type>: <message>"``, on
        every rank).
    """
    return _BUILDERS[spec.dim][0](comm, spec)


def domain_size(spec: GeometrySpec) -> DomainSize | None:
    """The sizes of ``build_domain(comm, spec)`` in closed form, without a mesh: for the
    structured square and L-shape (``fem_py.mesh.polygon.polygon_size``); None where only
    meshing tells (gmsh meshes, mesh files). Raises the errors ``build_domain`` raises
    for ``spec`` before it meshes."""
    return _BUILDERS[spec.dim][1](spec)
