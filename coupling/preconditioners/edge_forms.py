"""Discrete H^{1/2}_00 forms on the edges of the coarse partition (docs/method.md section 6).

An edge gamma of the coarse partition carries the fine nodes x_0 = a, x_1, ..., x_n = b
(both end points included, in order along the edge). A function phi in V_h(gamma)
that vanishes at a and b is given by its m = n - 1 interior values, and the edge form
A^0_gamma is an m x m symmetric positive definite matrix, spectrally equivalent to
the H^{1/2}_00(gamma) norm uniformly in h:

``"paper"`` (docs/method.md (5.1), the paper's formula)::

    |phi|^2 = sum_{i<j} h_i h_j (phi_i - phi_j)^2 / |x_i - x_j|^2
              + sum_i h_i phi_i^2 (1/|x_i - a| + 1/|x_i - b|),
    h_i = (|x_i - x_{i-1}| + |x_{i+1} - x_i|) / 2.

``"sqrt-laplacian"`` (our extension)
    A^0 = M^{1/2} (M^{-1/2} L M^{-1/2})^{1/2} M^{1/2} = M V diag(sqrt(lambda)) V^T M,
    with L, M the 1D P1 stiffness and mass matrices of the edge (homogeneous
    Dirichlet ends, arc-length parametrisation) and L V = M V diag(lambda),
    V^T M V = I; then (A^0)^{-1} = V diag(lambda^{-1/2}) V^T exactly.

The same "paper" formula one level up, applied to the arc-length positions of the
coarse vertices of a Signorini arc, is the coarse part of B_s; ``closed_paper_form``
is its version on a closed curve (our extension). All functions are batched: a
leading axis runs over edges with the same number of nodes, so the set-up of the
preconditioner needs no Python loop over edges.
"""
from __future__ import annotations

import numpy as np

from fem_py.polyline import segment_lengths

EDGE_FORMS = ("paper", "sqrt-laplacian")


def _as_batch(points: np.ndarray) -> tuple[np.ndarray, bool]:
    """Return points as (batch, n+1, dim) and whether a batch axis was added."""
    p = np.asarray(points, dtype=float)
    if p.ndim == 1:  # positions on a line (arc length)
        p = p[:, None]
    single = p.ndim == 2
    if single:
        p = p[None]
    if p.ndim != 3 or p.shape[1] < 2:
        raise ValueError(
            "edge points must have shape (n+1, dim) or (batch, n+1, dim) with n >= 1, got "
            f"{np.shape(points)}"
        )
    return p, single


def _positive_segment_lengths(p: np.ndarray) -> np.ndarray:
    seg = segment_lengths(p)  # (B, n)
    if np.any(seg <= 0.0):
        raise ValueError(
            "edge points must be distinct and consecutive nodes of the edge; found a zero-length "
            "segment"
        )
    return seg


def _symmetric(a: np.ndarray) -> np.ndarray:
    """Remove the round-off asymmetry of a computed symmetric (batch of) matrix."""
    return 0.5 * (a + np.swapaxes(a, -1, -2))


def _pairwise_form(weights: np.ndarray, diagonal: np.ndarray) -> np.ndarray:
    """Matrix of sum_{i<j} w_ij (phi_i - phi_j)^2 + sum_i D_i phi_i^2 (w symmetric, zero "
    "diagonal)."""
    a = -weights
    idx = np.arange(weights.shape[-1])
    a[..., idx, idx] = weights.sum(axis=-1) + diagonal
    return a


