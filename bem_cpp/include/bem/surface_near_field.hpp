#pragma once
// The near part of the surface operators (surface_operators.hpp): the sums over the near
// triangle pairs (PairIntegrator::far false: shared vertices, or separation q below
// kFarSeparation) of V_h (P0 and P1), K_h and W_h (P1 x P1), as sparse matrices. Each
// unordered near pair is integrated once for all three, so that the H-matrices of V_h
// (P0, P1) and K_h (surface_entries.hpp) evaluate only far pairs themselves.
#include <Eigen/Sparse>
#include <utility>
#include <vector>

#include "bem/cluster_tree.hpp"
#include "bem/hmatrix.hpp"
#include "bem/surface_operators.hpp"

namespace bem {

using RowSparse = Eigen::SparseMatrix<double, Eigen::RowMajor, Index>;

/// For each triangle tau, the triangles sigma >= tau of its near pairs (PairIntegrator::far
/// false), sorted: found in a grid of cells as wide as the largest near distance
/// (far_distance). The pairs of SurfaceNearField (and of the Lame near field,
/// lame_surface_entries.hpp). `triangles` (a mask over the triangles, empty: all): only
/// the pairs with a triangle in the mask.
std::vector<std::vector<Index>> near_pairs(const Surface& s, const std::vector<char>& triangles = {});

/// The triangles whose near pairs one rank of a distributed operator needs: those with a
/// vertex in the rank's rows of one of the H-matrices `matrices` (each its cluster tree, of
/// the vertices or of their d node-major dofs, and the ranks' row bounds, its
/// distributed_row_bounds, which its constructor then takes as they are) built with
/// `options`. A near field of these triangles' pairs alone is exact in the rows and
/// columns of every such vertex, the only ones the rank's blocks read, and costs about
/// 1 / P of the whole. Empty (every triangle) when `options` has no communicator of more
/// than one rank.
std::vector<char> rank_triangles(const Surface& s, const HMatrixOptions& options,
                                 const std::vector<std::pair<const ClusterTree*, std::vector<Index>>>& matrices);

/// The ranks' row bounds of a distributed HMatrix on `tree` (rows and columns) with
/// `options`, symmetric or not (distributed_row_bounds); empty without a communicator of
/// more than one rank.
std::vector<Index> surface_row_bounds(const ClusterTree& tree, const HMatrixOptions& options, bool symmetric);

class SurfaceNearField {
 public:
  /// with_p0: also the P0 single layer (the P1 operators of S_h do not need it);
  /// triangles: only the pairs of these (near_pairs; rank_triangles), empty: all.
  explicit SurfaceNearField(const Surface& surface, bool with_p0 = true, const std::vector<char>& triangles = {});
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
