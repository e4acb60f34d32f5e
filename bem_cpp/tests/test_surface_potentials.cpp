#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "bem/surface_potential_operator.hpp"
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

namespace {

/// Points of a sheet around a surface centred at 0 of half-width `half`: a pixel grid of the
/// plane z = `plane` on [-2 half, 2 half]^2, outside the ball (sphere) or box of `half`.
Vertices sheet(double half, double plane, int k, bool sphere) {
  std::vector<Vec3> kept;
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      const Vec3 z{(4.0 * i / (k - 1) - 2.0 + 1.0 / (3 * k)) * half, (4.0 * j / (k - 1) - 2.0 + 1.0 / (3 * k)) * half,
                   plane};
      const double size = sphere ? norm(z) : std::max({std::abs(z.x), std::abs(z.y), std::abs(z.z)});
      if (size > 1.02 * half) kept.push_back(z);
    }
  Vertices Z(static_cast<Index>(kept.size()), 3);
  for (std::size_t r = 0; r < kept.size(); ++r) Z.row(static_cast<Index>(r)) << kept[r].x, kept[r].y, kept[r].z;
  return Z;
}

double max_relative_difference(const Vector& a, const Vector& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

}  // namespace

TEST(SurfacePotentialOperator, AgreesWithTheDirectSums) {
  // the admissible blocks' rule is the direct evaluation's for their closest pair or a finer
  // one, so the two differ by tol and by the direct evaluation's quadrature error, which
  // does not fall with tol: 1.5e-9 .. 1.24e-8 here at tol 1e-8, 1.23e-8 on the cube (P0) at
  // 1e-12 (docs/design/bem3d.md, "The exterior potential")
  struct Case {
    test::Mesh mesh;
    double half, plane;
    bool sphere;
  };
  const Case cases[] = {
      {test::icosphere(3), 1.0, 0.1, true},
      {test::cube(12, 1.0 / 12), 0.5, 0.5, false},  // the points in the plane of a face
      {test::fichera(12, 1.0 / 12), 0.5, 0.0, false},
  };
  const HMatrixOptions options{16, 2.0, 1e-8};
  for (const Case& c : cases) {
    const Surface s(c.mesh.vertices, c.mesh.triangles);
    const Vertices Z = sheet(c.half, c.plane, 40, c.sphere);
    Vector v(s.vertices());
    for (Index i = 0; i < s.vertices(); ++i) v(i) = std::sin(3 * s.vertex(i).x) + s.vertex(i).y * s.vertex(i).z;
    for (Space flux : {Space::P1, Space::P0}) {
      Vector psi(dofs(s, flux));
      for (Index j = 0; j < psi.size(); ++j) psi(j) = std::cos(0.7 * j);
      const Vector direct = exterior_potential(c.mesh.vertices, c.mesh.triangles, v, psi, Z, 0.3, flux);
      const SurfacePotentialOperator op(s, Z, flux, options);
      EXPECT_LE(max_relative_difference(op.evaluate(v, psi, 0.3), direct), 3e-8) << Z.rows();
      EXPECT_LT(op.nbytes(), static_cast<std::size_t>(Z.rows() * (s.vertices() + psi.size()) * 8));  // compressed
    }
  }
}

TEST(SurfacePotentialOperator, RefusesPointsInsideAndOnGammaAsTheDirectSums) {
  const test::Mesh mesh = test::cube(4, 0.25);
  const Surface s(mesh.vertices, mesh.triangles);
  Vertices Z = sheet(0.5, 0.2, 20, false);
  const Index n = Z.rows();
  const HMatrixOptions options{16, 2.0, 1e-6};
  EXPECT_NO_THROW(SurfacePotentialOperator(s, Z, Space::P1, options));
  const Vec3 bad[] = {
      {0.1, 0.2, 0.3}, {0.5, 0.1, 0.1}, {0.5, 0.5, 0.5}, {0.5, 0.25, 0.25}};  // inside, face, corner, vertex
  for (const Vec3& b : bad) {
    Vertices W(n + 2, 3);
    W.topRows(n) = Z;
    W.row(n) << b.x, b.y, b.z;
    W.row(n + 1) << 3.0, 0.0, 0.0;
    try {
      SurfacePotentialOperator(s, W, Space::P1, options);
      ADD_FAILURE() << "accepted " << b.x << " " << b.y << " " << b.z;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("point " + std::to_string(n) + " ("), std::string::npos) << e.what();
    }
  }
}
