#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "bem/kelvin.hpp"
#include "bem/lame_polygon.hpp"
#include "bem/log_integrals.hpp"
#include "bem/operators.hpp"
#include "test_helpers.hpp"

using namespace bem;
using bem::test::dart;
using bem::test::kron2;
using bem::test::l_shape;

namespace {

/// The three rigid motions at the nodes: e_x, e_y, x -> (-y, x).
Matrix rigid_motions(const Polygon& poly) {
  const Index n = poly.size();
  Matrix Rm = Matrix::Zero(2 * n, 3);
  for (Index i = 0; i < n; ++i) {
    const Vec2 x = poly.panel(i).a;
    Rm(2 * i, 0) = 1.0;
    Rm(2 * i + 1, 1) = 1.0;
    Rm(2 * i, 2) = -x.y;
    Rm(2 * i + 1, 2) = x.x;
  }
  return Rm;
}

double inf_norm(const Matrix& A) { return A.cwiseAbs().rowwise().sum().maxCoeff(); }

/// A sum of Kelvin fields U(x - x_s) f_s (a force and a force dipole) with sources inside
/// Omega: an exterior elastic field, regular on Gamma.
struct KelvinField {
  Lame m;
  std::vector<Vec2> x, f;
  Vec2 u(Vec2 y) const {
    Vec2 out{0, 0};
    for (std::size_t s = 0; s < x.size(); ++s) {
      const double r[2] = {y.x - x[s].x, y.y - x[s].y};
      const Mat3 U = kelvin(m, 2, r);
      out = out + Vec2{U[0][0] * f[s].x + U[0][1] * f[s].y, U[1][0] * f[s].x + U[1][1] * f[s].y};
    }
    return out;
  }
  Vec2 t(Vec2 y, Vec2 n) const {
    Vec2 out{0, 0};
    const double nn[2] = {n.x, n.y};
    for (std::size_t s = 0; s < x.size(); ++s) {
      const double r[2] = {y.x - x[s].x, y.y - x[s].y};
      const Mat3 T = kelvin_traction(m, 2, r, nn);
      out = out + Vec2{T[0][0] * f[s].x + T[0][1] * f[s].y, T[1][0] * f[s].x + T[1][1] * f[s].y};
    }
    return out;
  }
};

KelvinField kelvin_field(const Lame& m, Vec2 x0) {
  const Vec2 e{0.6, 0.8};
  const double eps = 0.05;
  const Vec2 g{0.3 / eps, 0.5 / eps};
  return {m, {x0, x0 + eps * e, x0 - eps * e}, {{0.7, -0.4}, g, -1.0 * g}};
}

struct CalderonErrors {
  double l2;        ///< ||t_h - t||_L2(Gamma)
  double discrete;  ///< ||t_h - Q_h t||_L2(Gamma), Q_h the L2 projection onto the flux space
  double force;     ///< |int (t_h - t)|, the error of the resultant force
  double residual;  ///< ||W_h v + (K_h + M_h)^T Q_h t||_{M1^{-1}} / ||W_h v||_{M1^{-1}}
};

/// Solves V_h t_h = (K_h - M_h) v (v the nodal values of the field) and measures t_h
/// and the residual of the second Calderon identity (8-point Gauss rule on every panel).
CalderonErrors calderon(const Polygon& poly, const KelvinField& kf, Space s) {
  const Index n = poly.size();
  OperatorRequest req;
  req.single_layer = s;
  req.double_layer = s;
  req.hypersingular = true;
  const Operators ops = assemble(poly, kf.m, req);
  const Matrix M = kron2(mass(poly, s)), M1 = kron2(mass(poly, Space::P1));
  Vector v(2 * n);
  for (Index i = 0; i < n; ++i) {
    const Vec2 u = kf.u(poly.panel(i).a);
    v(2 * i) = u.x;
    v(2 * i + 1) = u.y;
  }
  const Vector th = ops.single_layer.llt().solve((ops.double_layer - M) * v);
  const GaussRule& g = gauss_legendre(8);
  double l2 = 0;
  Vector b = Vector::Zero(2 * n);  // b = int t psi_i
  Vec2 force{0, 0};
  for (Index i = 0; i < n; ++i) {
    const Panel& p = poly.panel(i);
    const Index i1 = (i + 1) % n;
    for (int q = 0; q < 8; ++q) {
      const double x = g.x[static_cast<std::size_t>(q)], w = g.w[static_cast<std::size_t>(q)] * p.h;
      const Vec2 t = kf.t(p.a + (x * p.h) * p.t, p.n);
      const double phi[2] = {s == Space::P0 ? 1.0 : 1.0 - x, s == Space::P0 ? 0.0 : x};
      const Index row[2] = {s == Space::P0 ? i : i, i1};
      Vec2 th_y{0, 0};
      for (int a = 0; a < 2; ++a) {
        th_y = th_y + phi[a] * Vec2{th(2 * row[a]), th(2 * row[a] + 1)};
        b(2 * row[a]) += w * phi[a] * t.x;
        b(2 * row[a] + 1) += w * phi[a] * t.y;
      }
      const Vec2 d = th_y - t;
      l2 += w * dot(d, d);
      force = force + w * d;
    }
  }
  const Matrix gram = kron2(s == Space::P0 ? Matrix(poly.lengths().asDiagonal()) : mass(poly, Space::P1));
  const Vector tq = gram.llt().solve(b), e = th - tq;
  const Vector res = ops.hypersingular * v + (ops.double_layer + M).transpose() * tq, wv = ops.hypersingular * v;
  const Eigen::LLT<Matrix> m1(M1);
  return {std::sqrt(l2), std::sqrt(e.dot(gram * e)), norm(force),
          std::sqrt(res.dot(m1.solve(res)) / wv.dot(m1.solve(wv)))};
}

/// Rigid motions, symmetry and definiteness (checks 1 of the Lame operators).
void check_rigid_motions(const Polygon& poly, const Lame& m, Space s) {
  OperatorRequest req;
  req.single_layer = s;
  req.double_layer = s;
  req.hypersingular = true;
  const Operators ops = assemble(poly, m, req);
  const Matrix &V = ops.single_layer, &K = ops.double_layer, &W = ops.hypersingular;
  const Matrix M = kron2(mass(poly, s));
  EXPECT_TRUE(V.isApprox(V.transpose(), 0.0));
  EXPECT_TRUE(W.isApprox(W.transpose(), 0.0));
  const Matrix Rm = rigid_motions(poly);
  const Matrix A = K - M;
  const Matrix S = 0.5 * (W + A.transpose() * V.llt().solve(A));
  EXPECT_EQ(V.llt().info(), Eigen::Success);
  EXPECT_EQ(S.llt().info(), Eigen::Success);
  for (int c = 0; c < 3; ++c) {
    const Vector r = Rm.col(c);
    const double rn = r.cwiseAbs().maxCoeff();
    EXPECT_LT((W * r).cwiseAbs().maxCoeff(), 1e-13 * inf_norm(W) * rn) << "rigid motion " << c;
    EXPECT_LT((K * r + M * r).cwiseAbs().maxCoeff(), 1e-13 * inf_norm(K) * rn) << "rigid motion " << c;
    EXPECT_GT(r.dot(S * r), 0.0);
  }
}

double order(double coarse, double fine) { return std::log2(coarse / fine); }

/// Direction moments by brute force: tensor Gauss (12 points) on pieces of both panels,
/// graded geometrically (ratio 1/2, 50 levels, `split` equal parts each) towards the end
/// `end_i` / `end_j` of panels i and j (0 start, 1 end; -1: `split` uniform pieces). The
/// points are offsets from the graded end (no rounding of tiny distances near a common
/// node) and the sum runs in long double (millions of terms).
DirectionBlocks reference_direction_blocks(const Panel& pi, const Panel& pj, int end_i, int end_j, int split) {
  struct Node {
    Vec2 base, offset;
    double phi[2], w;
  };
  auto nodes = [split](const Panel& p, int end) {
    std::vector<double> cuts{0.0};  // distances from the graded end (from the start if uniform)
    if (end < 0)
      for (int k = 1; k <= split; ++k) cuts.push_back(p.h * k / split);
    else
      for (int level = 50; level >= 0; --level) {
        const double lo = std::ldexp(p.h, -level - 1), hi = std::ldexp(p.h, -level);
        for (int k = 1; k <= split; ++k) cuts.push_back(lo + (hi - lo) * k / split);
      }
    const GaussRule& g = gauss_legendre(12);
    std::vector<Node> out;
    for (std::size_t I = 0; I + 1 < cuts.size(); ++I)
      for (int q = 0; q < 12; ++q) {
        const double d = cuts[I] + (cuts[I + 1] - cuts[I]) * g.x[static_cast<std::size_t>(q)];
        const double w = (cuts[I + 1] - cuts[I]) * g.w[static_cast<std::size_t>(q)];
        if (end == 1)
          out.push_back({p.b, -d * p.t, {d / p.h, 1 - d / p.h}, w});
        else
          out.push_back({p.a, d * p.t, {1 - d / p.h, d / p.h}, w});
      }
    return out;
  };
  const std::vector<Node> ni = nodes(pi, end_i), nj = nodes(pj, end_j);
  long double xx[2][2] = {}, xy[2][2] = {};
  for (const Node& x : ni)
    for (const Node& y : nj) {
      const Vec2 r = (x.base - y.base) + (x.offset - y.offset);
      const double inv = x.w * y.w / dot(r, r);
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) {
          xx[a][b] += x.phi[a] * y.phi[b] * r.x * r.x * inv;
          xy[a][b] += x.phi[a] * y.phi[b] * r.x * r.y * inv;
        }
    }
  DirectionBlocks out;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      out.xx[a][b] = static_cast<double>(xx[a][b]);
      out.xy[a][b] = static_cast<double>(xy[a][b]);
    }
  return out;
}

