#pragma once
// Solves V_h X = B with V_h held as an H-matrix (hmatrix.hpp) by preconditioned
// conjugate gradients, the columns of B as independent systems sharing the products
// (V_h is symmetric positive definite when the logarithmic capacity of Gamma is below 1,
// e.g. diam(Omega) < 1; docs/method.md section 2). The preconditioner is an argument
// (calderon_preconditioner.hpp gives iteration counts bounded in n).
#include <functional>
#include <memory>

#include "bem/hmatrix.hpp"

namespace bem {

/// Z = C R for the columns of R.
using Preconditioner = std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)>;

class SingleLayerSolver {
 public:
  SingleLayerSolver(std::shared_ptr<const HMatrix> V, Preconditioner preconditioner);

  /// X = V^{-1} B, each column to the relative residual |V x - b| <= tol |b|. Returns the
  /// largest number of iterations over the columns. Throws std::invalid_argument naming
  /// the logarithmic capacity if V is found indefinite (p^T V p <= 0), std::runtime_error
  /// if a column has not converged in max_iterations.
  int solve(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::MatrixXd& X, double tol, int max_iterations) const;

 private:
  std::shared_ptr<const HMatrix> V_;
  Preconditioner preconditioner_;
};

}  // namespace bem
