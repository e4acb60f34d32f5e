#pragma once
// The potentials of the 3D representation formula (surface_potentials.hpp, docs/method.md
// section 11) as rectangular H-matrices from k target points to the boundary dofs:
//   u_e(z_i) = a + 1/2 (sum_j D(i, j) (v_j - a) - sum_j S(i, j) psi_j),
//   D(i, j) = int_Gamma 2 dG/dn_y(z_i, y) phi_j(y) ds_y   (P1 hat phi_j),
//   S(i, j) = int_Gamma 2 G(z_i, y) chi_j(y) ds_y         (P1 hat or P0 indicator chi_j),
// G = 1/(4 pi |z - y|). Rows: a cluster tree on the points; columns: the cluster tree of
// the space (surface_cluster_tree). Every entry is summed from the point-triangle integrals
// of the direct evaluation (point_integrals: the triangle split near the point), so the
// dense blocks are those of exterior_potential to round-off and the admissible ones ACA
// approximations of them to tol. The 2D counterpart is potential_operator.hpp.
#include <memory>

#include "bem/hmatrix.hpp"
#include "bem/potential_operator.hpp"
#include "bem/surface.hpp"
#include "bem/surface_operators.hpp"

namespace bem {

/// The entries D(i, j) or S(i, j) above on index sets. The surface and the points must
/// outlive the object. Thread-safe.
class SurfacePotentialEntries : public EntrySource {
 public:
  /// `companion` (cols P1): the other potential as the companion matrix 1 (HMatrix::family).
  SurfacePotentialEntries(const Surface& surface, const Vertices& points, PotentialKernel kernel, Space cols,
                          bool companion = false);
  std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const override;

 private:
  const Surface& surface_;
  const Vertices& points_;
  PotentialKernel kernel_;
  Space cols_;
  bool companion_;
};

/// D and S on the points, built once; evaluate() is two H-matrix products.
class SurfacePotentialOperator {
 public:
  /// Throws std::invalid_argument, with exterior_potential's message, naming the first
  /// point inside Omega or on Gamma: D 1 (minus the solid angle of Gamma over 2 pi: -2
  /// inside, 0 outside) from the H-matrix, and points within 1e-12 of the bounding-box
  /// diameter of a vertex or a centroid (as the direct evaluation).
  SurfacePotentialOperator(const Surface& surface, const Eigen::Ref<const Vertices>& points, Space flux,
                           HMatrixOptions options);
  /// u_e at the points (dirichlet: one value per vertex; flux_coefficients: one per dof).
  Vector evaluate(const Eigen::Ref<const Vector>& dirichlet, const Eigen::Ref<const Vector>& flux_coefficients,
                  double a) const;
  Index points() const { return points_.rows(); }
  std::size_t nbytes() const { return double_layer_->nbytes() + single_layer_->nbytes(); }
  const HMatrix& double_layer() const { return *double_layer_; }
  const HMatrix& single_layer() const { return *single_layer_; }

 private:
  Vertices points_;
  Index vertices_, flux_dofs_;
  std::shared_ptr<const HMatrix> double_layer_, single_layer_;
};

/// exterior_potential (surface_potentials.hpp) through SurfacePotentialOperator.
Vector exterior_potential_hmatrix(VerticesRef vertices, TrianglesRef triangles,
                                  const Eigen::Ref<const Vector>& dirichlet,
                                  const Eigen::Ref<const Vector>& flux_coefficients,
                                  const Eigen::Ref<const Vertices>& points, double a, Space flux,
                                  const HMatrixOptions& options);

}  // namespace bem
