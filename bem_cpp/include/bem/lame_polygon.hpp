#pragma once
// Dense Galerkin matrices of the boundary integral operators of plane-strain linear
// elastostatics (the Lame operators, Kelvin fundamental solution U of kelvin.hpp) on a
// closed polygon, in the factor-2 convention of operators.hpp: V = 2 V0, K = 2 K0,
// W = 2 W0, so that an exterior field u_e (n pointing out of Omega) with Dirichlet trace v
// and traction t = sigma(u_e) n satisfies  V t = (K - I) v  and  W v = -(K' + I) t,  and
// every rigid motion r (two translations, x -> (-y, x)) has K r = -r, W r = 0.
//
// Vector dofs are node-major, dof = 2 node + component (P0: 2 panel + component):
//   V_h[(i,k),(j,l)] = 2 int int psi_i(x) U_kl(x - y) psi_j(y)
//   K_h[(i,k),(j,l)] = <K (v_j e_l), psi_i e_k>          (rows: flux space, columns: P1)
//   W_h[(i,k),(j,l)] = <W (v_j e_l), v_i e_k>            (P1 x P1)
// With c = 1/(8 pi mu (1 - nu)), U(r) = c [ -(3 - 4 nu) log|r| I + g(r) ], g(r) = r r^T/|r|^2,
// G_L = -(1/2pi) log|r| (the Laplace kernel), the arc-length derivative u' = du/ds along
// the counter-clockwise tangent and R = [[0, -1], [1, 0]] (so that the Gunter derivative
// M(d_y, n_y) u = R u'), the double layer and the hypersingular operator are integrated
// by parts (Kupradze; Steinbach 2008, sect. 6.3; confirmed here by rigid motions and the
// Calderon identities of a Kelvin field, tests/test_lame_polygon.cpp):
//   K0 u(x) = int dG_L/dn_y u(y) - int G_L(x,y) R u'(y) + 2 mu int U(x,y) R u'(y)
//   <W0 u, v> = 4 mu int int G_L v'(x).u'(y) - 4 mu^2 int int v'(x)^T R^T U(x,y) R u'(y)
// (R^T g R = I - g). Every entry is then a sum of three scalar moments of each panel pair
// (i, j) with the P1 shapes phi_a on panel i, phi_b on panel j (a, b = 0 start, 1 end):
//   L[a][b] = int_i int_j log|x - y| phi_a phi_b             (log_integrals.hpp)
//   D_kl[a][b] = int_i int_j g_kl(x - y) phi_a phi_b          (direction_blocks below;
//                D_yy = h_i h_j/4 - D_xx since g_xx + g_yy = 1)
// and the Laplace double-layer moments kij, kji of log_integrals.hpp; with the derivative
// of the hats, v_j' = sigma/h on a panel (sigma = -1 at its start node, +1 at its end):
//   V blocks: 1/(4 pi mu (1 - nu)) [ -(3 - 4 nu) L I + D ]
//   K blocks: (1/pi) kij I + (sigma_b/h_j) 1/(2 pi (1 - nu)) [ -(1 - 2 nu) L0 R + D0 R ]
//             (L0, D0: summed over the trial shapes b, i.e. P0 on panel j)
//   W blocks: sigma_a sigma_b/(h_i h_j) mu/(pi (1 - nu)) [ -L00 I + D00 ]
//             (L00, D00 summed over a and b; the constant part of R^T U R drops out
//             since the derivatives of a hat integrate to 0 over Gamma).
//
// Quadrature of the direction kernel g (bounded, homogeneous of degree 0): coincident
// panels g = t t^T exactly; adjacent panels: Duffy split at the common node (as
// adjacent_blocks), after which g depends on one variable only and its moments are
// closed forms of a segment seen from a point (direction_segment_moments); near pairs:
// the outer rule of near_outer with the point-segment moments inside; far pairs: the
// tensor Gauss rule with far_field_points points (the poles of g are those of log|r|).
#include "bem/geometry.hpp"
#include "bem/kelvin.hpp"
#include "bem/log_integrals.hpp"
#include "bem/operators.hpp"

