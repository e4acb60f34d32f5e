#include "bem/lame_potentials.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bem/log_integrals.hpp"
#include "bem/potentials.hpp"
#include "bem/surface_potentials.hpp"

namespace bem {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxDepth = 60;  // pieces of 2^-60 of the panel or triangle: any point off Gamma

/// The constants of the kernels (header): c, alpha = 3 - 4 nu, 1 - alpha = -2 (1 - 2 nu) and
/// b = lambda (1 - alpha) = -4 mu nu, without cancellation as nu -> 1/2.
struct Constants {
  double mu, c, alpha, oma, b;
};

Constants constants(const Lame& m, int d) {
  const double c = 1.0 / ((d == 3 ? 16.0 : 8.0) * kPi * m.mu * (1.0 - m.nu));
  return {m.mu, c, 3.0 - 4.0 * m.nu, -2.0 * (1.0 - 2.0 * m.nu), -4.0 * m.mu * m.nu};
}

template <int D>
double dotd(const double* a, const double* b) {
  double s = 0.0;
  for (int i = 0; i < D; ++i) s += a[i] * b[i];
  return s;
}

double sq(double x) { return x * x; }

/// 1/rho^d for r2 = rho^2.
template <int D>
double inverse_power(double r2) {
  return D == 3 ? 1.0 / (r2 * std::sqrt(r2)) : 1.0 / r2;
}

/// F (header) at r for the data w and normal n.
template <int D>
void double_layer_f(const Constants& k, const double* r, double r2, double inv, const double* n, const double* w,
                    double* F) {
  const double inv2 = inv / r2;
  const double nw = dotd<D>(n, w), nr = dotd<D>(n, r), wr = dotd<D>(w, r);
  const double radial = k.c * ((k.b + 2.0 * k.mu) * nw * inv - 2.0 * D * k.mu * nr * wr * inv2);
  const double tangential = k.c * k.mu * k.oma * inv;
  for (int i = 0; i < D; ++i) F[i] = radial * r[i] + tangential * (w[i] * nr + n[i] * wr);
}

/// G (header) at r for the data w and normal n, added times `scale` to G.
template <int D>
void add_double_layer_g(const Constants& k, const double* r, const double* n, const double* w, double scale,
                        double G[][D]) {
  const double r2 = dotd<D>(r, r), inv = inverse_power<D>(r2), inv2 = inv / r2, inv4 = inv2 / r2;
  const double nw = dotd<D>(n, w), nr = dotd<D>(n, r), wr = dotd<D>(w, r);
  const double tr = 2.0 * k.mu * nw, rtr = 2.0 * k.mu * nr * wr;
  double tau_r[D];
  for (int i = 0; i < D; ++i) tau_r[i] = k.mu * (w[i] * nr + n[i] * wr);
  const double cs = scale * k.c;
  const double diag = cs * ((k.b * nw + tr) * inv - D * rtr * inv2);
  const double rr = cs * (-D * (k.b * nw + tr) * inv2 + D * (D + 2) * rtr * inv4);
  const double a_tau = cs * k.oma * k.mu * inv, a_k = -cs * D * k.oma * inv2, a_s = -cs * 2.0 * D * inv2;
  for (int i = 0; i < D; ++i)
    for (int s = 0; s < D; ++s)
      G[i][s] += (i == s ? diag : 0.0) + rr * r[i] * r[s] + a_tau * (w[i] * n[s] + n[i] * w[s]) +
                 a_k * tau_r[i] * r[s] + a_s * tau_r[s] * r[i];
}

/// The sums of one point: u - a, grad u and P = lambda div u (header).
template <int D>
struct Sums {
  double u[D] = {};
  double g[D][D] = {};
  double p = 0.0;
};

/// Adds the quadrature node y (weight omega) at r = z - y with the data w = v - a and t and
/// the normal n at y.
template <int D, bool Stress>
inline void add_node(const Constants& k, const double* r, const double* n, const double* w, const double* t,
                     double omega, Sums<D>& s) {
  const double r2 = dotd<D>(r, r), inv = inverse_power<D>(r2);
  const double rt = dotd<D>(r, t);
  // single layer: 1/2 V t = int U t, U t = c (alpha g(rho) t + r (r.t) / rho^d), g = 1/rho (3D), -log rho (2D)
  const double g = D == 3 ? inv * r2 : -0.5 * std::log(r2);
  double F[D];
  double_layer_f<D>(k, r, r2, inv, n, w, F);
  for (int i = 0; i < D; ++i) s.u[i] -= omega * (F[i] + k.c * (k.alpha * g * t[i] + r[i] * rt * inv));
  if constexpr (Stress) {
    const double inv2 = inv / r2, nw = dotd<D>(n, w), nr = dotd<D>(n, r), wr = dotd<D>(w, r);
    add_double_layer_g<D>(k, r, n, w, -omega, s.g);
    // grad of 1/2 V t: d_s U_kl t_l = c (-alpha t_k r_s + d_ks (r.t) + t_s r_k) / rho^d - d c r_k r_s (r.t) / rho^(d+2)
    const double co = omega * k.c;
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j)
        s.g[i][j] -=
            co * ((-k.alpha * t[i] * r[j] + (i == j ? rt : 0.0) + t[j] * r[i]) * inv - D * r[i] * r[j] * rt * inv2);
    s.p -= co * k.b * (2.0 * k.mu * nw * inv - 2.0 * D * k.mu * nr * wr * inv2 + rt * inv);
  }
}

