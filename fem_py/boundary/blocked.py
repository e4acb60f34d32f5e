"""The boundary map of the vector space V_h^d (elasticity, docs/method.md section 12) and its
gap unknowns.

A boundary vector of the elastic problem holds d components per boundary node, node-major
(entry d k + c: component c at node k, the layout of the Lame operators of bem_cpp and of
DOLFINx's blocked P1 space, whose nodes are numbered as the scalar space's dofs). The trace
T and its transpose are those of :class:`fem_py.boundary.vectors.BoundaryVectors` on the
dofs d dofs[k] + c.

The gap unknowns g (what phi is for the scalar equation) sit at the Signorini nodes, in the
frame of the nodal normal n_k (the map's ``node_normals``) and, for ``"slip"``, tangents
t_k orthonormal to it (n_s unknowns for "stick", d n_s for "slip")::

    "stick":  j_k = g_k n_k,                              g_k >= 0
    "slip":   j_k = g_k n_k + sum_i g_{k,i} t_{k,i},      g_k >= 0, the g_{k,i} free

so that z = T u + E g with E the sparse matrix of :class:`GapMap`; the constraint set is a
product of half-lines and lines, and its projection in a diagonal metric is pointwise. The
scalar equation's E (``signorini`` positions, weight 1) is :func:`scalar_gap_map`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from fem_py.boundary.vectors import BoundaryVectors

__all__ = ["BlockedBoundary", "GapMap", "scalar_gap_map", "elastic_gap_map", "TANGENTIAL"]

#: The tangential conditions on Gamma_s: frictionless sliding or no slip.
TANGENTIAL = ("slip", "stick")


@dataclass(frozen=True)
class GapMap:
    """The extension E of the gap unknowns g into boundary vectors: z = T u + E g.

    Attributes
    ----------
    matrix
        E, sparse (boundary vector length x m): column j is unknown j's direction at its node.
    bounded
        (m,) bool: g_j >= 0 (a normal gap) where True, g_j free (a tangential slip) where False.
    nodes
        (m,) int: the boundary node of each unknown.
    """

    matrix: sp.csr_matrix
    bounded: np.ndarray
    nodes: np.ndarray

    @property
    def size(self) -> int:
        """m, the number of gap unknowns."""
        return int(self.bounded.size)

    @property
    def normal(self) -> np.ndarray:
        """The indices of the bounded (normal) unknowns, one per Signorini node."""
        return np.flatnonzero(self.bounded)

    def extend(self, z: np.ndarray, g: np.ndarray) -> np.ndarray:
        """z += E g (in place); returns z."""
        z += self.matrix @ g
        return z

    def restrict(self, y: np.ndarray) -> np.ndarray:
        """E^T y."""
        return self.matrix.T @ y


def _gap_map(n: int, positions: np.ndarray, weights: np.ndarray, bounded, nodes) -> GapMap:
    """E with column j = ``weights[j]`` at the boundary-vector entries ``positions[j]``."""
    m, k = positions.shape
    matrix = sp.csr_matrix(
        (weights.ravel(), (positions.ravel(), np.repeat(np.arange(m), k))), shape=(n, m)
    )
    return GapMap(matrix, np.asarray(bounded, dtype=bool), np.asarray(nodes, dtype=np.int64))


def scalar_gap_map(boundary: BoundaryVectors) -> GapMap:
    """E of the scalar equation: (E phi)_{signorini[j]} = phi_j, every phi_j >= 0."""
    signorini = np.asarray(boundary.signorini, dtype=np.int64)
    m = signorini.size
    return _gap_map(boundary.n_gamma, signorini[:, None], np.ones((m, 1)), np.ones(m), signorini)


def tangents(normals: np.ndarray) -> np.ndarray:
    """(m, d - 1, d) unit tangents orthonormal to the unit ``normals`` (m, d): in 2D the
    normal turned by +90 degrees; in 3D e x n for the axis e least aligned with n, and
    n x t1."""
    m, d = normals.shape
    if d == 2:
        return np.stack([-normals[:, 1], normals[:, 0]], axis=1)[:, None, :]
    axis = np.eye(3)[np.argmin(np.abs(normals), axis=1)]
    t1 = np.cross(axis, normals)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return np.stack([t1, np.cross(normals, t1)], axis=1)


def elastic_gap_map(boundary: "BlockedBoundary", tangential: str) -> GapMap:
    """E of the elastic problem (module docstring): the normal unknowns first (one per
    Signorini node, in the order of ``boundary.signorini``), then for ``"slip"`` the
    tangential ones, node by node."""
    if tangential not in TANGENTIAL:
        raise ValueError(f"tangential must be one of {TANGENTIAL}, got {tangential!r}")
    d = boundary.components
    nodes = np.asarray(boundary.signorini, dtype=np.int64)
    weights = boundary.node_normals[nodes]
    owner = nodes
    if tangential == "slip":
        weights = np.concatenate([weights, tangents(weights).reshape(-1, d)])
        owner = np.concatenate([nodes, np.repeat(nodes, d - 1)])
    positions = d * owner[:, None] + np.arange(d)
    bounded = np.arange(owner.size) < nodes.size
    return _gap_map(boundary.n_gamma, positions, weights, bounded, owner)


#: A rigid motion whose normal component on Gamma is below this fraction of its size is
#: one that "slip" on all of Gamma leaves free (:func:`free_rigid_motion`). The fraction
#: is 0 for a polygon inscribed in a circle, 0.015-0.020 for gmsh's ball at h = R/2 and
#: 0.010 at R/4 (its nodal normals are not quite radial), 0.048 for an ellipse of
#: semi-axes 0.3 and 0.28, 0.27 for the ellipse 0.3 x 0.2, 0.40 for the square, 0.26 for
#: the box (measured).
SLIDING_TOLERANCE = 0.03


def rigid_motions_at(points: np.ndarray) -> np.ndarray:
    """The rigid motions of R^d at ``points`` (n, d): (m, n, d), m = 3 in 2D (two
    translations, the rotation about the origin), 6 in 3D."""
    n, d = points.shape
    modes = [np.broadcast_to(np.eye(d)[k], (n, d)) for k in range(d)]
    for i, j in [(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]:
        mode = np.zeros((n, d))
        mode[:, i], mode[:, j] = -points[:, j], points[:, i]
        modes.append(mode)
    return np.stack(modes)


def free_rigid_motion(boundary: "BlockedBoundary", tangential: str) -> bool:
    """Whether a rigid motion of the body slides along all of Gamma: with ``"slip"`` on the
    whole boundary (no bonded node), a rigid motion r with r.n = 0 on Gamma (the rotation of
    a disk or a ball, the rotation of a body of revolution about its axis) changes u by r
    and the tangential gaps by -r, and J_h not at all: the solution is not unique. Found
    as a singular value of the normal components of the rigid motions at the nodes below
    :data:`SLIDING_TOLERANCE` of the largest (relative to the motions' sizes)."""
    if tangential != "slip" or len(boundary.signorini) < boundary.n_nodes:
        return False
    centred = boundary.nodes - boundary.nodes.mean(axis=0)
    motions = rigid_motions_at(centred)  # (m, n, d)
    m = motions.shape[0]
    # min over c of |normal part of sum c_j r_j| / |sum c_j r_j|: sigma_min(N R^-1) with
    # the QR factor R of the motions' columns
    _, R = np.linalg.qr(motions.reshape(m, -1).T)
    normal = np.einsum("mnd,nd->nm", motions, boundary.node_normals)
    fraction = np.linalg.svd(np.linalg.solve(R.T, normal.T).T, compute_uv=False)[-1]
    return bool(fraction < SLIDING_TOLERANCE)


class BlockedBoundary(BoundaryVectors):
    """The boundary map of V_h^d from the nodal map of the same mesh (``BoundaryMap`` in
    2D, ``SurfaceMap`` in 3D): T, T^T, ``gather`` and ``scatter_add`` on node-major boundary
    vectors of length d n; the node-level attributes (``nodes``, ``node_normals``,
    ``signorini``, ``triangles``, ...) are the nodal map's.

    Parameters
    ----------
    nodal
        The map of the nodes.
    components
        d.
    """

    def __init__(self, nodal: Any, components: int):
        self.nodal = nodal
        self.components = int(components)
        d = self.components
        self.dofs = (d * np.asarray(nodal.dofs, dtype=np.int64)[:, None] + np.arange(d)).ravel()
        self.n_dofs = d * int(nodal.n_dofs)

    def __getattr__(self, name: str) -> Any:
        if name == "nodal":  # not yet set: no recursion while unpickling or constructing
            raise AttributeError(name)
        return getattr(self.nodal, name)

    @property
    def n_nodes(self) -> int:
        """The number of boundary nodes (``n_gamma`` is the length d n of a boundary vector)."""
        return len(self.nodal.dofs)

    @property
    def n_signorini(self) -> int:
        """The number of Signorini nodes."""
        return len(self.nodal.signorini)

    def interpolate_boundary(self, expr: Any) -> np.ndarray:
        """Node-major nodal values (d n,) of vector boundary data: a list of d components,
        each text, a number or a callable as :meth:`BoundaryVectors.interpolate_boundary`
        takes them, or one number for every component."""
        d = self.components
        if isinstance(expr, (int, float, np.integer, np.floating)) and not isinstance(expr, bool):
            expr = [expr] * d
        if not isinstance(expr, (list, tuple)) or len(expr) != d:
            given = f"{len(expr)} components" if isinstance(expr, (list, tuple)) else "a scalar"
            raise ValueError(
                f"vector boundary data needs {d} components (a list such as "
                f"{['0'] * d}), got {given}"
            )
        return np.stack([self.nodal.interpolate_boundary(c) for c in expr], axis=1).ravel()
