"""A 3D gmsh file as a distributed mesh with named facet tags
(fem_py.mesh.tet_distribute) and its surface map."""
from __future__ import annotations

import numpy as np
import pytest
from dolfinx import fem
from mpi4py import MPI

from fem_py.mesh.tet_distribute import group_tags, solid_mesh
from fem_py.mesh.tet_file import SolidFile, read_tet_msh
from solid_files import solid_msh

COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module")
def cube(tmp_path_factory):
    return read_tet_msh(solid_msh(tmp_path_factory.mktemp("cube") / "cube.msh", h=0.3))


def test_group_tags(cube):
    facets, values, names = group_tags(cube)
    assert names == {"bottom": 1, "7": 2}
    for key, tag in names.items():
        assert np.sum(values == tag) == len(cube.surfaces[key])
    facets, values, names = group_tags(cube, ["7"])
    assert names == {"7": 1} and np.all(values == 1) and len(facets) == len(cube.surfaces["7"])
    overlapping = SolidFile(
        cube.x, cube.cells, {**cube.surfaces, "again": cube.surfaces["bottom"][:3]}, {}, "f"
    )
    with pytest.raises(ValueError, match="'bottom' and 'again' of f share boundary triangles"):
        group_tags(overlapping)
    with pytest.raises(ValueError, match="no physical surface group 'x'"):
        group_tags(cube, ["x"])
    # the Signorini groups first, then the file's others that overlap none before them
    _, values, names = group_tags(cube, ["7"], others=True)
    assert names == {"7": 1, "bottom": 2} and len(values) == len(facets) + len(
        cube.surfaces["bottom"]
    )
    _, values, names = group_tags(overlapping, ["again"], others=True)
    assert names == {"again": 1, "7": 3}  # "bottom" overlaps "again": left out whole


def test_solid_mesh_and_surface(cube):
    from fem_py.boundary.surface import SurfaceMap

    msh, facet_tags, names = solid_mesh(COMM, cube if COMM.rank == 0 else None)
    assert msh.topology.index_map(3).size_global == len(cube.cells)
    assert msh.topology.index_map(0).size_global == len(cube.x)
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    s = SurfaceMap(V, facet_tags, [names["bottom"]])
    # the unit cube: round-off of sums over the triangles
    assert s.area == pytest.approx(6.0, rel=1e-13) and s.volume == pytest.approx(1.0, rel=1e-13)
    for key, tag in names.items():
        assert np.sum(s.triangle_tags == tag) == len(cube.surfaces[key])
    assert np.allclose(s.triangle_normals[s.triangle_tags == names["bottom"]], [0, 0, -1])
    inside = np.all((s.nodes[:, :2] > 1e-12) & (s.nodes[:, :2] < 1 - 1e-12), axis=1)
    assert np.array_equal(s.signorini, np.flatnonzero(inside & (np.abs(s.nodes[:, 2]) < 1e-12)))
