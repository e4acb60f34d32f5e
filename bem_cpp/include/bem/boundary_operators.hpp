#pragma once
// The single- and double-layer Galerkin matrices V_h and K_h as H-matrices, applied and
// never formed (docs/method.md section 2; docs/design/hmatrix.md): residuals of the boundary
// integral equation on long boundaries, e.g. the a posteriori estimator's BIE term on the
// bisected boundary, in O(n log n) memory instead of two dense n x n matrices.
#include <memory>

#include "bem/geometry.hpp"
#include "bem/hmatrix.hpp"
#include "bem/operator_entries.hpp"

namespace bem {

/// The H-matrix of V_h (rows and columns in `rows`) or K_h (rows in `rows`, columns P1)
/// on `polygon`, on the given cluster trees; V_h is built symmetric (serial: half the
/// blocks; distributed: the rows of the rank, see hmatrix.hpp), K_h's ACA confirms its stop
/// on 8 sampled rows and columns (SampledAcaEntries, grouped_aca.hpp: the double-layer
/// kernel vanishes between panels on one line).
std::shared_ptr<const HMatrix> layer_hmatrix(const Polygon& polygon, Kernel kernel, Space rows,
                                             std::shared_ptr<const ClusterTree> row_tree,
                                             std::shared_ptr<const ClusterTree> col_tree,
                                             const HMatrixOptions& options);

class BoundaryOperators {
 public:
  /// V_h (trial and test functions in `space`) and K_h (tests in `space`, trial P1).
  BoundaryOperators(const Eigen::Ref<const Points>& nodes, Space space, const HMatrixOptions& options);

  Index size() const { return polygon_.size(); }
  /// V_h X for X (n, k).
  Eigen::MatrixXd single_layer(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// K_h X for X (n, k).
  Eigen::MatrixXd double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// Bytes held by the two H-matrices.
  std::size_t nbytes() const { return V_->nbytes() + K_->nbytes(); }

 private:
  Polygon polygon_;
  std::shared_ptr<const HMatrix> V_, K_;
};

}  // namespace bem
