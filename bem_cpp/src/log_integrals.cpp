#include "bem/log_integrals.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace bem {

namespace {

/// P_p(x) and P_p'(x) by the three-term recurrence.
std::pair<double, double> legendre(int p, double x) {
  double p0 = 1.0, p1 = x;
  for (int k = 2; k <= p; ++k) {
    const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
    p0 = p1;
    p1 = p2;
  }
  const double pp = p == 1 ? x : p1;
  const double pm = p == 1 ? 1.0 : p0;
  return {pp, p * (x * pp - pm) / (x * x - 1.0)};
}

GaussRule compute_gauss_legendre(int p) {
  GaussRule rule;
  rule.size = p;
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < p; ++i) {
    // Newton's method on P_p from the Tricomi initial guess (node i, descending in x).
    double x = std::cos(pi * (i + 0.75) / (p + 0.5));
    for (int it = 0; it < 100; ++it) {
      const auto [value, slope] = legendre(p, x);
      const double dx = value / slope;
      x -= dx;
      if (std::abs(dx) <= 1e-17) break;
    }
    const double dp = legendre(p, x).second;  // derivative at the converged node
    // Map [-1, 1] -> [0, 1]: ascending nodes, weights summing to 1.
    rule.x[static_cast<std::size_t>(i)] = 0.5 * (1.0 - x);
    rule.w[static_cast<std::size_t>(i)] = 1.0 / ((1.0 - x * x) * dp * dp);
  }
  return rule;
}

/// int_0^a s^q log s ds.
double power_log_integral(int q, double a) {
  const double q1 = q + 1.0;
  return std::pow(a, q1) / q1 * (std::log(a) - 1.0 / q1);
}

void clear(double (&m)[2][2]) { m[0][0] = m[0][1] = m[1][0] = m[1][1] = 0.0; }

template <int P, bool WithK>
void far_blocks_fixed(const Panel& pi, const Panel& pj, PairBlocks& out) {
  const GaussRule& g = gauss_legendre(P);
  double si[P], tj[P], wi0[P], wi1[P], wj0[P], wj1[P];
  for (int q = 0; q < P; ++q) {
    const double x = g.x[static_cast<std::size_t>(q)], w = g.w[static_cast<std::size_t>(q)];
    si[q] = x * pi.h;
    tj[q] = x * pj.h;
    wi0[q] = w * (1.0 - x) * pi.h;
    wi1[q] = w * x * pi.h;
    wj0[q] = w * (1.0 - x) * pj.h;
    wj1[q] = w * x * pj.h;
  }
  const Vec2 d0 = pi.a - pj.a;
  // Numerators as affine functions of the local coordinate: accurate even when tiny.
  const double dj0 = dot(d0, pj.n), dj1 = dot(pi.t, pj.n);   // (x - a_j).n_j
  const double di0 = -dot(d0, pi.n), di1 = dot(pj.t, pi.n);  // (y - a_i).n_i
  double v00 = 0, v01 = 0, v10 = 0, v11 = 0;
  double k00 = 0, k01 = 0, k10 = 0, k11 = 0;
  double q0[P] = {}, q1[P] = {};
  for (int a = 0; a < P; ++a) {
    const Vec2 xa = d0 + si[a] * pi.t;
    double g0 = 0, g1 = 0, c0 = 0, c1 = 0;
    for (int b = 0; b < P; ++b) {
      const double rx = xa.x - tj[b] * pj.t.x, ry = xa.y - tj[b] * pj.t.y;
      const double r2 = rx * rx + ry * ry;
      const double f = 0.5 * std::log(r2);
      g0 += wj0[b] * f;
      g1 += wj1[b] * f;
      if constexpr (WithK) {
        const double inv = 1.0 / r2;
        c0 += wj0[b] * inv;
        c1 += wj1[b] * inv;
        q0[b] += wi0[a] * inv;
        q1[b] += wi1[a] * inv;
      }
    }
    v00 += wi0[a] * g0;
    v01 += wi0[a] * g1;
    v10 += wi1[a] * g0;
    v11 += wi1[a] * g1;
    if constexpr (WithK) {
      const double dj = dj0 + si[a] * dj1;
      k00 += wi0[a] * dj * c0;
      k01 += wi0[a] * dj * c1;
      k10 += wi1[a] * dj * c0;
      k11 += wi1[a] * dj * c1;
    }
  }
  out.v[0][0] = v00;
  out.v[0][1] = v01;
  out.v[1][0] = v10;
  out.v[1][1] = v11;
  if constexpr (WithK) {
    out.kij[0][0] = k00;
    out.kij[0][1] = k01;
    out.kij[1][0] = k10;
    out.kij[1][1] = k11;
    double m00 = 0, m01 = 0, m10 = 0, m11 = 0;
    for (int b = 0; b < P; ++b) {
      const double di = di0 + tj[b] * di1;
      m00 += wj0[b] * di * q0[b];
      m01 += wj0[b] * di * q1[b];
      m10 += wj1[b] * di * q0[b];
      m11 += wj1[b] * di * q1[b];
    }
    out.kji[0][0] = m00;
    out.kji[0][1] = m01;
    out.kji[1][0] = m10;
    out.kji[1][1] = m11;
  }
}