void check_size(const char* name, Index got, Index expected, const char* per) {
  if (got != expected) {
    std::ostringstream s;
    s << name << ": expected " << expected << " values (" << per << ", node-major), got " << got;
    throw std::invalid_argument(s.str());
  }
}

/// Sizes and finiteness of the data (n nodes, m cells of P0).
void check_data(int d, Index n, Index m, const Lame& medium, const Eigen::Ref<const Vector>& dirichlet,
                const Eigen::Ref<const Vector>& traction, const Eigen::Ref<const Vector>& a, Space space,
                bool points_finite) {
  check_medium(medium);
  const char* per_node = d == 2 ? "2 per node" : "3 per vertex";
  check_size("dirichlet", dirichlet.size(), d * n, per_node);
  if (space == Space::P1)
    check_size("traction", traction.size(), d * n, per_node);
  else
    check_size("traction", traction.size(), d * m, d == 2 ? "2 per panel" : "3 per triangle");
  check_size("a", a.size(), d, "one per component");
  if (!dirichlet.allFinite() || !traction.allFinite() || !a.allFinite())
    throw std::invalid_argument("dirichlet, traction and a must be finite");
  if (!points_finite) throw std::invalid_argument("points: non-finite coordinates");
}

/// Writes u (or sigma) of one point from its sums into row i of out.
template <int D, bool Stress>
void store(const Constants& k, const Sums<D>& s, const Eigen::Ref<const Vector>& a, Index i, Matrix& out) {
  if constexpr (Stress) {
    for (int r = 0; r < D; ++r)
      for (int c = 0; c < D; ++c) out(i, D * r + c) = (r == c ? s.p : 0.0) + k.mu * (s.g[r][c] + s.g[c][r]);
  } else {
    for (int r = 0; r < D; ++r) out(i, r) = s.u[r] + a(r);
  }
}

// ---------------------------------------------------------------------------------- 2D

/// Calls f(u, weight) at the Gauss nodes of the pieces of [u0, u1], a panel's segment in the
/// coordinate u along it from the foot of z (z at the normal distance |qn| from its line),
/// halving it until z is kPanelSplitLengths of a piece's length away. The foot-centred
/// coordinate keeps the nodes of the small pieces near z accurate to round-off of their own
/// size (from a panel end, eps h / distance relative, eps h / distance^2 in the stress).
template <class F>
void panel_nodes(double qn, double u0, double u1, int depth, const F& f) {
  const double len = u1 - u0;
  const double dist = std::sqrt(sq(u0 > 0.0 ? u0 : (u1 < 0.0 ? -u1 : 0.0)) + qn * qn);
  if (dist < kPanelSplitLengths * len && depth < kMaxDepth) {
    const double mid = 0.5 * (u0 + u1);
    panel_nodes(qn, u0, mid, depth + 1, f);
    panel_nodes(qn, mid, u1, depth + 1, f);
    return;
  }
  int p = gauss_points_for(dist, len, kMaxGaussPoints);
  if (p == 0) p = kMaxGaussPoints;
  const GaussRule& g = gauss_legendre(p);
  for (int q = 0; q < p; ++q) f(u0 + len * g.x[static_cast<std::size_t>(q)], len * g.w[static_cast<std::size_t>(q)]);
}

