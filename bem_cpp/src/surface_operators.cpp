#include "bem/surface_operators.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace bem {

namespace {

constexpr double kInvTwoPi = 0.5 / M_PI;

/// Vertices of t in the order `order` (shared ones first).
struct Mapped {
  Vec3 q0, e1, e2;
  int order[3];
};

Mapped mapped(const Triangle& t, const int order[3]) {
  Mapped m;
  m.q0 = t.p[static_cast<std::size_t>(order[0])];
  m.e1 = t.p[static_cast<std::size_t>(order[1])] - m.q0;
  m.e2 = t.p[static_cast<std::size_t>(order[2])] - m.q0;
  for (int k = 0; k < 3; ++k) m.order[k] = order[k];
  return m;
}

/// Completes the first `count` local indices to a permutation of {0, 1, 2}.
void complete(int order[3], int count) {
  for (int v = 0; v < 3 && count < 3; ++v)
    if (std::find(order, order + count, v) == order + count) order[count++] = v;
}

/// The three integrals of the pair (a, b), test and trial in both orders, from points
/// x in a and y in b (d = x - y): V[i][j] (i: basis of a, j: basis of b),
/// Kab[i][j] = 2 int int dG/dn_y lambda_i(x) lambda_j(y) (test a, trial b, normal of b),
/// Kba[i][j] (test b, trial a, normal of a, d reversed). Index 3: the constant (P0).
struct Accumulated {
  double V[4][4] = {}, Kab[4][3] = {}, Kba[4][3] = {};
};

inline Vec3 point(const Mapped& m, double s, double t) { return m.q0 + s * m.e1 + t * m.e2; }

/// The basis functions of the mapped triangle m (by the triangle's own vertex numbering,
/// index 3 the constant) as coefficients of (1, s, t).
inline void basis_coefficients(const Mapped& m, double c[4][3]) {
  const double rows[3][3] = {{1.0, -1.0, -1.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) c[m.order[k]][l] = rows[k][l];
  c[3][0] = 1.0;
  c[3][1] = c[3][2] = 0.0;
}

/// The entries of every pair of basis functions from the moments m[alpha * 3 + beta] of the
/// kernels against (1, s1, t1) x (1, s2, t2): entry(i of a, j of b) = sum ca[i][alpha]
/// cb[j][beta] m[alpha][beta] (V from mv; with the double layer Kab from mk, Kba from mt).
void add_moments(const double ca[4][3], const double cb[4][3], const double mv[9], const double mk[9],
                 const double mt[9], bool double_layer, Accumulated& acc) {
  auto entry = [](const double m[9], const double ci[3], const double cj[3]) {
    double e = 0.0;
    for (int al = 0; al < 3; ++al)
      for (int be = 0; be < 3; ++be) e += ci[al] * cj[be] * m[al * 3 + be];
    return e;
  };
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) acc.V[i][j] += entry(mv, ca[i], cb[j]);
  if (double_layer)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) {
        acc.Kab[i][j] += entry(mk, ca[i], cb[j]);
        acc.Kba[i][j] += entry(mt, ca[j], cb[i]);  // test b (i), trial a (j)
      }
}

/// Scratch of the kernels of one thread (the largest pair rule has 7,776 points).
std::vector<double>& moment_scratch(std::size_t size) {
  thread_local std::vector<double> scratch;
  if (scratch.size() < size) scratch.resize(size);
  return scratch;
}

/// The differences d = x - y = (a.q0 - b.q0) + s1 a.e1 + t1 a.e2 - s2 b.e1 - t2 b.e2 at the
/// point pairs of a pair rule, into dx, dy, dz.
inline void pair_differences(const Mapped& a, const Mapped& b, const PairRule& r, double* dx, double* dy, double* dz) {
  const int n = r.size();
  const double *s1 = r.s1.data(), *t1 = r.t1.data(), *s2 = r.s2.data(), *t2 = r.t2.data();
  const Vec3 d0 = a.q0 - b.q0;
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    dx[q] = d0.x + s1[q] * a.e1.x + t1[q] * a.e2.x - s2[q] * b.e1.x - t2[q] * b.e2.x;
    dy[q] = d0.y + s1[q] * a.e1.y + t1[q] * a.e2.y - s2[q] * b.e1.y - t2[q] * b.e2.y;
    dz[q] = d0.z + s1[q] * a.e1.z + t1[q] * a.e2.z - s2[q] * b.e1.z - t2[q] * b.e2.z;
  }
}

