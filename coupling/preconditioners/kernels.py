"""Building blocks shared by the substructuring preconditioners (docs/method.md section 6):
factors computed once, the block-diagonal edge forms, the two-level form
B = (I - P R)^T A0 (I - P R) + R^T C R, the coarse matrix C and the arc-length
interpolation Pi along coarse edges.
"""
from __future__ import annotations

import functools
from typing import Any, Callable, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from petsc4py import PETSc
from scipy.sparse.csgraph import connected_components
from threadpoolctl import threadpool_limits

from bem_cpp.sparse import SparseCholesky
from coupling.options import NATURAL_ORDERING_MAX_BLOCK
from coupling.preconditioners.edge_forms import edge_form
from fem_py.partition import as_ragged
from fem_py.polyline import arc_length

__all__ = [
    "SparseFactor",
    "nested_dissection",
    "fill_reducing_ordering",
    "largest_subdomain_interior",
    "is_symmetric",
    "DenseFactor",
    "block_diagonal_edge_forms",
    "TwoLevelForm",
    "coarse_matrix",
    "coarse_vertex_pattern",
    "probing_colours",
    "galerkin_coarse_matrix",
    "hat_support_on_gamma",
    "edge_weights",
]


def is_symmetric(matrix: sp.spmatrix, rtol: float = 1e-12) -> bool:
    """Whether max |a_ij - a_ji| <= rtol max |a_ij|. With the sparsity pattern symmetric
    (the P1 matrices) it compares the entries of A and A^T directly, one transposition
    and no sparse subtraction."""
    a = sp.csr_matrix(matrix, dtype=float)
    if a.nnz == 0:
        return True
    if not a.has_canonical_format:  # sorted indices, no duplicates (as A^T's CSR is)
        a = a.copy()  # the caller's matrix is left as it was
        a.sum_duplicates()
    t = a.T.tocsr()
    scale = rtol * np.abs(a.data).max()
    if np.array_equal(a.indptr, t.indptr) and np.array_equal(a.indices, t.indices):
        return bool(np.abs(a.data - t.data).max() <= scale)
    return bool(abs(a - t).max() <= scale)


def fill_reducing_ordering(matrix: sp.spmatrix, largest_block: int | None = None) -> str:
    """The PETSc ordering for the Cholesky factor of ``matrix``: "natural" when every
    connected component of its graph (a block of a block-diagonal matrix, such as A_II:
    one block per subdomain) has at most NATURAL_ORDERING_MAX_BLOCK rows, "nd" (nested
    dissection) otherwise. Fill never crosses components, and within a small block the
    mesh's own locality-preserving numbering fills about as little as nested dissection,
    whose ordering of the whole graph costs several times the factorisation.

    ``largest_block``: a bound on the components' sizes known to the caller (A_II's
    components lie within subdomains: the most interior dofs of a subdomain), which spares
    finding the components when it is small enough."""
    n = matrix.shape[0]
    if n == 0:
        return "nd"
    if largest_block is not None and largest_block <= NATURAL_ORDERING_MAX_BLOCK:
        return "natural"
    _, labels = connected_components(matrix, directed=False)
    return "natural" if np.bincount(labels).max() <= NATURAL_ORDERING_MAX_BLOCK else "nd"


def largest_subdomain_interior(coarse: Any) -> int | None:
    """The most interior dofs of one subdomain of a coarse structure (a bound on the blocks
    of A_II), or None if it does not say which subdomain each interior dof is in."""
    labels = getattr(coarse, "subdomain_of_interior_dof", None)
    if labels is None or len(labels) == 0:
        return None
    return int(np.bincount(np.asarray(labels, dtype=np.int64)).max())


