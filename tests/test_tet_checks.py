"""Checks of 3D meshes for the exterior problem (fem_py.mesh.tet_checks, tet_file): pure
cases on arrays, then gmsh-written MSH 4.1 and 2.2 files, one per bad case, each refused
in one line naming the key at fault."""
from __future__ import annotations

import numpy as np
import pytest
from dolfinx import mesh as dmesh
from mpi4py import MPI

from fem_py.mesh.tet_checks import (
    ElementKind,
    body_facts,
    boundary_faces,
    check_body,
    check_signorini_groups,
    file_dimension,
    row_codes,
)
from fem_py.mesh.tet_file import check_solid, msh_dimension, read_tet_msh
from solid_files import solid_msh

TET4 = ElementKind("Tetrahedron 4", 3, 1, 4)
TRI3 = ElementKind("Triangle 3", 2, 1, 3)


def _cubes(n, keep):
    """The box [0, n]^3 of n^3 unit cubes, six tetrahedra each, keeping the cubes whose
    index (i, j, k) satisfies ``keep``: (vertex coordinates, cells)."""
    msh = dmesh.create_box(
        MPI.COMM_SELF, [np.zeros(3), np.full(3, float(n))], [n] * 3, dmesh.CellType.tetrahedron
    )
    cells = np.asarray(msh.geometry.dofmap.array).reshape(-1, 4)
    x = msh.geometry.x
    cube = np.floor(x[cells].mean(axis=1)).astype(int)
    return x, cells[np.array([keep(*c) for c in cube])]


def _one_line(err, word):
    message = str(err.value)
    assert message.startswith(word + ":") and "\n" not in message, message


# ------------------------------------------------------------------------- on arrays
def test_box_is_one_body_with_one_surface():
    x, cells = _cubes(3, lambda i, j, k: True)
    facts = check_body(cells, "box")
    assert facts == body_facts(cells)
    assert (facts.bodies, facts.surfaces, facts.euler_characteristic) == (1, 1, 2)
    faces, owner, inner, over = boundary_faces(cells, x)
    assert len(faces) == 12 * 9 and over == 0 and len(inner) == (4 * len(cells) - len(faces)) // 2
    # oriented out of the body: the divergence theorem gives the volume 27
    p = x[faces]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.einsum("ij,ij->", p[:, 0], cross) / 6 == pytest.approx(27.0, rel=1e-14)


def test_torus_is_allowed():
    # a ring of 8 cubes around the middle column: connected exterior, genus 1
    x, cells = _cubes(3, lambda i, j, k: k == 1 and (i, j) != (1, 1))
    facts = check_body(cells, "ring")
    assert facts.surfaces == 1 and facts.euler_characteristic == 0


def test_cavity_refused():
    _, cells = _cubes(3, lambda i, j, k: (i, j, k) != (1, 1, 1))
    with pytest.raises(ValueError, match="1 cavity") as err:
        check_body(cells, "hollow")
    _one_line(err, "mesh")


def test_two_bodies_refused():
    _, cells = _cubes(3, lambda i, j, k: i != 1)
    with pytest.raises(ValueError, match="2 separate bodies") as err:
        check_body(cells, "pair")
    _one_line(err, "mesh")
    # cubes touching along an edge only are not joined through a face: two bodies
    _, cells = _cubes(2, lambda i, j, k: k == 0 and i == j)
    with pytest.raises(ValueError, match="2 separate bodies"):
        check_body(cells, "edge")


def test_bodies_touching_along_an_edge_refused():
    # two diagonal cubes of the bottom layer, joined through the whole top layer
    _, cells = _cubes(2, lambda i, j, k: k == 1 or i == j)
    with pytest.raises(ValueError, match="touch along an edge") as err:
        check_body(cells, "pinched")
    _one_line(err, "mesh")


def test_overlapping_cells_refused():
    _, cells = _cubes(1, lambda i, j, k: True)
    with pytest.raises(ValueError, match="more than two tetrahedra"):
        check_body(np.vstack([cells, cells[:1]]), "twice")
    with pytest.raises(ValueError, match="no tetrahedra"):
        check_body(np.zeros((0, 4), int), "empty")


