#include "bem/surface_potential_operator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <stdexcept>

#include <Eigen/Sparse>

#include "bem/surface_entries.hpp"
#include "bem/surface_potentials.hpp"

namespace bem {

namespace {

constexpr double kInvTwoPi = 0.5 / M_PI;

/// |D 1| above this: inside Omega or on Gamma. D 1 is -2 inside, 0 outside and minus the
/// interior solid angle over 2 pi on Gamma; its H-matrix value is off by about tol and the
/// point-triangle quadrature by far less, so any threshold well between the two serves.
/// On Gamma only a vertex of interior solid angle below 2 pi 1e-3 passes it, and the
/// vertex test catches that.
constexpr double kInsideDoubleLayer = 1e-3;

/// The far rule's points of a block's triangles about their centre (the rule of the block's
/// closest pair, point_rule) and the map Q from them to the dofs (Q(q, c): the basis
/// function of column c at point q); weights w_q = 2 area w_g / (2 pi).
struct FarRule {
  std::vector<double> x, y, z, nx, ny, nz, w;
  Eigen::SparseMatrix<double> Q;
  Vec3 centre;
  Index size() const { return static_cast<Index>(w.size()); }
};

/// The entries of I x J: the triangles of the supports of J once (sorted, unique) and per
/// dof its terms (position among them, local basis b = 0..2 of a hat or 3 of an
/// indicator); the integrals of a row (one point, every triangle of J) go to per-block
/// scratch (a block is built by one thread). With `companion`, the other potential is the
/// companion matrix 1 (HMatrix::family: a dense block's point integrals give both).
class SurfacePotentialBlock : public EntryBlock {
 public:
  SurfacePotentialBlock(const Surface& s, const Vertices& points, PotentialKernel kernel, bool companion, Space cols,
                        const Index* I, Index m, const Index* J, Index k)
      : surface_(s),
        points_(points),
        double_layer_(kernel == PotentialKernel::DoubleLayer),
        companion_(companion),
        I_(I),
        m_(m),
        k_(k) {
    begin_.reserve(static_cast<std::size_t>(k + 1));
    begin_.push_back(0);
    for (Index c = 0; c < k; ++c) {
      const Index j = J[c];
      if (cols == Space::P0) {
        triangle_.push_back(j);
        basis_.push_back(3);
      } else {
        for (Index t : s.star(j)) {
          const auto& v = s.triangle(t).v;
          triangle_.push_back(t);
          basis_.push_back(static_cast<int>(std::find(v.begin(), v.end(), j) - v.begin()));
        }
      }
      begin_.push_back(static_cast<Index>(triangle_.size()));
    }
    triangles_ = triangle_;
    std::sort(triangles_.begin(), triangles_.end());
    triangles_.erase(std::unique(triangles_.begin(), triangles_.end()), triangles_.end());
    position_.resize(triangle_.size());
    for (std::size_t q = 0; q < triangle_.size(); ++q)
      position_[q] =
          static_cast<Index>(std::lower_bound(triangles_.begin(), triangles_.end(), triangle_[q]) - triangles_.begin());
    integrals_.resize(triangles_.size());
  }

  void row(Index i, double* out) const override { row(i, double_layer_, out); }

  void column(Index j, double* out) const override {
    const Index q0 = begin_[static_cast<std::size_t>(j)], q1 = begin_[static_cast<std::size_t>(j) + 1];
    for (Index r = 0; r < m_; ++r) {
      const Vec3 z = point(r);
      double sum = 0.0;
      for (Index q = q0; q < q1; ++q)
        sum += value(point_integrals(surface_.triangle(triangle_[static_cast<std::size_t>(q)]), z),
                     basis_[static_cast<std::size_t>(q)], double_layer_);
      out[r] = sum;
    }
  }

