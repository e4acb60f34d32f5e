#include <gtest/gtest.h>

#include <cmath>

#include "bem/operators.hpp"
#include "test_helpers.hpp"

using namespace bem;

TEST(Operators, SymmetryAndPositivity) {
  const Polygon poly(test::square(10));
  for (Space s : {Space::P1, Space::P0}) {
    const Matrix V = single_layer(poly, s);
    EXPECT_TRUE(V.isApprox(V.transpose(), 0.0));
    EXPECT_EQ(Eigen::LLT<Matrix>(V).info(), Eigen::Success);
  }
  const Matrix W = hypersingular(poly);
  EXPECT_TRUE(W.isApprox(W.transpose(), 0.0));
}

TEST(Operators, UpperTriangleOnlyRequest) {
  const Polygon poly(test::circle(37));  // odd n: three colours of panels
  OperatorRequest full, upper;
  full.single_layer = upper.single_layer = Space::P1;
  full.hypersingular = upper.hypersingular = true;
  upper.full_symmetric = false;
  const Operators a = assemble(poly, full), b = assemble(poly, upper);
  for (Index r = 0; r < 37; ++r)
    for (Index c = r; c < 37; ++c) {
      EXPECT_EQ(a.single_layer(r, c), b.single_layer(r, c));
      EXPECT_EQ(a.hypersingular(r, c), b.hypersingular(r, c));
    }
}

TEST(Operators, DoubleLayerOfConstant) {
  // K 1 = -1 inside every panel of a polygon: K_h 1 = -M_h 1 to round-off.
  for (const Points& X : {test::square(7), test::circle(41)}) {
    const Polygon poly(X);
    for (Space s : {Space::P1, Space::P0}) {
      const Matrix K = double_layer(poly, s), M = mass(poly, s);
      const Vector one = Vector::Ones(poly.size());
      EXPECT_LT((K * one + M * one).cwiseAbs().maxCoeff(), 1e-13 * K.cwiseAbs().rowwise().sum().maxCoeff());
    }
  }
}

TEST(Operators, MaueIdentity) {
  const Polygon poly(test::square(5));
  const Index n = poly.size();
  Matrix D = Matrix::Zero(n, n);
  for (Index i = 0; i < n; ++i) {
    D(i, i) = -1.0 / poly.panel(i).h;
    D(i, (i + 1) % n) = 1.0 / poly.panel(i).h;
  }
  const Matrix W = hypersingular(poly), ref = D.transpose() * single_layer(poly, Space::P0) * D;
  EXPECT_LT((W - ref).cwiseAbs().maxCoeff(), 1e-13 * ref.cwiseAbs().maxCoeff());
  EXPECT_LT((W * Vector::Ones(n)).cwiseAbs().maxCoeff(), 1e-13 * W.cwiseAbs().maxCoeff() * n);
}

TEST(Operators, CircleEigenvaluesToSecondOrder) {
  // Rayleigh quotients of cos(theta) on the inscribed 256-gon, R = 0.4: V -> R,
  // W -> 1/R, K -> 0, each within the O((h/R)^2) polygon/interpolation error.
  const double R = 0.4;
  const Index n = 256;
  const Polygon poly(test::circle(n, R));
  Vector c(n);
  for (Index k = 0; k < n; ++k) c(k) = std::cos(2 * M_PI * k / n);
  const Matrix M = mass(poly, Space::P1);
  const double norm2 = c.dot(M * c), bound = std::pow(2 * M_PI / n, 2);
  EXPECT_NEAR(c.dot(single_layer(poly, Space::P1) * c) / norm2, R, bound * R);
  EXPECT_NEAR(c.dot(hypersingular(poly) * c) / norm2, 1 / R, bound / R);
  EXPECT_NEAR(c.dot(double_layer(poly, Space::P1) * c) / norm2, 0.0, bound);
}

TEST(Operators, MassMatrices) {
  const Polygon poly(test::square(3));
  const Matrix M1 = mass(poly, Space::P1), M0 = mass(poly, Space::P0);
  EXPECT_NEAR(M1.sum(), 2.4, 1e-15);
  EXPECT_NEAR(M0.sum(), 2.4, 1e-15);
  EXPECT_DOUBLE_EQ(M1(0, 0), 2 * 0.2 / 3);
  EXPECT_DOUBLE_EQ(M1(0, 1), 0.2 / 6);
  EXPECT_DOUBLE_EQ(M0(0, 1), 0.1);
  EXPECT_DOUBLE_EQ(M0(1, 0), 0.0);
}