class SparseFactor:
    """Sparse Cholesky factor of an SPD matrix, computed once and rank-local.

    ``ordering="nd"`` (a connected graph, such as the coarse matrix C): bem_cpp's
    supernodal multifrontal factor (:class:`bem_cpp.sparse.SparseCholesky`) on PETSc's
    nested-dissection ordering. ``"natural"`` (A_II: many small diagonal blocks, whose
    fronts are too small for dense kernels): PETSc's built-in Cholesky, row by row. Both
    chosen by measurement (docs/design/preconditioners.md).
    """

    def __init__(self, matrix: sp.spmatrix, ordering: str = "nd") -> None:
        m = sp.csr_matrix(matrix, dtype=float)
        self.n = m.shape[0]
        self._factor: Any = None
        self._alive = True
        if self.n == 0:
            return
        m = _canonical(m)
        # the Mat wraps the arrays (no copy, no insertion): they outlive it, as it is
        # destroyed below
        mat = _wrapped(m)
        try:
            if ordering == "natural":
                self._factor = _PetscCholesky(mat, ordering)
            else:
                self._factor = SparseCholesky(m, _petsc_ordering(mat, ordering))
        finally:
            mat.destroy()

    def solve(self, b: np.ndarray) -> np.ndarray:
        """A^{-1} b for b of shape (n,) or (n, k)."""
        if not self._alive:
            raise RuntimeError("this factor has been destroyed; build a new preconditioner")
        if self._factor is None:  # empty matrix
            return np.zeros_like(b, dtype=float)
        return self._factor.solve(b)

    def destroy(self) -> None:
        """Free the PETSc objects (call on every rank)."""
        if isinstance(self._factor, _PetscCholesky):
            self._factor.destroy()
        self._factor = None
        self._alive = False


def nested_dissection(matrix: sp.spmatrix) -> np.ndarray:
    """PETSc's nested-dissection ordering of a sparse symmetric matrix: ``ordering[i]``
    is the row that becomes row i (as :class:`bem_cpp.sparse.SparseCholesky` takes it)."""
    m = _canonical(sp.csr_matrix(matrix, dtype=float))
    if m.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    mat = _wrapped(m)
    try:
        return _petsc_ordering(mat, "nd")
    finally:
        mat.destroy()


def _canonical(m: sp.csr_matrix) -> sp.csr_matrix:
    """``m``, or a copy with sorted rows and no duplicates (PETSc's arrays)."""
    if m.has_canonical_format:
        return m
    m = m.copy()
    m.sum_duplicates()
    return m


def _wrapped(m: sp.csr_matrix) -> PETSc.Mat:
    """A sequential PETSc Mat on the arrays of ``m`` (no copy: they must outlive it)."""
    return PETSc.Mat().createAIJWithArrays(
        m.shape,
        (
            m.indptr.astype(PETSc.IntType, copy=False),
            m.indices.astype(PETSc.IntType, copy=False),
            m.data,
        ),
        comm=PETSc.COMM_SELF,
    )


def _petsc_ordering(mat: PETSc.Mat, ordering: str) -> np.ndarray:
    rows, columns = mat.getOrdering(ordering)
    try:
        return rows.getIndices().astype(np.int64)
    finally:
        rows.destroy()
        columns.destroy()


class _PetscCholesky:
    """PETSc's built-in Cholesky factor of ``mat`` (COMM_SELF) with ``ordering``."""

    def __init__(self, mat: PETSc.Mat, ordering: str) -> None:
        self.n = mat.getSize()[0]
        mat.setOption(PETSc.Mat.Option.SPD, True)
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setOperators(mat)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("petsc")
        pc.setFactorOrdering(ordering)
        ksp.setUp()
        # only the factor is kept: PETSc's copy of the matrix goes with the KSP
        self._factor = pc.getFactorMatrix()
        self._rhs, self._sol = mat.createVecs()
        ksp.destroy()

    def solve(self, b: np.ndarray) -> np.ndarray:
        if b.ndim == 1:  # the Vecs wrap b and the result: no copies in and out
            out, rhs = np.empty(self.n), np.ascontiguousarray(b, dtype=float)
            self._rhs.placeArray(rhs)
            self._sol.placeArray(out)
            try:
                self._factor.solve(self._rhs, self._sol)
            finally:
                self._rhs.resetArray()
                self._sol.resetArray()
            return out
        out = np.zeros(b.shape, order="F")
        rhs = PETSc.Mat().createDense(
            b.shape, array=np.asfortranarray(b, dtype=float), comm=PETSc.COMM_SELF
        )
        sol = PETSc.Mat().createDense(b.shape, array=out, comm=PETSc.COMM_SELF)
        self._factor.matSolve(rhs, sol)
        rhs.destroy()
        sol.destroy()
        return np.ascontiguousarray(out)

    def destroy(self) -> None:
        for obj in (self._rhs, self._sol, self._factor):
            obj.destroy()


class DenseFactor:
    """Dense Cholesky factor of a small SPD matrix (LAPACK), computed once."""

    def __init__(self, matrix: np.ndarray) -> None:
        self._factor = sla.cho_factor(matrix, lower=True) if matrix.size else None

    def solve(self, b: np.ndarray) -> np.ndarray:
        return (
            sla.cho_solve(self._factor, b)
            if self._factor is not None
            else np.zeros_like(b, dtype=float)
        )

    def destroy(self) -> None:
        pass


