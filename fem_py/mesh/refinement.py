"""Local refinement of a :class:`fem_py.mesh.Domain` (triangles) or a
:class:`fem_py.mesh.SolidDomain` (tetrahedra) and P1 transfer to the refined mesh.

``dolfinx.mesh.refine(mesh, edges)`` (DOLFINx 0.5.2, Plaza, in 2D and 3D) bisects the
marked edges and whatever edges keep the mesh conforming, but transfers no tags after a
local refinement (its parent maps, ``plaza_refine_data``, exist for uniform refinement
only; ``transfer_facet_meshtag`` needs them). They are rebuilt here from the geometry,
which refinement does not change:

- cell tags: a child lies inside its parent, so the subdomain of a new cell is the tag of
  the old cell containing its midpoint. Subdomains stay unions of cells and the coarse
  partition is kept; the coarse structure is recomputed from the new tags
  (:func:`fem_py.partition.coarse.compute_coarse_structure`), so the substructuring
  preconditioner applies on every level (coarse vertices and edges do not change,
  only the fine chains along them); the adaptive loop then splits the subdomains the
  refinement has graded (:mod:`fem_py.mesh.grading`);
- facet tags: the midpoint of a new boundary facet lies on exactly one old boundary
  facet (its parent), whose tag (Gamma_t or Signorini arc k; in 3D the named face) it
  takes. In 3D the children of a boundary triangle are boundary triangles inside it (the
  surface is refined by the same Plaza bisections, conforming), so the named faces and
  Gamma_s follow exactly. A body has no cell tags and no coarse structure; the box's
  vertex lattice is dropped (the refined mesh is no lattice: the ``amg`` preconditioner
  then takes PETSc's algebraic multigrid). The new nodes' input numbers depend on the
  partition, so the refined body's boundary nodes are ordered by their coordinates
  (``SolidDomain.node_order``): the 3D quadrature of S_h depends on the order of a
  triangle's vertices (1e-5 relative in S_h 1 measured), which must not change with
  the number of ranks.

New nodes are edge midpoints and old nodes stay, so a P1 function is transferred
exactly by evaluating it at the new nodes (:func:`transfer_p1`): old values at old
nodes, the average of the two end values at a midpoint.

Under MPI, ``redistribute=False`` keeps each child on the rank of its parent, which the
rank-local point location below needs, and keeps whole subdomains per rank; the refined
mesh is the same as in serial up to the ordering (tests/test_mpi_adapt.py, 2 ranks).
DOLFINx 0.5.2 ghosts a child once per facet it shares with another rank, so a cell with
two such facets arrives twice as a ghost, and the vertices around it get wrong owners
(a subdomain interior dof owned by another rank, a ghost node outside the local old
mesh); :func:`fem_py.mesh.distribute.reghost` builds the mesh again from the owned
children, each ghosted once on the owners of its facet neighbours
(tests/test_adapt_mpi.py).
"""
from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import numpy as np
from dolfinx import cpp, fem, geometry
from dolfinx import mesh as dmesh
from scipy.spatial import cKDTree

from fem_py.dofs.p1 import tag_array
from fem_py.mesh.distribute import reghost
from fem_py.mesh.domain import max_facet_length
from fem_py.mesh.location import locate
from fem_py.mesh.location3d import locate_in_tetrahedra
from fem_py.partition.coarse import compute_coarse_structure
from fem_py.polyline import CORNER_ANGLE

__all__ = [
    "refine_domain",
    "transfer_p1",
    "boundary_transfer",
    "locate_cells",
    "facet_parents",
    "refined_facet_tags",
]


def locate_cells(msh: Any, points: np.ndarray) -> np.ndarray:
    """For each point (m, 2 or 3) the first local cell of ``msh`` containing it (-1: none).

    dolfinx's collision test (GJK, an absolute tolerance) misses some points that lie on
    the boundary of the mesh up to round-off (a node 6e-17 off a corner's side after
    several refinements); those get the cell of :func:`fem_py.mesh.location.locate` (barycentric
    coordinates to 1e-12 relative)."""
    pts = np.zeros((len(points), 3))
    pts[:, : points.shape[1]] = points[:, :3]
    tree = geometry.BoundingBoxTree(msh, msh.topology.dim)
    candidates = geometry.compute_collisions(tree, pts)
    colliding = geometry.compute_colliding_cells(msh, candidates, pts)
    offsets = colliding.offsets
    found = np.diff(offsets) > 0
    out = np.full(len(pts), -1, dtype=np.int32)
    out[found] = colliding.array[offsets[:-1][found]]
    missed = np.flatnonzero(~found)
    if len(missed):
        tdim = msh.topology.dim
        cells = msh.geometry.dofmap.array.reshape(-1, tdim + 1)
        if tdim == 3:
            out[missed] = locate_in_tetrahedra(msh.geometry.x, cells, pts[missed])[0]
        else:
            out[missed] = locate(msh.geometry.x, cells, pts[missed, :2])[0]
    return out