/// The moments m[alpha * 3 + beta] of the kernel values f[q] at the points q < n of a pair
/// rule against the monomials (1, s1, t1) x (1, s2, t2), in one vectorised pass.
inline void monomial_moments(int n, const double* f, const PairRule& r, double m[9]) {
  const double *s1 = r.s1.data(), *t1 = r.t1.data(), *s2 = r.s2.data(), *t2 = r.t2.data();
  double v0 = 0, v1 = 0, v2 = 0, v3 = 0, v4 = 0, v5 = 0, v6 = 0, v7 = 0, v8 = 0;
#pragma omp simd reduction(+ : v0, v1, v2, v3, v4, v5, v6, v7, v8)
  for (int q = 0; q < n; ++q) {
    const double g = f[q], gs = g * s1[q], gt = g * t1[q];
    v0 += g;
    v1 += g * s2[q];
    v2 += g * t2[q];
    v3 += gs;
    v4 += gs * s2[q];
    v5 += gs * t2[q];
    v6 += gt;
    v7 += gt * s2[q];
    v8 += gt * t2[q];
  }
  const double v[9] = {v0, v1, v2, v3, v4, v5, v6, v7, v8};
  for (int j = 0; j < 9; ++j) m[j] = v[j];
}

/// A pair rule (singular pairs): one list of point pairs. The kernels at every point pair,
/// then each summed against the monomials (1, s1, t1) x (1, s2, t2) (9 moments per kernel),
/// and the moments give the entries of every pair of basis functions.
template <bool kDoubleLayer>
void accumulate_pairs(const Mapped& a, const Mapped& b, Vec3 na, Vec3 nb, const PairRule& r, Accumulated& acc) {
  const int n = r.size();
  std::vector<double>& scratch = moment_scratch(6 * static_cast<std::size_t>(n));
  double *dx = scratch.data(), *dy = dx + n, *dz = dy + n, *g = dz + n, *kab = g + n, *kba = kab + n;
  pair_differences(a, b, r, dx, dy, dz);
  const double* w = r.w.data();
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const double r2 = dx[q] * dx[q] + dy[q] * dy[q] + dz[q] * dz[q];
    g[q] = w[q] * kInvTwoPi / std::sqrt(r2);
    if constexpr (kDoubleLayer) {
      kab[q] = g[q] * (dx[q] * nb.x + dy[q] * nb.y + dz[q] * nb.z) / r2;
      kba[q] = -g[q] * (dx[q] * na.x + dy[q] * na.y + dz[q] * na.z) / r2;
    }
  }
  // the moments [alpha * 3 + beta] of V (mv), Kab (mk) and Kba (mt)
  double mv[9], mk[9] = {}, mt[9] = {};
  monomial_moments(n, g, r, mv);
  if constexpr (kDoubleLayer) {
    monomial_moments(n, kab, r, mk);
    monomial_moments(n, kba, r, mt);
  }
  double ca[4][3], cb[4][3];
  basis_coefficients(a, ca);
  basis_coefficients(b, cb);
  add_moments(ca, cb, mv, mk, mt, kDoubleLayer, acc);
}

