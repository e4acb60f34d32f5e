#pragma once
// Cluster tree on the degrees of freedom of a boundary element space (docs/design/hmatrix.md):
// geometric bisection of the bounding box of the dof points (nodes for P1, panel
// midpoints for P0) along its longest side, until a cluster holds at most `leaf_size`
// dofs. The same tree serves 2D and 3D geometry: the points are (n, d) with d = 2 or 3,
// and boxes live in R^3 (a 2D box is flat, z0 = z1 = 0, so its diameter and distances
// are those of the plane). Each cluster is a contiguous range of the permuted order and carries the
// bounding box of the supports of its basis functions (the panels the dofs live on), so
// that the admissibility condition below is a statement about the integration domains.
#include <vector>

#include "bem/geometry.hpp"
#include "bem/operators.hpp"
#include "bem/vec3.hpp"

namespace bem {

/// Axis-parallel box [x0, x1] x [y0, y1] x [z0, z1] (2D: z0 = z1 = 0).
struct Box {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, z0 = 1e300, z1 = -1e300;
  void add(Vec2 p);  ///< the point (p.x, p.y, 0)
  void add(Vec3 p);
  void add(const Box& b);
  double diameter() const;
  /// Euclidean distance between the boxes (0 if they overlap or touch).
  double distance(const Box& b) const;
};

/// Standard admissibility: min(diam t, diam s) <= eta dist(t, s), dist > 0.
bool admissible(const Box& t, const Box& s, double eta);

struct Cluster {
  Index begin = 0, end = 0;  ///< range [begin, end) of the permuted order
  Box box;                   ///< bounding box of the supports of the cluster's dofs
  int children[2] = {-1, -1};
  bool leaf() const { return children[0] < 0; }
  Index size() const { return end - begin; }
};

class ClusterTree {
 public:
  /// points: (n, d) representative point of each dof, d = 2 or 3; supports[i]: box of its
  /// support.
  ClusterTree(const Eigen::Ref<const Matrix>& points, const std::vector<Box>& supports, Index leaf_size);
  /// The tree of the P1 (nodes) or P0 (panels) space of a polygon.
  static ClusterTree for_space(const Polygon& polygon, Space space, Index leaf_size);
  /// The same tree on d dofs per point (vector fields, node-major: dof d i + c is the
  /// component c of point i): the cluster of the positions [b, e) becomes [d b, d e) with
  /// the same box and children, and position d k + c holds dof d permutation()[k] + c, so
  /// that the d dofs of a point stay together (the block tree, admissibility and
  /// partitions of the points carry over). d >= 1.
  ClusterTree expanded(int d) const;

  Index size() const { return static_cast<Index>(permutation_.size()); }
  const Cluster& cluster(int c) const { return clusters_[static_cast<std::size_t>(c)]; }
  const std::vector<Cluster>& clusters() const { return clusters_; }
  /// permutation()[k]: the dof at position k of the permuted order (root is cluster 0).
  const std::vector<Index>& permutation() const { return permutation_; }
  /// Indices of the leaf clusters, in permuted order (they partition [0, n)).
  std::vector<int> leaves() const;
  /// Bounds b_0 = 0 <= b_1 <= ... <= b_parts = n of `parts` contiguous ranges of the
  /// permuted order (the rows of the ranks of a distributed H-matrix): b_r is the leaf
  /// boundary nearest to r n / parts (within half a leaf of it), so that no leaf is split.
  std::vector<Index> partition(int parts) const;
  /// The same with the cost cost[k] of position k of the permuted order: b_r is the leaf
  /// boundary whose cumulative cost is nearest to r / parts of the total.
  std::vector<Index> partition(int parts, const std::vector<double>& cost) const;

 private:
  ClusterTree() = default;
  int build(Index begin, Index end, const Eigen::Ref<const Matrix>& points, const std::vector<Box>& supports,
            Index leaf_size);
  std::vector<Cluster> clusters_;
  std::vector<Index> permutation_;
};

/// Cluster tree on target points (m, d), d = 2 or 3, each point its own support (the rows
/// of a potential, potential_operator.hpp and surface_potential_operator.hpp).
ClusterTree point_cluster_tree(const Eigen::Ref<const Matrix>& points, Index leaf_size);

}  // namespace bem
