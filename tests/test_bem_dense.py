"""bem_cpp.dense.SingleMatrix: a matrix held in single precision stands for the double
matrix of its entries in every use the Signorini algebra makes of M_s (products, blocks,
the diagonal, a float64 copy, Lanczos), and S_h with single-precision blocks gives W_h's
block in it."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg

import bem_cpp
from bem_cpp.dense import SingleMatrix
from bem_cpp.surfaces import cube


@pytest.fixture(scope="module")
def spd():
    rng = np.random.default_rng(3)
    A = rng.standard_normal((300, 300))
    return (A @ A.T / 300 + np.eye(300)).astype(np.float32)


def test_products_are_those_of_the_double_matrix_of_the_entries(spd):
    M, D = SingleMatrix(spd), spd.astype(np.float64)
    x = np.random.default_rng(4).standard_normal((300, 3))
    # summed in double: round-off of double (n eps), not of float (6e-8)
    assert np.linalg.norm(M @ x[:, 0] - D @ x[:, 0]) <= 1e-14 * np.linalg.norm(D @ x[:, 0])
    assert np.linalg.norm(M @ x - D @ x) <= 1e-14 * np.linalg.norm(D @ x)
    rows, cols = np.array([5, 1, 7]), np.array([2, 9])
    block = M[np.ix_(rows, cols)]
    assert block.dtype == np.float64 and np.array_equal(block, D[np.ix_(rows, cols)])
    free = np.random.default_rng(5).random(300) < 0.6  # a boolean mask, as a free set
    assert np.array_equal(M[np.ix_(free, free)], D[np.ix_(free, free)])  # in bands of rows
    assert np.array_equal(M[3:7, ::2], D[3:7, ::2])
    assert np.array_equal(M.diagonal(), np.diag(D))
    assert np.array_equal(np.asarray(M), D) and np.asarray(M).dtype == np.float64
    assert M.shape == (300, 300) and M.dtype == np.float64 and M.nbytes == 300 * 300 * 4
    top = scipy.sparse.linalg.eigsh(M, k=1, which="LA", return_eigenvectors=False, tol=1e-12)
    assert top[0] == pytest.approx(np.linalg.eigvalsh(D)[-1], rel=1e-10)


def test_a_square_matrix_is_needed():
    with pytest.raises(ValueError, match="square"):
        SingleMatrix(np.zeros((3, 4), dtype=np.float32))


def test_hypersingular_block_in_the_precision_of_the_blocks():
    """At a tolerance whose blocks are held in single precision, W_h's block on a face is a
    SingleMatrix: the integrated block to the tolerance, symmetric to the bit; at 1e-10 a
    float64 array."""
    X, T = cube(12)
    low = X[:, 2].min()
    edge = np.abs(X[:, :2]).max(axis=0) - 1e-9
    face = np.flatnonzero((X[:, 2] == low) & (np.abs(X[:, :2]) < edge).all(axis=1))
    integrated = bem_cpp.hypersingular(X, triangles=T, block=face)
    single = bem_cpp.steklov_poincare(X, triangles=T, compression="hmatrix", tol=1e-5)
    assert single.single_precision
    block = single.hypersingular_block(face)
    assert isinstance(block, SingleMatrix) and block.entries.dtype == np.float32
    dense = block.to_dense()
    assert np.linalg.norm(dense - integrated) <= 1e-5 * np.linalg.norm(integrated)
    assert np.array_equal(dense, dense.T)
    double = bem_cpp.steklov_poincare(X, triangles=T, compression="hmatrix", tol=1e-10)
    assert not double.single_precision
    assert isinstance(double.hypersingular_block(face), np.ndarray)
