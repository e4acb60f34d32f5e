#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "bem/far_field.hpp"
#include "test_helpers.hpp"

using namespace bem;

namespace {
double max_abs(const double (&a)[2][2]) {
  double m = 0;
  for (auto& row : a)
    for (double x : row) m = std::max(m, std::abs(x));
  return m;
}
}  // namespace

TEST(FarField, BatchEqualsScalarRule) {
  const Polygon circle(test::circle(64));
  const PanelArrays arrays(circle);
  std::vector<double> store(8 * 64), kstore(4 * 64);
  PairBlockColumns col, kcol;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      col.v[a][b] = store.data() + (2 * a + b) * 64;
      col.kij[a][b] = store.data() + (4 + 2 * a + b) * 64;
      kcol.v[a][b] = nullptr;
      kcol.kij[a][b] = kstore.data() + (2 * a + b) * 64;
    }
  const Index contiguous[4] = {20, 21, 22, 23}, scattered[5] = {20, 21, 22, 40, 7};
  for (const Index* js : {contiguous, scattered}) {
    const int m = js == contiguous ? 4 : 5;
    for (int p = 1; p <= kMaxFarPoints; ++p) {
      far_blocks_batch(circle.panel(0), arrays, js, m, p, true, true, col);
      far_blocks_batch(circle.panel(0), arrays, js, m, p, false, true, kcol);  // K only
      for (int k = 0; k < m; ++k) {
        const Index j = js[k];
        PairBlocks B;
        far_blocks(circle.panel(0), circle.panel(j), p, true, B);
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b) {
            EXPECT_NEAR(col.v[a][b][j], B.v[a][b], 1e-15 * max_abs(B.v));
            EXPECT_NEAR(col.kij[a][b][j], B.kij[a][b], 1e-15 * max_abs(B.kij));
            EXPECT_EQ(kcol.kij[a][b][j], col.kij[a][b][j]);
          }
      }
    }
  }
}

TEST(FarField, VectorisedPointCountEqualsScalar) {
  const Polygon square(test::square(40));
  const PanelArrays arrays(square);
  std::vector<int> points(static_cast<std::size_t>(square.size()));
  for (Index i : {0, 17, 159}) {
    far_field_points(square.panel(i), arrays, 0, square.size(), points.data());
    for (Index j = 0; j < square.size(); ++j)
      EXPECT_EQ(points[static_cast<std::size_t>(j)], far_field_points(square.panel(i), square.panel(j)));
  }
}

TEST(FarField, PointBatchEqualsScalarPointPanelMoments) {
  const Polygon circle(test::circle(200));
  const PanelArrays arrays(circle);
  const Index n = circle.size();
  std::vector<double> l0(n), l1(n), d0(n), d1(n);
  for (Index j = 0; j < n; ++j) {  // arbitrary weights
    l0[j] = std::cos(0.1 * j);
    l1[j] = std::sin(0.3 * j);
    d0[j] = 1.0 + 0.01 * j;
    d1[j] = -0.5;
  }
  std::vector<int> rule(static_cast<std::size_t>(n));
  for (Vec2 z : {Vec2{0.41, 0.0}, Vec2{0.0, -0.5}, Vec2{3.0, 2.0}}) {
    point_far_field_points(z, arrays, rule.data());
    double batch = 0, scalar = 0, scale = 0;
    for (int p = 1; p <= kMaxFarPoints; ++p) {
      std::vector<Index> js;
      for (Index j = 0; j < n; ++j)
        if (rule[j] == p) js.push_back(j);
      for (std::size_t k0 = 0; k0 < js.size(); k0 += kFarBatch) {
        const int m = static_cast<int>(std::min<std::size_t>(kFarBatch, js.size() - k0));
        batch += far_point_sum(z, arrays, js.data() + k0, m, p, l0.data(), l1.data(), d0.data(), d1.data());
      }
      for (Index j : js) {
        const Panel& q = circle.panel(j);
        // the scalar routine picks the same rule
        EXPECT_EQ(gauss_points_for(norm(z - q.m) - 0.5 * q.h, q.h, kMaxFarPoints), p);
        const PointPanelMoments s = point_panel_moments(z, q);
        const double term = l0[j] * s.log[0] + l1[j] * s.log[1] + d0[j] * s.dl[0] + d1[j] * s.dl[1];
        scalar += term;
        scale += std::abs(term);
      }
    }
    EXPECT_NEAR(batch, scalar, 1e-14 * scale);
  }
}
