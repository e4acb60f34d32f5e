// The 3D Lame S_h as H-matrices (lame_surface_entries.hpp, lame_surface_steklov.hpp): the
// grouped point ACA, the H-matrix products of V_h, K_h, W_h against the dense lame_surface
// matrices, S_h against the dense S_h, the CG iteration counts under refinement, and 1
// against 2 emulated ranks.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <thread>

#include "bem/lame_surface.hpp"
#include "bem/lame_surface_entries.hpp"
#include "bem/lame_surface_steklov.hpp"
#include "bem/surface_entries.hpp"
#include "bem/surface_near_field.hpp"
#include "test_helpers.hpp"
#include "test_ranks.hpp"
#include "test_surfaces.hpp"

using namespace bem;

namespace {

const Lame kSteel{1.0, 0.3};

double relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); }

/// The surfaces of the tests: the sphere |x| = 0.5, the cube and Fichera's corner of side 1.
test::Mesh mesh(int shape, int level) {
  if (shape == 0) return test::icosphere(level, 0.5);
  const int N = 1 << level;
  return shape == 1 ? test::cube(N, 1.0 / N) : test::fichera(N, 1.0 / N);
}
const char* kShapes[3] = {"sphere", "cube", "Fichera"};

SteklovOptions options(double tol, Index leaf = 16) { return test::steklov_options(tol, leaf, 4.0); }

/// Scalar matrix kron I_3 (node-major vector dofs).
Eigen::MatrixXd kron3(const Eigen::MatrixXd& A) {
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(3 * A.rows(), 3 * A.cols());
  for (Index r = 0; r < A.rows(); ++r)
    for (Index c = 0; c < A.cols(); ++c)
      for (int k = 0; k < 3; ++k) B(3 * r + k, 3 * c + k) = A(r, c);
  return B;
}

/// The dense V_h, K_h, W_h (lame_surface.hpp) of mesh(shape, level), assembled once for the
/// tests that compare with them.
const SurfaceMatrices& dense(int shape, int level) {
  static std::map<std::pair<int, int>, SurfaceMatrices> cache;
  const auto key = std::make_pair(shape, level);
  auto it = cache.find(key);
  if (it == cache.end()) {
    const test::Mesh m = mesh(shape, level);
    const SurfaceRequest request{Space::P1, Space::P1, true};
    it = cache.emplace(key, assemble(Surface(m.vertices, m.triangles), kSteel, request)).first;
  }
  return it->second;
}

using bem::test::ThreadGroup;

}  // namespace

TEST(LameSurfaceAca, GroupedPointAcaSeesEveryComponentOfCoplanarPoints) {
  // Two point sets in the plane z = 0: A's normal component decouples (A_xz = A_yz = 0), so
  // the block is [[A_t, 0], [0, a0 g]] in the tangential and normal rows; the grouped ACA sees
  // both parts (each pivot row brings its point's normal row along).
  const Index P = 150;
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(P, 2), Y = Eigen::MatrixXd::Random(P, 2);
  Y.col(0).array() += 5.0;
  auto block = [&](Index p, Index q, int k, int l) {
    const double r[3] = {X(p, 0) - Y(q, 0), X(p, 1) - Y(q, 1), 0.0};
    const double d = std::sqrt(r[0] * r[0] + r[1] * r[1]);
    return r[k] * r[l] / (d * d * d) + (k == l ? 0.4 / d : 0.0);
  };
  Eigen::MatrixXd A(3 * P, 3 * P);
  for (Index p = 0; p < P; ++p)
    for (Index q = 0; q < P; ++q)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) A(3 * p + k, 3 * q + l) = block(p, q, k, l);
  const auto rows = [&](Index p, double* out) {
    for (Index q = 0; q < P; ++q)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) out[(3 * k + l) * P + q] = A(3 * p + k, 3 * q + l);
  };
  const auto columns = [&](Index q, double* out) {
    for (Index p = 0; p < P; ++p)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) out[(3 * l + k) * P + p] = A(3 * p + k, 3 * q + l);
  };
  for (double tol : {1e-4, 1e-8}) {
    const LowRank F = grouped_point_aca(P, P, rows, columns, tol, 3 * P);
    const Eigen::MatrixXd E = A - F.U * F.V.transpose();
    EXPECT_LT(E.norm(), 10 * tol * A.norm()) << tol;
    // the normal rows and columns alone (a sixth of the norm)
    EXPECT_LT(test::component(E, 3, 2).norm(), 10 * tol * A.norm()) << tol;
    EXPECT_GT(test::component(A, 3, 2).norm(), 0.1 * A.norm());
  }
}

