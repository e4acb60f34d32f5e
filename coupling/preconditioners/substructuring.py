"""The substructuring preconditioner B = B_Omega + omega B_s (docs/method.md sections 5 and 6).

The PGPM (Algorithm 3.1, (3.21)-(3.22)) needs, for xi = (u, phi) in E_h =
V_h(Omega) x V_h(Gamma_s), an SPD form B(xi, eta) = B_Omega(u, w) + B_s(phi, psi)
that is spectrally equivalent to the linear form A of (4.2) and cheap to invert.

B_Omega (docs/method.md section 6). Write w = w_P + w_H (w_H discrete harmonic in every
subdomain, w_P = 0 on the skeleton) and, on the skeleton, w = w_e + w_v (w_v linear
in arc length along every coarse edge with the values of w at the coarse vertices).
Then

    B_Omega(u, w) = (grad u_P, grad w_P) + sum_gamma <A^0_gamma u_e, w_e>_gamma
                    + sum_{coarse edges (v_i, v_j)} (u(v_i) - u(v_j)) (w(v_i) - w(v_j))
                    + d sum_{coarse vertices v on Gamma} u(v) w(v).

In the splitting of the fine nodes into I (not on the skeleton) and Sk (skeleton),

    B_Omega = [[A_II,  A_ISk                          ],
               [A_SkI, A_SkI A_II^{-1} A_ISk + B_Sk   ]],

    B_Sk = (I - Pi R)^T A^0 (I - Pi R) + R^T C R,   B_Sk^{-1} = (A^0)^{-1} + Pi C^{-1} Pi^T,

where A^0 is the block-diagonal matrix of all edge forms A^0_gamma (on the edge
interior nodes), R picks the values at the coarse vertices, Pi interpolates them
linearly along the coarse edges and C = coarse graph Laplacian + d * (boundary
vertex term). B_Omega^{-1} g is the four steps of docs/method.md section 6 (local
Dirichlet solves, skeleton residual, edge and coarse solves, discrete harmonic
extension).

B_s: :mod:`coupling.preconditioners.signorini`.

Input data contract (produced by ``fem_py``): continuous P1 on a triangulation of
Omega with nodes 0..N-1; ``stiffness`` the P1 Laplace matrix A; ``coarse`` an object
with the numpy attributes ``vertex_coords (n_v, 2)``, ``vertex_dofs (n_v,)``,
``vertex_on_boundary (n_v,)``, ``edge_vertices (n_e, 2)``, ``edge_dofs`` (a
``fem_py.partition.Ragged`` or any sequence of n_e arrays: the fine nodes along each
coarse edge from end 0 to end 1, ends included),
``edge_on_boundary``, ``edge_arc``, ``skeleton_dofs`` (sorted), ``interior_dofs``,
``n_subdomains``, ``subdomain_of_interior_dof``; node coordinates ``x (N, 2)``, or
None with ``coarse.edge_coords`` (the nodes along each coarse edge, as ``edge_dofs``);
the subdomain size d; the Signorini arcs as :class:`SignoriniArc`.
"""
from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np
import scipy.sparse as sp

from coupling.preconditioners.base import check_length
from coupling.preconditioners.kernels import (
    SparseFactor,
    fill_reducing_ordering,
    largest_subdomain_interior,
    is_symmetric,
    TwoLevelForm,
    block_diagonal_edge_forms,
    coarse_matrix,
    edge_weights,
    galerkin_coarse_matrix,
)
from coupling.preconditioners.signorini import SignoriniArc, SignoriniBlock
from fem_py.partition import as_ragged

__all__ = ["SubstructuringPreconditioner", "skeleton_form"]


