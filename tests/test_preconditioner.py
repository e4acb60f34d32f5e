"""Tests of the substructuring preconditioner against the definitions of docs/method.md section 6.

The reference matrices here are assembled independently, by loops that read the
formulas literally: B_Omega from the change of basis {interior hats} U {harmonic
extensions of edge-interior hats} U {harmonic extensions of Pi e_v}, in which it is
block diagonal, diag(A_II, A^0, C); M_s likewise from {edge-interior hats} U {P_s e_v}.
Tolerances are round-off: the reference solves with B_Omega (cond ~ 1e3 here), so
errors up to eps * cond ~ 2e-13 are possible; measured <= 5e-15; RTOL = 1e-12.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from coupling.preconditioners import (
    IdentityPreconditioner,
    SignoriniArc,
    SubstructuringPreconditioner,
)
from coupling.preconditioners.base import DenseSignoriniBlock, largest_eigenvalue
from coupling.preconditioners.edge_forms import (
    closed_paper_form,
    edge_form,
    paper_edge_form,
    sqrt_laplacian_edge_form,
)
from coupling.preconditioners.kernels import block_diagonal_edge_forms, is_symmetric
from test_preconditioner_meshes import structured_square, substructuring

RTOL = 1e-12


# ---------------------------------------------------------------- references
def paper_form_loops(points: np.ndarray) -> np.ndarray:
    """(5.1) read literally: sum_{i<j} h_i h_j (phi_i-phi_j)^2/|x_i-x_j|^2
    + sum_i h_i phi_i^2 (1/|x_i-a| + 1/|x_i-b|)."""
    n = len(points) - 1
    dist = lambda p, q: float(np.linalg.norm(np.asarray(p) - np.asarray(q)))  # noqa: E731
    h = {
        i: 0.5 * (dist(points[i], points[i - 1]) + dist(points[i + 1], points[i]))
        for i in range(1, n)
    }
    a = np.zeros((n - 1, n - 1))
    for i in range(1, n):
        a[i - 1, i - 1] += h[i] * (
            1.0 / dist(points[i], points[0]) + 1.0 / dist(points[i], points[n])
        )
        for j in range(i + 1, n):
            w = h[i] * h[j] / dist(points[i], points[j]) ** 2
            a[i - 1, i - 1] += w
            a[j - 1, j - 1] += w
            a[i - 1, j - 1] -= w
            a[j - 1, i - 1] -= w
    return a


def sqrt_laplacian_reference(points: np.ndarray) -> np.ndarray:
    """M^{1/2} (M^{-1/2} L M^{-1/2})^{1/2} M^{1/2} with matrix square roots (scipy.linalg.sqrtm)."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    n = len(seg)
    lap, mass = np.zeros((n + 1, n + 1)), np.zeros((n + 1, n + 1))
    for k, length in enumerate(seg):  # element matrices of the P1 segments
        lap[k : k + 2, k : k + 2] += np.array([[1.0, -1.0], [-1.0, 1.0]]) / length
        mass[k : k + 2, k : k + 2] += np.array([[2.0, 1.0], [1.0, 2.0]]) * length / 6.0
    lap, mass = lap[1:-1, 1:-1], mass[1:-1, 1:-1]
    mh = np.real(sla.sqrtm(mass))
    mh_inv = np.linalg.inv(mh)
    return mh @ np.real(sla.sqrtm(mh_inv @ lap @ mh_inv)) @ mh


REFERENCE_FORMS = {"paper": paper_form_loops, "sqrt-laplacian": sqrt_laplacian_reference}


