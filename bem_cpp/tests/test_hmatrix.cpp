#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <vector>

#include "bem/hmatrix.hpp"
#include "bem/operator_entries.hpp"
#include "test_helpers.hpp"

using namespace bem;

namespace {
std::shared_ptr<const HMatrix> hmatrix(const Polygon& poly, Kernel kernel, Space rows, double tol) {
  const Space cols = kernel == Kernel::SingleLayer ? rows : Space::P1;
  auto tr = std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, rows, 16));
  auto tc = rows == cols ? tr : std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, cols, 16));
  const OperatorEntries e(poly, kernel, rows, cols);
  return std::make_shared<const HMatrix>(tr, tc, e, HMatrixOptions{16, 1.0, tol});
}
}  // namespace

TEST(HMatrix, ApproximatesVAndKToTheTolerance) {
  test::for_each_operator_case([](const Polygon& poly, Space s, Kernel kernel) {
    const Index n = poly.size();
    const Eigen::MatrixXd A = kernel == Kernel::SingleLayer ? single_layer(poly, s) : double_layer(poly, s);
    const auto H = hmatrix(poly, kernel, s, 1e-8);
    EXPECT_LT((H->to_dense() - A).norm(), 1e-8 * A.norm());
    // Products agree with the dense approximation, for blocks of vectors and transposed.
    const Eigen::MatrixXd Xr = Eigen::MatrixXd::Random(n, 3);
    const Eigen::MatrixXd Hd = H->to_dense();
    EXPECT_LT((H->apply(Xr) - Hd * Xr).norm(), 1e-13 * (Hd * Xr).norm());
    EXPECT_LT((H->apply(Xr, true) - Hd.transpose() * Xr).norm(), 1e-13 * (Hd * Xr).norm());
    // Compression: less than the dense n^2 doubles.
    EXPECT_LT(H->nbytes(), static_cast<std::size_t>(n * n) * sizeof(double));
    EXPECT_GT(H->max_rank(), 0);
  });
}

TEST(HMatrix, SymmetricStorageHoldsHalfTheOffDiagonalBlocks) {
  const Polygon poly(test::square(150));
  const Index n = poly.size();
  for (Space s : {Space::P0, Space::P1}) {
    const Eigen::MatrixXd A = single_layer(poly, s);
    auto tree = std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, s, 16));
    const OperatorEntries e(poly, Kernel::SingleLayer, s, s);
    const HMatrix full(tree, tree, e, HMatrixOptions{16, 1.0, 1e-8});
    const HMatrix sym(tree, tree, e, HMatrixOptions{16, 1.0, 1e-8, true});
    EXPECT_TRUE(sym.symmetric());
    const Eigen::MatrixXd D = sym.to_dense();
    EXPECT_LT((D - D.transpose()).norm(), 1e-14 * D.norm());  // diagonal blocks: round-off
    EXPECT_LT((D - A).norm(), 1e-8 * A.norm());
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(n, 2);
    EXPECT_LT((sym.apply(X) - D * X).norm(), 1e-13 * (D * X).norm());
    EXPECT_LT((sym.apply(X, true) - D * X).norm(), 1e-13 * (D * X).norm());
    EXPECT_LT(sym.blocks().size(), full.blocks().size());
    EXPECT_LT(sym.nbytes(), 0.75 * static_cast<double>(full.nbytes()));
  }
  // one tree for rows and columns is required
  const auto t0 = std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, Space::P0, 16));
  const auto t1 = std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, Space::P0, 16));
  const OperatorEntries e(poly, Kernel::SingleLayer, Space::P0, Space::P0);
  EXPECT_THROW(HMatrix(t0, t1, e, HMatrixOptions{16, 1.0, 1e-8, true}), std::invalid_argument);
}

