"""The structured box and the gmsh ball of fem_py.mesh (docs/method.md section 11): the
closed-form counts equal the meshed ones, the box written down in parallel is
``create_box``'s with a complete ghost layer on 1, 2 and 3 ranks, the faces are tagged by
name, bad sizes are refused in one line."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from conftest import ROOT, run_mpi
from fem_py.mesh.args3d import signorini_tags
from fem_py.mesh.ball import BALL_FACES, EQUATOR_TAG, ball_mesh, check_ball
from fem_py.mesh.box import BOX_FACES, box_counts, box_mesh, check_box, cubes_per_side

COMM = MPI.COMM_WORLD


def _owned_boundary_vertices(msh) -> int:
    msh.topology.create_connectivity(2, 3)
    v = dmesh.locate_entities_boundary(msh, 0, lambda x: np.full(x.shape[1], True))
    return int(np.sum(v < msh.topology.index_map(0).size_local))


@pytest.mark.parametrize("n", [1, 2, 3, 5])
def test_counts_closed_form_equal_meshed(n):
    width = 0.8
    msh, facet_tags, names = box_mesh(COMM, [0.1, -0.2, 0.3], width, width / n)
    counts = box_counts(n)
    assert cubes_per_side(width, width / n) == n
    assert msh.topology.index_map(3).size_global == counts.cells == 6 * n**3
    assert msh.topology.index_map(0).size_global == counts.vertices
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    assert V.dofmap.index_map.size_global == (n + 1) ** 3
    assert COMM.allreduce(_owned_boundary_vertices(msh)) == counts.boundary_vertices
    msh.topology.create_connectivity(2, 3)
    n_ext = len(dmesh.exterior_facet_indices(msh.topology))  # owned only
    assert COMM.allreduce(n_ext) == counts.boundary_triangles


@pytest.mark.mpi
def test_box_is_create_boxs_on_one_two_and_three_ranks(tmp_path):
    """The same tetrahedra as ``dolfinx.mesh.create_box``, every facet of an owned cell
    inside the box shared with a local (owned or ghost) cell, and the cubes split evenly."""
    for ranks in (1, 2, 3):
        out = tmp_path / f"box{ranks}.json"
        run_mpi(ranks, str(ROOT / "tests" / "mpi" / "box_mesh_check.py"), str(out), timeout=120)
        result = json.loads(out.read_text())
        assert result["ranks"] == ranks
        assert result["same_tetrahedra"] and result["tetrahedra"] == 6 * 5**3
        assert result["open_facets_inside"] == 0
        assert sum(result["owned"]) == 6 * 5**3
        assert max(result["owned"]) - min(result["owned"]) <= 6  # whole cubes, evenly


def test_faces_tagged_by_name():
    n, width = 4, 1.0
    center = np.array([0.5, 0.25, -0.5])
    msh, facet_tags, names = box_mesh(COMM, center, width, width / n)
    assert names == {face: k + 1 for k, face in enumerate(BOX_FACES)}
    owned = facet_tags.indices < msh.topology.index_map(2).size_local
    mid = dmesh.compute_midpoints(msh, 2, facet_tags.indices[owned])
    values = facet_tags.values[owned]
    for face, (axis, side) in BOX_FACES.items():
        here = values == names[face]
        assert COMM.allreduce(int(here.sum())) == 2 * n**2, face
        plane = center[axis] + (side - 0.5) * width
        assert np.allclose(mid[here, axis], plane, atol=1e-14), face
    assert set(BOX_FACES) == {"bottom", "top", "left", "right", "front", "back"}
    assert BOX_FACES["bottom"] == (2, 0) and BOX_FACES["left"] == (0, 0)
    assert BOX_FACES["front"] == (1, 0)


@pytest.mark.parametrize(
    "args,word",
    [
        (([0, 0], 1.0, 0.1), "center"),
        ((["a", 0, 0], 1.0, 0.1), "center"),
        (([0, 0, np.inf], 1.0, 0.1), "center"),
        (([0, 0, 0], -1.0, 0.1), "width"),
        (([0, 0, 0], 1.0, 0.0), "h"),
        (([0, 0, 0], 1.0, "x"), "h"),
    ],
)
def test_bad_box_one_line(args, word):
    with pytest.raises(ValueError) as err:
        check_box(*args)
    assert str(err.value).startswith(word) and "\n" not in str(err.value)


def test_box_counts_refuses_zero():
    with pytest.raises(ValueError, match="at least one cube"):
        box_counts(0)


def test_ball_mesh_tags_and_volume():
    center, radius, h = np.array([0.1, 0.0, -0.2]), 0.5, 0.2
    msh, facet_tags, names = ball_mesh(COMM, center, radius, h)
    assert names == BALL_FACES
    msh.topology.create_connectivity(2, 3)
    exterior = dmesh.exterior_facet_indices(msh.topology)
    mid = dmesh.compute_midpoints(msh, 2, exterior)
    tag = np.zeros(msh.topology.index_map(2).size_local + msh.topology.index_map(2).num_ghosts)
    tag[facet_tags.indices] = facet_tags.values
    t = tag[exterior]
    # every exterior facet is on the sphere and tagged by its hemisphere
    assert np.all(np.isin(t, list(BALL_FACES.values())))
    dz = mid[:, 2] - center[2]
    assert np.all(dz[t == BALL_FACES["bottom"]] < 0) and np.all(dz[t == BALL_FACES["top"]] > 0)
    # the equator disk: interior facets in the plane z = c_z
    inner = facet_tags.indices[facet_tags.values == EQUATOR_TAG]
    assert np.allclose(dmesh.compute_midpoints(msh, 2, inner)[:, 2], center[2], atol=1e-12)
    assert COMM.allreduce(len(inner)) > 0
    # the polyhedron is inscribed: each surface triangle (circumradius rho <= h / sqrt(3))
    # cuts off a cap of height about rho^2 / (2 r), a relative volume of at most (h/r)^2 / 2
    one = fem.form(fem.Constant(msh, 1.0) * ufl.dx)
    volume = COMM.allreduce(fem.assemble_scalar(one), op=MPI.SUM)
    exact = 4 / 3 * math.pi * radius**3
    assert 0 < exact - volume < 0.5 * (h / radius) ** 2 * exact


@pytest.mark.parametrize(
    "args,word",
    [(([0, 0, 0], 0.0, 0.1), "radius"), (([0, 0, 0], 0.5, 1.0), "h"), (([0, 0], 1, 0.1), "center")],
)
def test_bad_ball_one_line(args, word):
    with pytest.raises(ValueError) as err:
        check_ball(*args)
    assert str(err.value).startswith(word) and "\n" not in str(err.value)


def test_signorini_names_to_tags():
    names = {face: k + 1 for k, face in enumerate(BOX_FACES)}
    assert signorini_tags(["top", "bottom", "top"], names) == (1, 2)
    assert signorini_tags("left", names) == (3,)
    assert signorini_tags("all", names) == "all" and signorini_tags([], names) == ()
    assert signorini_tags([7], {"7": 2}) == (2,)
    for bad, word in ((["botom"], "unknown face or group 'botom'"), (["all", "top"], "combined")):
        with pytest.raises(ValueError, match=word) as err:
            signorini_tags(bad, names)
        assert str(err.value).startswith("signorini:") and "\n" not in str(err.value)