  void all(double* out) const override {
    std::vector<double> r(static_cast<std::size_t>(k_));
    if (companion_) other_.resize(m_, k_);
    for (Index i = 0; i < m_; ++i) {
      row(i, double_layer_, r.data());
      for (Index c = 0; c < k_; ++c) out[i + c * m_] = r[static_cast<std::size_t>(c)];
      if (companion_) other_.row(i) = sum_terms(!double_layer_).transpose();
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
  /// of the rule of the closest pair, projected onto the dofs (Q). (Unlike the Galerkin
  /// double layer between two faces of one plane, surface_entries.cpp, ACA of the double
  /// layer's kernel needs no split by plane here: points in the plane of a face zero only
  /// their own rows' part, measured in docs/design/bem3d.md.)
  bool low_rank(double tol, LowRank& out) const override { return far_low_rank(double_layer_, tol, out); }

  bool companion_low_rank(int /*which*/, double tol, LowRank& out) const override {
    return far_low_rank(!double_layer_, tol, out);
  }

 private:
  /// The row of point i in the single or double layer.
  void row(Index i, bool double_layer, double* out) const {
    const Vec3 z = point(i);
    for (std::size_t p = 0; p < triangles_.size(); ++p)
      integrals_[p] = point_integrals(surface_.triangle(triangles_[p]), z);
    const Eigen::VectorXd sums = sum_terms(double_layer);
    std::copy(sums.data(), sums.data() + k_, out);
  }

  /// Per column, its terms' values in integrals_.
  Eigen::VectorXd sum_terms(bool double_layer) const {
    Eigen::VectorXd out(k_);
    for (Index c = 0; c < k_; ++c) {
      double sum = 0.0;
      for (Index q = begin_[static_cast<std::size_t>(c)]; q < begin_[static_cast<std::size_t>(c) + 1]; ++q)
        sum += value(integrals_[static_cast<std::size_t>(position_[static_cast<std::size_t>(q)])],
                     basis_[static_cast<std::size_t>(q)], double_layer);
      out(c) = sum;
    }
    return out;
  }

  bool far_low_rank(bool double_layer, double tol, LowRank& out) const {
    if (!far_rule()) return false;  // not far enough: ACA on the entries
    const FarRule& f = *far_;
    const Slice row = [&](Index r, double* o) { double_layer ? kernel_row<true>(r, o) : kernel_row<false>(r, o); };
    const Slice column = [&](Index q, double* o) {
      double_layer ? kernel_column<true>(q, o) : kernel_column<false>(q, o);
    };
    const LowRank A = aca(m_, f.size(), row, column, 0.3 * tol, std::min(m_, f.size()));
    out.U = A.U;
    out.V = f.Q.transpose() * A.V;
    return true;
  }

  /// The far rule of the block, made on the first call (null: a pair too close for it).
  const FarRule* far_rule() const {
    if (far_made_) return far_.get();
    far_made_ = true;
    Box points, supports;
    double radius = 0.0, diameter = 0.0;
    Vec3 centre{0.0, 0.0, 0.0};
    for (Index r = 0; r < m_; ++r) points.add(point(r));
    for (Index t : triangles_) {
      const Triangle& T = surface_.triangle(t);
      for (const Vec3& p : T.p) supports.add(p);
      radius = std::max(radius, T.radius);
      diameter = std::max({diameter, norm(T.p[1] - T.p[0]), norm(T.p[2] - T.p[1]), norm(T.p[0] - T.p[2])});
      centre = centre + T.c;
    }
    // the rule of the closest pair (the direct evaluation's for it, or a finer one)
    const TriangleRule* rule = point_rule((points.distance(supports) - radius) / diameter);
    if (rule == nullptr) return nullptr;
    far_ = std::make_unique<FarRule>();
    FarRule& f = *far_;
    f.centre = (1.0 / static_cast<double>(triangles_.size())) * centre;
    const Index nr = rule->size();
    for (Index t : triangles_) {
      const Triangle& T = surface_.triangle(t);
      const Vec3 e1 = T.p[1] - T.p[0], e2 = T.p[2] - T.p[0];
      for (Index g = 0; g < nr; ++g) {
        const std::size_t gi = static_cast<std::size_t>(g);
        const Vec3 y = T.p[0] + rule->s[gi] * e1 + rule->t[gi] * e2 - f.centre;
        f.x.push_back(y.x), f.y.push_back(y.y), f.z.push_back(y.z);
        f.nx.push_back(T.n.x), f.ny.push_back(T.n.y), f.nz.push_back(T.n.z);
        f.w.push_back(2.0 * T.area * rule->w[gi] * kInvTwoPi);
      }
    }
    std::vector<Eigen::Triplet<double>> entries;
    for (Index c = 0; c < k_; ++c)
      for (Index q = begin_[static_cast<std::size_t>(c)]; q < begin_[static_cast<std::size_t>(c) + 1]; ++q) {
        const Index p = position_[static_cast<std::size_t>(q)];
        const int b = basis_[static_cast<std::size_t>(q)];
        for (Index g = 0; g < nr; ++g) {
          const std::size_t gi = static_cast<std::size_t>(g);
          const double l[4] = {1.0 - rule->s[gi] - rule->t[gi], rule->s[gi], rule->t[gi], 1.0};
          entries.emplace_back(p * nr + g, c, l[b]);
        }
      }
    f.Q.resize(f.size(), k_);
    f.Q.setFromTriplets(entries.begin(), entries.end());
    for (auto& zc : zs_) zc.resize(static_cast<std::size_t>(m_));
    for (Index r = 0; r < m_; ++r) {
      const Vec3 z = point(r) - f.centre;
      const std::size_t ri = static_cast<std::size_t>(r);
      zs_[0][ri] = z.x, zs_[1][ri] = z.y, zs_[2][ri] = z.z;
    }
    return far_.get();
  }

  /// 1/r (single layer) or (z - y).n_y / r^3 (double layer) at d = z - y.
  template <bool double_layer>
  static double kernel(double dx, double dy, double dz, double nx, double ny, double nz) {
    const double s = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
    if constexpr (double_layer) return (dx * nx + dy * ny + dz * nz) * s * s * s;
    return s;
  }
  template <bool double_layer>
  void kernel_row(Index r, double* out) const {
    const FarRule& f = *far_;
    const std::size_t ri = static_cast<std::size_t>(r);
    const double zx = zs_[0][ri], zy = zs_[1][ri], zz = zs_[2][ri];
    const double *x = f.x.data(), *y = f.y.data(), *z = f.z.data(), *w = f.w.data();
    const double *nx = f.nx.data(), *ny = f.ny.data(), *nz = f.nz.data();
    const Index nq = f.size();
#pragma omp simd
    for (Index q = 0; q < nq; ++q)
      out[q] = w[q] * kernel<double_layer>(zx - x[q], zy - y[q], zz - z[q], nx[q], ny[q], nz[q]);
  }
  template <bool double_layer>
  void kernel_column(Index q, double* out) const {
    const FarRule& f = *far_;
    const std::size_t qi = static_cast<std::size_t>(q);
    const double x = f.x[qi], y = f.y[qi], z = f.z[qi], w = f.w[qi], nx = f.nx[qi], ny = f.ny[qi], nz = f.nz[qi];
    const double *zx = zs_[0].data(), *zy = zs_[1].data(), *zz = zs_[2].data();
#pragma omp simd
    for (Index r = 0; r < m_; ++r) out[r] = w * kernel<double_layer>(zx[r] - x, zy[r] - y, zz[r] - z, nx, ny, nz);
  }
  Vec3 point(Index r) const {
    const Index i = I_[r];
    return {points_(i, 0), points_(i, 1), points_(i, 2)};
  }
  static double value(const PointIntegrals& q, int b, bool double_layer) { return double_layer ? q.K[b] : q.V[b]; }

  const Surface& surface_;
  const Vertices& points_;
  bool double_layer_, companion_;
  const Index* I_;
  Index m_, k_;
  std::vector<Index> begin_, triangle_, position_, triangles_;
  std::vector<int> basis_;
  mutable std::vector<PointIntegrals> integrals_;
  mutable Eigen::MatrixXd other_;  ///< the companion's dense block (all())
  mutable bool far_made_ = false;
  mutable std::unique_ptr<FarRule> far_;
  mutable std::array<std::vector<double>, 3> zs_;  ///< the points about the far rule's centre, by coordinate
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
