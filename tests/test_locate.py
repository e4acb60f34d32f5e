"""Point location in a triangle mesh (fem_py.mesh.location) against exact answers: nodes and
random points of a structured mesh of the unit square, P1 interpolation exact for
linear functions, points outside found in no triangle."""
from __future__ import annotations

import numpy as np
import pytest

import fem_py.mesh.location
from fem_py.mesh import interpolate_p1, locate
from fem_py.mesh.location import lattice_weights


def _mesh(n: int):
    g = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(g, g, indexing="ij")
    x = np.column_stack([X.ravel(), Y.ravel()])
    i, j = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
    p = lambda a, b: a * (n + 1) + b  # noqa: E731
    tris = np.concatenate(
        [
            np.stack([p(i, j), p(i + 1, j), p(i + 1, j + 1)], 1),
            np.stack([p(i, j), p(i + 1, j + 1), p(i, j + 1)], 1),
        ]
    )
    return x, tris


@pytest.mark.parametrize("max_candidates", [64, 0])  # 0: the k-d tree candidates
def test_random_points_are_in_the_triangle_that_holds_them(max_candidates, monkeypatch):
    monkeypatch.setattr(fem_py.mesh.location, "LOCATE_MAX_CANDIDATES", max_candidates)
    x, tris = _mesh(16)
    pts = np.random.default_rng(0).uniform(0, 1, (500, 2))
    cell, bary = locate(x, tris, pts)
    assert (cell >= 0).all() and (bary >= -1e-12).all()
    np.testing.assert_allclose(np.einsum("ij,ijk->ik", bary, x[tris[cell]]), pts, atol=1e-14)


def test_linear_functions_interpolate_exactly_and_outside_is_nan():
    x, tris = _mesh(8)
    f = lambda p: 1.0 + 2.0 * p[:, 0] - 3.0 * p[:, 1]  # noqa: E731
    pts = np.vstack(
        [np.random.default_rng(1).uniform(0, 1, (200, 2)), x, [[1.5, 0.5], [-0.1, 0.2]]]
    )
    values = interpolate_p1(x, tris, f(x), pts)
    np.testing.assert_allclose(values[:-2], f(pts[:-2]), atol=1e-13)
    assert np.isnan(values[-2:]).all()


@pytest.mark.parametrize("divisions", [2, 3, 4])
def test_nodes_of_the_uniform_refinement_are_matched_without_a_point_location(
    divisions, monkeypatch
):
    """Every node of the n-fold refined mesh is a node or a lattice point (i a + j b + l c)
    / n of a coarse triangle: it takes that combination of the corner values (exact for
    any P1 field, here a non-linear nodal field) and is found by sorting alone (the point
    location is not called for any point); far points are NaN, also beyond the range of
    the sorting keys."""
    x, tris = _mesh(8)
    values = np.sin(7 * x[:, 0]) + x[:, 1] ** 2
    fine, _ = _mesh(8 * divisions)
    cell, bary = locate(x, tris, fine)
    expected = np.einsum("ij,ij->i", bary, values[tris[cell]])

    def no_location(x, triangles, points, **kwargs):
        assert len(points) == 0, f"{len(points)} points were located"
        return locate(x, triangles, points, **kwargs)

    monkeypatch.setattr(fem_py.mesh.location, "locate", no_location)
    got = interpolate_p1(x, tris, values, fine, divisions=divisions)
    np.testing.assert_allclose(got, expected, atol=1e-15)
    monkeypatch.undo()
    far = np.array([[3.0, 3.0], [1.0, 3.5], [1e300, 0.0], [-2.0, 0.5]])
    assert np.isnan(interpolate_p1(x, tris, values, far, divisions=divisions)).all()


def test_lattice_weights_are_the_non_corner_points():
    for n in (1, 2, 4):
        w = lattice_weights(n)
        assert w.shape == ((n + 1) * (n + 2) // 2 - 3, 3)
        np.testing.assert_allclose(w.sum(axis=1), 1.0)
        assert (w.max(axis=1) < 1.0).all() and len(np.unique(w, axis=0)) == len(w)
