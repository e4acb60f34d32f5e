#include "bem/lame_polygon.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "bem/linear_algebra.hpp"

namespace bem {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr Index kTile = 32;

/// A := A + A^T, tile by tile in parallel (tiles (I, J) and (J, I) belong to one thread);
/// the result is exactly symmetric.
void symmetrise(Matrix& A) {
  const Index N = A.rows(), nb = (N + kTile - 1) / kTile;
#pragma omp parallel for schedule(dynamic, 1)
  for (Index I = 0; I < nb; ++I)
    for (Index J = I; J < nb; ++J)
      for (Index r = I * kTile; r < std::min(N, (I + 1) * kTile); ++r)
        for (Index c = std::max(J * kTile, r); c < std::min(N, (J + 1) * kTile); ++c) {
          const double s = A(r, c) + A(c, r);
          A(r, c) = A(c, r) = s;
        }
}

/// K := K + T^T.
void add_transposed(Matrix& K, const Matrix& T) {
  const Index N = K.rows(), nb = (N + kTile - 1) / kTile;
#pragma omp parallel for schedule(dynamic, 1)
  for (Index I = 0; I < nb; ++I)
    for (Index J = 0; J < nb; ++J)
      for (Index r = I * kTile; r < std::min(N, (I + 1) * kTile); ++r)
        for (Index c = J * kTile; c < std::min(N, (J + 1) * kTile); ++c) K(r, c) += T(c, r);
}

/// A[2 r + k][2 c + l] += s B[k][l].
inline void add_block(Matrix& A, Index r, Index c, double s, const double (&B)[2][2]) {
  A(2 * r, 2 * c) += s * B[0][0];
  A(2 * r, 2 * c + 1) += s * B[0][1];
  A(2 * r + 1, 2 * c) += s * B[1][0];
  A(2 * r + 1, 2 * c + 1) += s * B[1][1];
}

/// Coefficients A_m = int t^m d^2/rho^2, B_m = int t^m (tau - t) d/rho^2 (m = 0, 1) of the
/// segment Y(t) = a + t e, t in [0, h], seen from p, rho^2 = (tau - t)^2 + d^2, in its frame
/// (e, nu): p - Y(t) = (tau - t) e + d nu. With u = t - tau, u0 = -tau, u1 = h - tau,
/// theta = int d/(u^2 + d^2) du (the subtended angle) and l = log(u^2 + d^2):
///   A_0 = d theta,  A_1 = d (d (l1 - l0)/2 + tau theta),
///   B_0 = -d (l1 - l0)/2,  B_1 = -d h + d^2 theta - tau d (l1 - l0)/2.
void frame_moments(double tau, double d, double h, double (&A)[2], double (&B)[2]) {
  const double u0 = -tau, u1 = h - tau;
  const double r0s = u0 * u0 + d * d, r1s = u1 * u1 + d * d;
  const double l0 = r0s > 0 ? std::log(r0s) : 0.0, l1 = r1s > 0 ? std::log(r1s) : 0.0;
  const double theta = d != 0 ? std::atan2(d * h, d * d + u0 * u1) : 0.0;
  const double half_d_ell = d != 0 ? 0.5 * d * (l1 - l0) : 0.0;
  A[0] = d * theta;
  A[1] = d * (half_d_ell + tau * theta);
  B[0] = -half_d_ell;
  B[1] = -d * h + d * d * theta - tau * half_d_ell;
}

void clear(double (&m)[2][2]) { m[0][0] = m[0][1] = m[1][0] = m[1][1] = 0.0; }

void adjacent_direction_blocks(const Panel& pi, const Panel& pj, PairRelation relation, DirectionBlocks& out) {
  // Common node O at the origin, x = s e1 (s in [0, a]), y = t e2 (t in [0, b]). Duffy
  // split of [0, a] x [0, b] along t/b = s/a: t = s w' (w' in [0, r], r = b/a) on one
  // triangle, s = t w' (w' in [0, r'], r' = a/b) on the other. g is homogeneous of degree
  // 0 and even, so g(x - y) = g(e1 - w' e2) resp. g(e2 - w' e1), and
  //   int int s^k t^m g = a^(q+1)/(q+1) G1_m + b^(q+1)/(q+1) G2_k,  q = k + m + 1,
  // with G1_m = int_0^r w^m g(e1 - w e2) dw, G2_k = int_0^r' w^k g(e2 - w e1) dw.
  const bool i_vertex_at_end = relation == PairRelation::EndToStart;
  const Vec2 e1 = i_vertex_at_end ? -1.0 * pi.t : pi.t;
  const Vec2 e2 = i_vertex_at_end ? pj.t : -1.0 * pj.t;
  const double a = pi.h, b = pj.h;
  const Vec2 origin{0.0, 0.0};
  const DirectionMoments g1 = direction_segment_moments(e1, origin, e2, b / a);
  const DirectionMoments g2 = direction_segment_moments(e2, origin, e1, a / b);
  double Ixx[2][2], Ixy[2][2];
  for (int k = 0; k < 2; ++k)
    for (int m = 0; m < 2; ++m) {
      const int q = k + m + 1;
      const double fa = std::pow(a, q + 1) / (q + 1), fb = std::pow(b, q + 1) / (q + 1);
      Ixx[k][m] = fa * g1.xx[m] + fb * g2.xx[k];
      Ixy[k][m] = fa * g1.xy[m] + fb * g2.xy[k];
    }
  // Shape functions as c0 + c1 * (distance from the common node), as adjacent_blocks.
  const AdjacentShapes shapes(a, b, i_vertex_at_end);
  const auto& ci = shapes.ci;
  const auto& cj = shapes.cj;
  for (int al = 0; al < 2; ++al)
    for (int be = 0; be < 2; ++be) {
      double xx = 0, xy = 0;
      for (int k = 0; k < 2; ++k)
        for (int m = 0; m < 2; ++m) {
          xx += ci[al][k] * cj[be][m] * Ixx[k][m];
          xy += ci[al][k] * cj[be][m] * Ixy[k][m];
        }
      out.xx[al][be] = xx;
      out.xy[al][be] = xy;
    }
}

void far_direction_blocks(const Panel& pi, const Panel& pj, int p, DirectionBlocks& out) {
  const GaussRule& g = gauss_legendre(p);
  clear(out.xx);
  clear(out.xy);
  const Vec2 d0 = pi.a - pj.a;
  for (int q = 0; q < p; ++q) {
    const double xq = g.x[static_cast<std::size_t>(q)], wq = g.w[static_cast<std::size_t>(q)];
    const Vec2 x = d0 + (xq * pi.h) * pi.t;
    const double wi[2] = {wq * (1.0 - xq) * pi.h, wq * xq * pi.h};
    double xx[2] = {}, xy[2] = {};
    for (int k = 0; k < p; ++k) {
      const double tk = g.x[static_cast<std::size_t>(k)], wk = g.w[static_cast<std::size_t>(k)] * pj.h;
      const Vec2 r = x - (tk * pj.h) * pj.t;
      const double inv = 1.0 / dot(r, r);
      const double gxx = r.x * r.x * inv, gxy = r.x * r.y * inv;
      const double wj[2] = {wk * (1.0 - tk), wk * tk};
      for (int b = 0; b < 2; ++b) {
        xx[b] += wj[b] * gxx;
        xy[b] += wj[b] * gxy;
      }
    }
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        out.xx[a][b] += wi[a] * xx[b];
        out.xy[a][b] += wi[a] * xy[b];
      }
  }
}

