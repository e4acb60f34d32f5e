#include <gtest/gtest.h>

#include <Eigen/Sparse>
#include <algorithm>
#include <numeric>
#include <random>

#include "bem/sparse_cholesky.hpp"

using namespace bem;
using Indices = SparseCholesky::Indices;
using RowMajorSparse = Eigen::SparseMatrix<double, Eigen::RowMajor, std::int64_t>;

namespace {

/// The 5-point Laplacian of an m x m grid plus `shift` on the diagonal.
RowMajorSparse grid_laplacian(Index m, double shift) {
  std::vector<Eigen::Triplet<double, std::int64_t>> entries;
  auto id = [m](Index i, Index j) { return i * m + j; };
  for (Index i = 0; i < m; ++i)
    for (Index j = 0; j < m; ++j) {
      entries.emplace_back(id(i, j), id(i, j), 4.0 + shift);
      if (i > 0) entries.emplace_back(id(i, j), id(i - 1, j), -1.0);
      if (i + 1 < m) entries.emplace_back(id(i, j), id(i + 1, j), -1.0);
      if (j > 0) entries.emplace_back(id(i, j), id(i, j - 1), -1.0);
      if (j + 1 < m) entries.emplace_back(id(i, j), id(i, j + 1), -1.0);
    }
  RowMajorSparse A(m * m, m * m);
  A.setFromTriplets(entries.begin(), entries.end());
  return A;
}

/// A random symmetric matrix with `per_row` off-diagonal entries a row (both triangles),
/// made positive definite by diagonal dominance.
RowMajorSparse random_spd(Index n, Index per_row, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_int_distribution<Index> column(0, n - 1);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::vector<Eigen::Triplet<double, std::int64_t>> entries;
  Eigen::VectorXd diagonal = Eigen::VectorXd::Constant(n, 1.0);
  for (Index i = 0; i < n; ++i)
    for (Index e = 0; e < per_row; ++e) {
      const Index j = column(gen);
      if (j == i) continue;
      const double v = value(gen);
      entries.emplace_back(i, j, v);
      entries.emplace_back(j, i, v);
      diagonal[i] += std::abs(v);
      diagonal[j] += std::abs(v);
    }
  for (Index i = 0; i < n; ++i) entries.emplace_back(i, i, diagonal[i]);
  RowMajorSparse A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());  // duplicates summed
  return A;
}

Indices random_permutation(Index n, unsigned seed) {
  Indices p(n);
  std::iota(p.data(), p.data() + n, std::int64_t{0});
  std::shuffle(p.data(), p.data() + n, std::mt19937(seed));
  return p;
}

Indices identity(Index n) {
  Indices p(n);
  std::iota(p.data(), p.data() + n, std::int64_t{0});
  return p;
}

SparseCholesky factor(const RowMajorSparse& A, const Indices& ordering, Index n_schur = 0) {
  const Eigen::Map<const Indices> indptr(A.outerIndexPtr(), A.rows() + 1);
  const Eigen::Map<const Indices> indices(A.innerIndexPtr(), A.nonZeros());
  const Eigen::Map<const Eigen::VectorXd> data(A.valuePtr(), A.nonZeros());
  return SparseCholesky(A.rows(), indptr, indices, data, ordering, n_schur);
}

/// The nonzeros of the exact Cholesky factor of P A P^T, computed densely.
Index exact_factor_nonzeros(const RowMajorSparse& A, const Indices& ordering) {
  const Eigen::MatrixXd dense = Eigen::MatrixXd(A);
  Eigen::MatrixXd permuted(A.rows(), A.rows());
  for (Index i = 0; i < A.rows(); ++i)
    for (Index j = 0; j < A.rows(); ++j) permuted(i, j) = dense(ordering[i], ordering[j]);
  const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(permuted).matrixL();
  return (L.array() != 0.0).count();
}

}  // namespace

TEST(SparseCholesky, SolvesLikeTheDenseFactor) {
  struct Case {
    RowMajorSparse A;
    Indices ordering;
  };
  const Index m = 24;  // natural ordering: banded fronts of m + 1 rows, past the loop kernels
  std::vector<Case> cases{{grid_laplacian(m, 0.0), identity(m * m)},
                          {grid_laplacian(m, 0.0), random_permutation(m * m, 1)},
                          {grid_laplacian(7, 0.5), random_permutation(49, 2)},
                          {random_spd(400, 3, 3), random_permutation(400, 4)},
                          {random_spd(300, 1, 5), identity(300)}};
  for (const Case& c : cases) {
    const SparseCholesky F = factor(c.A, c.ordering);
    const Eigen::MatrixXd B = Eigen::MatrixXd::Random(c.A.rows(), 3);
    const Eigen::MatrixXd X = F.solve(B);
    const Eigen::MatrixXd expected = Eigen::LLT<Eigen::MatrixXd>(Eigen::MatrixXd(c.A)).solve(B);
    // both backward stable: the difference is the condition number (< 1e3 here) times round-off
    EXPECT_LT((X - expected).norm(), 1e-11 * expected.norm()) << c.A.rows();
    EXPECT_LT((c.A * X - B).norm(), 1e-12 * B.norm()) << c.A.rows();
    // the supernodes hold every entry of the exact factor, and explicit zeros only within limits
    const Index exact = exact_factor_nonzeros(c.A, c.ordering);
    EXPECT_GE(static_cast<Index>(F.factor_nonzeros()), exact);
    EXPECT_LE(static_cast<Index>(F.factor_nonzeros()), 2 * exact);
    EXPECT_LT(F.supernodes(), c.A.rows());
  }
}

