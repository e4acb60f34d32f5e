#pragma once
// The H-matrices of the 3D Lame operators on a closed triangulated surface (lame_surface.hpp,
// P1 traces and P1 flux, vector dofs node-major) for the Steklov-Poincare operator
// S_h = 1/2 (W_h + (K_h - M_h)^T V_h^{-1} (K_h - M_h)):
//   V_h                          one H-matrix (symmetric) on the vertex tree expanded by 3,
//   K_h = K_L kron I + Y,        W_h = 2 mu W_L kron I + Z,
// with K_L and W_L the Laplace H-matrices of surface_entries.hpp on the vertex tree (applied
// to the three components at once) and Y, Z vector H-matrices (lame_surface_entries.hpp: the
// split, and why). V_h and Z come from one pass over the symmetric block tree
// (HMatrix::family), which also computes Y's blocks; each admissible block's entries come from
// one cross approximation of each of the two point kernels g = 1 / (2 pi r) and
// A = (r r^T / (2 pi r^3) + (1 - 2 nu) g I) / (2 (1 - nu)). Near pairs: the dense assembly's
// entries (sparse near fields, the Lame and the Laplace one).
//
// lame_surface_steklov_parts gives them to LameSteklovOperator (lame_steklov.hpp) with
//   M_h = (P1 Gram matrix) kron I_3,
//   C0 = s (M^{-1} W_L M^{-1}) kron I_3,  s = 6 mu (1 - nu) / (3.5 - 4 nu) = 1.5 / (cu (3.5 - 4 nu)),
//   Q = the six rigid motions and the normal field at the vertices (deflated: C = C0 + Q (Q^T V Q)^{-1} Q^T),
// C0 the Laplace operator preconditioner of surface_steklov.hpp on each component (W_L is
// K_h's and W_h's own: no matrix more), scaled to the isotropic part of V_h: on a surface the
// near field's r r^T / r^2 averages to about (I - n n^T) / 2, so V_h ~ cu (3.5 - 4 nu) V_L kron I,
// and s is 1.5 times its inverse (measured, dense: cond(C V) = 2.9 on the sphere of 642
// vertices, 3.9 and 4.9 on the cube and Fichera's corner of 218, nu = 0.3; factors 1 and 2
// gave 3.4 / 4.7 / 5.8 and 3.2 / 3.6 / 4.5; without the normal field in Q: 5.7 on the sphere;
// nu = 0.49: 4.2 on the sphere, 13.6 on Fichera's corner).
#include <memory>

#include "bem/hmatrix.hpp"
#include "bem/kelvin.hpp"
#include "bem/lame_steklov.hpp"
#include "bem/surface.hpp"
#include "bem/surface_operators.hpp"

namespace bem {

/// Where the set-up went (wall seconds unless said otherwise) and what it holds.
struct LameSurfaceInfo {
  double near_field_seconds = 0;     ///< the Lame and the Laplace near fields
  double single_layer_seconds = 0;   ///< V_h and Z (one family)
  double double_layer_seconds = 0;   ///< Y and K_L
  double hypersingular_seconds = 0;  ///< W_L
  double dense_cpu_seconds = 0;      ///< of V_h, Z, Y: the dense blocks' entries (summed over threads)
  double low_rank_cpu_seconds = 0;   ///< of V_h, Z, Y: the admissible blocks' ACA and projections
  std::size_t nbytes_v = 0, nbytes_k = 0, nbytes_w = 0;  ///< V_h; Y + K_L; Z + W_L
  std::size_t nbytes_near = 0;                           ///< the near fields (freed after the set-up)
  Index max_rank = 0;
};

class LameSurfaceOperators {
 public:
  /// options.min_distance is set to far_distance(surface); leaf_size counts vertices (the
  /// vector trees hold 3 leaf_size dofs per leaf). Throws std::invalid_argument for an invalid
  /// medium.
  LameSurfaceOperators(const Surface& surface, const Lame& m, const HMatrixOptions& options);

  const std::shared_ptr<const HMatrix>& single_layer() const { return V_; }
  /// W_h X and K_h X (transpose: K_h^T X), X (3 n, k) node-major; collective if distributed.
  Eigen::MatrixXd hypersingular(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  Eigen::MatrixXd double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose = false) const;
  /// The principal submatrix of W_h on the vector dofs {3 i + c : i in nodes, c = 0, 1, 2}
  /// (3 k, 3 k) node-major: Z's on those dofs plus 2 mu (W_L's on the nodes) kron I_3, read
  /// from the H-matrices (HMatrix::principal_submatrix; to their tolerance). Distributed:
  /// collective, each part summed over the ranks (exact: every entry comes from one block of
  /// one rank) before they are combined, so every rank gets the serial formula's bits from
  /// the same blocks. Throws std::invalid_argument for a repeated or out-of-range node.
  Eigen::MatrixXd hypersingular_block(const std::vector<Index>& nodes) const;
  const LameSurfaceInfo& info() const { return info_; }
  std::size_t nbytes() const { return info_.nbytes_v + info_.nbytes_k + info_.nbytes_w; }
  /// The parts (tests): Y, Z and the Laplace K_L, W_L.
  const HMatrix& y() const { return *Y_; }
  const HMatrix& z() const { return *Z_; }
  const HMatrix& laplace_double_layer() const { return *KL_; }
  const HMatrix& laplace_hypersingular() const { return *WL_; }

 private:
  double mu_;
  std::shared_ptr<const Communicator> comm_;
  std::shared_ptr<const HMatrix> V_, Z_, Y_, KL_, WL_;
  LameSurfaceInfo info_;
};

/// The parts of the Lame S_h on a closed surface (d = 3; flux P1 only: P0 throws
/// std::invalid_argument). options.hmatrix as for LameSurfaceOperators; preconditioner_tol is
/// not used (C0 reuses W_L). Throws std::invalid_argument for an invalid medium.
LameSteklovParts lame_surface_steklov_parts(const Surface& surface, const Lame& m, Space flux,
                                            const SteklovOptions& options);

/// The operator on raw arrays (validated by the Surface constructor), info().setup_seconds the
/// whole set-up.
std::unique_ptr<LameSteklovOperator> lame_surface_steklov_operator(VerticesRef vertices, TrianglesRef triangles,
                                                                   const Lame& m, Space flux,
                                                                   const SteklovOptions& options);

/// (A kron I_3) X for a scalar n x n H-matrix A and X (3 n, k) node-major (transpose: A^T).
Eigen::MatrixXd kron3_apply(const HMatrix& A, const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose = false);

}  // namespace bem
