#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "bem/far_points.hpp"
#include "bem/hmatrix.hpp"
#include "bem/surface_entries.hpp"
#include "test_surfaces.hpp"

using namespace bem;

namespace {

std::vector<Index> every_other(Index n, Index start) {
  std::vector<Index> out;
  for (Index i = start; i < n; i += 2) out.push_back(i);
  return out;
}

/// f(surface, its dense P1 operators) on a sphere of radius 0.6 (the icosahedron refined
/// `level` times), the unit cube and Fichera's corner of n squares per side of a face.
template <typename F>
void on_three_surfaces(int level, int n, F&& f) {
  for (const test::Mesh& mesh : {test::icosphere(level, 0.6), test::cube(n, 1.0 / n), test::fichera(n, 1.0 / n)}) {
    const Surface s(mesh.vertices, mesh.triangles);
    f(s, assemble(s, {Space::P1, Space::P1, true}));
  }
}

}  // namespace

TEST(SurfaceEntries, RowsColumnsAndBlocksAreThoseOfTheDenseMatrices) {
  // with and without the near field (the near pairs integrated once, surface_near_field.hpp);
  // on the cube many pairs sit exactly at the far separation: far(a, b) must equal far(b, a)
  const test::Mesh meshes[2] = {test::icosphere(2, 0.6), test::cube(6, 1.0)};
  for (const test::Mesh& mesh : meshes) {
    const Surface s(mesh.vertices, mesh.triangles);
    const auto near = std::make_shared<const SurfaceNearField>(s);
    for (bool with_near : {false, true})
      for (Space rows : {Space::P0, Space::P1})
        for (SurfaceKernel kernel :
             {SurfaceKernel::SingleLayer, SurfaceKernel::DoubleLayer, SurfaceKernel::Hypersingular}) {
          SurfaceRequest request;
          const Space cols = kernel == SurfaceKernel::SingleLayer ? rows : Space::P1;
          if (with_near && rows != cols) continue;  // the near field holds P0 x P0 and P1 x P1
          if (kernel == SurfaceKernel::Hypersingular && rows != Space::P1) continue;
          if (kernel == SurfaceKernel::SingleLayer) request.single_layer = rows;
          if (kernel == SurfaceKernel::DoubleLayer) request.double_layer = rows;
          request.hypersingular = kernel == SurfaceKernel::Hypersingular;
          const SurfaceMatrices dense = assemble(s, request);
          const Matrix& A = kernel == SurfaceKernel::SingleLayer   ? dense.single_layer
                            : kernel == SurfaceKernel::DoubleLayer ? dense.double_layer
                                                                   : dense.hypersingular;
          const std::vector<Index> I = every_other(A.rows(), 0), J = every_other(A.cols(), 0);
          const Index m = static_cast<Index>(I.size()), k = static_cast<Index>(J.size());
          const SurfaceEntries entries(s, kernel, rows, cols, with_near ? near : nullptr);
          const auto block = entries.block(I.data(), m, J.data(), k);
          SCOPED_TRACE(with_near ? "near" : "plain");
          SCOPED_TRACE(rows == Space::P0 ? "P0" : "P1");
          SCOPED_TRACE(kernel == SurfaceKernel::SingleLayer ? "SL" : kernel == SurfaceKernel::DoubleLayer ? "DL" : "W");
          Eigen::MatrixXd all(m, k);
          block->all(all.data());
          Eigen::VectorXd row(k), column(m);
          const double scale = A.cwiseAbs().maxCoeff();
          for (Index i = 0; i < m; ++i) {
            block->row(i, row.data());
            for (Index j = 0; j < k; ++j) {
              EXPECT_NEAR(all(i, j), A(I[i], J[j]), 1e-14 * scale) << I[i] << " " << J[j];
              EXPECT_NEAR(row(j), A(I[i], J[j]), 1e-14 * scale);
            }
          }
          for (Index j = 0; j < k; ++j) {
            block->column(j, column.data());
            for (Index i = 0; i < m; ++i) EXPECT_NEAR(column(i), A(I[i], J[j]), 1e-14 * scale);
          }
        }
  }
}

