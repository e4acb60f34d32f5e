#pragma once
// The discrete Steklov-Poincare operator of linear elastostatics (the Lame operators,
// lame_polygon.hpp), applied and never formed, as the scalar one (steklov_operator.hpp):
//   S x = 1/2 ( W x + (K - M)^T V^{-1} (K - M) x )
// on the vector P1 traces (d n dofs, node-major), flux P1 or P0. The operator is assembled
// from parts that do not depend on the dimension d (LameSteklovParts: the H-matrix of V_h,
// the products with W_h and K_h, the mass matrix, a preconditioner for V_h and a basis to
// deflate); lame_polygon_steklov_parts builds them on a polygon (d = 2), in the notation
// of lame_polygon_entries.hpp (D_h: arc-length derivative of the hats kron I_2, K_L and
// V0_L: the Laplace double layer and P0 single layer):
//   flux P1: V_h the vector H-matrix of the P1 Kelvin-like matrix (node tree expanded by 2,
//            ClusterTree::expanded, symmetric storage), W_h = D_h^T X0 D_h with X0 that of
//            the P0 one (symmetric), K_h = K_L kron I_2 + Y D_h with Y that of the P1 x P0
//            one: three vector H-matrices and one scalar;
//   flux P0: V_h, X0 and Y are all combinations of the P0 moments L (log) and D (direction):
//            V_h = c (-(3 - 4 nu) L kron I + D), and with L = -pi V0_L,
//              X0 = 4 mu^2 V_h - 2 mu (1 - 2 nu)/(1 - nu) V0_L kron I_2,
//              Y  = (2 mu V_h - V0_L kron I_2) R   (R = [[0, -1], [1, 0]] per panel),
//            so one vector H-matrix (V_h) and two scalar ones (V0_L, K_L) give S_h (no
//            cancellation: the coefficients stay bounded as nu -> 1/2).
// V^{-1} is SingleLayerSolver (PCG) with the preconditioner
//   C = s (C_L - 1 1^T) kron I_d + Q (Q^T V Q)^{-1} Q^T,
// C_L = G^{-T} (W_L + c c^T) G^{-1} the scalar Laplace Calderon preconditioner
// (calderon_preconditioner.hpp: P1 flux G = M, W_L = D^T V0_L D; P0 flux the dual hats of
// the refined mesh), at the loose preconditioner_tol, without its constant mode (C_L 1 1^T
// part, G^{-T} c = 1), scaled by s = 8 mu (1 - nu)/(3 - 4 nu) (the Laplace V against the
// log part of the Lame V, 2 mu (1 - nu)/(3 - 4 nu), times 4: measured below), and Q the
// rigid motions and the normal field in the flux space with Q^T V Q's inverse: the form of
// M^{-1} (W + alpha sum_r (M r)(M r)^T) M^{-1} with W spectrally equivalent to W_L kron I,
// alpha_r = 1/(r^T V r) over V-orthogonal r (the scalar 3D operator's alpha = 1/(2 rho
// |Gamma|) is that on the sphere). The normal field n has V n -> 0 as nu -> 1/2 (the
// pressure mode, lame_polygon.hpp): deflated with the rigid motions, cond(C V) stays at
// 6-13 for nu = 0.49 (without: 60-70). Measured cond(C V) (dense, n = 200, nu = 0.3, circle /
// square / L-shape): 4.1 / 4.1 / 4.5 with s as above (3 s/4: 3.3 / 3.7 / 4.8; 5 s/4: 4.9 /
// 4.8 / 4.7); the Lame W_h in place of s W_L kron I: 1.2 / 2.8 / 7.1, whose products cost as
// much as V's in every iteration (W_L's: a scalar P0 matrix at the loose tolerance, held in
// single precision). CG iteration counts (tests/test_lame_steklov.cpp) stay bounded as
// h -> 0: circle 10, square 18-20, L-shape 21-23 for n = 256 ... 8,192 (P1 flux, nu = 0.3).
// Accuracy: the vector H-matrices (and V0_L of flux P0) at tol / 10, because their errors
// are amplified in S_h (by D_h^T ... D_h in W and K, about 8 times, and by V^{-1}): with
// them at tol, S_h's product error was 6e-10 at tol 1e-10, now 4e-11 ... 7e-11; the node
// trees of the vector matrices have leaves of leaf_size / 2 nodes (leaf_size dofs).
// Cost against SteklovPoincareOperator (same polygon, tol 1e-10, leaf 48, eta 2, one
// thread, CPU seconds, a shared machine: +-10 %; circle / L-shape, n = 16,000):
//   flux P1: set-up 3.9-4.6 / 4.4-4.7 s (Laplace 1.0-1.1 / 1.15-1.3), 416 / 496 MB (77 /
//            102), product 0.16-0.19 / 0.35-0.39 s (0.054-0.062 / 0.095-0.11): about 4.0 /
//            3.9, 5.4 / 4.9 and 3.0 / 3.7 times. Set-up (L-shape): V 0.9, X0 0.9, Y and K_L
//            2.2, preconditioner 0.3 s; product: 23 x (V 9.7 + C 2.8 ms) + W 9.5 + K 21 +
//            K^T 22 ms; bytes: V 113, X0 112, Y 216, K_L 43, preconditioner 12 MB;
//   flux P0: set-up 2.2 / 2.3 s, 170 / 207 MB, product 0.25 / 0.46 s (Laplace P0: 1.1 /
//            1.5 s, 87 / 109 MB, 0.083 / 0.127 s): 2.0 / 1.5, 2.0 / 1.9 and 2.9 / 3.6 times.
// The P1 flux needs three vector matrices where the Laplace operator has two scalar ones
// and a double layer that is nearly free on polygons; a vector block's rank is about twice
// the scalar's (10.3 against 5.5) on twice the rows and columns, and Y is not symmetric.
// Distributed (options.hmatrix.comm): every H-matrix holds the rows of its rank and every
// product returns the whole vector on every rank (hmatrix.hpp); the sparse and O(n) parts
// are replicated, so CG runs on the same vectors everywhere and every rank gets the same
// bits.
#include <Eigen/Sparse>
#include <atomic>
#include <functional>
#include <memory>
#include <vector>

