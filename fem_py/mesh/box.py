"""The structured box of ``[geometry] shape = "box"`` (docs/method.md section 11).

The cube [c - w/2, c + w/2]^3 is cut into n = round(w / h) cubes per side, each split
into six tetrahedra (``dolfinx.mesh.create_box`` with ``CellType.tetrahedron``), so

    cells 6 n^3,  vertices (n+1)^3 (the P1 dofs),
    boundary vertices (n+1)^3 - (n-1)^3 = 6 n^2 + 2,  boundary triangles 12 n^2

(:func:`box_counts`, without meshing, for the size plan). The six faces carry facet tags
named after their outward normal: ``bottom`` (z min), ``top`` (z max), ``left`` (x min),
``right`` (x max), ``front`` (y min), ``back`` (y max) (:data:`BOX_FACES`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.mesh.args3d import checked_point, checked_positive

__all__ = [
    "BOX_FACES",
    "BoxCounts",
    "BoxLattice",
    "box_counts",
    "box_mesh",
    "check_box",
    "cubes_per_side",
]

#: Face name -> (coordinate axis, 0 for its minimum / 1 for its maximum); the facet tag of
#: a face is its position in this table plus one (bottom 1, ..., back 6).
BOX_FACES: dict[str, tuple[int, int]] = {
    "bottom": (2, 0),
    "top": (2, 1),
    "left": (0, 0),
    "right": (0, 1),
    "front": (1, 0),
    "back": (1, 1),
}


@dataclass(frozen=True)
class BoxCounts:
    """Sizes of the box mesh with ``n`` cubes per side (closed form)."""

    n: int
    cells: int
    vertices: int
    boundary_vertices: int
    boundary_triangles: int


@dataclass(frozen=True, eq=False)
class BoxLattice:
    """The box's vertices as the lattice ``lower + spacing * (i, j, k)``, 0 <= i, j, k <= n
    (the geometric multigrid of the amg preconditioner coarsens it,
    ``coupling.preconditioners.lattice_multigrid``).

    Attributes
    ----------
    lower : (3,) array
        The corner c - w/2.
    spacing : float
        w / n, the cubes' side.
    n : int
        Cubes per side.
    """

    lower: np.ndarray
    spacing: float
    n: int

    def indices(self, x: np.ndarray) -> np.ndarray:
        """The lattice indices (m, 3) of points ``x`` (m, 3) that are vertices of the box."""
        return np.rint((np.asarray(x)[:, :3] - self.lower) / self.spacing).astype(np.int64)


def cubes_per_side(width: float, h: float) -> int:
    """n = round(width / h), at least 1."""
    return max(1, int(round(width / h)))


def box_counts(n: int) -> BoxCounts:
    """Cells, vertices, boundary vertices and boundary triangles of the box with ``n``
    cubes per side (see the module docstring)."""
    if n < 1:
        raise ValueError(f"a box needs at least one cube per side, got {n}")
    return BoxCounts(
        n=n,
        cells=6 * n**3,
        vertices=(n + 1) ** 3,
        boundary_vertices=(n + 1) ** 3 - (n - 1) ** 3,
        boundary_triangles=12 * n**2,
    )


def check_box(center: Any, width: Any, h: Any) -> tuple[np.ndarray, float, float]:
    """(center (3,), width, h) as finite numbers with width, h > 0; else a one-line
    ``ValueError`` naming the key at fault."""
    c = checked_point(center)
    return c, checked_positive("width", width), checked_positive("h", h)


def box_mesh(
    comm: MPI.Comm, center: Sequence[float], width: float, h: float
) -> tuple[dmesh.Mesh, Any, dict[str, int]]:
    """The tetrahedral box mesh and its face tags (collective).

    Parameters
    ----------
    comm
        The communicator the mesh is distributed over.
    center, width, h
        The cube [center - width/2, center + width/2]^3 and the wanted mesh size:
        :func:`cubes_per_side` cubes per side.

    Returns
    -------
    mesh : dolfinx.mesh.Mesh
        6 n^3 tetrahedra.
    facet_tags : MeshTags
        The exterior facets of each face tagged ``names[face]``.
    names : dict
        Face name -> facet tag (:data:`BOX_FACES`).
    """
    c, width, h = check_box(center, width, h)
    n = cubes_per_side(width, h)
    lo, hi = c - width / 2, c + width / 2
    msh = dmesh.create_box(comm, [lo, hi], [n, n, n], dmesh.CellType.tetrahedron)
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    tol = 1e-10 * width
    names: dict[str, int] = {}
    indices, values = [], []
    for tag, (face, (axis, side)) in enumerate(BOX_FACES.items(), start=1):
        plane = (lo, hi)[side][axis]
        found = dmesh.locate_entities_boundary(
            msh, fdim, lambda x, a=axis, p=plane: np.abs(x[a] - p) <= tol
        )
        indices.append(found)
        values.append(np.full(len(found), tag, dtype=np.int32))
        names[face] = tag
    idx = np.concatenate(indices).astype(np.int32)
    val = np.concatenate(values)
    order = np.argsort(idx, kind="stable")
    facet_tags = dmesh.meshtags(msh, fdim, idx[order], val[order])
    return msh, facet_tags, names