TEST(SparseCholesky, RejectsMatricesThatAreNotPositiveDefinite) {
  EXPECT_THROW(factor(grid_laplacian(10, -1.0), random_permutation(100, 6)), NotPositiveDefinite);
  // smallest eigenvalue 4 - 4 cos(pi / 31) = 0.0205 - 0.05: found in a LAPACK front
  EXPECT_THROW(factor(grid_laplacian(30, -0.05), identity(900)), NotPositiveDefinite);
}

TEST(SparseCholesky, RejectsMalformedInput) {
  const RowMajorSparse A = grid_laplacian(4, 0.0);
  Indices repeated = identity(16);
  repeated[3] = 2;
  EXPECT_THROW(factor(A, repeated), std::invalid_argument);
  EXPECT_THROW(factor(A, identity(15)), std::invalid_argument);
  const Eigen::Map<const Indices> indptr(A.outerIndexPtr(), A.rows() + 1);
  const Eigen::Map<const Indices> indices(A.innerIndexPtr(), A.nonZeros());
  const Eigen::Map<const Eigen::VectorXd> data(A.valuePtr(), A.nonZeros());
  EXPECT_THROW(SparseCholesky(17, indptr, indices, data, identity(17)), std::invalid_argument);
  const SparseCholesky F = factor(A, identity(16));
  EXPECT_THROW(F.solve(Eigen::MatrixXd::Ones(15, 1)), std::invalid_argument);
}

TEST(SparseCholesky, HandlesTheEmptyMatrixAndDiagonalOnes) {
  const SparseCholesky empty(0, Indices::Zero(1), Indices(0), Eigen::VectorXd(0), Indices(0));
  EXPECT_EQ(empty.solve(Eigen::MatrixXd(0, 2)).rows(), 0);
  RowMajorSparse D(5, 5);
  for (Index i = 0; i < 5; ++i) D.insert(i, i) = i + 1.0;
  D.makeCompressed();
  const Eigen::MatrixXd X = factor(D, random_permutation(5, 7)).solve(Eigen::MatrixXd::Ones(5, 1));
  for (Index i = 0; i < 5; ++i) EXPECT_DOUBLE_EQ(X(i, 0), 1.0 / (i + 1.0));
}

TEST(SparseCholesky, KeepsTheLastRowsAsADenseSchurComplement) {
  struct Case {
    RowMajorSparse A;
    Indices ordering;
    Index n_schur;
  };
  const Index m = 24;
  std::vector<Case> cases{{grid_laplacian(m, 0.0), random_permutation(m * m, 11), 37},
                          {grid_laplacian(m, 0.0), identity(m * m), m},  // the last grid line
                          {grid_laplacian(7, 0.5), random_permutation(49, 12), 1},
                          {grid_laplacian(7, 0.5), random_permutation(49, 13), 49},  // all of it
                          {random_spd(400, 3, 14), random_permutation(400, 15), 120}};
  for (const Case& c : cases) {
    const Index n = c.A.rows(), h = n - c.n_schur;
    const SparseCholesky F = factor(c.A, c.ordering, c.n_schur);
    // the dense blocks of A in the order of the ordering: H first, then S
    const Eigen::MatrixXd dense = Eigen::MatrixXd(c.A);
    Eigen::MatrixXd P(n, n);
    for (Index i = 0; i < n; ++i)
      for (Index j = 0; j < n; ++j) P(i, j) = dense(c.ordering[i], c.ordering[j]);
    const Eigen::MatrixXd A_hh = P.topLeftCorner(h, h), A_sh = P.bottomLeftCorner(c.n_schur, h);
    const Eigen::MatrixXd expected_schur =
        P.bottomRightCorner(c.n_schur, c.n_schur) - A_sh * Eigen::LLT<Eigen::MatrixXd>(A_hh).solve(A_sh.transpose());
    ASSERT_EQ(F.schur().rows(), c.n_schur);
    // both backward stable: the condition number (< 1e3 here) times round-off
    EXPECT_LT((F.schur() - expected_schur).norm(), 1e-12 * expected_schur.norm()) << n << " " << c.n_schur;

    const Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, 2);
    const Eigen::MatrixXd X = Eigen::LLT<Eigen::MatrixXd>(dense).solve(B);
    EXPECT_LT((F.solve(B) - X).norm(), 1e-11 * X.norm()) << n << " " << c.n_schur;

    // the sweeps: W_S = B_S - A_SH A_HH^{-1} B_H; with W_S := X_S, back to X
    Eigen::MatrixXd B_h(h, 2), B_s(c.n_schur, 2), X_s(c.n_schur, 2);
    for (Index i = 0; i < n; ++i) (i < h ? B_h.row(i) : B_s.row(i - h)) = B.row(c.ordering[i]);
    const Eigen::MatrixXd expected_w_s = B_s - A_sh * Eigen::LLT<Eigen::MatrixXd>(A_hh).solve(B_h);
    Eigen::MatrixXd W = F.eliminate(B);
    for (Index i = h; i < n; ++i) {
      EXPECT_LT((W.row(c.ordering[i]) - expected_w_s.row(i - h)).norm(), 1e-11 * expected_w_s.norm());
      W.row(c.ordering[i]) = X.row(c.ordering[i]);
    }
    EXPECT_LT((F.back_substitute(W) - X).norm(), 1e-11 * X.norm()) << n << " " << c.n_schur;
  }
  // not positive definite within S alone, and n_schur out of range
  EXPECT_THROW(factor(grid_laplacian(10, -1.0), identity(100), 100), NotPositiveDefinite);
  EXPECT_THROW(factor(grid_laplacian(4, 0.0), identity(16), 17), std::invalid_argument);
  EXPECT_THROW(factor(grid_laplacian(4, 0.0), identity(16), -1), std::invalid_argument);
}
