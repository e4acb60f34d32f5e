#pragma once
// Entries of the 3D Lame operators (lame_surface.hpp) for their H-matrices (hmatrix.hpp), on
// the vertex cluster tree expanded to three dofs per vertex (node-major, dof 3 i + k).
//
// Split. With g = 2 G = 1 / (2 pi |r|) and R = 2 r r^T / (4 pi |r|^3) (r = x - y) the factor-2
// Kelvin matrix is 2 U = cu ((3 - 4 nu) g I + R), cu = 1 / (4 mu (1 - nu)), and with the
// "companion" kernel
//   A = (R + (1 - 2 nu) g I) / (2 (1 - nu)) = 2 mu (2 U) - g I
// the three operators of lame_surface.hpp regroup (the header's formulas, expanded) as
//   V_h = (V_L kron I + V_A) / (2 mu),     V_A[(i,k),(j,l)] = int int psi_i A_kl psi_j,
//   K_h = K_L kron I + Y,                  Y = (A[i][3] [c_j]_x)_kl  summed over the pairs,
//   W_h = 2 mu W_L kron I + Z,             Z = -mu g[3][3] c_i c_j^T + 2 mu [c_i]_x A[3][3] [c_j]_x,
// where V_L, K_L, W_L are the Laplace P1 matrices (surface_operators.hpp: W_L = <V curl, curl>),
// c_j the surface curl of the hat j on the trial triangle, [c]_x the cross matrix and [3] the
// constant on a triangle (the moments' index, PairMoments). So K and W need the Laplace double
// layer and W_L as scalar matrices (applied to the three components) and the vector parts Y and
// Z, which, like V_h, are integrals of the two smooth kernels g and A only - no double-layer
// kernel (whose zeros between coplanar points need the Laplace code's split by plane).
//
// Near pairs (PairIntegrator::far false): the exact entries of the dense assembly, from the
// pair moments (PairIntegrator::moments), once per unordered pair, as sparse matrices
// (LameSurfaceNearField). Far pairs: the far rule's point kernels, as the Laplace blocks
// (surface_entries.hpp): a dense block sums the kernels g and A at the point pairs of its far
// triangle pairs against the hats (V_A, and A's rows and columns against the constant for Y, Z)
// in one pass over the point pairs; an admissible block (all pairs far) is
//   V_A = Q^T A Q,   Y = Q^T A P Cx,   Z = -mu D^T (P^T g P) D - 2 mu Cx^T (P^T A P) Cx
// with A and g the point kernels between the far-rule points (weights included), Q the hats'
// values at the points, P the sums over a triangle's points, D x = sum_j c_j . x_j and
// Cx x = sum_j c_j x x_j per triangle (the Gunter derivative, constant on a triangle): one
// adaptive cross approximation of A (3 x 3 blocks at point pairs, grouped_point_aca: every
// pivot row brings its point's other two rows) and one of g (aca.hpp) per block serve V_h, Y
// and Z, and Y's mirrored block Y(s, t) = Q_s^T A P_t Cx_t (A symmetric). V_h's factors are
// [Q^T g Q kron I, Q^T A Q] / (2 mu) side by side, Z's [D^T g, Cx^T A] (recompressed by
// HMatrix::fill). An admissible block whose rank would not pay (3 times g's point rank at
// least m k / (m + k): held dense anyway) is summed by the dense blocks' far pass instead,
// which is cheaper there than the cross approximation (most blocks at tol 1e-10 and a few
// hundred vertices), and handed over as D = D I.
//
// One pass over the blocks of the symmetric block tree (HMatrix::family: V_h and Z) computes
// Y's blocks (t, s) and (s, t) as well and leaves them, recompressed, in a
// LameSurfaceBlockCache, from which the non-symmetric H-matrix of Y then takes them (a block
// not found there - under MPI, where Y's rows may be partitioned otherwise - is computed
// again, to the same factors).
//
// Why A and g rather than the Kelvin matrix itself: K_h and W_h hold K_L kron I and W_L kron I
// (the part of each that is a scalar operator on every component), and kept apart these cost
// one scalar H-matrix each instead of raising the vector blocks' ranks (K_L kron I alone has
// three times K_L's rank); with A the vector parts Y and Z need no such term, and V_h takes
// V_L kron I from g's factors. The vector blocks are about 9 times the Laplace ones in bytes
// anyway (3 times the rows and columns, 3 times the rank: truncated SVDs of the dense blocks
// of V_h, K_h, W_h on the sphere of 2,562 vertices, tol 1e-6, leaves of 32, held 8.9, 9.8 and
// 8.6 times the entries of V_L, K_L, W_L's), and so are the dense blocks (3 x 3 per vertex
// pair).
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <vector>

