#include "bem/surface_quadrature.hpp"

#include <array>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <utility>

#include "bem/log_integrals.hpp"

namespace bem {

namespace {

TriangleRule make_triangle_rule(int p) {
  TriangleRule r;
  const GaussRule& g = gauss_legendre(p);
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j) {
      // (u, v) in [0, 1]^2 -> (s, t) = (u, v (1 - u)), Jacobian 1 - u
      r.s.push_back(g.x[i]);
      r.t.push_back(g.x[j] * (1.0 - g.x[i]));
      r.w.push_back(g.w[i] * g.w[j] * (1.0 - g.x[i]));
    }
  return r;
}

/// Points of the Sauter-Schwab reference triangle {0 <= x2 <= x1 <= 1} in (s, t) = (x1 - x2, x2).
void add(PairRule& r, double x1, double x2, double y1, double y2, double w) {
  r.s1.push_back(x1 - x2);
  r.t1.push_back(x2);
  r.s2.push_back(y1 - y2);
  r.t2.push_back(y2);
  r.w.push_back(w);
}

PairRule make_singular_rule(int shared, int p) {
  const GaussRule& g = gauss_legendre(p);
  PairRule r;
  for (int a = 0; a < p; ++a)
    for (int b = 0; b < p; ++b)
      for (int c = 0; c < p; ++c)
        for (int d = 0; d < p; ++d) {
          const double xi = g.x[a], e1 = g.x[b], e2 = g.x[c], e3 = g.x[d];
          const double w0 = g.w[a] * g.w[b] * g.w[c] * g.w[d];
          const double e12 = e1 * e2, e123 = e1 * e2 * e3;
          if (shared == 3) {
            // six regions of the 4-cube, Jacobian xi^3 eta1^2 eta2
            const double w = w0 * xi * xi * xi * e1 * e1 * e2;
            add(r, xi, xi * (1 - e1 + e12), xi * (1 - e123), xi * (1 - e1), w);
            add(r, xi * (1 - e123), xi * (1 - e1), xi, xi * (1 - e1 + e12), w);
            add(r, xi, xi * (e1 - e12 + e123), xi * (1 - e12), xi * (e1 - e12), w);
            add(r, xi * (1 - e12), xi * (e1 - e12), xi, xi * (e1 - e12 + e123), w);
            add(r, xi * (1 - e123), xi * (e1 - e123), xi, xi * (e1 - e12), w);
            add(r, xi, xi * (e1 - e12), xi * (1 - e123), xi * (e1 - e123), w);
          } else if (shared == 2) {
            // five regions, Jacobians xi^3 eta1^2 (first) and xi^3 eta1^2 eta2 (others)
            const double w = w0 * xi * xi * xi * e1 * e1;
            add(r, xi, xi * e1 * e3, xi * (1 - e12), xi * e1 * (1 - e2), w);
            add(r, xi, xi * e1, xi * (1 - e123), xi * e12 * (1 - e3), w * e2);
            add(r, xi * (1 - e12), xi * e1 * (1 - e2), xi, xi * e123, w * e2);
            add(r, xi * (1 - e123), xi * e12 * (1 - e3), xi, xi * e1, w * e2);
            add(r, xi * (1 - e123), xi * e1 * (1 - e2 * e3), xi, xi * e12, w * e2);
          } else if (shared == 1) {
            // two regions, Jacobian xi^3 eta2
            const double w = w0 * xi * xi * xi * e2;
            add(r, xi, xi * e1, xi * e2, xi * e2 * e3, w);
            add(r, xi * e2, xi * e2 * e3, xi, xi * e1, w);
          } else {
            throw std::invalid_argument("singular_rule: shared must be 1, 2 or 3");
          }
        }
  return r;
}

TriangleRule make_far_rule() {
  // barycentric (a, a, 1 - 2a) and its rotations, weights relative to the area
  TriangleRule r;
  auto orbit = [&r](double a, double w) {
    const double b = 1.0 - 2.0 * a;
    const double s[3] = {a, a, b}, t[3] = {a, b, a};
    for (int k = 0; k < 3; ++k) {
      r.s.push_back(s[k]);
      r.t.push_back(t[k]);
      r.w.push_back(0.5 * w);
    }
  };
  r.s.push_back(1.0 / 3.0);
  r.t.push_back(1.0 / 3.0);
  r.w.push_back(0.5 * 9.0 / 40.0);
  const double root15 = std::sqrt(15.0);
  orbit((6.0 - root15) / 21.0, (155.0 - root15) / 1200.0);
  orbit((6.0 + root15) / 21.0, (155.0 + root15) / 1200.0);
  return r;
}

template <class Rule, class Make, class Key>
const Rule& cached(std::map<Key, Rule>& cache, const Key& key, Make make) {
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, make()).first;
  return it->second;  // std::map never moves its elements
}

}  // namespace

const TriangleRule& triangle_rule(int p) {
  static std::map<int, TriangleRule> cache;
  if (p < 1 || p > kMaxGaussPoints) throw std::invalid_argument("triangle_rule: need 1 <= p <= 24");
  return cached(cache, p, [p] { return make_triangle_rule(p); });
}

const TriangleRule& far_rule() {
  static const TriangleRule rule = make_far_rule();
  return rule;
}

const PairRule& singular_rule(int shared, int p) {
  static std::map<std::pair<int, int>, PairRule> cache;
  if (p < 1 || p > kMaxGaussPoints) throw std::invalid_argument("singular_rule: need 1 <= p <= 24");
  return cached(cache, std::make_pair(shared, p), [shared, p] { return make_singular_rule(shared, p); });
}

}  // namespace bem
