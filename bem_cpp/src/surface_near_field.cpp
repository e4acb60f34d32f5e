#include "bem/surface_near_field.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <unordered_map>

#include "bem/cluster_tree.hpp"

namespace bem {

// centroids closer than ra + rb + 2 kFarSeparation max(ra, rb)
std::vector<std::vector<Index>> near_pairs(const Surface& s, const std::vector<char>& triangles) {
  const Index m = s.size();
  Box box;
  for (const Triangle& T : s.triangles()) box.add(T.c);
  const double cell = far_distance(s);
  auto key = [&](const Vec3& c) {
    return std::array<long, 3>{static_cast<long>(std::floor((c.x - box.x0) / cell)),
                               static_cast<long>(std::floor((c.y - box.y0) / cell)),
                               static_cast<long>(std::floor((c.z - box.z0) / cell))};
  };
  const long nx = static_cast<long>((box.x1 - box.x0) / cell) + 1, ny = static_cast<long>((box.y1 - box.y0) / cell) + 1;
  auto code = [&](long i, long j, long k) { return (k * ny + j) * nx + i; };
  std::unordered_map<long, std::vector<Index>> cells;
  for (Index t = 0; t < m; ++t) {
    const auto c = key(s.triangle(t).c);
    cells[code(c[0], c[1], c[2])].push_back(t);
  }
  std::vector<std::vector<Index>> out(static_cast<std::size_t>(m));
  const bool all = triangles.empty();
#pragma omp parallel for schedule(dynamic, 64)
  for (Index t = 0; t < m; ++t) {
    const Triangle& a = s.triangle(t);
    const auto c = key(a.c);
    std::vector<Index>& list = out[static_cast<std::size_t>(t)];
    for (long k = c[2] - 1; k <= c[2] + 1; ++k)
      for (long j = c[1] - 1; j <= c[1] + 1; ++j)
        for (long i = c[0] - 1; i <= c[0] + 1; ++i) {
          if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny) continue;
          const auto it = cells.find(code(i, j, k));
          if (it == cells.end()) continue;
          for (Index u : it->second)
            if (u >= t && (all || triangles[static_cast<std::size_t>(t)] || triangles[static_cast<std::size_t>(u)]) &&
                !PairIntegrator::far(a, s.triangle(u)))
              list.push_back(u);
        }
    std::sort(list.begin(), list.end());
  }
  return out;
}

std::vector<Index> surface_row_bounds(const ClusterTree& tree, const HMatrixOptions& options, bool symmetric) {
  if (!options.comm || options.comm->size == 1) return {};
  HMatrixOptions o = options;
  o.symmetric = symmetric;
  return distributed_row_bounds(tree, tree, o, options.comm->size);
}

std::vector<char> rank_triangles(const Surface& s, const HMatrixOptions& options,
                                 const std::vector<std::pair<const ClusterTree*, std::vector<Index>>>& matrices) {
  if (!options.comm || options.comm->size == 1) return {};
  std::vector<char> vertices(static_cast<std::size_t>(s.vertices()), 0);
  const auto rank = static_cast<std::size_t>(options.comm->rank);
  for (const auto& [tree, bounds] : matrices) {
    const Index dofs = tree->size() / s.vertices();
    for (Index k = bounds[rank]; k < bounds[rank + 1]; ++k)
      vertices[static_cast<std::size_t>(tree->permutation()[static_cast<std::size_t>(k)] / dofs)] = 1;
  }
  std::vector<char> triangles(static_cast<std::size_t>(s.size()), 0);
  for (Index t = 0; t < s.size(); ++t)
    for (Index v : s.triangle(t).v) triangles[static_cast<std::size_t>(t)] |= vertices[static_cast<std::size_t>(v)];
  return triangles;
}

