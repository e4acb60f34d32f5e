#pragma once
// The exterior solution at points of Omega_e by the representation formula (docs/method.md
// section 11): u_e(z) = 1/2 (K (v - a) - V psi)(z) + a with the potentials
//   K w(z) = 2 int dG/dn_y(z, y) w(y) ds_y,   V psi(z) = 2 int G(z, y) psi(y) ds_y,
// G = 1/(4 pi |z - y|). Near-panel integration: a triangle is split into four (recursively)
// until the point is at least 1.5 of its diameters from each piece, and every piece is
// integrated by a rule sized from that ratio (point_rule; docs/design/bem3d.md).
#include "bem/operators.hpp"
#include "bem/surface_operators.hpp"

namespace bem {

/// Closer than this many of its diameters to a (sub)triangle (from its circumscribed ball
/// around the centroid), a point splits it.
constexpr double kPointSplitDiameters = 1.5;

/// The rule over a whole (sub)triangle for a point at q of its diameters from it, as
/// above: symmetric_rule(4) (6 points) from 6 diameters, symmetric_rule(8) (16) from 3,
/// the 8 x 8 collapsed Gauss rule (degree 14) from kPointSplitDiameters; null below
/// (split).
const TriangleRule* point_rule(double q);

/// Integrals over triangle t of 2G(z, .) lambda_b (b = 0..2), 2G(z, .) (index 3) and
/// 2 dG/dn_y(z, .) lambda_b (b = 0..2), for z not on t.
struct PointIntegrals {
  double V[4];
  double K[3];
};
PointIntegrals point_integrals(const Triangle& t, Vec3 z);

/// Solid angle of triangle t seen from z, signed positive when z is on the side its normal
/// points away from (the sum over a closed surface: 4 pi inside Omega, 0 outside).
double solid_angle(const Triangle& t, Vec3 z);

/// Throws std::invalid_argument (ValueError) naming point k of `points` as one inside Omega
/// or on Gamma (the message of exterior_potential and of its compressed form).
[[noreturn]] void refuse_interior_point(const Eigen::Ref<const Vertices>& points, Index k);

/// u_e at the (k, 3) points; throws std::invalid_argument (ValueError) naming the first
/// point inside Omega or on Gamma (closer than 1e-12 of the bounding-box diameter).
Vector exterior_potential(VerticesRef vertices, TrianglesRef triangles, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients, const Eigen::Ref<const Vertices>& points,
                          double a, Space flux);

}  // namespace bem