def reference_omega(prob, kind: str) -> np.ndarray:
    """Dense B_Omega from its definition, via the basis in which it is block diagonal."""
    a = prob.stiffness.toarray()
    c = prob.coarse
    n = a.shape[0]
    interior, skeleton = c.interior_dofs, c.skeleton_dofs
    pos = {int(g): k for k, g in enumerate(skeleton)}
    harmonic = np.zeros((n, len(skeleton)))  # discrete harmonic extension of skeleton values
    harmonic[skeleton, np.arange(len(skeleton))] = 1.0
    harmonic[interior] = -np.linalg.solve(
        a[np.ix_(interior, interior)], a[np.ix_(interior, skeleton)]
    )
    n_v = len(c.vertex_dofs)
    pi = np.zeros((len(skeleton), n_v))
    for v, dof in enumerate(c.vertex_dofs):
        pi[pos[int(dof)], v] = 1.0
    edge_nodes, blocks = [], []
    coarse = np.zeros((n_v, n_v))
    for (v0, v1), dofs in zip(c.edge_vertices, c.edge_dofs):
        pts = prob.x[dofs]
        for k in range(1, len(dofs) - 1):  # straight edges: arc length = distance from end 0
            t = np.linalg.norm(pts[k] - pts[0]) / np.linalg.norm(pts[-1] - pts[0])
            pi[pos[int(dofs[k])], v0] = 1.0 - t
            pi[pos[int(dofs[k])], v1] = t
            edge_nodes.append(pos[int(dofs[k])])
        blocks.append(REFERENCE_FORMS[kind](pts))
        coarse[v0, v0] += 1.0
        coarse[v1, v1] += 1.0
        coarse[v0, v1] -= 1.0
        coarse[v1, v0] -= 1.0
    for v in np.flatnonzero(c.vertex_on_boundary):
        coarse[v, v] += prob.d
    basis = np.hstack([np.eye(n)[:, interior], harmonic[:, edge_nodes], harmonic @ pi])
    form = sla.block_diag(a[np.ix_(interior, interior)], *blocks, coarse)
    basis_inv = np.linalg.inv(basis)
    return basis_inv.T @ form @ basis_inv


def reference_signorini(arcs, d: float, kind: str, uniform_formula: bool = False) -> np.ndarray:
    """Dense M_s from its definition (docs/method.md section 6, "Signorini block").

    With ``uniform_formula`` the coarse part is docs/method.md's formula in vertex indices,
    sum_{i<j} (.)^2/(j-i)^2 + sum_i (1/i + 1/(n_s-i)) (.)^2, valid for equal coarse edges.
    """
    n_s = sum(len(arc.unknowns) for arc in arcs)
    basis_cols, blocks = [], []
    for arc in arcs:
        pts, mask = arc.coords, arc.coarse_vertex_mask
        phi = np.full(len(pts), -1)
        if arc.closed:
            pts, mask = np.vstack([pts, pts[:1]]), np.append(mask, True)
            phi = np.append(arc.unknowns, arc.unknowns[0])
            assert arc.coarse_vertex_mask[
                0
            ], "reference expects node 0 of a closed arc to be a coarse vertex"
        else:
            phi[1:-1] = arc.unknowns
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        corners = np.flatnonzero(mask)
        free = corners[:-1] if arc.closed else corners[1:-1]
        for a, b in zip(corners[:-1], corners[1:]):
            blocks.append(REFERENCE_FORMS[kind](pts[a : b + 1]))
            for k in range(a + 1, b):
                col = np.zeros(n_s)
                col[phi[k]] = 1.0
                basis_cols.append(col)
        m = len(free)
        coarse = np.zeros((m, m))
        # H at a coarse vertex: mean length of its two coarse edges
        big_h = [
            0.5 * (s[corners[min(q + 1, len(corners) - 1)]] - s[corners[max(q - 1, 0)]])
            for q in range(len(corners))
        ]
        if arc.closed:  # wrap the neighbours of the first coarse vertex
            big_h[0] = 0.5 * (s[corners[1]] - s[corners[0]] + s[-1] - s[corners[-2]])
        off = 0 if arc.closed else 1
        for i in range(m):
            qi = i + off
            if arc.closed:
                coarse[i, i] += d
            elif uniform_formula:
                coarse[i, i] += 1.0 / qi + 1.0 / (len(corners) - 1 - qi)
            else:
                coarse[i, i] += big_h[qi] * (
                    1.0 / (s[corners[qi]] - s[0]) + 1.0 / (s[-1] - s[corners[qi]])
                )
            for j in range(i + 1, m):
                qj = j + off
                if uniform_formula:
                    w = 1.0 / (qj - qi) ** 2
                else:
                    dist = s[corners[qj]] - s[corners[qi]]
                    if arc.closed:
                        dist = min(dist, s[-1] - dist)
                    w = big_h[qi] * big_h[qj] / dist**2
                coarse[[i, j], [i, j]] += w
                coarse[i, j] -= w
                coarse[j, i] -= w
        blocks.append(coarse)
        for q in free:  # P_s e_v: linear in arc length on the neighbouring coarse edges
            col = np.zeros(n_s)
            for a, b in zip(corners[:-1], corners[1:]):
                if q in (a, b) or (arc.closed and q == corners[0] and b == corners[-1]):
                    for k in range(a + 1, b):
                        t = (s[k] - s[a]) / (s[b] - s[a])
                        col[phi[k]] = 1.0 - t if q == a else t
            col[phi[q]] = 1.0
            basis_cols.append(col)
    # columns in the order of the blocks: per arc, its edge-interior hats, then its coarse hats
    basis_inv = np.linalg.inv(np.array(basis_cols).T)
    return basis_inv.T @ sla.block_diag(*blocks) @ basis_inv


