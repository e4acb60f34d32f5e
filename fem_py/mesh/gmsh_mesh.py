"""gmsh meshing, on one rank (docs/method.md section 6): the coarse triangles of a polygon and
the unstructured fine mesh of a coarse partition; :func:`gmsh_session`, the one way the
library starts and ends gmsh.

:func:`mesh_with_gmsh` runs one gmsh session (it initialises and finalises gmsh
itself) and returns plain arrays; ``fem_py.mesh.build_domain`` calls it on rank 0
only (``fem_py.parallel.run_on_root``) and hands the arrays to
``fem_py.mesh.distribute.distribute_mesh``. Each coarse cell is its own gmsh plane surface,
sharing the coarse edges with its neighbours, with its own physical group, so the fine
mesh is conforming and every fine cell carries its subdomain id.
"""
from __future__ import annotations

import signal

from contextlib import contextmanager
from typing import Any, Iterator

import numpy as np

from fem_py.mesh.shapes import Arc, BoundaryCurve, edge_tag
from fem_py.signals import kept_signal_actions

__all__ = ["gmsh_session", "mesh_with_gmsh"]


def _import_gmsh() -> Any:
    """The gmsh module, imported without its change of the SIGINT action: its first lines
    set SIGINT to the default action (``oldsig = signal.signal(SIGINT, SIG_DFL)``), and a
    Ctrl-C during the import, which takes seconds on a loaded machine, went to whichever
    thread of the process took it (MPI's among them) and killed the process without a
    word. While gmsh is imported, ``signal.signal`` answers the current handler and
    changes nothing (Python looks the function up at the call)."""
    real = signal.signal
    signal.signal = lambda signum, handler: signal.getsignal(signum)
    try:
        import gmsh
    finally:
        signal.signal = real
    return gmsh


@contextmanager
def gmsh_session() -> Iterator[Any]:
    """``with gmsh_session() as gmsh:`` gmsh initialised (no configuration files, silent)
    and finalised on leaving, with the process's SIGINT action kept as it was: gmsh's
    Python module sets SIGINT to the default action on import (a Ctrl-C then killed the
    process with no message, leaving its staging folder), and ``gmsh.finalize`` puts
    back a plain Python handler. Kept, a Ctrl-C while gmsh meshes meets the command
    line's handler (``coupling.app.cli``: one line, exit 130, nothing left; the watchdog
    ends the run if gmsh does not return to Python within seconds)."""
    gmsh = _import_gmsh()
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        yield gmsh
    finally:
        with kept_signal_actions():
            gmsh.finalize()


#: The fine mesh as arrays: (x (n, 2), cells (n_c, 3), subdomain id of every cell,
#: boundary facets (n_f, 2), facet tags), node numbers 0 .. n-1.
MeshArrays = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


_COARSE_SIZE_FACTOR = 1.2  # gmsh point size / wanted size of the polygon's triangles


def mesh_with_gmsh(
    boundary: BoundaryCurve,
    coarse: tuple[np.ndarray, list[list[int]]] | None,
    ends: list[np.ndarray],
    d: float,
    h: float,
    arcs: tuple[Arc, ...],
    *,
    fine: bool,
) -> tuple[np.ndarray, list[list[int]], MeshArrays | None]:
    """The coarse cells and the fine mesh, in one gmsh session (call it on one rank).

    Parameters
    ----------
    boundary
        Gamma (its polygon ``boundary.P`` and tolerance ``boundary.tol``).
    coarse
        (vertices, cells) of the coarse partition, or None for the coarse triangles of a
        gmsh mesh of size ``d`` of the polygon, with the arc ends ``ends`` as vertices.
    ends
        Arc end points (used only when ``coarse`` is None).
    d, h
        Coarse and fine mesh sizes.
    arcs
        The Signorini arcs (facet tags of the coarse boundary edges, ``edge_tag``).
    fine
        Also make the fine mesh of size ``h``.

    Returns
    -------
    vertices : (n_v, 2) float
    cells : list of vertex lists, counter-clockwise
    arrays : MeshArrays or None
        The fine mesh (see ``MeshArrays``), None unless ``fine``.
    """
    arrays = None
    with gmsh_session() as gmsh:
        if coarse is None:
            gmsh.model.add("fembem_coarse")
            coarse = _polygon_partition(boundary.P, ends, d, boundary.tol)
            gmsh.model.remove()
        if fine:
            gmsh.model.add("fembem_domain")
            arrays = _fine_mesh(coarse[0], coarse[1], h, boundary, arcs)
    return coarse[0], coarse[1], arrays