def block_diagonal_edge_forms(
    groups: Sequence[tuple[np.ndarray, np.ndarray]], n: int, kind: str
) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """All edge forms A^0_gamma and their inverses as two block-diagonal n x n sparse matrices.

    Each group is ``(ix, pts)`` for a batch of edges with equal node counts: ``ix (B, m)``
    the (local) numbers of the interior nodes, ``pts (B, m+2, dim)`` the nodes with both ends.
    """
    batches: dict[tuple, list] = {}  # one batch per shape: one edge_form call each
    for ix, pts in groups:
        if ix.shape[1]:
            batches.setdefault(pts.shape[1:], []).append((ix, pts))
    blocks = []
    # tiny batched LAPACK calls: threads only add overhead (docs/design/preconditioners.md)
    with threadpool_limits(limits=1):
        for batch in batches.values():
            ix = np.concatenate([b[0] for b in batch])
            blocks.append((ix, *_edge_forms_by_shape(np.concatenate([b[1] for b in batch]), kind)))
    return _block_diagonal(blocks, n)


def _edge_forms_by_shape(points: np.ndarray, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """:func:`edge_form` of every edge of the batch ``points`` (B, m+2[, dim]), computed once
    per distinct shape.

    A form depends on the nodes through their differences only, so it is computed from the
    nodes less the first one: the edges of a structured grid, translates of a few shapes,
    share a handful of computations, and an edge's form does not depend on the other edges
    of its batch (so on the rank that computes it)."""
    relative = points - points[:, :1]
    if len(relative) == 0:  # a rank without such edges
        return edge_form(relative, kind)
    flat = relative.reshape(len(relative), -1)
    key = flat @ np.sqrt(np.arange(2.0, 2.0 + flat.shape[1]))  # equal for equal rows
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    representative = first[inverse]
    if not np.array_equal(flat, flat[representative]):  # one key for different rows: rare
        return edge_form(relative, kind)
    a0, a0_inv = edge_form(relative[first], kind)
    return a0[inverse], a0_inv[inverse]


def _block_diagonal(
    blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]], n: int
) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The two n x n sparse matrices of the dense blocks ``(ix, a, b)``: a and b (B, m, m)
    on the rows and columns ix (B, m), with one sparsity structure. Where no row is in two
    blocks (the edges' interior nodes), the CSR arrays are written directly, each row's
    entries at its offset; otherwise the blocks are summed through COO."""
    if not blocks:
        return sp.csr_matrix((n, n)), sp.csr_matrix((n, n))
    rows = np.concatenate([ix.ravel() for ix, _, _ in blocks])
    if np.bincount(rows, minlength=n).max(initial=0) > 1:
        r = np.concatenate(
            [np.broadcast_to(ix[:, :, None], a.shape).ravel() for ix, a, _ in blocks]
        )
        c = np.concatenate(
            [np.broadcast_to(ix[:, None, :], a.shape).ravel() for ix, a, _ in blocks]
        )
        return tuple(
            sp.csr_matrix(
                (np.concatenate([blk[k].ravel() for blk in blocks]), (r, c)), shape=(n, n)
            )
            for k in (1, 2)
        )
    row_length = np.zeros(n, dtype=np.int64)
    for ix, _, _ in blocks:
        row_length[ix] = ix.shape[1]
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(row_length, out=indptr[1:])
    indices = np.empty(indptr[-1], dtype=np.int64)
    data = (np.empty(indptr[-1]), np.empty(indptr[-1]))
    for ix, a, b in blocks:
        at = (indptr[ix][:, :, None] + np.arange(ix.shape[1])).ravel()
        indices[at] = np.broadcast_to(ix[:, None, :], a.shape).ravel()
        data[0][at], data[1][at] = a.ravel(), b.ravel()
    # each matrix its own index array: an in-place sort_indices of one must not reach the other
    return (
        sp.csr_matrix((data[0], indices, indptr), shape=(n, n)),
        sp.csr_matrix((data[1], indices.copy(), indptr.copy()), shape=(n, n)),
    )


class TwoLevelForm:
    """The SPD form B = (I - P R)^T A0 (I - P R) + R^T C R on n nodes, with
    B^{-1} = A0^{-1} + P C^{-1} P^T.

    This is the skeleton part B_Sk of B_Omega and the Signorini matrix M_s alike
    (docs/method.md section 6): in the basis {edge-interior hats} U {P e_c} the form is
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

    def __init__(
        self,
        a0: sp.spmatrix,
        a0_inv: sp.spmatrix,
        interp: sp.spmatrix,
        coarse_nodes: np.ndarray,
        coarse: np.ndarray | sp.spmatrix,
    ) -> None:
        n = interp.shape[0]
        self.a0 = sp.csr_matrix(a0)
        self.a0_inv = sp.csr_matrix(a0_inv)
        self.interp = sp.csr_matrix(interp)
        self.interp_t = self.interp.T.tocsr()
        self.coarse_nodes = np.asarray(coarse_nodes, dtype=np.int64)
        self.coarse_form = sp.csr_matrix(coarse) if sp.issparse(coarse) else np.asarray(coarse)
        self.n = n
        self._coarse = (
            SparseFactor(coarse) if sp.issparse(coarse) else DenseFactor(np.asarray(coarse))
        )

    def matvec(self, v: np.ndarray) -> np.ndarray:
        """B v = Q^T A0 Q v + R^T C R v with Q = I - P R, as products (no assembled B):
        R v = v at the coarse nodes, Q^T w = w - R^T P^T w."""
        v_c = v[self.coarse_nodes]
        out = self.a0 @ (v - self.interp @ v_c)
        out[self.coarse_nodes] += self.coarse_form @ v_c - self.interp_t @ out
        return out

    @functools.cached_property
    def matrix(self) -> sp.csr_matrix:
        """B as a sparse matrix (assembled on first use: the dense forms of small problems
        and the metric M_s)."""
        n, n_c = self.interp.shape
        restrict = sp.csr_matrix(
            (np.ones(n_c), (np.arange(n_c), self.coarse_nodes)), shape=(n_c, n)
        )
        q = (sp.identity(n, format="csr") - self.interp @ restrict).tocsr()
        coarse = sp.csr_matrix(self.coarse_form)
        return (q.T @ self.a0 @ q + restrict.T @ coarse @ restrict).tocsr()

    def solve(self, r: np.ndarray) -> np.ndarray:
        return self.a0_inv @ r + self.interp @ self._coarse.solve(self.interp_t @ r)

    def destroy(self) -> None:
        self._coarse.destroy()


def coarse_matrix(coarse: Any, subdomain_size: float) -> sp.csc_matrix:
    """C of docs/method.md section 6: the coarse graph Laplacian + d * sum over the coarse
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
    s = arc_length(points)
    return s[:, 1:-1] / s[:, -1:]


def coarse_vertex_pattern(coarse: Any) -> sp.csr_matrix:
    """The pattern of the Galerkin coarse matrix: coarse vertices i, j couple when they
    lie on the boundary of one subdomain (the subdomains of a vertex are those of its
    coarse edges, ``coarse.edge_subdomains``, -1 for Gamma)."""
    ends = np.asarray(coarse.edge_vertices, dtype=np.int64)
    sides = np.asarray(coarse.edge_subdomains, dtype=np.int64)
    n_v = len(np.asarray(coarse.vertex_dofs))
    v = np.repeat(ends, 2, axis=1).ravel()  # each end with each side: a a b b
    s = np.tile(sides, (1, 2)).ravel()  # s0 s1 s0 s1
    keep = s >= 0
    member = sp.csr_matrix(
        (np.ones(int(keep.sum())), (v[keep], s[keep])), shape=(n_v, int(coarse.n_subdomains))
    )
    pattern = (member @ member.T).tocsr()
    pattern.data[:] = 1.0
    return pattern


def probing_colours(pattern: sp.csr_matrix) -> np.ndarray:
    """A colouring of the columns of a sparse symmetric ``pattern`` such that no row has
    two nonzero columns of one colour (a distance-2 colouring of its graph), so that the
    products of the matrix with the K colour indicator vectors determine every entry.

    Jones-Plassmann: in every round the uncoloured vertices whose (fixed, distinct)
    priority beats that of all their uncoloured conflicting vertices take the smallest
    colour none of their coloured conflicting vertices has. The result is a function of
    the pattern only, the same on every rank.
    """
    n = pattern.shape[0]
    conflict = (pattern @ pattern).tocsr()  # columns sharing a row
    conflict.setdiag(0)
    conflict.eliminate_zeros()
    conflict.sort_indices()
    row = np.repeat(np.arange(n), np.diff(conflict.indptr))
    col = conflict.indices.astype(np.int64)
    priority = np.random.default_rng(seed=0).permutation(n)  # fixed, distinct
    colour = np.full(n, -1, dtype=np.int64)
    while np.any(colour < 0):
        rival = (colour[col] < 0) & (priority[col] > priority[row])
        chosen = (colour < 0) & (np.bincount(row[rival], minlength=n) == 0)
        # the smallest colour missing among the coloured neighbours of each chosen vertex
        taken = chosen[row] & (colour[col] >= 0)
        width = int(colour.max()) + 2
        key = np.unique(row[taken] * width + colour[col[taken]])
        v, c = key // width, key % width
        rank = np.arange(len(v)) - np.searchsorted(v, v)  # position among the vertex's colours
        gap = np.bincount(v, minlength=n)  # no gap: the next colour after the taken ones
        np.minimum.at(gap, v[c != rank], rank[c != rank])
        colour[chosen] = gap[chosen]
        keep = colour[row] < 0  # only the uncoloured vertices' rows are needed again
        row, col = row[keep], col[keep]
    return colour


def galerkin_coarse_matrix(
    coarse: Any, subdomain_size: float, schur_of: Callable[[np.ndarray], np.ndarray]
) -> sp.csc_matrix:
    """C = Pi^T S Pi + sum_{v on Gamma} d_v u(v)^2: the coarse term of docs/method.md section 6
    with the coarse graph Laplacian replaced by the exact energy of the coarse functions,
    and d_v = min(d, the length of Gamma the coarse hat of v covers)
    (:func:`hat_support_on_gamma`): d as in the paper wherever the coarse vertices on
    Gamma are at least d/2 apart, less where subdomains smaller than d meet Gamma (the
    split subdomains of an adapted mesh), which d would over-weight.

    S is the Schur complement of the P1 Laplace matrix on the skeleton, so that
    (Pi e_i)^T S (Pi e_j) is the energy of the discrete harmonic extension of the
    function linear along the coarse edges with the vertex values e_i, e_j. On a
    shape-regular coarse grid this is spectrally equivalent to the graph Laplacian (the
    paper's choice); on subdomains cut from a mesh's cells (jagged interfaces, short
    coarse edges) it is not, and this one follows the partition.

    ``schur_of(E)`` returns Pi^T S Pi E for an (n_v, K) block E of coarse vertex values
    (collective under MPI). It is called once with the K colour indicators of
    :func:`probing_colours` (K about 20-40 for a 2D partition), i.e. K local Dirichlet
    solves on every subdomain.
    """
    pattern = coarse_vertex_pattern(coarse)
    colour = probing_colours(pattern)
    n_v = pattern.shape[0]
    indicators = np.zeros((n_v, int(colour.max()) + 1))
    indicators[np.arange(n_v), colour] = 1.0
    product = schur_of(indicators)  # (n_v, K): column k = sum of the columns of colour k
    coo = pattern.tocoo()
    values = product[coo.row, colour[coo.col]]
    galerkin = sp.csr_matrix((values, (coo.row, coo.col)), shape=(n_v, n_v))
    galerkin = 0.5 * (galerkin + galerkin.T)  # symmetric up to the solver's round-off
    support = hat_support_on_gamma(coarse)
    weights = np.where(support > 0, np.minimum(subdomain_size, support), 0.0)
    return (galerkin + sp.diags(weights)).tocsc()


def hat_support_on_gamma(coarse: Any) -> np.ndarray:
    """For every coarse vertex, the length of Gamma its coarse hat function covers (the
    arc lengths of its coarse edges on Gamma; 0 off Gamma), (n_v,)."""
    edges = as_ragged(coarse.edge_coords, dtype=float, item_shape=(2,))
    ends = np.asarray(coarse.edge_vertices, dtype=np.int64)
    on_gamma = np.asarray(coarse.edge_on_boundary, dtype=bool)
    step = np.linalg.norm(np.diff(edges.flat, axis=0), axis=1)
    cumulative = np.concatenate([[0.0], np.cumsum(step)])
    first, last = edges.offsets[:-1], edges.offsets[1:] - 1
    length = cumulative[last] - cumulative[first]  # the steps inside each edge
    support = np.zeros(len(np.asarray(coarse.vertex_dofs)))
    np.add.at(support, ends[on_gamma, 0], length[on_gamma])
    np.add.at(support, ends[on_gamma, 1], length[on_gamma])
    return support
