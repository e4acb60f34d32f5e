"""The 3D :class:`SolidDomain` of a :class:`fem_py.spec.GeometrySpec` (docs/method.md section 11):
a distributed tetrahedral mesh of Omega with its named facet tags and the facet tags of
the Signorini patches, built from the structured box (``fem_py.mesh.box``), the gmsh
ball (``fem_py.mesh.ball``) or a gmsh file of linear tetrahedra (``fem_py.mesh.tet_file``,
checked on rank 0 and distributed by ``fem_py.mesh.tet_distribute``).

A body in R^3 has no coarse partition (the 2D substructuring of docs/method.md section 6 is
not used there), so a ``SolidDomain`` has no ``coarse``, ``arcs`` or ``vertices``: the
boundary map is ``fem_py.boundary.surface.SurfaceMap(V, facet_tags, signorini)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from mpi4py import MPI

from fem_py.mesh.args3d import signorini_tags
from fem_py.mesh.ball import BALL_FACES, ball_mesh, check_ball
from fem_py.mesh.box import BOX_FACES, BoxLattice, box_counts, box_mesh, check_box, cubes_per_side
from fem_py.mesh.domain import DomainSize
from fem_py.mesh.tet_distribute import solid_mesh
from fem_py.mesh.tet_file import check_solid, read_tet_msh
from fem_py.parallel import run_on_root
from fem_py.spec import GeometrySpec

__all__ = ["SolidDomain", "box_size", "edge_range", "solid_domain", "solid_size"]


@dataclass(frozen=True, eq=False)
class SolidDomain:
    """A meshed body Omega in R^3 (see the module docstring).

    Attributes
    ----------
    mesh, facet_tags
        DOLFINx tetrahedral mesh; tags of its boundary triangles (dim 2), ``names[k]``
        on face or group ``k``.
    names : dict
        Face or group name -> facet tag.
    signorini : tuple of int or "all"
        The facet tags of Gamma_s (``()``: no Signorini part), the argument of
        ``SurfaceMap``.
    shape : str
        ``"box"``, ``"ball"`` or ``"mesh"`` (a file).
    h
        The requested mesh size (the longest edge for a file).
    h_min, h_max
        The shortest and the longest edge of the mesh.
    lattice : BoxLattice or None
        The box's vertex lattice (``None`` for other shapes).
    node_order : str
        The order of the boundary nodes (``SurfaceMap``'s ``order``): ``"input"`` (input
        node numbers), ``"coordinates"`` after a local refinement, whose new nodes'
        numbers depend on the partition (``fem_py.mesh.refinement``).
    """

    mesh: Any
    facet_tags: Any
    names: dict
    signorini: Any
    shape: str
    h: float
    h_min: float
    h_max: float
    lattice: BoxLattice | None = None
    node_order: str = "input"

    #: Omega's dimension (``Domain.dim`` is 2).
    dim = 3

    @property
    def comm(self) -> Any:
        return self.mesh.comm

    @property
    def signorini_is_whole_boundary(self) -> bool:
        return self.signorini == "all"


def solid_domain(comm: Any, spec: GeometrySpec) -> SolidDomain:
    """The :class:`SolidDomain` of a 3D spec (collective; ``fem_py.mesh.build_domain``).

    Raises
    ------
    ValueError
        One line starting with the field at fault, identically on every rank before any
        collective call (``center``, ``width``, ``radius``, ``h``, ``signorini``,
        ``mesh: ...`` for a bad file).
    """
    if spec.mesh:
        solid = run_on_root(comm, lambda: _checked_file(spec))
        # the Signorini groups first (they must not overlap), then every other surface
        # group that overlaps none of those before it (solution.xdmf names them all)
        groups = [] if spec.signorini == "all" else [str(s) for s in _items(spec.signorini)]
        msh, facet_tags, names = solid_mesh(comm, solid, groups, others=True)
        shape, h, lattice = "mesh", 0.0, None
    elif spec.shape == "box":
        c, width, h = check_box(spec.center, spec.width, spec.h)
        _check_faces(spec.signorini, _BOX_TAGS)  # before meshing
        msh, facet_tags, names = box_mesh(comm, c, width, h)
        shape = "box"
        n = cubes_per_side(width, h)
        lattice = BoxLattice(c - width / 2, width / n, n)
    else:
        c, radius, h = check_ball(spec.center, spec.radius, spec.h)
        _check_faces(spec.signorini, BALL_FACES)
        msh, facet_tags, names = ball_mesh(comm, c, radius, h)
        shape, lattice = "ball", None
    tags = signorini_tags(spec.signorini, names) if _items(spec.signorini) else ()
    h_min, h_max = edge_range(msh)
    return SolidDomain(msh, facet_tags, names, tags, shape, h or h_max, h_min, h_max, lattice)


#: The facet tags ``box_mesh`` gives the faces (their position in BOX_FACES plus one).
_BOX_TAGS = {name: tag for tag, name in enumerate(BOX_FACES, start=1)}


def _check_faces(signorini: Any, names: dict) -> None:
    """The Signorini names are faces of the shape (one-line ``signorini: ...`` error)."""
    if _items(signorini):
        signorini_tags(signorini, names)


def _items(signorini: Any) -> list:
    """The Signorini names as a list (``"all"`` a one-item list)."""
    return [signorini] if isinstance(signorini, (str, int)) else list(signorini)


def _checked_file(spec: GeometrySpec) -> Any:
    """Read and check ``spec.mesh`` (rank 0): one body, Signorini names that are surface
    groups on its boundary; the ``SolidFile``."""
    solid = read_tet_msh(spec.mesh)
    signorini = spec.signorini if _items(spec.signorini) else ()
    check_solid(solid, signorini)
    return solid


def edge_range(msh: Any) -> tuple[float, float]:
    """The shortest and the longest edge of the owned tetrahedra, over every rank
    (collective)."""
    x = msh.geometry.x
    owned = msh.topology.index_map(3).size_local
    corners = msh.geometry.dofmap.array.reshape(-1, 4)[:owned]
    shortest, longest = np.inf, 0.0
    for i, j in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)):
        d = x[corners[:, j]] - x[corners[:, i]]
        length2 = np.einsum("ij,ij->i", d, d)
        shortest = min(shortest, float(length2.min(initial=np.inf)))
        longest = max(longest, float(length2.max(initial=0.0)))
    comm = msh.comm
    return (
        math.sqrt(comm.allreduce(shortest, op=MPI.MIN)),
        math.sqrt(comm.allreduce(longest, op=MPI.MAX)),
    )


def box_size(n: int, width: float, faces: Any) -> DomainSize:
    """The sizes of the box with ``n`` cubes per side and Signorini faces ``faces``
    (names of :data:`fem_py.mesh.box.BOX_FACES`, or ``"all"``), in closed form.

    A boundary node is a phi unknown when every face through it is a Signorini face:
    (n - 1)^2 inside each such face, n - 1 inside each cube edge between two, one at
    each corner of three.
    """
    counts = box_counts(n)
    on = set(BOX_FACES) if faces == "all" else set(_items(faces))
    axes = {name: BOX_FACES[name] for name in on}
    n_s = (n - 1) ** 2 * len(on)
    pairs = [(a, b) for a in on for b in on if a < b and axes[a][0] != axes[b][0]]
    n_s += (n - 1) * len(pairs)
    for sides in np.ndindex(2, 2, 2):
        corner = {name for name, (axis, side) in BOX_FACES.items() if sides[axis] == side}
        n_s += corner <= on
    return DomainSize(
        dofs=counts.vertices,
        boundary_dofs=counts.boundary_vertices,
        signorini_dofs=int(n_s),
        subdomains=0,
        h_min=width / n,
        h_max=math.sqrt(3.0) * width / n,
        dim=3,
    )


def solid_size(spec: GeometrySpec) -> DomainSize | None:
    """The sizes of ``solid_domain(comm, spec)`` in closed form for the box; None for the
    ball and files (only meshing tells). Raises the errors ``solid_domain`` raises for
    ``spec`` before it meshes."""
    if spec.mesh:
        return None
    if spec.shape == "ball":
        check_ball(spec.center, spec.radius, spec.h)
        _check_faces(spec.signorini, BALL_FACES)
        return None
    _, width, h = check_box(spec.center, spec.width, spec.h)
    _check_faces(spec.signorini, _BOX_TAGS)
    return box_size(cubes_per_side(width, h), width, spec.signorini)