namespace {

/// A CSR pattern (row pointers and sorted column indices) with the position of an entry.
struct Pattern {
  std::vector<Index> ptr, col;
  Index position(Index i, Index j) const {
    const auto b = col.begin() + ptr[static_cast<std::size_t>(i)];
    const auto e = col.begin() + ptr[static_cast<std::size_t>(i) + 1];
    return static_cast<Index>(std::lower_bound(b, e, j) - col.begin());
  }
  RowSparse matrix(Index rows, Index cols, const std::vector<double>& values) const {
    RowSparse A(rows, cols);
    A.resizeNonZeros(static_cast<Index>(col.size()));
    std::copy(ptr.begin(), ptr.end(), A.outerIndexPtr());
    std::copy(col.begin(), col.end(), A.innerIndexPtr());
    std::copy(values.begin(), values.end(), A.valuePtr());
    return A;
  }
};

Pattern pattern(Index rows, const std::function<void(Index, std::vector<Index>&)>& columns) {
  std::vector<std::vector<Index>> lists(static_cast<std::size_t>(rows));
#pragma omp parallel for schedule(dynamic, 64)
  for (Index i = 0; i < rows; ++i) {
    std::vector<Index>& l = lists[static_cast<std::size_t>(i)];
    columns(i, l);
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
  }
  Pattern p;
  p.ptr.assign(static_cast<std::size_t>(rows) + 1, 0);
  for (Index i = 0; i < rows; ++i)
    p.ptr[static_cast<std::size_t>(i) + 1] =
        p.ptr[static_cast<std::size_t>(i)] + static_cast<Index>(lists[static_cast<std::size_t>(i)].size());
  p.col.reserve(static_cast<std::size_t>(p.ptr.back()));
  for (const auto& l : lists) p.col.insert(p.col.end(), l.begin(), l.end());
  return p;
}

}  // namespace

SurfaceNearField::SurfaceNearField(const Surface& s, bool with_p0, const std::vector<char>& triangles) {
  // As the dense assembly (surface_operators.cpp): each unordered pair (tau <= sigma) once,
  // into the rows of tau (V0) and of tau's vertices (V1, K, and K of the pair (sigma, tau)
  // transposed), the upper parts completed as H + H^T; threads own the rows by colouring.
  const Index m = s.size(), n = s.vertices();
  const std::vector<std::vector<Index>> near = near_pairs(s, triangles);
  const Pattern p0 =
      pattern(with_p0 ? m : 0, [&](Index t, std::vector<Index>& l) { l = near[static_cast<std::size_t>(t)]; });
  const Pattern p1 = pattern(n, [&](Index i, std::vector<Index>& l) {
    for (Index t : s.star(i))
      for (Index u : near[static_cast<std::size_t>(t)])
        for (Index v : s.triangle(u).v) l.push_back(v);
  });
  std::vector<double> h0(p0.col.size(), 0.0), h1(p1.col.size(), 0.0), k1(p1.col.size(), 0.0), kt1(p1.col.size(), 0.0),
      w1(p1.col.size(), 0.0);
  const PairIntegrator integrator(s);
  for_each_triangle_by_colour(s, [&](Index tau) {
    const Triangle& a = s.triangle(tau);
    PairIntegrals L;
    for (Index sigma : near[static_cast<std::size_t>(tau)]) {
      integrator.integrate(tau, sigma, true, L);
      const Triangle& b = s.triangle(sigma);
      const double half = sigma == tau ? 0.5 : 1.0;
      if (with_p0) h0[static_cast<std::size_t>(p0.position(tau, sigma))] += half * L.V[3][3];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const std::size_t k = static_cast<std::size_t>(p1.position(a.v[i], b.v[j]));
          h1[k] += half * L.V[i][j];
          w1[k] += half * L.V[3][3] * dot(surface_curl(a, i), surface_curl(b, j));
          k1[k] += L.K[i][j];
          if (sigma != tau) kt1[k] += L.Kt[j][i];
        }
    }
  });
  const RowSparse H1 = p1.matrix(n, n, h1);
  if (with_p0) {
    const RowSparse H0 = p0.matrix(m, m, h0);
    v0_ = RowSparse(H0 + RowSparse(H0.transpose()));
  }
  v1_ = RowSparse(H1 + RowSparse(H1.transpose()));
  const RowSparse W1 = p1.matrix(n, n, w1);
  w_ = RowSparse(W1 + RowSparse(W1.transpose()));
  k_ = RowSparse(p1.matrix(n, n, k1) + RowSparse(p1.matrix(n, n, kt1).transpose()));
  kt_ = RowSparse(k_.transpose());
}

}  // namespace bem
