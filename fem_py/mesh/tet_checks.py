"""Checks that a tetrahedral mesh can be Omega of the exterior problem in 3D (docs/method.md
section 11), as pure functions on arrays.

The exterior problem needs one body whose exterior is connected: the cells must be one
piece (joined through shared faces: :func:`body_facts` counts the pieces) and the
surface one closed surface (a cavity adds a second one: it counts the pieces of the
boundary triangles joined through shared edges). A body with handles (a solid torus) is
allowed: its exterior is connected; its genus is (2 - chi) / 2 with chi the Euler
characteristic of the surface. The element kinds of a file decide its dimension
(:func:`file_dimension`): linear tetrahedra make a 3D mesh, plane triangles a 2D one,
anything else is refused. :func:`check_signorini_groups` checks that the Signorini
names are physical surface groups on the boundary.

Every error is a one-line ``ValueError`` whose first word is the ``[geometry]`` key at
fault (``mesh``, ``signorini``), naming the problem and the fix.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Mapping, NamedTuple

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = [
    "BodyFacts",
    "ElementKind",
    "body_facts",
    "boundary_faces",
    "check_body",
    "check_signorini_groups",
    "file_dimension",
    "row_codes",
]

#: The faces of a tetrahedron (a, b, c, d), each ordered so that its normal (right-hand
#: rule) points away from the fourth vertex when the tetrahedron is positively oriented.
_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])


class ElementKind(NamedTuple):
    """An element type of a mesh file (``gmsh.model.mesh.getElementProperties``)."""

    name: str
    dim: int
    order: int
    nodes: int


@dataclass(frozen=True)
class BodyFacts:
    """The pieces of a tetrahedral mesh: ``bodies`` (cells joined through faces),
    ``surfaces`` (boundary triangles joined through edges), the Euler characteristic of
    the surface, the number of edges on other than two boundary triangles and of faces
    on more than two tetrahedra."""

    bodies: int
    surfaces: int
    euler_characteristic: int
    nonmanifold_edges: int
    overlapping_faces: int


def file_dimension(kinds: Iterable[ElementKind], x: np.ndarray, source: str) -> int:
    """3 for a mesh of linear tetrahedra, 2 for triangles in the plane z = 0.

    Parameters
    ----------
    kinds
        The element types in the file.
    x : (n, 3) float
        The node coordinates.
    source
        What to call the file in messages.

    Raises
    ------
    ValueError
        Higher-order or non-tetrahedral volume elements, higher-order triangles beside
        tetrahedra, triangles off the plane z = 0 without volume elements (a surface
        mesh), or neither triangles nor tetrahedra.
    """
    kinds = list(kinds)
    volume = [k for k in kinds if k.dim == 3]
    surface = [k for k in kinds if k.dim == 2]
    if volume:
        bad = sorted({k.name for k in volume + surface if k.order != 1 or k.nodes not in (3, 4)})
        if bad:
            raise ValueError(
                f"mesh: {source} has {', '.join(bad)} elements; fembem needs linear "
                "4-node tetrahedra (gmsh: Mesh.ElementOrder = 1, no recombination)"
            )
        return 3
    if not surface:
        raise ValueError(
            f"mesh: {source} holds no triangles or tetrahedra; save a gmsh mesh of "
            "tetrahedra (Mesh > 3D) or of plane triangles (Mesh > 2D)"
        )
    x = np.asarray(x, dtype=float)
    scale = max(float(np.ptp(x, axis=0).max(initial=0.0)), 1e-300)
    if np.abs(x[:, 2]).max(initial=0.0) > 1e-10 * scale:
        raise ValueError(
            f"mesh: {source} holds a surface mesh only (triangles in space, no "
            "tetrahedra); mesh the volume too (gmsh: Mesh > 3D) and, if the file has "
            "physical groups, add a physical volume (gmsh saves only grouped elements)"
        )
    return 2


def boundary_faces(cells: np.ndarray, x: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """The faces of the tetrahedra seen once (the boundary) and the face counts.

    Returns
    -------
    faces : (k, 3) int
        The boundary triangles, oriented out of the body when ``x`` is given (each
        tetrahedron is first made positive), else in the cells' own vertex order.
    cell : (k,) int
        The tetrahedron of each boundary triangle.
    inner : (j, 2) int
        The pairs of tetrahedra sharing an interior face.
    over : int
        The number of faces on more than two tetrahedra (a malformed mesh).
    """
    cells = np.asarray(cells, dtype=np.int64)
    if x is not None:
        p = np.asarray(x, dtype=float)[cells]
        e = p[:, 1:] - p[:, :1]
        negative = np.einsum("ij,ij->i", np.cross(e[:, 0], e[:, 1]), e[:, 2]) < 0
        cells = cells.copy()
        cells[negative] = cells[negative][:, [0, 2, 1, 3]]
    faces = cells[:, _FACES].reshape(-1, 3)
    owner = np.repeat(np.arange(len(cells)), 4)
    _, inverse, counts = np.unique(
        row_codes(np.sort(faces, axis=1)), return_inverse=True, return_counts=True
    )
    inverse = inverse.ravel()
    once = counts[inverse] == 1
    twice = np.flatnonzero(counts[inverse] == 2)
    pair_order = twice[np.argsort(inverse[twice], kind="stable")]
    inner = owner[pair_order].reshape(-1, 2)
    return faces[once], owner[once], inner, int(np.sum(counts > 2))


def row_codes(rows: np.ndarray) -> np.ndarray:
    """One number per row of non-negative ints (k, r): equal rows, equal numbers (int64
    while the rows fit, else the rows' bytes)."""
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    base = int(rows.max(initial=0)) + 1
    if base ** rows.shape[1] < 2**63:
        code = np.zeros(len(rows), dtype=np.int64)
        for column in rows.T:
            code = code * base + column
        return code
    return rows.view(np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))).ravel()