TEST(LameSurfaceSteklov, HMatricesMatchTheDenseOperators) {
  // V_h, K_h, K_h^T, W_h at tol 1e-10 against lame_surface.hpp's dense matrices (leaves of 16
  // vertices; at this tol and size most admissible blocks are summed densely, their ranks not
  // paying: LameBlock::far_factors). Measured relative product errors (V, K, K^T, W): sphere
  // (642 vertices) 1.4e-11, 5.7e-12, 5.4e-12, 6.3e-12; cube (386) 1.8e-12, 1.5e-13, 1.7e-13,
  // 2.0e-12; Fichera's corner (386) 1.6e-12, 7.7e-14, 8.3e-14, 1.5e-12.
  const double tol = 1e-10;
  for (int shape = 0; shape < 3; ++shape) {
    const test::Mesh m = mesh(shape, 3);
    const Surface s(m.vertices, m.triangles);
    const SurfaceMatrices& D = dense(shape, 3);
    const LameSurfaceOperators H(s, kSteel, options(tol).hmatrix);
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(3 * s.vertices(), 3);
    SCOPED_TRACE(kShapes[shape]);
    const double e[4] = {relative(H.single_layer()->apply(X), D.single_layer * X),
                         relative(H.double_layer(X), D.double_layer * X),
                         relative(H.double_layer(X, true), D.double_layer.transpose() * X),
                         relative(H.hypersingular(X), D.hypersingular * X)};
    for (double x : e) EXPECT_LT(x, 1e-8);
    EXPECT_TRUE(H.single_layer()->symmetric());
    EXPECT_EQ(H.nbytes(), H.info().nbytes_v + H.info().nbytes_k + H.info().nbytes_w);
  }
}

TEST(LameSurfaceSteklov, CompressedBlocksAtAModerateTolerance) {
  // At tol 1e-6 and leaves of 8 vertices the far blocks are held low-rank, from the point ACA
  // (not the dense fallback): flat faces (the cube: between coplanar points the normal
  // component decouples) as well as the sphere. Measured relative product errors (V, K, K^T,
  // W) and the largest ranks (V, Y, Z): sphere (642 vertices) 2.6e-7, 1.4e-7, 1.3e-7, 4.7e-8
  // (36, 40, 44); cube (602) 2.7e-7, 1.0e-7, 9.7e-8, 6.8e-8 (56, 62, 74).
  const double tol = 1e-6;
  for (int shape = 0; shape < 2; ++shape) {
    const test::Mesh m = shape == 0 ? mesh(0, 3) : test::cube(10, 0.1);
    const Surface s(m.vertices, m.triangles);
    const SurfaceRequest request{Space::P1, Space::P1, true};
    const SurfaceMatrices cube = shape == 0 ? SurfaceMatrices{} : assemble(s, kSteel, request);
    const SurfaceMatrices& D = shape == 0 ? dense(0, 3) : cube;
    const LameSurfaceOperators H(s, kSteel, options(tol, 8).hmatrix);
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(3 * s.vertices(), 3);
    SCOPED_TRACE(kShapes[shape]);
    for (const HMatrix* A : {H.single_layer().get(), &H.y(), &H.z()}) EXPECT_GT(A->max_rank(), 0);
    const double e[4] = {relative(H.single_layer()->apply(X), D.single_layer * X),
                         relative(H.double_layer(X), D.double_layer * X),
                         relative(H.double_layer(X, true), D.double_layer.transpose() * X),
                         relative(H.hypersingular(X), D.hypersingular * X)};
    for (double x : e) EXPECT_LT(x, tol);
  }
}

