#include <gtest/gtest.h>

#include "bem/cyclic_tridiagonal.hpp"

using namespace bem;

TEST(CyclicTridiagonal, SolvesLikeTheDenseMatrix) {
  for (Index n : {3, 4, 7, 200}) {
    const Eigen::VectorXd lower = Eigen::VectorXd::Random(n), upper = Eigen::VectorXd::Random(n);
    const Eigen::VectorXd diag = lower.cwiseAbs() + upper.cwiseAbs() + Eigen::VectorXd::Constant(n, 0.5);
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
    for (Index i = 0; i < n; ++i) {
      A(i, (i + n - 1) % n) += lower(i);
      A(i, i) += diag(i);
      A(i, (i + 1) % n) += upper(i);
    }
    const CyclicTridiagonal T(lower, diag, upper);
    const Eigen::MatrixXd R = Eigen::MatrixXd::Random(n, 3);
    const Eigen::MatrixXd X = T.solve(R);
    EXPECT_LT((A * X - R).norm(), 1e-13 * R.norm()) << n;
  }
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(5);
  EXPECT_THROW(CyclicTridiagonal(one, one, one), std::invalid_argument);  // not dominant
  EXPECT_THROW(CyclicTridiagonal(one.head(2), 3 * one.head(2), one.head(2)), std::invalid_argument);
}
