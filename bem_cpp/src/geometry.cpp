#include "bem/geometry.hpp"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>

namespace bem {

namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

double orient(Vec2 a, Vec2 b, Vec2 c) { return cross(b - a, c - a); }

/// c is known to be collinear with the segment [a, b]: is it inside its bounding box?
bool within_box(Vec2 a, Vec2 b, Vec2 c) {
  return std::min(a.x, b.x) <= c.x && c.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= c.y &&
         c.y <= std::max(a.y, b.y);
}

/// Closed segments [p.a, p.b] and [q.a, q.b] share a point (touching counts).
bool segments_intersect(const Panel& p, const Panel& q) {
  const double d1 = orient(q.a, q.b, p.a), d2 = orient(q.a, q.b, p.b);
  const double d3 = orient(p.a, p.b, q.a), d4 = orient(p.a, p.b, q.b);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  return (d1 == 0 && within_box(q.a, q.b, p.a)) || (d2 == 0 && within_box(q.a, q.b, p.b)) ||
         (d3 == 0 && within_box(p.a, p.b, q.a)) || (d4 == 0 && within_box(p.a, p.b, q.b));
}

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("nodes: " + what); }

}  // namespace

Panel make_panel(Vec2 a, Vec2 b) {
  const Vec2 d = b - a;
  const double h = norm(d);
  const Vec2 t = (1.0 / h) * d;
  return {a, b, t, rotate_cw(t), 0.5 * (a + b), h};
}

double distance(const Panel& p, Vec2 z) {
  const double s = std::clamp(dot(z - p.a, p.t), 0.0, p.h);
  return norm(z - (p.a + s * p.t));
}

double distance(const Panel& p, const Panel& q) {
  if (segments_intersect(p, q)) return 0.0;
  return std::min({distance(p, q.a), distance(p, q.b), distance(q, p.a), distance(q, p.b)});
}

Polygon::Polygon(const Eigen::Ref<const Points>& nodes) {
  const Index n = nodes.rows();
  if (n < 3)
    fail("a closed polygon needs at least 3 nodes, got " + std::to_string(n) +
         "; pass the (n, 2) boundary nodes in counter-clockwise order");
  for (Index j = 0; j < n; ++j)
    if (!std::isfinite(nodes(j, 0)) || !std::isfinite(nodes(j, 1)))
      fail("node " + std::to_string(j) + " has a non-finite coordinate; remove NaN/inf values");

  const double xmin = nodes.col(0).minCoeff(), xmax = nodes.col(0).maxCoeff();
  const double ymin = nodes.col(1).minCoeff(), ymax = nodes.col(1).maxCoeff();
  bbox_diameter_ = std::hypot(xmax - xmin, ymax - ymin);
  // Below this length a panel is a repeated node: the kernels would lose all digits.
  const double h_min = 1e-14 * bbox_diameter_;

  panels_.reserve(static_cast<std::size_t>(n));
  for (Index j = 0; j < n; ++j) {
    const Index k = (j + 1) % n;
    const Vec2 a{nodes(j, 0), nodes(j, 1)}, b{nodes(k, 0), nodes(k, 1)};
    if (!(norm(b - a) > h_min)) {
      if (k == 0)
        fail("the last node " + std::to_string(j) +
             " repeats the first node; do not close the polygon by repeating node 0");
      fail("nodes " + std::to_string(j) + " and " + std::to_string(k) +
           " coincide (zero-length panel); remove repeated consecutive nodes");
    }
    panels_.push_back(make_panel(a, b));
    area_ += 0.5 * cross(a, b);
  }

  // A panel going straight back along its predecessor overlaps it (adjacent panels
  // are not covered by the non-adjacent test below).
  for (Index j = 0; j < n; ++j) {
    const Panel& p = panel(j);
    const Panel& q = panel((j + 1) % n);
    if (std::abs(cross(p.t, q.t)) <= 1e-14 && dot(p.t, q.t) < 0)
      fail("panels " + std::to_string(j) + " and " + std::to_string((j + 1) % n) +
           " fold back onto each other (self-intersection); give a simple polygon");
  }

  // Self-intersection: sweep over x, test pairs of non-adjacent panels whose
  // x-ranges overlap.
  std::vector<Index> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), Index{0});
  auto lo_x = [&](Index j) { return std::min(panel(j).a.x, panel(j).b.x); };
  auto hi_x = [&](Index j) { return std::max(panel(j).a.x, panel(j).b.x); };
  std::sort(order.begin(), order.end(), [&](Index i, Index j) { return lo_x(i) < lo_x(j); });
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Index i = order[k];
    const Panel& p = panel(i);
    const double p_hi = hi_x(i);
    const double p_ylo = std::min(p.a.y, p.b.y), p_yhi = std::max(p.a.y, p.b.y);
    for (std::size_t l = k + 1; l < order.size() && lo_x(order[l]) <= p_hi; ++l) {
      const Index j = order[l];
      const Index d = std::abs(i - j);
      if (d == 1 || d == n - 1) continue;  // adjacent panels share a node
      const Panel& q = panel(j);
      if (std::max(q.a.y, q.b.y) < p_ylo || std::min(q.a.y, q.b.y) > p_yhi) continue;
      if (segments_intersect(p, q))
        fail("the polygon is self-intersecting (panels " + std::to_string(std::min(i, j)) + " and " +
             std::to_string(std::max(i, j)) + " intersect); give the nodes of a simple polygon");
    }
  }

  if (!(area_ > 0))
    fail("the nodes are ordered clockwise (signed area " + fmt(area_) + "); reverse them to counter-clockwise order");
}

Vector Polygon::lengths() const {
  Vector h(size());
  for (Index j = 0; j < size(); ++j) h(j) = panel(j).h;
  return h;
}

Location locate(const Polygon& polygon, Vec2 z, double on_tolerance) {
  bool inside = false;
  for (const Panel& p : polygon.panels()) {
    if (distance(p, z) <= on_tolerance) return Location::OnBoundary;
    if ((p.a.y > z.y) != (p.b.y > z.y)) {
      const double x = p.a.x + (z.y - p.a.y) * (p.b.x - p.a.x) / (p.b.y - p.a.y);
      if (z.x < x) inside = !inside;
    }
  }
  return inside ? Location::Interior : Location::Exterior;
}

}  // namespace bem