TEST(LameSurfaceSteklov, OperatorMatchesTheDenseOperator) {
  // S_h against 1/2 (W + (K - M)^T V^{-1} (K - M)) from the dense matrices at tol 1e-8, leaves of
  // 16 vertices. Measured relative errors of S_h X and of the flux V^{-1} (K - M) X: sphere (642
  // vertices) 9.0e-9 and 2.1e-8 (16 CG iterations), Fichera's corner (386) 2.5e-9 and 6.1e-9 (23):
  // the H-matrices' errors at about tol, as the Laplace S_h's (no tighter tol for the vector parts).
  const double tol = 1e-8;
  for (int shape : {0, 2}) {
    const test::Mesh m = mesh(shape, 3);
    const Surface s(m.vertices, m.triangles);
    const SurfaceMatrices& D = dense(shape, 3);
    const Eigen::MatrixXd A = Eigen::MatrixXd(D.double_layer) - kron3(mass(s, Space::P1));
    const Eigen::LLT<Eigen::MatrixXd> V(Eigen::MatrixXd(D.single_layer));
    const auto S = lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P1, options(tol));
    ASSERT_EQ(S->size(), 3 * s.vertices());
    EXPECT_EQ(S->dimension(), 3);
    const Eigen::MatrixXd Y = Eigen::MatrixXd::Random(S->size(), 4), flux = V.solve(A * Y);
    const Eigen::MatrixXd ref = 0.5 * (D.hypersingular * Y + A.transpose() * flux);
    SCOPED_TRACE(kShapes[shape]);
    const double e = relative(S->apply(Y), ref), f = relative(S->flux(Y), flux);
    EXPECT_LT(e, 10 * tol);
    EXPECT_GT(S->last_iterations(), 0);
    EXPECT_LT(f, 100 * tol);
    const int own = S->last_iterations();
    const Eigen::MatrixXd loose = S->apply(Y, 1e-6);
    EXPECT_LT(S->last_iterations(), own);
    EXPECT_LT(relative(loose, ref), 1e-4);
    EXPECT_EQ(S->apply(Eigen::MatrixXd::Zero(S->size(), 2)).norm(), 0.0);
    const LameSteklovInfo& i = S->info();
    EXPECT_EQ(S->nbytes(), i.nbytes_v + i.nbytes_v0 + i.nbytes_k + i.nbytes_w + i.nbytes_preconditioner);
    EXPECT_GT(i.setup_seconds, 0.0);
  }
}

TEST(LameSurfaceSteklov, IterationCountsStayBounded) {
  // CG iterations of the V solve (relative residual 1e-9, tol 1e-6), nu = 0.3, three levels of
  // refinement: sphere 42, 162, 642 vertices: 13 13 13 (2,562 and 10,242: 13 and 13, leaves of
  // 64); Fichera's corner 26, 98, 386 vertices: 17 19 20 (the Laplace operator of
  // surface_steklov.hpp: 7 on the sphere). The preconditioner (lame_surface_steklov.hpp) is the
  // Laplace one on each component with the rigid motions and the normal field deflated.
  for (int shape : {0, 2}) {
    std::vector<int> counts;
    for (int level = 1; level <= 3; ++level) {
      const test::Mesh m = mesh(shape, level);
      SteklovOptions o = options(1e-6);
      o.solver_tol = 1e-9;
      const auto S = lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P1, o);
      S->flux(Eigen::MatrixXd::Random(S->size(), 1));
      counts.push_back(S->last_iterations());
    }
    for (int n : counts) EXPECT_LE(n, shape == 0 ? 16 : 24) << kShapes[shape];
    EXPECT_LE(counts.back() - counts.front(), 4) << kShapes[shape];
  }
}

