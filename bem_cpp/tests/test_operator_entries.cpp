#include <gtest/gtest.h>

#include <numeric>
#include <vector>

#include "bem/operator_entries.hpp"
#include "test_helpers.hpp"

using namespace bem;

TEST(OperatorEntries, BlocksRowsAndColumnsMatchTheDenseMatrices) {
  const Polygon poly(test::square(12));
  const Index n = poly.size();
  std::vector<Index> all(static_cast<std::size_t>(n));
  std::iota(all.begin(), all.end(), Index{0});
  for (Space s : {Space::P0, Space::P1}) {
    const Matrix Vd = single_layer(poly, s), Kd = double_layer(poly, s);
    const OperatorEntries V(poly, Kernel::SingleLayer, s, s), K(poly, Kernel::DoubleLayer, s, Space::P1);
    Eigen::MatrixXd Vh(n, n), Kh(n, n), Kc(n, n);
    V.block(all.data(), n, all.data(), n, Vh.data(), n);
    K.block(all.data(), n, all.data(), n, Kh.data(), n);
    for (Index j = 0; j < n; ++j) K.block(all.data(), n, &all[static_cast<std::size_t>(j)], 1, Kc.col(j).data(), n);
    const double v = Vd.cwiseAbs().maxCoeff(), k = Kd.cwiseAbs().maxCoeff();
    EXPECT_LT((Vh - Vd).cwiseAbs().maxCoeff(), 1e-13 * v);
    EXPECT_LT((Kh - Kd).cwiseAbs().maxCoeff(), 1e-13 * k);
    EXPECT_LT((Kc - Kd).cwiseAbs().maxCoeff(), 1e-13 * k);
    // An unordered index set: rows 7, 2, 40, columns 30, 5.
    const Index I[3] = {7, 2, 40}, J[2] = {30, 5};
    double out[6];
    V.block(I, 3, J, 2, out, 3);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 2; ++c) EXPECT_NEAR(out[r + 3 * c], Vd(I[r], J[c]), 1e-13 * v);
  }
  EXPECT_THROW(OperatorEntries(poly, Kernel::SingleLayer, Space::P0, Space::P1), std::invalid_argument);
}
