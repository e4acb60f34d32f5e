"""The substructuring preconditioner B = B_Omega + omega B_s (METHOD.md sections 5 and 6).

The PGPM (Algorithm 3.1, (3.21)-(3.22)) needs, for xi = (u, phi) in E_h =
V_h(Omega) x V_h(Gamma_s), an SPD form B(xi, eta) = B_Omega(u, w) + B_s(phi, psi)
that is spectrally equivalent to the linear form A of (4.2) and cheap to invert.

B_Omega (METHOD.md section 6). Write w = w_P + w_H (w_H discrete harmonic in every
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
vertex term). B_Omega^{-1} g is the four steps of METHOD.md section 6 (local
Dirichlet solves, skeleton residual, edge and coarse solves, discrete harmonic
extension).

B_s (METHOD.md section 6, "Signorini block"). On each Signorini arc the same
two-level structure one level up: edge forms on the coarse edges of the arc for
phi_e, and the discrete H^{1/2}_00 formula (5.1) on the coarse vertices of the arc
(arc-length weights) for phi_v; for a closed arc, distances along the curve and
d * sum phi(v)^2 instead of the end-point term (our extension). Its matrix M_s has
M_s^{-1} = (A^0_s)^{-1} + P_s C_s^{-1} P_s^T, so it is "factorised" exactly by the
same edge inverses and one small dense Cholesky factor of C_s.

Input data contract (produced by ``fem_py``): continuous P1 on a triangulation of
Omega with nodes 0..N-1; ``stiffness`` the P1 Laplace matrix A; ``coarse`` an object
with the numpy attributes ``vertex_coords (n_v, 2)``, ``vertex_dofs (n_v,)``,
``vertex_on_boundary (n_v,)``, ``edge_vertices (n_e, 2)``, ``edge_dofs`` (a
``fem_py.coarse.Ragged`` or any sequence of n_e arrays: the fine nodes along each
coarse edge from end 0 to end 1, ends included),
``edge_on_boundary``, ``edge_arc``, ``skeleton_dofs`` (sorted), ``interior_dofs``,
``n_subdomains``, ``subdomain_of_interior_dof``; node coordinates ``x (N, 2)``; the
subdomain size d; the Signorini arcs as :class:`SignoriniArc`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from petsc4py import PETSc
from threadpoolctl import threadpool_limits

from coupling.edge_forms import EDGE_FORMS, closed_paper_form, edge_form, paper_edge_form
from fem_py.coarse import as_ragged

__all__ = [
    "SignoriniArc",
    "Preconditioner",
    "SubstructuringPreconditioner",
    "IdentityPreconditioner",
]


@dataclass(frozen=True, eq=False)
class SignoriniArc:
    """One Signorini arc of Gamma_s, as the preconditioner needs it.

    Attributes
    ----------
    coords : (m+1, 2) array
        Fine boundary nodes along the arc in counter-clockwise order, both end points
        included. For a closed arc (the whole boundary): the m nodes once, not repeated.
    coarse_vertex_mask : (m+1,) bool array
        Which of those nodes are coarse vertices; the two end points of an open arc
        always are (METHOD.md section 6 requires the arc ends to be coarse vertices).
    unknowns : int array
        For each node carrying a phi unknown, its index in the phi vector (length n_s):
        the m-1 interior nodes of an open arc, all m nodes of a closed arc, in order.
    closed : bool
        True when the arc is a whole closed boundary curve (no end points).
    """

    coords: np.ndarray
    coarse_vertex_mask: np.ndarray
    unknowns: np.ndarray
    closed: bool = False

    def __post_init__(self) -> None:
        coords = np.asarray(self.coords, dtype=float)
        mask = np.asarray(self.coarse_vertex_mask, dtype=bool)
        unknowns = np.asarray(self.unknowns, dtype=np.int64)
        if coords.ndim != 2 or coords.shape[1] != 2:
            raise ValueError(f"SignoriniArc.coords must have shape (k, 2), got {coords.shape}")
        k = coords.shape[0]
        if mask.shape != (k,):
            raise ValueError(f"SignoriniArc.coarse_vertex_mask must have shape ({k},), one flag per node, got {mask.shape}")
        expected = k if self.closed else k - 2
        if unknowns.shape != (expected,):
            raise ValueError(
                f"SignoriniArc.unknowns must have {expected} entries ({'all nodes of a closed arc' if self.closed else 'the interior nodes'}), got {unknowns.shape}"
            )
        if self.closed:
            if not mask.any():
                raise ValueError("a closed SignoriniArc needs at least one coarse vertex in coarse_vertex_mask")
        elif k < 2 or not (mask[0] and mask[-1]):
            raise ValueError("the two end points of an open SignoriniArc must be coarse vertices (mask[0] and mask[-1] True)")
        object.__setattr__(self, "coords", coords)
        object.__setattr__(self, "coarse_vertex_mask", mask)
        object.__setattr__(self, "unknowns", unknowns)


class Preconditioner(Protocol):
    """Interface of the block-diagonal preconditioner B = B_Omega + B_s used by the PGPM (3.21)-(3.22)."""

    def apply_omega(self, g: np.ndarray) -> np.ndarray: ...  # B_Omega^{-1} g

    def matvec_omega(self, u: np.ndarray) -> np.ndarray: ...  # B_Omega u

    def apply_signorini(self, g: np.ndarray) -> np.ndarray: ...  # M_s^{-1} g

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray: ...  # M_s phi

    @property
    def lambda_max_signorini(self) -> float: ...  # largest eigenvalue of M_s, for theta in (3.20)

    @property
    def signorini_metric(self) -> np.ndarray: ...  # M_s, dense (the metric of the projection (3.19))

    def destroy(self) -> None: ...  # free solver objects (PETSc) on every rank


class IdentityPreconditioner:
    """B = Euclidean inner product on R^N x R^{n_s} (plain projection-gradient, Remark 2.1).

    Parameters
    ----------
    n_omega : number N of fine nodes (length of u).
    n_signorini : number n_s of phi unknowns.
    """

    def __init__(self, n_omega: int, n_signorini: int) -> None:
        if n_omega < 1 or n_signorini < 0:
            raise ValueError(f"need n_omega >= 1 and n_signorini >= 0, got {n_omega}, {n_signorini}")
        self.n_omega = int(n_omega)
        self.n_signorini = int(n_signorini)

    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        return _check_length(g, self.n_omega, "g").copy()

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        return _check_length(u, self.n_omega, "u").copy()

    def apply_signorini(self, g: np.ndarray) -> np.ndarray:
        return _check_length(g, self.n_signorini, "g").copy()

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray:
        return _check_length(phi, self.n_signorini, "phi").copy()

    @property
    def lambda_max_signorini(self) -> float:
        return 1.0

    @property
    def signorini_metric(self) -> np.ndarray:
        return np.eye(self.n_signorini)

    def destroy(self) -> None:
        pass


def _check_length(v: np.ndarray, n: int, name: str) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    if v.ndim not in (1, 2) or v.shape[0] != n:
        raise ValueError(f"{name} must have shape ({n},) or ({n}, k), got {v.shape}")
    return v


class _SparseFactor:
    """Sparse Cholesky factor of an SPD matrix, computed once (PETSc built-in, nested dissection).

    Chosen by measurement (structured square, 263169 nodes, A_II of 1.5e5 to 2.3e5
    unknowns): PETSc's own sequential Cholesky with nested-dissection ordering solved
    in 2-9 ms, SuperLU (scipy ``splu``, any ordering) in 8-29 ms and MUMPS in
    100-180 ms; the set-up costs 0.1-0.5 s for all but MUMPS. CHOLMOD has no Debian
    Python binding. Works on ``PETSc.COMM_SELF``: the factor is rank-local.
    """

    def __init__(self, matrix: sp.spmatrix) -> None:
        m = sp.csr_matrix(matrix, dtype=float)
        self.n = m.shape[0]
        self._ksp = None
        self._alive = True
        if self.n == 0:
            return
        self._mat = PETSc.Mat().createAIJ(
            size=m.shape, csr=(m.indptr.astype(PETSc.IntType), m.indices.astype(PETSc.IntType), m.data),
            comm=PETSc.COMM_SELF)
        self._mat.setOption(PETSc.Mat.Option.SPD, True)
        self._ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        self._ksp.setOperators(self._mat)
        self._ksp.setType("preonly")
        pc = self._ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("petsc")
        pc.setFactorOrdering("nd")
        self._ksp.setUp()
        self._factor = pc.getFactorMatrix()
        self._rhs, self._sol = self._mat.createVecs()

    def solve(self, b: np.ndarray) -> np.ndarray:
        """A^{-1} b for b of shape (n,) or (n, k)."""
        if not self._alive:
            raise RuntimeError("this factor has been destroyed; build a new preconditioner")
        if self._ksp is None:  # empty matrix
            return np.zeros_like(b, dtype=float)
        if b.ndim == 1:
            self._rhs.array[:] = b
            self._factor.solve(self._rhs, self._sol)
            return self._sol.array.copy()
        out = np.zeros(b.shape, order="F")
        rhs = PETSc.Mat().createDense(b.shape, array=np.asfortranarray(b, dtype=float), comm=PETSc.COMM_SELF)
        sol = PETSc.Mat().createDense(b.shape, array=out, comm=PETSc.COMM_SELF)
        self._factor.matSolve(rhs, sol)
        rhs.destroy()
        sol.destroy()
        return np.ascontiguousarray(out)

    def destroy(self) -> None:
        """Free the PETSc objects (call on every rank)."""
        if self._ksp is not None:
            for obj in (self._rhs, self._sol, self._ksp, self._mat):
                obj.destroy()
            self._ksp = None
        self._alive = False


class _DenseFactor:
    """Dense Cholesky factor of a small SPD matrix (LAPACK), computed once."""

    def __init__(self, matrix: np.ndarray) -> None:
        self._factor = sla.cho_factor(matrix, lower=True) if matrix.size else None

    def solve(self, b: np.ndarray) -> np.ndarray:
        return sla.cho_solve(self._factor, b) if self._factor is not None else np.zeros_like(b, dtype=float)

    def destroy(self) -> None:
        pass


def _block_diagonal(groups: Sequence[tuple[np.ndarray, np.ndarray]], n: int,
                    kind: str) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """All edge forms A^0_gamma and their inverses as two block-diagonal n x n sparse matrices.

    Each group is ``(ix, pts)`` for a batch of edges with equal node counts: ``ix (B, m)``
    the (local) numbers of the interior nodes, ``pts (B, m+2, dim)`` the nodes with both ends.
    """
    rows, cols, vals, ivals = [], [], [], []
    batches: dict[tuple, list] = {}  # one batch per shape: one edge_form call each
    for ix, pts in groups:
        if ix.shape[1]:
            batches.setdefault(pts.shape[1:], []).append((ix, pts))
    # tiny batched LAPACK calls: threads only add overhead (11x slower with 2 threads)
    with threadpool_limits(limits=1):
        for batch in batches.values():
            ix = np.concatenate([b[0] for b in batch])
            a0, a0_inv = edge_form(np.concatenate([b[1] for b in batch]), kind)
            rows.append(np.broadcast_to(ix[:, :, None], a0.shape).ravel())
            cols.append(np.broadcast_to(ix[:, None, :], a0.shape).ravel())
            vals.append(a0.ravel())
            ivals.append(a0_inv.ravel())
    if not rows:
        return sp.csr_matrix((n, n)), sp.csr_matrix((n, n))
    r, c = np.concatenate(rows), np.concatenate(cols)
    a0 = sp.csr_matrix((np.concatenate(vals), (r, c)), shape=(n, n))
    a0_inv = sp.csr_matrix((np.concatenate(ivals), (r, c)), shape=(n, n))
    return a0, a0_inv


class _TwoLevelForm:
    """The SPD form B = (I - P R)^T A0 (I - P R) + R^T C R on n nodes, with B^{-1} = A0^{-1} + P C^{-1} P^T.

    This is the skeleton part B_Sk of B_Omega and the Signorini matrix M_s alike
    (METHOD.md section 6): in the basis {edge-interior hats} U {P e_c} the form is
    block diagonal, diag(A0, C), so B^{-1} needs only the edge inverses and C^{-1}.

    Parameters
    ----------
    a0, a0_inv : (n, n) sparse, block-diagonal edge forms on the edge-interior nodes
        (zero rows and columns at the coarse nodes) and their block inverses.
    interp : (n, n_c) sparse P, coarse values -> node values (unit rows at the coarse nodes).
    coarse_nodes : (n_c,) node number of each coarse unknown (R picks these).
    coarse : (n_c, n_c) SPD; a dense ndarray gets a dense Cholesky factor, a sparse
        matrix a sparse one.
    """

    def __init__(self, a0: sp.spmatrix, a0_inv: sp.spmatrix, interp: sp.spmatrix,
                 coarse_nodes: np.ndarray, coarse: np.ndarray | sp.spmatrix) -> None:
        n, n_c = interp.shape
        restrict = sp.csr_matrix((np.ones(n_c), (np.arange(n_c), coarse_nodes)), shape=(n_c, n))
        q = (sp.identity(n, format="csr") - interp @ restrict).tocsr()
        self.matrix = (q.T @ a0 @ q + restrict.T @ sp.csr_matrix(coarse) @ restrict).tocsr()
        self.a0_inv = sp.csr_matrix(a0_inv)
        self.interp = sp.csr_matrix(interp)
        self.interp_t = self.interp.T.tocsr()
        self.n = n
        self._coarse = _SparseFactor(coarse) if sp.issparse(coarse) else _DenseFactor(np.asarray(coarse))

    def matvec(self, v: np.ndarray) -> np.ndarray:
        return self.matrix @ v

    def solve(self, r: np.ndarray) -> np.ndarray:
        return self.a0_inv @ r + self.interp @ self._coarse.solve(self.interp_t @ r)

    def destroy(self) -> None:
        self._coarse.destroy()


def _arc_length(points: np.ndarray) -> np.ndarray:
    """Cumulative arc length along polylines (..., k, dim) -> (..., k), starting at 0."""
    seg = np.linalg.norm(np.diff(points, axis=-2), axis=-1)
    return np.concatenate([np.zeros(seg.shape[:-1] + (1,)), np.cumsum(seg, axis=-1)], axis=-1)


def _skeleton_form(coarse: Any, x: np.ndarray, subdomain_size: float, n_nodes: int,
                   kind: str) -> _TwoLevelForm:
    """B_Sk of METHOD.md section 6 in the numbering of ``coarse.skeleton_dofs``.

    Edge forms A^0_gamma on the interior nodes of every coarse edge; Pi = linear
    interpolation in arc length between the two end vertices; C = coarse graph
    Laplacian + d * sum over coarse vertices on Gamma.
    """
    skeleton = np.asarray(coarse.skeleton_dofs, dtype=np.int64)
    vertex_dofs = np.asarray(coarse.vertex_dofs, dtype=np.int64)
    ends = np.asarray(coarse.edge_vertices, dtype=np.int64)
    on_boundary = np.asarray(coarse.vertex_on_boundary, dtype=bool)
    edge_dofs = as_ragged(coarse.edge_dofs, dtype=np.int64)
    n_v, n_e = len(vertex_dofs), len(edge_dofs)
    if ends.shape != (n_e, 2) or on_boundary.shape != (n_v,):
        raise ValueError(f"coarse.edge_vertices must be ({n_e}, 2) and coarse.vertex_on_boundary ({n_v},); check the coarse partition")
    if not on_boundary.any():
        raise ValueError("no coarse vertex lies on Gamma: the coarse matrix C would be singular; mark the boundary vertices")
    pos = np.full(n_nodes, -1, dtype=np.int64)
    pos[skeleton] = np.arange(len(skeleton))
    n_sk = len(skeleton)
    if np.any(pos[vertex_dofs] < 0):
        raise ValueError("every coarse vertex dof must be a skeleton dof; check coarse.vertex_dofs and coarse.skeleton_dofs")
    count = np.bincount(pos[vertex_dofs], minlength=n_sk)
    rows, cols, vals = [pos[vertex_dofs]], [np.arange(n_v)], [np.ones(n_v)]
    groups = []
    for length, group in edge_dofs.length_groups():
        dofs = edge_dofs.rows(group)  # (B, n+1)
        if length < 2 or np.any(dofs[:, 0] != vertex_dofs[ends[group, 0]]) or np.any(dofs[:, -1] != vertex_dofs[ends[group, 1]]):
            raise ValueError("coarse.edge_dofs must run from the dof of edge_vertices[:, 0] to that of edge_vertices[:, 1]")
        inner = pos[dofs[:, 1:-1]]
        if np.any(inner < 0):
            raise ValueError("every dof along a coarse edge must be a skeleton dof; check coarse.edge_dofs")
        count += np.bincount(inner.ravel(), minlength=n_sk)
        pts = x[dofs]
        t = edge_weights(pts)
        rows += [inner.ravel(), inner.ravel()]
        cols += [np.repeat(ends[group, 0], length - 2), np.repeat(ends[group, 1], length - 2)]
        vals += [(1.0 - t).ravel(), t.ravel()]
        groups.append((inner, pts))
    if np.any(count != 1):
        raise ValueError(
            "each skeleton dof must be exactly one coarse vertex or one interior node of one coarse edge; "
            f"{np.count_nonzero(count == 0)} are on none and {np.count_nonzero(count > 1)} on several"
        )
    interp = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_sk, n_v))
    a0, a0_inv = _block_diagonal(groups, n_sk, kind)
    return _TwoLevelForm(a0, a0_inv, interp, pos[vertex_dofs], coarse_matrix(coarse, subdomain_size))


def coarse_matrix(coarse: Any, subdomain_size: float) -> sp.csc_matrix:
    """C of METHOD.md section 6: the coarse graph Laplacian + d * sum over the coarse
    vertices on Gamma, sum_{(v_i, v_j)} (u_i - u_j)^2 + d sum_{v on Gamma} u(v)^2."""
    ends = np.asarray(coarse.edge_vertices, dtype=np.int64)
    on_boundary = np.asarray(coarse.vertex_on_boundary, dtype=float)
    n_e, n_v = len(ends), len(on_boundary)
    incidence = sp.csr_matrix(
        (np.tile([1.0, -1.0], n_e), (np.repeat(np.arange(n_e), 2), ends.ravel())), shape=(n_e, n_v)
    )
    return (incidence.T @ incidence + sp.diags(subdomain_size * on_boundary)).tocsc()


def edge_weights(points: np.ndarray) -> np.ndarray:
    """Pi on the interior nodes of coarse edges (batch, n+1, dim): the arc-length position
    t in (0, 1) of every interior node; its value is (1 - t) u(end 0) + t u(end 1)."""
    s = _arc_length(points)
    return s[:, 1:-1] / s[:, -1:]


def _signorini_form(arcs: Sequence[SignoriniArc], subdomain_size: float, kind: str) -> _TwoLevelForm:
    """M_s of METHOD.md section 6 ("Signorini block") as a two-level form on the phi unknowns.

    On each arc: edge forms A^0_gamma on the coarse edges of the arc (phi_e), and the
    formula (5.1) one level up on the coarse vertices (arc-length positions, so uneven
    coarse edges get arc-length weights); for a closed arc the distances are taken
    along the curve and the end-point term is d * sum phi(v)^2. Arcs do not couple.
    """
    n_s = sum(len(arc.unknowns) for arc in arcs)
    every = np.concatenate([arc.unknowns for arc in arcs]) if arcs else np.zeros(0, np.int64)
    if not np.array_equal(np.sort(every), np.arange(n_s)):
        raise ValueError(f"the unknowns of the Signorini arcs must number the phi vector 0..{n_s - 1}, each once")
    groups = []
    rows, cols, vals = [], [], []
    coarse_nodes, coarse_blocks = [], []
    n_c = 0
    for arc in arcs:
        if arc.closed:
            # start at a coarse vertex and repeat it at the end: a chain of coarse edges
            k = arc.coords.shape[0]
            order = (np.arange(k + 1) + np.argmax(arc.coarse_vertex_mask)) % k
            pts, phi_index = arc.coords[order], arc.unknowns[order]
            corners = np.flatnonzero(arc.coarse_vertex_mask[order])  # includes 0 and k
            c_pos = corners[:-1]
        else:
            pts = arc.coords
            phi_index = np.concatenate([[-1], arc.unknowns, [-1]])  # the end points carry no phi
            corners = np.flatnonzero(arc.coarse_vertex_mask)
            c_pos = corners[1:-1]
        s = _arc_length(pts)
        c_index = np.full(len(pts), -1, dtype=np.int64)
        c_index[c_pos] = n_c + np.arange(len(c_pos))
        if arc.closed:
            c_index[-1] = c_index[0]
            coarse_blocks.append(closed_paper_form(s[c_pos], s[-1], subdomain_size))
        else:
            coarse_blocks.append(paper_edge_form(s[corners]) if len(c_pos) else np.zeros((0, 0)))
        coarse_nodes.append(phi_index[c_pos])
        rows.append(phi_index[c_pos])
        cols.append(c_index[c_pos])
        vals.append(np.ones(len(c_pos)))
        n_c += len(c_pos)
        for a, b in zip(corners[:-1], corners[1:]):
            inner = np.arange(a + 1, b)
            groups.append((phi_index[inner][None, :], pts[a:b + 1][None]))
            t = (s[inner] - s[a]) / (s[b] - s[a])
            for end, weight in ((a, 1.0 - t), (b, t)):
                if c_index[end] >= 0:
                    rows.append(phi_index[inner])
                    cols.append(np.full(len(inner), c_index[end]))
                    vals.append(weight)
    interp = sp.csr_matrix((_concat(vals, float), (_concat(rows, np.int64), _concat(cols, np.int64))), shape=(n_s, n_c))
    a0, a0_inv = _block_diagonal(groups, n_s, kind)
    coarse = sla.block_diag(*coarse_blocks) if coarse_blocks else np.zeros((0, 0))
    return _TwoLevelForm(a0, a0_inv, interp, _concat(coarse_nodes, np.int64), coarse)


def _concat(parts: list[np.ndarray], dtype: type) -> np.ndarray:
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)


class SignoriniBlock:
    """omega B_s of METHOD.md section 6 ("Signorini block"): the Signorini half of B.

    Small (one unknown per Signorini node) and replicated on every rank; shared by the
    serial and the distributed substructuring preconditioners.
    """

    def _init_signorini(self, arcs: Sequence[SignoriniArc], subdomain_size: float, kind: str,
                        weight: float) -> None:
        """Check the options shared by B_Omega and B_s, and build omega M_s."""
        if kind not in EDGE_FORMS:
            raise ValueError(f"edge_form must be one of {EDGE_FORMS}, got {kind!r}")
        if not subdomain_size > 0.0:
            raise ValueError(f"subdomain_size must be positive, got {subdomain_size}")
        if not weight > 0.0:
            raise ValueError(f"signorini_weight must be positive, got {weight}")
        self.edge_form, self.subdomain_size = kind, float(subdomain_size)
        self.signorini_weight = float(weight)
        self._signorini = _signorini_form(tuple(arcs), subdomain_size, kind)
        self.n_signorini = self._signorini.n
        self._lambda_max: float | None = None

    def apply_signorini(self, g: np.ndarray) -> np.ndarray:
        """phi = (omega M_s)^{-1} g with M_s^{-1} = (A^0_s)^{-1} + P_s C_s^{-1} P_s^T (exact)."""
        return self._signorini.solve(_check_length(g, self.n_signorini, "g")) / self.signorini_weight

    def matvec_signorini(self, phi: np.ndarray) -> np.ndarray:
        """omega M_s phi, the matrix of omega B_s (METHOD.md section 6)."""
        return self.signorini_weight * self._signorini.matvec(_check_length(phi, self.n_signorini, "phi"))

    @property
    def signorini_metric(self) -> np.ndarray:
        """omega M_s as a dense n_s x n_s array (the metric of the projection (3.19)-(3.20))."""
        return self.signorini_weight * self._signorini.matrix.toarray()

    @property
    def lambda_max_signorini(self) -> float:
        """Largest eigenvalue of omega M_s (0 without Signorini unknowns); bounds theta in (3.20)."""
        if self._lambda_max is None:  # of M_s, computed on first use
            m = self._signorini.matrix
            if m.shape[0] == 0:
                self._lambda_max = 0.0
            elif m.shape[0] <= 400:
                self._lambda_max = float(sla.eigvalsh(m.toarray(), subset_by_index=[m.shape[0] - 1] * 2)[0])
            else:
                self._lambda_max = float(spla.eigsh(m, k=1, which="LA", return_eigenvectors=False, tol=1e-10)[0])
        return self.signorini_weight * self._lambda_max


class SubstructuringPreconditioner(SignoriniBlock):
    """The substructuring preconditioner B = B_Omega + omega B_s of METHOD.md section 6.

    Parameters
    ----------
    stiffness : (N, N) sparse
        P1 Laplace stiffness matrix A on the fine mesh (symmetric).
    coarse : object
        Coarse partition (attributes listed in the module docstring).
    x : (N, 2) array
        Node coordinates.
    subdomain_size : float
        d, the size of the subdomains (weights the boundary-vertex term of C and the
        zero-order term of a closed Signorini arc).
    signorini_arcs : sequence of SignoriniArc
        The arcs of Gamma_s; their ``unknowns`` number the phi vector.
    edge_form : {"paper", "sqrt-laplacian"}
        A^0_gamma: the paper's formula (5.1) or the spectral square root of the edge
        Laplacian (see ``coupling.edge_forms``). Used on the skeleton and on the
        coarse edges of the Signorini arcs; the coarse form of B_s is always (5.1).
    signorini_weight : float
        omega > 0 multiplying B_s (our extension; METHOD.md section 6 reports that
        omega = 1/4 halves kappa).

    Notes
    -----
    Set-up factorises A_II once (one sparse Cholesky factor of the block-diagonal
    matrix of all local Dirichlet problems, PETSc built-in with nested dissection; see
    ``_SparseFactor`` for the measured alternatives), stores all (A^0_gamma)^{-1} as one
    block-diagonal sparse matrix, Pi as a sparse matrix, C by a sparse Cholesky factor
    (C is the sparse coarse graph Laplacian, with up to ~1e4 vertices at d/h = 4 on
    2.5e5 nodes, too many for a dense factor) and M_s^{-1} = (A^0_s)^{-1} + P_s C_s^{-1} P_s^T
    with a dense Cholesky factor of the small dense C_s. An application has no Python
    loop: two A_II solves, sparse products and one coarse solve. Measured on 263169
    nodes (structured square, d/h = 4, 8, 16): set-up 0.4-0.7 s, ``apply_omega``
    7-22 ms, ``matvec_omega`` 7-18 ms.

    The PETSc objects live on ``PETSc.COMM_SELF``; call :meth:`destroy` when done.
    """

    def __init__(self, stiffness: sp.spmatrix, coarse: Any, x: np.ndarray, subdomain_size: float,
                 signorini_arcs: Sequence[SignoriniArc] = (), *, edge_form: str = "paper",
                 signorini_weight: float = 1.0) -> None:
        self._init_signorini(signorini_arcs, subdomain_size, edge_form, signorini_weight)
        a = sp.csr_matrix(stiffness, dtype=float)
        n = a.shape[0]
        x = np.asarray(x, dtype=float)
        if a.shape != (n, n) or x.ndim != 2 or x.shape[0] != n:
            raise ValueError(f"stiffness must be square and x must have one row per node; got {a.shape} and {x.shape}")
        interior = np.asarray(coarse.interior_dofs, dtype=np.int64)
        skeleton = np.asarray(coarse.skeleton_dofs, dtype=np.int64)
        if len(interior) + len(skeleton) != n or not np.array_equal(
                np.bincount(np.concatenate([interior, skeleton]), minlength=n), np.ones(n, dtype=np.int64)):
            raise ValueError("coarse.interior_dofs and coarse.skeleton_dofs must split the nodes 0..N-1 into two disjoint sets")
        if np.any(np.diff(skeleton) <= 0):
            raise ValueError("coarse.skeleton_dofs must be sorted and unique")
        if n and abs(a - a.T).max() > 1e-12 * abs(a).max():
            raise ValueError("stiffness must be symmetric (the P1 Laplace matrix A); got a nonsymmetric matrix")
        self.n_omega = n
        self._interior = interior
        self._skeleton = skeleton
        a_i = a[interior]
        self._a_ii = a_i[:, interior].tocsr()
        self._a_is = a_i[:, skeleton].tocsr()
        self._a_si = self._a_is.T.tocsr()  # A is symmetric
        self._interior_factor = _SparseFactor(self._a_ii)
        self._skeleton_form = _skeleton_form(coarse, x, self.subdomain_size, n, edge_form)

    # -- the local Dirichlet problems (rank-local in coupling.distributed_substructuring) --
    def solve_interior(self, g_i: np.ndarray) -> np.ndarray:
        """x_I = A_II^{-1} g_I: independent Dirichlet problems on all subdomains (step 1 and 4)."""
        return self._interior_factor.solve(g_i)

    # -- B_Omega --
    def apply_omega(self, g: np.ndarray) -> np.ndarray:
        """u = B_Omega^{-1} g, the four steps of METHOD.md section 6.

        1. x_I = A_II^{-1} g_I; 2. r = g_Sk - A_{Sk,I} x_I;
        3. v = (A^0)^{-1} r + Pi C^{-1} Pi^T r; 4. u_Sk = v, u_I = x_I - A_II^{-1} A_{I,Sk} v.
        ``g`` may be (N,) or (N, k).
        """
        g = _check_length(g, self.n_omega, "g")
        x_i = self.solve_interior(g[self._interior])
        v = self._skeleton_form.solve(g[self._skeleton] - self._a_si @ x_i)
        u = np.empty_like(g)
        u[self._interior] = x_i - self.solve_interior(self._a_is @ v)
        u[self._skeleton] = v
        return u

    def matvec_omega(self, u: np.ndarray) -> np.ndarray:
        """B_Omega u = [A_II u_I + A_ISk u_Sk; A_SkI u_I + A_SkI A_II^{-1} A_ISk u_Sk + B_Sk u_Sk] (one A_II solve)."""
        u = _check_length(u, self.n_omega, "u")
        u_i, u_s = u[self._interior], u[self._skeleton]
        y = self._a_is @ u_s
        out = np.empty_like(u)
        out[self._interior] = self._a_ii @ u_i + y
        out[self._skeleton] = self._a_si @ (u_i + self.solve_interior(y)) + self._skeleton_form.matvec(u_s)
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
