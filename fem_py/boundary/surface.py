"""The boundary map in 3D (docs/method.md sections 4 and 11): the surface triangulation of
Gamma oriented out of Omega, T and E.

Gamma_h is the closed triangulated surface of the exterior facets of the tetrahedral
mesh. ``SurfaceMap`` lists its nodes in a fixed order, the order of every boundary
vector of the coupling (V_h(Gamma): continuous P1 on the triangles), with T and E of
``fem_py.boundary.vectors`` (z = T u + E phi).

- Orientation: each triangle (a, b, c) has (b - a) x (c - a) pointing away from the
  fourth vertex of its tetrahedron, so out of Omega. ``triangle_normals`` are these unit
  normals, ``node_normals`` the area-weighted average of the normals of the triangles
  at a node, normalised (the normal used for nx, ny, nz in boundary data).
- Order: nodes sorted by their input node number (``mesh.geometry.input_global_
  indices``: the order of the nodes given to DOLFINx, by ``create_box`` or gmsh),
  triangles rotated to start at their smallest node and sorted; both are independent of
  the partition and of the number of ranks (the DOLFINx dof numbers are not: ``dofs``
  changes with the partition, ``nodes`` and ``triangles`` do not).
- Signorini unknowns: Gamma_s is the union of the triangles whose facet tag is one of
  the given Signorini tags (or all of Gamma). A node is a phi unknown when every
  triangle at it lies in Gamma_s, so phi vanishes on the boundary curves of Gamma_s;
  with Gamma_s = Gamma every node is one.
- Checks: Gamma_h must be one closed, consistently oriented 2-manifold (every edge in
  exactly two triangles, traversed in opposite directions), connected, of positive
  enclosed volume (sum over triangles of (x . n) area / 3).

Built collectively: each rank orients its owned exterior facets (``exterior_facet_
indices`` gives owned facets only), rank 0 gathers them as global dof triples with
coordinates, orders and checks them, and broadcasts; every rank holds the same arrays.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from dolfinx import fem
from dolfinx import mesh as dmesh
from scipy.sparse.csgraph import connected_components

from fem_py.boundary.vectors import BoundaryVectors
from fem_py.dofs import input_node_numbers
from fem_py.parallel import broadcast_from_root, gather_to_root

__all__ = ["SurfaceMap", "surface_arrays"]


class SurfaceMap(BoundaryVectors):
    """The oriented surface triangulation of Gamma, its nodes and T, E (module docstring).

    ``SurfaceMap(V, facet_tags, signorini=(), order="input")`` (collective) with ``V``
    the P1 space of a tetrahedral mesh, its facet tags (MeshTags of dimension 2; untagged
    facets count as tag 0), ``signorini``: the facet tags of Gamma_s, or ``"all"``, and
    ``order``: the nodes sorted by input node number, or (``"coordinates"``)
    lexicographically by their coordinates, for meshes whose input numbers depend on
    the partition (a mesh refined on the ranks, ``fem_py.mesh.refinement``).

    Attributes
    ----------
    nodes : (n_gamma, 3) float
        Boundary nodes, sorted by input node number.
    dofs : (n_gamma,) int64
        Global P1 dofs of ``nodes`` (numbering of ``V``).
    triangles : (m, 3) int64
        Boundary triangles as positions in ``nodes``, oriented out of Omega.
    triangle_tags : (m,) int
        Facet tag of each triangle.
    triangle_normals : (m, 3) float
        Outward unit normals.
    triangle_areas : (m,) float
    node_normals : (n_gamma, 3) float
        Area-weighted average of the adjacent triangle normals, normalised.
    on_signorini : (m,) bool
        The triangles of Gamma_s.
    signorini : (n_s,) int64
        Positions in ``nodes`` of the phi unknowns, increasing.
    area, volume : float
        |Gamma_h| and the volume it encloses.
    euler_characteristic : int
        nodes - edges + triangles of Gamma_h (2 for a surface of genus 0).
    n_dofs : int
        Global number of P1 dofs N (columns of T).
    """

    nodes: np.ndarray
    dofs: np.ndarray
    triangles: np.ndarray
    triangle_tags: np.ndarray
    triangle_normals: np.ndarray
    triangle_areas: np.ndarray
    node_normals: np.ndarray
    on_signorini: np.ndarray
    signorini: np.ndarray
    area: float
    volume: float
    euler_characteristic: int
    n_dofs: int

    def __init__(
        self,
        V: fem.FunctionSpace,
        facet_tags: Any,
        signorini: Any = (),
        *,
        order: str = "input",
    ):
        if order not in ("input", "coordinates"):
            raise ValueError(f"order must be 'input' or 'coordinates', got {order!r}")
        wanted = _signorini_tags(signorini)
        msh = V.mesh
        if msh.topology.cell_type != dmesh.CellType.tetrahedron:
            raise ValueError("SurfaceMap needs a mesh of linear tetrahedra")
        n_cells = msh.topology.index_map(3).size_local + msh.topology.index_map(3).num_ghosts
        if msh.geometry.dofmap.array.size != 4 * n_cells:
            raise ValueError("SurfaceMap needs a mesh of linear tetrahedra")
        if V.dofmap.index_map_bs != 1 or V.dofmap.dof_layout.num_dofs != 4:
            raise ValueError("SurfaceMap needs the scalar P1 space of the mesh")
        local = _owned_triangles(V, facet_tags)
        parts = gather_to_root(msh.comm, local)
        n_dofs = V.dofmap.index_map.size_global
        # a ValueError of rank 0 (a surface that is not closed, an unknown Signorini
        # tag) is raised as it is on every rank
        arrays = broadcast_from_root(
            msh.comm,
            lambda: surface_arrays(
                *(np.concatenate(a) for a in zip(*parts)),
                wanted,
                n_dofs,
                by_coordinates=order == "coordinates",
            ),
        )
        for key, value in arrays.items():
            setattr(self, key, value)

    @property
    def lumped_mass(self) -> np.ndarray:
        """The row sums of the P1 mass matrix of Gamma_h: a third of the area of the
        triangles at each node."""
        weights = np.repeat(self.triangle_areas / 3.0, 3)
        return np.bincount(self.triangles.ravel(), weights=weights, minlength=self.n_gamma)

    @property
    def n_triangles(self) -> int:
        return len(self.triangles)


def _signorini_tags(signorini: Any) -> tuple[int, ...] | None:
    """The Signorini facet tags as a tuple of ints, None for ``"all"``."""
    if isinstance(signorini, str):
        if signorini == "all":
            return None
        raise ValueError(f"signorini must be facet tags or 'all', got {signorini!r}")
    items = [signorini] if isinstance(signorini, (int, np.integer)) else list(signorini)
    if any(isinstance(t, bool) or not isinstance(t, (int, np.integer)) for t in items):
        raise ValueError(f"signorini must be facet tags (integers) or 'all', got {signorini!r}")
    return tuple(sorted({int(t) for t in items}))


def _owned_triangles(V: fem.FunctionSpace, facet_tags: Any) -> tuple[np.ndarray, ...]:
    """The owned exterior facets of this rank: (global dofs (k, 3) oriented out of Omega,
    input node numbers (k, 3), vertex coordinates (k, 3, 3), facet tags (k,)).

    Coordinates are the mesh's geometry nodes (copies of the input, the same bits on any
    partition), not ``tabulate_dof_coordinates`` (computed through a cell's map, so
    rounded differently on different partitions).
    """
    msh = V.mesh
    top = msh.topology
    for a, b in ((3, 0), (2, 0), (2, 3)):
        top.create_connectivity(a, b)
    c2v = top.connectivity(3, 0).array.reshape(-1, 4)
    f2v = top.connectivity(2, 0).array.reshape(-1, 3)
    f2c = top.connectivity(2, 3)
    dofmap = V.dofmap.list.array.reshape(-1, 4)
    n_vertices = top.index_map(0).size_local + top.index_map(0).num_ghosts
    v2dof = np.full(n_vertices, -1, dtype=np.int32)
    v2dof[c2v[: len(dofmap)].ravel()] = dofmap.ravel()
    v2node = np.full(n_vertices, -1, dtype=np.int64)
    geometry = msh.geometry.dofmap.array.reshape(-1, 4)
    v2node[c2v[: len(geometry)].ravel()] = geometry.ravel()
    facets = np.asarray(dmesh.exterior_facet_indices(top), dtype=np.int64)
    vertices = f2v[facets]
    cell = f2c.array[f2c.offsets[facets]]
    opposite = c2v[cell].sum(axis=1) - vertices.sum(axis=1)
    X = msh.geometry.x
    p = X[v2node[vertices]]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    inward = np.einsum("ij,ij->i", normal, X[v2node[opposite]] - p[:, 0]) > 0
    vertices[inward] = vertices[inward][:, [0, 2, 1]]
    im = V.dofmap.index_map
    local = v2dof[vertices].ravel().astype(np.int32)
    dofs = np.asarray(im.local_to_global(local), dtype=np.int64).reshape(-1, 3)
    node = v2node[vertices]
    ids = input_node_numbers(msh)[node]
    n_facets = top.index_map(2).size_local + top.index_map(2).num_ghosts
    tag = np.zeros(n_facets, dtype=np.int32)
    if facet_tags is not None:
        tag[facet_tags.indices] = facet_tags.values
    return dofs, ids, X[node], tag[facets]


def surface_arrays(
    dofs: np.ndarray,
    ids: np.ndarray,
    coords: np.ndarray,
    tags: np.ndarray,
    signorini: tuple[int, ...] | None,
    n_dofs: int,
    *,
    by_coordinates: bool = False,
) -> dict[str, Any]:
    """The arrays of a :class:`SurfaceMap` from its oriented triangles (pure; rank 0).

    Parameters
    ----------
    dofs : (m, 3) int
        Global dofs of every boundary triangle, oriented out of Omega (any order of the
        triangles, as gathered from the ranks).
    ids : (m, 3) int
        Numbers of those vertices that do not depend on the partition (the mesh's input
        node numbers); the nodes are sorted by them.
    coords : (m, 3, 3) float
        Coordinates of those vertices.
    tags : (m,) int
        Facet tags.
    signorini
        The facet tags of Gamma_s, or None for Gamma_s = Gamma.
    n_dofs
        The global number of P1 dofs.
    by_coordinates
        Sort the nodes lexicographically by their coordinates instead of by ``ids``.

    Raises
    ------
    ValueError
        Gamma_h is not one closed, consistently oriented surface enclosing a positive
        volume, or a Signorini tag is on no boundary triangle.
    """
    dofs = np.asarray(dofs, dtype=np.int64).reshape(-1, 3)
    m = len(dofs)
    if m == 0:
        raise ValueError("the mesh has no boundary triangles")
    ids = np.asarray(ids, dtype=np.int64).reshape(-1, 3)
    if by_coordinates:  # the rank of each vertex's coordinates (x, then y, then z)
        points = np.asarray(coords, dtype=float).reshape(-1, 3)
        ids = np.unique(points, axis=0, return_inverse=True)[1].reshape(-1, 3).astype(np.int64)
    unique, first, inverse = np.unique(ids.ravel(), return_index=True, return_inverse=True)
    node_dofs = dofs.ravel()[first]
    if len(np.unique(node_dofs)) != len(unique):
        raise ValueError("the boundary nodes and their dofs do not match one to one")
    nodes = np.asarray(coords, dtype=float).reshape(-1, 3)[first]
    by_x = np.lexsort(nodes.T[::-1])
    if np.any(np.all(np.diff(nodes[by_x], axis=0) == 0, axis=1)):
        raise ValueError("two boundary nodes have the same coordinates")
    tri = inverse.reshape(-1, 3).astype(np.int64)
    shift = np.argmin(tri, axis=1)[:, None]
    tri = np.take_along_axis(tri, (shift + np.arange(3)) % 3, axis=1)
    by_nodes = np.lexsort((tri[:, 2], tri[:, 1], tri[:, 0]))
    tri, tags = tri[by_nodes], np.asarray(tags, dtype=np.int64)[by_nodes]
    n = len(nodes)
    euler = _check_closed_surface(tri, n)
    p = nodes[tri]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    double_area = np.linalg.norm(cross, axis=1)
    if np.any(double_area <= 1e-14 * double_area.max()):
        raise ValueError("the boundary has a degenerate (zero-area) triangle")
    volume = float(np.einsum("ij,ij->", p[:, 0], cross)) / 6.0
    if volume <= 0:
        raise ValueError(f"the boundary encloses volume {volume:g} <= 0 (oriented into Omega)")
    node_normals = np.zeros((n, 3))
    for k in range(3):
        np.add.at(node_normals, tri[:, k], cross)
    node_normals /= np.linalg.norm(node_normals, axis=1)[:, None]
    if signorini is None:
        on_s = np.ones(m, dtype=bool)
    else:
        missing = [t for t in signorini if not np.any(tags == t)]
        if missing:
            raise ValueError(
                f"signorini: facet tag {missing[0]} is on no boundary triangle; "
                f"the boundary tags are {sorted(set(tags.tolist()))}"
            )
        on_s = np.isin(tags, signorini)
    at_node = np.bincount(tri.ravel(), minlength=n)
    at_node_s = np.bincount(tri[on_s].ravel(), minlength=n)
    return dict(
        nodes=nodes,
        dofs=node_dofs,
        triangles=tri,
        triangle_tags=tags,
        triangle_normals=cross / double_area[:, None],
        triangle_areas=0.5 * double_area,
        node_normals=node_normals,
        on_signorini=on_s,
        signorini=np.flatnonzero(at_node_s == at_node).astype(np.int64),
        area=float(0.5 * double_area.sum()),
        volume=volume,
        euler_characteristic=euler,
        n_dofs=int(n_dofs),
    )


def _check_closed_surface(tri: np.ndarray, n: int) -> int:
    """Check that the triangles (m, 3) on n nodes form one closed, consistently oriented,
    connected surface; return its Euler characteristic n - edges + m (2 for a sphere)."""
    edges = tri[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
    code = edges[:, 0] * n + edges[:, 1]
    if len(np.unique(code)) < len(code):
        raise ValueError(
            "the boundary is not a consistently oriented surface (an edge is traversed "
            "twice in the same direction, or lies on more than two triangles)"
        )
    if not np.all(np.isin(edges[:, 1] * n + edges[:, 0], code)):
        raise ValueError("the boundary is not closed (an edge lies on one triangle only)")
    graph = sp.csr_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    n_parts, _ = connected_components(graph, directed=False)
    if n_parts > 1:
        raise ValueError(
            f"the boundary has {n_parts} separate surfaces; the exterior problem needs one "
            "body with one closed surface (no cavity, no second body)"
        )
    return int(n - len(edges) // 2 + len(tri))
