#pragma once
// Hierarchical matrix (docs/design/hmatrix.md): the block tree of a row and a column
// cluster tree (cluster_tree.hpp) under the admissibility condition
// min(diam t, diam s) <= eta dist(t, s); admissible leaves held as U V^T by ACA
// (aca.hpp) recompressed to the relative tolerance tol, the other leaves (near field,
// at least one cluster a leaf) dense and exact. Products with vectors and blocks of
// vectors run over the blocks in parallel (OpenMP). A symmetric matrix keeps the blocks
// (t, s) with t's range starting at or before s's (half the set-up and memory).
//
// Row-restricted (distributed) matrix: only the blocks of the block tree whose rows meet
// the range [row_begin, row_end) of the permuted row order, each cut to those rows (a
// low-rank block keeps its U rows and the whole V; no block is split, so the entries are
// those of the whole matrix). A symmetric matrix keeps its symmetric storage: the rank
// holds the blocks on and above the diagonal in its rows. With a Communicator the ranks
// hold the ranges of ClusterTree::partition, balanced by the bytes of the blocks in each
// row (a symmetric matrix's first rows hold more blocks), and apply() returns the whole
// product on every rank: A X of a non-symmetric A is the local rows and one allgather;
// A^T X, and A X of a symmetric A (an off-diagonal block also acts on the rows of its
// columns), are partial sums and one allreduce (Communicator: the same bits everywhere).
#include <Eigen/Dense>
#include <algorithm>
#include <cstddef>
#include <functional>
#include <memory>
#include <stdexcept>
#include <vector>

#include "bem/aca.hpp"
#include "bem/cluster_tree.hpp"
#include "bem/communicator.hpp"

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
  /// Distributed: this rank holds its range of rows of the row tree (balanced by bytes,
  /// ClusterTree::partition) and apply() is collective.
  std::shared_ptr<const Communicator> comm;
  /// An inadmissible pair with one leaf cluster: a dense block (false, the square operators,
  /// whose trees reach their leaves together) or the other cluster split further (true: a
  /// rectangular matrix whose row tree is much deeper than the column tree, e.g. m >> n
  /// target points of a potential; dense blocks only between two leaves).
  bool split_to_leaves = false;
  /// Admissible blocks also keep their clusters' boxes at least this far apart (the
  /// surface operators: every triangle pair of an admissible block is then a far pair,
  /// surface_entries.hpp).
  double min_distance = 0.0;
  /// Blocks held in single precision (float, round-off 6e-8), the products still summed
  /// in double: half the bytes and about half the memory traffic of a product, for a
  /// matrix whose tol is well above float's round-off (the 3D S_h at tol 1e-6,
  /// docs/design/bem3d.md "Single-precision storage"). Each block is computed in double
  /// and rounded once.
  bool single_precision = false;
};

/// Entries of one block A(I, J) (original dof order), by rows, columns or all at once.
class EntryBlock {
 public:
  virtual ~EntryBlock() = default;
  virtual void row(Index i, double* out) const = 0;     ///< out[c] = A(I[i], J[c])
  virtual void column(Index j, double* out) const = 0;  ///< out[r] = A(I[r], J[j])
  virtual void all(double* out) const = 0;              ///< out[r + c m] = A(I[r], J[c])
  /// all() and the mirrored block at once, transposed[c + r k] = A(J[c], I[r]), where the
  /// source computes both cheaper together (a square matrix on one tree: HMatrix builds the
  /// dense blocks (t, s) and (s, t) it holds by one call). false: not done, nothing written.
  virtual bool all_and_transpose(double* /*out*/, double* /*transposed*/) const { return false; }
  /// An admissible block's factors A(I, J) ~ U V^T to the relative accuracy tol by a
  /// cheaper route than ACA on row() and column() (false: none, the HMatrix runs that ACA).
  virtual bool low_rank(double /*tol*/, LowRank& /*out*/) const { return false; }
  /// The block of the matrix `which` >= 1 of a family (HMatrix::family), asked after all()
  /// or low_rank() of the first on the same object (which may keep what they share).
  virtual void companion_all(int /*which*/, double* /*out*/) const {
    throw std::logic_error("EntryBlock: no companion matrices");
  }
  /// Its factors to tol (false: none, the HMatrix compresses companion_all by SVD).
  virtual bool companion_low_rank(int /*which*/, double /*tol*/, LowRank& /*out*/) const { return false; }
};

/// Source of the entries of a matrix; block() may prepare per-block data. Thread-safe.
class EntrySource {
 public:
  virtual ~EntrySource() = default;
  virtual std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const = 0;
};

/// The bounds b_0 = 0 <= b_1 <= ... <= b_parts = rows.size() of the ranges of the permuted
/// row order that the `parts` ranks of a distributed HMatrix on these trees and options
/// hold (ClusterTree::partition balanced by the bytes of the blocks of each row), known
/// before any entry is computed: what a rank's entries need (e.g. the near field of its
/// rows alone, surface_near_field.hpp).
std::vector<Index> distributed_row_bounds(const ClusterTree& rows, const ClusterTree& cols,
                                          const HMatrixOptions& options, int parts);

class HMatrix {
 public:
  struct Block {
    int row_cluster, col_cluster;
    Index r0, m, c0, k;  ///< ranges in the permuted orders
    bool low_rank;
    Eigen::MatrixXd dense;  ///< m x k if !low_rank (double storage)
    LowRank factors;        ///< if low_rank (double storage)
    /// Single storage: dense_single (m x k) or the factors u_single, v_single; the double
    /// ones are then empty.
    Eigen::MatrixXf dense_single, u_single, v_single;
    Index rank() const { return std::max(factors.rank(), static_cast<Index>(u_single.cols())); }
  };

