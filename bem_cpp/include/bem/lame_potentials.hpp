#pragma once
// The exterior displacement and stress of linear elastostatics by the representation formula
// (Somigliana's identity) in 2D (plane strain, closed polygon) and 3D (closed triangulated
// surface), factor-2 convention of the boundary operators:
//   u_e(z) = 1/2 ( K (v - a) - V t )(z) + a,          z in Omega_e,
//   V t(z) = 2 int U(z - y) t(y) ds_y,                 K w(z) = 2 int D(z, y) w(y) ds_y,
//   D(z, y)_kl = T(y - z, n_y)[l][k]                   (T = kelvin_traction),
// v the Dirichlet trace (P1), t = sigma(u_e) n the traction (n out of Omega; P1 or P0) and a
// the translation at infinity (kelvin.hpp: U, c = 1/(8 pi mu (1 - nu)) in 2D,
// 1/(16 pi mu (1 - nu)) in 3D, alpha = 3 - 4 nu). In terms of the derivatives of U the
// double layer reads (K w)_k(z) = 2 int tau_pq(y) d_q U_pk(y - z) ds_y with the stress-like
// tensor tau(y) = lambda (n.w) I + mu (w n^T + n w^T) of the data w = v - a, so that with
// r = z - y, rho = |r| (d the dimension; kernels odd/even in r):
//   1/2 K w  = -int F(r),   F_k = tau_pq d_q U_pk(r)
//            = c [ b (n.w) r_k + mu ((1 - alpha)(w_k (n.r) + n_k (w.r)) + 2 (n.w) r_k) ] / rho^d
//              - 2 d c mu (n.r)(w.r) r_k / rho^(d+2),
//   grad_z of 1/2 K w:  -int G(r),   G_ks = tau_pq d_q d_s U_pk(r),
//   grad_z of 1/2 V t:   int d_s U_kl(r) t_l,
// where b = lambda (1 - alpha) = -4 mu nu folds the large lambda of nu -> 1/2 against the small
// 1 - alpha = -2 (1 - 2 nu) analytically. For tau = mu (w n^T + n w^T) (tr tau = 2 mu n.w,
// tau r = mu (w (n.r) + n (w.r)), r.tau.r = 2 mu (n.r)(w.r)) the second derivatives
//   d_q d_s U_pk = c [ -alpha d_pk (d_qs / rho^d - d r_q r_s / rho^(d+2)) + (d_pq d_ks + d_kq d_ps) / rho^d
//                      - d (d_pq r_k + d_kq r_p) r_s / rho^(d+2) - d (d_ps r_k r_q + d_ks r_p r_q + d_qs r_p r_k)
//                      / rho^(d+2) + d (d + 2) r_p r_k r_q r_s / rho^(d+4) ]
// contract to
//   G_ks = c [ (1 - alpha) tau_ks / rho^d + tr tau d_ks / rho^d + d (alpha - 1)(tau r)_k r_s / rho^(d+2)
//              - d tr tau r_k r_s / rho^(d+2) - 2 d (tau r)_s r_k / rho^(d+2) - d d_ks (r.tau.r) / rho^(d+2)
//              + d (d + 2) (r.tau.r) r_k r_s / rho^(d+4) ]
// and the lambda (n.w) I part to c b (n.w) (d_ks / rho^d - d r_k r_s / rho^(d+2)). The stress is
//   sigma = P I + mu (grad u + grad u^T),   P = lambda div u_e
//         = -int c b [ 2 mu (n.w) / rho^d - 2 d mu (n.r)(w.r) / rho^(d+2) + (r.t) / rho^d ]
// (the traces of the kernels are multiples of 1 - alpha, and the lambda (n.w) I part of the
// double layer is divergence-free): every kernel stays bounded as nu -> 1/2.
//
// Quadrature: the kernels are smooth off Gamma but vary on the scale of the distance. 2D: a
// panel is halved (recursively) until the point is at least kPanelSplitLengths of its
// lengths from each piece, and each piece gets gauss_points_for(distance, length) Gauss-
// Legendre points (log_integrals.hpp). 3D: a triangle is split into four until the point is
// kPointSplitDiameters of its diameters from each piece, each piece integrated by point_rule
// (surface_potentials.hpp). OpenMP over the points. The nodes are placed in coordinates from
// the foot of z on the panel's line / triangle's plane, anchored at the vertex nearest to z,
// so that the small pieces near z have nodes accurate to the round-off of their own distance
// from z and a vertex near z is one vector from z in all its panels / triangles: on exact data
// (test_lame_potentials.cpp) the stress at a distance delta from Gamma is then accurate to
// ~4e-14 h / delta in 2D (|sigma| ~ 1), and in 3D to point_rule's ~1e-12 h / delta (~1e-7 at
// delta = 1e-3 h; worse, ~1 / delta^2, right above an edge below delta ~ 1e-6 h, where the
// two triangles' planes meet to round-off of h only). The displacement: ~1e-15 (2D), ~5e-10
// (3D, point_rule's degree-4 rule from 6 diameters).
#include "bem/geometry.hpp"
#include "bem/kelvin.hpp"
#include "bem/operators.hpp"
#include "bem/surface.hpp"
#include "bem/surface_operators.hpp"

namespace bem {

/// Closer than this many of its lengths to a (piece of a) panel, a point halves it (2D).
constexpr double kPanelSplitLengths = 1.5;

/// The double layer's kernels at r = z - y for the data w at y and the normal n at y (d = 2, 3;
/// the formulas above): F (d values, 1/2 K w = -int F) and G (d x d, grad_z of 1/2 K w =
/// -int G, G[k][s] = d F_k / d z_s); exposed for the tests (against kelvin.hpp).
std::array<double, 3> lame_double_layer_kernel(const Lame& m, int d, const double* r, const double* n, const double* w);
Mat3 lame_double_layer_gradient_kernel(const Lame& m, int d, const double* r, const double* n, const double* w);

/// The field of the exterior medium that exterior_field evaluates.
enum class LameField {
  Displacement,  ///< u_e, a (k, d) matrix
  Stress,        ///< sigma(u_e), a (k, d * d) matrix: row-major d x d per point (symmetric)
};

/// `field` at the (k, d) points of Omega_e. dirichlet: the d n nodal values of the P1 trace v,
/// node-major (d * node + component); traction: d n (P1, nodal) or d m (P0, per panel /
/// triangle) values of t = sigma(u_e) n, node-major; a: d values. Throws
/// std::invalid_argument (one line) for a point inside Omega or on Gamma (within 1e-12 of the
/// bounding-box diameter), wrong sizes, non-finite data or an invalid medium (mu > 0,
/// -1 < nu < 1/2).
Matrix exterior_field(LameField field, const Polygon& polygon, const Lame& medium,
                      const Eigen::Ref<const Vector>& dirichlet, const Eigen::Ref<const Vector>& traction,
                      const Eigen::Ref<const Points>& points, const Eigen::Ref<const Vector>& a, Space traction_space);
Matrix exterior_field(LameField field, const Surface& surface, const Lame& medium,
                      const Eigen::Ref<const Vector>& dirichlet, const Eigen::Ref<const Vector>& traction,
                      const Eigen::Ref<const Vertices>& points, const Eigen::Ref<const Vector>& a,
                      Space traction_space);

}  // namespace bem
