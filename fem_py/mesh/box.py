"""The structured box of ``[geometry] shape = "box"`` (docs/method.md section 11).

The cube [c - w/2, c + w/2]^3 is cut into n = round(w / h) cubes per side, each split
into six tetrahedra (:data:`KUHN_TETRAHEDRA`, those of ``dolfinx.mesh.create_box`` with
``CellType.tetrahedron``), so

    cells 6 n^3,  vertices (n+1)^3 (the P1 dofs),
    boundary vertices (n+1)^3 - (n-1)^3 = 6 n^2 + 2,  boundary triangles 12 n^2

(:func:`box_counts`, without meshing, for the size plan). The six faces carry facet tags
named after their outward normal: ``bottom`` (z min), ``top`` (z max), ``left`` (x min),
``right`` (x max), ``front`` (y min), ``back`` (y max) (:data:`BOX_FACES`).

:func:`box_mesh` writes the mesh down in parallel from its closed form, as the 2D
structured mesh does (``fem_py.mesh.distribute.distribute_structured``): each rank makes
the tetrahedra of a contiguous range of cubes (lexicographic, x fastest: slabs of the box
when the ranks divide n) and an even block of the vertex coordinates, and the mesh is made
from them where they are (``fem_py.mesh.placed``), so no graph is partitioned and no rank
holds the whole mesh
(measured against ``create_box``: docs/design/three_dimensions.md, "Issue 34, continued
(2026-12-06): the box written down in parallel ...").
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.mesh.args3d import checked_point, checked_positive
from fem_py.mesh.placed import mesh_of_placed_cells

__all__ = [
    "BOX_FACES",
    "BoxCounts",
    "BoxLattice",
    "KUHN_TETRAHEDRA",
    "box_cells",
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

#: The six tetrahedra of a cube around its diagonal from corner 0 to corner 7 (Kuhn's, in
#: ``create_box``'s order); corner k of the cube with lowest vertex (i, j, l) is
#: (i + (k & 1), j + (k >> 1 & 1), l + (k >> 2)).
KUHN_TETRAHEDRA = np.array(
    [[0, 1, 3, 7], [0, 1, 7, 5], [0, 5, 7, 4], [0, 3, 2, 7], [0, 6, 4, 7], [0, 2, 6, 7]]
)


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
    """The vertices of the box (or of the structured square, ``fem_py.mesh.polygon``) as
    the lattice ``lower + spacing * (i, j[, k])``, 0 <= i, j, k <= n (the geometric
    multigrid of the amg preconditioner coarsens it,
    ``coupling.preconditioners.lattice_multigrid``).

    Attributes
    ----------
    lower : (dim,) array
        The corner c - w/2 (dim = 3: the box, 2: the square).
    spacing : float
        w / n, the cells' side.
    n : int
        Cells per side.
    """

    lower: np.ndarray
    spacing: float
    n: int

    @property
    def dim(self) -> int:
        """The lattice's dimension, ``len(lower)``."""
        return int(np.asarray(self.lower).size)

    def indices(self, x: np.ndarray) -> np.ndarray:
        """The lattice indices (m, dim) of points ``x`` (m, >= dim) that are vertices of
        the lattice."""
        dim = self.dim
        return np.rint((np.asarray(x)[:, :dim] - self.lower) / self.spacing).astype(np.int64)


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
    msh = mesh_of_placed_cells(comm, "tetrahedron", *box_cells(comm, lo, hi, n))
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


def box_cells(
    comm: MPI.Comm, lo: np.ndarray, hi: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """This rank's part of the box [lo, hi] of n cubes a side, written down where it is
    owned: the tetrahedra of its contiguous range of cubes (vertex numbers), its even block
    of the vertex coordinates, and the (tetrahedron, rank) rows of the ranks ghosting its
    tetrahedra (the inputs of ``fem_py.mesh.placed.mesh_of_placed_cells``; no
    communication)."""
    starts = n**3 * np.arange(comm.size + 1, dtype=np.int64) // comm.size
    cubes = np.arange(starts[comm.rank], starts[comm.rank + 1])
    N = (n + 1) ** 3
    x = _vertices(lo, hi, n, comm.rank * N // comm.size, (comm.rank + 1) * N // comm.size)
    return _cells_of_cubes(n, cubes), x, _ghost_links(n, cubes, starts, comm.rank)


def _corner_offsets(n: int) -> np.ndarray:
    """Vertex number of each cube corner (0..7) less that of its corner 0 (vertices
    numbered i + (n+1) (j + (n+1) l), as ``create_box`` numbers them)."""
    k = np.arange(8)
    return (k & 1) + (n + 1) * ((k >> 1 & 1) + (n + 1) * (k >> 2))


def _lattice_indices(numbers: np.ndarray, m: int) -> np.ndarray:
    """(len(numbers), 3) indices (i, j, l) of lattice points numbered i + m (j + m l)
    (cubes: m = n; vertices: m = n + 1)."""
    return np.stack([numbers % m, numbers // m % m, numbers // (m * m)], axis=1)


def _cells_of_cubes(n: int, cubes: np.ndarray) -> np.ndarray:
    """(6 len(cubes), 4) vertex numbers of the Kuhn tetrahedra of ``cubes``, cube after cube."""
    ijl = _lattice_indices(cubes, n)
    corner0 = ijl[:, 0] + (n + 1) * (ijl[:, 1] + (n + 1) * ijl[:, 2])
    local = _corner_offsets(n)[KUHN_TETRAHEDRA]  # (6, 4)
    return (corner0[:, None, None] + local[None]).reshape(-1, 4)


def _faces_of_tetrahedra() -> list[list[tuple[int, int]]]:
    """Per Kuhn tetrahedron, the cube faces (axis, side) it has a facet on (three of its
    corners on the face)."""
    bits = (KUHN_TETRAHEDRA[..., None] >> np.arange(3)) & 1  # (6, 4, 3)
    return [
        [(a, s) for a in range(3) for s in (0, 1) if np.sum(bits[t, :, a] == s) == 3]
        for t in range(len(KUHN_TETRAHEDRA))
    ]


def _ghost_links(n: int, cubes: np.ndarray, starts: np.ndarray, rank: int) -> np.ndarray:
    """(cell, rank) rows for DOLFINx's shared-facet ghost mode: a local tetrahedron is
    ghosted on the rank owning the cube across any of its facets on its cube's faces
    (cube ranges ``starts``: rank r owns cubes starts[r] .. starts[r+1] - 1)."""
    if len(starts) == 2:
        return np.empty((0, 2), dtype=np.int64)
    ijl, stride = _lattice_indices(cubes, n), np.array([1, n, n * n])
    rows = []
    for t, faces in enumerate(_faces_of_tetrahedra()):
        for axis, side in faces:
            step = 2 * side - 1
            inside = np.flatnonzero((ijl[:, axis] + step >= 0) & (ijl[:, axis] + step < n))
            owner = np.searchsorted(starts, cubes[inside] + step * stride[axis], "right") - 1
            away = owner != rank
            rows.append(np.stack([6 * inside[away] + t, owner[away]], axis=1))
    return np.unique(np.concatenate(rows), axis=0)


def _vertices(lo: np.ndarray, hi: np.ndarray, n: int, start: int, stop: int) -> np.ndarray:
    """Coordinates (stop - start, 3) of the box's vertices numbered start .. stop - 1."""
    ijl = _lattice_indices(np.arange(start, stop, dtype=np.int64), n + 1)
    return lo + (hi - lo) * (ijl / n)
