#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "bem/kelvin.hpp"
#include "bem/log_integrals.hpp"

using namespace bem;

namespace {

const Lame kMedium{0.8, 0.3};
// Field points r = x - y (2D uses the first two components).
const double kPoints[3][3] = {{0.3, -0.2, 0.5}, {-1.1, 0.4, 0.2}, {0.05, 0.07, -0.03}};

double max_abs(const Mat3& A, int d) {  // over the d x d block
  double m = 0;
  for (int k = 0; k < d; ++k)
    for (int l = 0; l < d; ++l) m = std::max(m, std::abs(A[k][l]));
  return m;
}

}  // namespace

TEST(Kelvin, GradientIsTheDerivativeOfU) {
  // Central differences, step s = 1e-5 |r|: truncation O(s^2) ~ 1e-10 relative, round-off
  // ~ 1e-16/1e-5 = 1e-11; measured worst error 1.4e-10 of the largest entry.
  for (int d : {2, 3})
    for (const auto& r0 : kPoints) {
      const double len = std::sqrt(r0[0] * r0[0] + r0[1] * r0[1] + (d == 3 ? r0[2] * r0[2] : 0.0));
      const double s = 1e-5 * len;
      const std::array<Mat3, 3> G = kelvin_gradient(kMedium, d, r0);
      double scale = 0;  // the size of the gradient
      for (int j = 0; j < d; ++j)
        for (int k = 0; k < d; ++k)
          for (int l = 0; l < d; ++l) scale = std::max(scale, std::abs(G[k][l][j]));
      for (int j = 0; j < d; ++j) {
        double rp[3] = {r0[0], r0[1], r0[2]}, rm[3] = {r0[0], r0[1], r0[2]};
        rp[j] += s;
        rm[j] -= s;
        const Mat3 Up = kelvin(kMedium, d, rp), Um = kelvin(kMedium, d, rm);
        for (int k = 0; k < d; ++k)
          for (int l = 0; l < d; ++l) EXPECT_NEAR(G[k][l][j], (Up[k][l] - Um[k][l]) / (2 * s), 1e-9 * scale);
      }
    }
}

TEST(Kelvin, StressIsDivergenceFreeAwayFromTheSource) {
  // div sigma(U e_l) = 0 for x != y: central differences of kelvin_stress (step 1e-5 |r|),
  // against max |sigma|/|r|; measured worst 7.7e-10 (the truncation error).
  for (const Lame& m : {kMedium, Lame{2.0, 0.49}, Lame{1.0, -0.5}})
    for (int d : {2, 3})
      for (const auto& r0 : kPoints) {
        const double len = std::sqrt(r0[0] * r0[0] + r0[1] * r0[1] + (d == 3 ? r0[2] * r0[2] : 0.0));
        const double s = 1e-5 * len;
        const std::array<Mat3, 3> S0 = kelvin_stress(m, d, r0);
        double div[3][3] = {}, scale = 0;
        for (int l = 0; l < d; ++l) scale = std::max(scale, max_abs(S0[static_cast<std::size_t>(l)], d) / len);
        for (int j = 0; j < d; ++j) {
          double rp[3] = {r0[0], r0[1], r0[2]}, rm[3] = {r0[0], r0[1], r0[2]};
          rp[j] += s;
          rm[j] -= s;
          const std::array<Mat3, 3> Sp = kelvin_stress(m, d, rp), Sm = kelvin_stress(m, d, rm);
          for (int l = 0; l < d; ++l)
            for (int k = 0; k < d; ++k) div[l][k] += (Sp[l][k][j] - Sm[l][k][j]) / (2 * s);
        }
        for (int l = 0; l < d; ++l)
          for (int k = 0; k < d; ++k) EXPECT_NEAR(div[l][k], 0.0, 1e-8 * scale);
      }
}

TEST(Kelvin, TractionAndEquilibriumOfTheUnitForce) {
  // T[k][l] = (sigma(U e_l) n)_k, and the traction on a circle / sphere around the source
  // balances the unit point force: int_{|x - y| = rho} T(x - y, n_x) ds_x = -I (n outward),
  // which fixes the normalisation of U. Trapezoidal rule on the circle (spectral),
  // Gauss-Legendre in cos(theta) x trapezoidal in phi on the sphere: round-off.
  for (int d : {2, 3}) {
    const std::array<Mat3, 3> S = kelvin_stress(kMedium, d, kPoints[0]);
    const double n[3] = {0.6, 0.0, 0.8};
    const double n2[3] = {0.6, 0.8, 0.0};
    const double* nd = d == 3 ? n : n2;
    const Mat3 T = kelvin_traction(kMedium, d, kPoints[0], nd);
    for (int k = 0; k < d; ++k)
      for (int l = 0; l < d; ++l) {
        double sn = 0;
        for (int j = 0; j < d; ++j) sn += S[l][k][j] * nd[j];
        EXPECT_DOUBLE_EQ(T[k][l], sn);
      }
  }
  const double rho = 0.37;
  Mat3 total{};
  const int m = 64;
  for (int q = 0; q < m; ++q) {
    const double a = 2 * M_PI * q / m, nx[2] = {std::cos(a), std::sin(a)}, r[2] = {rho * nx[0], rho * nx[1]};
    const Mat3 T = kelvin_traction(kMedium, 2, r, nx);
    for (int k = 0; k < 2; ++k)
      for (int l = 0; l < 2; ++l) total[k][l] += T[k][l] * 2 * M_PI * rho / m;
  }
  for (int k = 0; k < 2; ++k)
    for (int l = 0; l < 2; ++l) EXPECT_NEAR(total[k][l], k == l ? -1.0 : 0.0, 1e-14);
  total = Mat3{};
  const GaussRule& g = gauss_legendre(16);
  for (int i = 0; i < 16; ++i)
    for (int q = 0; q < 32; ++q) {
      const double c = 2 * g.x[static_cast<std::size_t>(i)] - 1, sn = std::sqrt(1 - c * c), p = 2 * M_PI * q / 32;
      const double nx[3] = {sn * std::cos(p), sn * std::sin(p), c}, r[3] = {rho * nx[0], rho * nx[1], rho * nx[2]};
      const double w = 2 * g.w[static_cast<std::size_t>(i)] * (2 * M_PI / 32) * rho * rho;
      const Mat3 T = kelvin_traction(kMedium, 3, r, nx);
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) total[k][l] += w * T[k][l];
    }
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) EXPECT_NEAR(total[k][l], k == l ? -1.0 : 0.0, 1e-14);
}

TEST(Kelvin, LameFromYoung) {
  const Lame m = lame_from_young(2.6, 0.3);
  EXPECT_DOUBLE_EQ(m.mu, 1.0);
  EXPECT_DOUBLE_EQ(m.nu, 0.3);
  EXPECT_DOUBLE_EQ(m.lambda(), 1.5);
  for (double E : {0.0, -1.0, double(NAN), double(INFINITY)})
    EXPECT_THROW(lame_from_young(E, 0.3), std::invalid_argument);
  for (double nu : {-1.0, 0.5, 0.7, double(NAN)}) EXPECT_THROW(lame_from_young(1.0, nu), std::invalid_argument);
}