template <bool WithK>
void far_blocks_dispatch(const Panel& pi, const Panel& pj, int p, PairBlocks& out) {
  switch (p) {
    case 1:
      return far_blocks_fixed<1, WithK>(pi, pj, out);
    case 2:
      return far_blocks_fixed<2, WithK>(pi, pj, out);
    case 3:
      return far_blocks_fixed<3, WithK>(pi, pj, out);
    case 4:
      return far_blocks_fixed<4, WithK>(pi, pj, out);
    case 5:
      return far_blocks_fixed<5, WithK>(pi, pj, out);
    case 6:
      return far_blocks_fixed<6, WithK>(pi, pj, out);
    case 7:
      return far_blocks_fixed<7, WithK>(pi, pj, out);
    case 8:
      return far_blocks_fixed<8, WithK>(pi, pj, out);
    case 10:
      return far_blocks_fixed<10, WithK>(pi, pj, out);
    case 12:
      return far_blocks_fixed<12, WithK>(pi, pj, out);
    case 16:
      return far_blocks_fixed<16, WithK>(pi, pj, out);
    case 20:
      return far_blocks_fixed<20, WithK>(pi, pj, out);
    case 24:
      return far_blocks_fixed<24, WithK>(pi, pj, out);
    default:
      throw std::invalid_argument("far_blocks: unsupported number of Gauss points");
  }
}

}  // namespace

const GaussRule& gauss_legendre(int p) {
  static const std::vector<GaussRule> rules = [] {
    std::vector<GaussRule> r(kMaxGaussPoints + 1);
    for (int q = 1; q <= kMaxGaussPoints; ++q) r[static_cast<std::size_t>(q)] = compute_gauss_legendre(q);
    return r;
  }();
  if (p < 1 || p > kMaxGaussPoints) throw std::invalid_argument("gauss_legendre: p out of range");
  return rules[static_cast<std::size_t>(p)];
}

const std::array<double, kMaxGaussPoints + 1>& gauss_thresholds() {
  static const std::array<double, kMaxGaussPoints + 1> y = [] {
    std::array<double, kMaxGaussPoints + 1> t{};
    for (int p = 1; p <= kMaxGaussPoints; ++p) {
      const double rho = std::pow(kQuadratureTolerance, -1.0 / (2.0 * p));
      t[static_cast<std::size_t>(p)] = 0.5 * (rho - 1.0 / rho);
    }
    return t;
  }();
  return y;
}

int gauss_points_for(double distance, double length, int max_points) {
  const auto& t = gauss_thresholds();
  const double y = 2.0 * distance / length;
  for (int p = 1; p <= max_points; ++p)
    if (y >= t[static_cast<std::size_t>(p)]) return p;
  return 0;
}

