#pragma once
// Representation formula for the exterior solution (docs/method.md section 2):
//   u_e(z) = 1/2 ( K(v - a) - V psi )(z) + a,   z in Omega_e,
// evaluated with the analytic panel integrals near Gamma and Gauss-Legendre far from it.
#include "bem/geometry.hpp"
#include "bem/operators.hpp"

namespace bem {

/// Relative distance (to the bounding-box diameter) below which a point counts as on Gamma.
constexpr double kOnBoundaryTolerance = 1e-12;

/// Throws std::invalid_argument (one line: how many, the first) if a point is inside Omega
/// or within kOnBoundaryTolerance * diameter of Gamma.
void check_exterior(const Polygon& polygon, const Eigen::Ref<const Points>& points);

/// Throws std::invalid_argument unless the trace v and the flux coefficients psi have n
/// values each and v, psi and a are finite.
void check_potential_data(Index n, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients, double a);

/// u_e at the points z (m x 2) of the exterior. v: nodal values of the P1 Dirichlet
/// trace, psi: coefficients of the flux in `flux` (both of length n). Throws
/// std::invalid_argument if a point is inside Omega or within kOnBoundaryTolerance *
/// diameter of Gamma.
Vector exterior_potential(const Polygon& polygon, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients, const Eigen::Ref<const Points>& points,
                          double a, Space flux);

Vector exterior_potential(const Eigen::Ref<const Points>& nodes, const Eigen::Ref<const Vector>& dirichlet,
                          const Eigen::Ref<const Vector>& flux_coefficients, const Eigen::Ref<const Points>& points,
                          double a, Space flux);

}  // namespace bem
