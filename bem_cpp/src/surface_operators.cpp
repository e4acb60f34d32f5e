#include "bem/surface_operators.hpp"

#include <algorithm>
#include <cmath>
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

/// The integrals of the pair (a, b) from points x in a, y in b; `swap`: the test triangle
/// is b (then out.V is the transpose and K uses d = y - x and the normal of a), so that the
/// pairs (tau, sigma) and (sigma, tau) are evaluated at the same points: V_h is symmetric
/// to round-off.
void accumulate(const Mapped& a, const Mapped& b, Vec3 na, Vec3 nb, const double* s1, const double* t1,
                const double* s2, const double* t2, const double* w, int size, bool swap, bool double_layer,
                PairIntegrals& out) {
  double V[4][4] = {}, K[4][3] = {};
  const Vec3 n_trial = swap ? na : nb;
  for (int q = 0; q < size; ++q) {
    const Vec3 x = a.q0 + s1[q] * a.e1 + t1[q] * a.e2;
    const Vec3 y = b.q0 + s2[q] * b.e1 + t2[q] * b.e2;
    const Vec3 d = x - y;
    const double r2 = dot(d, d), r = std::sqrt(r2);
    const double g = w[q] * kInvTwoPi / r;
    double la[4], lb[4];
    la[a.order[0]] = 1.0 - s1[q] - t1[q];
    la[a.order[1]] = s1[q];
    la[a.order[2]] = t1[q];
    la[3] = 1.0;
    lb[b.order[0]] = 1.0 - s2[q] - t2[q];
    lb[b.order[1]] = s2[q];
    lb[b.order[2]] = t2[q];
    lb[3] = 1.0;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) V[i][j] += g * la[i] * lb[j];
    if (double_layer) {
      // test point minus trial point, dotted with the trial normal
      const double k = (swap ? -g : g) * dot(d, n_trial) / r2;
      const double* lt = swap ? lb : la;
      const double* ls = swap ? la : lb;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 3; ++j) K[i][j] += k * lt[i] * ls[j];
    }
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) out.V[i][j] = swap ? V[j][i] : V[i][j];
  if (double_layer)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) out.K[i][j] = K[i][j];
}

}  // namespace

Index dofs(const Surface& surface, Space space) { return space == Space::P1 ? surface.vertices() : surface.size(); }

PairIntegrator::PairIntegrator(const Surface& surface) : surface_(surface) {
  singular_[0] = nullptr;
  for (int shared = 1; shared <= 3; ++shared) singular_[shared] = &singular_rule(shared, kSingularGaussPoints[shared]);
  for (int p = 3; p < 6; ++p) {
    const TriangleRule& r = triangle_rule(p);
    PairRule& t = regular_[p];
    for (int i = 0; i < r.size(); ++i)
      for (int j = 0; j < r.size(); ++j) {
        t.s1.push_back(r.s[static_cast<std::size_t>(i)]);
        t.t1.push_back(r.t[static_cast<std::size_t>(i)]);
        t.s2.push_back(r.s[static_cast<std::size_t>(j)]);
        t.t2.push_back(r.t[static_cast<std::size_t>(j)]);
        t.w.push_back(r.w[static_cast<std::size_t>(i)] * r.w[static_cast<std::size_t>(j)]);
      }
  }
}

int PairIntegrator::regular_points(const Triangle& a, const Triangle& b) {
  // distance of the circumscribing balls about the centroids, over the larger diameter
  const double h = 2.0 * std::max(a.radius, b.radius);
  const double q = (norm(a.c - b.c) - a.radius - b.radius) / h;
  // one rule for every pair from q = 1.5 on: the entries of an admissible block are then a
  // smooth function of the positions (a rule switching inside a block would add a jump at
  // the rule's error, which ACA could not compress below it; docs/design/bem3d.md)
  if (q >= 1.5) return 3;
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
  const PairRule& r = adj.shared > 0 ? *singular_[adj.shared] : regular_[regular_points(a, b)];
  accumulate(ma, mb, a.n, b.n, r.s1.data(), r.t1.data(), r.s2.data(), r.t2.data(), r.w.data(), r.size(), swap,
             double_layer, out);
  const double jac = 4.0 * a.area * b.area;
  for (auto& row : out.V)
    for (double& v : row) v *= jac;
  if (double_layer)
    for (auto& row : out.K)
      for (double& v : row) v *= jac;
}

