#pragma once
// Closed triangulated surface Gamma in R^3 (docs/method.md section 11): flat triangles with
// normals out of Omega, validation of the input arrays, and the vertex-sharing relation
// of triangle pairs that selects the singular quadrature (surface_quadrature.hpp).
#include <Eigen/Dense>
#include <array>
#include <functional>
#include <vector>

#include "bem/geometry.hpp"
#include "bem/vec3.hpp"

namespace bem {

/// (n, 3) vertices and (m, 3) triangles, row-major (numpy arrays map without copies).
using Vertices = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Triangles = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// Flat triangle with vertices p[0], p[1], p[2] (counter-clockwise seen from outside),
/// unit normal n = (p1 - p0) x (p2 - p0) / |.|, area and centroid c; `radius` is the
/// largest distance from c to a vertex.
struct Triangle {
  std::array<Index, 3> v;
  std::array<Vec3, 3> p;
  Vec3 n, c;
  double area, radius;
};

/// A validated closed surface. The constructor throws std::invalid_argument (ValueError
/// in Python) with a one-line message naming what and where if: the shapes are wrong, a
/// coordinate is not finite, a vertex index is out of range or unused, two vertices
/// coincide, a triangle has (numerically) zero area, an edge belongs to one triangle only
/// (open surface) or to more than two (non-manifold), two triangles traverse their common
/// edge in the same direction (inconsistent orientation), or the enclosed volume is
/// negative (normals point into Omega).
class Surface {
 public:
  Surface(const Eigen::Ref<const Vertices>& vertices, const Eigen::Ref<const Triangles>& triangles);

  Index vertices() const { return n_; }
  Index size() const { return static_cast<Index>(triangles_.size()); }
  const Triangle& triangle(Index t) const { return triangles_[static_cast<std::size_t>(t)]; }
  const std::vector<Triangle>& triangles() const { return triangles_; }
  Vec3 vertex(Index i) const { return points_[static_cast<std::size_t>(i)]; }
  /// Triangles containing vertex i.
  const std::vector<Index>& star(Index i) const { return stars_[static_cast<std::size_t>(i)]; }
  /// Largest triangle diameter.
  double mesh_size() const { return h_; }
  /// Diagonal of the bounding box.
  double bounding_diameter() const { return diameter_; }
  /// Volume enclosed (positive for outward normals).
  double volume() const { return volume_; }

 private:
  Index n_ = 0;
  std::vector<Vec3> points_;
  std::vector<Triangle> triangles_;
  std::vector<std::vector<Index>> stars_;
  double h_ = 0, diameter_ = 0, volume_ = 0;
};

/// How two triangles touch: the number of shared vertices (3: identical, 2: edge, 1: vertex,
/// 0: disjoint), and the local indices of the shared vertices in each, in matching order.
struct Adjacency {
  int shared = 0;
  std::array<int, 3> a{}, b{};
};
Adjacency adjacency(const Triangle& s, const Triangle& t);

/// The plane of each triangle as an id: equal ids for triangles whose normals and offsets
/// n . c (over the largest distance of a centroid from the origin) agree to 1e-8 - the
/// faces of a polyhedron, whose triangles' normals differ by round-off. (The double layer's
/// kernel n_y . (x - y) vanishes between the points of one plane, surface_entries.hpp.)
std::vector<int> triangle_planes(const Surface& surface);

/// Calls f(t) for every triangle t, OpenMP-parallel over one colour of a greedy vertex
/// colouring at a time: no two concurrent calls get triangles that share a vertex, so each
/// may write the rows of its own vertices (the assemblies over triangle pairs).
void for_each_triangle_by_colour(const Surface& surface, const std::function<void(Index)>& f);

}  // namespace bem
