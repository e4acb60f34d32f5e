#include <gtest/gtest.h>

#include <cmath>

#include "bem/aca.hpp"

using namespace bem;

namespace {
// log|x - y| for x in [0, 1], y in [3, 4]: asymptotically smooth, numerically low rank.
Eigen::MatrixXd log_block(Index m, Index n) {
  Eigen::MatrixXd A(m, n);
  for (Index i = 0; i < m; ++i)
    for (Index j = 0; j < n; ++j) A(i, j) = std::log(3.0 + double(j) / double(n) - double(i) / double(m));
  return A;
}
LowRank cross(const Eigen::MatrixXd& A, double tol) {
  const Slice row = [&](Index i, double* out) { Eigen::Map<Eigen::VectorXd>(out, A.cols()) = A.row(i); };
  const Slice col = [&](Index j, double* out) { Eigen::Map<Eigen::VectorXd>(out, A.rows()) = A.col(j); };
  return aca(A.rows(), A.cols(), row, col, tol, std::min(A.rows(), A.cols()));
}
}  // namespace

TEST(Aca, ApproximatesAnAsymptoticallySmoothBlock) {
  const Eigen::MatrixXd A = log_block(200, 150);
  for (double tol : {1e-6, 1e-10}) {
    LowRank a = cross(A, tol);
    EXPECT_LT((A - a.U * a.V.transpose()).norm(), 10 * tol * A.norm());
    EXPECT_LT(a.rank(), 20);
    const Index before = a.rank();
    recompress(a, tol);
    EXPECT_LE(a.rank(), before);
    EXPECT_LT((A - a.U * a.V.transpose()).norm(), 20 * tol * A.norm());
  }
}

TEST(Aca, ZeroRowsAndZeroBlocks) {
  // Rows 0 .. 149 zero (the double-layer kernel on a straight side), the rest smooth:
  // the pivot must leave the zero rows.
  Eigen::MatrixXd A = log_block(200, 150);
  A.topRows(150).setZero();
  const LowRank a = cross(A, 1e-10);
  EXPECT_LT((A - a.U * a.V.transpose()).norm(), 1e-9 * A.norm());
  const LowRank z = cross(Eigen::MatrixXd::Zero(40, 30), 1e-10);
  EXPECT_EQ(z.rank(), 0);
}

TEST(Aca, RecompressionTruncatesBySingularValuesWithOrthonormalFactors) {
  // U V^T of rank 3 given with 6 columns (as the stacked pieces of a split block), tall and
  // wide (more columns than rows): the product kept to round-off at a tight tol, the rank
  // cut at a loose one by the singular values, U's columns orthogonal, V's orthonormal
  const Eigen::MatrixXd X = Eigen::MatrixXd::Random(40, 3), Y = Eigen::MatrixXd::Random(25, 3);
  const Eigen::MatrixXd C = Eigen::MatrixXd::Random(3, 6);
  for (Index rows : {40, 2}) {
    LowRank a{X.topRows(rows) * C, Y * (Eigen::MatrixXd::Identity(3, 6) + 0.5 * C)};
    const Eigen::MatrixXd A = a.U * a.V.transpose();
    recompress(a, 1e-12);
    EXPECT_EQ(a.rank(), std::min<Index>(rows, 3));
    EXPECT_LT((A - a.U * a.V.transpose()).norm(), 1e-13 * A.norm());
    EXPECT_LT((a.V.transpose() * a.V - Eigen::MatrixXd::Identity(a.rank(), a.rank())).norm(), 1e-13);
    const Eigen::MatrixXd G = a.U.transpose() * a.U;
    EXPECT_LT((G - Eigen::MatrixXd(G.diagonal().asDiagonal())).norm(), 1e-13 * G.norm());
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A);
    const Eigen::VectorXd s = svd.singularValues();
    const Index rank = std::min<Index>(rows, 3);
    LowRank b{X.topRows(rows) * C, Y * (Eigen::MatrixXd::Identity(3, 6) + 0.5 * C)};
    recompress(b, 1.01 * s(rank - 1) / s.norm());  // drops the smallest nonzero one
    EXPECT_EQ(b.rank(), rank - 1);
    EXPECT_NEAR((A - b.U * b.V.transpose()).norm(), s(rank - 1), 1e-12 * s(0));
  }
  LowRank zero{Eigen::MatrixXd::Zero(10, 4), Eigen::MatrixXd::Random(8, 4)};
  recompress(zero, 1e-8);
  EXPECT_EQ(zero.rank(), 0);
  EXPECT_EQ(zero.U.rows(), 10);
  EXPECT_EQ(zero.V.rows(), 8);
}
