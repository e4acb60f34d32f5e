"""gmsh .msh files for the tests of users' own meshes (tests/test_own_mesh.py)."""
from __future__ import annotations

import math
from pathlib import Path


def _session():
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    return gmsh


def _name(gmsh, dim, tags, tag, name):
    gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, tags, tag), name)


def _write(gmsh, path: Path, h: float, version: float = 4.1) -> None:
    """Mesh the 2D model with cells of size at most h; write it as a .msh file."""
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.model.mesh.generate(2)
    gmsh.write(str(path))


def disk_msh(path: Path, h: float, *, radius: float = 0.25, version: float = 4.1) -> Path:
    """The disk of ``radius`` about 0: curve groups "contact" (the lower quarter, angles
    -3pi/4 .. -pi/4), "free" (the rest), "left" (a piece of "free", for overlaps), surface
    group "omega"."""
    gmsh = _session()
    try:
        geo = gmsh.model.geo
        c = geo.addPoint(0, 0, 0, h)
        angles = [-3 * math.pi / 4, -math.pi / 4, math.pi / 2]
        pts = [geo.addPoint(radius * math.cos(a), radius * math.sin(a), 0, h) for a in angles]
        arcs = [geo.addCircleArc(pts[i], c, pts[(i + 1) % 3]) for i in range(3)]
        s = geo.addPlaneSurface([geo.addCurveLoop(arcs)])
        geo.synchronize()
        _name(gmsh, 1, [arcs[0]], 1, "contact")
        _name(gmsh, 1, arcs[1:], 2, "free")
        _name(gmsh, 1, [arcs[2]], 3, "left")
        _name(gmsh, 2, [s], 4, "omega")
        _write(gmsh, path, h, version)
    finally:
        gmsh.finalize()
    return Path(path)


def square_msh(path: Path, h: float, *, width: float = 0.5) -> Path:
    """The square [-w/2, w/2]^2 (unstructured, size h): curve groups "bottom", "rest";
    surface "omega"."""
    gmsh = _session()
    try:
        geo = gmsh.model.geo
        a = width / 2
        P = [geo.addPoint(x, y, 0, h) for x, y in [(-a, -a), (a, -a), (a, a), (-a, a)]]
        L = [geo.addLine(P[i], P[(i + 1) % 4]) for i in range(4)]
        s = geo.addPlaneSurface([geo.addCurveLoop(L)])
        geo.synchronize()
        _name(gmsh, 1, [L[0]], 1, "bottom")
        _name(gmsh, 1, L[1:], 2, "rest")
        _name(gmsh, 2, [s], 3, "omega")
        _write(gmsh, path, h)
    finally:
        gmsh.finalize()
    return Path(path)


def bad_msh(path: Path, kind: str) -> Path:
    """A mesh the reader must refuse: "3d", "quads", "order2", "hole", "two_bodies",
    "interior_curve" (a curve group inside Omega only)."""
    gmsh = _session()
    try:
        occ = gmsh.model.occ
        if kind == "3d":
            occ.addBox(0, 0, 0, 0.2, 0.2, 0.2)
        elif kind == "hole":
            occ.cut([(2, occ.addDisk(0, 0, 0, 0.3, 0.3))], [(2, occ.addDisk(0, 0, 0, 0.1, 0.1))])
        elif kind == "two_bodies":
            occ.addDisk(-0.2, 0, 0, 0.1, 0.1)
            occ.addDisk(0.2, 0, 0, 0.1, 0.1)
        else:
            occ.addRectangle(0, 0, 0, 0.3, 0.3)
        occ.synchronize()
        if kind == "interior_curve":
            line = occ.addLine(occ.addPoint(0.1, 0.1, 0), occ.addPoint(0.2, 0.2, 0))
            occ.synchronize()
            gmsh.model.mesh.embed(1, [line], 2, 1)
            _name(gmsh, 1, [line], 7, "inside")
        dim = 3 if kind == "3d" else 2
        ents = [t for _, t in gmsh.model.getEntities(dim)]
        _name(gmsh, dim, ents, 1, "omega")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.05)
        if kind == "quads":
            gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.model.mesh.generate(dim)
        if kind == "order2":
            gmsh.model.mesh.setOrder(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return Path(path)


def notched_msh(path: Path, h: float) -> Path:
    """The OpenCASCADE body of issue 29: the rectangle [-0.3, 0.3] x [-0.2, 0.2] minus the
    disk of radius 0.12 about (0, 0.2); curve groups "bottom" (y = -0.2), "notch" (the
    circular arc) and "free" (the rest), surface group "omega"."""
    gmsh = _session()
    try:
        occ = gmsh.model.occ
        body, _ = occ.cut(
            [(2, occ.addRectangle(-0.3, -0.2, 0, 0.6, 0.4))],
            [(2, occ.addDisk(0, 0.2, 0, 0.12, 0.12))],
        )
        occ.synchronize()
        groups: dict[str, list[int]] = {"bottom": [], "notch": [], "free": []}
        for _, tag in gmsh.model.getBoundary(body, oriented=False):
            x0, y0, _, x1, y1, _ = gmsh.model.getBoundingBox(1, abs(tag))
            if y1 < -0.19:
                groups["bottom"].append(abs(tag))
            elif y0 > 0.05 and abs(x0) < 0.13 and abs(x1) < 0.13:
                groups["notch"].append(abs(tag))
            else:
                groups["free"].append(abs(tag))
        for k, (name, tags) in enumerate(groups.items()):
            _name(gmsh, 1, tags, k + 1, name)
        _name(gmsh, 2, [t for _, t in body], 4, "omega")
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return Path(path)


def t1_msh(path: Path, lc: float = 0.02) -> Path:
    """gmsh's tutorial t1.geo: the rectangle [0, 0.1] x [0, 0.3] with the unnamed curve
    group 5 (bottom, right and left sides: ``Physical Curve(5) = {1, 2, 4}``) and the
    surface group "My surface"."""
    gmsh = _session()
    try:
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, 0, lc) for x, y in [(0, 0), (0.1, 0), (0.1, 0.3), (0, 0.3)]]
        lines = [geo.addLine(p[0], p[1]), geo.addLine(p[2], p[1]), geo.addLine(p[2], p[3])]
        lines.append(geo.addLine(p[3], p[0]))
        s = geo.addPlaneSurface([geo.addCurveLoop([4, 1, -2, 3])])
        geo.synchronize()
        gmsh.model.addPhysicalGroup(1, [1, 2, 4], 5)
        _name(gmsh, 2, [s], 6, "My surface")
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return Path(path)