TEST(SurfaceEntries, HMatrixProductsAgreeWithTheDenseOnes) {
  // the 2D H-matrix code on 3D trees (a sphere, a cube, Fichera's corner): on surfaces this
  // small the admissible blocks stay dense (a low-rank block pays from a rank of half its
  // size); the compressed blocks are checked on a larger sphere by tests/test_bem_surface.py
  on_three_surfaces(2, 6, [](const Surface& s, const SurfaceMatrices& dense) {
    auto tree = std::make_shared<const ClusterTree>(surface_cluster_tree(s, Space::P1, 8));
    HMatrixOptions options{8, 1.5, 1e-10};
    const HMatrix K(tree, tree, SurfaceEntries(s, SurfaceKernel::DoubleLayer, Space::P1, Space::P1), options);
    options.symmetric = true;
    const HMatrix V(tree, tree, SurfaceEntries(s, SurfaceKernel::SingleLayer, Space::P1, Space::P1), options);
    const HMatrix W(tree, tree, SurfaceEntries(s, SurfaceKernel::Hypersingular, Space::P1, Space::P1), options);
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(s.vertices(), 2);
    for (const auto& [H, A] : {std::make_pair(&V, &dense.single_layer), std::make_pair(&K, &dense.double_layer),
                               std::make_pair(&W, &dense.hypersingular)}) {
      const Eigen::MatrixXd exact = *A * X;
      EXPECT_LE((H->apply(X) - exact).norm(), 1e-8 * exact.norm());
    }
  });
}

TEST(SurfaceEntries, CompressedOperatorsOfTheSteklovOperatorAgreeWithTheDenseOnes) {
  // the set-up of SurfaceSteklovOperator (near field, min_distance, V and W as a family, K)
  // on surfaces large enough for low-rank blocks: flat faces (the double-layer kernel
  // vanishes between coplanar points) and a re-entrant corner as well as the sphere (ACA
  // on the double layer's own kernel failed from 16 squares per side: tests/test_bem_surface.py)
  on_three_surfaces(3, 12, [](const Surface& s, const SurfaceMatrices& dense) {
    auto tree = std::make_shared<const ClusterTree>(surface_cluster_tree(s, Space::P1, 16));
    const auto near = std::make_shared<const SurfaceNearField>(s);
    HMatrixOptions options{16, 4.0, 1e-8};
    options.min_distance = far_distance(s);
    const HMatrix K(tree, tree, SurfaceEntries(s, SurfaceKernel::DoubleLayer, Space::P1, Space::P1, near), options);
    options.symmetric = true;
    const auto VW = HMatrix::family(
        tree, tree, SurfaceEntries(s, SurfaceKernel::SingleLayer, Space::P1, Space::P1, near, true), 2, options);
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(s.vertices(), 2);
    const char* names[3] = {"V", "K", "W"};
    const HMatrix* H[3] = {VW[0].get(), &K, VW[1].get()};
    const Matrix* A[3] = {&dense.single_layer, &dense.double_layer, &dense.hypersingular};
    for (int c = 0; c < 3; ++c) {
      SCOPED_TRACE(names[c]);
      if (c != 2) EXPECT_GT(H[c]->max_rank(), 0);  // (W: on the sphere its recompressed blocks stay dense)
      const Eigen::MatrixXd exact = *A[c] * X;
      EXPECT_LE((H[c]->apply(X) - exact).norm(), 1e-7 * exact.norm());
    }
  });
}

TEST(FarPoints, SumOverPartsAddsEachPartsConsecutiveRows) {
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(12, 5);  // 4 parts of 3 points
  const Eigen::MatrixXd sums = sum_over_parts(A, 3);
  ASSERT_EQ(sums.rows(), 4);
  ASSERT_EQ(sums.cols(), 5);
  for (Index t = 0; t < 4; ++t)
    for (Index j = 0; j < 5; ++j) EXPECT_NEAR(sums(t, j), A.block(3 * t, j, 3, 1).sum(), 1e-15);
}

