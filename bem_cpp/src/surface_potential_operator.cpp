#include "bem/surface_potential_operator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>

#include "bem/far_points.hpp"
#include "bem/surface_entries.hpp"
#include "bem/surface_potentials.hpp"

namespace bem {

namespace {

/// |D 1| above this: inside Omega or on Gamma. D 1 is -2 inside, 0 outside and minus the
/// interior solid angle over 2 pi on Gamma; its H-matrix value is off by about tol and the
/// point-triangle quadrature by far less, so any threshold well between the two serves.
/// On Gamma only a vertex of interior solid angle below 2 pi 1e-3 passes it, and the
/// vertex test catches that.
constexpr double kInsideDoubleLayer = 1e-3;

/// The entries of I x J from the parts of J (far_points.hpp: each triangle of J's supports
/// once, with the dofs it carries); the integrals of a row (one point, every part) go to
/// per-block scratch (a block is built by one thread). With `companion`, the other
/// potential is the companion matrix 1 (HMatrix::family: a dense block's point integrals
/// give both).
class SurfacePotentialBlock : public EntryBlock {
 public:
  SurfacePotentialBlock(const Surface& s, const Vertices& points, PotentialKernel kernel, bool companion, Space cols,
                        const Index* I, Index m, const Index* J, Index k)
      : surface_(s),
        points_(points),
        double_layer_(kernel == PotentialKernel::DoubleLayer),
        companion_(companion),
        cols_(cols),
        I_(I),
        J_(J),
        m_(m),
        k_(k),
        parts_(parts(s, cols, J, k)),
        integrals_(parts_.size()) {}

  void row(Index i, double* out) const override { row(i, double_layer_, out); }

  void column(Index j, double* out) const override {
    const std::vector<Part> own = parts(surface_, cols_, J_ + j, 1);
    for (Index r = 0; r < m_; ++r) {
      const Vec3 z = point(r);
      out[r] = 0.0;
      for (const Part& p : own)
        out[r] += value(point_integrals(surface_.triangle(p.triangle), z), p.basis[0], double_layer_);
    }
  }

  void all(double* out) const override {
    if (companion_) other_.resize(m_, k_);
    Eigen::Map<Eigen::MatrixXd> result(out, m_, k_);
    Eigen::RowVectorXd r(k_);
    for (Index i = 0; i < m_; ++i) {
      row(i, double_layer_, r.data());
      result.row(i) = r;
      if (companion_) other_.row(i) = sum_parts(!double_layer_);
    }
  }

  void companion_all(int /*which*/, double* out) const override {
    if (other_.rows() != m_ || other_.cols() != k_) {  // all() did not run (ACA on the first's entries)
      other_.resize(m_, k_);
      for (Index i = 0; i < m_; ++i) {
        row(i, !double_layer_, out);
        other_.row(i) = Eigen::Map<const Eigen::RowVectorXd>(out, k_);
      }
    }
    Eigen::Map<Eigen::MatrixXd>(out, m_, k_) = other_;
  }

  /// An admissible block (HMatrixOptions::min_distance of the operator: every point of I is
  /// kPointSplitDiameters of their diameters from the triangles of J, so no entry splits a
  /// triangle, surface_potentials.cpp): ACA of the kernel between the points and the points
  /// of the rule of the closest pair (far_points.hpp), projected onto the dofs. (Unlike the
  /// Galerkin double layer between two faces of one plane, surface_entries.cpp, ACA of the
  /// double layer's kernel needs no split by plane here: points in the plane of a face zero
  /// only their own rows' part, measured in docs/design/bem3d.md.)
  bool low_rank(double tol, LowRank& out) const override { return far_low_rank(double_layer_, tol, out); }

  bool companion_low_rank(int /*which*/, double tol, LowRank& out) const override {
    return far_low_rank(!double_layer_, tol, out);
  }

 private:
  /// The row of point i in the single or double layer.
  void row(Index i, bool double_layer, double* out) const {
    const Vec3 z = point(i);
    for (std::size_t p = 0; p < parts_.size(); ++p)
      integrals_[p] = point_integrals(surface_.triangle(parts_[p].triangle), z);
    Eigen::Map<Eigen::RowVectorXd>(out, k_) = sum_parts(double_layer);
  }

  /// The row of the point of integrals_: each part's integrals added to its dofs.
  Eigen::RowVectorXd sum_parts(bool double_layer) const {
    Eigen::RowVectorXd out = Eigen::RowVectorXd::Zero(k_);
    for (std::size_t p = 0; p < parts_.size(); ++p)
      for (int a = 0; a < parts_[p].count; ++a)
        out(parts_[p].position[a]) += value(integrals_[p], parts_[p].basis[a], double_layer);
    return out;
  }

