"""The test polygons of ``bem_cpp.polygons`` (imported by the other test_bem_* modules from
here), and checks that they are what the tests assume: simple, counter-clockwise, diameter < 1
(so the logarithmic capacity is below 1 and V is elliptic, docs/method.md section 2)."""
from __future__ import annotations

import numpy as np
import pytest

import bem_cpp
from bem_cpp.polygons import R_CIRCLE, circle, l_shape, square  # noqa: F401 (used by test_bem_*)


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