TEST(FarPoints, ValuesTransposeProductIsTheMapsProduct) {
  // Q^T A part by part without forming Q (built here entry by entry), P1 (three dofs on a triangle of the block, or
  // one or two where the block holds only some of its vertices) and P0; and a kernel column
  // over a range of the row points is that range of the whole column
  const test::Mesh mesh = test::icosphere(1, 0.7);
  const Surface s(mesh.vertices, mesh.triangles);
  const TriangleRule& rule = far_rule();
  for (Space space : {Space::P1, Space::P0}) {
    const std::vector<Index> dofs = every_other(space == Space::P1 ? s.vertices() : s.size(), 1);
    const Index k = static_cast<Index>(dofs.size());
    const std::vector<Part> p = parts(s, space, dofs.data(), k);
    const FarPoints points(s, p, k, false, rule);
    const Eigen::MatrixXd A = Eigen::MatrixXd::Random(points.size(), 4);
    Eigen::MatrixXd out = Eigen::MatrixXd::Ones(k, 4);
    add_values_transpose_product(p, rule, A, out);
    // the map Q (points x dofs) entry by entry: the dof's barycentric coordinate (P1) or 1
    // (P0) at the rule's points of each of its triangles
    Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(points.size(), k);
    for (std::size_t t = 0; t < p.size(); ++t)
      for (int q = 0; q < rule.size(); ++q) {
        const std::size_t i = static_cast<std::size_t>(q);
        const double value[4] = {1.0 - rule.s[i] - rule.t[i], rule.s[i], rule.t[i], 1.0};
        for (int a = 0; a < p[t].count; ++a)
          Q(static_cast<Index>(t) * rule.size() + q, p[t].position[a]) = value[p[t].basis[a]];
      }
    const Eigen::MatrixXd expected = Eigen::MatrixXd::Ones(k, 4) + Q.transpose() * A;
    EXPECT_LT((out - expected).norm(), 1e-14 * expected.norm());
    for (PointKernelKind kind : {PointKernelKind::SingleLayer, PointKernelKind::DoubleLayer}) {
      const PointKernel kernel{points, points, kind};
      Eigen::VectorXd whole(points.size()), range = Eigen::VectorXd::Zero(points.size());
      kernel.column(0, whole.data());
      kernel.column(0, 9, 30, range.data());
      EXPECT_EQ(range.segment(9, 21), whole.segment(9, 21));
      EXPECT_EQ(range.head(9).norm() + range.tail(points.size() - 30).norm(), 0.0);
    }
  }
}