/// A circle of 600 P1 nodes, its cluster tree and the entries of V (for symmetric H-matrices)
/// and K (for general ones).
class CircleHMatrix : public ::testing::Test {
 protected:
  const Polygon poly{test::circle(600)};
  const Index n = poly.size();
  const std::shared_ptr<const ClusterTree> tree =
      std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, Space::P1, 16));
  const OperatorEntries single{poly, Kernel::SingleLayer, Space::P1, Space::P1};
  const OperatorEntries dbl{poly, Kernel::DoubleLayer, Space::P1, Space::P1};
};

TEST_F(CircleHMatrix, PrincipalSubmatrixIsThatOfTheDenseMatrix) {
  const HMatrix sym(tree, tree, single, HMatrixOptions{16, 1.0, 1e-8, true});
  const HMatrix general(tree, tree, dbl, HMatrixOptions{16, 1.0, 1e-8});
  // every third node, in a scrambled order, and an arc of consecutive nodes
  std::vector<Index> scattered, arc;
  for (Index i = n - 2; i >= 0; i -= 3) scattered.push_back(i);
  for (Index i = 100; i < 260; ++i) arc.push_back(i);
  for (const HMatrix* H : {&sym, &general}) {
    const Eigen::MatrixXd D = H->to_dense();
    for (const auto& idx : {scattered, arc}) {
      const Eigen::MatrixXd B = H->principal_submatrix<double>(idx);
      ASSERT_EQ(B.rows(), static_cast<Index>(idx.size()));
      Eigen::MatrixXd expected(B.rows(), B.cols());
      for (std::size_t a = 0; a < idx.size(); ++a)
        for (std::size_t b = 0; b < idx.size(); ++b)
          expected(static_cast<Index>(a), static_cast<Index>(b)) = D(idx[a], idx[b]);
      EXPECT_LE((B - expected).norm(), 1e-14 * expected.norm());
    }
  }
  EXPECT_THROW(sym.principal_submatrix<double>({0, 5, 5}), std::invalid_argument);
  EXPECT_THROW(sym.principal_submatrix<double>({n}), std::invalid_argument);
}

TEST_F(CircleHMatrix, SinglePrecisionStorageRoundsEachBlockOnce) {
  // The same block tree and factors as double storage, each entry rounded to float (relative
  // 2^-24 = 6e-8): products within a few float round-offs of double storage's, products and
  // principal submatrices those of to_dense() (the entries as held), half the bytes.
  for (const bool symmetric : {true, false}) {
    const OperatorEntries& e = symmetric ? single : dbl;
    HMatrixOptions o{16, 1.0, 1e-6, symmetric};
    const HMatrix d(tree, tree, e, o);
    o.single_precision = true;
    const HMatrix f(tree, tree, e, o);
    EXPECT_TRUE(f.single_precision());
    EXPECT_FALSE(d.single_precision());
    EXPECT_EQ(f.blocks().size(), d.blocks().size());
    EXPECT_EQ(f.max_rank(), d.max_rank());
    const Eigen::MatrixXd Dd = d.to_dense(), Df = f.to_dense();
    EXPECT_LT((Df - Dd).norm(), 3e-7 * Dd.norm());
    EXPECT_GT((Df - Dd).norm(), 0.0);  // rounded indeed
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(n, 3);
    for (const bool tr : {false, true}) {
      const Eigen::MatrixXd Y = tr ? Eigen::MatrixXd(Df.transpose() * X) : Eigen::MatrixXd(Df * X);
      EXPECT_LT((f.apply(X, tr) - Y).norm(), 1e-13 * Y.norm());
    }
    std::vector<Index> arc;
    for (Index i = 100; i < 260; ++i) arc.push_back(i);
    const Eigen::MatrixXd B = f.principal_submatrix<double>(arc);
    EXPECT_LE((B - Df(arc, arc)).norm(), 1e-14 * B.norm());
    // in single precision: each entry of the double block rounded once, to the bit
    const Eigen::MatrixXf Bf = f.principal_submatrix<float>(arc);
    EXPECT_EQ(Bf, B.cast<float>());
    EXPECT_LT(static_cast<double>(f.nbytes()), 0.6 * static_cast<double>(d.nbytes()));
  }
}

