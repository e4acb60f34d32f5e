#include "bem/cluster_tree.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace bem {

void Box::add(Vec2 p) { add(Vec3{p.x, p.y, 0.0}); }

void Box::add(Vec3 p) { add(Box{p.x, p.x, p.y, p.y, p.z, p.z}); }

void Box::add(const Box& b) {
  x0 = std::min(x0, b.x0);
  x1 = std::max(x1, b.x1);
  y0 = std::min(y0, b.y0);
  y1 = std::max(y1, b.y1);
  z0 = std::min(z0, b.z0);
  z1 = std::max(z1, b.z1);
}

// hypot(hypot(dx, dy), dz): exactly the planar value when dz = 0 (a 2D box)
double Box::diameter() const { return std::hypot(std::hypot(x1 - x0, y1 - y0), z1 - z0); }

double Box::distance(const Box& b) const {
  const double dx = std::max({0.0, b.x0 - x1, x0 - b.x1});
  const double dy = std::max({0.0, b.y0 - y1, y0 - b.y1});
  const double dz = std::max({0.0, b.z0 - z1, z0 - b.z1});
  return std::hypot(std::hypot(dx, dy), dz);
}

bool admissible(const Box& t, const Box& s, double eta) {
  const double d = t.distance(s);
  return d > 0.0 && std::min(t.diameter(), s.diameter()) <= eta * d;
}

ClusterTree::ClusterTree(const Eigen::Ref<const Matrix>& points, const std::vector<Box>& supports, Index leaf_size) {
  const Index n = points.rows();
  if (n < 1 || static_cast<Index>(supports.size()) != n || leaf_size < 1 || (points.cols() != 2 && points.cols() != 3))
    throw std::invalid_argument(
        "ClusterTree: need n >= 1 points in 2 or 3 dimensions, one support each, leaf_size >= 1");
  permutation_.resize(static_cast<std::size_t>(n));
  std::iota(permutation_.begin(), permutation_.end(), Index{0});
  clusters_.reserve(static_cast<std::size_t>(4 * (n / leaf_size + 1)));
  build(0, n, points, supports, leaf_size);
}

int ClusterTree::build(Index begin, Index end, const Eigen::Ref<const Matrix>& points, const std::vector<Box>& supports,
                       Index leaf_size) {
  const int id = static_cast<int>(clusters_.size());
  clusters_.emplace_back();
  Cluster c;
  c.begin = begin;
  c.end = end;
  Box point_box;
  for (Index k = begin; k < end; ++k) {
    const Index i = permutation_[static_cast<std::size_t>(k)];
    c.box.add(supports[static_cast<std::size_t>(i)]);
    point_box.add(Vec3{points(i, 0), points(i, 1), points.cols() == 3 ? points(i, 2) : 0.0});
  }
  if (end - begin > leaf_size) {
    // Bisect the box of the points along its longest side (the first of equal ones); fall
    // back to the median if all points fall on one side (cannot happen for distinct
    // points, kept for safety).
    const double lo[3] = {point_box.x0, point_box.y0, point_box.z0};
    const double hi[3] = {point_box.x1, point_box.y1, point_box.z1};
    int axis = 0;
    for (int a = 1; a < points.cols(); ++a)
      if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    const double mid = 0.5 * (lo[axis] + hi[axis]);
    auto first = permutation_.begin() + begin, last = permutation_.begin() + end;
    auto cut = std::stable_partition(first, last, [&](Index i) { return points(i, axis) < mid; });
    if (cut == first || cut == last) {
      cut = first + (end - begin) / 2;
      std::nth_element(first, cut, last, [&](Index a, Index b) { return points(a, axis) < points(b, axis); });
    }
    const Index split = begin + (cut - first);
    c.children[0] = build(begin, split, points, supports, leaf_size);
    c.children[1] = build(split, end, points, supports, leaf_size);
  }
  clusters_[static_cast<std::size_t>(id)] = c;
  return id;
}

ClusterTree ClusterTree::for_space(const Polygon& polygon, Space space, Index leaf_size) {
  const Index n = polygon.size();
  Points points(n, 2);
  std::vector<Box> supports(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    const Panel& p = polygon.panel(i);
    Box& b = supports[static_cast<std::size_t>(i)];
    b.add(p.a);
    b.add(p.b);
    if (space == Space::P0) {  // indicator of panel i
      points(i, 0) = p.m.x;
      points(i, 1) = p.m.y;
    } else {  // hat of node i = start of panel i: panels i - 1 and i
      b.add(polygon.panel((i + n - 1) % n).a);
      points(i, 0) = p.a.x;
      points(i, 1) = p.a.y;
    }
  }
  return ClusterTree(points, supports, leaf_size);
}

ClusterTree ClusterTree::expanded(int d) const {
  if (d < 1) throw std::invalid_argument("ClusterTree::expanded: need d >= 1");
  ClusterTree out;
  out.clusters_ = clusters_;
  for (Cluster& c : out.clusters_) {
    c.begin *= d;
    c.end *= d;
  }
  out.permutation_.resize(permutation_.size() * static_cast<std::size_t>(d));
  for (std::size_t k = 0; k < permutation_.size(); ++k)
    for (int c = 0; c < d; ++c) out.permutation_[d * k + static_cast<std::size_t>(c)] = d * permutation_[k] + c;
  return out;
}

std::vector<int> ClusterTree::leaves() const {
  std::vector<int> out, stack{0};
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    const Cluster& cl = cluster(c);
    if (cl.leaf()) {
      out.push_back(c);
    } else {
      stack.push_back(cl.children[1]);
      stack.push_back(cl.children[0]);
    }
  }
  return out;
}

std::vector<Index> ClusterTree::partition(int parts) const {
  return partition(parts, std::vector<double>(static_cast<std::size_t>(size()), 1.0));
}

std::vector<Index> ClusterTree::partition(int parts, const std::vector<double>& cost) const {
  if (parts < 1) throw std::invalid_argument("ClusterTree::partition: need parts >= 1");
  if (static_cast<Index>(cost.size()) != size())
    throw std::invalid_argument("ClusterTree::partition: need one cost per dof");
  std::vector<Index> ends{0};      // leaf boundaries, increasing, from 0 to n
  std::vector<double> below{0.0};  // cumulative cost at each
  for (int c : leaves()) {
    const Cluster& cl = cluster(c);
    double sum = below.back();
    for (Index k = cl.begin; k < cl.end; ++k) sum += cost[static_cast<std::size_t>(k)];
    ends.push_back(cl.end);
    below.push_back(sum);
  }
  const Index n = size();
  std::vector<Index> bounds(static_cast<std::size_t>(parts) + 1, 0);
  for (int r = 1; r <= parts; ++r) {
    const double target = static_cast<double>(r) * below.back() / parts;
    std::size_t best = 0;
    for (std::size_t e = 1; e < ends.size(); ++e)
      if (std::abs(below[e] - target) < std::abs(below[best] - target)) best = e;
    bounds[static_cast<std::size_t>(r)] = std::max(ends[best], bounds[static_cast<std::size_t>(r) - 1]);
  }
  bounds.back() = n;
  return bounds;
}

ClusterTree point_cluster_tree(const Eigen::Ref<const Matrix>& points, Index leaf_size) {
  std::vector<Box> supports(static_cast<std::size_t>(points.rows()));
  const bool solid = points.cols() == 3;
  for (Index i = 0; i < points.rows(); ++i)
    supports[static_cast<std::size_t>(i)].add(Vec3{points(i, 0), points(i, 1), solid ? points(i, 2) : 0.0});
  return ClusterTree(points, supports, leaf_size);
}

}  // namespace bem