  /// With a communicator, `row_bounds` are the ranks' ranges when the caller has them
  /// already (distributed_row_bounds of these trees and options, e.g. from choosing the
  /// near field of its rows, rank_triangles); empty: computed here.
  HMatrix(std::shared_ptr<const ClusterTree> rows, std::shared_ptr<const ClusterTree> cols, const EntrySource& entries,
          const HMatrixOptions& options, const std::vector<Index>& row_bounds = {});
  /// The rows [row_begin, row_end) of the permuted row order only (no communicator:
  /// apply_local and apply_partial; apply() needs all rows).
  HMatrix(std::shared_ptr<const ClusterTree> rows, std::shared_ptr<const ClusterTree> cols, const EntrySource& entries,
          const HMatrixOptions& options, Index row_begin, Index row_end);
  /// `count` matrices on the same trees and block tree built in one pass over the blocks,
  /// each block's entries from one EntryBlock (matrix 0: all/low_rank, the others:
  /// companion_all/companion_low_rank): matrices that share their work block by block, as
  /// the surface V_h and W_h (one ACA of the single-layer kernel, surface_entries.hpp).
  /// `row_bounds` as in the constructor (computed once for the family when empty).
  static std::vector<std::shared_ptr<const HMatrix>> family(std::shared_ptr<const ClusterTree> rows,
                                                            std::shared_ptr<const ClusterTree> cols,
                                                            const EntrySource& entries, int count,
                                                            const HMatrixOptions& options,
                                                            const std::vector<Index>& row_bounds = {});

  Index rows() const { return rows_->size(); }
  Index cols() const { return cols_->size(); }
  /// Y = A X (transpose: Y = A^T X), X and Y in the original dof order (collective if
  /// distributed; the same result on every rank).
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose = false) const;
  /// The local rows of A X: (row_end - row_begin, k) in the permuted row order; X whole,
  /// in the original column order. Not for symmetric storage.
  Eigen::MatrixXd apply_local(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// The contribution of the held blocks to A X (transpose: A^T X), X whole in the original
  /// order: (rows, k) (transpose: (cols, k)) in the permuted order; the sum over the ranks
  /// of a distributed matrix is the product.
  Eigen::MatrixXd apply_partial(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) const;
  /// The held blocks as a dense matrix in the original order (with the transposes of the
  /// off-diagonal ones under symmetric storage; for tests): the whole matrix, or of a
  /// row-restricted one its contribution (summed over the ranks: the whole matrix).
  Eigen::MatrixXd to_dense() const;
  /// The entries (indices[a], indices[b]) of the held blocks, (m, m) for the m original
  /// dof indices (distinct, in [0, rows())): to_dense()'s submatrix without forming the
  /// whole, in O(sum over the blocks of their selected entries times their rank).
  /// Row-restricted: this rank's contribution (summed over the ranks: the whole block).
  /// In single precision (Scalar = float) the entries are rounded once, as they are written.
  template <typename Scalar = double>
  Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> principal_submatrix(const std::vector<Index>& indices) const;
  Index row_begin() const { return row_begin_; }
  Index row_end() const { return row_end_; }
  /// Built on a row range, with or without a communicator.
  bool row_restricted() const { return restricted_; }
  /// Bytes of the blocks (dense entries and factors) and of the permutations.
  std::size_t nbytes() const;
  Index max_rank() const;
  bool symmetric() const { return symmetric_; }
  bool single_precision() const { return single_; }
  const std::vector<Block>& blocks() const { return blocks_; }
  const ClusterTree& row_tree() const { return *rows_; }
  const ClusterTree& col_tree() const { return *cols_; }

 private:
  std::shared_ptr<const ClusterTree> rows_, cols_;
  struct Unfilled {};
  /// The rows of this rank (communicator; its range from `row_bounds`, computed when
  /// empty) without any block yet.
  HMatrix(std::shared_ptr<const ClusterTree> rows, std::shared_ptr<const ClusterTree> cols,
          const HMatrixOptions& options, const std::vector<Index>& row_bounds, Unfilled);
  void build(const EntrySource& entries, const HMatrixOptions& options);
  /// The leaves of the block tree in the held rows (entries not yet computed).
  void plan(const HMatrixOptions& options);
  /// The blocks' indices, largest first (the order of the parallel build).
  std::vector<std::size_t> build_order() const;
  std::unique_ptr<EntryBlock> entry_block(const EntrySource& entries, const Block& b) const;
  /// The entries of b (matrix `which` of the EntryBlock), compressed, cut to the held rows.
  void fill(Block& b, const EntryBlock& e, int which, const HMatrixOptions& options) const;
  /// A computed block as it is held: cut to the held rows (row-restricted), rounded to
  /// single precision (single storage).
  void hold(Block& b) const;
  /// Per block: the index of its mirror, the dense block (s, t) of a dense block (t, s),
  /// t != s, of a non-symmetric matrix on one tree (both held); -1 otherwise.
  std::vector<std::ptrdiff_t> mirrors() const;
  /// Y = the held blocks (transposed: tr) times Xp, both permuted; Xp starts at row in0 of
  /// the input if tr (else it is whole), Y at row out0 of the output if !tr (else whole).
  void accumulate(const Eigen::MatrixXd& Xp, Index in0, Index out0, bool tr, Eigen::MatrixXd& Y) const;
  std::vector<Block> blocks_;
  bool symmetric_ = false;  ///< symmetric storage (upper blocks, used twice)
  bool single_ = false;     ///< single-precision blocks
  bool restricted_ = false;
  Index row_begin_ = 0, row_end_ = 0;
  int product_threads_ = 0;
  std::shared_ptr<const Communicator> comm_;
  std::vector<Index> row_counts_, col_counts_;  ///< of the ranks (distributed)
};

}  // namespace bem
