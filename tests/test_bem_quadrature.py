"""Matrix entries of V_h (p0, p1) and K_h (p0, p1) against a 30-digit mpmath reference.

Reference: for every panel pair, the inner integral over panel j in closed form (the
textbook antiderivatives of log(u^2 + d^2) and d/(u^2 + d^2) against 1 and u, evaluated
at 30 digits), the outer integral over panel i by tanh-sinh quadrature (which is exact
for the end-point log singularities of coincident and adjacent pairs), each half of the
panel parametrised from its own end node so that the clustering nodes keep full
relative precision; levels are refined until two agree to 1e-16 in every component
(tanh-sinh doubles the correct digits per level, so the last level is good to ~1e-30).
This shares nothing with the library's methods (closed-form Duffy formulas for
coincident/adjacent pairs, point-panel moments for near pairs, tensor Gauss rules for
far pairs).

Entries must agree to 1e-12 relative (entries far below the matrix scale, e.g. of K
between nearly collinear panels, relative to 1e-6 of the largest entry). Measured worst
cases (V / K): octagon 5e-16 / 7e-15, triangles with angles 1 ... 179 degrees 7e-16 /
7e-15, far pairs on the circle 5e-16 / 7e-15, sliver (panel lengths differing by a
factor 5800, sides 1.7e-4 apart) 1.3e-14 / 3.4e-13.
"""
from __future__ import annotations

import numpy as np
import pytest
from mpmath import mp
from mpmath.calculus.quadrature import TanhSinh

import bem_cpp
from test_bem_polygons import circle

mp.dps = 30
_TANH_SINH = TanhSinh(mp)
TOL = 1e-12


def _vquad(f, a, b):
    """Tanh-sinh quadrature of the vector-valued f on [a, b]."""
    prev = None
    for degree in range(1, 12):
        step = mp.mpf(2) ** (-degree)
        acc = [p / (2 * step) for p in prev] if prev else None
        for x, w in _TANH_SINH.get_nodes(a, b, degree, mp.prec):
            fx = f(x)
            acc = [w * v for v in fx] if acc is None else [s + w * v for s, v in zip(acc, fx)]
        res = [step * s for s in acc]
        if prev is not None and degree >= 3:
            floor = mp.mpf(10) ** -8 * max(abs(r) for r in res)  # exact zeros (collinear K)
            if all(abs(r - p) <= mp.mpf(10) ** -16 * max(abs(r), floor) for r, p in zip(res, prev)):
                return res
        prev = res
    raise RuntimeError("reference quadrature did not converge")


