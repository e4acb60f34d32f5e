"""The supernodal sparse Cholesky factor (bem_cpp.sparse) and the factors of the
substructuring preconditioner built on it (coupling.preconditioners.kernels.SparseFactor)."""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from bem_cpp.sparse import SparseCholesky
from coupling.preconditioners.kernels import SparseFactor


def grid_laplacian(m: int, shift: float = 0.0) -> sp.csr_matrix:
    """The 5-point Laplacian of an m x m grid (Dirichlet rows) plus ``shift`` I."""
    t = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(m, m))
    one = sp.identity(m)
    return (sp.kron(one, t) + sp.kron(t, one) + shift * sp.identity(m * m)).tocsr()


# the 60 x 60 grid's condition number is below 2e3: solves agree to 2e3 x round-off
RTOL = 1e-11


@pytest.mark.parametrize("ordering", ["nd", "natural"])
def test_sparse_factor_solves_like_a_direct_solver(ordering):
    a = grid_laplacian(60)
    rng = np.random.default_rng(0)
    b = rng.standard_normal((a.shape[0], 3))
    expected = spla.spsolve(a.tocsc(), b)
    factor = SparseFactor(a, ordering)
    assert np.allclose(factor.solve(b), expected, rtol=0, atol=RTOL * np.abs(expected).max())
    x = factor.solve(b[:, 0])
    assert x.shape == (a.shape[0],)
    assert np.allclose(x, expected[:, 0], rtol=0, atol=RTOL * np.abs(expected).max())
    factor.destroy()
    with pytest.raises(RuntimeError, match="destroyed"):
        factor.solve(b[:, 0])


def test_supernodal_factor_of_a_random_ordering_and_a_disconnected_graph():
    rng = np.random.default_rng(1)
    a = sp.block_diag([grid_laplacian(9, 0.3), grid_laplacian(5), sp.identity(4)]).tocsr()
    n = a.shape[0]
    b = rng.standard_normal(n)
    factor = SparseCholesky(a, rng.permutation(n))
    x = factor.solve(b)
    assert np.linalg.norm(a @ x - b) <= 1e-13 * np.linalg.norm(b)
    assert factor.factor_nonzeros >= a.nnz // 2 + n // 2  # at least the lower triangle


def test_supernodal_factor_rejects_bad_input():
    a = grid_laplacian(8)
    n = a.shape[0]
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        SparseCholesky(grid_laplacian(8, shift=-1.0), np.arange(n))
    with pytest.raises(ValueError, match="not a permutation"):
        SparseCholesky(a, np.zeros(n, dtype=int))
    with pytest.raises(ValueError, match="square"):
        SparseCholesky(a[:-1], np.arange(n))
    with pytest.raises(ValueError, match="b must have shape"):
        SparseCholesky(a, np.arange(n)).solve(np.ones(n + 1))


def test_supernodal_factor_leaves_the_last_rows_to_a_dense_schur_complement():
    a = grid_laplacian(30, 0.1)
    n, n_s = a.shape[0], 30
    rng = np.random.default_rng(2)
    ordering = rng.permutation(n)
    h, s = ordering[:-n_s], ordering[-n_s:]
    factor = SparseCholesky(a, ordering, n_schur=n_s)
    a_hh, a_hs = a[h][:, h].tocsc(), a[h][:, s].toarray()
    expected = a[s][:, s].toarray() - a_hs.T @ spla.spsolve(a_hh, a_hs)
    assert np.abs(factor.schur - expected).max() <= RTOL * np.abs(expected).max()
    b = rng.standard_normal(n)
    x = spla.spsolve(a.tocsc(), b)
    assert np.abs(factor.solve(b) - x).max() <= RTOL * np.abs(x).max()
    # the sweeps with the Schur complement solved in between give the same x
    w = factor.eliminate(b)
    w[s] = np.linalg.solve(factor.schur, w[s])
    assert np.abs(factor.back_substitute(w) - x).max() <= RTOL * np.abs(x).max()
    with pytest.raises(ValueError, match="n_schur"):
        SparseCholesky(a, ordering, n_schur=n + 1)
