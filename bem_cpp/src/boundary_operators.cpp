#include "bem/boundary_operators.hpp"

#include <stdexcept>

#include "bem/grouped_aca.hpp"

namespace bem {

namespace {

/// Sampled rows and columns confirming the stop of K_h's ACA (SampledAcaEntries: the double
/// layer's [[0, A], [B, 0]] blocks on polygons with straight sides, grouped_aca.hpp).
constexpr int kDoubleLayerSamples = 8;

}  // namespace

std::shared_ptr<const HMatrix> layer_hmatrix(const Polygon& polygon, Kernel kernel, Space rows,
                                             std::shared_ptr<const ClusterTree> row_tree,
                                             std::shared_ptr<const ClusterTree> col_tree, const HMatrixOptions& o) {
  const OperatorEntries entries(polygon, kernel, rows, kernel == Kernel::SingleLayer ? rows : Space::P1);
  HMatrixOptions options = o;
  options.symmetric = kernel == Kernel::SingleLayer;  // V_h = V_h^T: half the blocks
  if (kernel == Kernel::DoubleLayer)
    return std::make_shared<const HMatrix>(std::move(row_tree), std::move(col_tree),
                                           SampledAcaEntries(entries, kDoubleLayerSamples), options);
  return std::make_shared<const HMatrix>(std::move(row_tree), std::move(col_tree), entries, options);
}

BoundaryOperators::BoundaryOperators(const Eigen::Ref<const Points>& nodes, Space space, const HMatrixOptions& o)
    : polygon_(nodes) {
  auto tree1 = std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon_, Space::P1, o.leaf_size));
  auto tree = space == Space::P1
                  ? tree1
                  : std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon_, space, o.leaf_size));
  V_ = layer_hmatrix(polygon_, Kernel::SingleLayer, space, tree, tree, o);
  K_ = layer_hmatrix(polygon_, Kernel::DoubleLayer, space, tree, tree1, o);
}

Eigen::MatrixXd BoundaryOperators::single_layer(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  if (X.rows() != size()) throw std::invalid_argument("BoundaryOperators: X must have n rows");
  return V_->apply(X);
}

Eigen::MatrixXd BoundaryOperators::double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  if (X.rows() != size()) throw std::invalid_argument("BoundaryOperators: X must have n rows");
  return K_->apply(X);
}

}  // namespace bem