Vec3 surface_curl(const Triangle& t, int a) {
  // n x grad(lambda_a) = (p_{a+1} - p_{a+2}) / (2 A)
  const Vec3 e = t.p[static_cast<std::size_t>((a + 1) % 3)] - t.p[static_cast<std::size_t>((a + 2) % 3)];
  return (0.5 / t.area) * e;
}

namespace {

/// Greedy colouring of the triangles: no two triangles of one colour share a vertex.
std::vector<std::vector<Index>> colours(const Surface& s) {
  const Index m = s.size();
  std::vector<int> colour(static_cast<std::size_t>(m), -1);
  std::vector<std::vector<Index>> out;
  for (Index t = 0; t < m; ++t) {
    std::vector<char> taken(out.size() + 1, 0);
    for (Index v : s.triangle(t).v)
      for (Index u : s.star(v)) {
        const int c = colour[static_cast<std::size_t>(u)];
        if (c >= 0) taken[static_cast<std::size_t>(c)] = 1;
      }
    const int c = static_cast<int>(std::find(taken.begin(), taken.end(), 0) - taken.begin());
    if (c == static_cast<int>(out.size())) out.emplace_back();
    colour[static_cast<std::size_t>(t)] = c;
    out[static_cast<std::size_t>(c)].push_back(t);
  }
  return out;
}

}  // namespace

SurfaceMatrices assemble(const Surface& surface, const SurfaceRequest& request) {
  const Index m = surface.size(), n = surface.vertices();
  SurfaceMatrices out;
  if (request.single_layer)
    out.single_layer = Matrix::Zero(dofs(surface, *request.single_layer), dofs(surface, *request.single_layer));
  if (request.double_layer) out.double_layer = Matrix::Zero(dofs(surface, *request.double_layer), n);
  if (request.hypersingular) out.hypersingular = Matrix::Zero(n, n);
  const bool k = request.double_layer.has_value();
  const PairIntegrator integrator(surface);
  for (const std::vector<Index>& colour : colours(surface)) {
    const long count = static_cast<long>(colour.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (long q = 0; q < count; ++q) {
      const Index tau = colour[static_cast<std::size_t>(q)];
      const Triangle& a = surface.triangle(tau);
      Vec3 curl_a[3];
      for (int i = 0; i < 3; ++i) curl_a[i] = surface_curl(a, i);
      PairIntegrals L;
      for (Index sigma = 0; sigma < m; ++sigma) {
        integrator.integrate(tau, sigma, k, L);
        const Triangle& b = surface.triangle(sigma);
        if (request.single_layer) {
          if (*request.single_layer == Space::P0) {
            out.single_layer(tau, sigma) += L.V[3][3];
          } else {
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) out.single_layer(a.v[i], b.v[j]) += L.V[i][j];
          }
        }
        if (k) {
          if (*request.double_layer == Space::P0) {
            for (int j = 0; j < 3; ++j) out.double_layer(tau, b.v[j]) += L.K[3][j];
          } else {
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) out.double_layer(a.v[i], b.v[j]) += L.K[i][j];
          }
        }
        if (request.hypersingular)
          for (int j = 0; j < 3; ++j) {
            const Vec3 cb = surface_curl(b, j);
            for (int i = 0; i < 3; ++i) out.hypersingular(a.v[i], b.v[j]) += L.V[3][3] * dot(curl_a[i], cb);
          }
      }
    }
  }
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

Matrix mass(VerticesRef vertices, TrianglesRef triangles, Space space) {
  return mass(Surface(vertices, triangles), space);
}

}  // namespace bem
