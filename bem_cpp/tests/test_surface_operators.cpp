#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "bem/surface_operators.hpp"
#include "test_surfaces.hpp"

using namespace bem;

namespace {

/// Y_l (zonal, unnormalised) at the vertices' directions, l = 0..3.
Eigen::VectorXd zonal(const Vertices& X, int l) {
  Eigen::VectorXd u(X.rows());
  for (Index i = 0; i < X.rows(); ++i) {
    const double z = X(i, 2) / X.row(i).norm();
    const double p[4] = {1.0, z, 1.5 * z * z - 0.5, 2.5 * z * z * z - 1.5 * z};
    u(i) = p[l];
  }
  return u;
}

double quotient(const Matrix& A, const Matrix& M, const Eigen::VectorXd& u) { return u.dot(A * u) / u.dot(M * u); }

}  // namespace

TEST(SurfaceQuadrature, SymmetricRulesAreExactToTheirDegreeTheCollapsedGaussRulesTo2pMinus2) {
  // int_T s^i t^j = i! j! / (i + j + 2)! on the reference triangle
  auto exact = [](int i, int j) { return std::tgamma(i + 1) * std::tgamma(j + 1) / std::tgamma(i + j + 3); };
  auto error = [&exact](const TriangleRule& r, int i, int j) {
    double out = 0.0;
    for (int k = 0; k < r.size(); ++k) out += r.w[k] * std::pow(r.s[k], i) * std::pow(r.t[k], j);
    return std::abs(out - exact(i, j)) / exact(i, j);
  };
  // the worst relative error of a degree's monomials (round-off: powers up to 8, 16 terms)
  auto worst = [&error](const TriangleRule& r, int d) {
    double out = 0.0;
    for (int i = 0; i <= d; ++i) out = std::max(out, error(r, i, d - i));
    return out;
  };
  const int degrees[4] = {4, 5, 6, 8}, points[4] = {6, 7, 12, 16};
  for (int k = 0; k < 4; ++k) {
    const TriangleRule& rule = symmetric_rule(degrees[k]);
    ASSERT_EQ(rule.size(), points[k]);
    for (int q = 0; q < rule.size(); ++q)
      EXPECT_TRUE(rule.w[q] > 0 && rule.s[q] > 0 && rule.t[q] > 0 && rule.s[q] + rule.t[q] < 1);
    for (int d = 0; d <= degrees[k]; ++d) EXPECT_LT(worst(rule, d), 1e-14) << degrees[k] << " " << d;
    EXPECT_GT(worst(rule, degrees[k] + 1), 1e-5) << degrees[k];
  }
  EXPECT_EQ(far_rule().size(), kFarRulePoints);
  for (int p = 3; p <= 5; ++p) {
    // p x p collapsed Gauss points: degree 2p - 2 (the collapse's Jacobian 1 - u takes one)
    for (int d = 0; d <= 2 * p - 2; ++d) EXPECT_LT(worst(triangle_rule(p), d), 1e-14) << p << " " << d;
    EXPECT_GT(worst(triangle_rule(p), 2 * p - 1), 1e-5) << p;
  }
}