/// A tensor-product rule (regular pairs): for each point x of a, the kernels summed over the
/// points y of b against (1, s2, t2) in one vectorised pass, then against a's basis at x.
template <bool kDoubleLayer>
void accumulate_tensor(const Mapped& a, const Mapped& b, Vec3 na, Vec3 nb, const TriangleRule& r, Accumulated& acc) {
  const int p = r.size();
  constexpr int kMax = 25;
  double yx[kMax], yy[kMax], yz[kMax], ys[kMax], yt[kMax], yw[kMax];
  for (int j = 0; j < p; ++j) {
    const std::size_t k = static_cast<std::size_t>(j);
    const Vec3 y = point(b, r.s[k], r.t[k]);
    yx[j] = y.x;
    yy[j] = y.y;
    yz[j] = y.z;
    ys[j] = r.s[k];
    yt[j] = r.t[k];
    yw[j] = r.w[k] * kInvTwoPi;
  }
  double ca[4][3], cb[4][3];
  basis_coefficients(a, ca);
  basis_coefficients(b, cb);
  // moments [alpha * 3 + beta] over both triangles of V, Kab, Kba
  double mv[9] = {}, mk[9] = {}, mt[9] = {};
  for (int i = 0; i < p; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const Vec3 x = point(a, r.s[k], r.t[k]);
    double g0 = 0, g1 = 0, g2 = 0, k0 = 0, k1 = 0, k2 = 0, u0 = 0, u1 = 0, u2 = 0;
#pragma omp simd reduction(+ : g0, g1, g2, k0, k1, k2, u0, u1, u2)
    for (int j = 0; j < p; ++j) {
      const double dx = x.x - yx[j], dy = x.y - yy[j], dz = x.z - yz[j];
      const double r2 = dx * dx + dy * dy + dz * dz;
      const double g = yw[j] / std::sqrt(r2);
      g0 += g;
      g1 += g * ys[j];
      g2 += g * yt[j];
      if constexpr (kDoubleLayer) {
        const double kab = g * (dx * nb.x + dy * nb.y + dz * nb.z) / r2;
        const double kba = -g * (dx * na.x + dy * na.y + dz * na.z) / r2;
        k0 += kab;
        k1 += kab * ys[j];
        k2 += kab * yt[j];
        u0 += kba;
        u1 += kba * ys[j];
        u2 += kba * yt[j];
      }
    }
    const double w = r.w[k], xs[3] = {w, w * r.s[k], w * r.t[k]};
    const double gv[3] = {g0, g1, g2}, kv[3] = {k0, k1, k2}, uv[3] = {u0, u1, u2};
    for (int al = 0; al < 3; ++al)
      for (int be = 0; be < 3; ++be) {
        mv[al * 3 + be] += xs[al] * gv[be];
        if constexpr (kDoubleLayer) {
          mk[al * 3 + be] += xs[al] * kv[be];
          mt[al * 3 + be] += xs[al] * uv[be];
        }
      }
  }
  add_moments(ca, cb, mv, mk, mt, kDoubleLayer, acc);
}

void accumulate_tensor(const Mapped& a, const Mapped& b, Vec3 na, Vec3 nb, const TriangleRule& r, bool double_layer,
                       Accumulated& acc) {
  if (double_layer)
    accumulate_tensor<true>(a, b, na, nb, r, acc);
  else
    accumulate_tensor<false>(a, b, na, nb, r, acc);
}

/// A pair (tau, sigma) as it is evaluated: on (a, b) = (min, max) (`swap` if tau > sigma), the
/// same points for both orders, each triangle mapped with the shared vertices first.
struct Selection {
  bool swap;
  const Triangle *a, *b;
  int shared;
  Mapped ma, mb;
};

Selection select(const Surface& surface, Index tau, Index sigma) {
  const bool swap = tau > sigma;
  const Triangle& a = surface.triangle(swap ? sigma : tau);
  const Triangle& b = surface.triangle(swap ? tau : sigma);
  const Adjacency adj = adjacency(a, b);
  int oa[3] = {0, 1, 2}, ob[3] = {0, 1, 2};
  if (adj.shared == 1 || adj.shared == 2) {
    for (int k = 0; k < adj.shared; ++k) {
      oa[k] = adj.a[static_cast<std::size_t>(k)];
      ob[k] = adj.b[static_cast<std::size_t>(k)];
    }
    complete(oa, adj.shared);
    complete(ob, adj.shared);
  }
  return {swap, &a, &b, adj.shared, mapped(a, oa), mapped(b, ob)};
}

// PairMoments: the moment kernels at a point pair (d = x - y, g = w / (2 pi |d|), the rule's
// weight w): 0: g; 1..6: g d_k d_l / |d|^2 for (k, l) = (0, 0), (1, 1), (2, 2), (0, 1),
// (0, 2), (1, 2); with the double layer 7: g n_b . d / |d|^2, 8: -g n_a . d / |d|^2 (Kab and
// Kba of Accumulated).
constexpr int kMomentKernels = 9;
constexpr int kMomentPairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};

