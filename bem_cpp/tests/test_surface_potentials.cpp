#include <gtest/gtest.h>

#include <cmath>

#include "bem/surface_potentials.hpp"
#include "test_surfaces.hpp"

using namespace bem;

TEST(SurfacePotentials, DoubleLayerOfOneIsTheSolidAngleUpToTheTriangle) {
  // sum_b 2 int dG/dn lambda_b = -(solid angle) / (2 pi), exactly, however close z is
  const test::Mesh mesh = test::icosphere(0);
  const Surface s(mesh.vertices, mesh.triangles);
  const Triangle& t = s.triangle(0);
  const double h = std::sqrt(t.area);
  for (double d : {1.0, 1e-1, 1e-2, 1e-3, 1e-4})
    for (double w : {1.0 / 3.0, 0.01, 0.49}) {
      const Vec3 foot = t.p[0] + w * (t.p[1] - t.p[0]) + 0.5 * w * (t.p[2] - t.p[0]);
      for (double side : {-1.0, 1.0}) {
        const Vec3 z = foot + (side * d * h) * t.n;
        const PointIntegrals I = point_integrals(t, z);
        EXPECT_NEAR(I.K[0] + I.K[1] + I.K[2], -solid_angle(t, z) / (2 * M_PI), 1e-9) << d << " " << w;
        EXPECT_NEAR(I.V[0] + I.V[1] + I.V[2], I.V[3], 1e-13 * std::abs(I.V[3]));
      }
    }
}

TEST(SurfacePotentials, ConstantDataGiveTheConstantCloseToGamma) {
  // v = a, psi = 0: u_e = a at every exterior point (K 1 = 0 outside)
  const test::Mesh mesh = test::cube(4, 0.25);
  const Surface s(mesh.vertices, mesh.triangles);
  const Vector v = Vector::Constant(s.vertices(), 1.0), psi = Vector::Zero(s.vertices());
  Vertices Z(4, 3);
  Z << 0.5 + 1e-6, 0.1, 0.2, 0.1, 0.5 + 1e-3, -0.3, 0.51, 0.51, 0.51, 2.0, 0.0, 0.0;
  const Vector u =
      exterior_potential(mesh.vertices, mesh.triangles, v + Vector::Constant(v.size(), 2.0), psi, Z, 2.0, Space::P1);
  for (Index k = 0; k < Z.rows(); ++k) EXPECT_NEAR(u(k), 2.0, 1e-8);
}

TEST(SurfacePotentials, RefusesPointsInsideAndOnGamma) {
  const test::Mesh mesh = test::cube(2, 0.5);
  const Vector v = Vector::Zero(mesh.vertices.rows());
  Vertices Z(2, 3);
  Z << 2.0, 0.0, 0.0, 0.5, 0.1, 0.1;  // the second on a face
  EXPECT_THROW(exterior_potential(mesh.vertices, mesh.triangles, v, v, Z, 0.0, Space::P1), std::invalid_argument);
  Z.row(1) << 0.0, 0.1, 0.1;  // inside
  EXPECT_THROW(exterior_potential(mesh.vertices, mesh.triangles, v, v, Z, 0.0, Space::P1), std::invalid_argument);
}
