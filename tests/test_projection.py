"""P_s: the M_s-orthogonal projection onto {phi >= 0} (docs/method.md (3.19), (3.20), (3.6))."""
import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from coupling.options import SolverOptions
from coupling.preconditioners.base import DenseSignoriniBlock, inverse_from_cholesky
from bem_cpp.sparse import SparseCholesky
from coupling.solvers.projection import DenseBlockFactor, SignoriniProjection
from coupling.solvers.solution import build_projection


def h12_like_matrix(n: int) -> np.ndarray:
    """A dense SPD matrix that is not an M-matrix, like M_s (a discrete H^1/2_00 form)."""
    i = np.arange(1, n + 1)
    distance = (i[:, None] - i[None, :]).astype(float)
    np.fill_diagonal(distance, np.inf)
    M = -1.0 / distance**2
    np.fill_diagonal(M, -M.sum(axis=1) + 1.0 / i + 1.0 / (n + 1 - i))
    rng = np.random.default_rng(1)
    Q = np.eye(n) + 0.3 * rng.standard_normal((n, n)) / np.sqrt(n)
    return Q @ M @ Q.T


def two_level_like_matrix(n_coarse: int, m: int) -> np.ndarray:
    """M = E^T A0 E + R^T C R on a chain of n_coarse coarse nodes with m nodes on each
    edge between them, like the Signorini block's two-level form: A0 block diagonal on
    the edges' nodes, C dense on the coarse nodes, E = I - P R with P the linear
    interpolation of the coarse values. SPD, sparse but for the coarse rows."""
    n = n_coarse + (n_coarse - 1) * m
    coarse = np.arange(0, n, m + 1)
    P = np.zeros((n, n_coarse))
    A0 = np.zeros((n, n))
    P[coarse, np.arange(n_coarse)] = 1.0
    t = np.arange(1, m + 1) / (m + 1)
    for j in range(n_coarse - 1):
        nodes = coarse[j] + np.arange(1, m + 1)
        P[nodes, j], P[nodes, j + 1] = 1.0 - t, t
        A0[np.ix_(nodes, nodes)] = h12_like_matrix(m)
    R = np.zeros((n_coarse, n))
    R[np.arange(n_coarse), coarse] = 1.0
    E = np.eye(n) - P @ R
    M = E.T @ A0 @ E + R.T @ h12_like_matrix(n_coarse) @ R
    return 0.5 * (M + M.T)


def kkt_residual(M, target, psi):
    lam = M @ (psi - target)
    return max(
        np.abs(np.minimum(psi, 0)).max(),
        np.abs(np.minimum(lam, 0)).max(),
        np.abs(psi * lam).max() / np.abs(M).max(),
    )


@pytest.mark.parametrize("n", [5, 40, 120])
def test_exact_projection_solves_the_qp_to_round_off(n):
    M = h12_like_matrix(n)
    rng = np.random.default_rng(n)
    projection = SignoriniProjection.exact(M)
    for _ in range(5):
        target = rng.standard_normal(n)
        psi = projection(target, np.zeros(n)).phi
        # KKT: psi >= 0, lambda = M (psi - target) >= 0, psi * lambda = 0
        assert kkt_residual(M, target, psi) < 1e-12 * np.abs(target).max() * n
        L = np.linalg.cholesky(M)
        reference, _ = scipy.optimize.nnls(L.T, L.T @ target)
        assert np.allclose(psi, reference, atol=1e-10 * np.abs(target).max())


def test_inexact_projection_converges_to_the_exact_one():
    n = 30
    M = h12_like_matrix(n)
    rng = np.random.default_rng(3)
    target = rng.standard_normal(n)
    exact = SignoriniProjection.exact(M)(target, np.zeros(n)).phi
    inexact = SignoriniProjection(M, "inexact", rho_in=0.0, max_iterations=200000)
    result = inexact(target, np.zeros(n))
    # rho_in = 0 runs the projected iteration (a contraction in the M norm for
    # theta = 1/lambda_max) to its fixed point, which is the exact projection.
    assert result.iterations > 1
    assert np.linalg.norm(result.phi - exact) < 1e-8 * np.linalg.norm(exact)


def test_inexact_projection_satisfies_the_accuracy_condition_3_6():
    n = 30
    M = h12_like_matrix(n)
    rng = np.random.default_rng(4)
    exact = SignoriniProjection.exact(M)
    rho = 0.5
    inexact = SignoriniProjection(M, "inexact", rho_in=rho, max_iterations=10000)
    norm = inexact.norm
    for _ in range(10):
        start = np.maximum(rng.standard_normal(n), 0)
        target = start + 0.3 * rng.standard_normal(n)
        approx = inexact(target, start).phi
        best = exact(target, start).phi
        assert approx.min() >= 0
        lhs = norm(approx - target) ** 2
        rhs = rho * norm(target - start) ** 2 + (1 - rho) * norm(best - target) ** 2
        assert lhs <= rhs * (1 + 1e-12)