void near_direction_blocks(const Panel& pi, const Panel& pj, DirectionBlocks& out) {
  clear(out.xx);
  clear(out.xy);
  near_outer(pi, pj, [&](double s, double w) {
    const DirectionMoments m = direction_segment_moments(pi.a + s * pi.t, pj.a, pj.t, pj.h);
    const double phi[2] = {w * (1.0 - s / pi.h), w * (s / pi.h)};
    const double xx[2] = {m.xx[0] - m.xx[1] / pj.h, m.xx[1] / pj.h};
    const double xy[2] = {m.xy[0] - m.xy[1] / pj.h, m.xy[1] / pj.h};
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        out.xx[a][b] += phi[a] * xx[b];
        out.xy[a][b] += phi[a] * xy[b];
      }
  });
}

}  // namespace

DirectionMoments direction_segment_moments(Vec2 p, Vec2 a, Vec2 e, double h) {
  DirectionMoments out;
  const Vec2 q = p - a;
  const double separation = norm(q - (0.5 * h) * e) - 0.5 * h;
  const int points = separation > 0 ? gauss_points_for(separation, h, kMaxFarPoints) : 0;
  if (points > 0) {
    const GaussRule& g = gauss_legendre(points);
    for (int m = 0; m < 2; ++m) out.xx[m] = out.xy[m] = 0.0;
    for (int k = 0; k < points; ++k) {
      const double t = g.x[static_cast<std::size_t>(k)] * h, w = g.w[static_cast<std::size_t>(k)] * h;
      const Vec2 r = q - t * e;
      const double inv = 1.0 / dot(r, r);
      const double gxx = r.x * r.x * inv, gxy = r.x * r.y * inv;
      out.xx[0] += w * gxx;
      out.xy[0] += w * gxy;
      out.xx[1] += w * t * gxx;
      out.xy[1] += w * t * gxy;
    }
    return out;
  }
  // g = C e e^T + B (e nu^T + nu e^T) + A nu nu^T with C_m = h^(m+1)/(m+1) - A_m.
  const Vec2 nu = rotate_cw(e);
  double A[2], B[2];
  frame_moments(dot(q, e), dot(q, nu), h, A, B);
  for (int m = 0; m < 2; ++m) {
    const double C = (m == 0 ? h : 0.5 * h * h) - A[m];
    out.xx[m] = C * e.x * e.x + 2.0 * B[m] * e.x * nu.x + A[m] * nu.x * nu.x;
    out.xy[m] = C * e.x * e.y + B[m] * (e.x * nu.y + nu.x * e.y) + A[m] * nu.x * nu.y;
  }
  return out;
}