def _squared_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a_i - b_j|^2 for batches of points a (B, k, dim), b (B, l, dim): (B, k, l), summed
    over the coordinates one at a time (no (B, k, l, dim) temporary)."""
    out = np.zeros((a.shape[0], a.shape[1], b.shape[1]))
    for d in range(a.shape[2]):
        out += np.square(a[:, :, None, d] - b[:, None, :, d])
    return out


def paper_edge_form(points: np.ndarray) -> np.ndarray:
    """A^0_gamma of docs/method.md (5.1) for one edge or a batch of edges.

    Parameters
    ----------
    points : (n+1, dim) or (batch, n+1, dim)
        Nodes of the edge from a to b, both ends included. A 1D array is read as
        positions on a line (used with arc lengths for the coarse form of B_s).

    Returns
    -------
    (n-1, n-1) or (batch, n-1, n-1) array: the matrix of
    sum_{i<j} h_i h_j (phi_i - phi_j)^2 / |x_i - x_j|^2
    + sum_i h_i phi_i^2 (1/|x_i - a| + 1/|x_i - b|) over the interior nodes.
    """
    p, single = _as_batch(points)
    seg = _positive_segment_lengths(p)
    h = 0.5 * (seg[:, :-1] + seg[:, 1:])  # (B, m)
    xi = p[:, 1:-1]  # interior nodes (B, m, dim)
    m = xi.shape[1]
    dist2 = _squared_distances(xi, xi)
    dist2[:, np.arange(m), np.arange(m)] = np.inf  # no weight on the diagonal
    w = h[:, :, None] * h[:, None, :] / dist2
    to_a = np.sqrt(_squared_distances(xi, p[:, :1])[..., 0])
    to_b = np.sqrt(_squared_distances(xi, p[:, -1:])[..., 0])
    a0 = _pairwise_form(w, h * (1.0 / to_a + 1.0 / to_b))
    return a0[0] if single else a0


def closed_paper_form(s: np.ndarray, length: float, mass: float) -> np.ndarray:
    """The paper's form on a closed curve (our extension, docs/method.md section 6).

    Parameters
    ----------
    s : (m,) increasing arc-length positions in [0, length) of the m nodes.
    length : total length of the closed curve.
    mass : weight of the zero-order term (d for the coarse form of B_s).

    Returns
    -------
    (m, m) array: the matrix of sum_{i<j} H_i H_j (phi_i - phi_j)^2 / dist_ij^2
    + mass * sum_i phi_i^2, where dist_ij is the distance along the curve (the
    shorter way round) and H_i the mean length of the two curve pieces at node i.
    """
    s = np.asarray(s, dtype=float)
    m = s.size
    gaps = np.diff(np.append(s, s[0] + length))  # piece after each node
    if m < 1 or np.any(gaps <= 0.0):
        raise ValueError("closed-curve positions must be strictly increasing within one period")
    big_h = 0.5 * (gaps + np.roll(gaps, 1))
    delta = np.abs(s[:, None] - s[None, :])
    dist = np.minimum(delta, length - delta)
    w = np.zeros((m, m))
    off = ~np.eye(m, dtype=bool)
    w[off] = np.outer(big_h, big_h)[off] / dist[off] ** 2
    return _pairwise_form(w, np.full(m, float(mass)))


def sqrt_laplacian_edge_form(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Spectral square root of the 1D Dirichlet Laplacian on an edge, and its inverse.

    Parameters
    ----------
    points : (n+1, dim) or (batch, n+1, dim), nodes of the edge, ends included.

    Returns
    -------
    a0, a0_inv : (batch, m, m) arrays (no batch axis for a single edge),
        a0 = M V diag(sqrt(lambda)) V^T M and a0_inv = V diag(1/sqrt(lambda)) V^T,
        where L V = M V diag(lambda), V^T M V = I, and L, M are the P1 stiffness
        and mass matrices in arc length with homogeneous Dirichlet ends.
    """
    p, single = _as_batch(points)
    seg = _positive_segment_lengths(p)
    m = seg.shape[1] - 1
    idx = np.arange(m)
    lap = np.zeros((p.shape[0], m, m))
    mass = np.zeros_like(lap)
    lap[:, idx, idx] = 1.0 / seg[:, :-1] + 1.0 / seg[:, 1:]
    mass[:, idx, idx] = (seg[:, :-1] + seg[:, 1:]) / 3.0
    lap[:, idx[:-1], idx[1:]] = lap[:, idx[1:], idx[:-1]] = -1.0 / seg[:, 1:-1]
    mass[:, idx[:-1], idx[1:]] = mass[:, idx[1:], idx[:-1]] = seg[:, 1:-1] / 6.0
    # M = R R^T; K = R^{-1} L R^{-T} = U diag(lambda) U^T; V = R^{-T} U has V^T M V = I
    r = np.linalg.cholesky(mass)
    r_inv_lap = np.linalg.solve(r, lap)
    k = np.linalg.solve(r, np.swapaxes(r_inv_lap, 1, 2))
    lam, u = np.linalg.eigh(0.5 * (k + np.swapaxes(k, 1, 2)))
    v = np.linalg.solve(np.swapaxes(r, 1, 2), u)
    mv = mass @ v
    a0 = _symmetric((mv * np.sqrt(lam)[:, None, :]) @ np.swapaxes(mv, 1, 2))
    a0_inv = _symmetric((v / np.sqrt(lam)[:, None, :]) @ np.swapaxes(v, 1, 2))
    return (a0[0], a0_inv[0]) if single else (a0, a0_inv)


def edge_form(points: np.ndarray, kind: str = "paper") -> tuple[np.ndarray, np.ndarray]:
    """A^0_gamma and its inverse for one edge or a batch of edges with equal node counts.

    Parameters
    ----------
    points : (n+1, dim) or (batch, n+1, dim), edge nodes from a to b, ends included (n >= 2).
    kind : "paper" (docs/method.md (5.1)) or "sqrt-laplacian" (our extension).

    Returns
    -------
    a0, a0_inv : symmetric (…, n-1, n-1) arrays.
    """
    if kind not in EDGE_FORMS:
        raise ValueError(f"edge_form must be one of {EDGE_FORMS}, got {kind!r}")
    if kind == "sqrt-laplacian":
        return sqrt_laplacian_edge_form(points)
    a0 = paper_edge_form(points)
    return a0, _symmetric(np.linalg.inv(a0))
