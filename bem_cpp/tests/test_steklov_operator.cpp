#include <gtest/gtest.h>

#include "bem/steklov_operator.hpp"
#include "bem/steklov_poincare.hpp"
#include "test_helpers.hpp"

using namespace bem;

TEST(SteklovPoincareOperator, MatchesTheDenseOperator) {
  for (const Points& X : {test::circle(700), test::square(160)}) {
    for (Space flux : {Space::P1, Space::P0}) {
      const double tol = 1e-10;
      const SteklovPoincareOperator S(X, flux, SteklovOptions{{32, 1.0, tol}, 1e-4, 1e-3 * tol, 1000});
      const Matrix dense = steklov_poincare(Polygon(X), flux);
      const Eigen::MatrixXd Y = Eigen::MatrixXd::Random(X.rows(), 4);
      const Eigen::MatrixXd ref = dense * Y;
      EXPECT_LT((S.apply(Y) - ref).norm(), 10 * tol * ref.norm());
      EXPECT_GT(S.last_iterations(), 0);
      const SteklovInfo& info = S.info();
      EXPECT_EQ(S.nbytes(),
                info.nbytes_v + info.nbytes_v0 + info.nbytes_k + info.nbytes_w + info.nbytes_preconditioner);
    }
  }
}

TEST(SteklovPoincareOperator, LooserSolverTolGivesACheaperProductWithinThatTolerance) {
  const Points X = test::square(160);
  const double tol = 1e-10;
  const SteklovPoincareOperator S(X, Space::P1, SteklovOptions{{32, 1.0, tol}, 1e-4, 1e-3 * tol, 1000});
  const Eigen::MatrixXd Y = Eigen::MatrixXd::Random(X.rows(), 2);
  const Eigen::MatrixXd exact = S.apply(Y);
  const int own = S.last_iterations();
  for (double loose : {1e-4, 1e-7}) {
    const Eigen::MatrixXd product = S.apply(Y, loose);
    EXPECT_LT(S.last_iterations(), own);
    // the V solve's relative residual times the conditioning of the preconditioned V (tens)
    EXPECT_LT((product - exact).norm(), 100 * loose * exact.norm());
    EXPECT_GT((product - exact).norm(), 0.0);
  }
  // tighter than the options' own: the options' solve (the products' threads may sum in
  // another order: equal to round-off)
  EXPECT_LT((S.apply(Y, 1e-20) - exact).norm(), 1e-13 * exact.norm());
  EXPECT_EQ(S.last_iterations(), own);
}
