#pragma once
// The potentials of the representation formula (potentials.hpp, docs/method.md section 2) as
// rectangular H-matrices from m target points to the boundary dofs
// (docs/design/hmatrix.md, "Potentials"):
//   u_e(z_i) = a + sum_j D(i, j) (v_j - a) + sum_j S(i, j) psi_j,
//   D(i, j) = 1/(2 pi) int_Gamma (z_i - y).n_y / |z_i - y|^2 phi_j(y) ds_y   (P1 hat phi_j),
//   S(i, j) = 1/(2 pi) int_Gamma log|z_i - y| chi_j(y) ds_y   (P1 hat or P0 indicator chi_j).
// Rows: a cluster tree on the points (geometric bisection, the points' own boxes); columns:
// the cluster tree of the space (ClusterTree::for_space). Every entry is the point-panel
// integral of the direct evaluation (point_panel_moments: closed form near, the sized Gauss
// rule far), so the dense (inadmissible) blocks are those of exterior_potential to
// round-off and the admissible ones are ACA approximations of them to tol.
#include <memory>
#include <vector>

#include "bem/cluster_tree.hpp"
#include "bem/geometry.hpp"
#include "bem/hmatrix.hpp"
#include "bem/operators.hpp"

namespace bem {

enum class PotentialKernel {
  DoubleLayer,  ///< D: columns the P1 hats of the Dirichlet trace
  SingleLayer,  ///< S: columns the flux space (P1 or P0)
};

/// The entries D(i, j) or S(i, j) above on index sets. The polygon and the points must
/// outlive the object. Thread-safe.
class PotentialEntries : public EntrySource {
 public:
  PotentialEntries(const Polygon& polygon, const Points& points, PotentialKernel kernel, Space cols);
  std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const override;

 private:
  const Polygon& polygon_;
  const Points& points_;
  PotentialKernel kernel_;
  Space cols_;
};

/// D and S on the points, built once; evaluate() is two H-matrix products.
class PotentialOperator {
 public:
  /// Throws std::invalid_argument as exterior_potential does for points inside Omega or on
  /// Gamma. options.split_to_leaves is set (the point tree is usually the deeper one).
  PotentialOperator(const Polygon& polygon, const Eigen::Ref<const Points>& points, Space flux, HMatrixOptions options);
  /// u_e at the points (dirichlet, flux_coefficients of length n).
  Vector evaluate(const Eigen::Ref<const Vector>& dirichlet, const Eigen::Ref<const Vector>& flux_coefficients,
                  double a) const;
  Index points() const { return points_.rows(); }
  Index size() const { return n_; }
  std::size_t nbytes() const { return double_layer_->nbytes() + single_layer_->nbytes(); }
  const HMatrix& double_layer() const { return *double_layer_; }
  const HMatrix& single_layer() const { return *single_layer_; }

 private:
  Points points_;
  Index n_;
  std::unique_ptr<HMatrix> double_layer_, single_layer_;
};

/// exterior_potential (potentials.hpp) through PotentialOperator.
Vector exterior_potential_hmatrix(const Eigen::Ref<const Points>& nodes, const Eigen::Ref<const Vector>& dirichlet,
                                  const Eigen::Ref<const Vector>& flux_coefficients,
                                  const Eigen::Ref<const Points>& points, double a, Space flux,
                                  const HMatrixOptions& options);

}  // namespace bem
