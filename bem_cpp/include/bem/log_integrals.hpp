#pragma once
// Integrals of the logarithmic kernel and of the double-layer kernel over straight
// panels (docs/method.md sections 2 and 9), and the quadrature rules they use.
//
// Kernels (without the factor-2 scaling, which operators.cpp applies):
//   log kernel          l(x, y) = log|x - y|                      (V = -(1/pi) int l)
//   double-layer kernel k(x, y) = (x - y).n_y / |x - y|^2          (K = (1/pi) int k)
// Shape functions on a panel of length h, local coordinate s in [0, h] from its start
// node: phi_0 = 1 - s/h (start node), phi_1 = s/h (end node).
//
// Panel pairs, by relation:
//   coincident  closed form (constants of int_0^1 int_0^1 log|s - t| s^k t^m);
//   adjacent    closed form: Duffy split of [0,a]x[0,b] along its diagonal, after which
//               the log kernel separates into log(s) + log q(w) and the double-layer
//               kernel into a bounded function of w; the w-integrals are the analytic
//               point-segment moments below (no quadrature at all);
//   near        inner integral over panel j (closed form when x is within 2.5 lengths
//               of panel j, Gauss-Legendre beyond, where the closed forms would lose
//               digits to cancellation) + Gauss-Legendre outer rule on panel i,
//               subdivided until each piece lies at least its own length away from
//               panel j, with the number of points chosen from that ratio; an adjacent
//               pair with length ratio > 2 is split into an equal-length adjacent pair
//               and a near pair;
//   far         tensor Gauss-Legendre, p points per panel chosen from distance/length
//               (the integrand is analytic on a Bernstein ellipse of parameter rho and
//               the error is O(rho^(-2p)); far away the analytic inner integrals would
//               lose digits to cancellation, the tensor rule does not).
#include <array>

#include "bem/geometry.hpp"

