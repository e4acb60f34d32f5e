#include "bem/potential_operator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "bem/log_integrals.hpp"
#include "bem/potentials.hpp"

namespace bem {

namespace {
constexpr double kInv2Pi = 0.159154943091895335768883763372514;

/// The two shape moments of one kernel of point_panel_moments for a pair (point, panel).
struct Moments {
  double m[2];
};

/// Moments of many pairs (z_k, panel P_k) with the rule of point_panel_moments and of the
/// direct evaluation (point_far_field_points: the smallest p <= kMaxFarPoints with
/// |z - m_j| >= h_j (1 + y_p) / 2, else the closed form); the far pairs sorted by p and
/// evaluated in vector loops over the pairs (the double layer needs no logarithm).
class PairMoments {
 public:
  void clear() { z_.clear(), panel_.clear(); }
  void add(Vec2 z, Index panel) {
    z_.push_back(z);
    panel_.push_back(panel);
  }
  /// out[k] for the pairs added, in order.
  void evaluate(const Polygon& polygon, bool double_layer, std::vector<Moments>& out);

 private:
  std::vector<Vec2> z_;
  std::vector<Index> panel_;
  std::vector<std::size_t> order_;
  std::vector<double> ox_, oy_, tx_, ty_, h_, dn_;
};

__attribute__((target_clones("avx2", "default"))) void far_moments(const double* ox, const double* oy, const double* tx,
                                                                   const double* ty, const double* h, const double* dn,
                                                                   std::size_t count, int p, bool double_layer,
                                                                   double* m0, double* m1) {
  const GaussRule& g = gauss_legendre(p);
#pragma omp simd
  for (std::size_t k = 0; k < count; ++k) m0[k] = m1[k] = 0.0;
  for (int b = 0; b < p; ++b) {
    const double x = g.x[static_cast<std::size_t>(b)], w = g.w[static_cast<std::size_t>(b)];
    if (double_layer) {
#pragma omp simd
      for (std::size_t k = 0; k < count; ++k) {
        const double t = x * h[k], rx = ox[k] - t * tx[k], ry = oy[k] - t * ty[k];
        const double f = w * h[k] * dn[k] / (rx * rx + ry * ry);
        m0[k] += (1.0 - x) * f;
        m1[k] += x * f;
      }
    } else {
#pragma omp simd
      for (std::size_t k = 0; k < count; ++k) {
        const double t = x * h[k], rx = ox[k] - t * tx[k], ry = oy[k] - t * ty[k];
        const double f = w * h[k] * 0.5 * log(rx * rx + ry * ry);
        m0[k] += (1.0 - x) * f;
        m1[k] += x * f;
      }
    }
  }
}

void PairMoments::evaluate(const Polygon& polygon, bool double_layer, std::vector<Moments>& out) {
  // Far pairs queue by their rule (kFar at a time per rule, as in the direct evaluation).
  constexpr std::size_t kFar = 32;
  const std::size_t count = z_.size();
  out.resize(count);
  for (auto* v : {&ox_, &oy_, &tx_, &ty_, &h_, &dn_}) v->resize(static_cast<std::size_t>(kMaxFarPoints + 1) * kFar);
  order_.resize(static_cast<std::size_t>(kMaxFarPoints + 1) * kFar);
  std::size_t queued[kMaxFarPoints + 1] = {};
  double m0[kFar], m1[kFar];
  auto flush = [&](int p) {
    const std::size_t b = static_cast<std::size_t>(p) * kFar, c = queued[p];
    far_moments(&ox_[b], &oy_[b], &tx_[b], &ty_[b], &h_[b], &dn_[b], c, p, double_layer, m0, m1);
    for (std::size_t q = 0; q < c; ++q) out[order_[b + q]] = Moments{{m0[q], m1[q]}};
    queued[p] = 0;
  };
  const auto& y = gauss_thresholds();
  double bound2[kMaxFarPoints + 1];
  for (int p = 1; p <= kMaxFarPoints; ++p) {
    const double f = 0.5 * (1.0 + y[static_cast<std::size_t>(p)]);
    bound2[p] = f * f;  // times h^2
  }
  for (std::size_t k = 0; k < count; ++k) {
    const Panel& P = polygon.panel(panel_[k]);
    const Vec2 d = z_[k] - P.m;
    const double r2 = dot(d, d) / (P.h * P.h);
    int p = 1;
    while (p <= kMaxFarPoints && r2 < bound2[p]) ++p;
    if (p > kMaxFarPoints) {
      const PointPanelMoments q = point_panel_moments(z_[k], P);
      out[k] = double_layer ? Moments{{q.dl[0], q.dl[1]}} : Moments{{q.log[0], q.log[1]}};
      continue;
    }
    const std::size_t at = static_cast<std::size_t>(p) * kFar + queued[p]++;
    ox_[at] = z_[k].x - P.a.x;
    oy_[at] = z_[k].y - P.a.y;
    tx_[at] = P.t.x;
    ty_[at] = P.t.y;
    h_[at] = P.h;
    dn_[at] = ox_[at] * P.n.x + oy_[at] * P.n.y;  // (z - y).n, the same for all y on the panel
    order_[at] = k;
    if (queued[p] == kFar) flush(p);
  }
  for (int p = 1; p <= kMaxFarPoints; ++p)
    if (queued[p] > 0) flush(p);
}

/// The entries of I x J: the panels of the dofs of J once (sorted, unique) and per dof the
/// positions and shapes of its two panel terms; the moments of a row (one point, every
/// panel of J) go to per-block scratch (a block is built by one thread).
class PotentialBlock : public EntryBlock {
 public:
  PotentialBlock(const Polygon& polygon, const Points& points, PotentialKernel kernel, Space cols, const Index* I,
                 Index m, const Index* J, Index k)
      : polygon_(polygon), points_(points), double_layer_(kernel == PotentialKernel::DoubleLayer), I_(I), m_(m), k_(k) {
    const Index n = polygon.size();
    terms_.resize(static_cast<std::size_t>(2 * k));
    shape_.resize(static_cast<std::size_t>(2 * k));
    for (Index c = 0; c < k; ++c) {
      const Index j = J[c];
      const std::size_t t = static_cast<std::size_t>(2 * c);
      if (cols == Space::P1) {  // hat of node j: phi_1 on panel j - 1, phi_0 on panel j
        terms_[t] = (j + n - 1) % n;
        shape_[t] = 1;
        terms_[t + 1] = j;
        shape_[t + 1] = 0;
      } else {  // indicator of panel j
        terms_[t] = terms_[t + 1] = j;
        shape_[t] = 0;
        shape_[t + 1] = 1;
      }
    }
    panels_ = terms_;
    std::sort(panels_.begin(), panels_.end());
    panels_.erase(std::unique(panels_.begin(), panels_.end()), panels_.end());
    position_.resize(terms_.size());
    for (std::size_t t = 0; t < terms_.size(); ++t)
      position_[t] = static_cast<Index>(std::lower_bound(panels_.begin(), panels_.end(), terms_[t]) - panels_.begin());
  }

