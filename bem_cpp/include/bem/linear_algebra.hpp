#pragma once
// Thin wrappers of the dense LAPACK/BLAS kernels (dpotrf, dpotrs, dtrsm, dsyrk) used
// by the Steklov-Poincare operator, and of dgesvd for the recompression of low-rank
// blocks. The first four run on the row-major matrices in place; OpenBLAS (what
// libblas.so.3/liblapack.so.3 point to) parallelises them. And one kernel of their own:
// the product of a matrix stored in single precision with a vector in double.
#include <Eigen/Dense>

#include "bem/geometry.hpp"

namespace bem {

/// Cholesky factorisation V = L L^T in place (V symmetric, n x n, only its upper
/// triangle is read). Returns 0 on success, otherwise the order k of the first leading
/// minor that is not positive definite (LAPACK's info). Afterwards the buffer holds the
/// factor in LAPACK's layout; use it only through the functions below.
int cholesky_in_place(Matrix& V);

/// b := V^{-1} b, with `factor` the output of cholesky_in_place(V).
void cholesky_solve_in_place(const Matrix& factor, Vector& b);

/// A := L^{-1} A (triangular solve with n right-hand sides), L L^T = V the Cholesky
/// factorisation held in `factor`.
void lower_solve_in_place(const Matrix& factor, Matrix& A);

/// C := scale * (C + Y^T Y), computed on the upper triangle by a rank-k update and
/// mirrored, so C is exactly symmetric on return (only C's upper triangle is read).
void add_gram_symmetric(const Matrix& Y, double scale, Matrix& C);

/// The thin singular value decomposition A = U diag(s) V^T of an m x n matrix: U m x k,
/// s (descending) and V n x k, k = min(m, n), by LAPACK's dgesvd. (Eigen 3.4.0's
/// BDCSVD, used before, reads out of bounds on some rank-deficient matrices when built
/// with -march=native, as this library is: a segmentation fault in S_h's set-up.)
struct ThinSvd {
  Eigen::MatrixXd U;
  Eigen::VectorXd s;
  Eigen::MatrixXd V;
};
ThinSvd thin_svd(Eigen::MatrixXd A);

using SingleMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// y = A x for A held in single precision (row-major), every product and sum in double:
/// the product of the double matrix with A's entries, at half the memory traffic of a
/// double matrix (rows split over the OpenMP threads).
Eigen::VectorXd single_matvec(const Eigen::Ref<const SingleMatrix>& A, const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace bem