SegmentMoments segment_moments(Vec2 p, Vec2 a, Vec2 e, double h, Vec2 nu) {
  const Vec2 q = p - a;
  const double tau = dot(q, e), d = dot(q, nu);
  const double u0 = -tau, u1 = h - tau;
  const double r0s = u0 * u0 + d * d, r1s = u1 * u1 + d * d;
  // r^2 log r^2 -> 0 and u log r^2 -> 0 at an endpoint (r = 0 forces u = d = 0).
  const double l0 = r0s > 0 ? std::log(r0s) : 0.0;
  const double l1 = r1s > 0 ? std::log(r1s) : 0.0;
  // Signed angle subtended by the segment: atan2(cross, dot) of the vectors p->a, p->b.
  const double theta = d != 0 ? std::atan2(d * h, d * d + u0 * u1) : 0.0;
  SegmentMoments m;
  // int (1/2) log(u^2 + d^2) du = (1/2) u log(u^2 + d^2) - u + d atan(u/d)
  m.log0 = 0.5 * (u1 * l1 - u0 * l0) - h + d * theta;
  // int (u + tau)(1/2) log(u^2 + d^2) du, with int u log(u^2+d^2)/2 = ((u^2+d^2) log(u^2+d^2) - u^2)/4
  m.log1 = 0.25 * (r1s * l1 - r0s * l0 - h * (u1 + u0)) + tau * m.log0;
  const double d_ell = d != 0 ? d * (l1 - l0) : 0.0;  // d log(r1^2/r0^2)
  m.ang0 = theta;
  m.ang1 = 0.5 * d_ell + tau * theta;
  m.ang2 = d * h + tau * d_ell + (tau * tau - d * d) * theta;
  return m;
}

void coincident_blocks(const Panel& p, PairBlocks& out) {
  // int_0^1 int_0^1 log|s - t| phi_a(s) phi_b(t) = -7/16 (a = b), -5/16 (a != b);
  // scaling by h adds (1/4) log h times h^2.
  const double h2 = p.h * p.h, lh = std::log(p.h);
  out.v[0][0] = out.v[1][1] = h2 * (0.25 * lh - 7.0 / 16.0);
  out.v[0][1] = out.v[1][0] = h2 * (0.25 * lh - 5.0 / 16.0);
  clear(out.kij);  // (x - y).n = 0 on a straight panel
  clear(out.kji);
}

namespace {

/// The part [s0, s1] of panel p (same tangent and normal, no re-rounding).
Panel sub_panel(const Panel& p, double s0, double s1) {
  Panel q = p;
  q.a = p.a + s0 * p.t;
  q.b = p.a + s1 * p.t;
  q.m = 0.5 * (q.a + q.b);
  q.h = s1 - s0;
  return q;
}

/// out += blocks of a sub-pair mapped to the full panels: on the part [s0, s1] of a
/// panel of length h, phi_k = sum_l R[k][l] psi_l with psi the shapes of the part and
/// R[k][l] = phi_k(endpoint l) (ri for panel i, rj for panel j).
void add_restricted(const PairBlocks& sub, const double (&ri)[2][2], const double (&rj)[2][2], PairBlocks& out) {
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int l = 0; l < 2; ++l)
        for (int m = 0; m < 2; ++m) {
          const double w = ri[a][l] * rj[b][m];
          out.v[a][b] += w * sub.v[l][m];
          out.kij[a][b] += w * sub.kij[l][m];
          out.kji[b][a] += w * sub.kji[m][l];
        }
}

void restriction(double h, double s0, double s1, double (&r)[2][2]) {
  r[0][0] = 1.0 - s0 / h;
  r[0][1] = 1.0 - s1 / h;
  r[1][0] = s0 / h;
  r[1][1] = s1 / h;
}

void adjacent_equal_blocks(const Panel& pi, const Panel& pj, PairRelation relation, PairBlocks& out);

}  // namespace