  void row(Index i, double* out) const override {
    const Vec2 z = point(i);
    pairs_.clear();
    for (Index p : panels_) pairs_.add(z, p);
    pairs_.evaluate(polygon_, double_layer_, moments_);
    for (Index c = 0; c < k_; ++c) {
      const std::size_t t = static_cast<std::size_t>(2 * c);
      out[c] = kInv2Pi * (moments_[static_cast<std::size_t>(position_[t])].m[shape_[t]] +
                          moments_[static_cast<std::size_t>(position_[t + 1])].m[shape_[t + 1]]);
    }
  }

  void column(Index j, double* out) const override {
    const std::size_t t = static_cast<std::size_t>(2 * j);
    const bool same = terms_[t] == terms_[t + 1];  // P0: one panel, both shapes
    pairs_.clear();
    for (Index r = 0; r < m_; ++r) {
      pairs_.add(point(r), terms_[t]);
      if (!same) pairs_.add(point(r), terms_[t + 1]);
    }
    pairs_.evaluate(polygon_, double_layer_, moments_);
    const std::size_t stride = same ? 1 : 2;
    for (Index r = 0; r < m_; ++r) {
      const Moments& q0 = moments_[stride * static_cast<std::size_t>(r)];
      const Moments& q1 = moments_[stride * static_cast<std::size_t>(r) + stride - 1];
      out[r] = kInv2Pi * (q0.m[shape_[t]] + q1.m[shape_[t + 1]]);
    }
  }

