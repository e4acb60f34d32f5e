#include <gtest/gtest.h>

#include <random>

#include "bem/potential_operator.hpp"
#include "bem/potentials.hpp"
#include "test_helpers.hpp"

using namespace bem;

namespace {
/// The L-shape [0, 0.6]^2 minus [0.3, 0.6]^2 with k panels per 0.3 of side.
Points l_shape(Index k) { return test::l_shape(k, 0.3, {0.3, 0.3}); }

/// Points at distances 1e-6 ... 1e-2 outside random panel points, and an exterior grid.
Points targets(const Polygon& poly, Index near, Index grid) {
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec2> z;
  for (Index k = 0; k < near; ++k) {
    const Panel& p = poly.panel(static_cast<Index>(u(gen) * static_cast<double>(poly.size())) % poly.size());
    const double s = 0.02 + 0.96 * u(gen), d = std::pow(10.0, -6.0 + 4.0 * u(gen));
    z.push_back(Vec2{p.a.x + s * p.h * p.t.x + d * p.t.y, p.a.y + s * p.h * p.t.y - d * p.t.x});
  }
  for (Index i = 0; i < grid; ++i)
    for (Index j = 0; j < grid; ++j) z.push_back(Vec2{-1.0 + 2.2 * i / (grid - 1.0), -1.0 + 2.2 * j / (grid - 1.0)});
  const double tol = 1e-9 * poly.bounding_diameter();
  Points Z(static_cast<Index>(z.size()), 2);
  Index m = 0;
  for (const Vec2& q : z)
    if (locate(poly, q, tol) == Location::Exterior) {
      Z(m, 0) = q.x;
      Z(m, 1) = q.y;
      ++m;
    }
  return Points(Z.topRows(m));
}
}  // namespace

TEST(PotentialOperator, BlocksCoverEveryPointDofPairOnce) {
  const Polygon poly(l_shape(40));
  const Points Z = targets(poly, 600, 50);
  for (Space flux : {Space::P1, Space::P0}) {
    const PotentialOperator op(poly, Z, flux, HMatrixOptions{16, 2.0, 1e-8});
    for (const HMatrix* H : {&op.double_layer(), &op.single_layer()}) {
      ASSERT_EQ(H->rows(), Z.rows());
      ASSERT_EQ(H->cols(), poly.size());
      Eigen::MatrixXi count = Eigen::MatrixXi::Zero(H->rows(), H->cols());
      Index low_rank = 0;
      for (const HMatrix::Block& b : H->blocks()) {
        count.block(b.r0, b.c0, b.m, b.k).array() += 1;
        const bool leaves = H->row_tree().cluster(b.row_cluster).leaf() && H->col_tree().cluster(b.col_cluster).leaf();
        const bool adm =
            admissible(H->row_tree().cluster(b.row_cluster).box, H->col_tree().cluster(b.col_cluster).box, 2.0);
        EXPECT_TRUE(adm || leaves);  // dense blocks only between two leaves
        low_rank += b.low_rank;
      }
      EXPECT_EQ(count.minCoeff(), 1);
      EXPECT_EQ(count.maxCoeff(), 1);
      EXPECT_GT(low_rank, 0);
      EXPECT_LT(H->nbytes(), static_cast<std::size_t>(H->rows() * H->cols()) * sizeof(double));
    }
  }
}

TEST(PotentialOperator, EqualsTheDirectEvaluation) {
  for (const Points& X : {test::circle(500), l_shape(60)}) {
    const Polygon poly(X);
    const Points Z = targets(poly, 1500, 60);
    const Index n = poly.size();
    const Vector v = Vector::Random(n), psi = Vector::Random(n);
    for (Space flux : {Space::P1, Space::P0})
      for (double tol : {1e-6, 1e-10}) {
        const Vector direct = exterior_potential(poly, v, psi, Z, 0.3, flux);
        const Vector h = exterior_potential_hmatrix(X, v, psi, Z, 0.3, flux, HMatrixOptions{48, 2.0, tol});
        const double err = (h - direct).lpNorm<Eigen::Infinity>() / direct.lpNorm<Eigen::Infinity>();
        EXPECT_LT(err, 10 * tol) << "n " << n << " tol " << tol;
      }
  }
}

TEST(PotentialOperator, RejectsInteriorPoints) {
  const Polygon poly(test::circle(64));
  Points Z(2, 2);
  Z << 1.0, 0.0, 0.0, 0.0;
  EXPECT_THROW(PotentialOperator(poly, Z, Space::P1, HMatrixOptions{16, 2.0, 1e-8}), std::invalid_argument);
}

TEST(PotentialOperator, ExteriorCheckAgreesWithLocate) {
  // The tree-pruned check of check_exterior against locate, point by point: nodes, points
  // on and within 1e-13 of panels, and a grid whose rows pass through the square's nodes.
  for (const Points& X : {test::square(20), l_shape(15), test::circle(90)}) {
    const Polygon poly(X);
    std::vector<Vec2> z;
    const double h = 0.6 / 30.0;
    for (Index i = -40; i <= 40; ++i)
      for (Index j = -40; j <= 40; ++j) z.push_back(Vec2{i * h, j * h});
    for (Index j = 0; j < poly.size(); ++j) {
      const Panel& p = poly.panel(j);
      z.push_back(p.a);
      z.push_back(p.m);
      z.push_back(Vec2{p.m.x + 1e-13 * p.t.y, p.m.y - 1e-13 * p.t.x});
      z.push_back(Vec2{p.m.x + 1e-9 * p.t.y, p.m.y - 1e-9 * p.t.x});
    }
    const double tol = kOnBoundaryTolerance * poly.bounding_diameter();
    Index exterior = 0, other = 0;
    for (const Vec2& q : z) {
      Points Z(1, 2);
      Z << q.x, q.y;
      const bool out = locate(poly, q, tol) == Location::Exterior;
      (out ? exterior : other) += 1;
      if (out)
        EXPECT_NO_THROW(check_exterior(poly, Z));
      else
        EXPECT_THROW(check_exterior(poly, Z), std::invalid_argument);
    }
    EXPECT_GT(exterior, 0);
    EXPECT_GT(other, 0);
  }
}
