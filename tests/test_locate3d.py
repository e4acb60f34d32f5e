"""Point location in a tetrahedral mesh and on its surface (fem_py.mesh.location3d)
against exact answers: the unit cube cut into six tetrahedra per sub-cube (the Kuhn
split), P1 interpolation exact for linear functions, points outside found nowhere, and
points on the cube's faces found on a surface triangle with barycentric coordinates that
reproduce them."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

import fem_py.mesh.location
import fem_py.mesh.location3d
from fem_py.mesh import interpolate_p1
from fem_py.mesh.location import lattice_weights
from fem_py.mesh.location3d import locate_in_tetrahedra, on_surface


def _cube(n: int):
    g = np.linspace(0.0, 1.0, n + 1)
    x = np.array(list(itertools.product(g, g, g)))
    index = lambda i, j, k: (i * (n + 1) + j) * (n + 1) + k  # noqa: E731
    tets = []
    for i, j, k in itertools.product(range(n), repeat=3):
        for order in itertools.permutations(range(3)):  # the Kuhn split: six tetrahedra
            corner, path = np.array([i, j, k]), [index(i, j, k)]
            for axis in order:
                corner = corner.copy()
                corner[axis] += 1
                path.append(index(*corner))
            tets.append(path)
    return x, np.array(tets)


def _faces(x, tets):
    """The boundary triangles (faces of one tetrahedron only)."""
    faces = np.sort(
        np.concatenate(
            [tets[:, [0, 1, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 3]], tets[:, [1, 2, 3]]]
        ),
        axis=1,
    )
    unique, count = np.unique(faces, axis=0, return_counts=True)
    return unique[count == 1]


def test_points_inside_are_located_and_linear_functions_reproduced():
    x, tets = _cube(3)
    rng = np.random.default_rng(0)
    points = rng.uniform(0.0, 1.0, (500, 3))
    cell, bary = locate_in_tetrahedra(x, tets, points)
    assert np.all(cell >= 0) and np.all(bary >= -1e-12)
    assert np.abs(np.einsum("ij,ijk->ik", bary, x[tets[cell]]) - points).max() <= 1e-14
    values = 1.0 + 2.0 * x[:, 0] - x[:, 1] + 0.5 * x[:, 2]
    exact = 1.0 + 2.0 * points[:, 0] - points[:, 1] + 0.5 * points[:, 2]
    assert np.abs(interpolate_p1(x, tets, values, points) - exact).max() <= 1e-13
    # the nodes themselves, and points outside the cube
    assert np.all(locate_in_tetrahedra(x, tets, x)[0] >= 0)
    outside = np.array([[1.01, 0.5, 0.5], [-0.2, 0.1, 0.1], [0.5, 0.5, 2.0]])
    assert np.all(locate_in_tetrahedra(x, tets, outside)[0] == -1)
    assert np.all(np.isnan(interpolate_p1(x, tets, values, outside)))


def test_points_on_the_surface_are_found_on_a_triangle():
    x, tets = _cube(3)
    surface = _faces(x, tets)
    assert len(surface) == 6 * 2 * 3**2
    rng = np.random.default_rng(1)
    points = rng.uniform(0.0, 1.0, (300, 3))
    points[:, 0] = np.repeat([0.0, 1.0], 150)  # on the faces x = 0 and x = 1
    triangle, bary = on_surface(x, surface, points, 1e-12)
    assert np.all(triangle >= 0)
    assert np.abs(np.einsum("ij,ijk->ik", bary, x[surface[triangle]]) - points).max() <= 1e-14
    # inside, or off the surface by more than the distance: not on it
    off = np.array([[0.5, 0.5, 0.5], [1.0 + 1e-9, 0.5, 0.5], [0.3, 0.3, 1e-6]])
    assert np.all(on_surface(x, surface, off, 1e-12)[0] == -1)


def test_nodes_of_the_refined_cube_are_matched_without_a_point_location(monkeypatch):
    """Every node of the cube with twice the sub-cubes per side (the Kuhn split is nested)
    is a coarse node or a coarse edge midpoint: it takes the mean of the edge's values
    (exact for any P1 field, here a non-linear nodal field) and is found by sorting alone
    (the point location is not called); far points are NaN, also beyond the sorting keys'
    range; a point between the lattice points is located."""
    x, tets = _cube(4)
    values = np.sin(7 * x[:, 0]) + x[:, 1] ** 2 - x[:, 2] * x[:, 0]
    fine, _ = _cube(8)
    cell, bary = locate_in_tetrahedra(x, tets, fine)
    expected = np.einsum("ij,ij->i", bary, values[tets[cell]])
    located = locate_in_tetrahedra

    def no_location(x, tetrahedra, points, **kwargs):
        assert len(points) == 0, f"{len(points)} points were located"
        return located(x, tetrahedra, points, **kwargs)

    monkeypatch.setattr(fem_py.mesh.location, "locate_in_tetrahedra", no_location)
    np.testing.assert_allclose(
        interpolate_p1(x, tets, values, fine, divisions=2), expected, atol=1e-15
    )
    monkeypatch.undo()
    far = np.array([[3.0, 3.0, 0.5], [1e300, 0.0, 0.0], [-2.0, 0.5, 0.5]])
    assert np.isnan(interpolate_p1(x, tets, values, far)).all()
    # points in the bounding box of two separate tetrahedra, in neither's box or in one's
    # box but outside it
    two = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [5, 5, 5], [6, 5, 5]], float)
    two = np.vstack([two, [[5, 6, 5], [5, 5, 6]]])
    pair = np.array([[0, 1, 2, 3], [4, 5, 6, 7]])
    between = np.array([[3.0, 3.0, 3.0]])
    assert locate_in_tetrahedra(two, pair, between)[0].tolist() == [-1]
    corner = np.array([[0.9, 0.9, 0.9], [3.0, 3.0, 3.0], [0.1, 0.1, 0.1]])
    assert locate_in_tetrahedra(two, pair, corner)[0].tolist() == [-1, -1, 0]
    assert locate_in_tetrahedra(two, pair, corner[:1])[0].tolist() == [-1]  # no candidate
    inner = np.array([[0.3, 0.41, 0.77]])
    c, b = locate_in_tetrahedra(x, tets, inner)
    np.testing.assert_allclose(
        interpolate_p1(x, tets, values, inner), b[0] @ values[tets[c[0]]], atol=1e-15
    )


@pytest.mark.parametrize("n", [1, 2, 3])
def test_lattice_weights_of_a_tetrahedron_are_its_non_corner_points(n):
    w = lattice_weights(n, corners=4)
    assert w.shape == ((n + 1) * (n + 2) * (n + 3) // 6 - 4, 4)
    np.testing.assert_allclose(w.sum(axis=1), 1.0)
    assert (w.max(axis=1) < 1.0).all() and len(np.unique(w, axis=0)) == len(w)


@pytest.mark.parametrize("chunk", [7, 1 << 18], ids=["chunked", "whole"])
def test_cells_meeting_a_box_are_those_whose_bounding_boxes_meet_it(chunk, monkeypatch):
    """The cells a section's plane (or any box) meets, tested one coordinate at a time, the
    box's thinnest first, against every cell's bounding box at once."""
    monkeypatch.setattr(fem_py.mesh.location3d, "_CELLS_PER_CHUNK", chunk)
    x, tets = _cube(5)
    x = x * np.array([1.0, 2.0, 0.5])  # unequal extents
    corners = x[tets]
    rng = np.random.default_rng(0)
    boxes = [
        (np.array([0.0, 0.0, 0.21]), np.array([1.0, 2.0, 0.21])),  # a plane z = const
        (np.array([0.3, -1.0, -1.0]), np.array([0.3, 3.0, 1.0])),  # a plane x = const
        (np.array([-1.0, -1.0, -1.0]), np.array([2.0, 3.0, 1.0])),  # all of it
        (np.array([5.0, 5.0, 5.0]), np.array([6.0, 6.0, 6.0])),  # none of it
    ] + [tuple(np.sort(rng.uniform(-0.2, 2.2, (2, 3)), axis=0)) for _ in range(5)]
    for lo, hi in boxes:
        expected = np.flatnonzero(
            ((corners.max(axis=1) >= lo) & (corners.min(axis=1) <= hi)).all(axis=1)
        )
        found = fem_py.mesh.location3d._cells_meeting_box(x, tets, lo, hi)
        np.testing.assert_array_equal(found, expected)
