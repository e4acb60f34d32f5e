#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "bem/potentials.hpp"
#include "bem/steklov_poincare.hpp"
#include "test_helpers.hpp"

using namespace bem;

namespace {
// Exterior harmonic function with x0 inside: a + log|x - x0| + c.(x - x0)/|x - x0|^2.
double u_exact(double x, double y) {
  const double dx = x - 0.05, dy = y + 0.02, r2 = dx * dx + dy * dy;
  return 0.3 + 0.5 * std::log(r2) + (0.2 * dx - 0.1 * dy) / r2;
}
}  // namespace

TEST(Potentials, RepresentationFormulaConverges) {
  Points Z(3, 2);
  Z << 0.8, 0.1, -0.3, 0.9, 3.0, -4.0;
  double previous = 0;
  for (Index n : {64, 256}) {
    const Polygon poly(test::square(n / 4));
    Vector v(n);
    for (Index k = 0; k < n; ++k) v(k) = u_exact(poly.panel(k).a.x, poly.panel(k).a.y);
    const Vector psi = exterior_flux(poly, v, 0.3, Space::P0);
    const Vector u = exterior_potential(poly, v, psi, Z, 0.3, Space::P0);
    double err = 0;
    for (Index k = 0; k < 3; ++k) err = std::max(err, std::abs(u(k) - u_exact(Z(k, 0), Z(k, 1))));
    if (previous > 0) EXPECT_GT(previous / err, 16 / 1.3);  // O(h^2): factor 16 per 4x refinement
    previous = err;
  }
}

TEST(Potentials, RejectsInteriorAndBoundaryPoints) {
  const Polygon poly(test::square(4));
  const Vector v = Vector::Zero(16);
  Points inside(1, 2), on(1, 2), outside(1, 2);
  inside << 0.0, 0.1;
  on << 0.3, 0.05;
  outside << 0.3 + 1e-9, 0.05;
  EXPECT_THROW(exterior_potential(poly, v, v, inside, 0.0, Space::P1), std::invalid_argument);
  EXPECT_THROW(exterior_potential(poly, v, v, on, 0.0, Space::P1), std::invalid_argument);
  EXPECT_NO_THROW(exterior_potential(poly, v, v, outside, 0.0, Space::P1));
}

TEST(Potentials, ConstantDataGiveTheConstant) {
  // v = a, psi = 0: u_e = a everywhere outside.
  const Polygon poly(test::circle(50));
  const Vector v = Vector::Constant(50, 1.7), psi = Vector::Zero(50);
  Points Z(2, 2);
  Z << 0.41, 0.0, -2.0, 1.0;
  const Vector u = exterior_potential(poly, v, psi, Z, 1.7, Space::P1);
  EXPECT_DOUBLE_EQ(u(0), 1.7);
  EXPECT_DOUBLE_EQ(u(1), 1.7);
  // The double layer of 1 is 0 outside: K 1 (z) / 2 + a with v = a + 1.
  const Vector w = exterior_potential(poly, Vector::Constant(50, 2.7), psi, Z, 1.7, Space::P1);
  EXPECT_NEAR(w(0), 1.7, 1e-13);
  EXPECT_NEAR(w(1), 1.7, 1e-13);
}
