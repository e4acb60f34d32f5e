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