  void all(double* out) const override {
    std::vector<double> r(static_cast<std::size_t>(k_));
    for (Index i = 0; i < m_; ++i) {
      row(i, r.data());
      for (Index c = 0; c < k_; ++c) out[i + c * m_] = r[static_cast<std::size_t>(c)];
    }
  }

 private:
  Vec2 point(Index r) const {
    const Index i = I_[r];
    return {points_(i, 0), points_(i, 1)};
  }
  const Polygon& polygon_;
  const Points& points_;
  bool double_layer_;
  const Index* I_;
  Index m_, k_;
  std::vector<Index> terms_, panels_, position_;
  std::vector<int> shape_;
  mutable PairMoments pairs_;
  mutable std::vector<Moments> moments_;
};

}  // namespace

PotentialEntries::PotentialEntries(const Polygon& polygon, const Points& points, PotentialKernel kernel, Space cols)
    : polygon_(polygon), points_(points), kernel_(kernel), cols_(cols) {
  if (kernel == PotentialKernel::DoubleLayer && cols != Space::P1)
    throw std::invalid_argument("PotentialEntries: the double-layer potential acts on the P1 trace");
}

std::unique_ptr<EntryBlock> PotentialEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<PotentialBlock>(polygon_, points_, kernel_, cols_, I, m, J, k);
}

PotentialOperator::PotentialOperator(const Polygon& polygon, const Eigen::Ref<const Points>& points, Space flux,
                                     HMatrixOptions options)
    : points_(points), n_(polygon.size()) {
  if (points_.rows() < 1) throw std::invalid_argument("PotentialOperator: need at least one point");
  if (!points_.allFinite()) throw std::invalid_argument("points: non-finite coordinates");
  check_exterior(polygon, points_);
  options.symmetric = false;
  options.comm = nullptr;
  options.split_to_leaves = true;
  auto rows = std::make_shared<const ClusterTree>(point_cluster_tree(points_, options.leaf_size));
  auto p1 = std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon, Space::P1, options.leaf_size));
  auto cols = flux == Space::P1
                  ? p1
                  : std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon, Space::P0, options.leaf_size));
  double_layer_ = std::make_unique<HMatrix>(
      rows, p1, PotentialEntries(polygon, points_, PotentialKernel::DoubleLayer, Space::P1), options);
  single_layer_ = std::make_unique<HMatrix>(
      rows, cols, PotentialEntries(polygon, points_, PotentialKernel::SingleLayer, flux), options);
}

Vector PotentialOperator::evaluate(const Eigen::Ref<const Vector>& dirichlet,
                                   const Eigen::Ref<const Vector>& flux_coefficients, double a) const {
  check_potential_data(n_, dirichlet, flux_coefficients, a);
  const Vector w = dirichlet.array() - a;
  Vector u = double_layer_->apply(w).col(0) + single_layer_->apply(flux_coefficients).col(0);
  u.array() += a;
  return u;
}

Vector exterior_potential_hmatrix(const Eigen::Ref<const Points>& nodes, const Eigen::Ref<const Vector>& dirichlet,
                                  const Eigen::Ref<const Vector>& flux_coefficients,
                                  const Eigen::Ref<const Points>& points, double a, Space flux,
                                  const HMatrixOptions& options) {
  const Polygon polygon(nodes);
  check_potential_data(polygon.size(), dirichlet, flux_coefficients, a);  // before the build
  return PotentialOperator(polygon, points, flux, options).evaluate(dirichlet, flux_coefficients, a);
}

}  // namespace bem
