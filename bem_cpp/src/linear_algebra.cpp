#include "bem/linear_algebra.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

// Fortran LAPACK/BLAS symbols (LP64). The trailing lengths are the hidden
// character-argument lengths of the Fortran calling convention.
extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t);
void dpotrs_(const char* uplo, const int* n, const int* nrhs, const double* a, const int* lda, double* b,
             const int* ldb, int* info, std::size_t);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m, const int* n,
            const double* alpha, const double* a, const int* lda, double* b, const int* ldb, std::size_t, std::size_t,
            std::size_t, std::size_t);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha, const double* a,
            const int* lda, const double* beta, double* c, const int* ldc, std::size_t, std::size_t);
void dgesvd_(const char* jobu, const char* jobvt, const int* m, const int* n, double* a, const int* lda, double* s,
             double* u, const int* ldu, double* vt, const int* ldvt, double* work, const int* lwork, int* info,
             std::size_t, std::size_t);
}

// A row-major n x n buffer is the column-major buffer of the transpose: the row-major
// upper triangle that we fill is LAPACK's lower triangle ('L'). For symmetric V,
// dpotrf('L') gives V = Lc Lc^T with Lc in that triangle.

namespace bem {

namespace {
int checked_size(const Matrix& A) {
  if (A.rows() != A.cols()) throw std::invalid_argument("linear algebra: matrix must be square");
  if (A.rows() > 46340) throw std::invalid_argument("linear algebra: matrix too large for LP64 LAPACK");
  return static_cast<int>(A.rows());
}
}  // namespace

int cholesky_in_place(Matrix& V) {
  const int n = checked_size(V);
  int info = 0;
  dpotrf_("L", &n, V.data(), &n, &info, 1);
  if (info < 0) throw std::logic_error("dpotrf: illegal argument");
  return info;
}

void cholesky_solve_in_place(const Matrix& factor, Vector& b) {
  const int n = checked_size(factor), one = 1;
  if (b.size() != n) throw std::invalid_argument("cholesky_solve: size mismatch");
  int info = 0;
  dpotrs_("L", &n, &one, factor.data(), &n, b.data(), &n, &info, 1);
  if (info != 0) throw std::logic_error("dpotrs: illegal argument");
}

void lower_solve_in_place(const Matrix& factor, Matrix& A) {
  const int n = checked_size(factor);
  if (A.rows() != n) throw std::invalid_argument("lower_solve: size mismatch");
  const int m = static_cast<int>(A.cols());
  const double one = 1.0;
  // Column-major view: the buffer of A holds A^T (m x n); A^T := A^T Lc^{-T} is
  // A := Lc^{-1} A.
  dtrsm_("R", "L", "T", "N", &m, &n, &one, factor.data(), &n, A.data(), &m, 1, 1, 1, 1);
}

void add_gram_symmetric(const Matrix& Y, double scale, Matrix& C) {
  const int n = checked_size(C);
  if (Y.cols() != n) throw std::invalid_argument("add_gram: size mismatch");
  const int k = static_cast<int>(Y.rows());
  const double one = 1.0;
  // Column-major view: the buffer of Y holds Y^T (n x k); C := C + Y^T (Y^T)^T on the
  // column-major lower triangle, which is the row-major upper triangle.
  dsyrk_("L", "N", &n, &k, &one, Y.data(), &n, &one, C.data(), &n, 1, 1);
  // Scale and mirror the upper triangle, tile by tile for cache locality.
  constexpr Index tile = 64;
  const Index nn = n, nb = (nn + tile - 1) / tile;
#pragma omp parallel for schedule(dynamic, 1)
  for (Index I = 0; I < nb; ++I)
    for (Index J = 0; J <= I; ++J)
      for (Index r = I * tile; r < std::min(nn, (I + 1) * tile); ++r)
        for (Index c = J * tile; c < std::min(r + 1, (J + 1) * tile); ++c) {
          const double s = scale * C(c, r);
          C(r, c) = s;
          C(c, r) = s;
        }
}

ThinSvd thin_svd(Eigen::MatrixXd A) {
  const int m = static_cast<int>(A.rows()), n = static_cast<int>(A.cols()), k = std::min(m, n);
  ThinSvd r{Eigen::MatrixXd(m, k), Eigen::VectorXd(k), Eigen::MatrixXd(k, n)};
  if (k == 0) {
    r.V.resize(n, 0);
    return r;
  }
  const int lda = std::max(1, m), ldvt = std::max(1, k);
  int info = 0, lwork = -1;
  double query = 0.0;
  dgesvd_("S", "S", &m, &n, A.data(), &lda, r.s.data(), r.U.data(), &lda, r.V.data(), &ldvt, &query, &lwork, &info, 1,
          1);
  lwork = static_cast<int>(query);
  std::vector<double> work(static_cast<std::size_t>(std::max(lwork, 1)));
  dgesvd_("S", "S", &m, &n, A.data(), &lda, r.s.data(), r.U.data(), &lda, r.V.data(), &ldvt, work.data(), &lwork, &info,
          1, 1);
  if (info < 0) throw std::logic_error("dgesvd: illegal argument");
  if (info > 0) throw std::runtime_error("dgesvd: the QR iteration did not converge");
  r.V.transposeInPlace();  // V^T (k x n) -> V (n x k)
  return r;
}

Eigen::VectorXd single_matvec(const Eigen::Ref<const SingleMatrix>& A, const Eigen::Ref<const Eigen::VectorXd>& x) {
  if (A.cols() != x.size())
    throw std::invalid_argument("single_matvec: A has " + std::to_string(A.cols()) + " columns, x " +
                                std::to_string(x.size()) + " entries");
  const Index m = A.rows(), n = A.cols();
  Eigen::VectorXd y(m);
  const double* xs = x.data();
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < m; ++i) {
    const float* a = A.data() + i * A.outerStride();
    double s = 0.0;
#pragma omp simd reduction(+ : s)
    for (Index j = 0; j < n; ++j) s += static_cast<double>(a[j]) * xs[j];
    y(i) = s;
  }
  return y;
}

}  // namespace bem
