"""Users' own meshes: a gmsh .msh file or given arrays, checked and prepared on one rank.

:func:`read_msh` reads a gmsh MSH 2.2 or 4.1 file with the gmsh Python API (one gmsh
session, arrays out, like ``fem_py.mesh.gmsh_mesh``). :func:`prepare_mesh` checks a triangle
mesh (one connected, simply connected body: the exterior problem needs one Omega whose
boundary is one closed curve), turns the Signorini curve groups into facet tags (one
Signorini arc, tag ``SIGNORINI_TAG0 + k``, per connected piece of the groups) and gives
every cell its subdomain: the automatic partition of ``fem_py.partition`` (size d) or the
physical surface groups. The arrays are those of ``fem_py.mesh.gmsh_mesh`` (``MeshArrays``),
for ``fem_py.mesh.distribute.distribute_mesh``.

Every error is a one-line ``ValueError`` whose first word is the argument (the
``[geometry]`` key) at fault: ``mesh``, ``signorini``, ``subdomains``, ``diam(Omega)``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from fem_py.dofs import input_node_numbers
from fem_py.mesh.shapes import Arc
from fem_py.mesh.tet_file import opened_msh, used_nodes
from fem_py.parallel import gather_to_root
from fem_py.partition.cells import cell_adjacency, partition_cells
from fem_py.polyline import diameter
from fem_py.spec import GeometrySpec
from fem_py.tags import GAMMA_T_TAG, SIGNORINI_TAG0

__all__ = ["MeshFile", "PreparedMesh", "read_msh", "mesh_of_model", "prepare_mesh", "gather_mesh"]

#: gmsh element types: 2 the 3-node triangle, 1 the 2-node line, 15 the point.
_TRIANGLE, _LINE, _POINT = 2, 1, 15


@dataclass
class MeshFile:
    """A triangle mesh with its physical groups (node numbers 0 .. n-1).

    ``curves``: group key (its name, or its tag as a string when unnamed) -> (k, 2) node
    pairs; ``surfaces``: group key -> the cells in it; ``source``: what to call it in
    messages (the file name).
    """

    x: np.ndarray
    cells: np.ndarray
    curves: dict[str, np.ndarray] = field(default_factory=dict)
    surfaces: dict[str, np.ndarray] = field(default_factory=dict)
    source: str = "the mesh"


@dataclass
class PreparedMesh:
    """What ``fem_py.mesh`` needs from a checked mesh: the ``MeshArrays``, Omega's
    boundary nodes counter-clockwise (``polygon``), the arcs and the sizes."""

    arrays: tuple
    polygon: np.ndarray
    arcs: tuple
    whole: bool
    n_subdomains: int
    subdomain_size: float


def read_msh(path: str | Path) -> MeshFile:
    """Read a gmsh mesh file (MSH 2.2 or 4.1): 2D linear triangles and the physical groups.

    Call it on one rank; it initialises and finalises gmsh itself.

    Raises
    ------
    ValueError
        ``mesh: ...``: a missing file, a file gmsh cannot read as a mesh, a 3D mesh,
        quadrilaterals or higher-order cells.
    """
    with opened_msh(path):
        return mesh_of_model(str(Path(path)))


def mesh_of_model(name: str) -> MeshFile:
    """The mesh of the current gmsh model (inside a gmsh session) as a :class:`MeshFile`;
    ``name`` is what messages call it."""
    import gmsh

    types = {int(t) for t in gmsh.model.mesh.getElementTypes()}
    if not types or _TRIANGLE not in types and not (types - {_LINE, _POINT}):
        raise ValueError(
            f"mesh: {name!r} holds no triangles (not a 2D gmsh mesh); save a 2D "
            "triangle mesh from gmsh (Mesh > 2D, File > Export .msh)"
        )
    dims = {int(gmsh.model.mesh.getElementProperties(t)[1]) for t in types}
    if 3 in dims:
        raise ValueError(
            f"mesh: {name!r} is a 3D mesh; fembem solves in 2D: give a mesh of "
            "triangles in the plane z = 0"
        )
    other = sorted(
        gmsh.model.mesh.getElementProperties(t)[0] for t in types - {_TRIANGLE, _LINE, _POINT}
    )
    if other:
        raise ValueError(
            f"mesh: {name!r} has {', '.join(other)} elements; fembem needs linear "
            "3-node triangles (gmsh: Mesh.ElementOrder = 1, no recombination)"
        )
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    tags = tags[order]
    xyz = xyz.reshape(-1, 3)[order]
    scale = max(float(np.ptp(xyz[:, 0])), float(np.ptp(xyz[:, 1])), 1e-300)
    if np.abs(xyz[:, 2]).max(initial=0.0) > 1e-10 * scale:
        raise ValueError(
            f"mesh: {name!r} is not plane (nodes with z != 0); give a 2D mesh in z = 0"
        )
    _, tri_nodes = gmsh.model.mesh.getElementsByType(_TRIANGLE)
    cells = np.searchsorted(tags, tri_nodes).reshape(-1, 3)
    tri_tags, _ = gmsh.model.mesh.getElementsByType(_TRIANGLE)
    tri_tags = np.asarray(tri_tags)
    curves: dict[str, np.ndarray] = {}
    surfaces: dict[str, np.ndarray] = {}
    for dim, tag in gmsh.model.getPhysicalGroups():
        key = gmsh.model.getPhysicalName(dim, tag) or str(tag)
        if dim == 1:
            segs = []
            for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
                _, nodes = gmsh.model.mesh.getElementsByType(_LINE, entity)
                segs.append(np.searchsorted(tags, nodes).reshape(-1, 2))
            curves[key] = np.concatenate(segs) if segs else np.zeros((0, 2), np.int64)
        elif dim == 2:
            elems = []
            for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
                etags, _ = gmsh.model.mesh.getElementsByType(_TRIANGLE, entity)
                elems.append(np.asarray(etags))
            found = np.concatenate(elems) if elems else np.zeros(0, tri_tags.dtype)
            surfaces[key] = np.flatnonzero(np.isin(tri_tags, found))
    used, cells, curves = used_nodes(len(tags), cells, curves)
    return MeshFile(xyz[used, :2].copy(), cells, curves, surfaces, name)


def _orient(x: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """The triangles counter-clockwise."""
    p = x[cells]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    neg = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    cells = cells.copy()
    cells[neg] = cells[neg][:, [0, 2, 1]]
    return cells


def _boundary_loop(x: np.ndarray, cells: np.ndarray, source: str) -> np.ndarray:
    """The boundary nodes counter-clockwise (one closed loop), or a one-line error."""
    n = len(cells)
    a, b, _ = cell_adjacency(cells)
    graph = sp.csr_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    n_bodies, _ = connected_components(graph, directed=False)
    if n_bodies > 1:
        raise ValueError(
            f"mesh: {source} holds {n_bodies} separate bodies; the exterior problem needs "
            "one simply connected Omega: mesh one body"
        )
    # boundary facets, oriented with Omega on the left (counter-clockwise cells)
    directed = cells[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
    key = np.sort(directed, axis=1)
    code = key[:, 0] * len(x) + key[:, 1]
    uniq, count = np.unique(code, return_counts=True)
    once = np.isin(code, uniq[count == 1])
    bnd = directed[once]
    out_deg = np.bincount(bnd[:, 0], minlength=len(x))
    if out_deg.max(initial=0) > 1:
        raise ValueError(
            f"mesh: {source}: Omega touches itself at a point; the exterior problem needs "
            "one simply connected Omega"
        )
    succ = np.full(len(x), -1, dtype=np.int64)
    succ[bnd[:, 0]] = bnd[:, 1]
    start = int(bnd[np.lexsort((x[bnd[:, 0], 0], x[bnd[:, 0], 1]))[0], 0])
    loop = [start]
    node = int(succ[start])
    while node != start and len(loop) <= len(bnd):
        loop.append(node)
        node = int(succ[node])
    if len(loop) != len(bnd):
        raise ValueError(
            f"mesh: {source}: Omega has a hole (its boundary is several closed curves); the "
            "exterior problem needs one simply connected Omega: fill the hole"
        )
    return np.asarray(loop, dtype=np.int64)


def _group_arcs(mesh: MeshFile, loop: np.ndarray, signorini: Any) -> tuple[np.ndarray, bool]:
    """Panel tags along ``loop`` (panel i from loop[i] to loop[i+1]) from the Signorini
    groups: one tag per connected piece; (tags, whole)."""
    n = len(loop)
    position = np.full(len(mesh.x), -1, dtype=np.int64)
    position[loop] = np.arange(n)
    if isinstance(signorini, (str, int)):
        signorini = [signorini]
    items = list(signorini)
    panel_group = np.full(n, -1, dtype=np.int64)
    if items == ["all"]:
        return np.full(n, SIGNORINI_TAG0, dtype=np.int32), True
    for k, item in enumerate(items):
        name = str(item)
        if name not in mesh.curves:
            if name in mesh.surfaces:
                raise ValueError(
                    f"signorini: group {name!r} of {mesh.source} is a surface, not a curve; "
                    "give physical curve groups on the boundary"
                )
            known = ", ".join(repr(c) for c in mesh.curves) or "none"
            raise ValueError(
                f"signorini: {mesh.source} has no physical curve group {name!r}; its curve "
                f"groups are {known}"
            )
        seg = mesh.curves[name]
        p, q = position[seg[:, 0]], position[seg[:, 1]]
        ok = (p >= 0) & (q >= 0) & (((p + 1) % n == q) | ((q + 1) % n == p))
        if not ok.any():
            raise ValueError(
                f"signorini: group {name!r} of {mesh.source} has no boundary facets; give "
                "a curve group on the boundary of Omega"
            )
        panel = np.where((p + 1) % n == q, p, q)[ok]
        clash = panel_group[panel] >= 0
        if clash.any():
            other = items[int(panel_group[panel[clash][0]])]
            raise ValueError(
                f"signorini: groups {str(other)!r} and {name!r} overlap; Signorini groups "
                "may only touch at end points"
            )
        panel_group[panel] = k
    on = panel_group >= 0
    if on.all() and len(items) == 1:
        return np.full(n, SIGNORINI_TAG0, dtype=np.int32), True
    # one arc per run of panels of one group (counter-clockwise from the loop's start)
    tags = np.full(n, GAMMA_T_TAG, dtype=np.int32)
    if not on.any():
        return tags, False
    shift = int(np.flatnonzero(panel_group != np.roll(panel_group, 1))[0])
    order = (shift + np.arange(n)) % n
    g = panel_group[order]
    run_start = np.concatenate([[True], g[1:] != g[:-1]])
    arc_of_run = np.cumsum(run_start & (g >= 0)) - 1
    tags[order[g >= 0]] = SIGNORINI_TAG0 + arc_of_run[g >= 0]
    return tags, False


def _arcs(polygon: np.ndarray, tags: np.ndarray, whole: bool) -> tuple:
    """The :class:`fem_py.mesh.shapes.Arc` of every Signorini tag along ``polygon``."""
    closed = np.vstack([polygon, polygon[:1]])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    if whole:
        first = tuple(map(float, polygon[0]))
        return (Arc(first, first, 0.0, float(s[-1]), True, "all"),)
    arcs = []
    n = len(polygon)
    for tag in sorted(set(tags[tags >= SIGNORINI_TAG0].tolist())):
        panels = tags == tag
        i0 = int(np.flatnonzero(panels & ~np.roll(panels, 1))[0])
        k = int(panels.sum())
        i1 = (i0 + k) % n
        arcs.append(
            Arc(
                tuple(map(float, polygon[i0])),
                tuple(map(float, polygon[i1])),
                float(s[i0]),
                float((s[i0 + k] - s[i0]) if i0 + k <= n else s[-1] - s[i0] + s[i1]),
                False,
                f"arc{tag - SIGNORINI_TAG0}",
            )
        )
    return tuple(arcs)


def prepare_mesh(
    mesh: MeshFile,
    *,
    signorini: Any,
    subdomain_size: float,
    subdomains: str = GeometrySpec.subdomains,
    allow_large: bool = GeometrySpec.allow_large,
) -> PreparedMesh:
    """Check ``mesh``, tag its Signorini groups and partition it into subdomains.

    Parameters
    ----------
    mesh
        The triangles and their physical groups.
    signorini
        Names of physical curve groups (Gamma_s), ``"all"``, or () for none.
    subdomain_size
        d of the automatic partition (``subdomains = "auto"``).
    subdomains
        ``"auto"`` (:func:`fem_py.partition.partition_cells`) or ``"physical"`` (one
        subdomain per physical surface group).
    allow_large
        Allow diam(Omega) >= 1.
    """
    source = mesh.source
    if len(mesh.cells) == 0:
        raise ValueError(f"mesh: {source} holds no triangles; give a 2D triangle mesh")
    cells = _orient(mesh.x, np.asarray(mesh.cells, dtype=np.int64))
    loop = _boundary_loop(mesh.x, cells, source)
    polygon = mesh.x[loop]
    diam = diameter(polygon)
    if diam >= 1.0 and not allow_large:
        raise ValueError(
            f"diam(Omega) = {diam:.4g} >= 1 for {source}: the single-layer operator may not "
            "be elliptic (docs/method.md section 2); scale the mesh down, or opt out with "
            "allow_large (geometry.allow_large = true) at your own risk"
        )
    tags, whole = _group_arcs(mesh, loop, signorini)
    # start the boundary walk at the start of the first arc (a coarse vertex)
    if not whole and (tags != GAMMA_T_TAG).any():
        on = tags != GAMMA_T_TAG
        starts = np.flatnonzero(on & (tags != np.roll(tags, 1)))
        shift = int(starts[0]) if starts.size else 0
        loop, tags = np.roll(loop, -shift), np.roll(tags, -shift)
        polygon = mesh.x[loop]
    arcs = _arcs(polygon, tags, whole)
    if subdomains == "physical":
        part = np.full(len(cells), -1, dtype=np.int64)
        for k, c in enumerate(mesh.surfaces.values()):
            part[c] = k
        if not mesh.surfaces or (part < 0).any():
            raise ValueError(
                f"subdomains: {source} has cells outside every physical surface group; "
                'put every cell in a surface group or use subdomains = "auto"'
            )
        part = np.unique(part, return_inverse=True)[1].astype(np.int32)
    elif subdomains == "auto":
        part = partition_cells(mesh.x, cells, subdomain_size)
    else:
        raise ValueError(f'subdomains must be "auto" or "physical", got {subdomains!r}')
    facets = np.stack([loop, np.roll(loop, -1)], axis=1)
    arrays = (mesh.x.copy(), cells, part, facets, tags)
    n_sub = int(part.max()) + 1
    if subdomains == "physical":  # d: the side of a square of the mean subdomain area
        p = mesh.x[cells]
        e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        area = 0.5 * float(np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum())
        subdomain_size = float(np.sqrt(area / n_sub))
    return PreparedMesh(arrays, polygon.copy(), arcs, whole, n_sub, float(subdomain_size))


def gather_mesh(msh: Any, facet_tags: Any, cell_tags: Any = None, names: Any = None) -> Any:
    """A DOLFINx triangle mesh and its tags as a :class:`MeshFile` on rank 0 (None on the
    other ranks; collective). Curve groups are the facet tag values (as strings, or the
    names of ``names``: name -> tag), surface groups the cell tag values."""
    comm = msh.comm
    n_local = msh.topology.index_map(2).size_local + msh.topology.index_map(2).num_ghosts
    if msh.topology.dim != 2 or msh.geometry.dofmap.array.size != 3 * n_local:
        raise ValueError("mesh: domain_from_mesh needs a mesh of linear triangles")
    n_owned = msh.topology.index_map(2).size_local
    node = input_node_numbers(msh)
    x = msh.geometry.x[:, :2]
    cells = node[msh.geometry.dofmap.array.reshape(-1, 3)[:n_owned]]
    msh.topology.create_connectivity(1, 0)
    msh.topology.create_connectivity(2, 0)
    c2v = msh.topology.connectivity(2, 0).array.reshape(-1, 3)
    v2node = np.empty(
        msh.topology.index_map(0).size_local + msh.topology.index_map(0).num_ghosts, np.int64
    )
    v2node[c2v.ravel()] = msh.geometry.dofmap.array
    f2v = msh.topology.connectivity(1, 0).array.reshape(-1, 2)
    n_f_owned = msh.topology.index_map(1).size_local
    keep = facet_tags.indices < n_f_owned
    fpairs = node[v2node[f2v[facet_tags.indices[keep]]]]
    fvals = np.asarray(facet_tags.values[keep])
    cvals = None
    if cell_tags is not None:
        ck = cell_tags.indices < n_owned
        cvals = np.full(n_owned, -1, dtype=np.int64)
        cvals[cell_tags.indices[ck]] = cell_tags.values[ck]
    parts = gather_to_root(comm, (node, x, cells, fpairs, fvals, cvals))
    if comm.rank != 0:
        return None
    n_nodes = int(max(p[0].max(initial=-1) for p in parts)) + 1
    X = np.zeros((n_nodes, 2))
    for p in parts:
        X[p[0]] = p[1]
    C = np.concatenate([p[2] for p in parts])
    fp = np.concatenate([p[3] for p in parts])
    fv = np.concatenate([p[4] for p in parts])
    label = {int(t): str(t) for t in np.unique(fv)}
    for name, t in (names or {}).items():
        label[int(t)] = str(name)
    curves = {label[int(t)]: fp[fv == t] for t in np.unique(fv)}
    surfaces = {}
    if cell_tags is not None:
        cv = np.concatenate([p[5] for p in parts])
        surfaces = {str(t): np.flatnonzero(cv == t) for t in np.unique(cv) if t >= 0}
    return MeshFile(X, C, curves, surfaces, "the mesh")


def polygon_mesh(boundary: Any, ends: list, h: float, arcs: tuple) -> MeshFile:
    """A gmsh mesh of size h of the polygon of ``boundary`` (a ``fem_py.mesh.shapes.
    BoundaryCurve``) with the arc ends ``ends`` as nodes, as a :class:`MeshFile` whose
    curve groups ``arc<k>`` hold the boundary facets inside arc k (call on one rank)."""
    from fem_py.mesh.gmsh_mesh import mesh_with_gmsh

    x, tri, _ = mesh_with_gmsh(boundary, None, ends, h, h, arcs, fine=False)
    cells = np.asarray(tri, dtype=np.int64)
    facets = np.sort(cells[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    uniq, count = np.unique(facets, axis=0, return_counts=True)
    bnd = uniq[count == 1]
    position = np.array([boundary.locate(0.5 * (x[a] + x[b]))[1] for a, b in bnd])
    curves = {}
    for k, arc in enumerate(arcs):
        curves["all" if arc.whole else f"arc{k}"] = bnd[boundary.inside(position, arc)]
    return MeshFile(np.asarray(x, dtype=float), cells, curves, {}, "the polygon")
