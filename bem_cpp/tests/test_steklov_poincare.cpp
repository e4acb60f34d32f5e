#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "bem/steklov_poincare.hpp"
#include "test_helpers.hpp"

using namespace bem;

TEST(SteklovPoincare, SymmetricPositiveDefiniteAndConsistent) {
  for (Space flux : {Space::P1, Space::P0}) {
    const Polygon poly(test::square(9));
    StageTimes times;
    const Matrix S = steklov_poincare(poly, flux, &times);
    EXPECT_TRUE(S.isApprox(S.transpose(), 0.0));
    EXPECT_EQ(Eigen::LLT<Matrix>(S).info(), Eigen::Success);
    Matrix A = double_layer(poly, flux);
    add_mass(poly, flux, -1.0, A);
    const Matrix ref = 0.5 * (hypersingular(poly) + A.transpose() * single_layer(poly, flux).llt().solve(A));
    EXPECT_LT((S - ref).cwiseAbs().maxCoeff(), 1e-12 * ref.cwiseAbs().maxCoeff());
    EXPECT_GE(times.assembly, 0.0);
  }
}

TEST(SteklovPoincare, CircleValueOfConstant) {
  // S 1 = -1/(R log R) on the circle, O(h^2) on the inscribed polygon.
  const double R = 0.4;
  const Polygon poly(test::circle(256, R));
  const Matrix S = steklov_poincare(poly, Space::P1), M = mass(poly, Space::P1);
  const Vector one = Vector::Ones(256);
  EXPECT_NEAR(one.dot(S * one) / one.dot(M * one), -1 / (R * std::log(R)), 1e-3);
}

TEST(SteklovPoincare, CapacityAboveOneIsReported) {
  const Polygon big(test::circle(32, 2.0));
  try {
    steklov_poincare(big, Space::P1);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("not positive definite"), std::string::npos);
    EXPECT_NE(what.find("logarithmic capacity"), std::string::npos);
    EXPECT_NE(what.find("rescale"), std::string::npos);
  }
  EXPECT_THROW(exterior_flux(big, Vector::Ones(32), 0.0, Space::P0), std::invalid_argument);
}

TEST(SteklovPoincare, FluxOfLogarithm) {
  // u_e = log|x| on the circle: v = log R, a = 0, du/dn = 1/R exactly, total 2 pi.
  const double R = 0.4;
  const Polygon poly(test::circle(128, R));
  const Vector v = Vector::Constant(128, std::log(R));
  for (Space flux : {Space::P1, Space::P0}) {
    const Vector psi = exterior_flux(poly, v, 0.0, flux);
    const double total = (mass(poly, flux).rowwise().sum().transpose() * psi)(0);
    EXPECT_NEAR(total, 2 * M_PI, 2 * M_PI * 1e-3);
  }
}