void adjacent_blocks(const Panel& pi, const Panel& pj, PairRelation relation, PairBlocks& out) {
  // The Duffy formulas see a segment of length b/a from unit distance; for very unequal
  // lengths they lose digits to cancellation. Then the longer panel is split at the
  // shorter length from the common node: an adjacent pair of equal lengths plus a
  // separated pair, mapped back to the full panels' shape functions.
  constexpr double kMaxRatio = 2.0;
  if (pi.h <= kMaxRatio * pj.h && pj.h <= kMaxRatio * pi.h) return adjacent_equal_blocks(pi, pj, relation, out);
  const bool i_vertex_at_end = relation == PairRelation::EndToStart;
  const bool split_i = pi.h > pj.h;
  const Panel& longer = split_i ? pi : pj;
  const double m = split_i ? pj.h : pi.h;
  // Part of the longer panel next to the common node, and the rest.
  const bool vertex_at_end = split_i ? i_vertex_at_end : !i_vertex_at_end;
  const double near0 = vertex_at_end ? longer.h - m : 0.0, near1 = vertex_at_end ? longer.h : m;
  const double far0 = vertex_at_end ? 0.0 : m, far1 = vertex_at_end ? longer.h - m : longer.h;
  const Panel near_part = sub_panel(longer, near0, near1), far_part = sub_panel(longer, far0, far1);
  double r_near[2][2], r_far[2][2];
  restriction(longer.h, near0, near1, r_near);
  restriction(longer.h, far0, far1, r_far);
  const double identity[2][2] = {{1.0, 0.0}, {0.0, 1.0}};

  clear(out.v);
  clear(out.kij);
  clear(out.kji);
  PairBlocks sub;
  if (split_i) {
    adjacent_equal_blocks(near_part, pj, relation, sub);
    add_restricted(sub, r_near, identity, out);
    pair_blocks(far_part, pj, PairRelation::Separated, true, sub);
    add_restricted(sub, r_far, identity, out);
  } else {
    adjacent_equal_blocks(pi, near_part, relation, sub);
    add_restricted(sub, identity, r_near, out);
    pair_blocks(pi, far_part, PairRelation::Separated, true, sub);
    add_restricted(sub, identity, r_far, out);
  }
}

namespace {

void adjacent_equal_blocks(const Panel& pi, const Panel& pj, PairRelation relation, PairBlocks& out) {
  // Common node O at the origin, x = s e1 on panel i (s in [0, a]), y = t e2 on
  // panel j (t in [0, b]). Duffy split: t = r s w (r = b/a) on the triangle t <= r s
  // and s = r' t w (r' = a/b) on the other one, w in [0, 1]. Then
  //   log|x - y| = log s + (1/2) log|e1 - r w e2|^2   (and symmetrically),
  // and every w-integral is a moment of a segment of length r seen from the point e1
  // (or of length r' seen from e2), see segment_moments.
  const bool i_vertex_at_end = relation == PairRelation::EndToStart;
  const Vec2 e1 = i_vertex_at_end ? -1.0 * pi.t : pi.t;
  const Vec2 e2 = i_vertex_at_end ? pj.t : -1.0 * pj.t;
  const double a = pi.h, b = pj.h, r = b / a, rp = a / b;
  const Vec2 origin{0.0, 0.0};
  const SegmentMoments s1 = segment_moments(e1, origin, e2, r, rotate_cw(e2));
  const SegmentMoments s2 = segment_moments(e2, origin, e1, rp, rotate_cw(e1));
  const double s1log[2] = {s1.log0, s1.log1}, s2log[2] = {s2.log0, s2.log1};
  const double s1ang[3] = {s1.ang0, s1.ang1, s1.ang2}, s2ang[3] = {s2.ang0, s2.ang1, s2.ang2};
  // The normals of the panels are +-rotate_cw(e): the angle moments change sign with them.
  const double sj = dot(pj.n, rotate_cw(e2)), si = dot(pi.n, rotate_cw(e1));

  // Monomial moments: I[k][m] = int int s^k t^m log|x - y|,
  // KIJ[k][m] = int int s^k t^m (x - y).n_j/|x - y|^2, KJI[k][m] = int int t^k s^m (y - x).n_i/|x - y|^2.
  double I[2][2], KIJ[2][2], KJI[2][2];
  for (int k = 0; k < 2; ++k)
    for (int m = 0; m < 2; ++m) {
      const int q = k + m + 1;
      I[k][m] = std::pow(r, m + 1) * power_log_integral(q, a) / (m + 1) + std::pow(a, q + 1) / (q + 1) * s1log[m] +
                std::pow(rp, k + 1) * power_log_integral(q, b) / (k + 1) + std::pow(b, q + 1) / (q + 1) * s2log[k];
      // (x - y).n_j = s (e1.n_j): the kernel is homogeneous of degree -1, the Duffy
      // Jacobian removes the singularity and leaves angle moments.
      KIJ[k][m] = std::pow(a, q) / q * sj * s1ang[m] - std::pow(b, q) / q * sj * s2ang[k + 1];
      KJI[k][m] = std::pow(b, q) / q * si * s2ang[m] - std::pow(a, q) / q * si * s1ang[k + 1];
    }

  // Shape functions as c0 + c1 * (distance from the common node).
  const AdjacentShapes shapes(a, b, i_vertex_at_end);
  const auto& ci = shapes.ci;
  const auto& cj = shapes.cj;
  for (int al = 0; al < 2; ++al)
    for (int be = 0; be < 2; ++be) {
      double v = 0, kij = 0, kji = 0;
      for (int k = 0; k < 2; ++k)
        for (int m = 0; m < 2; ++m) {
          v += ci[al][k] * cj[be][m] * I[k][m];
          kij += ci[al][k] * cj[be][m] * KIJ[k][m];
          kji += cj[be][k] * ci[al][m] * KJI[k][m];
        }
      out.v[al][be] = v;
      out.kij[al][be] = kij;
      out.kji[be][al] = kji;
    }
}

}  // namespace

