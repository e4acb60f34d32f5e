#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "bem/log_integrals.hpp"

using namespace bem;

namespace {

/// int_lo^hi f(u) du by Gauss-Legendre (24 points) on pieces graded geometrically
/// toward u = 0, where f has its nearest complex singularities +- i d: every piece lies
/// at least about its own length away from them, so each piece is exact to round-off.
/// (Integrating in u = t - tau, not t, keeps points near the singularity exact.)
double graded_integral(const std::function<double(double)>& f, double lo, double hi, double d) {
  const GaussRule& g = gauss_legendre(24);
  auto piece = [&](double a, double b) {
    double s = 0;
    for (int q = 0; q < 24; ++q) s += (b - a) * g.w[q] * f(a + (b - a) * g.x[q]);
    return s;
  };
  const double c = std::clamp(0.0, lo, hi);
  double total = 0;
  for (double end : {lo, hi}) {
    double a = c, len = std::max(0.5 * d, 1e-300);
    while (a != end) {
      const double b = end < c ? std::max(end, a - len) : std::min(end, a + len);
      total += piece(std::min(a, b), std::max(a, b));
      a = b;
      len *= 2;
    }
  }
  return total;
}

double max_abs_diff(const double (&a)[2][2], const double (&b)[2][2]) {
  double m = 0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) m = std::max(m, std::abs(a[i][j] - b[i][j]));
  return m;
}

double max_abs(const double (&a)[2][2]) {
  double m = 0;
  for (auto& row : a)
    for (double x : row) m = std::max(m, std::abs(x));
  return m;
}

double sum(const double (&a)[2][2]) { return a[0][0] + a[0][1] + a[1][0] + a[1][1]; }

}  // namespace

TEST(GaussLegendre, ExactForPolynomials) {
  for (int p = 1; p <= kMaxGaussPoints; ++p) {
    const GaussRule& g = gauss_legendre(p);
    for (int k = 0; k <= 2 * p - 1; ++k) {
      double s = 0;
      for (int q = 0; q < p; ++q) s += g.w[q] * std::pow(g.x[q], k);
      EXPECT_NEAR(s, 1.0 / (k + 1), 2e-15) << "p=" << p << " k=" << k;
    }
  }
}

TEST(GaussLegendre, PointsFromDistance) {
  // Farther panels need fewer points; the worst-case error bound rho^(-2p) holds.
  int previous = kMaxGaussPoints + 1;
  for (double ratio : {1.0, 3.0, 10.0, 100.0, 1e4, 1e9}) {
    const int p = gauss_points_for(ratio, 1.0, kMaxGaussPoints);
    ASSERT_GT(p, 0);
    EXPECT_LE(p, previous);
    const double y = 2 * ratio, rho = y + std::sqrt(1 + y * y);
    EXPECT_LE(std::pow(rho, -2 * p), kQuadratureTolerance * (1 + 1e-12));
    previous = p;
  }
  EXPECT_EQ(gauss_points_for(0.5, 1.0, kMaxFarPoints), 0);  // too close: near field
}