double total_difference(const DirectionBlocks& A, const DirectionBlocks& B) {
  double m = 0;  // sum of the differences (NaN propagates)
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) m += std::abs(A.xx[a][b] - B.xx[a][b]) + std::abs(A.xy[a][b] - B.xy[a][b]);
  return m;
}

}  // namespace

TEST(LamePolygon, DirectionMomentsAgainstBruteForce) {
  // Adjacent pairs (Duffy split, closed forms) at interior angles 60 ... 300 degrees and
  // length ratios 1, 4, 1/20, both relations; near and far pairs (near_outer with the
  // point-segment closed forms, tensor Gauss). Measured: the sum of the 8 differences
  // <= 5.6e-16 h_i h_j (the reference itself is accurate to ~1e-16).
  const Vec2 O{0.1, -0.2};
  const double base = 0.3;
  for (double angle_deg : {60.0, 90.0, 135.0, 180.0, 230.0, 300.0})
    for (double ratio : {1.0, 4.0, 0.05})
      for (bool end_to_start : {true, false}) {
        const double a = 0.1, b = ratio * a, ang = angle_deg * M_PI / 180.0;
        const Vec2 u1{std::cos(base), std::sin(base)}, u2{std::cos(base + ang), std::sin(base + ang)};
        // panel i along u1 from the common node O, panel j along u2
        const Panel pi = end_to_start ? make_panel(O + a * u1, O) : make_panel(O, O + a * u1);
        const Panel pj = end_to_start ? make_panel(O, O + b * u2) : make_panel(O + b * u2, O);
        DirectionBlocks D;
        direction_blocks(pi, pj, end_to_start ? PairRelation::EndToStart : PairRelation::StartToEnd, D);
        const DirectionBlocks ref = reference_direction_blocks(pi, pj, end_to_start ? 1 : 0, end_to_start ? 0 : 1, 3);
        EXPECT_LT(total_difference(D, ref), 2e-15 * a * b)
            << "angle " << angle_deg << " ratio " << ratio << " end_to_start " << end_to_start;
      }
  // Separated pairs: parallel at 1/20 of the length, a T (the end of j at 1/50 of the
  // length from the middle of i), and a far pair; the coincident pair is t t^T h^2/4.
  const Panel pi = make_panel({0.0, 0.0}, {0.1, 0.0});
  for (const Panel& pj : {make_panel({0.12, 0.005}, {0.02, 0.005}), make_panel({0.05, 0.002}, {0.04, 0.08}),
                          make_panel({0.5, 0.3}, {0.45, 0.4})}) {
    DirectionBlocks D;
    direction_blocks(pi, pj, PairRelation::Separated, D);
    EXPECT_LT(total_difference(D, reference_direction_blocks(pi, pj, -1, -1, 64)), 2e-15 * pi.h * pj.h);
  }
  const Panel p = make_panel({0.1, 0.2}, {0.4, 0.6});
  DirectionBlocks D;
  direction_blocks(p, p, PairRelation::Coincident, D);
  EXPECT_DOUBLE_EQ(D.xx[0][1], 0.36 * 0.25 * 0.25);
  EXPECT_DOUBLE_EQ(D.xy[1][0], 0.48 * 0.25 * 0.25);
}

