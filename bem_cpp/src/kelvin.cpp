#include "bem/kelvin.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace bem {

Lame lame_from_young(double E, double nu) {
  std::ostringstream msg;
  if (!(std::isfinite(E) && E > 0.0))
    msg << "Young's modulus E = " << E << " must be positive: give E > 0";
  else if (!(std::isfinite(nu) && nu > -1.0 && nu < 0.5))
    msg << "Poisson's ratio nu = " << nu << " must lie in (-1, 1/2): give -1 < nu < 0.5";
  if (!msg.str().empty()) throw std::invalid_argument(msg.str());
  return {E / (2.0 * (1.0 + nu)), nu};
}

void check_medium(const Lame& m, const char* nu_note) {
  std::ostringstream msg;
  if (!(std::isfinite(m.mu) && m.mu > 0.0))
    msg << "Lame: the shear modulus mu = " << m.mu << " must be positive: give mu > 0";
  else if (!(std::isfinite(m.nu) && m.nu > -1.0 && m.nu < 0.5))
    msg << "Lame: Poisson's ratio nu = " << m.nu << " must lie in (-1, 1/2)" << nu_note << ": give -1 < nu < 0.5";
  if (!msg.str().empty()) throw std::invalid_argument(msg.str());
}

namespace {

constexpr double kPi = 3.14159265358979323846;

double dot(int d, const double* a, const double* b) {
  double s = 0.0;
  for (int i = 0; i < d; ++i) s += a[i] * b[i];
  return s;
}

}  // namespace

Mat3 kelvin(const Lame& m, int d, const double* r) {
  Mat3 U{};
  const double r2 = dot(d, r, r);
  const double a = 3.0 - 4.0 * m.nu;
  if (d == 3) {
    const double rr = std::sqrt(r2), c = 1.0 / (16.0 * kPi * m.mu * (1.0 - m.nu) * rr);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) U[k][l] = c * ((k == l ? a : 0.0) + r[k] * r[l] / r2);
  } else {
    const double c = 1.0 / (8.0 * kPi * m.mu * (1.0 - m.nu)), lg = 0.5 * std::log(r2);
    for (int k = 0; k < 2; ++k)
      for (int l = 0; l < 2; ++l) U[k][l] = c * ((k == l ? -a * lg : 0.0) + r[k] * r[l] / r2);
  }
  return U;
}

std::array<Mat3, 3> kelvin_gradient(const Lame& m, int d, const double* r) {
  // 3D: c [ -a d_kl r_j / r^3 + (d_kj r_l + d_lj r_k) / r^3 - 3 r_k r_l r_j / r^5 ]
  // 2D: c [ -a d_kl r_j / r^2 + (d_kj r_l + d_lj r_k) / r^2 - 2 r_k r_l r_j / r^4 ]
  std::array<Mat3, 3> G{};
  const double r2 = dot(d, r, r), a = 3.0 - 4.0 * m.nu;
  double c, p;  // c / |r|^p is the common factor, p + 2 the power of the last term
  if (d == 3) {
    c = 1.0 / (16.0 * kPi * m.mu * (1.0 - m.nu));
    p = r2 * std::sqrt(r2);
  } else {
    c = 1.0 / (8.0 * kPi * m.mu * (1.0 - m.nu));
    p = r2;
  }
  const double f = c / p, g = d * c / (p * r2);
  for (int k = 0; k < d; ++k)
    for (int l = 0; l < d; ++l)
      for (int j = 0; j < d; ++j)
        G[k][l][j] =
            f * ((k == l ? -a * r[j] : 0.0) + (k == j ? r[l] : 0.0) + (l == j ? r[k] : 0.0)) - g * r[k] * r[l] * r[j];
  return G;
}

std::array<Mat3, 3> kelvin_stress(const Lame& m, int d, const double* r) {
  const std::array<Mat3, 3> G = kelvin_gradient(m, d, r);
  const double lambda = m.lambda();
  std::array<Mat3, 3> S{};
  for (int l = 0; l < d; ++l) {
    // the field U e_l: u_k = U_kl, grad u_kj = G[k][l][j]
    double div = 0.0;
    for (int k = 0; k < d; ++k) div += G[k][l][k];
    for (int k = 0; k < d; ++k)
      for (int j = 0; j < d; ++j) S[l][k][j] = (k == j ? lambda * div : 0.0) + m.mu * (G[k][l][j] + G[j][l][k]);
  }
  return S;
}

Mat3 kelvin_traction(const Lame& m, int d, const double* r, const double* nx) {
  const std::array<Mat3, 3> S = kelvin_stress(m, d, r);
  Mat3 T{};
  for (int k = 0; k < d; ++k)
    for (int l = 0; l < d; ++l) T[k][l] = dot(d, S[l][k].data(), nx);
  return T;
}

PointForceField kelvin_field(const Lame& m, const Eigen::Ref<const Matrix>& points,
                             const Eigen::Ref<const Vector>& source, const Eigen::Ref<const Vector>& force) {
  const Index k = points.rows(), d = points.cols();
  if (d != 2 && d != 3) throw std::invalid_argument("points must have 2 or 3 columns, got " + std::to_string(d));
  if (source.size() != d || force.size() != d)
    throw std::invalid_argument("source and force must have " + std::to_string(d) + " components each");
  PointForceField out{Matrix::Zero(k, d), Matrix::Zero(k, d * d)};
  for (Index p = 0; p < k; ++p) {
    double r[3] = {0.0, 0.0, 0.0};
    for (Index j = 0; j < d; ++j) r[j] = points(p, j) - source(j);
    if (dot(static_cast<int>(d), r, r) == 0.0)
      throw std::invalid_argument("point " + std::to_string(p) + " is the source of the point force");
    const Mat3 U = kelvin(m, static_cast<int>(d), r);
    const std::array<Mat3, 3> S = kelvin_stress(m, static_cast<int>(d), r);
    for (Index a = 0; a < d; ++a)
      for (Index l = 0; l < d; ++l) {
        out.displacement(p, a) += U[a][l] * force(l);
        for (Index b = 0; b < d; ++b) out.stress(p, a * d + b) += S[l][a][b] * force(l);
      }
  }
  return out;
}

}  // namespace bem
