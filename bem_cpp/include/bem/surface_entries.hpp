#pragma once
// Entries of the surface operators (surface_operators.hpp) for the H-matrix
// (hmatrix.hpp): rows, columns or whole blocks of V_h (P0 or P1), K_h (rows P0 or P1,
// columns P1) and W_h (P1), each entry summed over the triangle pairs of the two basis supports, and
// the cluster tree of a surface space (the 2D tree of cluster_tree.hpp on 3D points).
#include <memory>
#include <vector>

#include "bem/cluster_tree.hpp"
#include "bem/hmatrix.hpp"
#include "bem/surface_near_field.hpp"
#include "bem/surface_operators.hpp"

namespace bem {

/// Hypersingular: W_h (P1 x P1) by Nedelec's identity, sum_c C_c^T V0_h C_c, from the
/// single-layer kernel and the surface curls of the hats.
enum class SurfaceKernel { SingleLayer, DoubleLayer, Hypersingular };

class SurfaceEntries : public EntrySource {
 public:
  /// rows/cols: the spaces of the test and trial functions (DoubleLayer: cols P1).
  /// `near`: the near pairs' part of the entries (surface_near_field.hpp), so that blocks
  /// integrate only their far pairs (rows and cols P0 x P0 or P1 x P1); null: every pair.
  /// `with_hypersingular` (the P1 single layer): W_h as the companion matrix 1 of each block
  /// (HMatrix::family), from the same point kernel and ACA.
  SurfaceEntries(const Surface& surface, SurfaceKernel kernel, Space rows, Space cols,
                 std::shared_ptr<const SurfaceNearField> near = nullptr, bool with_hypersingular = false);
  std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const override;

 private:
  const Surface& surface_;
  PairIntegrator integrator_;
  SurfaceKernel kernel_;
  Space rows_, cols_;
  std::shared_ptr<const SurfaceNearField> near_;
  bool with_hypersingular_;
};

/// Dof points (P1: vertices, P0: centroids) and supports (the triangles the basis
/// function lives on) of `space`, bisected down to `leaf_size`.
ClusterTree surface_cluster_tree(const Surface& surface, Space space, Index leaf_size);

}  // namespace bem
