#include "bem/potentials.hpp"

#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

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

Vector exterior_potential(const Polygon& polygon, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients,
                          const Eigen::Ref<const Points>& points, double a, Space flux) {
  const Index n = polygon.size(), m = points.rows();
  check_size("dirichlet", dirichlet.size(), n);
  check_size("flux_coefficients", flux_coefficients.size(), n);
  if (!dirichlet.allFinite() || !flux_coefficients.allFinite() || !std::isfinite(a))
    throw std::invalid_argument("dirichlet, flux_coefficients and a must be finite");
  if (!points.allFinite()) throw std::invalid_argument("points: non-finite coordinates");

  // Reject points inside Omega or on Gamma before any work.
  const double tol = kOnBoundaryTolerance * polygon.bounding_diameter();
  std::vector<char> bad(static_cast<std::size_t>(m), 0);
#pragma omp parallel for schedule(static)
  for (Index k = 0; k < m; ++k)
    bad[static_cast<std::size_t>(k)] =
        locate(polygon, {points(k, 0), points(k, 1)}, tol) != Location::Exterior;
  Index n_bad = 0, first = -1;
  for (Index k = 0; k < m; ++k)
    if (bad[static_cast<std::size_t>(k)]) {
      if (first < 0) first = k;
      ++n_bad;
    }
  if (n_bad > 0) {
    std::ostringstream s;
    s << "points: " << n_bad << " of the " << m << " points lie inside or on Gamma (first: point "
      << first << " at (" << points(first, 0) << ", " << points(first, 1)
      << ")); the representation formula holds only in the exterior";
    throw std::invalid_argument(s.str());
  }

  const Vector w = dirichlet.array() - a;
  Vector u(m);
#pragma omp parallel for schedule(dynamic, 16)
  for (Index k = 0; k < m; ++k) {
    const Vec2 z{points(k, 0), points(k, 1)};
    double sum = 0.0;  // pi * (K w - V psi)(z)
    for (Index j = 0; j < n; ++j) {
      const Index j1 = (j + 1) % n;
      const PointPanelMoments q = point_panel_moments(z, polygon.panel(j));
      sum += w(j) * q.dl[0] + w(j1) * q.dl[1];
      // -V psi = (1/pi) int log|z - y| psi(y) ds_y
      if (flux == Space::P1)
        sum += flux_coefficients(j) * q.log[0] + flux_coefficients(j1) * q.log[1];
      else
        sum += flux_coefficients(j) * (q.log[0] + q.log[1]);
    }
    u(k) = a + 0.5 * kInvPi * sum;
  }
  return u;
}

Vector exterior_potential(const Eigen::Ref<const Points>& nodes, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients,
                          const Eigen::Ref<const Points>& points, double a, Space flux) {
  return exterior_potential(Polygon(nodes), dirichlet, flux_coefficients, points, a, flux);
}

}  // namespace bem
