"""Closed test polygons in 2D (nodes (n, 2), counter-clockwise, diameter < 1 so that V is
elliptic: docs/method.md section 2): the regular n-gon, the square and the L-shape, for
the tests and the benchmarks (the 3D counterparts are in ``bem_cpp.surfaces``)."""
from __future__ import annotations

import numpy as np

__all__ = ["R_CIRCLE", "circle", "l_shape", "polygon_nodes", "square"]

R_CIRCLE = 0.4


def circle(n: int, radius: float = R_CIRCLE) -> np.ndarray:
    """Regular n-gon inscribed in the circle |x| = radius, node 0 at angle 0."""
    theta = 2 * np.pi * np.arange(n) / n
    return np.c_[radius * np.cos(theta), radius * np.sin(theta)]


def polygon_nodes(corners: np.ndarray, n: int) -> np.ndarray:
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
    return polygon_nodes(np.array([[-s, -s], [s, -s], [s, s], [-s, s]]), n)


def l_shape(n: int, side: float = 0.6) -> np.ndarray:
    """L-shaped polygon: the square of `side` without its upper right quarter."""
    s = side / 2
    corners = np.array([[-s, -s], [s, -s], [s, 0.0], [0.0, 0.0], [0.0, s], [-s, s]])
    return polygon_nodes(corners, n)
