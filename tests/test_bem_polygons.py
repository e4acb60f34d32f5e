"""Test polygons for the bem_cpp tests (imported by the other test_bem_* modules), and
checks that they are what the tests assume: simple, counter-clockwise, diameter < 1
(so the logarithmic capacity is below 1 and V is elliptic, docs/method.md section 2)."""
from __future__ import annotations

import numpy as np
import pytest

import bem_cpp

R_CIRCLE = 0.4


def circle(n: int, radius: float = R_CIRCLE) -> np.ndarray:
    """Regular n-gon inscribed in the circle |x| = radius, node 0 at angle 0."""
    theta = 2 * np.pi * np.arange(n) / n
    return np.c_[radius * np.cos(theta), radius * np.sin(theta)]


def _refine(corners: np.ndarray, n: int) -> np.ndarray:
    """Nodes on the closed polygon `corners`, about n in total, uniform on each side."""
    sides = np.roll(corners, -1, axis=0) - corners
    lengths = np.linalg.norm(sides, axis=1)
    h = lengths.sum() / n
    nodes = []
    for a, side, length in zip(corners, sides, lengths):
        k = max(1, int(round(length / h)))
        nodes += [a + side * i / k for i in range(k)]
    return np.array(nodes)


def square(n: int, side: float = 0.6) -> np.ndarray:
    """Square centred at the origin, n/4 panels per side."""
    s = side / 2
    return _refine(np.array([[-s, -s], [s, -s], [s, s], [-s, s]]), n)


def l_shape(n: int, side: float = 0.6) -> np.ndarray:
    """L-shaped polygon: the square of `side` without its upper right quarter."""
    s = side / 2
    corners = np.array([[-s, -s], [s, -s], [s, 0.0], [0.0, 0.0], [0.0, s], [-s, s]])
    return _refine(corners, n)


def signed_area(nodes: np.ndarray) -> float:
    x, y = nodes[:, 0], nodes[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def diameter(nodes: np.ndarray) -> float:
    return float(np.max(np.linalg.norm(nodes[:, None, :] - nodes[None, :, :], axis=-1)))


@pytest.mark.parametrize("make", [circle, square, l_shape])
@pytest.mark.parametrize("n", [24, 96])
def test_polygons_are_valid_inputs(make, n):
    nodes = make(n)
    assert signed_area(nodes) > 0
    assert diameter(nodes) < 1
    # The library accepts them (validation passes) and the mass matrix sums to |Gamma|.
    perimeter = np.linalg.norm(np.roll(nodes, -1, axis=0) - nodes, axis=1).sum()
    assert bem_cpp.mass(nodes, "p1").sum() == pytest.approx(perimeter, rel=1e-14)
    assert bem_cpp.mass(nodes, "p0").sum() == pytest.approx(perimeter, rel=1e-14)