TEST(LamePolygon, RigidMotionsSymmetryDefiniteness) {
  // W_h r = 0 and K_h r = -M_h r for the three rigid motions, in the max norm relative to
  // ||W_h||_inf ||r||_inf (resp. ||K_h||_inf): measured <= 4.4e-16 (W), 1.9e-16 (K) on
  // all polygons below, the odd 45-gon (three colours of panels) and the dart (10 degree
  // corner, graded panels) included: the closed forms leave round-off only. V_h, W_h
  // exactly symmetric; V_h and S_h = 1/2 (W_h + (K_h - M_h)^T V_h^{-1} (K_h - M_h))
  // positive definite, <S_h r, r> > 0 (rigid Dirichlet data have an exterior traction).
  const Lame m{1.0, 0.3};
  for (const Points& X : {test::circle(45, 0.35), test::square(8), l_shape(5), dart(12)})
    for (Space s : {Space::P1, Space::P0}) check_rigid_motions(Polygon(X), m, s);
}

TEST(LamePolygon, CalderonIdentitiesOfAKelvinFieldConverge) {
  // Circle of radius 0.35, regular 32-, 64-, 128-gons; field: a force and a force dipole
  // inside (kelvin_field); t_h from V_h t_h = (K_h - M_h) v, v the nodal values, nu = 0.3.
  // Measured:
  //   ||t_h - Q_h t||_L2 (Q_h: L2 projection onto the flux space; t_h's discrete error):
  //     P0 7.5e-3, 8.6e-4, 1.2e-4 (orders 3.1, 2.8); P1 9.7e-2, 2.5e-2, 6.3e-3 (1.96, 1.99);
  //   ||t_h - t||_L2, limited by the best approximation: P0 order 1.00, P1 1.45, 1.19;
  //   the resultant force |int (t_h - t)|: 1.9e-3, 4.8e-4, 1.2e-4 (2.0, 2.0) for both spaces;
  //   the second identity, ||W_h v + (K_h + M_h)^T Q_h t||_{M1^{-1}} / ||W_h v||_{M1^{-1}}:
  //     P0 4.1e-3, 4.4e-4, 5.0e-5 (3.2, 3.1); P1 2.9e-2, 7.5e-3, 1.9e-3 (1.94, 1.97).
  const Lame m{1.0, 0.3};
  const KelvinField kf = kelvin_field(m, {-0.05, 0.04});
  for (Space s : {Space::P0, Space::P1}) {
    CalderonErrors e[3];
    for (int k = 0; k < 3; ++k) e[k] = calderon(Polygon(test::circle(32 << k, 0.35)), kf, s);
    for (int k = 1; k < 3; ++k) {
      EXPECT_GE(order(e[k - 1].discrete, e[k].discrete), 1.8);
      EXPECT_GE(order(e[k - 1].force, e[k].force), 1.8);
      EXPECT_GE(order(e[k - 1].residual, e[k].residual), 1.8);
      EXPECT_GE(order(e[k - 1].l2, e[k].l2), 0.9);
    }
  }
}

