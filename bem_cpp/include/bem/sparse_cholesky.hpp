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
  ///
  /// `n_schur` > 0 keeps the last n_schur rows of the ordering (the set S, in that order)
  /// out of the sparse elimination: the other rows H are eliminated by the multifrontal
  /// method, and S's block becomes the dense Schur complement A_SS - A_SH A_HH^{-1} A_HS
  /// (schur()), factored densely. The sweeps eliminate() and back_substitute() let a
  /// caller solve with another Schur complement in between (the interface problem of a
  /// coarse matrix split over ranks).
  SparseCholesky(Index n, const Eigen::Ref<const Indices>& indptr, const Eigen::Ref<const Indices>& indices,
                 const Eigen::Ref<const Eigen::VectorXd>& data, const Eigen::Ref<const Indices>& ordering,
                 Index n_schur = 0);

  Index size() const { return static_cast<Index>(perm_.size()); }
  /// Nonzeros of L (with the explicit zeros inside the supernodes' dense blocks).
  std::size_t factor_nonzeros() const { return values_at_.back(); }
  Index supernodes() const { return static_cast<Index>(first_.size()) - 1; }
  /// The Schur complement A_SS - A_SH A_HH^{-1} A_HS (n_schur x n_schur, S in the order
  /// of the ordering's last n_schur rows).
  const Eigen::MatrixXd& schur() const { return schur_; }

  /// X = A^{-1} B for the columns of B.
  Eigen::MatrixXd solve(const Eigen::Ref<const Eigen::MatrixXd>& B) const;
  /// The forward sweep over H for the columns of B: on S, B_S - A_SH A_HH^{-1} B_H; on H,
  /// intermediate values for back_substitute() (rows in A's numbering).
  Eigen::MatrixXd eliminate(const Eigen::Ref<const Eigen::MatrixXd>& B) const;
  /// The backward sweep over H: with W from eliminate() whose S rows were replaced by
  /// X_S, X_H = A_HH^{-1} (B_H - A_HS X_S); returns X (X_S as given).
  Eigen::MatrixXd back_substitute(const Eigen::Ref<const Eigen::MatrixXd>& W) const;

 private:
  void amalgamate(const std::vector<Index>& parent);  ///< merge the fundamental supernodes
  void forward(double* y, double* work) const;        ///< y := L_H^{-1} y over H, in place
  void backward(double* y, double* work) const;       ///< y := L_H^{-T} y over H, in place
  /// The columns of B permuted (a = false: Y_i = B_perm(i)) or back (a = true).
  Eigen::MatrixXd permuted(const Eigen::Ref<const Eigen::MatrixXd>& B, bool back) const;

  std::vector<Index> perm_;             ///< row i of P A P^T is row perm_[i] of A
  std::vector<Index> first_;            ///< supernode s holds the columns first_[s] .. first_[s+1]-1
  std::vector<std::size_t> rows_at_;    ///< the row indices of supernode s: rows_[rows_at_[s] ..]
  std::vector<Index> rows_;             ///< sorted; the first ones are the supernode's own columns
  std::vector<std::size_t> values_at_;  ///< supernode s's dense m x k block (column-major) at values_at_[s]
  Buffer values_;
  std::size_t largest_front_ = 0;  ///< the most rows of a supernode (a solve's work array)
  Eigen::MatrixXd schur_;          ///< S's Schur complement (lower and upper triangles)
  Eigen::LLT<Eigen::MatrixXd> schur_factor_;
};

}  // namespace bem
