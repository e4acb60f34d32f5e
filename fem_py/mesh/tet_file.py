"""Users' own 3D meshes: a gmsh .msh file (MSH 2.2 or 4.1) of linear tetrahedra with
named physical groups, read and checked on one rank (docs/method.md section 11).

:func:`read_tet_msh` reads the tetrahedra, the physical surface groups (as boundary
triangles, for the Signorini patches) and the physical volume groups; a group without
a name is called by its number, as text. :func:`check_solid` applies the checks of
``fem_py.mesh.tet_checks``: one body with a connected exterior, Signorini names that are
surface groups on the boundary. Errors are one-line ``ValueError`` messages starting
with the ``[geometry]`` key at fault.
"""
from __future__ import annotations

import re
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from fem_py.mesh.gmsh_mesh import gmsh_session
from fem_py.mesh.tet_checks import (
    BodyFacts,
    ElementKind,
    boundary_faces,
    check_body,
    check_signorini_groups,
    file_dimension,
)

__all__ = ["SolidFile", "check_solid", "msh_dimension", "opened_msh", "read_tet_msh", "used_nodes"]

#: gmsh element types: 4 the 4-node tetrahedron, 2 the 3-node triangle.
_TETRAHEDRON, _TRIANGLE = 4, 2


@dataclass
class SolidFile:
    """A tetrahedral mesh with its physical groups (node numbers 0 .. n-1).

    ``surfaces``: group key (its name, or its tag as text when unnamed) -> (k, 3) node
    triples; ``volumes``: group key -> the indices of its cells; ``source``: what to call
    it in messages (the file name).
    """

    x: np.ndarray
    cells: np.ndarray
    surfaces: dict[str, np.ndarray] = field(default_factory=dict)
    volumes: dict[str, np.ndarray] = field(default_factory=dict)
    source: str = "the mesh"


#: the section markers of an MSH file, each opened section closed by $End<name>
_SECTION = re.compile(rb"^\$(End)?(\w+)\s*$", re.M)


def _unreadable(path: Path, reason: str) -> str:
    """The one-line message for a file gmsh cannot read: a file cut short (a section
    opened and never closed: a copy or a download that stopped) or corrupt (gmsh's
    reason names the line) is said to be so; anything else is not an MSH file."""
    name = str(path)
    head = path.read_bytes()[:64]
    if not head.lstrip().startswith(b"$MeshFormat"):
        return (
            f"mesh: {name!r} is not a gmsh mesh file ({reason}); save the mesh from gmsh "
            "in MSH 2.2 or 4.1 format"
        )
    data = path.read_bytes()
    open_section, size = None, len(data)
    for m in _SECTION.finditer(data):
        open_section = None if m.group(1) else (m.group(2).decode(), m.start())
    if open_section is not None:
        section, start = open_section
        line = data.count(b"\n", 0, start) + 1
        return (
            f"mesh: {name!r} is cut short: its ${section} section (from line {line}) ends "
            f"at byte {size} without $End{section} ({reason}); copy or save the whole "
            "file again"
        )
    return (
        f"mesh: {name!r} is corrupt ({reason}); save the mesh from gmsh again in MSH 2.2 "
        "or 4.1 format"
    )


