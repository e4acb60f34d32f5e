#pragma once
// Supernodal sparse Cholesky factorisation P A P^T = L L^T of a symmetric positive
// definite matrix, by the multifrontal method: the columns of L that share one row
// structure (a supernode) are factored together as a dense frontal matrix with LAPACK
// (dpotrf, dtrsm, dsyrk), and each front passes its Schur complement (the update
// matrix) to its parent in the elimination tree. The ordering P is the caller's (a
// fill-reducing one, e.g. nested dissection); the elimination tree is postordered on
// top of it, which changes no fill.
//
// Used for the coarse problem of the substructuring preconditioner, which every rank
// factors whole: a row-by-row sparse factorisation spends its time in indexed scalar
// updates, the dense fronts in BLAS-3 (docs/design/preconditioners.md).
#include <Eigen/Dense>
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <vector>

#include "bem/geometry.hpp"

namespace bem {

/// A pivot <= 0 in a Cholesky factorisation: the matrix is not positive definite.
class NotPositiveDefinite : public std::domain_error {
 public:
  using std::domain_error::domain_error;
};

class SparseCholesky {
 public:
  using Indices = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>;
  struct Free {
    void operator()(double* p) const { std::free(p); }
  };
  using Buffer = std::unique_ptr<double[], Free>;

  /// Factor the n x n matrix A held in CSR (indptr, indices, data), which must hold both
  /// triangles of its symmetric pattern (only the entries that land on or below the
  /// diagonal of P A P^T are read). `ordering[i]` is the row of A that becomes row i
  /// (a permutation of 0..n-1). Throws std::invalid_argument on malformed input and
  /// NotPositiveDefinite if A is not positive definite.
  SparseCholesky(Index n, const Eigen::Ref<const Indices>& indptr, const Eigen::Ref<const Indices>& indices,
                 const Eigen::Ref<const Eigen::VectorXd>& data, const Eigen::Ref<const Indices>& ordering);

  Index size() const { return static_cast<Index>(perm_.size()); }
  /// Nonzeros of L (with the explicit zeros inside the supernodes' dense blocks).
  std::size_t factor_nonzeros() const { return values_at_.back(); }
  Index supernodes() const { return static_cast<Index>(first_.size()) - 1; }

  /// X = A^{-1} B for the columns of B.
  Eigen::MatrixXd solve(const Eigen::Ref<const Eigen::MatrixXd>& B) const;

 private:
  void amalgamate(const std::vector<Index>& parent);   ///< merge the fundamental supernodes
  void solve_permuted(double* y, double* work) const;  ///< y := (L L^T)^{-1} y, in place

  std::vector<Index> perm_;             ///< row i of P A P^T is row perm_[i] of A
  std::vector<Index> first_;            ///< supernode s holds the columns first_[s] .. first_[s+1]-1
  std::vector<std::size_t> rows_at_;    ///< the row indices of supernode s: rows_[rows_at_[s] ..]
  std::vector<Index> rows_;             ///< sorted; the first ones are the supernode's own columns
  std::vector<std::size_t> values_at_;  ///< supernode s's dense m x k block (column-major) at values_at_[s]
  Buffer values_;
  std::size_t largest_front_ = 0;  ///< the most rows of a supernode (a solve's work array)
};

}  // namespace bem