  bool far_low_rank(bool double_layer, double tol, LowRank& out) const {
    if (!far_points()) return false;  // not far enough: ACA on the entries
    const PointKernel kernel{*rows_, *cols_points_,
                             double_layer ? PointKernelKind::DoubleLayer : PointKernelKind::SingleLayer};
    const Slice row = [&kernel](Index r, double* o) { kernel.row(r, o); };
    const Slice column = [&kernel](Index q, double* o) { kernel.column(q, o); };
    const Index n = cols_points_->size();
    const LowRank A = aca(m_, n, row, column, 0.3 * tol, std::min(m_, n));
    out.U = A.U;
    out.V.setZero(k_, A.rank());
    add_values_transpose_product(parts_, *rule_, A.V, out.V);
    return true;
  }

  /// The points of I and the rule of the block's closest pair on J's triangles, made on the
  /// first call (false: a pair too close for a rule without splitting).
  bool far_points() const {
    if (cols_points_) return true;
    if (far_checked_) return false;
    far_checked_ = true;
    Box points, supports;
    double radius = 0.0, diameter = 0.0;
    for (Index r = 0; r < m_; ++r) points.add(point(r));
    for (const Part& p : parts_) {
      const Triangle& T = surface_.triangle(p.triangle);
      for (const Vec3& v : T.p) supports.add(v);
      radius = std::max(radius, T.radius);
      diameter = std::max({diameter, norm(T.p[1] - T.p[0]), norm(T.p[2] - T.p[1]), norm(T.p[0] - T.p[2])});
    }
    // the direct evaluation's rule for the closest pair, or a finer one
    const TriangleRule* rule = point_rule((points.distance(supports) - radius) / diameter);
    if (rule == nullptr) return false;
    rows_ = std::make_unique<FarPoints>(points_, I_, m_);
    cols_points_ = std::make_unique<FarPoints>(surface_, parts_, k_, false, *rule);
    rule_ = rule;
    return true;
  }

  Vec3 point(Index r) const {
    const Index i = I_[r];
    return {points_(i, 0), points_(i, 1), points_(i, 2)};
  }
  static double value(const PointIntegrals& q, int b, bool double_layer) { return double_layer ? q.K[b] : q.V[b]; }

  const Surface& surface_;
  const Vertices& points_;
  bool double_layer_, companion_;
  Space cols_;
  const Index *I_, *J_;
  Index m_, k_;
  std::vector<Part> parts_;
  mutable std::vector<PointIntegrals> integrals_;
  mutable Eigen::MatrixXd other_;  ///< the companion's dense block (all())
  mutable bool far_checked_ = false;
  mutable std::unique_ptr<FarPoints> rows_, cols_points_;  ///< the points of I, the rule's on J
  mutable const TriangleRule* rule_ = nullptr;             ///< cols_points_'s rule
};

/// The first point within `on` of a vertex or a centroid of the surface (-1: none), through
/// a grid of cells of side `on` over the surface's bounding box.
Index first_point_at_a_vertex(const Surface& s, const Vertices& points, double on) {
  Box box;
  for (const Triangle& T : s.triangles())
    for (const Vec3& p : T.p) box.add(p);
  using Cell = std::array<std::int64_t, 3>;
  auto cell = [&](Vec3 p) {
    return Cell{static_cast<std::int64_t>(std::floor((p.x - box.x0) / on)),
                static_cast<std::int64_t>(std::floor((p.y - box.y0) / on)),
                static_cast<std::int64_t>(std::floor((p.z - box.z0) / on))};
  };
  std::map<Cell, std::vector<Vec3>> grid;
  for (Index i = 0; i < s.vertices(); ++i) grid[cell(s.vertex(i))].push_back(s.vertex(i));
  for (const Triangle& T : s.triangles()) grid[cell(T.c)].push_back(T.c);
  for (Index k = 0; k < points.rows(); ++k) {
    const Vec3 z{points(k, 0), points(k, 1), points(k, 2)};
    if (z.x < box.x0 - on || z.x > box.x1 + on || z.y < box.y0 - on || z.y > box.y1 + on || z.z < box.z0 - on ||
        z.z > box.z1 + on)
      continue;
    const Cell c = cell(z);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto found = grid.find(Cell{c[0] + dx, c[1] + dy, c[2] + dz});
          if (found == grid.end()) continue;
          for (const Vec3& p : found->second)
            if (norm(z - p) <= on) return k;
        }
  }
  return -1;
}

}  // namespace

