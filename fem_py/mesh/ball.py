"""The ball of ``[geometry] shape = "ball"`` (docs/method.md section 11), meshed by gmsh.

The ball |x - c| <= r is the union of its lower and upper halves (two OpenCASCADE
half-balls fragmented along the plane z = c_z, so the mesh is conforming across it). Its
surface carries two facet tags named ``bottom`` (z <= c_z) and ``top`` (z >= c_z), which
meet along the equator; ``signorini = "all"`` or ``["bottom", "top"]`` is the whole
sphere. Every surface and volume carries a physical group (an untagged one can crash
``gmshio.model_to_mesh`` in DOLFINx 0.5.2): the volume tag 1, the equatorial disk inside
the ball :data:`EQUATOR_TAG` (an interior facet tag, part of no boundary name).

gmsh runs on rank 0 only (one thread, so the mesh does not depend on the run), and
``gmshio.model_to_mesh(..., gdim=3)`` distributes the mesh.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.mesh.args3d import checked_point, checked_positive
from fem_py.mesh.gmsh_mesh import gmsh_session
from fem_py.parallel import run_on_root

__all__ = ["BALL_FACES", "EQUATOR_TAG", "VOLUME_TAG", "ball_mesh", "check_ball"]

#: Boundary name -> facet tag.
BALL_FACES: dict[str, int] = {"bottom": 1, "top": 2}
#: Facet tag of the equatorial disk (interior facets) and cell tag of the ball.
EQUATOR_TAG = 3
VOLUME_TAG = 1


def check_ball(center: Any, radius: Any, h: Any) -> tuple[np.ndarray, float, float]:
    """(center (3,), radius, h) as finite numbers with radius, h > 0 and h <= radius;
    else a one-line ``ValueError`` naming the key at fault."""
    c = checked_point(center)
    radius, h = checked_positive("radius", radius), checked_positive("h", h)
    if h > radius:
        raise ValueError(f"h = {h:g} exceeds the radius {radius:g}; take h <= radius")
    return c, radius, h


def ball_mesh(
    comm: MPI.Comm, center: Sequence[float], radius: float, h: float
) -> tuple[dmesh.Mesh, Any, dict[str, int]]:
    """The tetrahedral mesh of the ball and its facet tags (collective).

    Parameters
    ----------
    comm
        The communicator the mesh is distributed over (gmsh runs on its rank 0).
    center, radius
        The ball |x - center| <= radius.
    h
        The largest mesh size (gmsh ``Mesh.MeshSizeMax``).

    Returns
    -------
    mesh : dolfinx.mesh.Mesh
    facet_tags : MeshTags
        ``names["bottom"]`` / ``names["top"]`` on the lower / upper hemisphere,
        :data:`EQUATOR_TAG` on the interior disk z = c_z.
    names : dict
        Boundary name -> facet tag (:data:`BALL_FACES`).
    """
    c, radius, h = check_ball(center, radius, h)
    with gmsh_session() as gmsh:
        from dolfinx.io import gmshio  # imports gmsh: after gmsh_session has, to keep SIGINT

        # an error of gmsh on rank 0 is raised on every rank (no rank left in model_to_mesh)
        run_on_root(comm, lambda: _mesh_ball(gmsh, c, radius, h), error_prefix="ball mesh")
        msh, _, facet_tags = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=3)
    return msh, facet_tags, dict(BALL_FACES)


def _mesh_ball(gmsh: Any, c: np.ndarray, radius: float, h: float) -> None:
    """The two half-balls, their physical groups and the 3D mesh in the current gmsh model."""
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.model.add("fembem_ball")
    occ = gmsh.model.occ
    x, y, z = (float(v) for v in c)
    lower = occ.addSphere(x, y, z, radius, angle1=-math.pi / 2, angle2=0.0)
    upper = occ.addSphere(x, y, z, radius, angle1=0.0, angle2=math.pi / 2)
    occ.fragment([(3, lower)], [(3, upper)])
    occ.synchronize()
    tol = 1e-6 * radius
    groups: dict[int, list[int]] = {tag: [] for tag in (*BALL_FACES.values(), EQUATOR_TAG)}
    for _, surface in gmsh.model.getEntities(2):
        _, _, z0, _, _, z1 = gmsh.model.getBoundingBox(2, surface)
        if z1 - z0 <= 2 * tol:
            groups[EQUATOR_TAG].append(surface)
        elif z1 <= z + tol:
            groups[BALL_FACES["bottom"]].append(surface)
        else:
            groups[BALL_FACES["top"]].append(surface)
    for tag, surfaces in groups.items():
        gmsh.model.addPhysicalGroup(2, surfaces, tag)
    names = {tag: name for name, tag in BALL_FACES.items()}
    for tag, name in names.items():
        gmsh.model.setPhysicalName(2, tag, name)
    volumes = [v for _, v in gmsh.model.getEntities(3)]
    gmsh.model.addPhysicalGroup(3, volumes, VOLUME_TAG)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(3)