#include "bem/cluster_tree.hpp"
#include "bem/hmatrix.hpp"
#include "bem/kelvin.hpp"
#include "bem/surface_near_field.hpp"
#include "bem/surface_operators.hpp"

namespace bem {

/// The near parts (sums over the near triangle pairs) of V_h, Y and Z (above), 3 n x 3 n,
/// node-major; every unordered near pair integrated once (PairIntegrator::moments), as the
/// dense assembly of lame_surface.hpp.
class LameSurfaceNearField {
 public:
  /// triangles: only the pairs of these (near_pairs; rank_triangles), empty: all.
  LameSurfaceNearField(const Surface& surface, const Lame& m, const std::vector<char>& triangles = {});
  const RowSparse& single_layer() const { return v_; }
  const RowSparse& double_layer() const { return y_; }   ///< of Y = K_h - K_L kron I
  const RowSparse& hypersingular() const { return z_; }  ///< of Z = W_h - 2 mu W_L kron I
  std::size_t nbytes() const;

 private:
  RowSparse v_, y_, z_;
};

/// The blocks of Y that the pass over the symmetric block tree computed, by their index
/// ranges (thread-safe; each taken once).
class LameSurfaceBlockCache {
 public:
  using Key = std::tuple<const Index*, Index, const Index*, Index>;
  void put_dense(const Key& key, Eigen::MatrixXd block);
  void put_low_rank(const Key& key, LowRank block);
  bool take_dense(const Key& key, Eigen::MatrixXd& block);
  bool take_low_rank(const Key& key, LowRank& block);
  void clear();

 private:
  std::mutex mutex_;
  std::map<Key, Eigen::MatrixXd> dense_;
  std::map<Key, LowRank> low_rank_;
};

/// CPU seconds (summed over the threads) of the entries of an H-matrix's set-up.
struct LameSurfaceTimes {
  double dense = 0;     ///< the dense blocks (near field added, far pairs summed)
  double low_rank = 0;  ///< the admissible blocks (ACA and projections, not the recompression)
};

class LameSurfaceEntries : public EntrySource {
 public:
  /// SingleLayer: V_h, with Z as the companion matrix 1 (HMatrix::family, symmetric); Y's
  /// blocks go to `cache` if given. DoubleLayer: Y (non-symmetric), its blocks from `cache`
  /// where found. Indices: the vector dofs of the tree lame_surface_cluster_tree (blocks of
  /// whole vertices). Throws std::invalid_argument for an invalid medium.
  enum class Kind { SingleLayer, DoubleLayer };
  LameSurfaceEntries(const Surface& surface, const Lame& m, Kind kind, std::shared_ptr<const LameSurfaceNearField> near,
                     std::shared_ptr<LameSurfaceBlockCache> cache = nullptr);
  std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const override;
  LameSurfaceTimes times() const;
  /// ACA tolerance on the point kernels over the blocks' tol (the projection sums many
  /// point rows into a dof row, as for the Laplace blocks: 0.3).
  static constexpr double kPointTolerance = 0.3;

  struct Data;  ///< what the blocks share

 private:
  std::shared_ptr<Data> data_;
};

/// The tree of the vector P1 dofs: surface_cluster_tree(surface, P1, leaf_size) expanded to
/// each vertex's three dofs (ClusterTree::expanded).
ClusterTree lame_surface_cluster_tree(const Surface& surface, Index leaf_size);

/// Adaptive cross approximation of a point kernel of 3 x 3 blocks (rows 3 p + k, columns
/// 3 q + l for points_r row and points_c column points; `row_group(p, out)`: the three rows of
/// point p, out[(3 k + l) points_c + q]; `column_group(q, out)`: the three columns of point q,
/// out[(3 l + k) points_r + p]): as aca() with partial pivoting, but each pivot row brings the
/// other rows of its point along (each with its own pivot column, the kernel evaluated once per
/// point), and the stop asks every cross of the group for |u| |v| <= tol |U V^T|_F, confirmed on
/// a sampled row and column group. (ACA row by row can stay in one component: between coplanar
/// points the normal component decouples.) The factors' rows are 3 p + k and 3 q + l.
LowRank grouped_point_aca(Index points_r, Index points_c, const std::function<void(Index, double*)>& row_group,
                          const std::function<void(Index, double*)>& column_group, double tol, Index max_rank);

}  // namespace bem
