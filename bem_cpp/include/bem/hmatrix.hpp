#pragma once
// Hierarchical matrix (docs/design/hmatrix.md): the block tree of a row and a column
// cluster tree (cluster_tree.hpp) under the admissibility condition
// min(diam t, diam s) <= eta dist(t, s); admissible leaves held as U V^T by ACA
// (aca.hpp) recompressed to the relative tolerance tol, the other leaves (near field,
// at least one cluster a leaf) dense and exact. Products with vectors and blocks of
// vectors run over the blocks in parallel (OpenMP). A symmetric matrix keeps the blocks
// (t, s) with t's range starting at or before s's (half the set-up and memory).
#include <Eigen/Dense>
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "bem/aca.hpp"
#include "bem/cluster_tree.hpp"

namespace bem {

struct HMatrixOptions {
  Index leaf_size;  ///< largest leaf cluster
  double eta;       ///< admissibility parameter
  double tol;       ///< relative accuracy of each low-rank block (ACA and recompression)
  /// A symmetric matrix on one cluster tree (V_h): only the blocks on and above the block
  /// diagonal are built and held; the products use each off-diagonal block twice.
  bool symmetric = false;
  /// OpenMP threads of a product (0: omp_get_max_threads()). A product is many short
  /// parallel loops; on an oversubscribed machine each waits for a descheduled thread
  /// (docs/design/hmatrix.md), so the operator of S_h uses one.
  int product_threads = 0;
};

/// Entries of one block A(I, J) (original dof order), by rows, columns or all at once.
class EntryBlock {
 public:
  virtual ~EntryBlock() = default;
  virtual void row(Index i, double* out) const = 0;     ///< out[c] = A(I[i], J[c])
  virtual void column(Index j, double* out) const = 0;  ///< out[r] = A(I[r], J[j])
  virtual void all(double* out) const = 0;              ///< out[r + c m] = A(I[r], J[c])
};

/// Source of the entries of a matrix; block() may prepare per-block data. Thread-safe.
class EntrySource {
 public:
  virtual ~EntrySource() = default;
  virtual std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const = 0;
};

class HMatrix {
 public:
  struct Block {
    int row_cluster, col_cluster;
    Index r0, m, c0, k;  ///< ranges in the permuted orders
    bool low_rank;
    Eigen::MatrixXd dense;  ///< m x k if !low_rank
    LowRank factors;        ///< if low_rank
  };

  HMatrix(std::shared_ptr<const ClusterTree> rows, std::shared_ptr<const ClusterTree> cols,
          const EntrySource& entries, const HMatrixOptions& options);

  Index rows() const { return rows_->size(); }
  Index cols() const { return cols_->size(); }
  /// Y = A X (transpose: Y = A^T X), X and Y in the original dof order.
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose = false) const;
  /// The approximation as a dense matrix in the original order (for tests).
  Eigen::MatrixXd to_dense() const;
  /// Bytes of the blocks (dense entries and factors) and of the permutations.
  std::size_t nbytes() const;
  Index max_rank() const;
  bool symmetric() const { return symmetric_; }
  const std::vector<Block>& blocks() const { return blocks_; }
  const ClusterTree& row_tree() const { return *rows_; }
  const ClusterTree& col_tree() const { return *cols_; }

 private:
  std::shared_ptr<const ClusterTree> rows_, cols_;
  std::vector<Block> blocks_;
  bool symmetric_ = false;
  int product_threads_ = 0;
};

}  // namespace bem