TEST(LamePolygon, CalderonOnTheLShape) {
  // On a polygon the exact traction jumps at the corners (n does): the L2 errors are
  // spoilt there (measured ||t_h - Q_h t||: P0 6.0e-1, 1.5e-1, 5.3e-2; P1 6.5e-1, 2.4e-1,
  // 7.3e-2), a functional of t_h is not: the resultant force converges at order 2.0
  // (P0 1.2e-2, 2.8e-3, 7.0e-4; P1 1.2e-2, 2.9e-3, 7.2e-4). L-shape with 32, 64, 128 panels.
  const Lame m{1.0, 0.3};
  const KelvinField kf = kelvin_field(m, {-0.15, -0.12});
  for (Space s : {Space::P0, Space::P1}) {
    CalderonErrors e[3];
    for (int k = 0; k < 3; ++k) e[k] = calderon(Polygon(l_shape(4 << k)), kf, s);
    for (int k = 1; k < 3; ++k) EXPECT_GE(order(e[k - 1].force, e[k].force), 1.8);
  }
}

TEST(LamePolygon, NearIncompressibility) {
  // The kernels are regular as nu -> 1/2 and the checks above hold at nu = 0.49 and 0.499
  // (Calderon: ||t_h - Q_h t|| P0 1.3e-2, 1.4e-3, 1.7e-4 and P1 1.3e-1, 3.5e-2, 8.7e-3 at
  // both). But V loses its definiteness: V n = R (1 - 2 nu)/(2 mu (1 - nu)) n on the circle
  // (U's columns become divergence free), so the smallest eigenvalue of V_h goes to 0 like
  // 1 - 2 nu. cond(V_h) (P0, 64-gon, R = 0.35): 99.8 (nu = 0.3), 115 (0.49), 778 (0.499),
  // 7.8e3 (0.4999); at nu = 1/2, 1e16 (refused).
  const double R = 0.35;
  for (double nu : {0.49, 0.499}) {
    const Lame m{1.0, nu};
    for (Space s : {Space::P1, Space::P0}) check_rigid_motions(Polygon(l_shape(4)), m, s);
    const KelvinField kf = kelvin_field(m, {-0.05, 0.04});
    for (Space s : {Space::P0, Space::P1}) {
      CalderonErrors e[3];
      for (int k = 0; k < 3; ++k) e[k] = calderon(Polygon(test::circle(32 << k, R)), kf, s);
      for (int k = 1; k < 3; ++k) {
        EXPECT_GE(order(e[k - 1].discrete, e[k].discrete), 1.8);
        EXPECT_GE(order(e[k - 1].residual, e[k].residual), 1.8);
      }
    }
    // The normal field: Rayleigh quotient within the O((h/R)^2) of the polygon.
    const Polygon poly(test::circle(64, R));
    Vector n(128), mn(128);
    for (Index i = 0; i < 64; ++i) {
      n.segment<2>(2 * i) << poly.panel(i).n.x, poly.panel(i).n.y;
      mn.segment<2>(2 * i) = poly.panel(i).h * n.segment<2>(2 * i);
    }
    const double q = n.dot(single_layer(poly, m, Space::P0) * n) / n.dot(mn);
    const double exact = R * (1 - 2 * nu) / (2 * m.mu * (1 - nu));
    EXPECT_NEAR(q / exact, 1.0, std::pow(2 * M_PI / 64, 2));
  }
  EXPECT_THROW(single_layer(Polygon(test::circle(16, R)), Lame{1.0, 0.5}, Space::P0), std::invalid_argument);
}