def skeleton_form(
    coarse: Any,
    x: np.ndarray | None,
    subdomain_size: float,
    n_nodes: int,
    kind: str,
    coarse_of: Callable[[sp.csr_matrix], sp.spmatrix] | None = None,
) -> TwoLevelForm:
    """B_Sk of docs/method.md section 6 in the numbering of ``coarse.skeleton_dofs``.

    Edge forms A^0_gamma on the interior nodes of every coarse edge; Pi = linear
    interpolation in arc length between the two end vertices; C = coarse graph
    Laplacian + d * sum over coarse vertices on Gamma, or ``coarse_of(Pi)`` (the
    Galerkin C of :func:`coupling.preconditioners.kernels.galerkin_coarse_matrix`).
    The nodes along the edges are at ``x[coarse.edge_dofs]``, or with ``x`` None at
    ``coarse.edge_coords`` (a ``fem_py.partition.CoarseStructure`` has them).
    """
    skeleton = np.asarray(coarse.skeleton_dofs, dtype=np.int64)
    vertex_dofs = np.asarray(coarse.vertex_dofs, dtype=np.int64)
    ends = np.asarray(coarse.edge_vertices, dtype=np.int64)
    on_boundary = np.asarray(coarse.vertex_on_boundary, dtype=bool)
    edge_dofs = as_ragged(coarse.edge_dofs, dtype=np.int64)
    coords = as_ragged(coarse.edge_coords, dtype=float, item_shape=(2,)) if x is None else None
    n_v, n_e = len(vertex_dofs), len(edge_dofs)
    if ends.shape != (n_e, 2) or on_boundary.shape != (n_v,):
        raise ValueError(
            f"coarse.edge_vertices must be ({n_e}, 2) and coarse.vertex_on_boundary ({n_v},); "
            "check the coarse partition"
        )
    if not on_boundary.any():
        raise ValueError(
            "no coarse vertex lies on Gamma: the coarse matrix C would be singular; mark the "
            "boundary vertices"
        )
    pos = np.full(n_nodes, -1, dtype=np.int64)
    pos[skeleton] = np.arange(len(skeleton))
    n_sk = len(skeleton)
    if np.any(pos[vertex_dofs] < 0):
        raise ValueError(
            "every coarse vertex dof must be a skeleton dof; check coarse.vertex_dofs and "
            "coarse.skeleton_dofs"
        )
    count = np.bincount(pos[vertex_dofs], minlength=n_sk)
    rows, cols, vals = [pos[vertex_dofs]], [np.arange(n_v)], [np.ones(n_v)]
    groups = []
    for length, group in edge_dofs.length_groups():
        dofs = edge_dofs.rows(group)  # (B, n+1)
        if (
            length < 2
            or np.any(dofs[:, 0] != vertex_dofs[ends[group, 0]])
            or np.any(dofs[:, -1] != vertex_dofs[ends[group, 1]])
        ):
            raise ValueError(
                "coarse.edge_dofs must run from the dof of edge_vertices[:, 0] to that of "
                "edge_vertices[:, 1]"
            )
        inner = pos[dofs[:, 1:-1]]
        if np.any(inner < 0):
            raise ValueError(
                "every dof along a coarse edge must be a skeleton dof; check coarse.edge_dofs"
            )
        count += np.bincount(inner.ravel(), minlength=n_sk)
        pts = x[dofs] if coords is None else coords.rows(group)
        t = edge_weights(pts)
        rows += [inner.ravel(), inner.ravel()]
        cols += [np.repeat(ends[group, 0], length - 2), np.repeat(ends[group, 1], length - 2)]
        vals += [(1.0 - t).ravel(), t.ravel()]
        groups.append((inner, pts))
    if np.any(count != 1):
        raise ValueError(
            "each skeleton dof must be exactly one coarse vertex or one interior node of one "
            "coarse edge; "
            f"{np.count_nonzero(count == 0)} are on none and {np.count_nonzero(count > 1)} on "
            "several"
        )
    interp = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_sk, n_v)
    )
    a0, a0_inv = block_diagonal_edge_forms(groups, n_sk, kind)
    c = coarse_matrix(coarse, subdomain_size) if coarse_of is None else coarse_of(interp)
    return TwoLevelForm(a0, a0_inv, interp, pos[vertex_dofs], c)