def relerr(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def graded_lines(n: int, width: float = 0.5) -> np.ndarray:
    """Grid lines graded towards 0 (x = width t^1.4), so every edge is uneven."""
    return width * np.linspace(0.0, 1.0, n + 1) ** 1.4


# ---------------------------------------------------------------- edge forms
@pytest.mark.parametrize("n", [2, 3, 7, 16])
def test_paper_form_uniform_identity(n):
    """On a uniform edge with n segments, (5.1) is
    sum_{i<j} (.)^2/(j-i)^2 + sum_i (1/i + 1/(n-i)) phi_i^2."""
    direction = np.array([0.6, 0.8])
    pts = np.array([0.1, -0.2]) + np.outer(np.linspace(0.0, 0.37, n + 1), direction)
    expected = np.zeros((n - 1, n - 1))
    for i in range(1, n):
        expected[i - 1, i - 1] += 1.0 / i + 1.0 / (n - i)
        for j in range(i + 1, n):
            w = 1.0 / (j - i) ** 2
            expected[[i - 1, j - 1], [i - 1, j - 1]] += w
            expected[i - 1, j - 1] -= w
            expected[j - 1, i - 1] -= w
    np.testing.assert_allclose(paper_edge_form(pts), expected, rtol=1e-13, atol=1e-13)


def test_edge_forms_match_references_on_uneven_edges():
    rng = np.random.default_rng(1)
    t = np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0.0, 1.0, 9)]))
    pts = np.array([0.2, 0.1]) + np.outer(0.3 * t, [np.cos(0.4), np.sin(0.4)])
    np.testing.assert_allclose(paper_edge_form(pts), paper_form_loops(pts), rtol=1e-12)
    a0, a0_inv = sqrt_laplacian_edge_form(pts)
    ref = sqrt_laplacian_reference(pts)
    assert relerr(a0, ref) < RTOL
    assert relerr(a0 @ a0_inv, np.eye(len(a0))) < RTOL
    for kind in ("paper", "sqrt-laplacian"):
        a, a_inv = edge_form(pts, kind)
        np.testing.assert_array_equal(a, a.T)
        assert np.linalg.eigvalsh(a).min() > 0.0
        assert relerr(a @ a_inv, np.eye(len(a))) < RTOL
    # batched = one by one
    batch = np.stack([pts, pts[::-1], 2.0 * pts])
    for kind in ("paper", "sqrt-laplacian"):
        a_b, inv_b = edge_form(batch, kind)
        for k in range(3):
            a, a_inv = edge_form(batch[k], kind)
            np.testing.assert_allclose(a_b[k], a, rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(inv_b[k], a_inv, rtol=1e-10, atol=1e-12)


def test_block_diagonal_edge_forms_place_every_block_and_sum_shared_rows():
    """The block-diagonal matrices of the edge forms, written directly into CSR arrays
    (every row in one block), equal a dense matrix filled block by block; rows in two
    blocks (not an edge's interior nodes, but allowed) are summed, as COO would."""
    rng = np.random.default_rng(3)
    n = 20
    rows = rng.permutation(n)[:13]
    # two batches of different node counts: 3 edges of 2 interior nodes, 1 of 3 (+ spare)
    pts2 = np.cumsum(rng.uniform(0.1, 1.0, (3, 4, 2)), axis=1)
    pts3 = np.cumsum(rng.uniform(0.1, 1.0, (2, 5, 2)), axis=1)
    groups = [(rows[:6].reshape(3, 2), pts2), (rows[6:12].reshape(2, 3), pts3)]

    def dense(groups, which):
        out = np.zeros((n, n))
        for ix, pts in groups:
            forms = edge_form(pts, "paper")[which]
            for k in range(len(ix)):
                out[np.ix_(ix[k], ix[k])] += forms[k]
        return out

    def close(a, b):  # the forms are computed from the nodes less the first: round-off
        np.testing.assert_allclose(a, b, rtol=0.0, atol=1e-14 * np.abs(b).max())

    a0, a0_inv = block_diagonal_edge_forms(groups, n, "paper")
    close(a0.toarray(), dense(groups, 0))
    close(a0_inv.toarray(), dense(groups, 1))
    shared = [(rows[:6].reshape(3, 2), pts2), (np.array([[rows[0], rows[12], rows[7]]]), pts3[:1])]
    a0, a0_inv = block_diagonal_edge_forms(shared, n, "paper")
    close(a0.toarray(), dense(shared, 0))
    close(a0_inv.toarray(), dense(shared, 1))
    assert block_diagonal_edge_forms([], n, "paper")[0].nnz == 0
    # a batch without edges (a rank without edges of that node count)
    none = [(np.zeros((0, 3), dtype=np.int64), np.zeros((0, 5, 2)))]
    assert all(m.nnz == 0 for m in block_diagonal_edge_forms(none, n, "paper"))


@pytest.mark.parametrize("kind", ["paper", "sqrt-laplacian"])
def test_translated_edges_share_one_form(kind):
    """Edges that are translates of each other (a structured grid's) get one form, computed
    once from the nodes less the first: the same bits for all six; each is the edge's own
    form to round-off (the batch's LAPACK calls may round the last bits otherwise than one
    call for one edge: 3e-15 relative with AVX-512), and the other edges of the batch get
    their own."""
    rng = np.random.default_rng(5)
    # eighths and whole shifts: the translates' differences are exact, as a grid's often are
    shape = np.cumsum(rng.integers(1, 8, (5, 2)) / 8.0, axis=0)
    shifts = rng.integers(-3, 4, (6, 1, 2)).astype(float)
    pts = np.concatenate([shape + shifts, np.cumsum(rng.uniform(0.1, 1.0, (2, 5, 2)), axis=1)])
    relative = pts - pts[:, :1]
    n = 3 * len(pts)
    a0, a0_inv = block_diagonal_edge_forms([(np.arange(n).reshape(-1, 3), pts)], n, kind)
    blocks = [
        (a0[rows][:, rows].toarray(), a0_inv[rows][:, rows].toarray())
        for rows in np.arange(n).reshape(-1, 3)
    ]
    for k, (form, inverse) in enumerate(blocks):
        if 0 < k < 6:  # a translate of edge 0: its form, shared
            np.testing.assert_array_equal(form, blocks[0][0])
            np.testing.assert_array_equal(inverse, blocks[0][1])
        expected = edge_form(relative[0 if k < 6 else k], kind)
        np.testing.assert_allclose(form, expected[0], rtol=1e-13, atol=0)
        np.testing.assert_allclose(inverse, expected[1], rtol=1e-13, atol=0)


def test_edge_forms_spectrally_equivalent_uniformly_in_m():
    """lambda_max/lambda_min of (A_paper, A_sqrt) stays bounded for m = 4..64.

    Measured: 2.24, 2.48, 2.60, 2.65, 2.68 (m = 4, 8, 16, 32, 64), 2.71 at m = 128; the
    growth factors between doublings fall (1.11, 1.05, 1.02, 1.01), as for a bounded
    quantity and unlike the 1 + ln m growth of a non-equivalent pair.
    """
    ratios = []
    for m in (4, 8, 16, 32, 64):
        pts = np.outer(np.linspace(0.0, 0.25, m + 2), [1.0, 0.0])
        lam = sla.eigh(paper_edge_form(pts), sqrt_laplacian_edge_form(pts)[0], eigvals_only=True)
        assert lam.min() > 0.0
        ratios.append(lam.max() / lam.min())
    growth = np.array(ratios[1:]) / np.array(ratios[:-1])
    assert max(ratios) < 3.0
    assert np.all(np.diff(growth) < 0.0)
    assert growth[-1] < 1.02


def test_closed_form_reduces_to_uniform_indices():
    """Closed curve, m equal pieces: weights 1/dist_idx^2 with the cyclic index distance."""
    m, length, mass = 6, 2.0, 0.3
    a = closed_paper_form(np.arange(m) * length / m, length, mass)
    expected = mass * np.eye(m)
    for i in range(m):
        for j in range(i + 1, m):
            w = 1.0 / min(j - i, m - j + i) ** 2
            expected[[i, j], [i, j]] += w
            expected[i, j] -= w
            expected[j, i] -= w
    np.testing.assert_allclose(a, expected, rtol=1e-13, atol=1e-13)


# ---------------------------------------------------------------- B_Omega
CASES = [
    pytest.param(12, 4, None, "paper", id="uniform-paper"),
    pytest.param(12, 4, None, "sqrt-laplacian", id="uniform-sqrt"),
    pytest.param(12, 3, graded_lines(12), "paper", id="graded-paper"),
    pytest.param(12, 3, graded_lines(12), "sqrt-laplacian", id="graded-sqrt"),
]


@pytest.mark.parametrize("n, ratio, lines, kind", CASES)
def test_apply_omega_is_inverse_of_definition(n, ratio, lines, kind):
    prob = structured_square(n, ratio, lines=lines)
    pc = substructuring(prob, edge_form=kind)
    b_ref = reference_omega(prob, kind)
    b = pc.omega_matrix()
    assert relerr(b, b_ref) < RTOL
    assert relerr(b.T, b) < 1e-14  # symmetric to round-off
    assert np.linalg.eigvalsh(b).min() > 0.0
    rng = np.random.default_rng(0)
    g = rng.standard_normal(prob.x.shape[0])
    assert relerr(pc.apply_omega(g), np.linalg.solve(b_ref, g)) < RTOL
    assert relerr(pc.matvec_omega(g), b_ref @ g) < RTOL
    assert relerr(pc.matvec_omega(pc.apply_omega(g)), g) < RTOL
    # several right-hand sides at once
    g2 = rng.standard_normal((prob.x.shape[0], 3))
    np.testing.assert_allclose(
        pc.apply_omega(g2),
        np.column_stack([pc.apply_omega(c) for c in g2.T]),
        rtol=1e-12,
        atol=1e-12,
    )
    pc.destroy()


def test_apply_omega_without_interior_nodes():
    """d = h: every node lies on the skeleton, A_II is empty and B_Omega = B_Sk."""
    prob = structured_square(4, 1)
    pc = substructuring(prob)
    b = reference_omega(prob, "paper")
    g = np.linspace(-1.0, 1.0, prob.x.shape[0])
    assert relerr(pc.apply_omega(g), np.linalg.solve(b, g)) < RTOL


# ---------------------------------------------------------------- B_s
SIGNORINI_CASES = [
    pytest.param(16, 4, "bottom", None, id="bottom"),
    pytest.param(16, 4, "two", None, id="two-arcs"),
    pytest.param(16, 4, "bottom-right", None, id="corner"),
    pytest.param(16, 4, "closed", None, id="closed"),
    pytest.param(12, 3, "bottom-right", graded_lines(12), id="graded-corner"),
    pytest.param(12, 3, "closed", graded_lines(12), id="graded-closed"),
]


@pytest.mark.parametrize("n, ratio, layout, lines", SIGNORINI_CASES)
@pytest.mark.parametrize("kind", ["paper", "sqrt-laplacian"])
def test_signorini_block_matches_definition(n, ratio, layout, lines, kind):
    prob = structured_square(n, ratio, signorini=layout, lines=lines)
    pc = substructuring(prob, edge_form=kind)
    m_ref = reference_signorini(prob.arcs, prob.d, kind)
    m = pc.signorini_metric
    assert relerr(m, m_ref) < RTOL
    lam = np.linalg.eigvalsh(m)
    assert lam[0] > 0.0
    assert pc.lambda_max_signorini == pytest.approx(lam[-1], rel=1e-10)
    phi = np.cos(np.arange(m.shape[0]))
    assert relerr(pc.apply_signorini(phi), np.linalg.solve(m_ref, phi)) < RTOL
    assert relerr(pc.matvec_signorini(phi), m_ref @ phi) < RTOL


def test_signorini_coarse_form_is_methods_formula_on_equal_edges():
    """Arc-length weights reduce to docs/method.md's 1/(j-i)^2 and 1/i + 1/(n_s-i) for equal
    coarse edges."""
    prob = structured_square(24, 4, signorini="bottom-right")
    pc = substructuring(prob)
    m_ref = reference_signorini(prob.arcs, prob.d, "paper", uniform_formula=True)
    assert relerr(pc.signorini_metric, m_ref) < RTOL


def test_signorini_weight_scales_the_block_only():
    prob = structured_square(16, 4)
    pc1 = substructuring(prob)
    pc4 = substructuring(prob, signorini_weight=0.25)
    phi = np.linspace(0.0, 1.0, pc1.n_signorini)
    g = np.sin(np.arange(prob.x.shape[0]))
    np.testing.assert_allclose(
        pc4.matvec_signorini(phi), 0.25 * pc1.matvec_signorini(phi), rtol=1e-15
    )
    np.testing.assert_allclose(pc4.apply_signorini(phi), 4.0 * pc1.apply_signorini(phi), rtol=1e-15)
    assert pc4.lambda_max_signorini == pytest.approx(0.25 * pc1.lambda_max_signorini, rel=1e-14)
    np.testing.assert_allclose(pc4.signorini_metric, 0.25 * pc1.signorini_metric, rtol=1e-15)
    np.testing.assert_array_equal(pc4.apply_omega(g), pc1.apply_omega(g))


def test_no_signorini_arcs():
    prob = structured_square(8, 4, signorini="none")
    pc = substructuring(prob)
    assert pc.n_signorini == 0
    assert pc.apply_signorini(np.zeros(0)).shape == (0,)
    assert pc.lambda_max_signorini == 0.0


def test_lambda_max_by_lanczos_on_large_arcs():
    """Above 400 unknowns lambda_max comes from ARPACK; compare with the dense value."""
    prob = structured_square(128, 8, signorini="closed")
    pc = substructuring(prob)
    assert pc.n_signorini == 512
    assert pc.lambda_max_signorini == pytest.approx(
        np.linalg.eigvalsh(pc.signorini_metric)[-1], rel=1e-9
    )


# ---------------------------------------------------------------- identity and input checks
def test_identity_preconditioner():
    pc = IdentityPreconditioner(5, 3)
    v = np.arange(5.0)
    np.testing.assert_array_equal(pc.apply_omega(v), v)
    np.testing.assert_array_equal(pc.matvec_omega(v), v)
    np.testing.assert_array_equal(pc.apply_signorini(v[:3]), v[:3])
    assert pc.lambda_max_signorini == 1.0
    np.testing.assert_array_equal(pc.signorini_metric, np.eye(3))
    with pytest.raises(ValueError, match="shape"):
        pc.apply_omega(np.zeros(4))


def test_bad_input_is_rejected():
    prob = structured_square(8, 4)
    args = (prob.stiffness, prob.coarse, prob.x, prob.d, prob.arcs)
    unweighted = dict(edge_form="paper", signorini_weight=1.0, coarse_space="graph")
    with pytest.raises(ValueError, match="edge_form"):
        SubstructuringPreconditioner(
            *args, edge_form="exact", signorini_weight=1.0, coarse_space="graph"
        )
    with pytest.raises(ValueError, match="signorini_weight"):
        SubstructuringPreconditioner(
            *args, edge_form="paper", signorini_weight=0.0, coarse_space="graph"
        )
    reversed_edge = dict(vars(prob.coarse))
    reversed_edge["edge_dofs"] = (prob.coarse.edge_dofs[0][::-1],) + prob.coarse.edge_dofs[1:]
    with pytest.raises(ValueError, match="edge_dofs"):
        SubstructuringPreconditioner(
            prob.stiffness, type(prob.coarse)(**reversed_edge), *args[2:], **unweighted
        )
    missing_edge = dict(vars(prob.coarse))
    missing_edge["edge_dofs"] = prob.coarse.edge_dofs[1:]
    missing_edge["edge_vertices"] = prob.coarse.edge_vertices[1:]
    with pytest.raises(ValueError, match="exactly one coarse vertex or one interior node"):
        SubstructuringPreconditioner(
            prob.stiffness, type(prob.coarse)(**missing_edge), *args[2:], **unweighted
        )
    with pytest.raises(ValueError, match="unknowns"):
        arc = prob.arcs[0]
        SubstructuringPreconditioner(
            *args[:4],
            [SignoriniArc(arc.coords, arc.coarse_vertex_mask, arc.unknowns + 1)],
            **unweighted,
        )
    with pytest.raises(ValueError, match="end points"):
        SignoriniArc(arc.coords, np.zeros(len(arc.coords), bool), arc.unknowns)
    nonsymmetric = prob.stiffness.tolil()
    nonsymmetric[0, 1] += 1e-6
    with pytest.raises(ValueError, match="symmetric"):
        SubstructuringPreconditioner(nonsymmetric, *args[1:], **unweighted)
    pc = SubstructuringPreconditioner(*args, **unweighted)
    with pytest.raises(ValueError, match="shape"):
        pc.apply_omega(np.zeros(3))


def test_is_symmetric_leaves_a_non_canonical_matrix_as_it_was():
    """A CSR matrix with unsorted column indices and a duplicate entry (not canonical):
    judged by its sum, and handed back unchanged."""
    # [[2, -1], [-1, 2]] with row 0 stored as (1: -1), (0: 1), (0: 1)
    indptr, indices = np.array([0, 3, 5]), np.array([1, 0, 0, 0, 1])
    data = np.array([-1.0, 1.0, 1.0, -1.0, 2.0])
    matrix = sp.csr_matrix((data, indices, indptr), shape=(2, 2))
    assert is_symmetric(matrix)
    assert np.array_equal(matrix.indices, indices) and np.array_equal(matrix.data, data)
    matrix.data[0] = -1.5
    assert not is_symmetric(matrix)


def test_edge_coordinates_of_the_coarse_structure_stand_for_the_node_coordinates():
    """B built with x = None (the nodes along the coarse edges from coarse.edge_coords)
    is B built with the node coordinates: the same edge forms and interpolation."""
    prob = structured_square(8, 2)
    with_x = substructuring(prob)
    coarse = SimpleNamespace(
        **vars(prob.coarse), edge_coords=tuple(prob.x[d] for d in prob.coarse.edge_dofs)
    )
    without_x = SubstructuringPreconditioner(
        prob.stiffness,
        coarse,
        None,
        prob.d,
        prob.arcs,
        edge_form="paper",
        signorini_weight=1.0,
        coarse_space="graph",
    )
    g = np.random.default_rng(0).standard_normal(prob.stiffness.shape[0])
    assert np.array_equal(without_x.apply_omega(g), with_x.apply_omega(g))


@pytest.mark.parametrize("n", [50, 900])
def test_largest_eigenvalue_of_the_signorini_metric(n):
    """LAPACK below 400 rows, Lanczos above (dense and sparse), to the eigenvalue's
    round-off: the largest eigenvalue of a 1D Laplacian plus a dense rank-one term."""
    lap = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]).tocsr()
    c = np.linspace(0.0, 1.0, n)
    dense = lap.toarray() + np.outer(c, c) / n
    exact = sla.eigvalsh(dense)[-1]
    assert abs(largest_eigenvalue(dense) - exact) <= 1e-9 * exact
    assert abs(largest_eigenvalue(lap) - sla.eigvalsh(lap.toarray())[-1]) <= 1e-9 * exact
    block = DenseSignoriniBlock(dense)
    assert block._lambda_max is None  # computed on first use only
    assert abs(block.lambda_max_signorini - exact) <= 1e-9 * exact