TEST(LamePolygon, SingleLayerCriticalScale) {
  // V_h (Kelvin, nu = 0.3) is positive definite on the circle of radius 0.5; it stops being
  // so at the radius R* = exp(1/(2 (3 - 4 nu))) = 1.320193 of the circle (the constant
  // vectors' eigenvalue 2 pi R c (1 - 2 (3 - 4 nu) log R) vanishes; the scalar single layer
  // needs R < 1). Measured R*_h (single_layer_critical_scale, P0 and P1 alike): 1.324395,
  // 1.321248, 1.320457 on the 32-, 64-, 128-gons (errors 4.2e-3, 1.1e-3, 2.6e-4: order 2).
  const Lame m{1.0, 0.3};
  const double exact = std::exp(1.0 / (2.0 * (3.0 - 4.0 * m.nu)));
  for (Space s : {Space::P0, Space::P1}) {
    EXPECT_TRUE(single_layer_positive_definite(Polygon(test::circle(64, 0.5)), m, s));
    double error[3];
    for (int k = 0; k < 3; ++k) {
      const Index n = 32 << k;
      const double crit = 0.5 * single_layer_critical_scale(Polygon(test::circle(n, 0.5)), m, s);
      error[k] = std::abs(crit - exact);
      EXPECT_TRUE(single_layer_positive_definite(Polygon(test::circle(n, 0.999 * crit)), m, s));
      EXPECT_FALSE(single_layer_positive_definite(Polygon(test::circle(n, 1.001 * crit)), m, s));
    }
    EXPECT_GE(order(error[0], error[1]), 1.8);
    EXPECT_GE(order(error[1], error[2]), 1.8);
  }
}

