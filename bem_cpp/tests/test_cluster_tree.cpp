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