TEST(LameSurfaceSteklov, DistributedOverThreadsEqualsTheSerialOperator) {
  // 1 and 2 emulated ranks (products on one thread): on 1 rank the serial bits; on 2 the blocks
  // of Y that the other rank's rows need are computed again (not from the cache) and the dense
  // ones summed in another order: measured 4.6e-16 (S_h X) and 9.4e-16 (the flux) relative, the
  // same CG iterations, every rank the same bits and about half the bytes (0.495, 0.508).
  const double tol = 1e-6;
  const test::Mesh m = mesh(2, 3);
  const SteklovOptions serial_options = options(tol);
  const auto serial = lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P1, serial_options);
  const Eigen::MatrixXd Y = Eigen::MatrixXd::Random(serial->size(), 2);
  const Eigen::MatrixXd ref = serial->apply(Y), ref_flux = serial->flux(Y);
  const int iterations = serial->last_iterations();
  for (int size : {1, 2}) {
    const test::RankRuns runs = test::run_on_ranks(size, Y, [&](std::shared_ptr<const Communicator> comm) {
      SteklovOptions o = serial_options;
      o.hmatrix.comm = std::move(comm);
      return lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P1, o);
    });
    test::expect_serial_results(runs, ref, ref_flux, iterations, test::hmatrix_bytes(serial->info()), 1e-13, true, 1.1);
  }
}

TEST(LameSurfaceSteklov, EachRankIntegratesTheNearPairsOfItsRowsAlone) {
  // rank_triangles: the triangles touching a vertex of the rank's rows of the five
  // H-matrices. On 2 emulated ranks of the cube every triangle is some rank's, and each
  // rank's near field (its pairs alone) holds less than the whole one (before: each rank
  // the whole). Measured: 0.67 and 0.89 of its bytes with 8 x 8 squares a face, 0.59 and
  // 0.75 with 16 x 16 (the symmetric matrices' rows balanced by bytes give rank 1 more
  // rows than the others': the union of the ranges is what a rank integrates). The rows
  // are exact: DistributedOverThreadsEqualsTheSerialOperator.
  const test::Mesh m = mesh(1, 3);
  const Surface s(m.vertices, m.triangles);
  const HMatrixOptions serial = options(1e-6).hmatrix;
  const std::size_t whole = LameSurfaceOperators(s, kSteel, serial).info().nbytes_near;
  EXPECT_TRUE(rank_triangles(s, serial, {}).empty());  // not distributed: every triangle
  ThreadGroup group(2);
  std::vector<std::size_t> near(2);
  std::vector<std::vector<char>> mine(2);
  std::vector<std::thread> ranks;
  for (int r = 0; r < 2; ++r)
    ranks.emplace_back([&, r] {
      HMatrixOptions o = serial;
      o.comm = group.communicator(r);
      near[static_cast<std::size_t>(r)] = LameSurfaceOperators(s, kSteel, o).info().nbytes_near;
      HMatrixOptions f = o;
      f.min_distance = far_distance(s);
      const ClusterTree tree = surface_cluster_tree(s, Space::P1, f.leaf_size);
      mine[static_cast<std::size_t>(r)] = rank_triangles(s, f, {{&tree, surface_row_bounds(tree, f, false)}});
    });
  for (std::thread& t : ranks) t.join();
  for (Index t = 0; t < s.size(); ++t)
    EXPECT_TRUE(mine[0][static_cast<std::size_t>(t)] || mine[1][static_cast<std::size_t>(t)]) << t;
  for (int r = 0; r < 2; ++r) {
    EXPECT_EQ(mine[static_cast<std::size_t>(r)].size(), static_cast<std::size_t>(s.size()));
    EXPECT_LT(static_cast<double>(near[static_cast<std::size_t>(r)]), 0.95 * static_cast<double>(whole)) << r;
  }
}