def test_feasible_target_is_a_fixed_point():
    M = h12_like_matrix(10)
    target = np.linspace(0.1, 1.0, 10)
    for method in ("exact", "inexact"):
        projection = SignoriniProjection(M, method, rho_in=0.5, max_iterations=100)
        assert np.allclose(projection(target, target).phi, target)


def test_unknown_method_is_rejected():
    with pytest.raises(ValueError, match="projection must be"):
        SignoriniProjection(np.eye(2), "approximate", rho_in=0.5, max_iterations=100)


@pytest.mark.parametrize("lower", [False, True])
def test_inverse_from_the_cholesky_factor_is_the_symmetric_inverse(lower):
    """M^{-1} from potri and the blockwise mirrored triangle: the inverse to round-off
    (several blocks and a ragged last one), exactly symmetric."""
    rng = np.random.default_rng(1)
    n = 700
    A = rng.standard_normal((n, n))
    M = A @ A.T + n * np.eye(n)
    W = inverse_from_cholesky(scipy.linalg.cho_factor(M, lower=lower), block=256)
    assert np.array_equal(W, W.T)
    assert np.abs(W @ M - np.eye(n)).max() <= 1e-13


def test_a_dense_signorini_block_shares_its_inverse_with_the_exact_projection():
    """DenseSignoriniBlock.signorini_inverse replaces the block's Cholesky factor (one n x n
    array kept, not two); build_projection hands it to the exact projection, which then
    drops the factor too; the projections and M_s^{-1} g equal the unshared ones to
    round-off (the inverse's products against the triangular solves)."""
    n = 120
    M = h12_like_matrix(n)
    block = DenseSignoriniBlock(M)
    g = np.random.default_rng(7).standard_normal(n)
    before = block.apply_signorini(g)
    projection = build_projection(block, SolverOptions(method="ssn", projection="exact"))
    reference = SignoriniProjection.exact(M)
    target = g - 0.2  # a few nodes active: the projection works through M^{-1} ...
    projection._factorised_flops = float(n) ** 3  # ... once it has bought it (here at once)
    psi = projection(target, np.zeros(n)).phi
    assert 0 < np.count_nonzero(psi == 0.0) < n / 2
    np.testing.assert_allclose(psi, reference(target, np.zeros(n)).phi, atol=1e-12)
    assert block.signorini_factor is None and projection._factor is None
    assert projection._inverse is block.signorini_inverse
    np.testing.assert_allclose(block.apply_signorini(g), before, rtol=1e-11)
    # an inexact projection given only the inverse uses it in its dual bound: run to its
    # fixed point (rho_in = 0), it is the exact projection
    inexact = SignoriniProjection(
        M, "inexact", rho_in=0.0, max_iterations=200000, inverse=lambda: block.signorini_inverse
    )
    assert inexact._factor is None
    result = inexact(target, np.zeros(n))
    assert result.iterations > 1
    assert np.linalg.norm(result.phi - psi) < 1e-8 * np.linalg.norm(psi)


def test_the_exact_twin_of_a_projection_shares_its_factor_and_inverse():
    """as_exact: the exact projection is itself; an inexact one's exact twin (the ssn
    predictor's, and the residual scale's of a nested level) factors and inverts nothing
    of its own: it reads the same Cholesky factor and the same M_s^{-1} array, and
    projects as a fresh exact projection does."""
    n = 60
    M = h12_like_matrix(n)
    exact = SignoriniProjection.exact(M)
    assert exact.as_exact() is exact
    inexact = SignoriniProjection(M, "inexact", rho_in=0.5, max_iterations=1000)
    twin = inexact.as_exact()
    assert twin.method == "exact" and twin.M is inexact.M
    assert twin._cholesky() is inexact._cholesky()  # one factor, made once
    targets = np.random.default_rng(3).standard_normal((20, n)) - 0.3
    for target in targets:  # until M^{-1} is bought (below), then through it
        psi = twin(target, np.zeros(n)).phi
        assert 0 < np.count_nonzero(psi == 0.0) < n / 2  # few active nodes
        np.testing.assert_allclose(psi, exact(target, np.zeros(n)).phi, atol=1e-12)
    assert twin._inverse is inexact._inverse_matrix()