TEST(SurfaceOperators, SphereRayleighQuotientsConvergeAtOrderTwo) {
  const double R = 0.7;
  const int levels[3] = {1, 2, 3};
  double err[3][4][3] = {};  // [level][l][V, K, W]
  for (int k = 0; k < 3; ++k) {
    const test::Mesh mesh = test::icosphere(levels[k], R);
    const Surface s(mesh.vertices, mesh.triangles);
    const SurfaceMatrices A = assemble(s, {Space::P1, Space::P1, true});
    const Matrix M = mass(s, Space::P1);
    for (int l = 0; l < 4; ++l) {
      const Eigen::VectorXd u = zonal(mesh.vertices, l);
      err[k][l][0] = std::abs(quotient(A.single_layer, M, u) - 2 * R / (2 * l + 1));
      err[k][l][1] = std::abs(quotient(A.double_layer, M, u) + 1.0 / (2 * l + 1));
      err[k][l][2] = std::abs(quotient(A.hypersingular, M, u) - 2.0 * l * (l + 1) / ((2 * l + 1) * R));
    }
  }
  for (int l = 0; l < 4; ++l)
    for (int op = 0; op < 3; ++op) {
      // W 1 = 0 and K 1 = -1 hold on every polyhedron: no discretisation error to converge
      if (l == 0 && op > 0) continue;
      for (int k = 1; k < 3; ++k) {
        const double order = std::log2(err[k - 1][l][op] / err[k][l][op]);
        EXPECT_GE(order, 1.8) << "l = " << l << ", operator "
                              << "VKW"[op] << ", errors " << err[k - 1][l][op] << " -> " << err[k][l][op];
      }
    }
}

TEST(SurfaceOperators, IdentitiesOnPolyhedra) {
  // K 1 = -1 and W 1 = 0 on every closed polyhedron; V, W symmetric
  for (const test::Mesh& mesh : {test::cube(3, 1.0 / 3), test::fichera(4, 0.25)}) {
    const Surface s(mesh.vertices, mesh.triangles);
    for (Space space : {Space::P0, Space::P1}) {
      const SurfaceMatrices A = assemble(s, {space, space, space == Space::P1});
      const Matrix M = mass(s, space);
      const Eigen::VectorXd one = Eigen::VectorXd::Ones(s.vertices());
      const Eigen::VectorXd m1 = M * one;
      // the quadrature's accuracy (docs/design/bem3d.md)
      EXPECT_LE((A.double_layer * one + m1).cwiseAbs().maxCoeff(), 2e-4 * m1.cwiseAbs().maxCoeff());
      const double v = A.single_layer.cwiseAbs().maxCoeff();
      EXPECT_LE((A.single_layer - A.single_layer.transpose()).cwiseAbs().maxCoeff(), 1e-14 * v);
      if (space == Space::P1) {
        const double w = A.hypersingular.cwiseAbs().maxCoeff();
        EXPECT_LE((A.hypersingular - A.hypersingular.transpose()).cwiseAbs().maxCoeff(), 1e-14 * w);
        EXPECT_LE((A.hypersingular * one).cwiseAbs().maxCoeff(), 1e-14 * w);
      }
    }
  }
}

TEST(SurfaceOperators, HypersingularBlockIsTheRestrictionOfW) {
  // E^T W_h E from the triangles touching the block only: the same sums as the whole W_h
  for (const test::Mesh& mesh : {test::cube(3, 1.0 / 3), test::fichera(4, 0.25)}) {
    const Surface s(mesh.vertices, mesh.triangles);
    const Matrix W = assemble(s, {std::nullopt, std::nullopt, true}).hypersingular;
    std::vector<Index> block;  // the vertices below the centre plane, in descending order
    for (Index v = s.vertices() - 1; v >= 0; --v)
      if (mesh.vertices(v, 2) < mesh.vertices.col(2).mean()) block.push_back(v);
    ASSERT_GT(block.size(), 2u);
    const Matrix Wb = hypersingular_block(s, block);
    for (std::size_t i = 0; i < block.size(); ++i)
      for (std::size_t j = 0; j < block.size(); ++j)
        EXPECT_NEAR(Wb(static_cast<Index>(i), static_cast<Index>(j)), W(block[i], block[j]),
                    1e-14 * W.cwiseAbs().maxCoeff());
  }
  const test::Mesh mesh = test::cube(2, 1.0);
  const Surface s(mesh.vertices, mesh.triangles);
  EXPECT_THROW(hypersingular_block(s, {0, 0}), std::invalid_argument);
  EXPECT_THROW(hypersingular_block(s, {s.vertices()}), std::invalid_argument);
}
