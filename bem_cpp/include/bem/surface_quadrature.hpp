#pragma once
// Quadrature over pairs of flat triangles (docs/method.md section 11, docs/design/bem3d.md).
// Points are in the reference triangle {(s, t): s, t >= 0, s + t <= 1}, mapped to a
// triangle with vertices (q0, q1, q2) as q0 + s (q1 - q0) + t (q2 - q0); the weights of
// a pair rule sum to 1/4 (the product of the two reference areas), those of a triangle
// rule to 1/2.
//   regular pairs:   the tensor product of two symmetric rules, of degree 8, 6 or 5 (far
//                    pairs) by the pair's separation (surface_operators.hpp);
//   singular pairs:  the Sauter-Schwab transformations of [0, 1]^4 (Sauter and Schwab,
//                    Boundary Element Methods, 2011, sect. 5.2) with a Gauss-Legendre rule
//                    in each of the four directions: 6 regions for identical triangles,
//                    5 for a common edge, 2 for a common vertex; the shared vertices are
//                    the first vertices of both triangles, in the same order.
#include <vector>

namespace bem {

/// Points (s, t) and weights of a rule on the reference triangle.
struct TriangleRule {
  std::vector<double> s, t, w;
  int size() const { return static_cast<int>(w.size()); }
};

/// Points (s1, t1) on the first and (s2, t2) on the second triangle, and weights.
struct PairRule {
  std::vector<double> s1, t1, s2, t2, w;
  int size() const { return static_cast<int>(w.size()); }
};

/// The collapsed Gauss rule with p x p points (exact for polynomials of degree 2p - 2: the
/// collapse's Jacobian takes one degree from the Gauss rules' 2p - 1).
const TriangleRule& triangle_rule(int p);

/// A fully symmetric rule with positive weights and interior points, exact for
/// polynomials of degree 4 (Dunavant's, 6 points), 5 (Radon's, 7), 6 (Dunavant's, 12) or 8
/// (Dunavant's, 16): two fifths to three quarters of the points of the collapsed Gauss
/// rules of the same degree.
const TriangleRule& symmetric_rule(int degree);

/// The degree of the far pairs' rule (surface_operators.hpp) and its points.
constexpr int kFarRuleDegree = 5;
constexpr int kFarRulePoints = 7;
inline const TriangleRule& far_rule() { return symmetric_rule(kFarRuleDegree); }

/// Sauter-Schwab rule for two triangles sharing `shared` = 3 (identical), 2 (an edge:
/// vertices 0 and 1 of both) or 1 (vertex 0 of both) vertices, p Gauss points per direction.
const PairRule& singular_rule(int shared, int p);

}  // namespace bem