namespace bem {

/// Largest Gauss-Legendre rule used anywhere.
constexpr int kMaxGaussPoints = 24;
/// Largest tensor rule used for far panel pairs (beyond it the pair counts as near).
constexpr int kMaxFarPoints = 8;
/// Target of the quadrature error bound rho^(-2p), relative to the kernel size.
constexpr double kQuadratureTolerance = 1e-16;

/// Gauss-Legendre rule on [0, 1]: nodes x (ascending) and weights w (sum 1).
struct GaussRule {
  std::array<double, kMaxGaussPoints> x{}, w{};
  int size = 0;
};

/// The p-point Gauss-Legendre rule on [0, 1], 1 <= p <= kMaxGaussPoints (computed
/// once by Newton's method on the Legendre polynomial, nodes accurate to round-off).
const GaussRule& gauss_legendre(int p);

/// Number of Gauss points p such that rho^(-2p) <= kQuadratureTolerance for a
/// singularity at distance `distance` from a segment of length `length`
/// (rho = y + sqrt(1 + y^2), y = 2 distance/length: the worst, perpendicular, case).
/// Returns 0 if more than `max_points` would be needed.
int gauss_points_for(double distance, double length, int max_points);

/// Outer integration over panel `outer` of f(s, w) (s the local coordinate, w the
/// weight including the length) for an inner integral over `inner`: the panel is
/// bisected until each piece is at least its own length away from `inner`, then each
/// piece gets the Gauss rule that the distance/length ratio requires.
template <class F>
void near_outer(const Panel& outer, const Panel& inner, F&& f) {
  struct Piece {
    double s0, s1;
    int depth;
  };
  Piece stack[128];
  int top = 0;
  stack[top++] = {0.0, outer.h, 0};
  while (top > 0) {
    const Piece piece = stack[--top];
    const double len = piece.s1 - piece.s0;
    const Panel sub = make_panel(outer.a + piece.s0 * outer.t, outer.a + piece.s1 * outer.t);
    const double dist = distance(sub, inner);
    if (dist < len && piece.depth < 60) {
      const double mid = 0.5 * (piece.s0 + piece.s1);
      stack[top++] = {piece.s0, mid, piece.depth + 1};
      stack[top++] = {mid, piece.s1, piece.depth + 1};
      continue;
    }
    int p = gauss_points_for(dist, len, kMaxGaussPoints);
    if (p == 0) p = kMaxGaussPoints;
    const GaussRule& g = gauss_legendre(p);
    for (int q = 0; q < p; ++q)
      f(piece.s0 + len * g.x[static_cast<std::size_t>(q)], len * g.w[static_cast<std::size_t>(q)]);
  }
}

/// Analytic moments over the segment Y(t) = a + t e, t in [0, h] (|e| = 1), seen from
/// the point p, with d = (p - a).nu for a unit normal nu of the segment:
///   log_m = int_0^h t^m log|p - Y(t)| dt          (m = 0, 1)
///   ang_m = int_0^h t^m d / |p - Y(t)|^2 dt        (m = 0, 1, 2)
/// ang_0 is the signed angle under which p sees the segment. Exact for every p not in
/// the open segment; points on the segment's line give ang_m = 0 (principal value).
struct SegmentMoments {
  double log0, log1, ang0, ang1, ang2;
};
SegmentMoments segment_moments(Vec2 p, Vec2 a, Vec2 e, double h, Vec2 nu);

/// Local 2x2 blocks of a panel pair (i, j), shape index 0 = start node, 1 = end node:
///   v[a][b]   = int_i int_j log|x - y|            phi_a(x) phi_b(y)
///   kij[a][b] = int_i int_j (x - y).n_j/|x - y|^2  phi_a(x) phi_b(y)   (test i, trial j)
///   kji[b][a] = int_j int_i (y - x).n_i/|x - y|^2  phi_b(y) phi_a(x)   (test j, trial i)
struct PairBlocks {
  double v[2][2];
  double kij[2][2];
  double kji[2][2];
};

/// How two panels of a polygon meet.
enum class PairRelation {
  Separated,   ///< no common node
  Coincident,  ///< the same panel
  EndToStart,  ///< the end node of panel i is the start node of panel j
  StartToEnd,  ///< the start node of panel i is the end node of panel j
};

/// The relation of panels i and j of a closed polygon of n panels (panel i runs from node i
/// to node i + 1 mod n).
inline PairRelation panel_relation(Index i, Index j, Index n) {
  if (i == j) return PairRelation::Coincident;
  if (j == (i + 1) % n) return PairRelation::EndToStart;
  if (j == (i + n - 1) % n) return PairRelation::StartToEnd;
  return PairRelation::Separated;
}

/// The shape functions of two adjacent panels of lengths a (panel i) and b (panel j) as
/// c0 + c1 * (distance from their common node): ci[shape][0 or 1] on panel i, cj on panel
/// j, the common node the end of panel i (i_vertex_at_end, PairRelation::EndToStart) or its
/// start. The coefficients of the adjacent pairs' monomial moments.
struct AdjacentShapes {
  double ci[2][2], cj[2][2];
  AdjacentShapes(double a, double b, bool i_vertex_at_end)
      : ci{{i_vertex_at_end ? 0.0 : 1.0, i_vertex_at_end ? 1.0 / a : -1.0 / a},
           {i_vertex_at_end ? 1.0 : 0.0, i_vertex_at_end ? -1.0 / a : 1.0 / a}},
        cj{{i_vertex_at_end ? 1.0 : 0.0, i_vertex_at_end ? -1.0 / b : 1.0 / b},
           {i_vertex_at_end ? 0.0 : 1.0, i_vertex_at_end ? 1.0 / b : -1.0 / b}} {}
};

/// Blocks of a panel pair, choosing the method from the relation and the distance.
/// With with_k = false only v is computed (kij, kji are left unset).
void pair_blocks(const Panel& pi, const Panel& pj, PairRelation relation, bool with_k, PairBlocks& out);

// The individual methods, exposed for the tests.
void coincident_blocks(const Panel& p, PairBlocks& out);
void adjacent_blocks(const Panel& pi, const Panel& pj, PairRelation relation, PairBlocks& out);
void near_blocks(const Panel& pi, const Panel& pj, bool with_k, PairBlocks& out);
/// Tensor Gauss rule with p points on each panel (1 <= p <= kMaxGaussPoints).
void far_blocks(const Panel& pi, const Panel& pj, int p, bool with_k, PairBlocks& out);

/// y_p = (rho_p - 1/rho_p)/2 with rho_p = kQuadratureTolerance^(-1/(2p)), p = 1 ...
/// kMaxGaussPoints: p Gauss points suffice at distance/length >= y_p/2.
const std::array<double, kMaxGaussPoints + 1>& gauss_thresholds();

/// Number of points of the tensor Gauss rule for a separated pair, from a lower bound
/// of the panel distance (midpoint distance minus half lengths) and the larger length;
/// 0 if the pair is too close for kMaxFarPoints points (near field). y = gauss_thresholds().
inline int far_field_points(const Panel& pi, const Panel& pj, const std::array<double, kMaxGaussPoints + 1>& y) {
  const Vec2 d = pi.m - pj.m;
  const double d2 = dot(d, d), half_sum = 0.5 * (pi.h + pj.h);
  const double half_h = 0.5 * (pi.h > pj.h ? pi.h : pj.h);
  for (int p = 1; p <= kMaxFarPoints; ++p) {
    // separation = |d| - half_sum >= y_p * half_h, compared without a square root
    const double bound = half_sum + y[static_cast<std::size_t>(p)] * half_h;
    if (d2 >= bound * bound) return p;
  }
  return 0;
}
inline int far_field_points(const Panel& pi, const Panel& pj) { return far_field_points(pi, pj, gauss_thresholds()); }

/// The integration of a panel pair chosen by its relation and distance, as pair_blocks and
/// direction_blocks (lame_polygon.hpp) choose it: coincident() for the same panel,
/// adjacent() for two panels with a common node, far(p) for a separated pair that the
/// tensor Gauss rule of p = far_field_points(pi, pj) > 0 points integrates, near() for the
/// other separated pairs.
template <typename Coincident, typename Adjacent, typename Far, typename Near>
void integrate_pair(const Panel& pi, const Panel& pj, PairRelation relation, Coincident&& coincident,
                    Adjacent&& adjacent, Far&& far, Near&& near) {
  switch (relation) {
    case PairRelation::Coincident:
      return coincident();
    case PairRelation::EndToStart:
    case PairRelation::StartToEnd:
      return adjacent();
    case PairRelation::Separated:
      break;
  }
  const int p = far_field_points(pi, pj);
  if (p > 0)
    far(p);
  else
    near();
}

/// Integrals of one panel seen from a point z off the panel, trial shape b = 0, 1:
///   log[b] = int_p log|z - y| phi_b(y) ds_y,   dl[b] = int_p (z - y).n/|z - y|^2 phi_b(y) ds_y.
/// Analytic (segment_moments) when z is near the panel, Gauss-Legendre otherwise.
struct PointPanelMoments {
  double log[2];
  double dl[2];
};
PointPanelMoments point_panel_moments(Vec2 z, const Panel& p);

}  // namespace bem
