"""The builders of a :class:`fem_py.mesh.domain.Domain` from a
:class:`fem_py.spec.GeometrySpec`: :func:`build_domain` (collective) and
:func:`domain_size` (its sizes in closed form, without a mesh).

The one dispatch on the spec: by Omega's dimension (:func:`spec_dimension`: ``spec.dim``,
or for a mesh file the file's own, read on rank 0), then by its source. In 2D: a mesh
file (``fem_py.mesh.domain.domain_from_file``), the disk or the ellipse
(``fem_py.mesh.conic``), the square, the L-shape or a polygon (``fem_py.mesh.polygon``);
in 3D the box, the ball or a file of tetrahedra (``fem_py.mesh.solid``, a
:class:`fem_py.mesh.solid.SolidDomain`).
"""
from __future__ import annotations

from typing import Any, Callable

from fem_py.mesh.conic import CONICS, conic_domain, conic_plan
from fem_py.mesh.domain import Domain, DomainSize, domain_from_file
from fem_py.mesh.polygon import polygon_domain, polygon_size
from fem_py.mesh.solid import SolidDomain, solid_domain, solid_size
from fem_py.mesh.tet_file import msh_dimension
from fem_py.parallel import broadcast_from_root
from fem_py.spec import GeometrySpec

__all__ = ["build_domain", "domain_size", "spec_dimension"]


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
    3: (solid_domain, solid_size),
}


def spec_dimension(spec: GeometrySpec, comm: Any = None) -> int:
    """Omega's dimension: ``spec.dim``, or for a mesh file with ``dim = 0`` the file's
    (``fem_py.mesh.tet_file.msh_dimension``: read on rank 0 of ``comm`` and broadcast,
    or here without ``comm``). A missing or unreadable file raises its one-line
    ``mesh: ...`` error (on every rank)."""
    if spec.dim:
        return spec.dim
    if comm is None:
        return msh_dimension(spec.mesh)
    return broadcast_from_root(comm, lambda: msh_dimension(spec.mesh))


def build_domain(comm: Any, spec: GeometrySpec) -> Domain | SolidDomain:
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
    Domain or SolidDomain
        The planar domain with its coarse partition, or the body in R^3.

    Raises
    ------
    ValueError
        Invalid spec, the message starting with the field at fault (raised identically on
        every rank before any collective call).
    RuntimeError
        gmsh failed on rank 0 (``"meshing the domain failed: <type>: <message>"``, on
        every rank).
    """
    return _BUILDERS[spec_dimension(spec, comm)][0](comm, spec)


def domain_size(spec: GeometrySpec) -> DomainSize | None:
    """The sizes of ``build_domain(comm, spec)`` in closed form, without a mesh: for the
    structured square and L-shape (``fem_py.mesh.polygon.polygon_size``) and the box
    (``fem_py.mesh.solid.solid_size``); None where only meshing tells (gmsh meshes, mesh
    files). Raises the errors ``build_domain`` raises for ``spec`` before it meshes."""
    if spec.mesh:  # only reading the file tells
        return None
    return _BUILDERS[spec.dim][1](spec)