@pytest.mark.parametrize(
    "kinds,z,result",
    [
        ([TET4, TRI3], 1.0, 3),
        ([TRI3, ElementKind("Line 2", 1, 1, 2)], 0.0, 2),
        ([ElementKind("Tetrahedron 10", 3, 2, 10), ElementKind("Triangle 6", 2, 2, 6)], 1.0, "10"),
        ([ElementKind("Hexahedron 8", 3, 1, 8)], 1.0, "Hexahedron"),
        ([TRI3], 1.0, "surface mesh only"),
        ([ElementKind("Line 2", 1, 1, 2)], 0.0, "no triangles or tetrahedra"),
    ],
)
def test_file_dimension(kinds, z, result):
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, z]], float)
    if isinstance(result, int):
        assert file_dimension(kinds, x, "f") == result
    else:
        with pytest.raises(ValueError, match=result) as err:
            file_dimension(kinds, x, "f")
        _one_line(err, "mesh")


def test_signorini_groups_on_arrays():
    x, cells = _cubes(1, lambda i, j, k: True)
    boundary = boundary_faces(cells)[0]
    z = x[boundary][:, :, 2]
    surfaces = {"bottom": boundary[np.all(z == 0, axis=1)], "7": boundary[np.all(z == 1, axis=1)]}
    # an interior surface group: a face shared by two tetrahedra
    inner = np.sort(cells[:, [[1, 2, 3]]].reshape(-1, 3), axis=1)
    surfaces["middle"] = np.array(
        [f for f in inner if not (np.sort(boundary, 1) == f).all(1).any()]
    )
    check = lambda s: check_signorini_groups(s, surfaces, ["omega"], boundary, "f")  # noqa: E731
    assert check("all") is None
    assert check(["bottom", 7]) == ("bottom", "7")
    for bad, word in (
        (["nope"], "no physical surface group 'nope'"),
        (["omega"], "is a volume, not a surface"),
        (["middle"], "no triangle on the boundary"),
        (["all", "bottom"], "cannot be combined"),
    ):
        with pytest.raises(ValueError, match=word) as err:
            check(bad)
        _one_line(err, "signorini")


# ------------------------------------------------------------------------- on files
@pytest.mark.parametrize("version", [4.1, 2.2])
def test_good_file(tmp_path, version):
    path = solid_msh(tmp_path / "box.msh", version=version)
    assert msh_dimension(path) == 3
    solid = read_tet_msh(path)
    assert solid.x.shape[1] == 3 and solid.cells.shape[1] == 4
    assert set(solid.surfaces) == {"bottom", "7"} and set(solid.volumes) == {"omega"}
    assert len(solid.volumes["omega"]) == len(solid.cells)
    facts, names = check_solid(solid, ["bottom", "7"])
    assert (facts.bodies, facts.surfaces, facts.euler_characteristic) == (1, 1, 2)
    assert names == ("bottom", "7")
    assert np.allclose(solid.x[solid.surfaces["bottom"]][:, :, 2], 0)
    # the surface groups cover the boundary
    boundary = np.sort(boundary_faces(solid.cells)[0], axis=1)
    grouped = np.sort(np.vstack(list(solid.surfaces.values())), axis=1)
    assert len(boundary) == len(grouped)
    assert np.array_equal(np.unique(boundary, axis=0), np.unique(grouped, axis=0))


@pytest.mark.parametrize("version", [4.1, 2.2])
@pytest.mark.parametrize(
    "kind,order,signorini,key,message",
    [
        ("box", 2, (), "mesh", "Tetrahedron 10"),
        ("surface", 1, (), "mesh", "surface mesh only"),
        ("cavity", 1, (), "mesh", "1 cavity"),
        ("two", 1, (), "mesh", "2 separate bodies"),
        ("box", 1, ["contact"], "signorini", "no physical surface group 'contact'"),
        ("box", 1, ["omega"], "signorini", "'omega' .* is a volume, not a surface"),
    ],
)
def test_bad_files(tmp_path, version, kind, order, signorini, key, message):
    path = solid_msh(tmp_path / f"{kind}.msh", kind, h=0.25, version=version, order=order)
    with pytest.raises(ValueError, match=message) as err:
        check_solid(read_tet_msh(path), signorini)
    _one_line(err, key)


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(ValueError, match="not found") as err:
        read_tet_msh(tmp_path / "none.msh")
    _one_line(err, "mesh")
    bad = tmp_path / "bad.msh"
    bad.write_text("not a mesh\n")
    with pytest.raises(ValueError, match="not a gmsh mesh file") as err:
        read_tet_msh(bad)
    _one_line(err, "mesh")


@pytest.mark.parametrize("scale", [1, 10**7])  # int64 codes, then the rows' bytes
def test_row_codes(scale):
    rows = np.array([[1, 2, 3], [3, 2, 1], [1, 2, 3], [0, 0, 0]]) * scale
    codes = row_codes(rows)
    assert codes[0] == codes[2] and len(np.unique(codes)) == 3
