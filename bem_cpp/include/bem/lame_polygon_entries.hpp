#pragma once
// Entries of the plane-strain Lame matrices of lame_polygon.hpp on arbitrary sets of
// vector dofs, for their H-matrices (hmatrix.hpp): a row, a column or a dense block at a
// time, from the same panel-pair moments as the dense assembly.
//
// Every Lame matrix is built from "Kelvin-like" matrices: with the log moments L and the
// direction moments D (g = r r^T/|r|^2, D_yy = h_i h_j/4 - D_xx) of lame_polygon.hpp, the
// 2 x 2 block of the dof pair (i, j) (sums of panel-shape terms, as operator_entries.hpp) is
//   A_ij = (a L_ij I + b D_ij) R^rot,  R = [[0, -1], [1, 0]],  rot = 0 or 1,
// and, with c = 1/(4 pi mu (1 - nu)), D_h the arc-length derivative of the hats (P1 -> P0,
// (D_h x)_p = (x_(p+1) - x_p)/h_p) kron I_2 and K_L the Laplace double-layer matrix
// (operator_entries.hpp):
//   V_h = A(flux, flux)      a = -(3 - 4 nu) c,         b = c,            rot = 0
//   W_h = D_h^T X0 D_h,      X0 = A(P0, P0): a = -4 mu^2 c, b = 4 mu^2 c, rot = 0
//   K_h = K_L kron I_2 + Y D_h,  Y = A(flux, P0): a = -2 mu (1 - 2 nu) c, b = 2 mu c, rot = 1
// (lame_polygon.hpp's V, W and K blocks regrouped: W's blocks sigma_a sigma_b/(h_i h_j) are
// D_h^T ... D_h, K's (sigma_b/h_j) Z are Y D_h).
//
// Vector dofs are node-major (dof 2 u + k: component k of node or panel u); the entries of
// a set of dofs come from the moments of the panels of their nodes: near pairs exactly as
// the dense assembly (pair_blocks for L, direction_blocks for D), far pairs by the same
// tensor Gauss rules (far_field_points points per panel) in vector batches over the panels;
// the rows and columns of ACA (the admissible blocks, approximated to tol anyway) by the
// rules for the quadrature tolerance max(1e-16, 1e-3 tol) instead of 1e-16 (fewer points).
// An admissible block is approximated by grouped_aca (grouped_aca.hpp), the two components of
// a node a group; a row or column computes both components' (one set of moments) and keeps
// the other for later.
#include <array>
#include <atomic>
#include <memory>
#include <vector>

#include "bem/cluster_tree.hpp"
#include "bem/hmatrix.hpp"
#include "bem/kelvin.hpp"
#include "bem/log_integrals.hpp"
#include "bem/operator_entries.hpp"

namespace bem {

enum class LameKernel {
  SingleLayer,    ///< V_h, rows and columns in the same space
  Hypersingular,  ///< X0 (P0 x P0) of W_h = D_h^T X0 D_h
  DoubleLayer,    ///< Y (rows: the flux space, columns P0) of K_h = K_L kron I_2 + Y D_h
};

/// Coefficients of a Kelvin-like matrix (above).
struct KelvinLike {
  double a, b;
  bool rotate;
};
KelvinLike kelvin_like(const Lame& m, LameKernel kernel);

class LamePolygonEntries : public EntrySource {
 public:
  /// The vector matrix of `kernel` (2n x 2n): rows in `rows`, columns in `rows`
  /// (SingleLayer) or P0 (Hypersingular: rows must be P0; DoubleLayer). The polygon must
  /// outlive the object. Throws std::invalid_argument for an invalid medium or spaces.
  LamePolygonEntries(const Polygon& polygon, const Lame& m, LameKernel kernel, Space rows);

  Index size() const { return 2 * polygon_.size(); }
  Space row_space() const { return rows_; }
  Space col_space() const { return cols_; }
  /// out[r + c ld] = A(I[r], J[c]) (vector dofs) for r < m, c < k. Thread-safe.
  void block(const Index* I, Index m, const Index* J, Index k, double* out, Index ld) const;
  /// EntrySource: a block whose rows and columns are computed node by node (both
  /// components at once, kept for the other component's row or column of ACA).
  std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const override;

  /// The 2 x 2 blocks of all pairs of the nodes (panels) of `rows` and `cols`:
  /// out[((r * cols.size() + c) * 2 + k) * 2 + l] = A(2 u_r + k, 2 u_c + l). Far pairs by
  /// the tensor Gauss rule with the points of far_field_points for the thresholds y
  /// (log_integrals.hpp; nullptr: gauss_thresholds(), the dense assembly's).
  void node_blocks(const DofSet& rows, const DofSet& cols, double* out,
                   const std::array<double, kMaxGaussPoints + 1>* y = nullptr) const;
  DofSet nodes(Space space, const Index* nodes, Index m) const { return scalar_.dofs(space, nodes, m); }
  void nodes_into(Space space, const Index* nodes, Index m, DofSet& d) const { scalar_.dofs_into(space, nodes, m, d); }

  /// Set-up statistics: CPU seconds summed over the threads in the dense blocks (near
  /// field) and in the rows and columns of the low-rank blocks (far field).
  double dense_seconds() const { return dense_ns_.load() * 1e-9; }
  double low_rank_seconds() const { return low_rank_ns_.load() * 1e-9; }
  void count(bool dense, long nanoseconds) const { (dense ? dense_ns_ : low_rank_ns_) += nanoseconds; }

 private:
  const Polygon& polygon_;
  OperatorEntries scalar_;  ///< the dof sets (panels and shapes) of nodes and panels
  KelvinLike coef_;
  Space rows_, cols_;
  mutable std::atomic<long> dense_ns_{0}, low_rank_ns_{0};
};

/// CPU seconds (summed over the threads) of the entries of an H-matrix's set-up.
struct LameEntryTimes {
  double dense = 0;     ///< the dense blocks (near field)
  double low_rank = 0;  ///< the rows and columns of ACA (far field)
};

/// The H-matrix of `kernel` on the vector trees `row_tree`, `col_tree` (ClusterTree::
/// expanded(2) of the trees of the node or panel spaces); V_h and X0 are built symmetric.
/// times, if given, receives where the entries' time went.
std::shared_ptr<const HMatrix> lame_hmatrix(const Polygon& polygon, const Lame& m, LameKernel kernel, Space rows,
                                            std::shared_ptr<const ClusterTree> row_tree,
                                            std::shared_ptr<const ClusterTree> col_tree, const HMatrixOptions& options,
                                            LameEntryTimes* times = nullptr);

}  // namespace bem
