#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bem/surface.hpp"
#include "test_surfaces.hpp"

using namespace bem;

namespace {

/// The message of the std::invalid_argument the Surface constructor throws ("" if none).
std::string refusal(const test::Mesh& m) {
  try {
    const Surface s(m.vertices, m.triangles);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

TEST(Surface, AcceptsClosedOutwardSurfaces) {
  for (const test::Mesh& m : {test::icosphere(2), test::cube(2, 0.5), test::fichera(2, 0.5)}) {
    const Surface s(m.vertices, m.triangles);
    EXPECT_GT(s.volume(), 0.0);
    EXPECT_EQ(s.size(), m.triangles.rows());
  }
  const test::Mesh c = test::cube(4, 0.25);
  EXPECT_NEAR(Surface(c.vertices, c.triangles).volume(), 1.0, 1e-14);
  const test::Mesh f = test::fichera(4, 0.25);
  EXPECT_NEAR(Surface(f.vertices, f.triangles).volume(), 7.0 / 8.0, 1e-14);
}

TEST(Surface, RefusesEachDefectNamingWhatAndWhere) {
  const test::Mesh good = test::icosphere(1);
  test::Mesh m = good;
  m.vertices(3, 1) = std::nan("");
  EXPECT_TRUE(contains(refusal(m), "non-finite coordinates at vertex 3"));

  m = good;
  m.triangles.row(5) = m.triangles.row(5).reverse().eval();
  EXPECT_TRUE(contains(refusal(m), "inconsistent orientation")) << refusal(m);

  m = good;
  for (Index t = 0; t < m.triangles.rows(); ++t) m.triangles.row(t) = m.triangles.row(t).reverse().eval();
  EXPECT_TRUE(contains(refusal(m), "inward orientation"));

  m = good;  // drop a triangle: three boundary edges
  m.triangles = good.triangles.topRows(good.triangles.rows() - 1);
  EXPECT_TRUE(contains(refusal(m), "open surface: boundary edge"));

  m = good;  // a copy of vertex 0 used by one triangle
  m.vertices.conservativeResize(good.vertices.rows() + 1, 3);
  m.vertices.row(good.vertices.rows()) = good.vertices.row(0);
  EXPECT_TRUE(contains(refusal(m), "duplicate vertices 0 and " + std::to_string(good.vertices.rows())));

  m = good;  // collapse a triangle onto an edge
  m.triangles(7, 2) = m.triangles(7, 0);
  EXPECT_TRUE(contains(refusal(m), "zero-area triangle 7"));

  m = good;  // a fin: a third triangle on the edge of triangle 0
  m.vertices.conservativeResize(good.vertices.rows() + 1, 3);
  m.vertices.row(good.vertices.rows()) << 3.0, 3.0, 3.0;
  m.triangles.conservativeResize(good.triangles.rows() + 1, 3);
  m.triangles.row(good.triangles.rows()) << good.triangles(0, 0), good.triangles(0, 1), good.vertices.rows();
  EXPECT_TRUE(contains(refusal(m), "non-manifold edge")) << refusal(m);
}

TEST(Surface, AdjacencyListsTheSharedVerticesInMatchingOrder) {
  const test::Mesh m = test::icosphere(1);
  const Surface s(m.vertices, m.triangles);
  for (Index a = 0; a < s.size(); ++a)
    for (Index b = 0; b < s.size(); ++b) {
      const Adjacency adj = adjacency(s.triangle(a), s.triangle(b));
      if (a == b) EXPECT_EQ(adj.shared, 3);
      for (int k = 0; k < adj.shared; ++k)
        EXPECT_EQ(s.triangle(a).v[static_cast<std::size_t>(adj.a[k])],
                  s.triangle(b).v[static_cast<std::size_t>(adj.b[k])]);
    }
}

TEST(Surface, TrianglePlanesAreTheFacesOfAPolyhedron) {
  // the cube: six planes, a triangle's id that of its face (its normal and offset); the
  // sphere's triangles lie in as many planes as there are triangles; Fichera's corner (the
  // cube without an octant): 9 planes, of which the three re-entrant faces' planes through
  // the origin (offset 0) are told apart by their normals
  const test::Mesh cube = test::cube(4, 0.25), sphere = test::icosphere(2), fichera = test::fichera(4, 0.25);
  for (const auto& [mesh, count] :
       {std::make_pair(&cube, 6), std::make_pair(&sphere, 320), std::make_pair(&fichera, 9)}) {
    const Surface s(mesh->vertices, mesh->triangles);
    const std::vector<int> planes = triangle_planes(s);
    ASSERT_EQ(static_cast<Index>(planes.size()), s.size());
    EXPECT_EQ(*std::max_element(planes.begin(), planes.end()) + 1, count);
    for (Index a = 0; a < s.size(); ++a)
      for (Index b = 0; b < s.size(); ++b) {
        const Triangle &A = s.triangle(a), &B = s.triangle(b);
        const bool same = norm(A.n - B.n) < 1e-12 && std::abs(dot(A.n, A.c) - dot(B.n, B.c)) < 1e-12;
        EXPECT_EQ(planes[static_cast<std::size_t>(a)] == planes[static_cast<std::size_t>(b)], same) << a << " " << b;
      }
  }
}
