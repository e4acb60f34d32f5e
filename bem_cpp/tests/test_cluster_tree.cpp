#include <gtest/gtest.h>

#include <algorithm>

#include "bem/cluster_tree.hpp"
#include "test_helpers.hpp"

using namespace bem;

TEST(ClusterTree, PartitionsTheDofsIntoSmallLeaves) {
  const Polygon poly(test::square(50));
  for (Space space : {Space::P0, Space::P1}) {
    const ClusterTree tree = ClusterTree::for_space(poly, space, 16);
    std::vector<Index> perm = tree.permutation();
    std::sort(perm.begin(), perm.end());
    for (Index k = 0; k < tree.size(); ++k) EXPECT_EQ(perm[static_cast<std::size_t>(k)], k);
    Index covered = 0;
    for (int l : tree.leaves()) {
      const Cluster& c = tree.cluster(l);
      EXPECT_EQ(c.begin, covered);
      EXPECT_LE(c.size(), 16);
      EXPECT_GE(c.size(), 1);
      covered = c.end;
    }
    EXPECT_EQ(covered, tree.size());
    for (const Cluster& c : tree.clusters())
      if (!c.leaf()) {
        const Cluster& a = tree.cluster(c.children[0]);
        const Cluster& b = tree.cluster(c.children[1]);
        EXPECT_EQ(a.begin, c.begin);
        EXPECT_EQ(a.end, b.begin);
        EXPECT_EQ(b.end, c.end);
      }
  }
}

TEST(ClusterTree, Admissibility) {
  Box a, b, c;
  a.add(Vec2{0, 0});
  a.add(Vec2{1, 1});
  b.add(Vec2{3, 0});
  b.add(Vec2{4, 1});
  c.add(Vec2{1, 0});
  c.add(Vec2{2, 1});
  EXPECT_DOUBLE_EQ(a.distance(b), 2.0);
  EXPECT_DOUBLE_EQ(a.distance(c), 0.0);
  EXPECT_TRUE(admissible(a, b, 1.0));     // sqrt 2 <= 2
  EXPECT_FALSE(admissible(a, b, 0.5));    // sqrt 2 > 1
  EXPECT_FALSE(admissible(a, c, 100.0));  // touching
}

TEST(ClusterTree, SplitsThreeDimensionalPointsAlongTheLongestSide) {
  // points on a segment along z: a 2D tree would see them all at one (x, y)
  const Index n = 64;
  Matrix X(n, 3);
  std::vector<Box> supports(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    X.row(i) << 0.01 * static_cast<double>(i % 2), 0.0, static_cast<double>(i);
    supports[static_cast<std::size_t>(i)].add(Vec3{X(i, 0), X(i, 1), X(i, 2)});
  }
  const ClusterTree tree(X, supports, 8);
  const Cluster& root = tree.cluster(0);
  EXPECT_DOUBLE_EQ(root.box.diameter(), std::hypot(0.01, 63.0));
  const Cluster& low = tree.cluster(root.children[0]);
  const Cluster& high = tree.cluster(root.children[1]);
  EXPECT_EQ(low.size(), 32);
  EXPECT_LT(low.box.z1, high.box.z0);  // cut across z
  EXPECT_DOUBLE_EQ(low.box.distance(high.box), high.box.z0 - low.box.z1);
  for (int l : tree.leaves()) EXPECT_LE(tree.cluster(l).size(), 8);
}

TEST(ClusterTree, PlanarBoxesAreFlat) {
  Box a;
  a.add(Vec2{0, 0});
  a.add(Vec2{3, 4});
  EXPECT_EQ(a.z0, 0.0);
  EXPECT_EQ(a.z1, 0.0);
  EXPECT_EQ(a.diameter(), 5.0);
}
