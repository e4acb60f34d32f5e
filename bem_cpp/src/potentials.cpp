#include "bem/potentials.hpp"

#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bem/cluster_tree.hpp"
#include "bem/far_field.hpp"
#include "bem/log_integrals.hpp"

namespace bem {

namespace {
constexpr double kInvPi = 0.318309886183790671537767526745;

void check_size(const char* name, Index got, Index expected) {
  if (got != expected)
    throw std::invalid_argument(std::string(name) + ": expected " + std::to_string(expected) +
                                " values (one per node), got " + std::to_string(got));
}
}  // namespace

namespace {
/// locate(polygon, z, tol) != Exterior, with the panels in the boxes of a cluster tree:
/// the same tests on the same panels (any panel within tol: on Gamma; else the parity of
/// the crossings of the ray to the right), skipping the clusters that cannot pass them.
class Locator {
 public:
  Locator(const Polygon& polygon, double tol)
      : polygon_(polygon),
        tree_(ClusterTree::for_space(polygon, Space::P0, 16)),
        tol_(tol),
        margin_(1e-12 * polygon.bounding_diameter()) {}
  bool not_exterior(Vec2 z) const { return near(0, z) || crossings(0, z) % 2 == 1; }

 private:
  bool near(int c, Vec2 z) const {
    const Cluster& cl = tree_.cluster(c);
    Box b;
    b.add(z);
    if (cl.box.distance(b) > tol_ + margin_) return false;
    if (!cl.leaf()) return near(cl.children[0], z) || near(cl.children[1], z);
    for (Index k = cl.begin; k < cl.end; ++k)
      if (distance(polygon_.panel(tree_.permutation()[static_cast<std::size_t>(k)]), z) <= tol_) return true;
    return false;
  }
  int crossings(int c, Vec2 z) const {
    const Cluster& cl = tree_.cluster(c);
    // a crossing needs min y <= z.y < max y and z.x < x <= max x (up to round-off)
    if (cl.box.y0 > z.y || cl.box.y1 <= z.y || cl.box.x1 + margin_ < z.x) return 0;
    if (!cl.leaf()) return crossings(cl.children[0], z) + crossings(cl.children[1], z);
    int count = 0;
    for (Index k = cl.begin; k < cl.end; ++k) {
      const Panel& p = polygon_.panel(tree_.permutation()[static_cast<std::size_t>(k)]);
      if ((p.a.y > z.y) != (p.b.y > z.y)) {
        const double x = p.a.x + (z.y - p.a.y) * (p.b.x - p.a.x) / (p.b.y - p.a.y);
        if (z.x < x) ++count;
      }
    }
    return count;
  }
  const Polygon& polygon_;
  ClusterTree tree_;
  double tol_, margin_;
};
}  // namespace

void check_exterior(const Polygon& polygon, const Eigen::Ref<const Points>& points) {
  const Index m = points.rows();
  const Locator locator(polygon, kOnBoundaryTolerance * polygon.bounding_diameter());
  std::vector<char> bad(static_cast<std::size_t>(m), 0);
#pragma omp parallel for schedule(static)
  for (Index k = 0; k < m; ++k) bad[static_cast<std::size_t>(k)] = locator.not_exterior({points(k, 0), points(k, 1)});
  Index n_bad = 0, first = -1;
  for (Index k = 0; k < m; ++k)
    if (bad[static_cast<std::size_t>(k)]) {
      if (first < 0) first = k;
      ++n_bad;
    }
  if (n_bad > 0) {
    std::ostringstream s;
    s << "points: " << n_bad << " of the " << m << " points lie inside or on Gamma (first: point " << first << " at ("
      << points(first, 0) << ", " << points(first, 1) << ")); the representation formula holds only in the exterior";
    throw std::invalid_argument(s.str());
  }
}

void check_potential_data(Index n, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients, double a) {
  check_size("dirichlet", dirichlet.size(), n);
  check_size("flux_coefficients", flux_coefficients.size(), n);
  if (!dirichlet.allFinite() || !flux_coefficients.allFinite() || !std::isfinite(a))
    throw std::invalid_argument("dirichlet, flux_coefficients and a must be finite");
}

Vector exterior_potential(const Polygon& polygon, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients, const Eigen::Ref<const Points>& points,
                          double a, Space flux) {
  const Index n = polygon.size(), m = points.rows();
  check_potential_data(n, dirichlet, flux_coefficients, a);
  if (!points.allFinite()) throw std::invalid_argument("points: non-finite coordinates");

  check_exterior(polygon, points);  // before any work

  // Per panel j: coefficients of its integrals in pi (K w - V psi)(z), w = v - a:
  // the log moments carry psi (start/end shape, or the panel value for P0), the
  // double-layer moments carry w at the start and end node.
  std::vector<double> l0(static_cast<std::size_t>(n)), l1(l0), d0(l0), d1(l0);
  for (Index j = 0; j < n; ++j) {
    const Index j1 = (j + 1) % n;
    const auto k = static_cast<std::size_t>(j);
    l0[k] = flux_coefficients(j);
    l1[k] = flux == Space::P1 ? flux_coefficients(j1) : flux_coefficients(j);
    d0[k] = dirichlet(j) - a;
    d1[k] = dirichlet(j1) - a;
  }
  const PanelArrays arrays(polygon);
  Vector u(m);
#pragma omp parallel
  {
    std::vector<int> rule(static_cast<std::size_t>(n));  // Gauss points per panel, 0: closed form
#pragma omp for schedule(dynamic, 16)
    for (Index i = 0; i < m; ++i) {
      const Vec2 z{points(i, 0), points(i, 1)};
      point_far_field_points(z, arrays, rule.data());
      double sum = 0.0;  // pi (K w - V psi)(z)
      FarBatches far([&](int p, const Index* js, int count) {
        sum += far_point_sum(z, arrays, js, count, p, l0.data(), l1.data(), d0.data(), d1.data());
      });
      for (Index j = 0; j < n; ++j) {
        const int p = rule[static_cast<std::size_t>(j)];
        if (p > 0) {
          far.push(p, j);
          continue;
        }
        const PointPanelMoments q = point_panel_moments(z, polygon.panel(j));  // closed form
        const auto k = static_cast<std::size_t>(j);
        sum += l0[k] * q.log[0] + l1[k] * q.log[1] + d0[k] * q.dl[0] + d1[k] * q.dl[1];
      }
      far.finish();
      // u = a + (K w - V psi)/2, -V psi = (1/pi) int log|z - y| psi, K w = (1/pi) int ... w
      u(i) = a + 0.5 * kInvPi * sum;
    }
  }
  return u;
}

Vector exterior_potential(const Eigen::Ref<const Points>& nodes, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients, const Eigen::Ref<const Points>& points,
                          double a, Space flux) {
  return exterior_potential(Polygon(nodes), dirichlet, flux_coefficients, points, a, flux);
}

}  // namespace bem