def transfer_p1(u_old: fem.Function, V_new: fem.FunctionSpace) -> np.ndarray:
    """Values of the P1 function ``u_old`` at the local dofs (owned then ghost) of the P1
    space ``V_new`` on a refinement of its mesh: exact nested interpolation."""
    x = V_new.tabulate_dof_coordinates()
    cells = locate_cells(u_old.function_space.mesh, x)
    if np.any(cells < 0):
        raise RuntimeError("transfer_p1: a node of the refined mesh lies outside the old mesh")
    return u_old.eval(x, cells).ravel().astype(float)


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(m, k) distances of m points to k segments [a_j, b_j]."""
    t = b - a
    rel = points[:, None, :] - a[None, :, :]
    s = np.clip(np.einsum("mkd,kd->mk", rel, t) / np.einsum("kd,kd->k", t, t), 0.0, 1.0)
    closest = a[None, :, :] + s[..., None] * t[None, :, :]
    return np.linalg.norm(points[:, None, :] - closest, axis=2)


def _facet_corners(msh: Any, facets: np.ndarray) -> np.ndarray:
    """Corners (k, tdim, gdim) of the local facets ``facets`` (gdim = tdim)."""
    tdim = msh.topology.dim
    geo = cpp.mesh.entities_to_geometry(msh._mesh, tdim - 1, np.asarray(facets, np.int32), False)
    return msh.geometry.x[:, :tdim][geo]


def _triangle_misfit(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """How far each point (m, 3) is from lying in its triangle (m, 3, 3), relative to the
    triangle's size: the distance to its plane over its longest side plus how far the
    smallest barycentric coordinate in the plane falls below 0 (0 for a point inside)."""
    a, e1, e2 = corners[:, 0], corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    rel = points - a
    g11, g12, g22 = (np.einsum("md,md->m", u, v) for u, v in ((e1, e1), (e1, e2), (e2, e2)))
    r1, r2 = np.einsum("md,md->m", rel, e1), np.einsum("md,md->m", rel, e2)
    det = g11 * g22 - g12**2
    s, t = (g22 * r1 - g12 * r2) / det, (g11 * r2 - g12 * r1) / det
    bary = np.column_stack([1.0 - s - t, s, t])
    off = rel - s[:, None] * e1 - t[:, None] * e2
    size = np.sqrt(np.maximum(g11, g22))
    return np.linalg.norm(off, axis=1) / size + np.maximum(0.0, -bary.min(axis=1))


def facet_parents(corners: np.ndarray, points: np.ndarray) -> np.ndarray:
    """For each point (m, d) the index of the facet (``corners`` (k, d, d): segments in
    2D, triangles in 3D) it lies on (the closest one). 3D candidates: the triangles whose
    centroid lies within the largest centroid-to-corner distance of the point."""
    out = np.empty(len(points), dtype=np.int64)
    if corners.shape[1] == 2:
        for start in range(0, len(points), 512):
            block = slice(start, start + 512)
            d = _segment_distance(points[block], corners[:, 0], corners[:, 1])
            out[block] = np.argmin(d, axis=1)
        return out
    centroids = corners.mean(axis=1)
    reach = float(np.linalg.norm(corners - centroids[:, None], axis=2).max(initial=0.0))
    near = cKDTree(centroids).query_ball_point(points, reach * (1 + 1e-9) + 1e-300)
    counts = np.array([len(c) for c in near], dtype=np.int64)
    if np.any(counts == 0):
        raise RuntimeError("facet_parents: a boundary facet has no parent on this rank")
    flat = np.fromiter(itertools.chain.from_iterable(near), dtype=np.int64, count=counts.sum())
    point = np.repeat(np.arange(len(points)), counts)
    misfit = _triangle_misfit(points[point], corners[flat])
    # the candidate of least misfit per point: sort by (point, misfit), first of each
    order = np.lexsort((misfit, point))
    first = np.r_[0, np.cumsum(counts)[:-1]]
    out[:] = flat[order[first]]
    return out


def _corner_angle(domain: Any) -> float | None:
    """The ``corner_angle`` the coarse structure of ``domain`` was computed with: none for
    the grid partitions of the square and L-shape of build_domain,
    fem_py.mesh.CORNER_ANGLE for the other shapes and meshes and for partitions made
    of cells (curved coarse edges, e.g. after ``fem_py.mesh.grading``). The new nodes are
    midpoints of straight facets, so they add no bend and the coarse vertices stay the
    same."""
    grid = domain.shape in ("square", "lshape") and domain.partition == "grid"
    return None if grid else CORNER_ANGLE


#: Edges of a cell, by the cell's topological dimension.
_CELL_EDGES = {2: 3, 3: 6}


def refined_facet_tags(old: Any, facet_tags: Any, new: Any) -> Any:
    """The facet tags of the refined mesh ``new`` of ``old``: every exterior facet of
    ``new`` takes the value of the facet of ``facet_tags`` (on ``old``) it lies on
    (rank-local: with ``redistribute=False`` every child lies on its parent's rank)."""
    tdim = new.topology.dim
    new.topology.create_connectivity(tdim - 1, tdim)
    facets = np.sort(dmesh.exterior_facet_indices(new.topology)).astype(np.int32)
    mids = dmesh.compute_midpoints(new, tdim - 1, facets)[:, :tdim]
    parents = facet_parents(_facet_corners(old, facet_tags.indices), mids)
    return dmesh.meshtags(new, tdim - 1, facets, facet_tags.values[parents].astype(np.int32))


def refine_domain(domain: Any, cells: np.ndarray) -> Any:
    """Refine ``domain`` (a :class:`fem_py.mesh.Domain` or a
    :class:`fem_py.mesh.SolidDomain`) at the local cells ``cells`` (every edge of a marked
    cell is bisected, plus the closure of Plaza's refinement) and return the refined
    domain with re-built tags (and, in 2D, coarse structure; collective).
    """
    old = domain.mesh
    tdim = old.topology.dim
    old.topology.create_connectivity(tdim, 1)
    c2e = old.topology.connectivity(tdim, 1).array.reshape(-1, _CELL_EDGES[tdim])
    edges = np.unique(c2e[np.asarray(cells, dtype=np.int64)].ravel()).astype(np.int32)
    new = reghost(dmesh.refine(old, edges, redistribute=False))
    new.topology.create_connectivity(tdim - 1, tdim)
    new.topology.create_connectivity(tdim, 0)
    ft = refined_facet_tags(old, domain.facet_tags, new)
    if tdim == 3:  # a body: named faces, no cell tags, no coarse structure
        from fem_py.mesh.solid import edge_range

        h_min, h_max = edge_range(new)
        return dataclasses.replace(
            domain,
            mesh=new,
            facet_tags=ft,
            h_min=h_min,
            h_max=h_max,
            lattice=None,
            node_order="coordinates",  # the new nodes' input numbers follow the partition
        )

    # cell tags: the parent (old cell containing the midpoint)
    n_old = old.topology.index_map(tdim).size_local + old.topology.index_map(tdim).num_ghosts
    old_tags = tag_array(domain.cell_tags, n_old)
    n_new = new.topology.index_map(tdim).size_local + new.topology.index_map(tdim).num_ghosts
    mids = dmesh.compute_midpoints(new, tdim, np.arange(n_new, dtype=np.int32))
    parents = locate_cells(old, mids)
    if np.any(parents < 0):
        raise RuntimeError("refine_domain: a refined cell has no parent on this rank")
    ct = dmesh.meshtags(
        new, tdim, np.arange(n_new, dtype=np.int32), old_tags[parents].astype(np.int32)
    )
    # the other fields (arcs, sizes, polygon, ...) are those of the refined domain
    return dataclasses.replace(
        domain,
        mesh=new,
        cell_tags=ct,
        facet_tags=ft,
        coarse=compute_coarse_structure(new, ct, ft, corner_angle=_corner_angle(domain)),
        structured=False,
        h_max=max_facet_length(new),
        lattice=None,  # the refined mesh is no lattice
    )


def boundary_transfer(
    old_nodes: np.ndarray, old_values: np.ndarray, new_nodes: np.ndarray
) -> np.ndarray:
    """A continuous piecewise linear function on the closed polygon ``old_nodes`` (n, 2)
    with nodal ``old_values`` evaluated at the points ``new_nodes`` (m, 2) on it."""
    a = old_nodes
    b = np.roll(old_nodes, -1, axis=0)
    out = np.empty(len(new_nodes))
    for start in range(0, len(new_nodes), 512):
        block = slice(start, start + 512)
        p = new_nodes[block]
        panel = np.argmin(_segment_distance(p, a, b), axis=1)
        t = b[panel] - a[panel]
        s = np.clip(np.einsum("md,md->m", p - a[panel], t) / np.einsum("md,md->m", t, t), 0, 1)
        out[block] = (1 - s) * old_values[panel] + s * np.roll(old_values, -1)[panel]
    return out
