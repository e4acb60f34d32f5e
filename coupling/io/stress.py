"""The stress of a P1 displacement: its gradient on every simplex, sigma(u) of an elastic
material from it, and the von Mises stress (the figures of an elastic run and ``fembem
evaluate``'s stress inside the body; docs/method.md section 12)."""
from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["cell_gradients", "stress_tensors", "von_mises", "equivalent_stress"]

#: Cells whose gradients are computed at once (bounds the scratch memory).
_CHUNK = 1 << 18


def cell_gradients(x: np.ndarray, cells: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The gradient (m, d, d) of the vector P1 field ``u`` (N, d) on each simplex of
    ``cells`` (m, d + 1): [c, i, j] = du_i/dx_j, from the edges out of the first vertex,
    the inverse of their matrix written out (its adjugate over its determinant: a tenth
    of the time of a batched solve)."""
    x, u = np.asarray(x, dtype=float), np.asarray(u, dtype=float)
    d = x.shape[1]
    out = np.empty((len(cells), d, d))
    for start in range(0, len(cells), _CHUNK):
        c = cells[start : start + _CHUNK]
        edges = x[c[:, 1:]] - x[c[:, :1]]  # (m, d, d): row k the edge to vertex k + 1
        rise = u[c[:, 1:]] - u[c[:, :1]]  # (m, d, d): row k the change of u along it
        # rise[k, i] = sum_j grad[i, j] edges[k, j], so grad = rise^T edges^-T
        out[start : start + _CHUNK] = np.einsum("mki,mjk->mij", rise, _inverse(edges))
    return out


def _inverse(a: np.ndarray) -> np.ndarray:
    """The inverses of the 2 x 2 or 3 x 3 matrices ``a`` (m, d, d), by their adjugates."""
    if a.shape[-1] == 2:
        adj = np.empty_like(a)
        adj[:, 0, 0], adj[:, 1, 1] = a[:, 1, 1], a[:, 0, 0]
        adj[:, 0, 1], adj[:, 1, 0] = -a[:, 0, 1], -a[:, 1, 0]
    else:  # the columns of the adjugate: cross products of the rows
        r0, r1, r2 = a[:, 0], a[:, 1], a[:, 2]
        adj = np.stack([np.cross(r1, r2), np.cross(r2, r0), np.cross(r0, r1)], axis=2)
    det = np.einsum("mj,mj->m", a[:, 0], adj[:, :, 0])  # (a adj)_00 = det a
    return adj / det[:, None, None]


def stress_tensors(gradients: np.ndarray, material: Any) -> np.ndarray:
    """sigma(u) (m, 3, 3) from the gradients (m, d, d) of u and the elastic ``material``
    (:class:`fem_py.forms.elasticity.ElasticMaterial`: sigma = kappa tr eps I +
    2 mu(|dev eps|) dev eps, docs/method.md section 12), dev the d-dimensional deviator.

    In 2D (plane strain) the upper d x d block is the planar stress and sigma_zz =
    (kappa - mu) tr eps: for linear elasticity lambda tr eps, the plane-strain value; for a
    Hencky body the same expression with the secant shear modulus mu(|dev eps|) (the planar
    model defines no sigma_zz of its own).
    """
    d = gradients.shape[-1]
    eps = 0.5 * (gradients + gradients.transpose(0, 2, 1))
    trace = np.trace(eps, axis1=1, axis2=2)
    eye = np.eye(d)
    dev = eps - trace[:, None, None] / d * eye
    rho = np.broadcast_to(
        np.asarray(material.deviatoric.rho_np(np.sqrt(np.einsum("mij,mij->m", dev, dev))), float),
        trace.shape,
    )  # 2 mu(|dev eps|)
    sigma = np.zeros((len(eps), 3, 3))
    sigma[:, :d, :d] = (material.bulk * trace)[:, None, None] * eye + rho[:, None, None] * dev
    if d == 2:
        sigma[:, 2, 2] = (material.bulk - 0.5 * rho) * trace
    return sigma


def von_mises(gradients: np.ndarray, material: Any) -> np.ndarray:
    """The von Mises stress sqrt(3/2 dev sigma : dev sigma) (m,) of sigma(u)
    (:func:`stress_tensors`), dev the 3D deviator."""
    return equivalent_stress(stress_tensors(gradients, material))


def equivalent_stress(sigma: np.ndarray) -> np.ndarray:
    """The von Mises stress sqrt(3/2 dev sigma : dev sigma) (m,) of the stress tensors
    ``sigma`` (m, 3, 3), dev the 3D deviator."""
    mean = np.trace(sigma, axis1=1, axis2=2) / 3.0
    deviator = sigma - mean[:, None, None] * np.eye(3)
    return np.sqrt(1.5 * np.einsum("mij,mij->m", deviator, deviator))
