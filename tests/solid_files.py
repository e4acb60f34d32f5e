"""gmsh .msh files of 3D bodies for the tests of fem_py.mesh.tet_file and tet_checks:
a box (the good case), quadratic tetrahedra, a surface-only file, a box with a cavity
and two boxes."""
from __future__ import annotations

from pathlib import Path


def box_toml(center: str, width: float, h: float, data: str) -> str:
    """The configuration of a box about ``center`` ("[x, y, z]") of ``width``, mesh size
    ``h``, pressed onto its bottom face (Signorini) under Carstensen's material, f = 1 and
    t0 = -1, with the further lines ``data`` of [data] (u0, ...)."""
    return (
        f'[geometry]\nshape = "box"\ncenter = {center}\nwidth = {width}\nh = {h}\n'
        'signorini = ["bottom"]\n\n[material]\nrho = "carstensen"\n\n'
        f'[data]\nf = "1"\nt0 = "-1"\n{data}\n'
    )


def _session():
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    return gmsh


def _bottom(gmsh, volume_tags):
    """The surfaces of the volumes that lie in their lowest plane z = z_min."""
    z0 = min(gmsh.model.getBoundingBox(3, v)[2] for v in volume_tags)
    out = []
    for _, s in gmsh.model.getEntities(2):
        bb = gmsh.model.getBoundingBox(2, s)
        if abs(bb[2] - z0) < 1e-6 and abs(bb[5] - z0) < 1e-6:
            out.append(s)
    return out


def group_bottom_faces(gmsh, volume: int, bottom: str = "bottom") -> list[int]:
    """The physical groups of a synchronized OpenCASCADE body (the volume tag ``volume``):
    its faces in the plane z = 0 the group ``bottom`` (2), the other faces "rest" (3), the
    volume 10. Returns the bottom faces."""
    occ = gmsh.model.occ
    faces = [tag for _, tag in gmsh.model.getEntities(2)]
    at_z0 = [t for t in faces if abs(occ.getCenterOfMass(2, t)[2]) < 1e-9]
    rest = [t for t in faces if t not in at_z0]
    gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, at_z0, 2), bottom)
    gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, rest, 3), "rest")
    gmsh.model.addPhysicalGroup(3, [volume], 10)
    return at_z0


def solid_msh(
    path: Path, kind: str = "box", *, h: float = 0.2, version: float = 4.1, order: int = 1
) -> Path:
    """Write a 3D mesh of ``kind``: "box" (the unit cube), "cavity" (the cube minus an
    inner cube), "two" (two disjoint cubes) or "surface" (the cube's surface mesh only).

    Groups: surface "bottom" (z = z_min), surface 7 unnamed (every other surface),
    volume "omega" (every volume; none for "surface").
    """
    gmsh = _session()
    try:
        occ = gmsh.model.occ
        if kind == "cavity":
            occ.cut(
                [(3, occ.addBox(0, 0, 0, 1, 1, 1))], [(3, occ.addBox(0.3, 0.3, 0.3, 0.4, 0.4, 0.4))]
            )
        elif kind == "two":
            occ.addBox(0, 0, 0, 1, 1, 1)
            occ.addBox(2, 0, 0, 1, 1, 1)
        else:
            occ.addBox(0, 0, 0, 1, 1, 1)
        occ.synchronize()
        volumes = [v for _, v in gmsh.model.getEntities(3)]
        bottom = _bottom(gmsh, volumes)
        rest = [s for _, s in gmsh.model.getEntities(2) if s not in bottom]
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, bottom, 1), "bottom")
        gmsh.model.addPhysicalGroup(2, rest, 7)
        if kind != "surface":
            gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, volumes, 9), "omega")
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.model.mesh.generate(2 if kind == "surface" else 3)
        if order != 1:
            gmsh.model.mesh.setOrder(order)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return Path(path)