template <bool Stress>
Matrix evaluate(const Polygon& polygon, const Lame& medium, const Eigen::Ref<const Vector>& dirichlet,
                const Eigen::Ref<const Vector>& traction, const Eigen::Ref<const Points>& points,
                const Eigen::Ref<const Vector>& a, Space space) {
  const Index n = polygon.size(), count = points.rows();
  check_data(2, n, n, medium, dirichlet, traction, a, space, points.allFinite());
  check_exterior(polygon, points);  // before any work
  const Constants k = constants(medium, 2);
  Matrix out(count, Stress ? 4 : 2);
#pragma omp parallel for schedule(dynamic, 8)
  for (Index i = 0; i < count; ++i) {
    const Vec2 z{points(i, 0), points(i, 1)};
    Sums<2> sums;
    for (Index j = 0; j < n; ++j) {
      const Panel& P = polygon.panel(j);
      const Index j0 = 2 * j, j1 = 2 * ((j + 1) % n);
      const double n_y[2] = {P.n.x, P.n.y};
      const double w0[2] = {dirichlet(j0) - a(0), dirichlet(j0 + 1) - a(1)};
      const double w1[2] = {dirichlet(j1) - a(0), dirichlet(j1 + 1) - a(1)};
      const double t0[2] = {traction(j0), traction(j0 + 1)};
      const double t1[2] = {space == Space::P1 ? traction(j1) : t0[0], space == Space::P1 ? traction(j1 + 1) : t0[1]};
      const double inv_h = 1.0 / P.h;
      // z = y(u) - u t + qn n, u the coordinate along the panel from the foot of z, anchored at
      // the nearer end e (u(e) = (e - z).t, qn = (z - e).n): a node shared by two panels is
      // then the same vector from z in both (to round-off of its distance from z), and a small
      // piece near z has accurate nodes (panel_nodes)
      const Vec2 ea = P.a - z, eb = P.b - z;
      const bool at_a = dot(ea, ea) <= dot(eb, eb);
      const double u0 = at_a ? dot(ea, P.t) : dot(eb, P.t) - P.h, u1 = at_a ? u0 + P.h : dot(eb, P.t);
      const double qn = -dot(at_a ? ea : eb, P.n);
      panel_nodes(qn, u0, u1, 0, [&](double u, double weight) {
        const double l1 = (u - u0) * inv_h, l0 = 1.0 - l1;
        const double r[2] = {qn * P.n.x - u * P.t.x, qn * P.n.y - u * P.t.y};
        const double w[2] = {l0 * w0[0] + l1 * w1[0], l0 * w0[1] + l1 * w1[1]};
        const double t[2] = {l0 * t0[0] + l1 * t1[0], l0 * t0[1] + l1 * t1[1]};
        add_node<2, Stress>(k, r, n_y, w, t, weight, sums);
      });
    }
    store<2, Stress>(k, sums, a, i, out);
  }
  return out;
}

// ---------------------------------------------------------------------------------- 3D

/// Distance from z to the triangle T.
double triangle_distance(const Triangle& T, Vec3 z) {
  const double h = dot(z - T.p[0], T.n);
  const Vec3 q = z - h * T.n;
  bool inside = true;
  for (int e = 0; e < 3; ++e) inside = inside && dot(cross(T.p[(e + 1) % 3] - T.p[e], q - T.p[e]), T.n) >= 0.0;
  if (inside) return std::abs(h);
  double best = std::numeric_limits<double>::infinity();
  for (int e = 0; e < 3; ++e) {
    const Vec3 a = T.p[e], ab = T.p[(e + 1) % 3] - a;
    const double s = std::clamp(dot(z - a, ab) / dot(ab, ab), 0.0, 1.0);
    best = std::min(best, norm(z - (a + s * ab)));
  }
  return best;
}

/// Refuses (refuse_interior_point) the first point inside Omega (the solid angle of Gamma,
/// 4 pi inside and 0 outside, beyond 1e-6) or within 1e-12 of the bounding-box diameter of
/// a triangle.
void check_exterior_surface(const Surface& s, const Eigen::Ref<const Vertices>& points) {
  const Index count = points.rows(), m = s.size();
  const double on = 1e-12 * s.bounding_diameter();
  Index bad = count;
#pragma omp parallel for schedule(dynamic, 16) reduction(min : bad)
  for (Index i = 0; i < count; ++i) {
    const Vec3 z{points(i, 0), points(i, 1), points(i, 2)};
    double omega = 0.0;
    bool on_gamma = false;
    for (Index t = 0; t < m && !on_gamma; ++t) {
      const Triangle& T = s.triangle(t);
      omega += solid_angle(T, z);
      on_gamma = norm(z - T.c) <= T.radius + on && triangle_distance(T, z) <= on;
    }
    if (on_gamma || std::abs(omega) > 1e-6) bad = std::min(bad, i);
  }
  if (bad < count) refuse_interior_point(points, bad);
}