def _panel(a, b):
    a = [mp.mpf(float(a[0])), mp.mpf(float(a[1]))]
    b = [mp.mpf(float(b[0])), mp.mpf(float(b[1]))]
    h = mp.sqrt((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2)
    t = [(b[0] - a[0]) / h, (b[1] - a[1]) / h]
    return {"a": a, "b": b, "h": h, "t": t, "n": [t[1], -t[0]]}


def _inner(base, offset, Q, on_line):
    """int_Q log|x - y| phi_b(y) and int_Q (x - y).n_Q/|x - y|^2 phi_b(y), b = 0, 1, at
    x = base + offset (x - a_Q formed as (base - a_Q) + offset, exact for node bases)."""
    h, t, n = Q["h"], Q["t"], Q["n"]
    q = [(base[0] - Q["a"][0]) + offset[0], (base[1] - Q["a"][1]) + offset[1]]
    qe = [(base[0] - Q["b"][0]) + offset[0], (base[1] - Q["b"][1]) + offset[1]]
    tau = q[0] * t[0] + q[1] * t[1]
    d = mp.zero if on_line else q[0] * n[0] + q[1] * n[1]
    u0, u1 = -tau, -(qe[0] * t[0] + qe[1] * t[1])

    def f0(u):  # int log sqrt(u^2 + d^2) du
        if d == 0:
            return u * mp.log(abs(u)) - u if u != 0 else mp.zero
        return u / 2 * mp.log(u * u + d * d) - u + d * mp.atan(u / d)

    def f1(u):  # int u log sqrt(u^2 + d^2) du
        r2 = u * u + d * d
        return (r2 * mp.log(r2) - u * u) / 4 if r2 != 0 else mp.zero

    i0 = f0(u1) - f0(u0)
    i1 = f1(u1) - f1(u0) + tau * i0  # int t log, t = u + tau
    if d == 0:
        a0 = a1 = mp.zero
    else:
        a0 = mp.atan(u1 / d) - mp.atan(u0 / d)
        a1 = d / 2 * (mp.log(u1 * u1 + d * d) - mp.log(u0 * u0 + d * d)) + tau * a0
    return (i0 - i1 / h, i1 / h), (a0 - a1 / h, a1 / h)


def _outer(P, Q, on_line):
    h, t = P["h"], P["t"]

    def from_a(s):
        (l0, l1), (k0, k1) = _inner(P["a"], [s * t[0], s * t[1]], Q, on_line)
        p0, p1 = 1 - s / h, s / h
        return [p0 * l0, p0 * l1, p1 * l0, p1 * l1, p0 * k0, p0 * k1, p1 * k0, p1 * k1]

    def from_b(s):
        (l0, l1), (k0, k1) = _inner(P["b"], [-s * t[0], -s * t[1]], Q, on_line)
        p0, p1 = s / h, 1 - s / h
        return [p0 * l0, p0 * l1, p1 * l0, p1 * l1, p0 * k0, p0 * k1, p1 * k0, p1 * k1]

    r = [x + y for x, y in zip(_vquad(from_a, mp.zero, h / 2), _vquad(from_b, mp.zero, h / 2))]
    return np.array(r[:4], dtype=object).reshape(2, 2), np.array(r[4:], dtype=object).reshape(2, 2)


class Reference:
    """Pair blocks v[a][b] = int_i int_j log|x-y| phi_a phi_b and
    k[a][b] = int_i int_j (x-y).n_j/|x-y|^2 phi_a phi_b for ordered pairs, cached."""

    def __init__(self, nodes):
        self.nodes = np.asarray(nodes)
        self.n = len(nodes)
        self.cache = {}

    def _pair(self, i, j):
        n = self.n
        key = (min(i, j), max(i, j))
        if key not in self.cache:
            P = _panel(self.nodes[key[0]], self.nodes[(key[0] + 1) % n])
            Q = _panel(self.nodes[key[1]], self.nodes[(key[1] + 1) % n])
            same = key[0] == key[1]
            v, kij = _outer(P, Q, same)
            _, kji = _outer(Q, P, same)
            self.cache[key] = (v, kij, kji)
        v, kij, kji = self.cache[key]
        return (v, kij) if i <= j else (v.T, kji)

    def v0(self, i, j):
        return -self._pair(i, j)[0].sum() / mp.pi

    def k0(self, i, c):
        n = self.n
        _, k_prev = self._pair(i, (c - 1) % n)
        _, k_this = self._pair(i, c)
        return (k_prev[:, 1].sum() + k_this[:, 0].sum()) / mp.pi

    def _p1(self, r, c, which):
        n = self.n
        total = mp.zero
        for i, a in (((r - 1) % n, 1), (r, 0)):
            for j, b in (((c - 1) % n, 1), (c, 0)):
                total += self._pair(i, j)[which][a, b]
        return total

    def v1(self, r, c):
        return -self._p1(r, c, 0) / mp.pi

    def k1(self, r, c):
        return self._p1(r, c, 1) / mp.pi


def relative_errors(computed, reference, entries):
    ref = np.array([float(reference(r, c)) for r, c in entries])
    got = np.array([computed[r, c] for r, c in entries])
    scale = 1e-6 * np.abs(ref).max()
    return np.abs(got - ref) / np.maximum(np.abs(ref), scale)


def pair_kind(i, j, n):
    d = abs(i - j)
    return "coincident" if d == 0 else "adjacent" if d in (1, n - 1) else "separated"


# Interior angles 71.6, 180 (exactly collinear), 178.65, 21.3 (sharp), 310.7 (reflex),
# 34.9, 99.1, 183.8 degrees; panel lengths 0.13 ... 0.52.
OCTAGON = np.array(
    [
        [0, 0],
        [0.25, 0],
        [0.5, 0],
        [0.62, 0.004],
        [0.3, 0.12],
        [0.62, 0.3],
        [0.1, 0.35],
        [0.04, 0.12],
    ]
)
# Thin quadrilateral: two panels of length 1e-4 far apart (tensor Gauss with 2 points),
# adjacent panels with length ratio 5800, long sides 1.7e-4 apart (subdivided near field).
SLIVER = np.array([[0, 0], [1e-4, 0], [0.5, 0.3], [0.5 - 1e-4, 0.3]])


@pytest.mark.parametrize("nodes", [OCTAGON, SLIVER], ids=["octagon", "sliver"])
def test_all_entries_against_mpmath(nodes):
    n = len(nodes)
    ref = Reference(nodes)
    entries = [(r, c) for r in range(n) for c in range(n)]
    checks = [
        (bem_cpp.single_layer(nodes, "p0"), ref.v0),
        (bem_cpp.single_layer(nodes, "p1"), ref.v1),
        (bem_cpp.double_layer(nodes, "p0"), ref.k0),
        (bem_cpp.double_layer(nodes, "p1"), ref.k1),
    ]
    for computed, reference in checks:
        assert relative_errors(computed, reference, entries).max() < TOL
    # Panels 0 and 1 of the octagon are exactly collinear: the hat of node 1 lives on
    # them only, so its K entries against them vanish exactly.
    if nodes is OCTAGON:
        K = bem_cpp.double_layer(nodes, "p0")
        assert K[0, 1] == 0.0 and K[1, 1] == 0.0


def test_adjacent_pairs_at_many_angles():
    """Triangles with the given angle between two sides of the given length ratio: every
    pair of panels of a triangle is coincident or adjacent."""
    entries = [(r, c) for r in range(3) for c in range(3)]
    for angle, ratio in [(1, 1.0), (5, 0.37), (90, 3.1), (150, 0.01), (179, 1.0)]:
        a, b = 0.3, 0.3 * ratio
        turn = np.radians(180 - angle)
        d1 = np.array([np.cos(0.3), np.sin(0.3)])
        d2 = np.array([np.cos(0.3 + turn), np.sin(0.3 + turn)])
        origin = np.array([0.1, 0.2])
        nodes = np.array([origin - a * d1, origin, origin + b * d2])
        if np.cross(nodes[1] - nodes[0], nodes[2] - nodes[1]) < 0:
            nodes = nodes[::-1].copy()  # keep the triangle counter-clockwise
        ref = Reference(nodes)
        for computed, reference in (
            (bem_cpp.single_layer(nodes, "p0"), ref.v0),
            (bem_cpp.single_layer(nodes, "p1"), ref.v1),
            (bem_cpp.double_layer(nodes, "p0"), ref.k0),
            (bem_cpp.double_layer(nodes, "p1"), ref.k1),
        ):
            assert relative_errors(computed, reference, entries).max() < TOL, (angle, ratio)


def test_distant_pairs_on_a_fine_circle():
    """Panel 0 against panels at 2 ... 128 panel lengths (near field, then tensor Gauss
    rules with 8 down to 3 points)."""
    nodes = circle(256)
    ref = Reference(nodes)
    entries = [(0, j) for j in (3, 6, 17, 60, 128)]
    assert relative_errors(bem_cpp.single_layer(nodes, "p0"), ref.v0, entries).max() < TOL
    assert relative_errors(bem_cpp.double_layer(nodes, "p0"), ref.k0, entries).max() < TOL