/// The moment kernels c (0..6, with the double layer 0..8) at the point pairs d = (dx, dy, dz)[q]
/// with weights w[q] (kInvTwoPi included), q < n, into k[c * n + q].
template <bool kDoubleLayer>
void moment_kernels(int n, const double* dx, const double* dy, const double* dz, const double* w, Vec3 na, Vec3 nb,
                    double* k) {
  double *k0 = k, *k1 = k + n, *k2 = k + 2 * n, *k3 = k + 3 * n, *k4 = k + 4 * n, *k5 = k + 5 * n, *k6 = k + 6 * n,
         *k7 = k + 7 * n, *k8 = k + 8 * n;
#pragma omp simd
  for (int q = 0; q < n; ++q) {
    const double x = dx[q], y = dy[q], z = dz[q];
    const double r2 = x * x + y * y + z * z;
    const double g = w[q] / std::sqrt(r2), h = g / r2;
    k0[q] = g;
    k1[q] = h * x * x;
    k2[q] = h * y * y;
    k3[q] = h * z * z;
    k4[q] = h * x * y;
    k5[q] = h * x * z;
    k6[q] = h * y * z;
    if constexpr (kDoubleLayer) {
      k7[q] = h * (x * nb.x + y * nb.y + z * nb.z);
      k8[q] = -h * (x * na.x + y * na.y + z * na.z);
    }
  }
}

/// A pair rule: the kernels at every point pair, then each summed against the monomials
/// (1, s1, t1) x (1, s2, t2): m[c][alpha * 3 + beta].
template <bool kDoubleLayer>
void pair_moments(const Mapped& a, const Mapped& b, Vec3 na, Vec3 nb, const PairRule& r, double m[][9]) {
  constexpr int count = kDoubleLayer ? kMomentKernels : 7;
  const int n = r.size();
  const std::size_t un = static_cast<std::size_t>(n);
  std::vector<double>& scratch = moment_scratch((4 + kMomentKernels) * un);
  double *dx = scratch.data(), *dy = dx + n, *dz = dy + n, *w = dz + n, *k = w + n;
  pair_differences(a, b, r, dx, dy, dz);
  const double* rw = r.w.data();
#pragma omp simd
  for (int q = 0; q < n; ++q) w[q] = rw[q] * kInvTwoPi;
  moment_kernels<kDoubleLayer>(n, dx, dy, dz, w, na, nb, k);
  for (int c = 0; c < count; ++c) monomial_moments(n, k + c * n, r, m[c]);
}

/// The tensor product of symmetric_rule(degree) with itself as a pair rule (the regular pairs'
/// points of `integrate`, in one list for the moments' vectorised passes).
const PairRule& tensor_rule(int degree) {
  static const std::array<PairRule, 9> rules = [] {
    std::array<PairRule, 9> out;
    for (int d : kRegularDegrees) {
      const TriangleRule& r = symmetric_rule(d);
      PairRule& t = out[static_cast<std::size_t>(d)];
      for (int i = 0; i < r.size(); ++i)
        for (int j = 0; j < r.size(); ++j) {
          const std::size_t u = static_cast<std::size_t>(i), v = static_cast<std::size_t>(j);
          t.s1.push_back(r.s[u]);
          t.t1.push_back(r.t[u]);
          t.s2.push_back(r.s[v]);
          t.t2.push_back(r.t[v]);
          t.w.push_back(r.w[u] * r.w[v]);
        }
    }
    return out;
  }();
  return rules[static_cast<std::size_t>(degree)];
}

}  // namespace

Index dofs(const Surface& surface, Space space) { return space == Space::P1 ? surface.vertices() : surface.size(); }

PairIntegrator::PairIntegrator(const Surface& surface) : surface_(surface), planes_(triangle_planes(surface)) {
  singular_[0] = nullptr;
  for (int shared = 1; shared <= 3; ++shared) singular_[shared] = &singular_rule(shared, kSingularGaussPoints[shared]);
  std::fill(std::begin(regular_), std::end(regular_), nullptr);
  for (int d : kRegularDegrees) regular_[d] = &symmetric_rule(d);
}

