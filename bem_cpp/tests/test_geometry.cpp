#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "bem/geometry.hpp"
#include "test_helpers.hpp"

using namespace bem;

namespace {
Points make(std::initializer_list<std::pair<double, double>> pts) {
  Points X(static_cast<Index>(pts.size()), 2);
  Index k = 0;
  for (auto [x, y] : pts) {
    X(k, 0) = x;
    X(k, 1) = y;
    ++k;
  }
  return X;
}

std::string error_of(const Points& X) {
  try {
    Polygon p(X);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Geometry, PanelsTangentsOutwardNormals) {
  const Polygon square(test::square(1));
  ASSERT_EQ(square.size(), 4);
  // Bottom side runs left to right: outward normal points down.
  const Panel& p = square.panel(0);
  EXPECT_DOUBLE_EQ(p.h, 0.6);
  EXPECT_DOUBLE_EQ(p.t.x, 1.0);
  EXPECT_DOUBLE_EQ(p.n.x, 0.0);
  EXPECT_DOUBLE_EQ(p.n.y, -1.0);
  EXPECT_DOUBLE_EQ(square.signed_area(), 0.36);
  // Every normal points away from the centre.
  for (const Panel& q : square.panels()) EXPECT_GT(dot(q.m, q.n), 0.0);
}

TEST(Geometry, RejectsBadPolygons) {
  EXPECT_NE(error_of(make({{0, 0}, {1, 0}})).find("at least 3 nodes"), std::string::npos);
  EXPECT_NE(error_of(make({{0, 0}, {0.5, NAN}, {0, 0.5}})).find("node 1 has a non-finite"), std::string::npos);
  EXPECT_NE(error_of(make({{0, 0}, {0.5, 0}, {0.5, 0}, {0, 0.5}})).find("nodes 1 and 2 coincide"), std::string::npos);
  EXPECT_NE(error_of(make({{0, 0}, {0.5, 0}, {0, 0.5}, {0, 0}})).find("repeats the first node"), std::string::npos);
  EXPECT_NE(error_of(make({{0, 0}, {0, 0.5}, {0.5, 0}})).find("clockwise"), std::string::npos);
  EXPECT_NE(error_of(make({{0, 0}, {0.5, 0.5}, {0.5, 0}, {0, 0.5}})).find("panels 0 and 2 intersect"),
            std::string::npos);
  EXPECT_NE(error_of(make({{0, 0}, {0.5, 0}, {0.25, 0}, {0.25, 0.3}})).find("fold back"), std::string::npos);
  // A node touching a non-adjacent panel.
  EXPECT_NE(error_of(make({{0, 0}, {0.6, 0}, {0.6, 0.4}, {0.3, 0}, {0, 0.4}})).find("self-intersecting"),
            std::string::npos);
  EXPECT_EQ(error_of(test::circle(7)), "");
}

TEST(Geometry, SweepFindsOneCrossingAmongManyPanels) {
  Points X = test::circle(200000);
  EXPECT_EQ(error_of(X), "");
  X(100000, 0) = X(0, 0) + 0.01;  // jumps across the disc, just past node 0
  X(100000, 1) = X(0, 1);
  EXPECT_NE(error_of(X).find("self-intersecting"), std::string::npos);
}

TEST(Geometry, LocatePoints) {
  const Polygon square(test::square(3));
  EXPECT_EQ(locate(square, {0.0, 0.0}, 1e-12), Location::Interior);
  EXPECT_EQ(locate(square, {0.29, -0.29}, 1e-12), Location::Interior);
  EXPECT_EQ(locate(square, {0.31, 0.0}, 1e-12), Location::Exterior);
  EXPECT_EQ(locate(square, {0.3, 0.1}, 1e-12), Location::OnBoundary);
  EXPECT_EQ(locate(square, {-0.3, -0.3}, 1e-12), Location::OnBoundary);
  EXPECT_EQ(locate(square, {5.0, 0.0}, 1e-12), Location::Exterior);
}

TEST(Geometry, Distances) {
  const Panel p = make_panel({0, 0}, {1, 0});
  EXPECT_DOUBLE_EQ(distance(p, Vec2{0.5, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(distance(p, Vec2{4.0, 4.0}), 5.0);
  EXPECT_DOUBLE_EQ(distance(p, make_panel({2, 1}, {2, 3})), std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(distance(p, make_panel({0.5, -1}, {0.5, 1})), 0.0);
}