/// Calls f(x, y, weight) at the nodes of the rules on the pieces of a triangle with vertices
/// (x[k], y[k]) in its plane, in coordinates from the foot of z (z at the normal distance
/// |qn| from the plane), split into four until z is kPointSplitDiameters of a piece's
/// diameters away, each piece integrated by point_rule (as surface_potentials.cpp does; the
/// foot-centred coordinates as in 2D).
template <class F>
void triangle_nodes(double qn, const double x[3], const double y[3], int depth, const F& f) {
  const double cx = (x[0] + x[1] + x[2]) / 3.0, cy = (y[0] + y[1] + y[2]) / 3.0;
  double diam = 0.0, radius = 0.0;
  for (int k = 0; k < 3; ++k) {
    diam = std::max(diam, sq(x[(k + 1) % 3] - x[k]) + sq(y[(k + 1) % 3] - y[k]));
    radius = std::max(radius, sq(x[k] - cx) + sq(y[k] - cy));
  }
  diam = std::sqrt(diam);  // from the squares
  radius = std::sqrt(radius);
  const TriangleRule* rule = point_rule((std::sqrt(cx * cx + cy * cy + qn * qn) - radius) / diam);
  if (rule == nullptr && depth >= kMaxDepth) rule = point_rule(kPointSplitDiameters);
  if (rule == nullptr) {  // split at the edge midpoints
    const double mx[3] = {0.5 * (x[0] + x[1]), 0.5 * (x[1] + x[2]), 0.5 * (x[2] + x[0])};
    const double my[3] = {0.5 * (y[0] + y[1]), 0.5 * (y[1] + y[2]), 0.5 * (y[2] + y[0])};
    const double x4[4][3] = {{x[0], mx[0], mx[2]}, {mx[0], x[1], mx[1]}, {mx[2], mx[1], x[2]}, {mx[0], mx[1], mx[2]}};
    const double y4[4][3] = {{y[0], my[0], my[2]}, {my[0], y[1], my[1]}, {my[2], my[1], y[2]}, {my[0], my[1], my[2]}};
    for (int p = 0; p < 4; ++p) triangle_nodes(qn, x4[p], y4[p], depth + 1, f);
    return;
  }
  const TriangleRule& r = *rule;
  const double ax = x[1] - x[0], ay = y[1] - y[0], bx = x[2] - x[0], by = y[2] - y[0];
  const double jac = std::abs(ax * by - bx * ay);  // the rule's weights sum to 1/2
  for (int p = 0; p < r.size(); ++p) {
    const double u = r.s[static_cast<std::size_t>(p)], v = r.t[static_cast<std::size_t>(p)];
    f(x[0] + u * ax + v * bx, y[0] + u * ay + v * by, jac * r.w[static_cast<std::size_t>(p)]);
  }
}