def test_the_exact_projection_buys_the_inverse_only_once_it_pays():
    """M^{-1} costs about n^3 flops: the exact projection factors M_II instead until those
    factorisations have cost as much (|I|^3 / 3 each), then computes M^{-1} once and uses
    it from there on; with no active node it solves with M's factor. The projections
    are the same either way (to round-off)."""
    n = 60
    M = h12_like_matrix(n)
    reference = SignoriniProjection.exact(M)
    reference._factorised_flops = float(n) ** 3  # buys M^{-1} at once
    projection = SignoriniProjection.exact(M)
    positive = projection(np.ones(n), np.zeros(n))  # no active node: the factor solves
    np.testing.assert_allclose(positive.phi, np.ones(n), atol=1e-12)
    assert projection._inverse is None
    targets = np.random.default_rng(5).standard_normal((20, n)) - 0.3
    bought = []
    for target in targets:
        psi = projection(target, np.zeros(n)).phi
        np.testing.assert_allclose(psi, reference(target, np.zeros(n)).phi, atol=1e-12)
        bought.append(projection._inverse is not None)
    assert not bought[0] and bought[-1] and bought == sorted(bought)  # bought once, kept
    assert projection._factorised_flops <= float(n) ** 3


@pytest.mark.parametrize("method", ["exact", "inexact"])
def test_building_the_projection_computes_no_inverse(method):
    """The solver's projection shares the preconditioner's factor and, lazily, its M_s^{-1}:
    building it computes neither the inverse (n_s^3 flops: 90 s at 128^3 cubes, once paid by
    a hasattr on the property), nor lambda_max, nor the factor; a projection with no
    active node solves with the factor, made then and shared with the block."""
    n = 40
    block = DenseSignoriniBlock(h12_like_matrix(n))
    projection = build_projection(block, SolverOptions(projection=method))
    assert block._signorini_inverse is None and block._lambda_max is None
    assert block._signorini_factor is None
    projection(np.ones(n), np.zeros(n))
    assert projection._factor is block._signorini_factor is not None
    assert block._signorini_inverse is None


def test_an_exact_projected_step_solves_nothing_with_the_metric():
    """step(phi, g, tau) = P_s(phi - tau M_s^{-1} g) for both methods; the exact projection
    reads the target only through M_s phi - tau g, so from an iterate with active nodes it
    factors M_s[I, I] alone: the block's factor of M_s (n_s^3/3 flops, an n_s^2 array) is
    never made. The inexact projection forms the target with the solve it is given."""
    n = 80
    M = h12_like_matrix(n)
    rng = np.random.default_rng(13)
    phi = np.maximum(rng.standard_normal(n), 0.0)
    g = rng.standard_normal(n) + 0.5
    tau = 0.7
    target = phi - tau * np.linalg.solve(M, g)
    reference = SignoriniProjection.exact(M)(target, phi).phi
    assert 0 < np.count_nonzero(reference == 0.0) < n
    block = DenseSignoriniBlock(M)
    exact = build_projection(block, SolverOptions(projection="exact"))
    rents = []
    for _ in range(2):  # the second from the first one's active set and kept factor of M_II
        psi = exact.step(phi, g, tau).phi
        np.testing.assert_allclose(psi, reference, atol=1e-12)
        rents.append(exact._factorised_flops)
    assert block._signorini_factor is None and exact._factor is None
    assert rents[0] > 0 and rents[1] == rents[0]  # the second step factored nothing
    inexact = SignoriniProjection(M, "inexact", rho_in=0.0, max_iterations=200000)
    solves = []
    result = inexact.step(phi, g, tau, lambda v: solves.append(v) or np.linalg.solve(M, v))
    assert len(solves) == 1
    assert np.linalg.norm(result.phi - reference) < 1e-8 * np.linalg.norm(reference)


def test_the_factor_of_m_ii_is_kept_for_the_same_free_set():
    """free_factor keeps the last factor of M_II: asked again for the same free set (the
    Newton step after the prediction that found it) it returns that one; another set
    replaces it; destroy drops it."""
    n = 30
    M = h12_like_matrix(n)
    projection = SignoriniProjection.exact(M)
    free = np.arange(n) % 3 != 0
    factor = projection.free_factor(free)
    b = np.random.default_rng(2).standard_normal(n)
    np.testing.assert_allclose(
        factor.solve(b[free]), np.linalg.solve(M[np.ix_(free, free)], b[free])
    )
    assert projection.free_factor(free.copy()) is factor
    other = projection.free_factor(~free)
    assert other is not factor and projection.free_factor(~free) is other
    projection.destroy()
    assert projection._free is None