void direction_blocks(const Panel& pi, const Panel& pj, PairRelation relation, DirectionBlocks& out) {
  const auto coincident = [&] {
    // g = t t^T on the whole square; int phi_a = h/2.
    const double q = 0.25 * pi.h * pi.h;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        out.xx[a][b] = q * pi.t.x * pi.t.x;
        out.xy[a][b] = q * pi.t.x * pi.t.y;
      }
  };
  integrate_pair(
      pi, pj, relation, coincident, [&] { adjacent_direction_blocks(pi, pj, relation, out); },
      [&](int p) { far_direction_blocks(pi, pj, p, out); }, [&] { near_direction_blocks(pi, pj, out); });
}

Operators assemble(const Polygon& polygon, const Lame& m, const OperatorRequest& request) {
  check_medium(m, " (at 1/2 the single layer is singular: V n = 0)");
  const Index n = polygon.size(), N = 2 * n;
  const bool v_p1 = request.single_layer == Space::P1;
  const bool v_p0 = request.single_layer == Space::P0;
  const bool w = request.hypersingular;
  const bool k_p1 = request.double_layer == Space::P1;
  const bool k_p0 = request.double_layer == Space::P0;
  const bool with_k = k_p1 || k_p0;

  // Pairs (P, Q >= P) only, each pair's moments once. The symmetric V and W collect the
  // blocks of the pairs in the rows of panel P (the pair (P, P) halved): V = A + A^T.
  // K collects the blocks (test P, trial Q) in the rows of panel P and the blocks
  // (test Q, trial P) transposed in KT, also in the rows of panel P: K = K + KT^T.
  Matrix AV, AW, AK, KT;
  if (v_p1 || v_p0) AV = parallel_zeros(N);
  if (w) AW = parallel_zeros(N);
  if (with_k) {
    AK = parallel_zeros(N);
    KT = parallel_zeros(N);
  }

  const double nu = m.nu;
  const double cv = 1.0 / (4.0 * kPi * m.mu * (1.0 - nu)), av = -(3.0 - 4.0 * nu);
  const double ck = 1.0 / (2.0 * kPi * (1.0 - nu)), ek = 1.0 - 2.0 * nu;
  const double cw = m.mu / (kPi * (1.0 - nu));
  const double sigma[2] = {-1.0, 1.0};  // h * (derivative of the hat) at the start / end node

  for_each_panel_coloured(n, [&](Index P) {
    const Panel& pp = polygon.panel(P);
    const Index nodeP[2] = {P, (P + 1) % n};
    for (Index Q = P; Q < n; ++Q) {
      const Panel& pq = polygon.panel(Q);
      const Index nodeQ[2] = {Q, (Q + 1) % n};
      const PairRelation rel = panel_relation(P, Q, n);
      PairBlocks lap;
      pair_blocks(pp, pq, rel, with_k, lap);
      DirectionBlocks dir;
      direction_blocks(pp, pq, rel, dir);
      const double quarter = 0.25 * pp.h * pq.h;  // int phi_a int phi_b
      const double half = Q == P ? 0.5 : 1.0;     // the pair (P, P) is mirrored onto itself

      if (v_p1 || v_p0 || w) {
        double S[2][2] = {}, sum_l = 0, sum_xx = 0, sum_xy = 0;
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b) {
            const double L = lap.v[a][b], xx = dir.xx[a][b], xy = dir.xy[a][b], yy = quarter - xx;
            const double blk[2][2] = {{av * L + xx, xy}, {xy, av * L + yy}};
            if (v_p1) add_block(AV, nodeP[a], nodeQ[b], half * cv, blk);
            sum_l += L;
            sum_xx += xx;
            sum_xy += xy;
          }
        if (v_p0) {
          const double blk[2][2] = {{av * sum_l + sum_xx, sum_xy}, {sum_xy, av * sum_l + 4 * quarter - sum_xx}};
          add_block(AV, P, Q, half * cv, blk);
        }
        if (w) {
          S[0][0] = -sum_l + sum_xx;
          S[0][1] = S[1][0] = sum_xy;
          S[1][1] = -sum_l + 4 * quarter - sum_xx;
          const double s = half * cw / (pp.h * pq.h);
          for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b) add_block(AW, nodeP[a], nodeQ[b], s * sigma[a] * sigma[b], S);
        }
      }

      if (with_k) {
        // Z = ck [ -(1 - 2 nu) L0 R + D0 R ] for a P0 trial function, R = [[0, -1], [1, 0]]:
        // D0 R = [[D_xy, -D_xx], [D_yy, -D_xy]].
        auto z_block = [&](double L0, double xx, double xy, double yy, double(&Z)[2][2]) {
          Z[0][0] = ck * xy;
          Z[0][1] = ck * (ek * L0 - xx);
          Z[1][0] = ck * (yy - ek * L0);
          Z[1][1] = -ck * xy;
        };
        // The test shape of one panel (the sums L0, xx, xy of its moments over the other
        // panel's shapes) against the trial nodes c of the other panel (its length h, the
        // Laplace entries kl[c]): the blocks (test, trial[c]) of AK, or (to_kt) stored
        // transposed in KT at (trial[c], test).
        auto add_k = [&](double L0, double xx, double xy, const double(&kl)[2], double h, Index test,
                         const Index(&trial)[2], bool to_kt) {
          double Z[2][2];
          z_block(L0, xx, xy, 2 * quarter - xx, Z);
          for (int c = 0; c < 2; ++c) {
            const double s = sigma[c] / h, k = kl[c] / kPi;
            const double blk[2][2] = {{k + s * Z[0][0], s * Z[0][1]}, {s * Z[1][0], k + s * Z[1][1]}};
            if (!to_kt) {
              add_block(AK, test, trial[c], 1.0, blk);
              continue;
            }
            const double blkT[2][2] = {{blk[0][0], blk[1][0]}, {blk[0][1], blk[1][1]}};
            add_block(KT, trial[c], test, 1.0, blkT);
          }
        };
        // Test P (shape a), trial node b of Q.
        for (int a = 0; a < 2; ++a)
          add_k(lap.v[a][0] + lap.v[a][1], dir.xx[a][0] + dir.xx[a][1], dir.xy[a][0] + dir.xy[a][1], lap.kij[a], pq.h,
                k_p1 ? nodeP[a] : P, nodeQ, false);
        // Test Q (shape b), trial node a of P, stored transposed.
        if (Q != P)
          for (int b = 0; b < 2; ++b) {
            const double kl[2] = {lap.kji[b][0], lap.kji[b][1]};
            add_k(lap.v[0][b] + lap.v[1][b], dir.xx[0][b] + dir.xx[1][b], dir.xy[0][b] + dir.xy[1][b], kl, pp.h,
                  k_p1 ? nodeQ[b] : Q, nodeP, true);
          }
      }
    }
  });

  Operators ops;
  if (v_p1 || v_p0) {
    symmetrise(AV);
    ops.single_layer = std::move(AV);
  }
  if (w) {
    symmetrise(AW);
    ops.hypersingular = std::move(AW);
  }
  if (with_k) {
    add_transposed(AK, KT);
    ops.double_layer = std::move(AK);
  }
  return ops;
}

