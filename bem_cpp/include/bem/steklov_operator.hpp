#pragma once
// The discrete Steklov-Poincare operator as an operator that is applied, never formed
// (docs/method.md section 4, docs/design/hmatrix.md):
//   S x = 1/2 ( W x + (K - M)^T V^{-1} (K - M) x ),   W x = D^T V0 D x (Maue),
// with V (flux space), V0 (P0, for W) and K (rows in the flux space, columns P1)
// H-matrices, M and D sparse, and V^{-1} by SingleLayerSolver (PCG).
// Distributed (options.hmatrix.comm): every H-matrix holds the rows of its rank
// (hmatrix.hpp) and every product in S, the CG and the preconditioner returns the whole
// vector on every rank; the CG scalars then come from the same vectors on every rank, so
// the iterates and the result are the same bits everywhere. M, D, G stay replicated (O(n)).
#include <atomic>
#include <memory>

#include "bem/calderon_preconditioner.hpp"
#include "bem/hmatrix.hpp"
#include "bem/operators.hpp"
#include "bem/single_layer_solver.hpp"

namespace bem {

struct SteklovOptions {
  HMatrixOptions hmatrix;
  double preconditioner_tol;  ///< flux P0: tolerance of the refined-mesh V0 of the preconditioner
  double solver_tol;          ///< relative residual of the V solves
  int max_iterations;         ///< of each V solve
};

/// What the set-up built.
struct SteklovInfo {
  double setup_seconds = 0;
  double near_field_seconds = 0;    ///< of set-up: the near pairs of the surface operators (3D)
  double single_layer_seconds = 0;  ///< of set-up: the H-matrices of V_h and W_h (3D)
  double double_layer_seconds = 0;  ///< of set-up: the H-matrix of K_h (3D)
  Index max_rank = 0;               ///< largest rank of a low-rank block (V, V0 or W, K)
  /// bytes of V_h, V0_h (2D: the Calderon preconditioner's P0 single layer), K_h, W_h (3D),
  /// and of the sparse preconditioner parts
  std::size_t nbytes_v = 0, nbytes_v0 = 0, nbytes_k = 0, nbytes_w = 0, nbytes_preconditioner = 0;
};

class SteklovPoincareOperator {
 public:
  SteklovPoincareOperator(const Eigen::Ref<const Points>& nodes, Space flux, const SteklovOptions& options);

  Index size() const { return polygon_.size(); }
  /// Y = S_h X for X (n, k); its V solve to the relative residual `solver_tol` where that
  /// is looser than the options' solver_tol (else, and for 0, to the options'): a cheaper,
  /// less accurate product for an outer iteration that needs only a few digits.
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol = 0.0) const;
  /// Psi = V_h^{-1} (K_h - M_h)(X): the exterior Neumann data of the Dirichlet traces X
  /// (columns; cf. exterior_flux with a = 0); `solver_tol` as for apply.
  Eigen::MatrixXd flux(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol = 0.0) const;
  std::size_t nbytes() const;
  const SteklovInfo& info() const { return info_; }
  /// CG iterations of the V solve of the last apply/flux call.
  int last_iterations() const { return last_iterations_.load(); }

 private:
  Eigen::MatrixXd double_layer_minus_mass(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) const;
  Polygon polygon_;
  Space flux_;
  SteklovOptions options_;
  std::shared_ptr<const HMatrix> V_, V0_, K_;
  std::unique_ptr<CalderonPreconditioner> preconditioner_;
  std::unique_ptr<SingleLayerSolver> solver_;
  SteklovInfo info_;
  mutable std::atomic<int> last_iterations_{0};
};

}  // namespace bem