def used_nodes(
    n_nodes: int, cells: np.ndarray, groups: dict[str, np.ndarray]
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Keep the nodes the cells use (gmsh also stores the geometry's points): (the kept
    node indices, the cells and the boundary groups' elements renumbered, elements with a
    node not kept dropped)."""
    used = np.unique(cells)
    remap = np.full(n_nodes, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    groups = {k: remap[v] for k, v in groups.items()}
    return used, remap[cells], {k: v[(v >= 0).all(axis=1)] for k, v in groups.items()}


@contextmanager
def opened_msh(path: str | Path) -> Iterator[Any]:
    """``with opened_msh(path) as gmsh:`` a gmsh session with the mesh file ``path`` open
    (one rank; finalised on leaving), or a one-line ``mesh: ...`` error for a missing or
    unreadable file. For any reader of gmsh files, 2D or 3D."""
    path = Path(path)
    name = str(path)
    if not path.is_file():
        raise ValueError(
            f"mesh: file {name!r} not found; give the path of a gmsh .msh file (relative "
            "to the configuration file's folder)"
        )
    with gmsh_session() as gmsh:
        try:
            gmsh.open(name)
        except Exception as err:  # noqa: BLE001 - gmsh raises a bare Exception
            raise ValueError(_unreadable(path, str(err).splitlines()[0])) from None
        yield gmsh


def _kinds_and_nodes(gmsh: Any) -> tuple[list[ElementKind], np.ndarray, np.ndarray]:
    """The element kinds of the open model, its node tags (sorted) and coordinates."""
    kinds = [
        ElementKind(*gmsh.model.mesh.getElementProperties(int(t))[:4])
        for t in gmsh.model.mesh.getElementTypes()
    ]
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    return kinds, np.asarray(tags)[order], xyz.reshape(-1, 3)[order]


def msh_dimension(path: str | Path) -> int:
    """3 for a file of linear tetrahedra, 2 for plane triangles (``fem_py.mesh.
    tet_checks.file_dimension``); call on one rank."""
    with opened_msh(path) as gmsh:
        kinds, _, x = _kinds_and_nodes(gmsh)
        return file_dimension(kinds, x, repr(str(path)))


def read_tet_msh(path: str | Path) -> SolidFile:
    """Read a gmsh mesh file of linear tetrahedra and its physical groups (one rank).

    Raises
    ------
    ValueError
        ``mesh: ...``: a missing or unreadable file, a 2D file, a surface-only file,
        higher-order or non-tetrahedral volume elements.
    """
    name = repr(str(path))
    with opened_msh(path) as gmsh:
        kinds, tags, x = _kinds_and_nodes(gmsh)
        if file_dimension(kinds, x, name) != 3:
            raise ValueError(
                f"mesh: {name} is a 2D mesh (plane triangles); give a mesh of tetrahedra "
                "for a 3D body"
            )
        cell_tags, cell_nodes = gmsh.model.mesh.getElementsByType(_TETRAHEDRON)
        cells = np.searchsorted(tags, cell_nodes).reshape(-1, 4)
        cell_tags = np.asarray(cell_tags)
        surfaces: dict[str, np.ndarray] = {}
        volumes: dict[str, np.ndarray] = {}
        for dim, tag in gmsh.model.getPhysicalGroups():
            key = gmsh.model.getPhysicalName(dim, tag) or str(tag)
            entities = gmsh.model.getEntitiesForPhysicalGroup(dim, tag)
            if dim == 2:
                tri = [gmsh.model.mesh.getElementsByType(_TRIANGLE, e)[1] for e in entities]
                nodes = np.concatenate(tri) if tri else np.zeros(0, np.uint64)
                surfaces[key] = np.searchsorted(tags, nodes).reshape(-1, 3)
            elif dim == 3:
                found = [gmsh.model.mesh.getElementsByType(_TETRAHEDRON, e)[0] for e in entities]
                found = np.concatenate(found) if found else np.zeros(0, cell_tags.dtype)
                volumes[key] = np.flatnonzero(np.isin(cell_tags, found))
    used, cells, surfaces = used_nodes(len(tags), cells, surfaces)
    return SolidFile(x[used].copy(), cells, surfaces, volumes, name)


def check_solid(solid: SolidFile, signorini: Any = ()) -> tuple[BodyFacts, tuple | None]:
    """Check ``solid`` for the exterior problem and its Signorini group names.

    Returns
    -------
    facts : BodyFacts
        One body, one surface; its Euler characteristic.
    names : tuple of str or None
        The Signorini surface groups (None for ``"all"``).

    Raises
    ------
    ValueError
        Several bodies, a cavity, a non-manifold surface; a Signorini name that is no
        group, a volume group, or a group off the boundary.
    """
    facts = check_body(solid.cells, solid.source)
    boundary = boundary_faces(solid.cells)[0]
    names = check_signorini_groups(signorini, solid.surfaces, solid.volumes, boundary, solid.source)
    return facts, names
