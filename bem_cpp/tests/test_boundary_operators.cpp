#include <gtest/gtest.h>

#include "bem/boundary_operators.hpp"
#include "bem/operators.hpp"
#include "test_helpers.hpp"

using namespace bem;

// The H-matrix products equal the dense Galerkin matrices' to the block tolerance (each
// block to relative tol in the Frobenius norm, so the product to a small multiple of it).
TEST(BoundaryOperators, MatchTheDenseMatrices) {
  for (const Points& X : {test::circle(700), test::square(160)}) {
    for (Space space : {Space::P1, Space::P0}) {
      const double tol = 1e-10;
      const BoundaryOperators ops(X, space, HMatrixOptions{32, 1.0, tol});
      const Polygon polygon(X);
      const Eigen::MatrixXd Y = Eigen::MatrixXd::Random(X.rows(), 3);
      const Eigen::MatrixXd v = single_layer(polygon, space) * Y;
      const Eigen::MatrixXd k = double_layer(polygon, space) * Y;
      EXPECT_LT((ops.single_layer(Y) - v).norm(), 10 * tol * v.norm());
      EXPECT_LT((ops.double_layer(Y) - k).norm(), 10 * tol * k.norm());
      EXPECT_LT(ops.nbytes(), 2 * sizeof(double) * X.rows() * X.rows());
      EXPECT_THROW(ops.single_layer(Eigen::MatrixXd::Zero(3, 1)), std::invalid_argument);
    }
  }
}
