#pragma once
// The near part of the surface operators (surface_operators.hpp): the sums over the near
// triangle pairs (PairIntegrator::far false: shared vertices, or separation q below
// kFarSeparation) of V_h (P0 and P1), K_h and W_h (P1 x P1), as sparse matrices. Each
// unordered near pair is integrated once for all three, so that the H-matrices of V_h
// (P0, P1) and K_h (surface_entries.hpp) evaluate only far pairs themselves.
#include <Eigen/Sparse>
#include <vector>

#include "bem/surface_operators.hpp"

namespace bem {

using RowSparse = Eigen::SparseMatrix<double, Eigen::RowMajor, Index>;

/// For each triangle tau, the triangles sigma >= tau of its near pairs (PairIntegrator::far
/// false), sorted: found in a grid of cells as wide as the largest near distance
/// (far_distance). The pairs of SurfaceNearField (and of the Lame near field,
/// lame_surface_entries.hpp).
std::vector<std::vector<Index>> near_pairs(const Surface& s);

class SurfaceNearField {
 public:
  /// with_p0: also the P0 single layer (the P1 operators of S_h do not need it).
  explicit SurfaceNearField(const Surface& surface, bool with_p0 = true);
  /// The near part of V_h in `space` (symmetric; P0 empty unless with_p0).
  const RowSparse& single_layer(Space space) const { return space == Space::P0 ? v0_ : v1_; }
  /// The near part of K_h (rows and columns P1), and its transpose (for columns).
  const RowSparse& double_layer() const { return k_; }
  const RowSparse& double_layer_transpose() const { return kt_; }
  /// The near part of W_h (P1, symmetric): sum_c C_c^T (near part of V0_h) C_c.
  const RowSparse& hypersingular() const { return w_; }

 private:
  RowSparse v0_, v1_, k_, kt_, w_;
};

}  // namespace bem