Matrix single_layer(const Polygon& polygon, const Lame& m, Space space) {
  OperatorRequest r;
  r.single_layer = space;
  return std::move(assemble(polygon, m, r).single_layer);
}

Matrix double_layer(const Polygon& polygon, const Lame& m, Space space) {
  OperatorRequest r;
  r.double_layer = space;
  return std::move(assemble(polygon, m, r).double_layer);
}

Matrix hypersingular(const Polygon& polygon, const Lame& m) {
  OperatorRequest r;
  r.hypersingular = true;
  return std::move(assemble(polygon, m, r).hypersingular);
}

Matrix single_layer(const Eigen::Ref<const Points>& nodes, const Lame& m, Space space) {
  return single_layer(Polygon(nodes), m, space);
}
Matrix double_layer(const Eigen::Ref<const Points>& nodes, const Lame& m, Space space) {
  return double_layer(Polygon(nodes), m, space);
}
Matrix hypersingular(const Eigen::Ref<const Points>& nodes, const Lame& m) { return hypersingular(Polygon(nodes), m); }

double single_layer_critical_scale(const Polygon& polygon, const Lame& m, Space space) {
  const Matrix V = single_layer(polygon, m, space);
  const Index n = polygon.size();
  Vector mass = Vector::Zero(n);  // int psi_i: P0 h_i, P1 (h_(i-1) + h_i)/2; B = mass kron I_2
  for (Index i = 0; i < n; ++i) {
    const double h = polygon.panel(i).h;
    mass(i) += 0.5 * h;
    mass(space == Space::P0 ? i : (i + 1) % n) += 0.5 * h;
  }
  const double kappa = (3.0 - 4.0 * m.nu) / (4.0 * kPi * m.mu * (1.0 - m.nu));
  // A0 = V - kappa tau0 B B^T is positive definite for tau0 small enough (V is positive
  // definite on the tractions of zero resultant); tau0 = 0, -1, -2, -4, ...
  for (double tau0 = 0.0; tau0 >= -1024.0; tau0 = tau0 == 0.0 ? -1.0 : 2.0 * tau0) {
    Matrix A0 = V;
    for (Index i = 0; i < n; ++i)
      for (Index j = 0; j < n; ++j)
        for (int k = 0; k < 2; ++k) A0(2 * i + k, 2 * j + k) -= kappa * tau0 * mass(i) * mass(j);
    if (cholesky_in_place(A0) != 0) continue;
    double G[2][2] = {};  // B^T A0^{-1} B
    for (int l = 0; l < 2; ++l) {
      Vector x = Vector::Zero(2 * n);
      for (Index i = 0; i < n; ++i) x(2 * i + l) = mass(i);
      cholesky_solve_in_place(A0, x);
      for (int k = 0; k < 2; ++k)
        for (Index i = 0; i < n; ++i) G[k][l] += mass(i) * x(2 * i + k);
    }
    const double mean = 0.5 * (G[0][0] + G[1][1]), half_diff = 0.5 * (G[0][0] - G[1][1]);
    const double off = 0.5 * (G[0][1] + G[1][0]);
    const double lambda = mean + std::sqrt(half_diff * half_diff + off * off);
    return std::exp(tau0 + 1.0 / (kappa * lambda));
  }
  throw std::runtime_error("single_layer_critical_scale: V_h is not positive definite on zero-resultant tractions");
}

bool single_layer_positive_definite(const Polygon& polygon, const Lame& m, Space space) {
  Matrix V = single_layer(polygon, m, space);
  return cholesky_in_place(V) == 0;
}

}  // namespace bem
