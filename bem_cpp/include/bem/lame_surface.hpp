#pragma once
// Dense Galerkin matrices of the Lame (linear isotropic elastostatics) boundary integral
// operators on a closed triangulated surface, the counterparts of surface_operators.hpp with
// the Kelvin matrix U (kelvin.hpp) for G. Factor-2 convention, n out of Omega, vector dofs
// node-major (dof 3 p + k: component k of node p; P0: of triangle p):
//   V_h[(i,k),(j,l)] = <V psi_j e_l, psi_i e_k> = 2 int int psi_i(x) U_kl(x, y) psi_j(y)
//   K_h[(i,k),(j,l)] = <K v_j e_l, psi_i e_k>   (rows: psi_i, P0 or P1; columns: P1 hats v_j)
//   W_h[(i,k),(j,l)] = <W v_j e_l, v_i e_k>     (P1)
// so that an exterior field with Dirichlet trace v and traction t satisfies V t = (K - I) v,
// W v = -(K' + I) t, and K r = -r, W r = 0 for the six rigid motions r.
//
// Integration by parts (Steinbach, Numerical Approximation Methods for Elliptic BVPs, 2008,
// sect. 6.3): with G = 1/(4 pi |x - y|) and the Gunter derivative
// M(d, n)_ml = n_l d_m - n_m d_l, whose value on a P1 hat v on a flat triangle is constant,
//   M(d, n) v_j e_l = A_j e_l,   A_j = [c_j]_x (A_j w = c_j x w),   c_j = n x grad v_j = curl v_j,
// the textbook (no factor 2) operators are
//   K0 u(x) = int dG/dn_y u - int G M(d_y, n_y) u + 2 mu int U M(d_y, n_y) u,
//   <W0 u, v> = mu int int G sum_k curl u_k(y) . curl v_k(x)
//             + int int (M(d_x, n_x) v)^T [2 mu G I - 4 mu^2 U] M(d_y, n_y) u
//             + mu int int G sum_{i,j,k} M_kj(d_x, n_x) v_i M_ki(d_y, n_y) u_j,
// (Steinbach's sect. 6.3; the signs and index placements are confirmed by the tests: rigid
// motions, Calderon identities of a Kelvin field, P0 and P1). With
// U = [(3 - 4 nu) G I + r r^T / (4 pi |r|^3)] / (4 mu (1 - nu)), r = x - y, every entry is a sum
// over the triangle pairs of the moments of PairIntegrator::moments (surface_operators.hpp),
//   G[a][b] = 2 int int G phi_a(x) phi_b(y),  R[k][l][a][b] = 2 int int r_k r_l / (4 pi |r|^3) phi_a phi_b
// (index 3: the constant), and of the Laplace double layer D[a][b] = PairIntegrals::K:
//   V_h:  ((3 - 4 nu) delta_kl G[i][j] + R[k][l][i][j]) / (4 mu (1 - nu))           (P0: i = j = 3)
//   K_h:  delta_kl D[i][j] + (1 - 2 nu) / (2 (1 - nu)) G[i][3] (A_j)_kl + (R[.][.][i][3] A_j)_kl / (2 (1 - nu))
//   W_h:  mu / (1 - nu) { G[3][3] [(c_i . c_j) delta_kl + (1 - 2 nu) (c_j)_k (c_i)_l - (1 - nu) (c_i)_k (c_j)_l]
//                         + ([c_i]_x R[.][.][3][3] [c_j]_x)_kl }
// (i: the test function on x's triangle, j: the trial hat on y's; the K_h and W_h lines are the
// formulas above with U expanded: -G A_j + 2 mu U A_j for K, and for W the three G terms
// mu G (4 (c_i . c_j) I - 2 c_j c_i^T - c_i c_j^T) plus -4 mu^2 A_i^T U A_j = 4 mu^2 [c_i]_x U [c_j]_x,
// using [c_i]_x [c_j]_x = c_j c_i^T - (c_i . c_j) I). The weakly singular
// kernels are integrated by the Laplace operators' rules (Sauter-Schwab for the pairs sharing a
// vertex, symmetric rules by separation); the Gunter terms need no other rule.
#include "bem/kelvin.hpp"
#include "bem/surface_operators.hpp"

namespace bem {

/// One OpenMP pass over the unordered triangle pairs: the requested Lame matrices (vector dofs
/// node-major: 3 n x 3 n for P1, P0 rows 3 per triangle). single_layer: rows and columns in that
/// space; double_layer: rows in that space, columns P1; hypersingular: P1. Throws
/// std::invalid_argument (one line) unless mu > 0 and -1 < nu < 1/2.
SurfaceMatrices assemble(const Surface& surface, const Lame& m, const SurfaceRequest& request);

// The same on raw arrays, validated by the Surface constructor (used by the bindings).
Matrix single_layer(VerticesRef vertices, TrianglesRef triangles, const Lame& m, Space space);
Matrix double_layer(VerticesRef vertices, TrianglesRef triangles, const Lame& m, Space space);
Matrix hypersingular(VerticesRef vertices, TrianglesRef triangles, const Lame& m);

}  // namespace bem
