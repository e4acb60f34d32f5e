#pragma once
// The fundamental solution of linear isotropic elastostatics (Kelvin's solution,
// docs/method.md section 12) in 2D (plane strain) and 3D, its gradient and its traction,
// without the factor 2 of the boundary operators (which the assemblies apply). U(r) is the
// displacement at x from a unit point force at y, r = x - y:
//   3D: U(r) = 1/(16 pi mu (1 - nu) |r|) [ (3 - 4 nu) I + r r^T / |r|^2 ]
//   2D: U(r) = -1/(8 pi mu (1 - nu)) [ (3 - 4 nu) log|r| I - r r^T / |r|^2 ]
// Both are regular at nu = 1/2 (the incompressible limit): only the stress needs lambda.
#include <array>

#include "bem/geometry.hpp"

namespace bem {

/// An isotropic linear elastic medium: shear modulus mu > 0 and Poisson ratio nu in
/// (-1, 1/2). Plane strain in 2D.
struct Lame {
  double mu, nu;
  /// lambda = 2 mu nu / (1 - 2 nu).
  double lambda() const { return 2.0 * mu * nu / (1.0 - 2.0 * nu); }
};

/// From Young's modulus E > 0 and nu in (-1, 1/2): mu = E / (2 (1 + nu)). Throws
/// std::invalid_argument (ValueError in Python) with a one-line message otherwise.
Lame lame_from_young(double E, double nu);

/// Throws std::invalid_argument (one line, naming the value and the fix) unless mu > 0 and
/// nu in (-1, 1/2); `nu_note` follows the range of nu in the message (why 1/2 is excluded).
void check_medium(const Lame& m, const char* nu_note = "");

/// d x d matrices and d-vectors (d = 2, 3), row-major; entries beyond d unused.
using Mat3 = std::array<std::array<double, 3>, 3>;

/// U(r) (above) in dimension d = 2 or 3; r != 0.
Mat3 kelvin(const Lame& m, int d, const double* r);

/// dU[k][l][j] = d U_kl / d x_j at r = x - y (the gradient in the field point x).
std::array<Mat3, 3> kelvin_gradient(const Lame& m, int d, const double* r);

/// The stress of the column l of U (the field of a unit force e_l at y) at x:
/// S[l] = sigma(U e_l)(x) = lambda tr(eps) I + 2 mu eps, a d x d matrix (plane strain in 2D).
std::array<Mat3, 3> kelvin_stress(const Lame& m, int d, const double* r);

/// T[k][l] = (sigma(U e_l)(x) nx)_k: the traction at x on the plane with unit normal nx of
/// the field of a unit force e_l at y.
Mat3 kelvin_traction(const Lame& m, int d, const double* r, const double* nx);

/// The field of a point force F at x0, u(x) = U(x - x0) F, at k points: displacement (k, d)
/// and stress (k, d * d, row-major d x d per point). Throws std::invalid_argument (one line)
/// for d not 2 or 3, sizes that disagree, or a point at x0.
struct PointForceField {
  Matrix displacement, stress;
};
PointForceField kelvin_field(const Lame& m, const Eigen::Ref<const Matrix>& points,
                             const Eigen::Ref<const Vector>& source, const Eigen::Ref<const Vector>& force);

}  // namespace bem