TEST(LameSurfaceSteklov, HypersingularBlockMatchesTheDenseBlock) {
  // The principal submatrix of W_h = Z + 2 mu W_L kron I_3 on the vector dofs of some nodes (a
  // face of the cube and every third vertex, in a scattered order), read from the H-matrices,
  // against the dense W_h's (lame_surface.hpp) at tol 1e-6, leaves of 8 vertices (low-rank far
  // blocks). Measured relative (Frobenius) errors: the bottom face (81 nodes) 7.6e-9, every
  // third vertex (129) 1.9e-8; symmetric (measured: exactly, both halves of a block from its
  // one copy); on 1 and 2 emulated ranks the serial operator's bits, on every rank.
  const double tol = 1e-6;
  const test::Mesh m = mesh(1, 3);
  const Surface s(m.vertices, m.triangles);
  const SurfaceMatrices& D = dense(1, 3);
  const Eigen::MatrixXd W = D.hypersingular;
  std::vector<Index> face, third;
  for (Index i = 0; i < s.vertices(); ++i)
    if (std::abs(m.vertices(i, 2) - m.vertices.col(2).minCoeff()) < 1e-12) face.push_back(i);
  for (Index i = s.vertices() - 1; i >= 0; i -= 3) third.push_back(i);
  const SteklovOptions serial_options = options(tol, 8);
  const auto serial = lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P1, serial_options);
  ASSERT_TRUE(serial->holds_hypersingular());
  std::vector<Eigen::MatrixXd> reference;
  for (const std::vector<Index>* nodes : {&face, &third}) {
    const Index k = static_cast<Index>(nodes->size());
    std::vector<Index> dofs;
    for (Index i : *nodes)
      for (int c = 0; c < 3; ++c) dofs.push_back(3 * i + c);
    const Eigen::MatrixXd expected = W(dofs, dofs);
    const Eigen::MatrixXd B = serial->hypersingular_block(*nodes);
    ASSERT_EQ(B.rows(), 3 * k);
    ASSERT_EQ(B.cols(), 3 * k);
    EXPECT_LT(relative(B, expected), tol);
    EXPECT_LT((B - B.transpose()).norm(), 1e-14 * B.norm());
    reference.push_back(B);
  }
  EXPECT_THROW(serial->hypersingular_block({0, 0}), std::invalid_argument);
  EXPECT_THROW(serial->hypersingular_block({s.vertices()}), std::invalid_argument);
  for (int size : {1, 2}) {
    ThreadGroup group(size);
    std::vector<std::vector<Eigen::MatrixXd>> out(static_cast<std::size_t>(size));
    std::vector<std::thread> ranks;
    for (int r = 0; r < size; ++r)
      ranks.emplace_back([&, r] {
        SteklovOptions o = serial_options;
        o.hmatrix.comm = group.communicator(r);
        const auto S = lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P1, o);
        for (const std::vector<Index>* nodes : {&face, &third})
          out[static_cast<std::size_t>(r)].push_back(S->hypersingular_block(*nodes));
      });
    for (std::thread& t : ranks) t.join();
    for (int r = 0; r < size; ++r)
      for (std::size_t j = 0; j < reference.size(); ++j) {
        const Eigen::MatrixXd& B = out[static_cast<std::size_t>(r)][j];
        EXPECT_EQ((B - reference[j]).cwiseAbs().maxCoeff(), 0.0) << size << " ranks, rank " << r;
        EXPECT_EQ((B - out[0][j]).cwiseAbs().maxCoeff(), 0.0) << size << " ranks, rank " << r;
      }
  }
}

TEST(LameSurfaceSteklov, Refusals) {
  const test::Mesh m = mesh(1, 1);
  EXPECT_THROW(lame_surface_steklov_operator(m.vertices, m.triangles, Lame{-1.0, 0.3}, Space::P1, options(1e-8)),
               std::invalid_argument);
  EXPECT_THROW(lame_surface_steklov_operator(m.vertices, m.triangles, Lame{1.0, 0.5}, Space::P1, options(1e-8)),
               std::invalid_argument);
  EXPECT_THROW(lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P0, options(1e-8)),
               std::invalid_argument);
  SteklovOptions bad = options(1e-8);
  bad.solver_tol = 0.0;
  EXPECT_THROW(lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P1, bad), std::invalid_argument);
  const auto S = lame_surface_steklov_operator(m.vertices, m.triangles, kSteel, Space::P1, options(1e-8));
  EXPECT_EQ(S->size(), 3 * m.vertices.rows());
  EXPECT_THROW(S->apply(Eigen::MatrixXd::Ones(5, 1)), std::invalid_argument);
}
