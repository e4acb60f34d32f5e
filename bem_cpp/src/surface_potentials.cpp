#include "bem/surface_potentials.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace bem {

namespace {

constexpr double kInvTwoPi = 0.5 / M_PI;
constexpr int kMaxDepth = 60;  // pieces of 2^-60 of the triangle: any point off Gamma

/// Adds the integrals over the sub-triangle with parent coordinates (s, t) of its vertices
/// c[0..2] (the parent maps (s, t) to q0 + s e1 + t e2).
void integrate(const Triangle& T, Vec3 z, const double cs[3], const double ct[3], int depth, PointIntegrals& out) {
  const Vec3 e1 = T.p[1] - T.p[0], e2 = T.p[2] - T.p[0];
  Vec3 q[3];
  for (int k = 0; k < 3; ++k) q[k] = T.p[0] + cs[k] * e1 + ct[k] * e2;
  const Vec3 c = (1.0 / 3.0) * (q[0] + q[1] + q[2]);
  const double diam = std::max({norm(q[1] - q[0]), norm(q[2] - q[1]), norm(q[0] - q[2])});
  const double radius = std::max({norm(q[0] - c), norm(q[1] - c), norm(q[2] - c)});
  const TriangleRule* rule = point_rule((norm(z - c) - radius) / diam);
  if (rule == nullptr && depth >= kMaxDepth) rule = point_rule(kPointSplitDiameters);
  if (rule == nullptr) {  // split at the edge midpoints
    const double ms[3] = {0.5 * (cs[0] + cs[1]), 0.5 * (cs[1] + cs[2]), 0.5 * (cs[2] + cs[0])};
    const double mt[3] = {0.5 * (ct[0] + ct[1]), 0.5 * (ct[1] + ct[2]), 0.5 * (ct[2] + ct[0])};
    const double s4[4][3] = {
        {cs[0], ms[0], ms[2]}, {ms[0], cs[1], ms[1]}, {ms[2], ms[1], cs[2]}, {ms[0], ms[1], ms[2]}};
    const double t4[4][3] = {
        {ct[0], mt[0], mt[2]}, {mt[0], ct[1], mt[1]}, {mt[2], mt[1], ct[2]}, {mt[0], mt[1], mt[2]}};
    for (int k = 0; k < 4; ++k) integrate(T, z, s4[k], t4[k], depth + 1, out);
    return;
  }
  const TriangleRule& r = *rule;
  // area of the piece over the area of the reference triangle, times the parent's Jacobian
  const double jac = 2.0 * T.area * std::abs((cs[1] - cs[0]) * (ct[2] - ct[0]) - (cs[2] - cs[0]) * (ct[1] - ct[0]));
  for (int k = 0; k < r.size(); ++k) {
    const double u = r.s[static_cast<std::size_t>(k)], v = r.t[static_cast<std::size_t>(k)];
    const double s = cs[0] + u * (cs[1] - cs[0]) + v * (cs[2] - cs[0]);
    const double t = ct[0] + u * (ct[1] - ct[0]) + v * (ct[2] - ct[0]);
    const Vec3 d = z - (T.p[0] + s * e1 + t * e2);
    const double r2 = dot(d, d), rr = std::sqrt(r2);
    const double g = jac * r.w[static_cast<std::size_t>(k)] * kInvTwoPi / rr;
    const double kd = g * dot(d, T.n) / r2;
    const double l[3] = {1.0 - s - t, s, t};
    for (int b = 0; b < 3; ++b) {
      out.V[b] += g * l[b];
      out.K[b] += kd * l[b];
    }
    out.V[3] += g;
  }
}

}  // namespace

const TriangleRule* point_rule(double q) {
  // degrees 4, 8 and 14 (symmetric rules of 6 and 16 points, 8 x 8 collapsed Gauss points)
  static const TriangleRule& far = symmetric_rule(4);  // the rules' caches lock
  static const TriangleRule& middle = symmetric_rule(8);
  static const TriangleRule& near = triangle_rule(8);
  if (q >= 6.0) return &far;
  if (q >= 3.0) return &middle;
  if (q >= kPointSplitDiameters) return &near;
  return nullptr;
}

PointIntegrals point_integrals(const Triangle& t, Vec3 z) {
  PointIntegrals out{};
  const double cs[3] = {0.0, 1.0, 0.0}, ct[3] = {0.0, 0.0, 1.0};
  integrate(t, z, cs, ct, 0, out);
  return out;
}

double solid_angle(const Triangle& t, Vec3 z) {
  // Van Oosterom and Strackee (1983)
  const Vec3 a = t.p[0] - z, b = t.p[1] - z, c = t.p[2] - z;
  const double la = norm(a), lb = norm(b), lc = norm(c);
  const double num = dot(a, cross(b, c));
  const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return 2.0 * std::atan2(num, den);
}

Vector exterior_potential(VerticesRef vertices, TrianglesRef triangles, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients, const Eigen::Ref<const Vertices>& points,
                          double a, Space flux) {
  const Surface s(vertices, triangles);
  if (dirichlet.size() != s.vertices() || flux_coefficients.size() != dofs(s, flux))
    throw std::invalid_argument("exterior_potential: one Dirichlet value per vertex and one flux coefficient per dof");
  const Index count = points.rows(), m = s.size();
  Vector u(count);
  const double on = 1e-12 * s.bounding_diameter();
  Index bad = -1;
  std::string why;
#pragma omp parallel for schedule(dynamic, 4)
  for (Index k = 0; k < count; ++k) {
    const Vec3 z{points(k, 0), points(k, 1), points(k, 2)};
    double omega = 0.0, dl = 0.0, sl = 0.0, nearest = std::numeric_limits<double>::infinity();
    for (Index t = 0; t < m; ++t) {
      const Triangle& T = s.triangle(t);
      nearest = std::min({nearest, norm(z - T.p[0]), norm(z - T.p[1]), norm(z - T.p[2]), norm(z - T.c)});
      omega += solid_angle(T, z);
      const PointIntegrals I = point_integrals(T, z);
      for (int b = 0; b < 3; ++b) dl += I.K[b] * (dirichlet(T.v[static_cast<std::size_t>(b)]) - a);
      if (flux == Space::P0)
        sl += I.V[3] * flux_coefficients(t);
      else
        for (int b = 0; b < 3; ++b) sl += I.V[b] * flux_coefficients(T.v[static_cast<std::size_t>(b)]);
    }
    // the solid angle of Gamma is 4 pi inside, 0 outside (to round-off), in between on Gamma
    const bool inside = std::abs(omega) > 1e-6 || nearest <= on;
    if (inside) {
#pragma omp critical
      if (bad < 0 || k < bad) bad = k;
    }
    u(k) = 0.5 * (dl - sl) + a;
  }
  if (bad >= 0) refuse_interior_point(points, bad);
  return u;
}

void refuse_interior_point(const Eigen::Ref<const Vertices>& points, Index k) {
  std::ostringstream msg;
  msg.precision(6);
  msg << "points: point " << k << " (" << points(k, 0) << ", " << points(k, 1) << ", " << points(k, 2)
      << ") lies inside Omega or on Gamma; the representation formula gives u_e only outside";
  throw std::invalid_argument(msg.str());
}

}  // namespace bem
