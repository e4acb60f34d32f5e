#include "bem/cyclic_tridiagonal.hpp"

#include <cmath>
#include <stdexcept>

namespace bem {

CyclicTridiagonal::CyclicTridiagonal(const Eigen::VectorXd& lower, const Eigen::VectorXd& diag,
                                     const Eigen::VectorXd& upper)
    : lower_(lower), diag_(diag), upper_(upper) {
  const Index n = diag.size();
  if (n < 3 || lower.size() != n || upper.size() != n)
    throw std::invalid_argument("CyclicTridiagonal: need n >= 3 and three vectors of length n");
  for (Index i = 0; i < n; ++i)
    if (!(std::abs(diag(i)) > std::abs(lower(i)) + std::abs(upper(i))))
      throw std::invalid_argument("CyclicTridiagonal: the matrix is not strictly diagonally dominant");
  // A = T + u v^T, u = (gamma, 0, ..., 0, alpha), v = (1, 0, ..., 0, beta / gamma), where
  // alpha = A[n-1, 0] = upper[n-1], beta = A[0, n-1] = lower[0]; T is A without corners and
  // diagonal entries diag[0] - gamma, diag[n-1] - alpha beta / gamma.
  const double alpha = upper(n - 1);
  beta_ = lower(0);
  gamma_ = -diag(0);
  diag_(0) -= gamma_;
  diag_(n - 1) -= alpha * beta_ / gamma_;
  for (Index i = 1; i < n; ++i) {  // Thomas: pivots in diag_, multipliers in lower_
    lower_(i) /= diag_(i - 1);
    diag_(i) -= lower_(i) * upper_(i - 1);
  }
  z_ = Eigen::VectorXd::Zero(n);
  z_(0) = gamma_;
  z_(n - 1) = alpha;
  thomas(z_.data());
  denominator_ = 1.0 + z_(0) + beta_ * z_(n - 1) / gamma_;
}

void CyclicTridiagonal::thomas(double* x) const {
  const Index n = diag_.size();
  for (Index i = 1; i < n; ++i) x[i] -= lower_(i) * x[i - 1];
  x[n - 1] /= diag_(n - 1);
  for (Index i = n - 2; i >= 0; --i) x[i] = (x[i] - upper_(i) * x[i + 1]) / diag_(i);
}

Eigen::MatrixXd CyclicTridiagonal::solve(const Eigen::MatrixXd& R) const {
  const Index n = diag_.size();
  if (R.rows() != n) throw std::invalid_argument("CyclicTridiagonal::solve: R has the wrong number of rows");
  Eigen::MatrixXd X = R;
  for (Index j = 0; j < X.cols(); ++j) {
    double* x = X.col(j).data();
    thomas(x);
    const double f = (x[0] + beta_ * x[n - 1] / gamma_) / denominator_;
    X.col(j) -= f * z_;
  }
  return X;
}

}  // namespace bem
