#pragma once
// Test surfaces shared by the GoogleTest files of the 3D code: the icosphere and the
// boundaries of voxel sets (cube, Fichera-type L-shaped polyhedron).
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "bem/surface.hpp"

namespace bem::test {

struct Mesh {
  Vertices vertices;
  Triangles triangles;
};

/// Icosahedron refined `level` times (each triangle into 4), vertices projected to |x| = R.
inline Mesh icosphere(int level, double R = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> P = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<Index, 3>> T = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                         {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                         {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                         {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  auto project = [](std::array<double, 3> p) {
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / r, p[1] / r, p[2] / r};
  };
  for (auto& p : P) p = project(p);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<Index, Index>, Index> mid;
    auto midpoint = [&](Index a, Index b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const auto& p = P[static_cast<std::size_t>(a)];
      const auto& q = P[static_cast<std::size_t>(b)];
      P.push_back(project({p[0] + q[0], p[1] + q[1], p[2] + q[2]}));
      return mid[key] = static_cast<Index>(P.size()) - 1;
    };
    std::vector<std::array<Index, 3>> next;
    for (const auto& f : T) {
      const Index a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    T = next;
  }
  Mesh m{Vertices(static_cast<Index>(P.size()), 3), Triangles(static_cast<Index>(T.size()), 3)};
  for (std::size_t i = 0; i < P.size(); ++i)
    for (int k = 0; k < 3; ++k) m.vertices(static_cast<Index>(i), k) = R * P[i][static_cast<std::size_t>(k)];
  for (std::size_t i = 0; i < T.size(); ++i)
    for (int k = 0; k < 3; ++k) m.triangles(static_cast<Index>(i), k) = T[i][static_cast<std::size_t>(k)];
  return m;
}

/// Boundary of the union of the voxels [i, i+1] x [j, j+1] x [k, k+1] (scaled by h) with
/// inside(i, j, k), 0 <= i, j, k < N: two triangles per exposed voxel face, outward.
inline Mesh voxels(int N, double h, const std::function<bool(int, int, int)>& inside) {
  std::map<std::array<int, 3>, Index> index;
  std::vector<std::array<int, 3>> P;
  std::vector<std::array<Index, 3>> T;
  auto vertex = [&](std::array<int, 3> p) {
    auto it = index.find(p);
    if (it != index.end()) return it->second;
    P.push_back(p);
    return index[p] = static_cast<Index>(P.size()) - 1;
  };
  auto in = [&](int i, int j, int k) {
    return i >= 0 && j >= 0 && k >= 0 && i < N && j < N && k < N && inside(i, j, k);
  };
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j)
      for (int k = 0; k < N; ++k) {
        if (!inside(i, j, k)) continue;
        for (int axis = 0; axis < 3; ++axis)
          for (int side = 0; side < 2; ++side) {
            std::array<int, 3> c{i, j, k}, nb{i, j, k};
            nb[static_cast<std::size_t>(axis)] += side ? 1 : -1;
            if (in(nb[0], nb[1], nb[2])) continue;
            c[static_cast<std::size_t>(axis)] += side;
            const std::size_t u = static_cast<std::size_t>((axis + 1) % 3),
                              v = static_cast<std::size_t>((axis + 2) % 3);
            std::array<Index, 4> q;
            const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
            for (int r = 0; r < 4; ++r) {
              std::array<int, 3> p = c;
              p[u] += du[r];
              p[v] += dv[r];
              q[static_cast<std::size_t>(r)] = vertex(p);
            }
            if (side) {
              T.push_back({q[0], q[1], q[2]});
              T.push_back({q[0], q[2], q[3]});
            } else {
              T.push_back({q[0], q[2], q[1]});
              T.push_back({q[0], q[3], q[2]});
            }
          }
      }
  Mesh m{Vertices(static_cast<Index>(P.size()), 3), Triangles(static_cast<Index>(T.size()), 3)};
  for (std::size_t i = 0; i < P.size(); ++i)
    for (int k = 0; k < 3; ++k)
      m.vertices(static_cast<Index>(i), k) = h * (P[i][static_cast<std::size_t>(k)] - 0.5 * N);
  for (std::size_t i = 0; i < T.size(); ++i)
    for (int k = 0; k < 3; ++k) m.triangles(static_cast<Index>(i), k) = T[i][static_cast<std::size_t>(k)];
  return m;
}

/// The cube [-N h / 2, N h / 2]^3 with N x N squares per face.
inline Mesh cube(int N, double h) {
  return voxels(N, h, [](int, int, int) { return true; });
}

/// Fichera-type L-shaped polyhedron: the cube without one octant (N even).
inline Mesh fichera(int N, double h) {
  return voxels(N, h, [N](int i, int j, int k) { return !(2 * i >= N && 2 * j >= N && 2 * k >= N); });
}

}  // namespace bem::test