TEST(SegmentMoments, AgainstGradedQuadrature) {
  const double h = 0.7;
  // Oblique segment, points off its line (d != 0), near and far, also near an end.
  // Axis-aligned segment, points exactly on its line (d = 0): beyond the ends and at one.
  struct Case {
    Vec2 e, nu, off;  // p = a + off.x e + off.y nu, i.e. tau = off.x, d = off.y
  };
  const Vec2 e1{0.6, 0.8}, n1{0.8, -0.6}, e2{1.0, 0.0}, n2{0.0, -1.0};
  for (const Case& c : {Case{e1, n1, {0.3, 0.5}}, Case{e1, n1, {-1.0, 0.2}}, Case{e1, n1, {0.35, 1e-3}},
                        Case{e1, n1, {0.35, -1e-7}}, Case{e1, n1, {0.9, 1e-4}}, Case{e1, n1, {0.7, 0.3}},
                        Case{e2, n2, {1.2, 0.0}}, Case{e2, n2, {-0.5, 0.0}}, Case{e2, n2, {0.7, 0.0}}}) {
    const Vec2 a{0.1, -0.2};
    const Vec2 p = a + c.off.x * c.e + c.off.y * c.nu;
    // tau and d of the rounded point (what the formulas see).
    const double tau = dot(p - a, c.e), d = dot(p - a, c.nu);
    const SegmentMoments m = segment_moments(p, a, c.e, h, c.nu);
    // Integrands in u = t - tau.
    auto lg = [&](double u) { return 0.5 * std::log(u * u + d * d); };
    auto ker = [&](double u) { return d / (u * u + d * d); };
    auto ref = [&](const std::function<double(double)>& f) { return graded_integral(f, -tau, h - tau, std::abs(d)); };
    const double scale = std::abs(ref(lg));
    EXPECT_NEAR(m.log0, ref(lg), 1e-14 * scale);
    EXPECT_NEAR(m.log1, ref([&](double u) { return (u + tau) * lg(u); }), 1e-14 * scale);
    if (c.off.y == 0) {  // principal value on the line: the kernel vanishes identically
      EXPECT_EQ(m.ang0, 0.0);
      EXPECT_EQ(m.ang1, 0.0);
      continue;
    }
    const double ascale = std::abs(ref(ker));
    EXPECT_NEAR(m.ang0, ref(ker), 1e-13 * ascale);
    EXPECT_NEAR(m.ang1, ref([&](double u) { return (u + tau) * ker(u); }), 1e-13 * ascale * h);
    EXPECT_NEAR(m.ang2, ref([&](double u) { return (u + tau) * (u + tau) * ker(u); }), 1e-13 * ascale * h * h);
  }
}

TEST(PairBlocks, CoincidentClosedForm) {
  // int int log|s - t| over [0, h]^2 = h^2 (log h - 3/2) (docs/method.md section 9 without
  // the factor -1/(2 pi)); the P1 moments add up to it.
  for (double h : {1.0, 0.01, 0.37}) {
    PairBlocks B;
    coincident_blocks(make_panel({0.2, 0.1}, {0.2 + 0.6 * h, 0.1 + 0.8 * h}), B);
    EXPECT_NEAR(sum(B.v), h * h * (std::log(h) - 1.5), 1e-15 * h * h * std::abs(std::log(h) - 1.5) + 1e-17);
    EXPECT_DOUBLE_EQ(B.v[0][1], B.v[1][0]);
    EXPECT_EQ(max_abs(B.kij), 0.0);
  }
}

TEST(PairBlocks, AdjacentClosedForms) {
  // Collinear continuation: int_0^1 int_0^1 log(s + t) = 2 log 2 - 3/2, K = 0.
  PairBlocks B;
  adjacent_blocks(make_panel({-1, 0}, {0, 0}), make_panel({0, 0}, {1, 0}), PairRelation::EndToStart, B);
  EXPECT_NEAR(sum(B.v), 2 * std::log(2.0) - 1.5, 1e-15);
  EXPECT_EQ(max_abs(B.kij), 0.0);
  EXPECT_EQ(max_abs(B.kji), 0.0);
  // Right angle: int_0^1 int_0^1 log sqrt(s^2 + t^2) = (log 2 - 3 + pi/2)/2.
  adjacent_blocks(make_panel({1, 0}, {0, 0}), make_panel({0, 0}, {0, 1}), PairRelation::EndToStart, B);
  EXPECT_NEAR(sum(B.v), 0.5 * (std::log(2.0) - 3 + M_PI / 2), 1e-15);
  // x = (s, 0) on panel i, y = (0, t) on panel j, n_j = (1, 0): (x - y).n_j = s.
  // int_0^1 int_0^1 s/(s^2 + t^2) dt ds = int_0^1 atan(1/s) ds = pi/4 + log(2)/2.
  EXPECT_NEAR(sum(B.kij), M_PI / 4 + 0.5 * std::log(2.0), 1e-15);
}

TEST(PairBlocks, SymmetryUnderExchange) {
  // v(i, j) = v(j, i)^T and kij(i, j) = kji(j, i), with different outer/inner roles.
  const Panel p = make_panel({0.0, 0.0}, {0.3, 0.05});
  for (const Panel& q :
       {make_panel({0.5, 0.2}, {0.35, 0.4}), make_panel({0.3, 0.05}, {0.1, 0.4}), make_panel({2.0, 1.0}, {1.9, 1.3})}) {
    const PairRelation r = (q.a.x == p.b.x && q.a.y == p.b.y) ? PairRelation::EndToStart : PairRelation::Separated;
    const PairRelation rs = r == PairRelation::EndToStart ? PairRelation::StartToEnd : PairRelation::Separated;
    PairBlocks B, C;
    pair_blocks(p, q, r, true, B);
    pair_blocks(q, p, rs, true, C);
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        EXPECT_NEAR(B.v[a][b], C.v[b][a], 1e-14 * max_abs(B.v));
        EXPECT_NEAR(B.kij[a][b], C.kji[a][b], 1e-14 * max_abs(B.kij));
        EXPECT_NEAR(B.kji[a][b], C.kij[a][b], 1e-14 * max_abs(B.kji));
      }
  }
}