#include "bem/hmatrix.hpp"
#include "bem/kelvin.hpp"
#include "bem/single_layer_solver.hpp"
#include "bem/steklov_operator.hpp"

namespace bem {

/// SteklovInfo (nbytes_v: V_h; nbytes_w: X0 of W_h (flux P1); nbytes_v0: V0_L (flux P0);
/// nbytes_k: Y and K_L; nbytes_preconditioner: the preconditioner's matrices;
/// single_layer_seconds, double_layer_seconds: the set-up of V_h and of K_h's matrices;
/// near_field_seconds: CPU seconds summed over the threads on the entries of the vector
/// H-matrices' dense blocks) with the rest of the set-up.
struct LameSteklovInfo : SteklovInfo {
  double hypersingular_seconds = 0;   ///< of set-up: X0 (flux P1) or V0_L (flux P0)
  double preconditioner_seconds = 0;  ///< of set-up: the preconditioner and Q^T V Q
  double far_field_cpu_seconds = 0;   ///< CPU seconds on the ACA rows and columns (vector H-matrices)
};

/// The parts of S_h in any dimension d (flux space of N dofs, trace space of d n); the
/// functions are collective when distributed and return the same on every rank.
struct LameSteklovParts {
  int dimension = 2;
  Index traces = 0;                                                      ///< d n
  std::shared_ptr<const HMatrix> single_layer;                           ///< V_h (N x N)
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> hypersingular;  ///< X -> W_h X
  /// (X, transpose) -> K_h X (N rows) or K_h^T X (d n rows)
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&, bool)> double_layer;
  Eigen::SparseMatrix<double> mass;  ///< M_h (N x d n)
  /// R -> C0 R, a symmetric positive semi-definite preconditioner of V_h whose null space
  /// the deflation basis spans.
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> preconditioner;
  Eigen::MatrixXd deflation;  ///< Q (N, r): C = C0 + Q (Q^T V Q)^{-1} Q^T
  LameSteklovInfo info;       ///< the parts' set-up times and bytes
  /// nodes -> the principal submatrix of W_h on their d k vector dofs (node-major), read from
  /// W_h's H-matrices; empty where W_h is not held on the nodes (the polygon's: D_h^T X0 D_h).
  std::function<Eigen::MatrixXd(const std::vector<Index>&)> hypersingular_block;
};

/// The parts on a polygon (d = 2). Throws std::invalid_argument for an invalid medium.
LameSteklovParts lame_polygon_steklov_parts(const Polygon& polygon, const Lame& m, Space flux,
                                            const SteklovOptions& options);

class LameSteklovOperator {
 public:
  /// On a closed polygon (nodes counter-clockwise, as SteklovPoincareOperator); V_h must be
  /// positive definite (Gamma below the critical scale, single_layer_critical_scale).
  LameSteklovOperator(const Eigen::Ref<const Points>& nodes, const Lame& m, Space flux, const SteklovOptions& options);
  /// From parts of any dimension (options: solver_tol and max_iterations).
  LameSteklovOperator(LameSteklovParts parts, const SteklovOptions& options);

  /// d n (d = 2 on a polygon).
  Index size() const { return parts_.traces; }
  int dimension() const { return parts_.dimension; }
  /// Y = S_h X for X (d n, k); the V solve to `solver_tol` if looser than the options'.
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol = 0.0) const;
  /// Psi = V_h^{-1} (K_h - M_h) X: the exterior tractions of the traces X (a = 0), in the
  /// flux space (N rows).
  Eigen::MatrixXd flux(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol = 0.0) const;
  /// W_h X and K_h X (transpose: K_h^T Psi, Psi with N rows).
  Eigen::MatrixXd hypersingular(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  Eigen::MatrixXd double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose = false) const;
  /// Whether hypersingular_block can read W_h's blocks (the surface's operator, d = 3).
  bool holds_hypersingular() const { return static_cast<bool>(parts_.hypersingular_block); }
  /// The principal submatrix of W_h on the d k vector dofs {d i + c} of the k distinct nodes
  /// `nodes` (d k, d k) node-major, from the H-matrices of W_h (to their tolerance), without
  /// integrating it again; collective when distributed, the same bits on every rank. Throws
  /// std::logic_error where W_h is not held that way (holds_hypersingular() false).
  Eigen::MatrixXd hypersingular_block(const std::vector<Index>& nodes) const;
  /// C R for residuals R (N rows).
  Eigen::MatrixXd precondition(const Eigen::MatrixXd& R) const;
  const HMatrix& single_layer() const { return *parts_.single_layer; }
  std::size_t nbytes() const;
  const LameSteklovInfo& info() const { return parts_.info; }
  /// CG iterations of the V solve of the last apply/flux call.
  int last_iterations() const { return last_iterations_.load(); }

 private:
  void check_rows(Index rows, Index expected) const;
  LameSteklovParts parts_;
  SteklovOptions options_;
  Eigen::MatrixXd deflation_inverse_;  ///< (Q^T V Q)^{-1}
  std::unique_ptr<SingleLayerSolver> solver_;
  mutable std::atomic<int> last_iterations_{0};
};

}  // namespace bem