int PairIntegrator::regular_rule(const Triangle& a, const Triangle& b) {
  // distance of the circumscribing balls about the centroids, over the larger diameter
  const double h = 2.0 * std::max(a.radius, b.radius);
  const double q = (norm(a.c - b.c) - (a.radius + b.radius)) / h;  // symmetric in a, b to the last bit
  // one rule for every pair from q = 1.5 on: the entries of an admissible block are then a
  // smooth function of the positions (a rule switching inside a block would add a jump at
  // the rule's error, which ACA could not compress below it; docs/design/bem3d.md)
  if (q >= kFarSeparation) return kRegularDegrees[2];
  if (q >= 0.5) return kRegularDegrees[1];
  return kRegularDegrees[0];
}

void PairIntegrator::integrate(Index tau, Index sigma, bool double_layer, PairIntegrals& out) const {
  const Selection pair = select(surface_, tau, sigma);
  const bool swap = pair.swap;
  const Triangle &a = *pair.a, &b = *pair.b;
  const Mapped &ma = pair.ma, &mb = pair.mb;
  Accumulated acc;
  // n . (x - y) vanishes between the points of one plane: K is zero on a triangle with
  // itself and between the triangles of one face of a polyhedron, where V alone is integrated
  const bool k = double_layer && planes_[static_cast<std::size_t>(tau)] != planes_[static_cast<std::size_t>(sigma)];
  if (pair.shared > 0)
    if (k)
      accumulate_pairs<true>(ma, mb, a.n, b.n, *singular_[pair.shared], acc);
    else
      accumulate_pairs<false>(ma, mb, a.n, b.n, *singular_[pair.shared], acc);
  else
    accumulate_tensor(ma, mb, a.n, b.n, *regular_[regular_rule(a, b)], k, acc);
  const double jac = 4.0 * a.area * b.area;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) out.V[i][j] = jac * (swap ? acc.V[j][i] : acc.V[i][j]);
  if (double_layer)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) {
        out.K[i][j] = jac * (swap ? acc.Kba[i][j] : acc.Kab[i][j]);
        out.Kt[i][j] = jac * (swap ? acc.Kab[i][j] : acc.Kba[i][j]);
      }
}

void PairIntegrator::moments(Index tau, Index sigma, bool double_layer, PairMoments& out) const {
  const Selection pair = select(surface_, tau, sigma);
  const Triangle &a = *pair.a, &b = *pair.b;
  // as in `integrate`: the double layer's kernel vanishes between the points of one plane
  const bool k = double_layer && planes_[static_cast<std::size_t>(tau)] != planes_[static_cast<std::size_t>(sigma)];
  double m[kMomentKernels][9];
  // the regular pairs by the points of `integrate`'s tensor products
  const PairRule& rule = pair.shared > 0 ? *singular_[pair.shared] : tensor_rule(regular_rule(a, b));
  if (k)
    pair_moments<true>(pair.ma, pair.mb, a.n, b.n, rule, m);
  else
    pair_moments<false>(pair.ma, pair.mb, a.n, b.n, rule, m);
  double ca[4][3], cb[4][3];
  basis_coefficients(pair.ma, ca);
  basis_coefficients(pair.mb, cb);
  // e[c][i][j]: the entry (i of a, j of b) of the kernel c = sum ca[i][al] m[c][al, be] cb[j][be],
  // scaled by the Jacobians
  const double jac = 4.0 * a.area * b.area;
  const int count = k ? kMomentKernels : 7;
  double e[kMomentKernels][4][4];
  for (int c = 0; c < count; ++c) {
    double t[3][4];
    for (int al = 0; al < 3; ++al)
      for (int j = 0; j < 4; ++j)
        t[al][j] = jac * (m[c][al * 3] * cb[j][0] + m[c][al * 3 + 1] * cb[j][1] + m[c][al * 3 + 2] * cb[j][2]);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) e[c][i][j] = ca[i][0] * t[0][j] + ca[i][1] * t[1][j] + ca[i][2] * t[2][j];
  }
  // in the order (tau, sigma): tau's basis i is b's if swapped
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const int ia = pair.swap ? j : i, jb = pair.swap ? i : j;
      out.G[i][j] = e[0][ia][jb];
      for (int c = 0; c < 6; ++c) {
        const int kk = kMomentPairs[c][0], l = kMomentPairs[c][1];
        out.R[kk][l][i][j] = out.R[l][kk][i][j] = e[1 + c][ia][jb];
      }
    }
  if (double_layer)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) {
        // Kab (7): test a (i), trial b (j); Kba (8): test b (i), trial a (j)
        const double kab = k ? e[7][i][j] : 0.0, kba = k ? e[8][j][i] : 0.0;
        out.K[i][j] = pair.swap ? kba : kab;
        out.Kt[i][j] = pair.swap ? kab : kba;
      }
}