def body_facts(cells: np.ndarray) -> BodyFacts:
    """Count the bodies and surfaces of a tetrahedral mesh (module docstring)."""
    cells = np.asarray(cells, dtype=np.int64)
    n = len(cells)
    faces, _, inner, over = boundary_faces(cells)
    graph = sp.csr_matrix((np.ones(len(inner)), (inner[:, 0], inner[:, 1])), shape=(n, n))
    bodies = connected_components(graph, directed=False)[0] if n else 0
    edges = np.sort(faces[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    _, edge_id, per_edge = np.unique(row_codes(edges), return_inverse=True, return_counts=True)
    edge_id = edge_id.ravel()
    m = len(faces)
    # triangles joined through their edges: triangle -> edge incidence, squared
    incidence = sp.csr_matrix(
        (np.ones(3 * m), (np.repeat(np.arange(m), 3), edge_id)), shape=(m, len(per_edge))
    )
    surfaces = connected_components(incidence @ incidence.T, directed=False)[0] if m else 0
    n_vertices = len(np.unique(faces))
    return BodyFacts(
        bodies=int(bodies),
        surfaces=int(surfaces),
        euler_characteristic=int(n_vertices - len(per_edge) + m),
        nonmanifold_edges=int(np.sum(per_edge != 2)),
        overlapping_faces=over,
    )


def check_body(cells: np.ndarray, source: str) -> BodyFacts:
    """Check that the tetrahedra ``cells`` (m, 4) are one body with one closed surface;
    return its :class:`BodyFacts`.

    Raises
    ------
    ValueError
        No cells, a face on more than two tetrahedra, several bodies, a surface that is
        not a manifold (bodies touching along an edge), or a cavity.
    """
    cells = np.asarray(cells, dtype=np.int64)
    if cells.ndim != 2 or cells.shape[1] != 4 or len(cells) == 0:
        raise ValueError(f"mesh: {source} holds no tetrahedra; give a 3D tetrahedral mesh")
    facts = body_facts(cells)
    if facts.overlapping_faces:
        raise ValueError(
            f"mesh: {source} has faces shared by more than two tetrahedra (overlapping "
            "cells); remesh the volume"
        )
    if facts.bodies > 1:
        raise ValueError(
            f"mesh: {source} holds {facts.bodies} separate bodies; the exterior problem "
            "needs one body: mesh one body (or join the bodies)"
        )
    if facts.nonmanifold_edges:
        raise ValueError(
            f"mesh: {source}: parts of Omega touch along an edge (its surface is not a "
            "manifold); the exterior problem needs one body with a closed surface"
        )
    if facts.surfaces > 1:
        cavities = facts.surfaces - 1
        raise ValueError(
            f"mesh: {source}: Omega has {cavities} cavit{'y' if cavities == 1 else 'ies'} "
            f"(its surface is {facts.surfaces} closed surfaces); the exterior problem needs "
            "a body with a connected exterior: fill the cavity"
        )
    return facts


def check_signorini_groups(
    signorini: Any,
    surfaces: Mapping[str, np.ndarray],
    volumes: Iterable[str],
    boundary: np.ndarray,
    source: str,
) -> tuple[str, ...] | None:
    """The Signorini group names, checked; None for ``"all"``.

    Parameters
    ----------
    signorini
        ``"all"``, a group name, or a sequence of names (a group without a name is
        called by its number, as text).
    surfaces
        Physical surface group name -> its triangles (k, 3) as node numbers.
    volumes
        The names of the physical volume groups.
    boundary : (b, 3) int
        The boundary triangles of the mesh (:func:`boundary_faces`).
    source
        What to call the file in messages.

    Raises
    ------
    ValueError
        ``"all"`` among other names, a name of no group, a volume group, or a surface
        group with no triangle on the boundary.
    """
    items = [signorini] if isinstance(signorini, (str, int)) else list(signorini)
    names = [str(item) for item in items]
    if "all" in names:
        if len(names) != 1:
            raise ValueError(
                "signorini: 'all' (the whole surface) cannot be combined with group names"
            )
        return None
    volumes = {str(v) for v in volumes}
    key = np.sort(np.asarray(boundary, dtype=np.int64), axis=1)
    for name in names:
        if name not in surfaces:
            if name in volumes:
                raise ValueError(
                    f"signorini: group {name!r} of {source} is a volume, not a surface; "
                    "give physical surface groups on the boundary"
                )
            known = ", ".join(repr(s) for s in surfaces) or "none"
            raise ValueError(
                f"signorini: {source} has no physical surface group {name!r}; its surface "
                f"groups are {known}"
            )
        tri = np.sort(np.asarray(surfaces[name], dtype=np.int64).reshape(-1, 3), axis=1)
        if not _rows_in(tri, key).any():
            raise ValueError(
                f"signorini: group {name!r} of {source} has no triangle on the boundary; "
                "give a surface group on the boundary of Omega"
            )
    return tuple(names)


def _rows_in(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Mask of the rows of ``a`` (k, 3) that are rows of ``b`` (j, 3), both sorted rows."""
    if len(a) == 0 or len(b) == 0:
        return np.zeros(len(a), dtype=bool)
    codes = row_codes(np.vstack([a, b]))
    return np.isin(codes[: len(a)], codes[len(a) :])