TEST(LamePolygon, RequestsAndRefusals) {
  // One pass for all three equals the single calls up to round-off (the far-field rule
  // with and without the double-layer kernel compiles to different instructions;
  // measured 1.3e-16 relative).
  const Polygon poly(test::circle(13, 0.3));
  const Lame m{0.7, 0.25};
  OperatorRequest all;
  all.single_layer = Space::P0;
  all.double_layer = Space::P1;
  all.hypersingular = true;
  const Operators ops = assemble(poly, m, all);
  const Matrix V = single_layer(poly, m, Space::P0), K = double_layer(poly, m, Space::P1), W = hypersingular(poly, m);
  EXPECT_EQ(V.rows(), 26);
  EXPECT_LT((ops.single_layer - V).cwiseAbs().maxCoeff(), 1e-15 * V.cwiseAbs().maxCoeff());
  EXPECT_LT((ops.double_layer - K).cwiseAbs().maxCoeff(), 1e-15 * K.cwiseAbs().maxCoeff());
  EXPECT_LT((ops.hypersingular - W).cwiseAbs().maxCoeff(), 1e-15 * W.cwiseAbs().maxCoeff());
  EXPECT_TRUE(single_layer(test::circle(13, 0.3), m, Space::P1) == single_layer(poly, m, Space::P1));
  EXPECT_TRUE(hypersingular(test::circle(13, 0.3), m) == hypersingular(poly, m));
  const Points clockwise = test::circle(13, 0.3).colwise().reverse();
  EXPECT_THROW(double_layer(clockwise, m, Space::P0), std::invalid_argument);
  for (const Lame& bad : {Lame{0.0, 0.3}, Lame{1.0, 0.6}, Lame{1.0, -1.0}, Lame{double(NAN), 0.3}})
    EXPECT_THROW(hypersingular(poly, bad), std::invalid_argument);
}