double far_distance(const Surface& s) {
  double radius = 0.0;
  for (const Triangle& T : s.triangles()) radius = std::max(radius, T.radius);
  return far_distance(radius);
}

Vec3 surface_curl(const Triangle& t, int a) {
  // n x grad(lambda_a) = (p_{a+1} - p_{a+2}) / (2 A)
  const Vec3 e = t.p[static_cast<std::size_t>((a + 1) % 3)] - t.p[static_cast<std::size_t>((a + 2) % 3)];
  return (0.5 / t.area) * e;
}

SurfaceMatrices assemble(const Surface& surface, const SurfaceRequest& request) {
  // Each unordered pair {tau, sigma} is integrated once (tau <= sigma) and gives the entries
  // of both orders: V and W are accumulated as their upper parts H (pairs tau < sigma whole,
  // tau = sigma halved) and completed as H + H^T; K as the rows of tau (pair (tau, sigma))
  // plus, transposed, the rows of sigma (pair (sigma, tau), stored in Kt by the rows of
  // tau's vertices). Threads own the rows of tau's vertices (colouring), so no two write
  // the same row.
  const Index m = surface.size(), n = surface.vertices();
  const std::optional<Space> vs = request.single_layer, ks = request.double_layer;
  const bool k = ks.has_value(), w = request.hypersingular;
  Matrix V, K, Kt, W;
  if (vs) V = Matrix::Zero(dofs(surface, *vs), dofs(surface, *vs));
  if (k) {
    K = Matrix::Zero(dofs(surface, *ks), n);
    Kt = Matrix::Zero(n, dofs(surface, *ks));
  }
  if (w) W = Matrix::Zero(n, n);
  const PairIntegrator integrator(surface);
  for_each_triangle_by_colour(surface, [&](Index tau) {
    const Triangle& a = surface.triangle(tau);
    Vec3 curl_a[3];
    for (int i = 0; i < 3; ++i) curl_a[i] = surface_curl(a, i);
    PairIntegrals L;
    for (Index sigma = tau; sigma < m; ++sigma) {
      integrator.integrate(tau, sigma, k, L);
      const Triangle& b = surface.triangle(sigma);
      const double half = sigma == tau ? 0.5 : 1.0;
      if (vs) {
        if (*vs == Space::P0) {
          V(tau, sigma) += half * L.V[3][3];
        } else {
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) V(a.v[i], b.v[j]) += half * L.V[i][j];
        }
      }
      if (k) {
        if (*ks == Space::P0) {
          for (int j = 0; j < 3; ++j) K(tau, b.v[j]) += L.K[3][j];
          if (sigma != tau)
            for (int i = 0; i < 3; ++i) Kt(a.v[i], sigma) += L.Kt[3][i];
        } else {
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
              K(a.v[i], b.v[j]) += L.K[i][j];
              if (sigma != tau) Kt(a.v[i], b.v[j]) += L.Kt[j][i];
            }
        }
      }
      if (w)
        for (int j = 0; j < 3; ++j) {
          const Vec3 cb = surface_curl(b, j);
          for (int i = 0; i < 3; ++i) W(a.v[i], b.v[j]) += half * L.V[3][3] * dot(curl_a[i], cb);
        }
    }
  });
  SurfaceMatrices out;
  if (vs) out.single_layer = V + V.transpose();
  if (k) out.double_layer = K + Kt.transpose();
  if (w) out.hypersingular = W + W.transpose();
  return out;
}