TEST(SurfaceEntries, DoubleLayerBlocksOnFlatFacesAreThoseOfTheDenseMatrix) {
  // Blocks of K_h (near field apart) between vertex sets of the cube: a patch inside the
  // bottom face against the far end of its inside (one plane: zero), against vertices there
  // and on the side face beyond (a shared plane), against the top face (no shared plane):
  // the dense block by triangle pairs (coplanar pairs skipped) to round-off, the factors to
  // the tolerance
  const int N = 12;
  const test::Mesh mesh = test::cube(N, 1.0 / N);
  const Surface s(mesh.vertices, mesh.triangles);
  SurfaceRequest request;
  request.double_layer = Space::P1;
  const Matrix K = assemble(s, request).double_layer;
  const SurfaceEntries entries(s, SurfaceKernel::DoubleLayer, Space::P1, Space::P1,
                               std::make_shared<const SurfaceNearField>(s));
  auto select = [&](auto inside) {
    std::vector<Index> out;
    for (Index i = 0; i < s.vertices(); ++i)
      if (inside(s.vertex(i))) out.push_back(i);
    return out;
  };
  const double low = -0.5, eps = 1e-9;
  // (hats inside the face: vertices off its edges)
  auto inner = [&](Vec3 p) { return p.z < low + eps && std::abs(p.x) < 0.5 - eps && std::abs(p.y) < 0.5 - eps; };
  const std::vector<Index> I = select([&](Vec3 p) { return inner(p) && p.x < -0.1 && p.y < -0.1; });
  const std::vector<Index> sets[3] = {
      select([&](Vec3 p) { return inner(p) && p.x > 0.3 && p.y > -0.2; }),
      select([&](Vec3 p) { return (p.z < low + eps && p.x > 0.3 && p.y > 0.3) || (p.x > 0.5 - eps && p.y > 0.3); }),
      select([&](Vec3 p) { return p.z > 0.5 - eps && p.x > 0.0; })};
  const Index m = static_cast<Index>(I.size());
  for (int c = 0; c < 3; ++c) {
    SCOPED_TRACE(c);
    const std::vector<Index>& J = sets[c];
    const Index k = static_cast<Index>(J.size());
    ASSERT_GT(m, 10);
    ASSERT_GT(k, 10);
    Eigen::MatrixXd exact(m, k);
    for (Index i = 0; i < m; ++i)
      for (Index j = 0; j < k; ++j) exact(i, j) = K(I[i], J[j]);
    const auto block = entries.block(I.data(), m, J.data(), k);
    Eigen::MatrixXd all(m, k);
    block->all(all.data());
    const double scale = std::max(exact.cwiseAbs().maxCoeff(), K.cwiseAbs().maxCoeff() * 1e-3);
    EXPECT_LT((all - exact).cwiseAbs().maxCoeff(), 1e-14 * scale);
    LowRank f;
    ASSERT_TRUE(block->low_rank(1e-8, f));
    if (c == 0) {
      EXPECT_EQ(f.rank(), 0);
      EXPECT_EQ(exact.norm(), 0.0);
    } else {
      EXPECT_GT(f.rank(), 0);
      EXPECT_LT((f.U * f.V.transpose() - exact).norm(), 1e-7 * exact.norm());
    }
  }
}

TEST(SurfaceEntries, DoubleLayerBlockAndItsMirrorFromOnePass) {
  // K(I, J) and K(J, I) by all_and_transpose are all() of the two blocks (near field apart,
  // coplanar and cross-face pairs); the other kernels and blocks without the near field
  // decline
  const test::Mesh mesh = test::cube(6, 1.0 / 6);
  const Surface s(mesh.vertices, mesh.triangles);
  const auto near = std::make_shared<const SurfaceNearField>(s);
  const std::vector<Index> I = every_other(s.vertices(), 0), J = every_other(s.vertices(), 1);
  const Index m = static_cast<Index>(I.size()), k = static_cast<Index>(J.size());
  const SurfaceEntries K(s, SurfaceKernel::DoubleLayer, Space::P1, Space::P1, near);
  Eigen::MatrixXd IJ(m, k), JI(k, m), both(m, k), mirror(k, m);
  K.block(I.data(), m, J.data(), k)->all(IJ.data());
  K.block(J.data(), k, I.data(), m)->all(JI.data());
  ASSERT_TRUE(K.block(I.data(), m, J.data(), k)->all_and_transpose(both.data(), mirror.data()));
  EXPECT_LT((both - IJ).cwiseAbs().maxCoeff(), 1e-15 * IJ.cwiseAbs().maxCoeff());
  EXPECT_LT((mirror - JI).cwiseAbs().maxCoeff(), 1e-15 * JI.cwiseAbs().maxCoeff());
  const SurfaceEntries V(s, SurfaceKernel::SingleLayer, Space::P1, Space::P1, near);
  const SurfaceEntries plain(s, SurfaceKernel::DoubleLayer, Space::P1, Space::P1);
  EXPECT_FALSE(V.block(I.data(), m, J.data(), k)->all_and_transpose(both.data(), mirror.data()));
  EXPECT_FALSE(plain.block(I.data(), m, J.data(), k)->all_and_transpose(both.data(), mirror.data()));
}
