#include "bem/surface_operators.hpp"

#include <algorithm>
#include <cmath>
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

/// Barycentric coordinates (by the triangle's own vertex numbering) of the point (s, t) of
/// the mapped triangle m, and the constant 1 at index 3.
inline void basis(const Mapped& m, double s, double t, double out[4]) {
  out[m.order[0]] = 1.0 - s - t;
  out[m.order[1]] = s;
  out[m.order[2]] = t;
  out[3] = 1.0;
}

inline Vec3 point(const Mapped& m, double s, double t) { return m.q0 + s * m.e1 + t * m.e2; }

/// A pair rule (singular pairs): one list of point pairs.
void accumulate_pairs(const Mapped& a, const Mapped& b, Vec3 na, Vec3 nb, const PairRule& r, bool double_layer,
                      Accumulated& acc) {
  for (int q = 0; q < r.size(); ++q) {
    const std::size_t k = static_cast<std::size_t>(q);
    const Vec3 d = point(a, r.s1[k], r.t1[k]) - point(b, r.s2[k], r.t2[k]);
    const double r2 = dot(d, d);
    const double g = r.w[k] * kInvTwoPi / std::sqrt(r2);
    double la[4], lb[4];
    basis(a, r.s1[k], r.t1[k], la);
    basis(b, r.s2[k], r.t2[k], lb);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) acc.V[i][j] += g * la[i] * lb[j];
    if (double_layer) {
      const double kab = g * dot(d, nb) / r2, kba = -g * dot(d, na) / r2;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 3; ++j) {
          acc.Kab[i][j] += kab * la[i] * lb[j];
          acc.Kba[i][j] += kba * lb[i] * la[j];
        }
    }
  }
}

/// A tensor-product rule (regular pairs): the kernel at every point pair, contracted with
/// the basis values one triangle at a time (4 + 4 products per point pair instead of 16 + 24).
void accumulate_tensor(const Mapped& a, const Mapped& b, Vec3 na, Vec3 nb, const TriangleRule& r, bool double_layer,
                       Accumulated& acc) {
  const int p = r.size();
  constexpr int kMax = 25;
  Vec3 y[kMax];
  double lb[kMax][4], ynb[kMax], yna[kMax];
  for (int j = 0; j < p; ++j) {
    const std::size_t k = static_cast<std::size_t>(j);
    y[j] = point(b, r.s[k], r.t[k]);
    basis(b, r.s[k], r.t[k], lb[j]);
    for (int c = 0; c < 4; ++c) lb[j][c] *= r.w[k];
    ynb[j] = dot(y[j], nb);
    yna[j] = dot(y[j], na);
  }
  for (int i = 0; i < p; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const Vec3 x = point(a, r.s[k], r.t[k]);
    const double xnb = dot(x, nb), xna = dot(x, na);
    double la[4];
    basis(a, r.s[k], r.t[k], la);
    double tv[4] = {}, tk[3] = {}, tt[4] = {};
    for (int j = 0; j < p; ++j) {
      const Vec3 d = x - y[j];
      const double r2 = dot(d, d);
      const double g = kInvTwoPi / std::sqrt(r2);
      for (int c = 0; c < 4; ++c) tv[c] += g * lb[j][c];
      if (double_layer) {
        const double gk = g / r2;
        const double kab = gk * (xnb - ynb[j]), kba = -gk * (xna - yna[j]);
        for (int c = 0; c < 3; ++c) tk[c] += kab * lb[j][c];
        for (int c = 0; c < 4; ++c) tt[c] += kba * lb[j][c];
      }
    }
    const double w = r.w[k];
    for (int c = 0; c < 4; ++c) la[c] *= w;
    for (int i2 = 0; i2 < 4; ++i2)
      for (int j = 0; j < 4; ++j) acc.V[i2][j] += la[i2] * tv[j];
    if (double_layer)
      for (int i2 = 0; i2 < 4; ++i2)
        for (int j = 0; j < 3; ++j) {
          acc.Kab[i2][j] += la[i2] * tk[j];
          acc.Kba[i2][j] += tt[i2] * la[j];
        }
  }
}

}  // namespace

Index dofs(const Surface& surface, Space space) { return space == Space::P1 ? surface.vertices() : surface.size(); }

PairIntegrator::PairIntegrator(const Surface& surface) : surface_(surface) {
  singular_[0] = nullptr;
  for (int shared = 1; shared <= 3; ++shared) singular_[shared] = &singular_rule(shared, kSingularGaussPoints[shared]);
  for (int p = 0; p < 6; ++p) regular_[p] = p < 3 ? nullptr : &triangle_rule(p);
}

int PairIntegrator::regular_points(const Triangle& a, const Triangle& b) {
  // distance of the circumscribing balls about the centroids, over the larger diameter
  const double h = 2.0 * std::max(a.radius, b.radius);
  const double q = (norm(a.c - b.c) - (a.radius + b.radius)) / h;  // symmetric in a, b to the last bit
  // one rule for every pair from q = 1.5 on: the entries of an admissible block are then a
  // smooth function of the positions (a rule switching inside a block would add a jump at
  // the rule's error, which ACA could not compress below it; docs/design/bem3d.md)
  if (q >= kFarSeparation) return kFarGaussPoints;
  if (q >= 0.5) return 4;
  return 5;
}

void PairIntegrator::integrate(Index tau, Index sigma, bool double_layer, PairIntegrals& out) const {
  const bool swap = tau > sigma;  // evaluate on (min, max), the same points for both orders
  const Triangle& a = surface_.triangle(swap ? sigma : tau);
  const Triangle& b = surface_.triangle(swap ? tau : sigma);
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
  const Mapped ma = mapped(a, oa), mb = mapped(b, ob);
  Accumulated acc;
  if (adj.shared > 0)
    accumulate_pairs(ma, mb, a.n, b.n, *singular_[adj.shared], double_layer, acc);
  else
    accumulate_tensor(ma, mb, a.n, b.n, *regular_[regular_points(a, b)], double_layer, acc);
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