Matrix mass(const Surface& surface, Space space) {
  Matrix M = Matrix::Zero(dofs(surface, space), surface.vertices());
  for (Index t = 0; t < surface.size(); ++t) {
    const Triangle& T = surface.triangle(t);
    for (int j = 0; j < 3; ++j) {
      if (space == Space::P0) {
        M(t, T.v[j]) += T.area / 3.0;
      } else {
        for (int i = 0; i < 3; ++i) M(T.v[i], T.v[j]) += T.area / 12.0 * (i == j ? 2.0 : 1.0);
      }
    }
  }
  return M;
}

Matrix hypersingular_block(const Surface& surface, const std::vector<Index>& vertices) {
  // As `assemble` for W alone, over the pairs of triangles that touch a chosen vertex: the
  // upper part (tau <= sigma, tau = sigma halved) completed as H + H^T.
  const Index n = surface.vertices(), k = static_cast<Index>(vertices.size());
  std::vector<Index> local(static_cast<std::size_t>(n), -1);
  for (Index i = 0; i < k; ++i) {
    const Index v = vertices[static_cast<std::size_t>(i)];
    if (v < 0 || v >= n) throw std::invalid_argument("vertices: index " + std::to_string(v) + " out of range");
    if (local[static_cast<std::size_t>(v)] >= 0)
      throw std::invalid_argument("vertices: index " + std::to_string(v) + " repeated");
    local[static_cast<std::size_t>(v)] = i;
  }
  auto chosen = [&](Index v) { return local[static_cast<std::size_t>(v)]; };
  std::vector<Index> touching;  // ascending
  for (Index t = 0; t < surface.size(); ++t) {
    const Triangle& T = surface.triangle(t);
    if (chosen(T.v[0]) >= 0 || chosen(T.v[1]) >= 0 || chosen(T.v[2]) >= 0) touching.push_back(t);
  }
  std::vector<char> touches(static_cast<std::size_t>(surface.size()), 0);
  for (Index t : touching) touches[static_cast<std::size_t>(t)] = 1;
  Matrix W = Matrix::Zero(k, k);
  const PairIntegrator integrator(surface);
  for_each_triangle_by_colour(surface, [&](Index tau) {
    if (!touches[static_cast<std::size_t>(tau)]) return;
    const Triangle& a = surface.triangle(tau);
    Vec3 curl_a[3];
    for (int i = 0; i < 3; ++i) curl_a[i] = surface_curl(a, i);
    PairIntegrals L;
    for (auto it = std::lower_bound(touching.begin(), touching.end(), tau); it != touching.end(); ++it) {
      const Index sigma = *it;
      integrator.integrate(tau, sigma, false, L);
      const Triangle& b = surface.triangle(sigma);
      const double half = sigma == tau ? 0.5 : 1.0;
      for (int j = 0; j < 3; ++j) {
        const Index cj = chosen(b.v[j]);
        if (cj < 0) continue;
        const Vec3 cb = surface_curl(b, j);
        for (int i = 0; i < 3; ++i) {
          const Index ci = chosen(a.v[i]);
          if (ci >= 0) W(ci, cj) += half * L.V[3][3] * dot(curl_a[i], cb);
        }
      }
    }
  });
  return W + W.transpose();
}

Matrix single_layer(VerticesRef vertices, TrianglesRef triangles, Space space) {
  SurfaceRequest r;
  r.single_layer = space;
  return assemble(Surface(vertices, triangles), r).single_layer;
}

Matrix double_layer(VerticesRef vertices, TrianglesRef triangles, Space space) {
  SurfaceRequest r;
  r.double_layer = space;
  return assemble(Surface(vertices, triangles), r).double_layer;
}

Matrix hypersingular(VerticesRef vertices, TrianglesRef triangles) {
  SurfaceRequest r;
  r.hypersingular = true;
  return assemble(Surface(vertices, triangles), r).hypersingular;
}

Matrix hypersingular_block(VerticesRef vertices, TrianglesRef triangles, const std::vector<Index>& block) {
  return hypersingular_block(Surface(vertices, triangles), block);
}

Matrix mass(VerticesRef vertices, TrianglesRef triangles, Space space) {
  return mass(Surface(vertices, triangles), space);
}

}  // namespace bem