def _polygon_partition(
    P: np.ndarray, extra: list[np.ndarray], d: float, tol: float
) -> tuple[np.ndarray, list[list[int]]]:
    """Coarse triangles: a gmsh mesh of size d of the polygon with ``extra`` boundary points."""
    import gmsh

    B = BoundaryCurve(P)
    pts = [(float(B.S[i]), P[i]) for i in range(len(P))]
    for q in extra:
        _, s, proj = B.locate(q)
        if min(np.linalg.norm(P - proj, axis=1)) > tol:
            pts.append((s, proj))
    pts.sort(key=lambda x: x[0])
    # Sizes from the points only, 1.2 d: with the default (sizes extended from the
    # boundary) a side of about d is split in two and its half sets the size everywhere
    # (a 25-gon of sides 1.04 d gave triangles of median side 0.52 d; these: 1.04-1.08 d)
    size = _COARSE_SIZE_FACTOR * d
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    geo = gmsh.model.geo
    ptags = [geo.addPoint(float(p[0]), float(p[1]), 0.0, size) for _, p in pts]
    lines = [geo.addLine(ptags[i], ptags[(i + 1) % len(ptags)]) for i in range(len(ptags))]
    loop = geo.addCurveLoop(lines)
    surf = geo.addPlaneSurface([loop])
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, [surf], 1)
    gmsh.model.mesh.generate(2)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)  # gmsh's defaults again
    gmsh.option.setNumber("Mesh.MeshSizeMax", 1e22)
    tags, x, _ = gmsh.model.mesh.getNodes()
    x = x.reshape(-1, 3)[:, :2]
    order = np.argsort(tags)
    tags, x = tags[order], x[order]
    _, elem_nodes = gmsh.model.mesh.getElementsByType(2)
    tri = np.searchsorted(tags, elem_nodes.reshape(-1, 3))
    used = np.unique(tri)
    remap = -np.ones(len(tags), dtype=np.int64)
    remap[used] = np.arange(len(used))
    V = x[used]
    tri = remap[tri]
    a, b, c = V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]]
    neg = ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]) < 0
    tri[neg] = tri[neg][:, [0, 2, 1]]
    return V, [list(map(int, t)) for t in tri]


def _edge_key(a: int, b: int) -> tuple[int, int]:
    return (a, b) if a < b else (b, a)


def _boundary_edges(cells: list[list[int]]) -> dict[tuple[int, int], int]:
    count: dict[tuple[int, int], int] = {}
    for c in cells:
        for a, b in zip(c, c[1:] + c[:1]):
            k = _edge_key(a, b)
            count[k] = count.get(k, 0) + 1
    return count


def _fine_mesh(
    V: np.ndarray, cells: list[list[int]], h: float, B: BoundaryCurve, arcs: tuple[Arc, ...]
) -> MeshArrays:
    """Unstructured fine mesh: one gmsh plane surface per coarse cell (its own physical
    group), coarse lines shared between neighbours, mesh size h.

    Returns the mesh as arrays (x, cells, cell subdomain ids, boundary facets, facet tags).
    The arrays are read per surface and per line rather than through
    ``gmshio.extract_topology_and_markers``, whose per-physical-group queries are
    quadratic in the number of groups (measurements: docs/design/fem_py.md).
    """
    import gmsh

    geo = gmsh.model.geo
    ptags = [geo.addPoint(float(x), float(y), 0.0, h) for x, y in V]
    count = _boundary_edges(cells)
    line_of: dict[tuple[int, int], int] = {}
    for a, b in sorted(count):
        line_of[(a, b)] = geo.addLine(ptags[a], ptags[b])
    surfs = []
    for c in cells:
        loop = []
        for a, b in zip(c, c[1:] + c[:1]):
            tag = line_of[_edge_key(a, b)]
            loop.append(tag if a < b else -tag)
        surfs.append(geo.addPlaneSurface([geo.addCurveLoop(loop)]))
    geo.synchronize()
    for i, s in enumerate(surfs):  # every surface needs a physical group (else dolfinx segfaults)
        gmsh.model.addPhysicalGroup(2, [s], i + 1)
    groups: dict[int, list[int]] = {}
    for (a, b), n in count.items():
        if n == 1:
            groups.setdefault(edge_tag(V, a, b, B, arcs), []).append(line_of[(a, b)])
    for tag, lines in sorted(groups.items()):
        gmsh.model.addPhysicalGroup(1, lines, tag)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.model.mesh.generate(2)

    node_tags, xyz, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(node_tags)
    node_tags = node_tags[order]
    x = xyz.reshape(-1, 3)[order, :2]
    tri, tri_id = [], []
    for i, s in enumerate(surfs):
        _, enodes = gmsh.model.mesh.getElementsByType(2, s)
        tri.append(enodes)
        tri_id.append(np.full(len(enodes) // 3, i, dtype=np.int32))
    seg, seg_tag = [], []
    for tag, lines in sorted(groups.items()):
        for line in lines:
            _, enodes = gmsh.model.mesh.getElementsByType(1, line)
            seg.append(enodes)
            seg_tag.append(np.full(len(enodes) // 2, tag, dtype=np.int32))
    cells_arr = np.searchsorted(node_tags, np.concatenate(tri)).reshape(-1, 3)
    facets_arr = np.searchsorted(node_tags, np.concatenate(seg)).reshape(-1, 2)
    return x, cells_arr, np.concatenate(tri_id), facets_arr, np.concatenate(seg_tag)
