#pragma once
// Dense Galerkin matrices of the Laplace boundary integral operators on a closed
// triangulated surface (docs/method.md section 11, factor-2 convention, G = 1/(4 pi |x - y|)):
//   V_h[i, j] = <V psi_j, psi_i> = 2 int int G(x, y) psi_j(y) psi_i(x)
//   K_h[i, j] = <K v_j, psi_i>   = 2 int int dG/dn_y(x, y) v_j(y) psi_i(x)     (K' = K^T)
//   W_h[i, j] = <V curl v_j, curl v_i>   (Nedelec's identity; curl v = n x grad v)
//   M_h[i, j] = <v_j, psi_i>
// v_j: P1 hat of vertex j; psi_i: P1 hat of vertex i ("p1") or indicator of triangle i
// ("p0"). Pairs sharing a vertex, an edge or the triangle: Sauter-Schwab rules
// (surface_quadrature.hpp); other pairs: symmetric rules raised for near pairs.
#include <optional>

#include "bem/operators.hpp"
#include "bem/surface.hpp"
#include "bem/surface_quadrature.hpp"

namespace bem {

/// Gauss points per direction of the singular (Sauter-Schwab) rules, by the number of
/// shared vertices (1: vertex, 2: edge, 3: identical): pair errors about 2e-5 and 3e-6
/// relative (K and V, perpendicular edge-adjacent pair; docs/design/bem3d.md).
constexpr int kSingularGaussPoints[4] = {0, 5, 6, 6};

/// The far pairs, separation q >= kFarSeparation (PairIntegrator::regular_rule), are
/// integrated with far_rule() on both triangles. The admissible H-matrix blocks hold far
/// pairs only, so their entries are this rule's sums over the point kernel
/// (surface_entries.hpp).
constexpr double kFarSeparation = 1.5;
/// The degrees of the symmetric rules of the regular pairs (PairIntegrator::regular_rule):
/// below q = 0.5, below kFarSeparation, and the far rule's.
constexpr int kRegularDegrees[3] = {8, 6, kFarRuleDegree};

/// The distance between two triangles' centroids (or two sets of them) from which every
/// pair of triangles of radius <= `radius` is a far pair: 2 (1 + kFarSeparation) radius.
constexpr double far_distance(double radius) { return 2.0 * (1.0 + kFarSeparation) * radius; }
/// far_distance of the surface's largest triangle (the HMatrixOptions::min_distance of the
/// surface operators, the cells of the near-pair search).
double far_distance(const Surface& surface);

/// Number of dofs of `space` on the surface (P1: vertices, P0: triangles).
Index dofs(const Surface& surface, Space space);

/// Local integrals of a triangle pair (tau: test, sigma: trial). Basis index 0..2: the
/// barycentric coordinate of the vertex (P1); 3: the constant 1 (P0).
struct PairIntegrals {
  double V[4][4];   ///< 2 int int G phi_a(x) phi_b(y)
  double K[4][3];   ///< 2 int int dG/dn_y phi_a(x) lambda_b(y)
  double Kt[4][3];  ///< the same for the pair (sigma, tau): test sigma, trial tau
};

/// The geometric moments of a triangle pair (tau: x, sigma: y, r = x - y; basis index as in
/// PairIntegrals) from which kernels built of 1/|r| and r r^T/|r|^3 are sums (the Kelvin
/// matrix, lame_surface.hpp):
///   G[a][b]       = 2 int int 1/(4 pi |r|) phi_a(x) phi_b(y)   (PairIntegrals::V, to round-off)
///   R[k][l][a][b] = 2 int int r_k r_l / (4 pi |r|^3) phi_a(x) phi_b(y)   (R[k][l] = R[l][k])
///   K, Kt         as in PairIntegrals (zero between two triangles of one plane).
/// The kernels are evaluated once per point pair of the rule and summed against the monomials
/// of both triangles (9 moments each), which give the entries of every pair of basis functions.
struct PairMoments {
  double G[4][4];
  double R[3][3][4][4];
  double K[4][3], Kt[4][3];
};

/// Integrates every triangle pair with the rule its adjacency and distance call for.
class PairIntegrator {
 public:
  explicit PairIntegrator(const Surface& surface);
  /// `double_layer`: also K and Kt (otherwise they are left unset).
  void integrate(Index tau, Index sigma, bool double_layer, PairIntegrals& out) const;
  /// The moments of the pair by the same rule as `integrate` (K and Kt only with
  /// `double_layer`, otherwise left unset).
  void moments(Index tau, Index sigma, bool double_layer, PairMoments& out) const;
  /// The degree of the symmetric_rule of a disjoint pair, from the distance of the balls
  /// about the centroids over the larger diameter, q: kRegularDegrees below q = 0.5, below
  /// 1.5 and beyond (8, 6 and kFarRuleDegree; docs/design/bem3d.md).
  static int regular_rule(const Triangle& a, const Triangle& b);
  /// Whether the pair is a far pair (integrated by the far rule): disjoint, q >= kFarSeparation.
  static bool far(const Triangle& a, const Triangle& b) { return regular_rule(a, b) == kFarRuleDegree; }
  /// The triangles' planes (triangle_planes): the double layer is zero between two
  /// triangles of one plane.
  const std::vector<int>& planes() const { return planes_; }

 private:
  const Surface& surface_;
  std::vector<int> planes_;
  const PairRule* singular_[4];     ///< by the number of shared vertices (1..3)
  const TriangleRule* regular_[9];  ///< symmetric_rule(d) at d = regular_rule (kRegularDegrees)
};

/// The surface curl n x grad(lambda_a) of the barycentric coordinate a on triangle t.
Vec3 surface_curl(const Triangle& t, int a);

struct SurfaceRequest {
  std::optional<Space> single_layer;  ///< V_h in this space
  std::optional<Space> double_layer;  ///< K_h, rows in this space, columns P1
  bool hypersingular = false;         ///< W_h (P1)
};

struct SurfaceMatrices {
  Matrix single_layer, double_layer, hypersingular;  ///< empty if not requested
};

/// One OpenMP-parallel pass over the unordered triangle pairs (each integrated once for
/// both orders; the first triangles coloured so that no two threads share a vertex row).
SurfaceMatrices assemble(const Surface& surface, const SurfaceRequest& request);

/// Rows `space`, columns P1 (P1: the Gram matrix, element matrix A/12 (1 + delta_ab)).
Matrix mass(const Surface& surface, Space space);

/// W_h restricted to the P1 hats of `vertices` (k distinct vertex indices): the k x k matrix
/// W_h[vertices, vertices] = E^T W_h E, integrated over the triangles that touch those
/// vertices only (for the nodes inside a surface patch: the patch's triangles), so its cost
/// grows with the patch, not the surface. The H~^{1/2} metric of the Signorini block of
/// the 3D preconditioner (docs/method.md section 11).
Matrix hypersingular_block(const Surface& surface, const std::vector<Index>& vertices);

// The same on raw arrays, validated by the Surface constructor (used by the bindings).
using VerticesRef = const Eigen::Ref<const Vertices>&;
using TrianglesRef = const Eigen::Ref<const Triangles>&;
Matrix single_layer(VerticesRef vertices, TrianglesRef triangles, Space space);
Matrix double_layer(VerticesRef vertices, TrianglesRef triangles, Space space);
Matrix hypersingular(VerticesRef vertices, TrianglesRef triangles);
Matrix hypersingular_block(VerticesRef vertices, TrianglesRef triangles, const std::vector<Index>& block);
Matrix mass(VerticesRef vertices, TrianglesRef triangles, Space space);

}  // namespace bem
