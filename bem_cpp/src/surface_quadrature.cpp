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

/// Orbits of a symmetric rule in barycentric coordinates, weights relative to the area:
/// the centroid, (a, a, 1 - 2a) and its 3 rotations, (a, b, 1 - a - b) and its 6 permutations.
struct Orbits {
  double centroid;                           ///< its weight (0: none)
  std::vector<std::array<double, 2>> three;  ///< a, w
  std::vector<std::array<double, 3>> six;    ///< a, b, w
};

TriangleRule make_symmetric_rule(const Orbits& o) {
  TriangleRule r;
  auto add_point = [&r](double s, double t, double w) {
    r.s.push_back(s);
    r.t.push_back(t);
    r.w.push_back(0.5 * w);  // the reference triangle's area
  };
  if (o.centroid > 0) add_point(1.0 / 3.0, 1.0 / 3.0, o.centroid);
  for (const auto& [a, w] : o.three) {
    const double b = 1.0 - 2.0 * a;
    add_point(a, a, w);
    add_point(a, b, w);
    add_point(b, a, w);
  }
  for (const auto& [a, b, w] : o.six) {
    const double c = 1.0 - a - b;
    add_point(a, b, w);
    add_point(b, a, w);
    add_point(a, c, w);
    add_point(c, a, w);
    add_point(b, c, w);
    add_point(c, b, w);
  }
  return r;
}

/// Radon's rule (degree 5) in closed form; Dunavant's rules of degree 4, 6 and 8 (Int. J. Numer.
/// Meth. Eng. 21, 1985), their 15 published digits refined by Newton's method on the moment
/// equations to the last bit.
TriangleRule make_symmetric_rule(int degree) {
  const double root15 = std::sqrt(15.0);
  switch (degree) {
    case 4:
      return make_symmetric_rule(
          Orbits{0.0, {{0.44594849091596483, 0.22338158967801136}, {0.091576213509770771, 0.10995174365532195}}, {}});
    case 5:
      return make_symmetric_rule(Orbits{
          9.0 / 40.0,
          {{(6.0 - root15) / 21.0, (155.0 - root15) / 1200.0}, {(6.0 + root15) / 21.0, (155.0 + root15) / 1200.0}},
          {}});
    case 6:
      return make_symmetric_rule(
          Orbits{0.0,
                 {{0.063089014491508957, 0.050844906370216263}, {0.24928674517087865, 0.11678627572643321}},
                 {{0.053145049844794359, 0.31035245103380865, 0.082851075618341929}}});
    case 8:
      return make_symmetric_rule(Orbits{0.14431560767778701,
                                        {{0.45929258829272301, 0.095091634267284994},
                                         {0.17056930775175999, 0.10321737053471799},
                                         {0.050547228317030998, 0.032458497623198003}},
                                        {{0.0083947774099580007, 0.263112829634638, 0.027230314174435}}});
    default:
      throw std::invalid_argument("symmetric_rule: degree must be 4, 5, 6 or 8");
  }
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

const TriangleRule& symmetric_rule(int degree) {
  static std::map<int, TriangleRule> cache;
  return cached(cache, degree, [degree] { return make_symmetric_rule(degree); });
}

const PairRule& singular_rule(int shared, int p) {
  static std::map<std::pair<int, int>, PairRule> cache;
  if (p < 1 || p > kMaxGaussPoints) throw std::invalid_argument("singular_rule: need 1 <= p <= 24");
  return cached(cache, std::make_pair(shared, p), [shared, p] { return make_singular_rule(shared, p); });
}

}  // namespace bem