TEST(PairBlocks, NearAndFarMethodsAgree) {
  // Independent methods (analytic inner + subdivided Gauss outer vs tensor Gauss with
  // 24 points) on a pair 1.5 lengths apart.
  const Panel p = make_panel({0.0, 0.0}, {0.2, 0.0});
  const Panel q = make_panel({0.5, 0.1}, {0.45, 0.29});
  PairBlocks N, F;
  near_blocks(p, q, true, N);
  far_blocks(p, q, 24, true, F);
  EXPECT_LT(max_abs_diff(N.v, F.v), 1e-15 * max_abs(N.v));
  EXPECT_LT(max_abs_diff(N.kij, F.kij), 1e-14 * max_abs(N.kij));
  EXPECT_LT(max_abs_diff(N.kji, F.kji), 1e-14 * max_abs(N.kji));
}

TEST(PairBlocks, AdjacentSplitIsConsistent) {
  // Panel j split at its midpoint: blocks(i, j) = restricted blocks(i, j1) + (i, j2),
  // where j1 is adjacent with length ratio 2 and j2 separated.
  const Panel pi = make_panel({0.0, 0.0}, {0.3, 0.0});
  const Vec2 c{0.3, 0.0}, end{0.5, 0.9};
  const Panel pj = make_panel(c, end), j1 = make_panel(c, 0.5 * (c + end)), j2 = make_panel(0.5 * (c + end), end);
  PairBlocks B, B1, B2;
  adjacent_blocks(pi, pj, PairRelation::EndToStart, B);
  adjacent_blocks(pi, j1, PairRelation::EndToStart, B1);
  pair_blocks(pi, j2, PairRelation::Separated, true, B2);
  // On j: phi_0 = psi_0 + psi_1/2 on j1, psi_1/2 on j2 (psi the halves' shapes), etc.
  for (int a = 0; a < 2; ++a) {
    const double v0 = B1.v[a][0] + 0.5 * B1.v[a][1] + 0.5 * B2.v[a][0];
    const double v1 = 0.5 * B1.v[a][1] + 0.5 * B2.v[a][0] + B2.v[a][1];
    EXPECT_NEAR(B.v[a][0], v0, 1e-15 * max_abs(B.v));
    EXPECT_NEAR(B.v[a][1], v1, 1e-15 * max_abs(B.v));
    const double k0 = B1.kij[a][0] + 0.5 * B1.kij[a][1] + 0.5 * B2.kij[a][0];
    const double k1 = 0.5 * B1.kij[a][1] + 0.5 * B2.kij[a][0] + B2.kij[a][1];
    EXPECT_NEAR(B.kij[a][0], k0, 1e-14 * max_abs(B.kij));
    EXPECT_NEAR(B.kij[a][1], k1, 1e-14 * max_abs(B.kij));
  }
}

TEST(PointPanelMoments, AnalyticAndGaussAgreeAtTheSwitch) {
  const Panel p = make_panel({0.0, 0.0}, {0.1, 0.05});
  const double h = p.h;
  for (double dist : {2.4, 2.6, 6.0}) {
    const Vec2 z = p.m + (dist * h + 0.5 * h) * p.n;
    const PointPanelMoments q = point_panel_moments(z, p);
    const SegmentMoments m = segment_moments(z, p.a, p.t, p.h, p.n);
    EXPECT_NEAR(q.log[0], m.log0 - m.log1 / h, 1e-14 * std::abs(m.log0));
    EXPECT_NEAR(q.log[1], m.log1 / h, 1e-14 * std::abs(m.log0));
    EXPECT_NEAR(q.dl[0], m.ang0 - m.ang1 / h, 1e-13 * std::abs(m.ang0));
    EXPECT_NEAR(q.dl[1], m.ang1 / h, 1e-13 * std::abs(m.ang0));
  }
}
