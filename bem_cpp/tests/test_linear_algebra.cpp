#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>

#include "bem/aca.hpp"
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

namespace {
void expect_thin_svd_of(const Eigen::MatrixXd& A) {
  const ThinSvd d = thin_svd(A);
  const Index k = std::min(A.rows(), A.cols());
  ASSERT_EQ(d.U.rows(), A.rows());
  ASSERT_EQ(d.V.rows(), A.cols());
  ASSERT_EQ(d.s.size(), k);
  const double tol = 1e-14 * static_cast<double>(std::max(A.rows(), A.cols()));
  EXPECT_LT((d.U * d.s.asDiagonal() * d.V.transpose() - A).norm(), tol * A.norm());
  EXPECT_LT((d.U.transpose() * d.U - Eigen::MatrixXd::Identity(k, k)).norm(), tol);
  EXPECT_LT((d.V.transpose() * d.V - Eigen::MatrixXd::Identity(k, k)).norm(), tol);
  for (Index i = 1; i < k; ++i) EXPECT_GE(d.s(i - 1), d.s(i));
}
}  // namespace

TEST(LinearAlgebra, ThinSvdOfWideTallAndRankDeficientMatrices) {
  expect_thin_svd_of(Eigen::MatrixXd::Random(7, 12));
  expect_thin_svd_of(Eigen::MatrixXd::Random(12, 7));
  const Eigen::MatrixXd low = Eigen::MatrixXd::Random(30, 3) * Eigen::MatrixXd::Random(3, 20);
  expect_thin_svd_of(low);
  EXPECT_LT(thin_svd(low).s(3), 1e-13 * thin_svd(low).s(0));
}

TEST(LinearAlgebra, ThinSvdOfTheMatrixThatCrashedBdcsvd) {
  // R_U R_V^T of one block's recompression in S_h's set-up on the cube of 96 squares per
  // side (singular values 2e-5 .. 2e-27): Eigen 3.4.0's BDCSVD, built with -march=native,
  // read out of bounds on it and the set-up ended in a segmentation fault.
  std::ifstream in(std::string(BEM_TEST_DATA) + "/bdcsvd_crash_36x72.bin", std::ios::binary);
  ASSERT_TRUE(in.good());
  std::int64_t shape[2];
  in.read(reinterpret_cast<char*>(shape), sizeof(shape));
  ASSERT_EQ(shape[0], 36);
  ASSERT_EQ(shape[1], 72);
  Eigen::MatrixXd A(shape[0], shape[1]);  // column-major, as written
  in.read(reinterpret_cast<char*>(A.data()), static_cast<std::streamsize>(A.size() * sizeof(double)));
  ASSERT_TRUE(in.good());
  expect_thin_svd_of(A);
  // and the recompression that met it keeps the block to its tolerance
  LowRank a{A, Eigen::MatrixXd::Identity(72, 72)};
  recompress(a, 1e-6);
  EXPECT_LT(a.rank(), 36);
  EXPECT_LT((a.U * a.V.transpose() - A).norm(), 1e-6 * A.norm());
}

TEST(LinearAlgebra, SingleMatvecIsTheDoubleProductOfTheStoredEntries) {
  // A in single precision times x in double: the double product of A's entries (exactly
  // representable in double), summed in double: within n round-offs of double, far below
  // float's 6e-8; a float product would be off by about 1e-7.
  const Index m = 37, n = 1001;
  const SingleMatrix A = SingleMatrix::Random(m, n);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(n);
  const Eigen::VectorXd expected = A.cast<double>() * x;
  const Eigen::VectorXd y = single_matvec(A, x);
  EXPECT_LT((y - expected).norm(), 1e-14 * expected.norm());
  const Eigen::VectorXf in_float = A * x.cast<float>();
  EXPECT_GT((in_float.cast<double>() - expected).norm(), 1e-9 * expected.norm());
  EXPECT_THROW(single_matvec(A, Eigen::VectorXd::Zero(n + 1)), std::invalid_argument);
}
