#include <gtest/gtest.h>

#include "bem/linear_algebra.hpp"

using namespace bem;

TEST(LinearAlgebra, WrappersMatchEigen) {
  const Index n = 50;
  Matrix B = Matrix::Random(n, n);
  Matrix V = B * B.transpose() + n * Matrix::Identity(n, n);
  const Matrix A = Matrix::Random(n, n), C0 = Matrix::Random(n, n);
  const Matrix C = C0 + C0.transpose();
  const Matrix ref = 0.5 * (C + A.transpose() * V.llt().solve(A));
  Matrix L = V;
  ASSERT_EQ(cholesky_in_place(L), 0);
  Matrix Y = A, S = C;
  lower_solve_in_place(L, Y);
  add_gram_symmetric(Y, 0.5, S);
  EXPECT_LT((S - ref).cwiseAbs().maxCoeff(), 1e-12 * ref.cwiseAbs().maxCoeff());
  EXPECT_TRUE(S.isApprox(S.transpose(), 0.0));
  Vector b = Vector::Random(n), x = b;
  cholesky_solve_in_place(L, x);
  EXPECT_LT((V * x - b).norm(), 1e-12 * b.norm());
  Matrix indefinite = -V;
  EXPECT_EQ(cholesky_in_place(indefinite), 1);
}
