"""Bad input raises ValueError with a one-line message naming the problem and the fix."""
from __future__ import annotations

import numpy as np
import pytest

import bem_cpp
from test_bem_polygons import circle, square

SQUARE = square(8)
GOOD_V = np.zeros(len(SQUARE))


@pytest.mark.parametrize(
    "nodes,message",
    [
        (np.array([[0.0, 0.0], [0.5, 0.0]]), r"at least 3 nodes, got 2"),
        (np.zeros((4, 3)), r"nodes must have shape \(n, 2\), got \(4, 3\)"),
        (np.zeros(8), r"nodes must have shape \(n, 2\), got \(8,\)"),
        ([["a", "b"], ["c", "d"], ["e", "f"]], r"nodes must be a real \(n, 2\) array"),
        (np.array([[0.0, 0.0], [0.5, np.nan], [0.0, 0.5]]), r"node 1 has a non-finite coordinate"),
        (np.array([[0.0, 0.0], [0.5, 0.0], [0.5, 0.0], [0.0, 0.5]]), r"nodes 1 and 2 coincide"),
        (
            np.array([[0.0, 0.0], [0.5, 0.0], [0.0, 0.5], [0.0, 0.0]]),
            r"last node 3 repeats the first node",
        ),
        (circle(16)[::-1], r"ordered clockwise \(signed area -0\.4"),
        (
            np.array([[0.0, 0.0], [0.5, 0.5], [0.5, 0.0], [0.0, 0.5]]),
            r"self-intersecting \(panels 0 and 2 intersect\)",
        ),
        (np.array([[0.0, 0.0], [0.5, 0.0], [0.25, 0.0], [0.25, 0.3]]), r"panels 0 and 1 fold back"),
        # a node touching a non-adjacent panel is an intersection too
        (
            np.array([[0.0, 0.0], [0.6, 0.0], [0.6, 0.4], [0.3, 0.0], [0.0, 0.4]]),
            r"self-intersecting",
        ),
    ],
)
@pytest.mark.parametrize(
    "call",
    [
        lambda X: bem_cpp.single_layer(X),
        lambda X: bem_cpp.double_layer(X, "p0"),
        lambda X: bem_cpp.hypersingular(X),
        lambda X: bem_cpp.mass(X),
        lambda X: bem_cpp.steklov_poincare(X),
        lambda X: bem_cpp.exterior_flux(X, np.zeros(np.shape(X)[0])),
    ],
)
def test_invalid_polygons(call, nodes, message):
    with pytest.raises(ValueError, match=message) as info:
        call(nodes)
    assert "\n" not in str(info.value)


def test_self_intersection_found_in_a_large_polygon():
    """The sweep checks all non-adjacent pairs; a crossing far along the list is found.
    exterior_potential is O(n) per point, so a large polygon is cheap to validate."""
    X = circle(100_000)
    X[50_000] = X[0] + [0.01, 0.0]  # node 50000 jumps across the disc, just past node 0
    v = np.zeros(len(X))
    with pytest.raises(ValueError, match=r"self-intersecting"):
        bem_cpp.exterior_potential(X, v, v, [[2.0, 0.0]])


@pytest.mark.parametrize("flux", ["p1", "p0"])
def test_large_domain_is_rejected(flux):
    """R = 2: V 1 = -2 R log R < 0, V_h is not positive definite (capacity >= 1)."""
    X = circle(64, radius=2.0)
    message = (
        r"V_h is not positive definite.*logarithmic capacity of Gamma is >= 1.*rescale the geometry"
    )
    with pytest.raises(ValueError, match=message):
        bem_cpp.steklov_poincare(X, flux)
    with pytest.raises(ValueError, match=message):
        bem_cpp.exterior_flux(X, np.ones(64), flux=flux)


@pytest.mark.parametrize(
    "call,message",
    [
        (lambda: bem_cpp.single_layer(SQUARE, "p2"), r"space must be 'p0' or 'p1', got 'p2'"),
        (
            lambda: bem_cpp.steklov_poincare(SQUARE, flux=None),
            r"flux must be 'p0' or 'p1', got None",
        ),
        (lambda: bem_cpp.exterior_flux(SQUARE, np.zeros(3)), r"dirichlet must have shape \(8,\)"),
        (
            lambda: bem_cpp.exterior_flux(SQUARE, GOOD_V + np.inf),
            r"dirichlet contains non-finite values",
        ),
        (lambda: bem_cpp.exterior_flux(SQUARE, GOOD_V, a=np.nan), r"a must be finite"),
        (lambda: bem_cpp.exterior_flux(SQUARE, GOOD_V, a="x"), r"a must be a real number"),
        (
            lambda: bem_cpp.exterior_potential(SQUARE, GOOD_V, GOOD_V[:-1], [[1.0, 1.0]]),
            r"flux_coefficients must have shape \(8,\)",
        ),
        (
            lambda: bem_cpp.exterior_potential(SQUARE, GOOD_V, GOOD_V, [1.0, 1.0]),
            r"points must have shape \(m, 2\)",
        ),
        (
            lambda: bem_cpp.exterior_potential(SQUARE, GOOD_V, GOOD_V, [[np.nan, 1.0]]),
            r"points contains non-finite",
        ),
    ],
)
def test_invalid_arguments(call, message):
    with pytest.raises(ValueError, match=message):
        call()
