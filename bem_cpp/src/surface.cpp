#include "bem/surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace bem {

namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

std::string str(Vec3 p) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << p.x << ", " << p.y << ", " << p.z << ")";
  return s.str();
}

}  // namespace

Surface::Surface(const Eigen::Ref<const Vertices>& vertices, const Eigen::Ref<const Triangles>& triangles) {
  n_ = vertices.rows();
  const Index m = triangles.rows();
  if (n_ < 4) fail("vertices: a closed surface needs at least 4 vertices, got " + std::to_string(n_));
  if (m < 4) fail("triangles: a closed surface needs at least 4 triangles, got " + std::to_string(m));
  points_.resize(static_cast<std::size_t>(n_));
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (Index i = 0; i < n_; ++i) {
    const Vec3 p{vertices(i, 0), vertices(i, 1), vertices(i, 2)};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      fail("vertices: non-finite coordinates at vertex " + std::to_string(i));
    points_[static_cast<std::size_t>(i)] = p;
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  diameter_ = norm(hi - lo);
  {  // duplicate vertices: sort by coordinates, compare neighbours
    std::vector<Index> order(static_cast<std::size_t>(n_));
    for (Index i = 0; i < n_; ++i) order[static_cast<std::size_t>(i)] = i;
    auto key = [&](Index i) {
      const Vec3& p = points_[static_cast<std::size_t>(i)];
      return std::make_tuple(p.x, p.y, p.z);
    };
    std::sort(order.begin(), order.end(), [&](Index a, Index b) { return key(a) < key(b); });
    for (std::size_t k = 1; k < order.size(); ++k)
      if (key(order[k]) == key(order[k - 1]))
        fail("vertices: duplicate vertices " + std::to_string(std::min(order[k], order[k - 1])) + " and " +
             std::to_string(std::max(order[k], order[k - 1])) + " at " + str(points_[order[k]]) +
             " (merge them and renumber the triangles)");
  }
  stars_.resize(static_cast<std::size_t>(n_));
  triangles_.resize(static_cast<std::size_t>(m));
  const double zero_area = 1e-14 * diameter_ * diameter_;
  for (Index t = 0; t < m; ++t) {
    Triangle& T = triangles_[static_cast<std::size_t>(t)];
    for (int a = 0; a < 3; ++a) {
      const Index v = static_cast<Index>(triangles(t, a));
      if (v < 0 || v >= n_)
        fail("triangles: vertex index " + std::to_string(v) + " of triangle " + std::to_string(t) +
             " is out of range [0, " + std::to_string(n_) + ")");
      T.v[static_cast<std::size_t>(a)] = v;
      T.p[static_cast<std::size_t>(a)] = points_[static_cast<std::size_t>(v)];
    }
    const Vec3 c = cross(T.p[1] - T.p[0], T.p[2] - T.p[0]);
    const double twice = norm(c);
    if (T.v[0] == T.v[1] || T.v[1] == T.v[2] || T.v[0] == T.v[2] || !(0.5 * twice > zero_area))
      fail("triangles: zero-area triangle " + std::to_string(t) + " (vertices " + std::to_string(T.v[0]) + ", " +
           std::to_string(T.v[1]) + ", " + std::to_string(T.v[2]) + ")");
    T.area = 0.5 * twice;
    T.n = (1.0 / twice) * c;
    T.c = (1.0 / 3.0) * (T.p[0] + T.p[1] + T.p[2]);
    T.radius = std::max({norm(T.p[0] - T.c), norm(T.p[1] - T.c), norm(T.p[2] - T.c)});
    h_ = std::max({h_, norm(T.p[1] - T.p[0]), norm(T.p[2] - T.p[1]), norm(T.p[0] - T.p[2])});
    volume_ += dot(T.p[0], cross(T.p[1], T.p[2])) / 6.0;
    for (Index v : T.v) stars_[static_cast<std::size_t>(v)].push_back(t);
  }
  for (Index i = 0; i < n_; ++i)
    if (stars_[static_cast<std::size_t>(i)].empty())
      fail("vertices: vertex " + std::to_string(i) + " belongs to no triangle (remove it)");
  // Edges: each undirected edge in exactly two triangles, traversed in opposite directions.
  std::map<std::pair<Index, Index>, std::vector<std::pair<Index, bool>>> edges;  // -> (triangle, forward)
  for (Index t = 0; t < m; ++t)
    for (int a = 0; a < 3; ++a) {
      const Index u = triangles_[static_cast<std::size_t>(t)].v[static_cast<std::size_t>(a)];
      const Index w = triangles_[static_cast<std::size_t>(t)].v[static_cast<std::size_t>((a + 1) % 3)];
      edges[{std::min(u, w), std::max(u, w)}].push_back({t, u < w});
    }
  for (const auto& [e, ts] : edges) {
    const std::string edge = "edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) + ")";
    if (ts.size() == 1)
      fail("triangles: open surface: boundary " + edge + " belongs to triangle " + std::to_string(ts[0].first) +
           " only (the surface must be closed)");
    if (ts.size() > 2)
      fail("triangles: non-manifold " + edge + " shared by " + std::to_string(ts.size()) + " triangles (" +
           std::to_string(ts[0].first) + ", " + std::to_string(ts[1].first) + ", " + std::to_string(ts[2].first) +
           ", ...)");
    if (ts[0].second == ts[1].second)
      fail("triangles: inconsistent orientation: triangles " + std::to_string(ts[0].first) + " and " +
           std::to_string(ts[1].first) + " traverse " + edge +
           " in the same direction (order every triangle counter-clockwise seen from outside)");
  }
  if (!(volume_ > 0))
    fail("triangles: inward orientation: the normals point into Omega (enclosed volume " + std::to_string(volume_) +
         "); reverse the vertex order of every triangle");
}

std::vector<int> triangle_planes(const Surface& surface) {
  double scale = 0.0;
  for (const Triangle& T : surface.triangles()) scale = std::max(scale, norm(T.c));
  auto q = [](double v) { return static_cast<long long>(std::llround(v * 1e8)); };
  std::map<std::array<long long, 4>, int> ids;
  std::vector<int> out;
  out.reserve(surface.triangles().size());
  for (const Triangle& T : surface.triangles()) {
    const std::array<long long, 4> key{q(T.n.x), q(T.n.y), q(T.n.z), q(dot(T.n, T.c) / (scale + 1e-300))};
    out.push_back(ids.emplace(key, static_cast<int>(ids.size())).first->second);
  }
  return out;
}

Adjacency adjacency(const Triangle& s, const Triangle& t) {
  Adjacency r;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (s.v[static_cast<std::size_t>(a)] == t.v[static_cast<std::size_t>(b)]) {
        r.a[static_cast<std::size_t>(r.shared)] = a;
        r.b[static_cast<std::size_t>(r.shared)] = b;
        ++r.shared;
      }
  return r;
}

namespace {

/// Greedy colouring of the triangles: no two triangles of one colour share a vertex.
std::vector<std::vector<Index>> vertex_colouring(const Surface& s) {
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

void for_each_triangle_by_colour(const Surface& s, const std::function<void(Index)>& f) {
  for (const std::vector<Index>& colour : vertex_colouring(s)) {
    const long count = static_cast<long>(colour.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (long q = 0; q < count; ++q) f(colour[static_cast<std::size_t>(q)]);
  }
}

}  // namespace bem
