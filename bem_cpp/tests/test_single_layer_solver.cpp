#include <gtest/gtest.h>

#include "bem/calderon_preconditioner.hpp"
#include "bem/operator_entries.hpp"
#include "bem/single_layer_solver.hpp"
#include "test_helpers.hpp"

using namespace bem;

namespace {
std::shared_ptr<const HMatrix> single_layer_h(const Polygon& poly, Space s) {
  auto tree = std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, s, 32));
  const OperatorEntries e(poly, Kernel::SingleLayer, s, s);
  return std::make_shared<const HMatrix>(tree, tree, e, HMatrixOptions{32, 1.0, 1e-10});
}
}  // namespace

TEST(SingleLayerSolver, CalderonKeepsTheIterationsBounded) {
  for (Space s : {Space::P0, Space::P1}) {
    std::vector<int> counts;
    for (const Points& nodes : {test::circle(500), test::circle(2000), test::square(500)}) {
      const Polygon poly(nodes);
      const Index n = poly.size();
      auto V = single_layer_h(poly, s);
      auto V0 = s == Space::P0 ? V : single_layer_h(poly, Space::P0);
      const CalderonPreconditioner C(poly, s, V0, HMatrixOptions{32, 1.0, 1e-4});
      const SingleLayerSolver solver(V, [&C](const Eigen::MatrixXd& R) { return C.apply(R); });
      const Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, 2);
      Eigen::MatrixXd X;
      counts.push_back(solver.solve(B, X, 1e-10, 200));
      EXPECT_LT((V->apply(X) - B).norm(), 1e-9 * B.norm());
    }
    for (int c : counts) EXPECT_LT(c, 40);
    EXPECT_LE(counts[1], counts[0] + 3);  // n = 2000 against n = 500
  }
}
