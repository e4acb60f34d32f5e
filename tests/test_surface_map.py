"""The 3D boundary map fem_py.boundary.surface.SurfaceMap (docs/method.md sections 4, 11):
the surface of the box and of the ball, oriented out of Omega, checked against exact
areas, volumes and normals; the Signorini nodes; T, E, gather and scatter_add; the
refusal of surfaces that are not one closed oriented surface; and the same arrays on 1,
2 and 3 ranks (tests/mpi/surface_map_check.py)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from conftest import ROOT, run_mpi
from fem_py.boundary.surface import SurfaceMap, surface_arrays
from fem_py.mesh.ball import ball_mesh
from fem_py.mesh.box import BOX_FACES, box_counts, box_mesh

COMM = MPI.COMM_WORLD
SCRIPT = ROOT / "tests" / "mpi" / "surface_map_check.py"
CENTER = np.array([0.1, -0.2, 0.3])


def _box(n, width=0.5, signorini=()):
    msh, tags, names = box_mesh(COMM, CENTER, width, width / n)
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    tags_s = "all" if signorini == "all" else [names[f] for f in signorini]
    return V, names, SurfaceMap(V, tags, tags_s)


@pytest.mark.parametrize("n", [1, 3, 6])
def test_box_surface_exact(n):
    width = 0.5
    V, names, s = _box(n, width)
    counts = box_counts(n)
    assert s.n_gamma == counts.boundary_vertices and s.n_triangles == counts.boundary_triangles
    assert s.euler_characteristic == 2
    # round-off of sums of O(n^2) terms of size w^2 / n^2
    assert s.area == pytest.approx(6 * width**2, rel=1e-13)
    assert np.allclose(s.triangle_areas.sum(), s.area, rtol=1e-15)
    assert np.allclose((s.triangle_normals * s.triangle_areas[:, None]).sum(0), 0, atol=1e-15)
    # divergence theorem: sum over triangles of (x . n) area / 3 = |Omega|
    centroid = s.nodes[s.triangles].mean(axis=1)
    flux = np.einsum("ij,ij->i", centroid, s.triangle_normals) * s.triangle_areas
    assert flux.sum() / 3 == pytest.approx(width**3, rel=1e-12)
    assert s.volume == pytest.approx(width**3, rel=1e-12)
    # outward: each triangle's normal is its face's normal
    for face, (axis, side) in BOX_FACES.items():
        on = s.triangle_tags == names[face]
        assert on.sum() == 2 * n**2
        expected = np.zeros(3)
        expected[axis] = 1.0 if side else -1.0
        assert np.allclose(s.triangle_normals[on], expected, atol=1e-14), face
    # nodes: on the box surface, distinct dofs, unit node normals (face normal inside a face)
    r = np.abs(s.nodes - CENTER).max(axis=1)
    assert np.allclose(r, width / 2, atol=1e-15)
    assert len(np.unique(s.dofs)) == s.n_gamma and s.n_dofs == (n + 1) ** 3
    assert np.allclose(np.linalg.norm(s.node_normals, axis=1), 1, atol=1e-15)
    on_faces = (np.abs(np.abs(s.nodes - CENTER) - width / 2) < 1e-12).sum(axis=1) == 1
    axis = np.argmax(np.abs(s.nodes - CENTER), axis=1)
    face_normal = np.zeros_like(s.nodes)
    face_normal[np.arange(s.n_gamma), axis] = np.sign(
        (s.nodes - CENTER)[np.arange(s.n_gamma), axis]
    )
    assert np.allclose(s.node_normals[on_faces], face_normal[on_faces], atol=1e-14)


@pytest.mark.parametrize("n", [2, 4])
def test_signorini_nodes(n):
    width = 0.5
    rel = lambda s: s.nodes[s.signorini] - CENTER  # noqa: E731
    _, _, s = _box(n, width, ["bottom"])
    assert s.n_signorini == (n - 1) ** 2
    p = rel(s)
    assert np.allclose(p[:, 2], -width / 2) and np.all(np.abs(p[:, :2]) < width / 2 - 1e-12)
    assert s.on_signorini.sum() == 2 * n**2
    # two faces sharing an edge: one patch, the shared edge's inner nodes are unknowns
    _, _, s = _box(n, width, ["bottom", "left"])
    assert s.n_signorini == 2 * (n - 1) ** 2 + (n - 1)
    # opposite faces: two patches
    _, _, s = _box(n, width, ["bottom", "top"])
    assert s.n_signorini == 2 * (n - 1) ** 2
    _, _, s = _box(n, width, "all")
    assert np.array_equal(s.signorini, np.arange(s.n_gamma)) and s.on_signorini.all()
    _, _, s = _box(n, width, [])
    assert s.n_signorini == 0


def test_trace_extension_gather_scatter():
    V, _, s = _box(4, 0.5, ["bottom", "right"])
    T, E = s.trace_matrix(), s.extension_matrix()
    assert T.shape == (s.n_gamma, s.n_dofs) and E.shape == (s.n_gamma, s.n_signorini)
    assert (E.T @ E - np.eye(s.n_signorini) == 0).all()
    u = fem.Function(V)
    u.interpolate(lambda x: 1.0 + x[0] + 2 * x[1] + 3 * x[2])
    exact = 1.0 + s.nodes @ np.array([1.0, 2.0, 3.0])
    # round-off of the linear function at the nodes
    assert np.allclose(s.gather(u.vector), exact, rtol=1e-14, atol=1e-14)
    # scatter_add is the transpose of gather: <T u, w> = <u, T^T w>
    w = np.cos(np.arange(s.n_gamma))
    v = u.vector.duplicate()
    v.set(0.0)
    s.scatter_add(w, v)
    assert v.dot(u.vector) == pytest.approx(float(w @ s.gather(u.vector)), rel=1e-13)
    assert np.allclose(s.gather(v), w, rtol=0, atol=0)
    with pytest.raises(ValueError, match="shape"):
        s.scatter_add(w[:-1], v)


def test_interpolate_boundary():
    _, _, s = _box(3)
    x, y, z = s.nodes.T
    assert np.array_equal(s.interpolate_boundary(lambda x, y, z: x + 2 * y - z), x + 2 * y - z)
    values = s.interpolate_boundary(lambda x, y, z, nx, ny, nz: nz)
    assert np.array_equal(values, s.node_normals[:, 2])
    assert np.array_equal(s.interpolate_boundary(2), np.full(s.n_gamma, 2.0))
    # text in x, y, z, nx, ny, nz (issue 31: the data of a 3D run)
    text = s.interpolate_boundary("x + 2*y - z + nz")
    assert np.array_equal(text, x + 2 * y - z + s.node_normals[:, 2])
    with pytest.raises(ValueError, match="text, a number or a callable"):
        s.interpolate_boundary(None)
    with pytest.raises(ValueError, match="not finite"):
        s.interpolate_boundary(lambda x, y, z: np.where(x > 0, np.nan, 0.0))


def test_ball_surface():
    radius, h = 0.5, 0.15
    msh, tags, names = ball_mesh(COMM, CENTER, radius, h)
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    s = SurfaceMap(V, tags, [names["bottom"]])
    assert s.euler_characteristic == 2
    radial = (s.nodes - CENTER) / radius
    assert np.allclose(np.linalg.norm(radial, axis=1), 1, atol=1e-12)
    # inscribed: area and volume below the sphere's, by at most (h/r)^2 / 2 relatively
    # (caps of height rho^2 / (2r) over triangles of circumradius rho <= h / sqrt(3))
    for value, exact in (
        (s.area, 4 * math.pi * radius**2),
        (s.volume, 4 / 3 * math.pi * radius**3),
    ):
        assert 0 < exact - value < 0.5 * (h / radius) ** 2 * exact
    centroid_dir = s.nodes[s.triangles].mean(axis=1) - CENTER
    assert np.all(np.einsum("ij,ij->i", centroid_dir, s.triangle_normals) > 0)
    # node normals tend to the radial direction as h -> 0 (angle O(h / r))
    assert np.all(np.einsum("ij,ij->i", s.node_normals, radial) > math.cos(h / radius))
    # the lower hemisphere: unknowns strictly below the equator
    assert np.all(s.nodes[s.signorini, 2] < CENTER[2]) and s.n_signorini > 0
    equator = np.abs(s.nodes[:, 2] - CENTER[2]) < 1e-12
    assert equator.any() and not np.isin(np.flatnonzero(equator), s.signorini).any()


# ------------------------------------------------------------- pure checks of the surface
def _tetrahedron(shift=0.0):
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) + shift
    tri = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])  # outward
    return tri, x


def _arrays(tri, x, offset=0):
    tri = np.asarray(tri) + offset
    return tri, tri, np.asarray(x)[tri - offset], np.zeros(len(tri), int)


def test_tetrahedron_surface():
    tri, x = _tetrahedron()
    out = surface_arrays(*_arrays(tri, x), (), 4)
    assert out["volume"] == pytest.approx(1 / 6, rel=1e-15)
    assert out["area"] == pytest.approx(1.5 + math.sqrt(3) / 2, rel=1e-15)
    assert out["euler_characteristic"] == 2


@pytest.mark.parametrize(
    "change,message",
    [
        (lambda t: t[1:], "not closed"),
        (lambda t: np.vstack([t[:1, ::-1], t[1:]]), "consistently oriented"),
        (lambda t: t[:, ::-1], "oriented into Omega"),
        (lambda t: np.vstack([t, t[:1]]), "consistently oriented"),
    ],
)
def test_bad_surfaces(change, message):
    tri, x = _tetrahedron()
    bad = change(tri)
    with pytest.raises(ValueError, match=message):
        surface_arrays(*_arrays(bad, x), (), 4)


def test_two_surfaces_refused():
    tri, x = _tetrahedron()
    tri2, x2 = _tetrahedron(shift=3.0)
    a = _arrays(tri, x)
    b = _arrays(tri2, x2, offset=4)
    joined = [np.concatenate([p, q]) for p, q in zip(a, b)]
    with pytest.raises(ValueError, match="2 separate surfaces"):
        surface_arrays(*joined, (), 8)


def test_missing_signorini_tag():
    tri, x = _tetrahedron()
    with pytest.raises(ValueError, match="facet tag 7 is on no boundary triangle"):
        surface_arrays(*_arrays(tri, x), (7,), 4)


def test_needs_tetrahedra_and_p1():
    square = dmesh.create_unit_square(COMM, 2, 2)
    with pytest.raises(ValueError, match="linear tetrahedra"):
        SurfaceMap(fem.FunctionSpace(square, ("Lagrange", 1)), None)
    V, _, _ = _box(1)
    with pytest.raises(ValueError, match="scalar P1"):
        SurfaceMap(fem.FunctionSpace(V.mesh, ("Lagrange", 2)), None)


def test_bad_signorini_argument():
    V, _, _ = _box(1)
    with pytest.raises(ValueError, match="facet tags"):
        SurfaceMap(V, None, "bottom")
    with pytest.raises(ValueError, match="facet tags"):
        SurfaceMap(V, None, [1.5])


# ------------------------------------------------------------------- 1 rank = 2 ranks
@pytest.mark.mpi
def test_one_rank_equals_two_and_three(tmp_path):
    result = {}
    for ranks in (1, 2, 3):
        out = tmp_path / f"surface{ranks}.json"
        run_mpi(ranks, str(SCRIPT), str(out), timeout=240)
        result[ranks] = json.loads(out.read_text())
    ser = result[1]
    for ranks, par in ((2, result[2]), (3, result[3])):
        _assert_same(ser, par, ranks)


def _assert_same(ser, par, ranks):
    assert set(par) == set(ser)
    for name in ser:
        p, s = par[name], ser[name]
        assert p["ranks"] == ranks and s["ranks"] == 1
        # integer arrays and the coordinates (copies of the mesh input): equal
        for key in ("nodes", "triangles", "triangle_tags", "signorini", "on_signorini"):
            assert np.array_equal(p[key], s[key]), (name, key)
        # computed on rank 0 from equal arrays in the same order: equal
        for key in ("node_normals", "triangle_normals", "triangle_areas", "area", "volume"):
            assert np.array_equal(p[key], s[key]), (name, key)
        # gather/scatter_add through the partition's own dof numbers: the values at the
        # nodes (round-off of the interpolation), and T^T T 1 counted once per node
        assert np.allclose(p["trace"], s["trace"], rtol=1e-14, atol=1e-14), name
        assert p["scatter_sum"] == s["scatter_sum"] == len(s["nodes"]), name
    refused = par["box"]["refused_everywhere"]
    assert len(refused) == ranks and len(set(refused)) == 1
    assert refused[0].startswith("signorini: facet tag 99 is on no boundary triangle")