template <bool Stress>
Matrix evaluate(const Surface& surface, const Lame& medium, const Eigen::Ref<const Vector>& dirichlet,
                const Eigen::Ref<const Vector>& traction, const Eigen::Ref<const Vertices>& points,
                const Eigen::Ref<const Vector>& a, Space space) {
  const Index count = points.rows(), m = surface.size();
  check_data(3, surface.vertices(), m, medium, dirichlet, traction, a, space, points.allFinite());
  check_exterior_surface(surface, points);  // before any work
  const Constants k = constants(medium, 3);
  Matrix out(count, Stress ? 9 : 3);
  // per triangle: the data w = v - a and t at its vertices, [vertex][component], and the
  // orthonormal frame (b1, b2, n) of its plane
  struct Local {
    double w[3][3], t[3][3];
    Vec3 b1, b2;
  };
  std::vector<Local> local(static_cast<std::size_t>(m));
  for (Index j = 0; j < m; ++j) {
    const Triangle& T = surface.triangle(j);
    Local& L = local[static_cast<std::size_t>(j)];
    for (int b = 0; b < 3; ++b) {
      const Index v = 3 * T.v[static_cast<std::size_t>(b)], c = space == Space::P1 ? v : 3 * j;
      for (int l = 0; l < 3; ++l) {
        L.w[b][l] = dirichlet(v + l) - a(l);
        L.t[b][l] = traction(c + l);
      }
    }
    L.b1 = (1.0 / norm(T.p[1] - T.p[0])) * (T.p[1] - T.p[0]);
    L.b2 = cross(T.n, L.b1);
  }
#pragma omp parallel for schedule(dynamic, 4)
  for (Index i = 0; i < count; ++i) {
    const Vec3 z{points(i, 0), points(i, 1), points(i, 2)};
    Sums<3> sums;
    for (Index j = 0; j < m; ++j) {
      const Triangle& T = surface.triangle(j);
      const Local& L = local[static_cast<std::size_t>(j)];
      const double n_y[3] = {T.n.x, T.n.y, T.n.z};
      const Vec3 b1 = L.b1, b2 = L.b2;
      // the triangle in the frame (b1, b2, n) from the foot of z: vertices (x, y), r = z - y =
      // qn n - X b1 - Y b2 at the node (X, Y); qn from the vertex nearest to z, so that a
      // vertex near z is the same vector from z in all its triangles (as in 2D)
      double x[3], y[3], qn = 0.0, nearest = std::numeric_limits<double>::infinity();
      for (int b = 0; b < 3; ++b) {
        const Vec3 e = T.p[b] - z;
        const double e2 = dot(e, e);
        x[b] = dot(e, b1);
        y[b] = dot(e, b2);
        if (e2 < nearest) {
          nearest = e2;
          qn = -dot(e, T.n);
        }
      }
      // barycentric coordinates (s, t) of vertices 1 and 2 from (X - x0, Y - y0)
      const double ax = x[1] - x[0], ay = y[1] - y[0], bx = x[2] - x[0], by = y[2] - y[0];
      const double inv_det = 1.0 / (ax * by - bx * ay);
      triangle_nodes(qn, x, y, 0, [&](double X, double Y, double weight) {
        const double dx = X - x[0], dy = Y - y[0];
        const double s = (by * dx - bx * dy) * inv_det, tt = (ax * dy - ay * dx) * inv_det;
        const double l[3] = {1.0 - s - tt, s, tt};
        const double r[3] = {qn * T.n.x - X * b1.x - Y * b2.x, qn * T.n.y - X * b1.y - Y * b2.y,
                             qn * T.n.z - X * b1.z - Y * b2.z};
        double wy[3], ty[3];
        for (int c = 0; c < 3; ++c) {
          wy[c] = l[0] * L.w[0][c] + l[1] * L.w[1][c] + l[2] * L.w[2][c];
          ty[c] = l[0] * L.t[0][c] + l[1] * L.t[1][c] + l[2] * L.t[2][c];
        }
        add_node<3, Stress>(k, r, n_y, wy, ty, weight, sums);
      });
    }
    store<3, Stress>(k, sums, a, i, out);
  }
  return out;
}

}  // namespace

std::array<double, 3> lame_double_layer_kernel(const Lame& m, int d, const double* r, const double* n,
                                               const double* w) {
  std::array<double, 3> F{};
  const double r2 = r[0] * r[0] + r[1] * r[1] + (d == 3 ? r[2] * r[2] : 0.0);
  if (d == 3)
    double_layer_f<3>(constants(m, 3), r, r2, inverse_power<3>(r2), n, w, F.data());
  else
    double_layer_f<2>(constants(m, 2), r, r2, inverse_power<2>(r2), n, w, F.data());
  return F;
}

Mat3 lame_double_layer_gradient_kernel(const Lame& m, int d, const double* r, const double* n, const double* w) {
  Mat3 out{};
  if (d == 3) {
    double G[3][3] = {};
    add_double_layer_g<3>(constants(m, 3), r, n, w, 1.0, G);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out[i][j] = G[i][j];
  } else {
    double G[2][2] = {};
    add_double_layer_g<2>(constants(m, 2), r, n, w, 1.0, G);
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) out[i][j] = G[i][j];
  }
  return out;
}

Matrix exterior_field(LameField field, const Polygon& polygon, const Lame& medium,
                      const Eigen::Ref<const Vector>& dirichlet, const Eigen::Ref<const Vector>& traction,
                      const Eigen::Ref<const Points>& points, const Eigen::Ref<const Vector>& a, Space traction_space) {
  if (field == LameField::Stress)
    return evaluate<true>(polygon, medium, dirichlet, traction, points, a, traction_space);
  return evaluate<false>(polygon, medium, dirichlet, traction, points, a, traction_space);
}

Matrix exterior_field(LameField field, const Surface& surface, const Lame& medium,
                      const Eigen::Ref<const Vector>& dirichlet, const Eigen::Ref<const Vector>& traction,
                      const Eigen::Ref<const Vertices>& points, const Eigen::Ref<const Vector>& a,
                      Space traction_space) {
  if (field == LameField::Stress)
    return evaluate<true>(surface, medium, dirichlet, traction, points, a, traction_space);
  return evaluate<false>(surface, medium, dirichlet, traction, points, a, traction_space);
}

}  // namespace bem