namespace {
// The entries of a dense matrix; its blocks also give all_and_transpose, counted.
class PairedEntries : public EntrySource {
 public:
  explicit PairedEntries(const Eigen::MatrixXd& A) : A_(A) {}
  std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const override {
    return std::make_unique<Block>(*this, I, m, J, k);
  }
  mutable std::atomic<int> pairs{0}, singles{0};

 private:
  struct Block : EntryBlock {
    Block(const PairedEntries& s, const Index* I, Index m, const Index* J, Index k) : s(s), I(I), J(J), m(m), k(k) {}
    void row(Index i, double* out) const override {
      for (Index c = 0; c < k; ++c) out[c] = s.A_(I[i], J[c]);
    }
    void column(Index j, double* out) const override {
      for (Index r = 0; r < m; ++r) out[r] = s.A_(I[r], J[j]);
    }
    void all(double* out) const override {
      ++s.singles;
      for (Index c = 0; c < k; ++c)
        for (Index r = 0; r < m; ++r) out[r + c * m] = s.A_(I[r], J[c]);
    }
    bool all_and_transpose(double* out, double* transposed) const override {
      ++s.pairs;
      for (Index c = 0; c < k; ++c)
        for (Index r = 0; r < m; ++r) {
          out[r + c * m] = s.A_(I[r], J[c]);
          transposed[c + r * k] = s.A_(J[c], I[r]);
        }
      return true;
    }
    const PairedEntries& s;
    const Index *I, *J;
    Index m, k;
  };
  const Eigen::MatrixXd& A_;
};
}  // namespace

TEST(HMatrix, MirroredDenseBlocksAreBuiltTogether) {
  // a non-symmetric matrix on one tree: each pair of dense blocks (t, s), (s, t), t != s,
  // by one all_and_transpose, the diagonal ones by all(); row-restricted, only the pairs
  // whose two blocks the rows hold; symmetric storage or two trees: no pairs
  const Polygon poly(test::circle(600));
  const Eigen::MatrixXd A = double_layer(poly, Space::P1);
  auto tree = std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, Space::P1, 16));
  const HMatrixOptions o{16, 1.0, 1e-8};
  const PairedEntries e(A);
  const HMatrix H(tree, tree, e, o);
  int dense = 0, diagonal = 0;
  for (const HMatrix::Block& b : H.blocks())
    if (!b.low_rank) {
      ++dense;
      diagonal += b.row_cluster == b.col_cluster;
    }
  // (admissible blocks whose recompressed factors are larger than their entries turn dense
  // too, from their factors: at most `dense` blocks planned dense)
  EXPECT_GT(e.pairs.load(), 0);
  EXPECT_LE(2 * e.pairs.load() + e.singles.load(), dense);
  EXPECT_EQ(e.singles.load(), diagonal);
  EXPECT_LT((H.to_dense() - A).norm(), 1e-8 * A.norm());
  const std::vector<Index> bounds = tree->partition(3);
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(A.rows(), A.cols());
  for (int r = 0; r < 3; ++r) D += HMatrix(tree, tree, e, o, bounds[r], bounds[r + 1]).to_dense();
  EXPECT_LT((D - H.to_dense()).norm(), 1e-14 * A.norm());
  const PairedEntries symmetric(A);
  const HMatrix S(tree, tree, symmetric, HMatrixOptions{16, 1.0, 1e-8, true});
  EXPECT_EQ(symmetric.pairs.load(), 0);
  auto other = std::make_shared<const ClusterTree>(ClusterTree::for_space(poly, Space::P1, 16));
  const PairedEntries two_trees(A);
  const HMatrix T(tree, other, two_trees, o);
  EXPECT_EQ(two_trees.pairs.load(), 0);
  EXPECT_LT((T.to_dense() - A).norm(), 1e-8 * A.norm());
}