SurfacePotentialEntries::SurfacePotentialEntries(const Surface& surface, const Vertices& points, PotentialKernel kernel,
                                                 Space cols, bool companion)
    : surface_(surface), points_(points), kernel_(kernel), cols_(cols), companion_(companion) {
  if ((kernel == PotentialKernel::DoubleLayer || companion) && cols != Space::P1)
    throw std::invalid_argument("SurfacePotentialEntries: the double-layer potential acts on the P1 trace");
}

std::unique_ptr<EntryBlock> SurfacePotentialEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<SurfacePotentialBlock>(surface_, points_, kernel_, companion_, cols_, I, m, J, k);
}

SurfacePotentialOperator::SurfacePotentialOperator(const Surface& surface, const Eigen::Ref<const Vertices>& points,
                                                   Space flux, HMatrixOptions options)
    : points_(points), vertices_(surface.vertices()), flux_dofs_(dofs(surface, flux)) {
  if (points_.rows() < 1) throw std::invalid_argument("SurfacePotentialOperator: need at least one point");
  if (!points_.allFinite()) throw std::invalid_argument("points: non-finite coordinates");
  const Index at_vertex = first_point_at_a_vertex(surface, points_, 1e-12 * surface.bounding_diameter());
  options.symmetric = false;
  options.comm = nullptr;
  options.split_to_leaves = true;
  // admissible blocks: no triangle split (SurfacePotentialBlock::low_rank)
  options.min_distance = (kPointSplitDiameters + 1.0) * surface.mesh_size();
  auto rows = std::make_shared<const ClusterTree>(point_cluster_tree(points_, options.leaf_size));
  auto p1 = std::make_shared<const ClusterTree>(surface_cluster_tree(surface, Space::P1, options.leaf_size));
  if (flux == Space::P1) {  // one pass: a dense block's point integrals give both
    const auto both = HMatrix::family(
        rows, p1, SurfacePotentialEntries(surface, points_, PotentialKernel::DoubleLayer, Space::P1, true), 2, options);
    double_layer_ = both[0];
    single_layer_ = both[1];
  } else {
    double_layer_ = std::make_shared<const HMatrix>(
        rows, p1, SurfacePotentialEntries(surface, points_, PotentialKernel::DoubleLayer, Space::P1), options);
    single_layer_ = std::make_shared<const HMatrix>(
        rows, std::make_shared<const ClusterTree>(surface_cluster_tree(surface, Space::P0, options.leaf_size)),
        SurfacePotentialEntries(surface, points_, PotentialKernel::SingleLayer, Space::P0), options);
  }
  const Vector solid = double_layer_->apply(Vector::Ones(vertices_)).col(0);
  Index inside = at_vertex;
  for (Index k = 0; k < solid.size(); ++k)
    if (!(std::abs(solid(k)) <= kInsideDoubleLayer)) {  // NaN too: a point at a quadrature node of Gamma
      inside = inside < 0 ? k : std::min(inside, k);
      break;
    }
  if (inside >= 0) refuse_interior_point(points_, inside);
}

Vector SurfacePotentialOperator::evaluate(const Eigen::Ref<const Vector>& dirichlet,
                                          const Eigen::Ref<const Vector>& flux_coefficients, double a) const {
  if (dirichlet.size() != vertices_ || flux_coefficients.size() != flux_dofs_)
    throw std::invalid_argument("exterior_potential: one Dirichlet value per vertex and one flux coefficient per dof");
  const Vector w = dirichlet.array() - a;
  Vector u = 0.5 * (double_layer_->apply(w).col(0) - single_layer_->apply(flux_coefficients).col(0));
  u.array() += a;
  return u;
}

Vector exterior_potential_hmatrix(VerticesRef vertices, TrianglesRef triangles,
                                  const Eigen::Ref<const Vector>& dirichlet,
                                  const Eigen::Ref<const Vector>& flux_coefficients,
                                  const Eigen::Ref<const Vertices>& points, double a, Space flux,
                                  const HMatrixOptions& options) {
  const Surface s(vertices, triangles);
  if (dirichlet.size() != s.vertices() || flux_coefficients.size() != dofs(s, flux))  // before the build
    throw std::invalid_argument("exterior_potential: one Dirichlet value per vertex and one flux coefficient per dof");
  return SurfacePotentialOperator(s, points, flux, options).evaluate(dirichlet, flux_coefficients, a);
}

}  // namespace bem
