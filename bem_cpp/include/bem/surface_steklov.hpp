#pragma once
// The discrete Steklov-Poincare operator of a closed surface, applied and never formed
// (docs/method.md section 11, docs/design/bem3d.md):
//   S x = 1/2 ( W x + (K - M)^T V^{-1} (K - M) x ),
// V (P1 flux), W and K (P1 x P1) H-matrices on the 3D cluster tree of the vertices, W by
// Nedelec's identity W = sum_c C_c^T V0 C_c (C_c: the component c of the surface curls of
// the hats, V0 the P0 single layer) block by block from the single-layer kernel, so that
// the P0 operator on the twice as many triangles is never held; M the sparse P1 Gram matrix,
// and V^{-1} by SingleLayerSolver (PCG) with the operator preconditioner
//   C = M^{-1} (W + alpha c c^T) M^{-1},  c = M 1,  alpha = 1 / (2 rho |Gamma|),
// rho = (|Gamma| / 4 pi)^(1/2) (on a sphere the constant mode then has C V = 1 like the
// others, 4 l (l+1) / (2l+1)^2), whose iteration counts stay bounded as h -> 0.
// Distributed (options.hmatrix.comm): as the 2D operator (steklov_operator.hpp), every
// H-matrix holds the rows of its rank and every product returns the whole vector on
// every rank; M and C_c stay replicated.
#include <Eigen/Sparse>
#include <atomic>
#include <memory>

#include "bem/hmatrix.hpp"
#include "bem/single_layer_solver.hpp"
#include "bem/steklov_operator.hpp"
#include "bem/surface_entries.hpp"

namespace bem {

class SurfaceSteklovOperator {
 public:
  /// options.preconditioner_tol is not used (the preconditioner reuses W).
  SurfaceSteklovOperator(VerticesRef vertices, TrianglesRef triangles, const SteklovOptions& options);

  Index size() const { return surface_.vertices(); }
  /// Y = S_h X for X (n, k); the V solve to `solver_tol` if looser than the options' (as in 2D).
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol = 0.0) const;
  /// Psi = V_h^{-1} (K_h - M_h) X (the exterior Neumann data of the traces X, a = 0).
  Eigen::MatrixXd flux(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol = 0.0) const;
  /// V_h X and K_h X (the operator's H-matrices of the P1 single and double layer, alone:
  /// e.g. the residual of the boundary integral equation in an a posteriori estimator).
  Eigen::MatrixXd single_layer(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  Eigen::MatrixXd double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// W_h X (the H-matrix of Nedelec's identity).
  Eigen::MatrixXd hypersingular(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// The principal submatrix of W_h on the vertices `indices` (m, m), from its H-matrix
  /// (to its tolerance): the hypersingular block of the dofs whose hats lie in a part of
  /// the surface (e.g. Gamma_s's interior nodes), without integrating it again. The same
  /// on every rank (collective when distributed).
  Eigen::MatrixXd hypersingular_block(const std::vector<Index>& indices) const;
  /// The same block in single precision (half the memory), for an operator that stores its
  /// blocks in single precision (its entries carry that rounding already). Serial: written
  /// in single precision directly; distributed: summed in double, then rounded.
  Eigen::MatrixXf hypersingular_block_single(const std::vector<Index>& indices) const;
  std::size_t nbytes() const;
  const SteklovInfo& info() const { return info_; }
  int last_iterations() const { return last_iterations_.load(); }

 private:
  Eigen::MatrixXd precondition(const Eigen::MatrixXd& R) const;
  Surface surface_;
  SteklovOptions options_;
  std::shared_ptr<const HMatrix> V_, W_, K_;
  Eigen::SparseMatrix<double> M_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> mass_factor_;
  Eigen::VectorXd c_;
  double alpha_ = 1.0;
  std::unique_ptr<SingleLayerSolver> solver_;
  SteklovInfo info_;
  mutable std::atomic<int> last_iterations_{0};
};

}  // namespace bem
