"""Synthetic structured meshes for the preconditioner tests (numpy/scipy only, no DOLFINx).

The square [0, width]^2 with n cells per side, each cell cut into two triangles by
its (0,0)-(1,1) diagonal; continuous P1 stiffness matrix; coarse squares of
``ratio`` cells per side (d = ratio * h). The data mirror the contract of
``fem_py`` described in ``coupling/preconditioners/substructuring.py``. This module holds no tests;
it is shared by ``test_preconditioner.py`` and ``test_preconditioner_spectral.py``.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import scipy.sparse as sp

from coupling.preconditioners import SignoriniArc, SubstructuringPreconditioner


@dataclass
class StructuredSquare:
    """A structured P1 problem: fine mesh, stiffness, coarse partition, Signorini arcs."""

    n: int
    ratio: int
    width: float
    x: np.ndarray
    triangles: np.ndarray
    stiffness: sp.csr_matrix
    coarse: SimpleNamespace
    boundary_nodes: np.ndarray  # counter-clockwise, starting at the origin
    arcs: tuple[SignoriniArc, ...]
    signorini_nodes: np.ndarray  # global node of each phi unknown

    @property
    def h(self) -> float:
        return self.width / self.n

    @property
    def d(self) -> float:
        return self.ratio * self.h


def p1_stiffness(x: np.ndarray, triangles: np.ndarray) -> sp.csr_matrix:
    """P1 Laplace stiffness matrix, assembled from the element matrices |T| grad l_a . grad l_b."""
    p = x[triangles]  # (T, 3, 2)
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    # gradients of the barycentric coordinates: rows of inv([e1 e2])^T, plus l_0 = 1 - l_1 - l_2
    g1 = np.stack([e2[:, 1], -e2[:, 0]], axis=1) / det[:, None]
    g2 = np.stack([-e1[:, 1], e1[:, 0]], axis=1) / det[:, None]
    grads = np.stack([-g1 - g2, g1, g2], axis=1)  # (T, 3, 2)
    local = 0.5 * np.abs(det)[:, None, None] * np.einsum("tad,tbd->tab", grads, grads)
    rows = np.repeat(triangles, 3, axis=1).ravel()
    cols = np.tile(triangles, (1, 3)).ravel()
    n = x.shape[0]
    return sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n, n))


def structured_square(
    n: int,
    ratio: int,
    width: float = 0.5,
    signorini: str = "bottom",
    lines: np.ndarray | None = None,
) -> StructuredSquare:
    """Build the structured square problem.

    Parameters
    ----------
    n : cells per side; must be a multiple of ``ratio``.
    ratio : d/h, fine cells per coarse square side.
    signorini : "bottom" (one open arc along y = 0), "bottom-right" (one open arc along
        the bottom and right sides, turning a corner), "two" (the bottom and top sides,
        two arcs), "closed" (the whole boundary, one closed arc) or "none".
    lines : optional increasing (n+1,) positions of the grid lines (the same in x and
        y) from 0 to width, for graded meshes with uneven fine and coarse edges;
        uniform by default.
    """
    if n % ratio:
        raise ValueError(f"n = {n} is not a multiple of ratio = {ratio}")
    nc = n // ratio
    ii, jj = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="xy")
    ii, jj = ii.ravel(), jj.ravel()
    lines = np.linspace(0.0, width, n + 1) if lines is None else np.asarray(lines, dtype=float)
    x = np.stack([lines[ii], lines[jj]], axis=1)
    node = lambda i, j: np.asarray(i) + np.asarray(j) * (n + 1)  # noqa: E731
    ci, cj = np.meshgrid(np.arange(n), np.arange(n), indexing="xy")
    ci, cj = ci.ravel(), cj.ravel()
    a, b, c, dd = node(ci, cj), node(ci + 1, cj), node(ci + 1, cj + 1), node(ci, cj + 1)
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, dd], 1)])
    stiffness = p1_stiffness(x, triangles)

    # coarse vertices (p, q), p, q = 0..nc
    vi, vj = np.meshgrid(np.arange(nc + 1), np.arange(nc + 1), indexing="xy")
    vi, vj = vi.ravel(), vj.ravel()
    vid = lambda i, j: np.asarray(i) + np.asarray(j) * (nc + 1)  # noqa: E731
    vertex_dofs = node(vi * ratio, vj * ratio).astype(np.int64)
    vertex_on_boundary = (vi == 0) | (vi == nc) | (vj == 0) | (vj == nc)
    edges, edge_dofs, edge_on_boundary, edge_side = [], [], [], []
    steps = np.arange(ratio + 1)
    for q in range(nc + 1):
        for p in range(nc):  # horizontal edges, left to right
            edges.append((vid(p, q), vid(p + 1, q)))
            edge_dofs.append(node(p * ratio + steps, q * ratio).astype(np.int64))
            edge_on_boundary.append(q in (0, nc))
            edge_side.append("bottom" if q == 0 else "top" if q == nc else "")
    for p in range(nc + 1):
        for q in range(nc):  # vertical edges, bottom to top
            edges.append((vid(p, q), vid(p, q + 1)))
            edge_dofs.append(node(p * ratio, q * ratio + steps).astype(np.int64))
            edge_on_boundary.append(p in (0, nc))
            edge_side.append("left" if p == 0 else "right" if p == nc else "")
    on_skeleton = (ii % ratio == 0) | (jj % ratio == 0)
    skeleton_dofs = np.flatnonzero(on_skeleton).astype(np.int64)
    interior_dofs = np.flatnonzero(~on_skeleton).astype(np.int64)

    # boundary nodes counter-clockwise from the origin
    r = np.arange(n)
    bottom, right = node(r, 0), node(n, r)
    top, left = node(n - r, n), node(0, n - r)
    boundary_nodes = np.concatenate([bottom, right, top, left]).astype(np.int64)

    def open_arc(path: np.ndarray, first_unknown: int) -> SignoriniArc:
        # path: global nodes along the arc, both ends included, counter-clockwise
        xi, yj = path % (n + 1), path // (n + 1)
        mask = (xi % ratio == 0) & (yj % ratio == 0)
        return SignoriniArc(
            coords=x[path],
            coarse_vertex_mask=mask,
            unknowns=first_unknown + np.arange(len(path) - 2),
        )

    sides = {
        "bottom": (bottom, right),
        "right": (right, top),
        "top": (top, left),
        "left": (left, bottom),
    }

    def full(side: str) -> np.ndarray:  # the side with both corners, counter-clockwise
        nodes, following = sides[side]
        return np.append(nodes, following[0])

    if signorini == "bottom":
        paths = [full("bottom")]
    elif signorini == "bottom-right":
        paths = [np.concatenate([bottom, full("right")])]
    elif signorini == "two":
        paths = [full("bottom"), full("top")]
    elif signorini in ("closed", "none"):
        paths = []
    else:
        raise ValueError(f"unknown signorini layout {signorini!r}")
    arcs, sig_nodes = [], []
    for path in paths:
        arcs.append(open_arc(path, sum(len(p) for p in sig_nodes)))
        sig_nodes.append(path[1:-1])
    if signorini == "closed":
        xi, yj = boundary_nodes % (n + 1), boundary_nodes // (n + 1)
        mask = (xi % ratio == 0) & (yj % ratio == 0)
        arcs.append(
            SignoriniArc(
                coords=x[boundary_nodes],
                coarse_vertex_mask=mask,
                unknowns=np.arange(len(boundary_nodes)),
                closed=True,
            )
        )
        sig_nodes.append(boundary_nodes)
    signorini_nodes = np.concatenate(sig_nodes) if sig_nodes else np.zeros(0, np.int64)

    # edge_arc: index of the Signorini arc containing each coarse boundary edge
    edge_arc = np.full(len(edges), -1)
    sig_set = [set(p.tolist()) for p in (paths if signorini != "closed" else [boundary_nodes])]
    for e, dofs in enumerate(edge_dofs):
        if edge_on_boundary[e]:
            for k, s in enumerate(sig_set):
                if set(dofs.tolist()) <= s:
                    edge_arc[e] = k

    coarse = SimpleNamespace(
        vertex_coords=x[vertex_dofs],
        vertex_dofs=vertex_dofs,
        vertex_on_boundary=vertex_on_boundary,
        edge_vertices=np.asarray(edges, dtype=np.int64),
        edge_dofs=tuple(edge_dofs),
        edge_on_boundary=np.asarray(edge_on_boundary),
        edge_arc=edge_arc,
        skeleton_dofs=skeleton_dofs,
        interior_dofs=interior_dofs,
        n_subdomains=nc * nc,
        subdomain_of_interior_dof=(
            ii[interior_dofs] // ratio + (jj[interior_dofs] // ratio) * nc
        ).astype(np.int64),
    )
    return StructuredSquare(
        n=n,
        ratio=ratio,
        width=width,
        x=x,
        triangles=triangles,
        stiffness=stiffness,
        coarse=coarse,
        boundary_nodes=boundary_nodes,
        arcs=tuple(arcs),
        signorini_nodes=signorini_nodes,
    )


def substructuring(
    prob: StructuredSquare, *, edge_form: str = "paper", signorini_weight: float = 1.0
) -> SubstructuringPreconditioner:
    """B of docs/method.md section 6 for ``prob``: the paper's edge form (5.1) and B_s
    unweighted (omega = 1), the definitions the references below read, unless told."""
    return SubstructuringPreconditioner(
        prob.stiffness,
        prob.coarse,
        prob.x,
        prob.d,
        prob.arcs,
        edge_form=edge_form,
        signorini_weight=signorini_weight,
        coarse_space="graph",
    )