namespace bem {

/// One OpenMP-parallel pass over the panel pairs (i, j >= i), each pair's moments computed
/// once: the requested Lame matrices (2n x 2n), single_layer in the space of rows and
/// columns, double_layer with rows in its space and P1 columns, hypersingular P1 x P1.
/// V_h and W_h are returned full (exactly symmetric) whatever request.full_symmetric says.
/// Throws std::invalid_argument unless mu > 0 and -1 < nu < 1/2. The kernels stay regular
/// as nu -> 1/2, but V loses its definiteness there: the columns of U become divergence
/// free, so V n -> 0 (on the circle of radius R, V n = R (1 - 2 nu)/(2 mu (1 - nu)) n) and
/// cond(V_h) grows like 1/(1 - 2 nu) (the traction of an incompressible medium is only
/// determined up to a pressure p n).
Operators assemble(const Polygon& polygon, const Lame& m, const OperatorRequest& request);

Matrix single_layer(const Polygon& polygon, const Lame& m, Space space);
/// Rows: flux space, columns: P1 trace.
Matrix double_layer(const Polygon& polygon, const Lame& m, Space space);
/// P1 x P1.
Matrix hypersingular(const Polygon& polygon, const Lame& m);

// The same on raw nodes, validated by the Polygon constructor (used by the bindings).
Matrix single_layer(const Eigen::Ref<const Points>& nodes, const Lame& m, Space space);
Matrix double_layer(const Eigen::Ref<const Points>& nodes, const Lame& m, Space space);
Matrix hypersingular(const Eigen::Ref<const Points>& nodes, const Lame& m);

/// V_h is positive definite only on a small enough boundary (the elastic analogue of the
/// logarithmic capacity condition of the Laplace single layer): scaling Gamma by s gives
///   V_h(s Gamma) = s^2 [ V_h(Gamma) - kappa log(s) B B^T ],  kappa = (3 - 4 nu)/(4 pi mu (1 - nu)),
/// B = (int psi_i) kron I_2 (2n x 2), which is positive definite exactly for s < s*,
///   s* = exp(tau0 + 1/(kappa lambda_max(B^T A0^{-1} B))),  A0 = V_h(Gamma) - kappa tau0 B B^T
/// for any tau0 making A0 positive definite. Returns s* (V_h(Gamma) itself is positive
/// definite iff s* > 1). On the circle of radius R, V 1 = 2 pi R c (1 - 2 (3 - 4 nu) log R) 1
/// for a constant vector, so s* R -> exp(1/(2 (3 - 4 nu))) (1.3202 for nu = 0.3).
double single_layer_critical_scale(const Polygon& polygon, const Lame& m, Space space);
/// V_h(Gamma) positive definite (its Cholesky factorisation succeeds).
bool single_layer_positive_definite(const Polygon& polygon, const Lame& m, Space space);

/// Moments of the direction kernel g(r) = r r^T/|r|^2 over the segment Y(t) = a + t e,
/// t in [0, h] (|e| = 1), seen from p (not in the open segment; on its line g = e e^T):
///   xx[m] = int_0^h t^m g_xx(p - Y(t)) dt,  xy[m] = int_0^h t^m g_xy(p - Y(t)) dt  (m = 0, 1);
/// g_yy = 1 - g_xx. Closed forms (in the frame of the segment, with the angle and the
/// logarithmic moments of segment_moments) near the segment, Gauss-Legendre where the
/// separation allows kMaxFarPoints points, as point_panel_moments.
struct DirectionMoments {
  double xx[2], xy[2];
};
DirectionMoments direction_segment_moments(Vec2 p, Vec2 a, Vec2 e, double h);

/// D_xx[a][b], D_xy[a][b] of a panel pair (above), choosing the method from the relation
/// and the distance as pair_blocks does.
struct DirectionBlocks {
  double xx[2][2], xy[2][2];
};
void direction_blocks(const Panel& pi, const Panel& pj, PairRelation relation, DirectionBlocks& out);

}  // namespace bem
