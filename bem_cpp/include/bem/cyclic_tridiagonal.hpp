#pragma once
// Solves with a cyclic tridiagonal matrix (the Gram matrices of the Calderon
// preconditioner, calderon_preconditioner.hpp): row i is
//   lower[i] x[i-1] + diag[i] x[i] + upper[i] x[i+1] = r[i]   (indices mod n),
// by the Thomas algorithm on the matrix with its corners removed and one Sherman-Morrison
// correction (gamma = -diag[0]), both factored once: O(n) per solve, no pivoting, so the
// matrix must be strictly diagonally dominant (checked).
#include <Eigen/Dense>

#include "bem/geometry.hpp"

namespace bem {

class CyclicTridiagonal {
 public:
  CyclicTridiagonal() = default;
  /// Throws std::invalid_argument unless n >= 3 and |diag[i]| > |lower[i]| + |upper[i]|.
  CyclicTridiagonal(const Eigen::VectorXd& lower, const Eigen::VectorXd& diag, const Eigen::VectorXd& upper);
  Index size() const { return diag_.size(); }
  /// X = A^{-1} R for the columns of R.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& R) const;
  std::size_t nbytes() const { return static_cast<std::size_t>(5 * diag_.size()) * sizeof(double); }

 private:
  void thomas(double* x) const;           ///< in place, the matrix without corners (modified diagonal)
  Eigen::VectorXd lower_, diag_, upper_;  ///< diag_: the factored (Thomas) pivots
  Eigen::VectorXd z_;                     ///< the Sherman-Morrison vector
  double beta_ = 0, gamma_ = 0, denominator_ = 1;
};

}  // namespace bem
