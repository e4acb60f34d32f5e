"""Exterior Dirichlet-to-Neumann map and representation formula (docs/method.md section 2).

Manufactured exterior solution, harmonic outside x0 (inside Omega):
    u_e(x) = a + b log|x - x0| + c.(x - x0)/|x - x0|^2,
which behaves like a + b log|x| + o(1) at infinity (docs/method.md section 1, note on (1.3)).
The polygon itself is the geometry, so v = u_e at the nodes is exact data up to P1
interpolation.

Expected orders (measured in brackets):
- flux psi_h -> du_e/dn in L2(Gamma): O(h) for p0 (best approximation) and for p1 on the
  inscribed circle polygon, whose exact flux jumps by O(h) at every node [1.0]; O(h^1/2)
  for p1 on the square and L-shape, where the exact flux jumps by O(1) at the corners
  and a continuous flux cannot follow [0.5];
- potential at fixed exterior points: O(h^2) [2.0], and the same O(h^2) uniformly up to
  Gamma thanks to the analytic panel integrals [2.0 at distance 1e-6].
"""
from __future__ import annotations

import numpy as np
import pytest

import bem_cpp
from test_bem_operators import mesh_size, observed_order
from test_bem_polygons import circle, l_shape, square

X0 = np.array([-0.1, -0.08])
A, B, C = 0.3, 0.7, np.array([0.2, -0.1])
POINTS = np.array([[0.7, 0.1], [-0.5, 0.6], [0.1, -0.9], [2.0, 3.0]])


def u_exact(x: np.ndarray) -> np.ndarray:
    d = x - X0
    r2 = (d**2).sum(-1)
    return A + 0.5 * B * np.log(r2) + (d @ C) / r2


def grad_exact(x: np.ndarray) -> np.ndarray:
    d = x - X0
    r2 = (d**2).sum(-1)[..., None]
    return B * d / r2 + C / r2 - 2 * (d @ C)[..., None] * d / r2**2


def flux_l2_error(nodes: np.ndarray, psi: np.ndarray, flux: str) -> float:
    """||psi_h - grad u_e . n||_{L2(Gamma)} by an 8-point Gauss rule on every panel."""
    g, w = np.polynomial.legendre.leggauss(8)
    g, w = (g + 1) / 2, w / 2
    a, b = nodes, np.roll(nodes, -1, axis=0)
    h = np.linalg.norm(b - a, axis=1)
    t = (b - a) / h[:, None]
    normal = np.c_[t[:, 1], -t[:, 0]]
    points = a[:, None, :] + g[None, :, None] * (b - a)[:, None, :]
    exact = np.einsum("pqk,pk->pq", grad_exact(points), normal)
    if flux == "p1":
        approx = psi[:, None] * (1 - g) + np.roll(psi, -1)[:, None] * g
    else:
        approx = np.repeat(psi[:, None], len(g), axis=1)
    return float(np.sqrt(np.sum(h[:, None] * w * (approx - exact) ** 2)))


CASES = [
    (circle, "p1", 0.9),
    (circle, "p0", 0.9),
    (square, "p1", 0.45),
    (square, "p0", 0.9),
    (l_shape, "p1", 0.45),
    (l_shape, "p0", 0.9),
]


@pytest.mark.parametrize("make,flux,flux_order", CASES)
def test_flux_and_potential_converge(make, flux, flux_order):
    flux_errors, potential_errors, h = [], [], []
    for n in (36, 72, 144, 288):
        X = make(n)
        v = u_exact(X)
        psi = bem_cpp.exterior_flux(X, v, a=A, flux=flux)
        flux_errors.append(flux_l2_error(X, psi, flux))
        u_h = bem_cpp.exterior_potential(X, v, psi, POINTS, a=A, flux=flux)
        potential_errors.append(np.abs(u_h - u_exact(POINTS)).max())
        h.append(mesh_size(X))
    assert observed_order(h, flux_errors) >= flux_order
    assert observed_order(h, potential_errors) >= 1.9


@pytest.mark.parametrize("flux", ["p1", "p0"])
def test_total_flux_gives_the_log_coefficient(flux):
    """b = (1/2pi) int psi ds: the log|x| growth of u_e is carried by the total flux;
    the integral converges at O(h^2) (measured 2.0), faster than psi itself."""
    errors, h = [], []
    for n in (64, 256):
        X = circle(n)
        psi = bem_cpp.exterior_flux(X, u_exact(X), a=A, flux=flux)
        total = bem_cpp.mass(X, flux).sum(axis=1) @ psi  # int psi ds
        errors.append(abs(total / (2 * np.pi) - B))
        h.append(mesh_size(X))
    assert observed_order(h, errors) >= 1.8


@pytest.mark.parametrize("flux", ["p1", "p0"])
def test_potential_near_gamma(flux):
    """Points at distance d = 1e-1 ... 1e-9 from Gamma (off a panel midpoint, off a
    node, off a point at 1/10 of a panel): the error stays at the O(h^2) level of the
    discrete trace (at most 2x its value at d = 0.1) and converges at O(h^2) there."""
    errors = {}
    for n in (64, 256):
        X = circle(n)
        v = u_exact(X)
        psi = bem_cpp.exterior_flux(X, v, a=A, flux=flux)
        j = n // 3
        a, b = X[j], X[j + 1]
        t = (b - a) / np.linalg.norm(b - a)
        normal = np.array([t[1], -t[0]])
        bisector = a / np.linalg.norm(a)
        for d in (1e-1, 1e-3, 1e-6, 1e-9):
            Z = np.array(
                [(a + b) / 2 + d * normal, a + d * bisector, a + 0.1 * (b - a) + d * normal]
            )
            errors[n, d] = np.abs(
                bem_cpp.exterior_potential(X, v, psi, Z, a=A, flux=flux) - u_exact(Z)
            ).max()
    for n in (64, 256):
        assert max(errors[n, d] for d in (1e-3, 1e-6, 1e-9)) <= 2 * errors[n, 1e-1]
    h = [mesh_size(circle(n)) for n in (64, 256)]
    assert observed_order(h, [errors[64, 1e-6], errors[256, 1e-6]]) >= 1.8


@pytest.mark.parametrize("flux", ["p1", "p0"])
def test_points_inside_or_on_gamma_are_rejected(flux):
    X = square(40)
    v = u_exact(X)
    psi = bem_cpp.exterior_flux(X, v, a=A, flux=flux)
    with pytest.raises(ValueError, match=r"points: 1 of the 2 points lie inside or on Gamma"):
        bem_cpp.exterior_potential(X, v, psi, [[0.7, 0.0], [0.1, 0.1]], a=A, flux=flux)
    with pytest.raises(ValueError, match=r"inside or on Gamma \(first: point 0"):
        bem_cpp.exterior_potential(X, v, psi, [X[3], [0.7, 0.0]], a=A, flux=flux)
    with pytest.raises(ValueError, match=r"inside or on Gamma"):
        bem_cpp.exterior_potential(X, v, psi, [[0.3, 0.05]], a=A, flux=flux)  # on a side
