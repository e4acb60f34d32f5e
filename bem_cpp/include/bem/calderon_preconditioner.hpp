#pragma once
// Operator (Calderon) preconditioner for the single-layer matrix V_h
// (docs/design/hmatrix.md): V W = 1/4 - K^2 on a closed curve, so with a stable pairing
// G between the flux space and a trace space T and the hypersingular matrix W_T on T,
//   C = G^{-T} (W_T + c c^T) G^{-1},   c_i = int_Gamma t_i ds  (c c^T fixes the kernel of W),
// has cond(C V_h) bounded independently of h (measured: docs/design/hmatrix.md,
// "Parameters and why").
//   flux P1: T = P1 on the same mesh, G = M (P1 Gram), W_T = D^T V0 D with the P0
//            H-matrix V0 that S_h needs anyway;
//   flux P0: T = the dual hats (centred at the panel midpoints, value 1/2 at the nodes,
//            piecewise linear on the mesh refined at the midpoints: the 2D Buffa-Christiansen
//            space); G is tridiagonal (3h_i/4 on the diagonal, h/8 beside it) and W_T is
//            formed by Maue's identity on the refined mesh, with its own P0 H-matrix.
#include <memory>

#include "bem/cyclic_tridiagonal.hpp"
#include "bem/hmatrix.hpp"
#include "bem/operators.hpp"

namespace bem {

class CalderonPreconditioner {
 public:
  /// flux P1: V0 is the P0 H-matrix of the polygon. flux P0: V0 is ignored and the one of
  /// the refined polygon is built with `refined` (a loose tolerance suffices).
  CalderonPreconditioner(const Polygon& polygon, Space flux, std::shared_ptr<const HMatrix> V0,
                         const HMatrixOptions& refined);
  /// Z = C R for the columns of R (residuals of V_h X = B).
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::MatrixXd>& R) const;
  std::size_t nbytes() const;

 private:
  /// W_T Y + c (c^T Y) on the trace space T.
  Eigen::MatrixXd hypersingular(const Eigen::MatrixXd& Y) const;
  Space flux_;
  Index n_;
  std::unique_ptr<Polygon> refined_;  ///< flux P0: nodes and midpoints
  Eigen::VectorXd h_;                 ///< panel lengths of the mesh W_T lives on
  std::shared_ptr<const HMatrix> V0_;
  /// G = diag(scale_) T with T cyclic tridiagonal (P1: G itself, symmetric, scale_ = 1;
  /// P0: T = (1/8, 3/4, 1/8), scale_ = h), so G^{-1} R = T^{-1}(R / scale_) and
  /// G^{-T} R = (T^{-T} R) / scale_ with T^T = T: O(n) solves.
  CyclicTridiagonal T_;
  Eigen::VectorXd scale_;
  Eigen::VectorXd c_;
};

}  // namespace bem
