#pragma once
// Discrete Steklov-Poincare operator and exterior Dirichlet-to-Neumann solve
// (docs/method.md sections 2 and 4, factor-2 convention):
//   S_h = 1/2 ( W_h + (K_h - M_h)^T V_h^{-1} (K_h - M_h) ),
//   V_h psi_h = (K_h - M_h)(v - a).
#include <utility>

#include "bem/geometry.hpp"
#include "bem/operators.hpp"

namespace bem {

/// Wall-clock seconds spent in each stage of steklov_poincare.
struct StageTimes {
  double assembly = 0;          ///< V_h, K_h, W_h (one pass over panel pairs) and K_h - M_h
  double cholesky = 0;          ///< V_h = L L^T (dpotrf)
  double triangular_solve = 0;  ///< Y = L^{-1} (K_h - M_h) (dtrsm)
  double rank_update = 0;       ///< S = 1/2 (W_h + Y^T Y) (dsyrk) and symmetrisation
};

/// Cholesky factorisation of V_h in place; throws std::invalid_argument naming the
/// cause (logarithmic capacity of Gamma >= 1) and the remedy (rescale) if V_h is not
/// positive definite.
void factorise_single_layer(Matrix& V);

/// S_h (n x n, P1 x P1), exactly symmetric; computed as S = 1/2 (W + Y^T Y) with
/// Y = L^{-1}(K - M), L L^T = V (Cholesky), which costs n^3/3 + n^3 + n^3 flops.
Matrix steklov_poincare(const Polygon& polygon, Space flux, StageTimes* times = nullptr);

/// Coefficients of psi_h in the flux space: V_h psi_h = (K_h - M_h)(v - a), v the
/// nodal values of the P1 Dirichlet trace. psi_h approximates du_e/dn (n pointing
/// into the exterior).
Vector exterior_flux(const Polygon& polygon, const Eigen::Ref<const Vector>& dirichlet, double a, Space flux);

// On raw nodes (validated), for the bindings.
Matrix steklov_poincare(const Eigen::Ref<const Points>& nodes, Space flux);
std::pair<Matrix, StageTimes> steklov_poincare_timed(const Eigen::Ref<const Points>& nodes, Space flux);
Vector exterior_flux(const Eigen::Ref<const Points>& nodes, const Eigen::Ref<const Vector>& dirichlet, double a,
                     Space flux);

}  // namespace bem