def test_a_two_level_metric_is_factored_sparsely_around_its_coarse_nodes():
    """M_s sparse but for its coarse rows: M_II is factored by a sparse elimination and a
    dense Schur complement on the coarse nodes, solves as M_II does (to round-off: M's
    condition number is below 1e3), and the exact projection through it solves the QP as
    the dense factors do; a dense M keeps dense factors."""
    M = two_level_like_matrix(40, 3)
    n = M.shape[0]
    assert np.linalg.cond(M) < 1e3
    projection = SignoriniProjection.exact(M)
    rng = np.random.default_rng(4)
    free = rng.random(n) < 0.7
    factor = projection.free_factor(free)
    assert isinstance(factor, SparseCholesky)
    assert factor.schur.shape[0] == np.count_nonzero(free[::4])  # the free coarse nodes
    b = rng.standard_normal(n)
    np.testing.assert_allclose(
        factor.solve(b[free]), np.linalg.solve(M[np.ix_(free, free)], b[free]), rtol=1e-12
    )
    for _ in range(3):
        target = rng.standard_normal(n)
        psi = projection(target, np.zeros(n)).phi
        assert kkt_residual(M, target, psi) <= 1e-12 * np.abs(M).max() * np.abs(target).max()
    assert isinstance(
        SignoriniProjection.exact(h12_like_matrix(n)).free_factor(free), DenseBlockFactor
    )


def test_the_factor_of_w_aa_is_kept_for_the_same_free_set():
    """Once M^{-1} = W is bought, a solve on the free set I goes through W_AA's factor (A the
    active nodes); the last one is kept, as an exact projection starts from the last active
    set; another set replaces it; destroy drops it."""
    n = 40
    M = h12_like_matrix(n)
    projection = SignoriniProjection.exact(M)
    projection._factorised_flops = float(n) ** 3  # buys W at once
    free = np.arange(n) % 4 != 0  # 10 active nodes, fewer than the free ones: through W
    b = np.random.default_rng(3).standard_normal(n)
    expected = np.zeros(n)
    expected[free] = np.linalg.solve(M[np.ix_(free, free)], b[free])
    psi = projection._solve_free(b, free)
    np.testing.assert_allclose(psi, expected, atol=1e-12 * np.abs(expected).max())
    assert np.all(psi[~free] == 0.0) and projection._inverse is not None
    factor = projection._kept_active[1]
    np.testing.assert_array_equal(projection._solve_free(b, free.copy()), psi)
    assert projection._kept_active[1] is factor
    other = np.arange(n) % 5 != 0
    projection._solve_free(b, other)
    assert projection._kept_active[1] is not factor
    projection.destroy()
    assert projection._kept_active is None


def test_a_dense_signorini_block_holds_a_fortran_ordered_metric_without_a_copy():
    """M_s comes from bem_cpp in Eigen's column-major order; the block holds the transpose,
    a C-ordered view of the same symmetric matrix (no n_s^2 copy), and works as with a
    C-ordered copy."""
    n = 50
    M = h12_like_matrix(n)
    M = 0.5 * (M + M.T)  # symmetric to the bit, as bem_cpp's W_h block is
    fortran = np.asfortranarray(M)
    block = DenseSignoriniBlock(fortran)
    assert np.shares_memory(block.signorini_metric, fortran)
    assert block.signorini_metric.flags.c_contiguous
    reference = DenseSignoriniBlock(np.ascontiguousarray(M))
    g = np.random.default_rng(11).standard_normal(n)
    np.testing.assert_array_equal(block.matvec_signorini(g), reference.matvec_signorini(g))
    np.testing.assert_allclose(block.apply_signorini(g), reference.apply_signorini(g), rtol=1e-13)


def test_a_free_block_is_solved_through_the_bought_inverse():
    """Once the exact projection holds W = M^{-1}, a Newton step's M_II^{-1} (fewer than
    half the nodes active) comes through W and W_AA's factor, the block-inverse identity,
    with no factor of M_II made: M_II's own solve to round-off."""
    rng = np.random.default_rng(3)
    n = 40
    A = rng.standard_normal((n, n))
    M = A @ A.T / n + np.eye(n)
    P = SignoriniProjection(
        M, "exact", rho_in=0.0, max_iterations=0, inverse=lambda: np.linalg.inv(M)
    )
    P(np.ones(n), np.ones(n))  # nothing active: solved through W, which it buys
    free = np.ones(n, dtype=bool)
    free[::4] = False
    b = rng.standard_normal(np.count_nonzero(free))
    block = P.free_factor(free)
    assert not isinstance(block, DenseBlockFactor)
    exact = np.linalg.solve(M[np.ix_(free, free)], b)
    assert np.linalg.norm(block.solve(b) - exact) <= 1e-12 * np.linalg.norm(exact)