class SubstructuringPreconditioner(SignoriniBlock):
    """The substructuring preconditioner B = B_Omega + omega B_s of docs/method.md section 6.

    Parameters
    ----------
    stiffness : (N, N) sparse
        P1 Laplace stiffness matrix A on the fine mesh (symmetric).
    coarse : object
        Coarse partition (attributes listed in the module docstring).
    x : (N, 2) array or None
        Node coordinates; None: those along the coarse edges from ``coarse.edge_coords``
        (the only ones B needs).
    subdomain_size : float
        d, the size of the subdomains (weights the boundary-vertex term of C and the
        zero-order term of a closed Signorini arc).
    signorini_arcs : sequence of SignoriniArc
        The arcs of Gamma_s; their ``unknowns`` number the phi vector.
    edge_form : {"paper", "sqrt-laplacian"}
        A^0_gamma: the paper's formula (5.1) or the spectral square root of the edge
        Laplacian (see ``coupling.preconditioners.edge_forms``). Used on the skeleton and on the
        coarse edges of the Signorini arcs; the coarse form of B_s is always (5.1).
    signorini_weight : float
        omega > 0 multiplying B_s (our extension; docs/method.md section 6 reports that
        omega = 1/4 halves kappa).
    coarse_space : {"graph", "galerkin"}
        C: the paper's coarse graph Laplacian, or the exact energy Pi^T S Pi of the coarse
        functions (:func:`coupling.preconditioners.kernels.galerkin_coarse_matrix`; our
        extension, for partitions cut from a mesh's cells).
    check_symmetry : bool
        Whether to refuse a ``stiffness`` that is not symmetric (A_SkI is taken as
        A_ISk^T, and A_II is factored by Cholesky). False for a matrix symmetric by
        construction, such as the assembly of the symmetric form (grad u, grad v) that
        :func:`coupling.preconditioners.build_preconditioner` makes: the check is a
        sizeable part of the set-up (docs/design/preconditioners.md, "Set-up cuts").

    Notes
    -----
    Set-up factorises A_II once (one sparse Cholesky factor of the block-diagonal
    matrix of all local Dirichlet problems), stores all (A^0_gamma)^{-1} as one
    block-diagonal sparse matrix, Pi as a sparse matrix, C by a sparse Cholesky factor
    (C is the sparse coarse graph Laplacian, too large for a dense factor) and
    M_s^{-1} = (A^0_s)^{-1} + P_s C_s^{-1} P_s^T with a dense Cholesky factor of the
    small dense C_s. An application has no Python loop: two A_II solves, sparse
    products and one coarse solve (timings: docs/design/preconditioners.md).

    The PETSc objects live on ``PETSc.COMM_SELF``; call :meth:`destroy` when done.
    """

    def __init__(
        self,
        stiffness: sp.spmatrix,
        coarse: Any,
        x: np.ndarray,
        subdomain_size: float,
        signorini_arcs: Sequence[SignoriniArc],
        *,
        edge_form: str,
        signorini_weight: float,
        coarse_space: str,
        check_symmetry: bool = True,
    ) -> None:
        self._init_signorini(signorini_arcs, subdomain_size, edge_form, signorini_weight)
        a = sp.csr_matrix(stiffness, dtype=float)
        n = a.shape[0]
        x = None if x is None else np.asarray(x, dtype=float)
        if a.shape != (n, n) or (x is not None and (x.ndim != 2 or x.shape[0] != n)):
            raise ValueError(
                f"stiffness must be square and x must have one row per node; got {a.shape} and "
                f"{None if x is None else x.shape}"
            )
        interior = np.asarray(coarse.interior_dofs, dtype=np.int64)
        skeleton = np.asarray(coarse.skeleton_dofs, dtype=np.int64)
        if len(interior) + len(skeleton) != n or not np.array_equal(
            np.bincount(np.concatenate([interior, skeleton]), minlength=n),
            np.ones(n, dtype=np.int64),
        ):
            raise ValueError(
                "coarse.interior_dofs and coarse.skeleton_dofs must split the nodes 0..N-1 into "
                "two disjoint sets"
            )
        if np.any(np.diff(skeleton) <= 0):
            raise ValueError("coarse.skeleton_dofs must be sorted and unique")
        if n and check_symmetry and not is_symmetric(a):
            raise ValueError(
                "stiffness must be symmetric (the P1 Laplace matrix A); got a nonsymmetric matrix"
            )
        self.n_omega = n
        self._interior = interior
        self._skeleton = skeleton
        a_i = a[interior]
        self._a_ii = a_i[:, interior].tocsr()
        self._a_is = a_i[:, skeleton].tocsr()
        self._interior_factor = SparseFactor(
            self._a_ii, fill_reducing_ordering(self._a_ii, largest_subdomain_interior(coarse))
        )
        coarse_of = None
        if coarse_space == "galerkin":
            a_ss = a[skeleton][:, skeleton].tocsr()

            def coarse_of(interp: sp.csr_matrix) -> sp.spmatrix:
                def schur_of(e: np.ndarray) -> np.ndarray:  # Pi^T S Pi e
                    p = interp @ e
                    return interp.T @ (
                        a_ss @ p - self._a_is.T @ self.solve_interior(self._a_is @ p)
                    )

                return galerkin_coarse_matrix(coarse, self.subdomain_size, schur_of)

        elif coarse_space != "graph":
            raise ValueError(f"coarse_space must be 'graph' or 'galerkin', got {coarse_space!r}")
        self._skeleton_form = skeleton_form(coarse, x, self.subdomain_size, n, edge_form, coarse_of)

    # -- the local Dirichlet problems (rank-local in coupling.preconditioners.distributed) --
    def solve_interior(self, g_i: np.ndarray) -> np.ndarray:
        """x_I = A_II^{-1} g_I: independent Dirichlet problems on all subdomains (step 1 and 4)."""
        return self._interior_factor.solve(g_i)

    # -- B_Omega --
    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        """u = B_Omega^{-1} g, the four steps of docs/method.md section 6.

        1. x_I = A_II^{-1} g_I; 2. r = g_Sk - A_{Sk,I} x_I;
        3. v = (A^0)^{-1} r + Pi C^{-1} Pi^T r; 4. u_Sk = v, u_I = x_I - A_II^{-1} A_{I,Sk} v.
        ``g`` may be (N,) or (N, k).
        """
        g = check_length(g, self.n_omega, "g")
        x_i = self.solve_interior(g[self._interior])
        v = self._skeleton_form.solve(g[self._skeleton] - self._a_is.T @ x_i)
        u = np.empty_like(g)
        u[self._interior] = x_i - self.solve_interior(self._a_is @ v)
        u[self._skeleton] = v
        return u

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        """B_Omega u = [A_II u_I + A_ISk u_Sk; A_SkI u_I + A_SkI A_II^{-1} A_ISk u_Sk + B_Sk "
        "u_Sk] (one A_II solve)."""
        u = check_length(u, self.n_omega, "u")
        u_i, u_s = u[self._interior], u[self._skeleton]
        y = self._a_is @ u_s
        out = np.empty_like(u)
        out[self._interior] = self._a_ii @ u_i + y
        out[self._skeleton] = self._a_is.T @ (
            u_i + self.solve_interior(y)
        ) + self._skeleton_form.matvec(u_s)
        return out

    def omega_matrix(self) -> np.ndarray:
        """The dense N x N matrix of B_Omega (for tests and small problems only: O(N^2) memory)."""
        b = np.zeros((self.n_omega, self.n_omega))
        ii, ss = np.ix_(self._interior, self._interior), np.ix_(self._skeleton, self._skeleton)
        a_is = self._a_is.toarray()
        b[ii] = self._a_ii.toarray()
        b[np.ix_(self._interior, self._skeleton)] = a_is
        b[np.ix_(self._skeleton, self._interior)] = a_is.T
        harmonic = self.solve_interior(a_is)
        b[ss] = a_is.T @ harmonic + self._skeleton_form.matrix.toarray()
        return b

    def destroy(self) -> None:
        """Free the PETSc factors (call on every rank when done)."""
        self._interior_factor.destroy()
        self._skeleton_form.destroy()
        self._signorini.destroy()
