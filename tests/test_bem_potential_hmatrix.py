"""The potentials as rectangular H-matrices (``bem_cpp.exterior_potential`` with
``compression="hmatrix"`` / ``"auto"``) against the direct panel sums
(docs/design/hmatrix.md, "Potentials").

The admissible blocks are ACA approximations, to the block tolerance tol (relative,
Frobenius), of the same point-panel integrals the direct evaluation sums; the near blocks
are those integrals themselves. The error bound asked of the product is 10 tol relative
to max |u_e| over the points (a sum of O(log) blocks per point, each within tol).
"""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.path import Path

import bem_cpp
from test_bem_exterior import A, u_exact
from test_bem_polygons import circle, l_shape


def exterior_points(X: np.ndarray, near: int, grid: int, seed: int = 3) -> np.ndarray:
    """`near` points at distances 1e-6 ... 1e-2 outside random points of random panels
    (along the outward normal (t_y, -t_x)) and the points of a grid x grid image on
    [-1, 1]^2 outside Omega and at least 1e-9 from Gamma."""
    rng = np.random.default_rng(seed)
    n = len(X)
    j = rng.integers(0, n, near)
    a, b = X[j], X[(j + 1) % n]
    t = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    s = rng.uniform(0.02, 0.98, near)[:, None]
    d = 10.0 ** rng.uniform(-6, -2, near)[:, None]
    Z_near = a + s * (b - a) + d * np.column_stack([t[:, 1], -t[:, 0]])
    g = np.linspace(-1, 1, grid)
    G = np.column_stack([c.ravel() for c in np.meshgrid(g, g)])
    G = G[~Path(X).contains_points(G)]
    # distance to Gamma, panel by panel
    e = np.roll(X, -1, axis=0) - X
    w = np.clip(
        np.einsum("mnk,nk->mn", G[:, None, :] - X[None], e) / np.einsum("nk,nk->n", e, e), 0, 1
    )
    dist = np.linalg.norm(G[:, None, :] - X[None] - w[..., None] * e[None], axis=2).min(axis=1)
    return np.vstack([Z_near, G[dist > 1e-9]])


@pytest.mark.parametrize("make", [circle, l_shape])
@pytest.mark.parametrize("flux", ["p1", "p0"])
@pytest.mark.parametrize("tol", [1e-6, 1e-10])
def test_hmatrix_potential_equals_the_direct_one(make, flux, tol):
    X = make(1200)
    v = u_exact(X)
    psi = bem_cpp.exterior_flux(X, v, a=A, flux=flux)
    Z = exterior_points(X, 1500, 60)
    direct = bem_cpp.exterior_potential(X, v, psi, Z, a=A, flux=flux)
    h = bem_cpp.exterior_potential(X, v, psi, Z, a=A, flux=flux, compression="hmatrix", tol=tol)
    assert np.abs(h - direct).max() <= 10 * tol * np.abs(direct).max()
    # random data (no smoothness to help the blocks)
    rng = np.random.default_rng(1)
    v, psi = rng.standard_normal(len(X)), rng.standard_normal(len(X))
    direct = bem_cpp.exterior_potential(X, v, psi, Z, a=A, flux=flux)
    h = bem_cpp.exterior_potential(X, v, psi, Z, a=A, flux=flux, compression="hmatrix", tol=tol)
    assert np.abs(h - direct).max() <= 10 * tol * np.abs(direct).max()


def test_auto_switches_at_the_crossover(monkeypatch):
    X = circle(400)
    v = u_exact(X)
    psi = bem_cpp.exterior_flux(X, v, a=A)
    Z = exterior_points(X, 200, 40)
    direct = bem_cpp.exterior_potential(X, v, psi, Z, a=A)
    hmatrix = bem_cpp.exterior_potential(X, v, psi, Z, a=A, compression="hmatrix")
    assert not np.array_equal(direct, hmatrix)  # the compressed path does differ in round-off
    # the auto rule: m n >= DOFS m + POINTS n; with POINTS = 0 it switches at DOFS = n
    n = len(X)
    monkeypatch.setattr(bem_cpp.defaults, "HMATRIX_POTENTIAL_CROSSOVER_POINTS", 0)
    monkeypatch.setattr(bem_cpp.defaults, "HMATRIX_POTENTIAL_CROSSOVER_DOFS", n + 1)
    assert np.array_equal(bem_cpp.exterior_potential(X, v, psi, Z, a=A, compression="auto"), direct)
    monkeypatch.setattr(bem_cpp.defaults, "HMATRIX_POTENTIAL_CROSSOVER_DOFS", n)
    auto = bem_cpp.exterior_potential(X, v, psi, Z, a=A, compression="auto")
    assert np.array_equal(auto, hmatrix)


@pytest.mark.parametrize("compression", ["hmatrix", "auto"])
def test_hmatrix_potential_rejects_points_inside(compression):
    X = circle(300)
    with pytest.raises(ValueError, match="inside or on Gamma"):
        bem_cpp.exterior_potential(
            X,
            np.ones(300),
            np.zeros(300),
            np.array([[2.0, 0.0], [0.0, 0.0]]),
            compression=compression,
        )


def test_bad_compression_or_tol():
    X = circle(64)
    with pytest.raises(ValueError, match="compression must be one of"):
        bem_cpp.exterior_potential(X, np.ones(64), np.zeros(64), [[2.0, 0.0]], compression="fmm")
    with pytest.raises(ValueError, match="tol must lie in"):
        bem_cpp.exterior_potential(X, np.ones(64), np.zeros(64), [[2.0, 0.0]], tol=2.0)