void near_blocks(const Panel& pi, const Panel& pj, bool with_k, PairBlocks& out) {
  clear(out.v);
  clear(out.kij);
  clear(out.kji);
  // Outer on panel i, inner on panel j (analytic near it, Gauss where panel j is short
  // compared with the distance, to avoid the cancellation of the closed forms there).
  near_outer(pi, pj, [&](double s, double w) {
    const PointPanelMoments m = point_panel_moments(pi.a + s * pi.t, pj);
    const double phi[2] = {w * (1.0 - s / pi.h), w * (s / pi.h)};
    for (int al = 0; al < 2; ++al)
      for (int be = 0; be < 2; ++be) {
        out.v[al][be] += phi[al] * m.log[be];
        out.kij[al][be] += phi[al] * m.dl[be];
      }
  });
  if (!with_k) return;
  // Outer on panel j, inner on panel i: kji.
  near_outer(pj, pi, [&](double t, double w) {
    const PointPanelMoments m = point_panel_moments(pj.a + t * pj.t, pi);
    const double phi[2] = {w * (1.0 - t / pj.h), w * (t / pj.h)};
    for (int be = 0; be < 2; ++be)
      for (int al = 0; al < 2; ++al) out.kji[be][al] += phi[be] * m.dl[al];
  });
}

void far_blocks(const Panel& pi, const Panel& pj, int p, bool with_k, PairBlocks& out) {
  if (with_k)
    far_blocks_dispatch<true>(pi, pj, p, out);
  else
    far_blocks_dispatch<false>(pi, pj, p, out);
}

void pair_blocks(const Panel& pi, const Panel& pj, PairRelation relation, bool with_k, PairBlocks& out) {
  integrate_pair(
      pi, pj, relation, [&] { coincident_blocks(pi, out); }, [&] { adjacent_blocks(pi, pj, relation, out); },
      [&](int p) { far_blocks(pi, pj, p, with_k, out); }, [&] { near_blocks(pi, pj, with_k, out); });
}

PointPanelMoments point_panel_moments(Vec2 z, const Panel& p) {
  PointPanelMoments out;
  const double separation = std::sqrt(dot(z - p.m, z - p.m)) - 0.5 * p.h;
  const int q = separation > 0 ? gauss_points_for(separation, p.h, kMaxFarPoints) : 0;
  if (q == 0) {
    const SegmentMoments m = segment_moments(z, p.a, p.t, p.h, p.n);
    out.log[0] = m.log0 - m.log1 / p.h;
    out.log[1] = m.log1 / p.h;
    out.dl[0] = m.ang0 - m.ang1 / p.h;
    out.dl[1] = m.ang1 / p.h;
    return out;
  }
  const GaussRule& g = gauss_legendre(q);
  const Vec2 d0 = z - p.a;
  const double dn = dot(d0, p.n);  // (z - y).n is the same for all y on the panel
  out.log[0] = out.log[1] = out.dl[0] = out.dl[1] = 0.0;
  for (int k = 0; k < q; ++k) {
    const double x = g.x[static_cast<std::size_t>(k)], w = g.w[static_cast<std::size_t>(k)] * p.h;
    const Vec2 r = d0 - (x * p.h) * p.t;
    const double r2 = dot(r, r);
    const double f = 0.5 * std::log(r2), kd = dn / r2;
    out.log[0] += w * (1.0 - x) * f;
    out.log[1] += w * x * f;
    out.dl[0] += w * (1.0 - x) * kd;
    out.dl[1] += w * x * kd;
  }
  return out;
}

}  // namespace bem
