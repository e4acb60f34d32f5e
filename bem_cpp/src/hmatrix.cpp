#include "bem/hmatrix.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include <omp.h>

namespace bem {

namespace {

/// The leaves of the block tree under (t, s). upper: only (t, s) on or above the block
/// diagonal (symmetric storage). [lo, hi): only row clusters meeting these rows.
void collect(const ClusterTree& rows, const ClusterTree& cols, int t, int s, double eta, double min_distance,
             bool upper, Index lo, Index hi, std::vector<HMatrix::Block>& out, bool split_to_leaves = false) {
  const Cluster& ct = rows.cluster(t);
  const Cluster& cs = cols.cluster(s);
  if (ct.end <= lo || ct.begin >= hi) return;
  // Symmetric: cluster ranges are nested or disjoint, so t starting after s (disjoint)
  // puts the whole subtree of (t, s) below the block diagonal.
  if (upper && ct.begin > cs.begin && ct.begin >= cs.end) return;
  const bool adm = admissible(ct.box, cs.box, eta) && ct.box.distance(cs.box) >= min_distance;
  if (adm || (split_to_leaves ? ct.leaf() && cs.leaf() : ct.leaf() || cs.leaf())) {
    HMatrix::Block b;
    b.row_cluster = t;
    b.col_cluster = s;
    b.r0 = ct.begin;
    b.m = ct.size();
    b.c0 = cs.begin;
    b.k = cs.size();
    b.low_rank = adm;
    out.push_back(std::move(b));
    return;
  }
  // split_to_leaves: a leaf stays whole while the other side is split
  const int ts[2] = {ct.leaf() ? t : ct.children[0], ct.leaf() ? -1 : ct.children[1]};
  const int ss[2] = {cs.leaf() ? s : cs.children[0], cs.leaf() ? -1 : cs.children[1]};
  for (int a : ts)
    for (int c : ss)
      if (a >= 0 && c >= 0) collect(rows, cols, a, c, eta, min_distance, upper, lo, hi, out, split_to_leaves);
}

std::vector<Index> counts(const std::vector<Index>& bounds) {
  const int parts = static_cast<int>(bounds.size()) - 1;
  std::vector<Index> c(static_cast<std::size_t>(parts));
  for (int r = 0; r < parts; ++r) c[static_cast<std::size_t>(r)] = bounds[r + 1] - bounds[r];
  return c;
}

Eigen::MatrixXd permuted(const Eigen::Ref<const Eigen::MatrixXd>& X, const ClusterTree& tree) {
  Eigen::MatrixXd Xp(X.rows(), X.cols());
  const std::vector<Index>& p = tree.permutation();
  for (Index r = 0; r < X.rows(); ++r) Xp.row(r) = X.row(p[static_cast<std::size_t>(r)]);
  return Xp;
}

Eigen::MatrixXd unpermuted(const Eigen::MatrixXd& Yp, const ClusterTree& tree) {
  Eigen::MatrixXd Y(Yp.rows(), Yp.cols());
  const std::vector<Index>& p = tree.permutation();
  for (Index r = 0; r < Yp.rows(); ++r) Y.row(p[static_cast<std::size_t>(r)]) = Yp.row(r);
  return Y;
}

/// y += A x (A single, m x k, column-major; x, y double), four columns per pass over y.
void add_product(const Eigen::MatrixXf& A, const double* x, double* y) {
  const Index m = A.rows(), k = A.cols();
  const float* a = A.data();
  Index c = 0;
  for (; c + 4 <= k; c += 4) {
    const float *a0 = a + c * m, *a1 = a0 + m, *a2 = a1 + m, *a3 = a2 + m;
    const double x0 = x[c], x1 = x[c + 1], x2 = x[c + 2], x3 = x[c + 3];
#pragma omp simd
    for (Index r = 0; r < m; ++r)
      y[r] += static_cast<double>(a0[r]) * x0 + static_cast<double>(a1[r]) * x1 + static_cast<double>(a2[r]) * x2 +
              static_cast<double>(a3[r]) * x3;
  }
  for (; c < k; ++c) {
    const float* a0 = a + c * m;
    const double x0 = x[c];
#pragma omp simd
    for (Index r = 0; r < m; ++r) y[r] += static_cast<double>(a0[r]) * x0;
  }
}

/// y += A^T x (A single, m x k, column-major; x, y double), four columns per pass over x.
void add_transposed_product(const Eigen::MatrixXf& A, const double* x, double* y) {
  const Index m = A.rows(), k = A.cols();
  const float* a = A.data();
  Index c = 0;
  for (; c + 4 <= k; c += 4) {
    const float *a0 = a + c * m, *a1 = a0 + m, *a2 = a1 + m, *a3 = a2 + m;
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
#pragma omp simd reduction(+ : s0, s1, s2, s3)
    for (Index r = 0; r < m; ++r) {
      s0 += static_cast<double>(a0[r]) * x[r];
      s1 += static_cast<double>(a1[r]) * x[r];
      s2 += static_cast<double>(a2[r]) * x[r];
      s3 += static_cast<double>(a3[r]) * x[r];
    }
    y[c] += s0, y[c + 1] += s1, y[c + 2] += s2, y[c + 3] += s3;
  }
  for (; c < k; ++c) {
    const float* a0 = a + c * m;
    double s0 = 0.0;
#pragma omp simd reduction(+ : s0)
    for (Index r = 0; r < m; ++r) s0 += static_cast<double>(a0[r]) * x[r];
    y[c] += s0;
  }
}

/// y += B x for a single-precision block B (transposed: tr), x and y double, column by
/// column of the right-hand sides; z: room for B's rank (the low-rank factors' product).
template <class In, class Out>
void accumulate_single(const HMatrix::Block& b, bool tr, const In& x, Out& y, std::vector<double>& z) {
  const Index rank = b.rank();
  if (b.low_rank && static_cast<Index>(z.size()) < rank) z.resize(static_cast<std::size_t>(rank));
  for (Index j = 0; j < x.cols(); ++j) {
    const double* xj = x.col(j).data();
    double* yj = y.col(j).data();
    if (!b.low_rank) {
      (tr ? add_transposed_product : add_product)(b.dense_single, xj, yj);
    } else if (rank > 0) {
      std::fill_n(z.begin(), rank, 0.0);
      add_transposed_product(tr ? b.u_single : b.v_single, xj, z.data());
      add_product(tr ? b.v_single : b.u_single, z.data(), yj);
    }
  }
}

/// The entries (rows, cols) of block b (its local indices: index lists or Eigen::all) in
/// double, from either storage.
template <class Rows, class Cols>
Eigen::MatrixXd block_entries(const HMatrix::Block& b, bool single, const Rows& rows, const Cols& cols) {
  if (single)
    return b.low_rank ? Eigen::MatrixXd(b.u_single(rows, Eigen::all).template cast<double>() *
                                        b.v_single(cols, Eigen::all).template cast<double>().transpose())
                      : Eigen::MatrixXd(b.dense_single(rows, cols).template cast<double>());
  return b.low_rank ? Eigen::MatrixXd(b.factors.U(rows, Eigen::all) * b.factors.V(cols, Eigen::all).transpose())
                    : Eigen::MatrixXd(b.dense(rows, cols));
}

void check_rows(Index got, Index expected, const char* what) {
  if (got != expected)
    throw std::invalid_argument(std::string("HMatrix::") + what + ": X has " + std::to_string(got) +
                                " rows, expected " + std::to_string(expected));
}

}  // namespace

std::vector<Index> distributed_row_bounds(const ClusterTree& rows, const ClusterTree& cols,
                                          const HMatrixOptions& options, int parts) {
  // Rows balanced by the bytes each will hold, ranks modelled as log10(1 / tol)
  // (docs/design/hmatrix.md, "Under MPI").
  std::vector<HMatrix::Block> all;
  collect(rows, cols, 0, 0, options.eta, options.min_distance, options.symmetric, 0, rows.size(), all);
  const double r = std::max(1.0, -std::log10(options.tol));
  std::vector<double> cost(static_cast<std::size_t>(rows.size()), 0.0);
  for (const HMatrix::Block& b : all) {
    const double per_row =
        b.low_rank ? r * (1.0 + static_cast<double>(b.k) / static_cast<double>(b.m)) : static_cast<double>(b.k);
    for (Index i = b.r0; i < b.r0 + b.m; ++i) cost[static_cast<std::size_t>(i)] += per_row;
  }
  return rows.partition(parts, cost);
}

HMatrix::HMatrix(std::shared_ptr<const ClusterTree> rows, std::shared_ptr<const ClusterTree> cols,
                 const EntrySource& entries, const HMatrixOptions& options, const std::vector<Index>& row_bounds)
    : HMatrix(std::move(rows), std::move(cols), options, row_bounds, Unfilled{}) {
  build(entries, options);
}

HMatrix::HMatrix(std::shared_ptr<const ClusterTree> rows, std::shared_ptr<const ClusterTree> cols,
                 const HMatrixOptions& options, const std::vector<Index>& row_bounds, Unfilled)
    : rows_(std::move(rows)),
      cols_(std::move(cols)),
      single_(options.single_precision),
      product_threads_(options.product_threads),
      comm_(options.comm) {
  row_end_ = rows_->size();
  if (comm_) {
    if (comm_->size < 1 || comm_->rank < 0 || comm_->rank >= comm_->size || !comm_->allgather || !comm_->allreduce)
      throw std::invalid_argument("HMatrix: the communicator needs 0 <= rank < size and both collectives");
    const std::vector<Index> bounds =
        row_bounds.empty() ? distributed_row_bounds(*rows_, *cols_, options, comm_->size) : row_bounds;
    if (static_cast<int>(bounds.size()) != comm_->size + 1 || bounds.front() != 0 || bounds.back() != rows_->size())
      throw std::invalid_argument("HMatrix: row_bounds need 0 = b_0 <= ... <= b_size = rows");
    row_begin_ = bounds[static_cast<std::size_t>(comm_->rank)];
    row_end_ = bounds[static_cast<std::size_t>(comm_->rank) + 1];
    row_counts_ = counts(bounds);
    col_counts_ = counts(cols_->partition(comm_->size));
    restricted_ = true;
  }
}

HMatrix::HMatrix(std::shared_ptr<const ClusterTree> rows, std::shared_ptr<const ClusterTree> cols,
                 const EntrySource& entries, const HMatrixOptions& options, Index row_begin, Index row_end)
    : rows_(std::move(rows)),
      cols_(std::move(cols)),
      single_(options.single_precision),
      restricted_(true),
      row_begin_(row_begin),
      row_end_(row_end),
      product_threads_(options.product_threads) {
  if (options.comm) throw std::invalid_argument("HMatrix: a row range or a communicator, not both");
  if (row_begin < 0 || row_begin > row_end || row_end > rows_->size())
    throw std::invalid_argument("HMatrix: need 0 <= row_begin <= row_end <= rows");
  build(entries, options);
}

void HMatrix::build(const EntrySource& entries, const HMatrixOptions& options) {
  plan(options);
  // a pair of mirrored dense blocks is one task (the first of the two in the build order)
  const std::vector<std::ptrdiff_t> mirror = mirrors();
  std::vector<std::size_t> order;
  std::vector<char> queued(blocks_.size(), 0);
  for (std::size_t b : build_order()) {
    const std::ptrdiff_t t = mirror[b];
    if (t >= 0 && queued[static_cast<std::size_t>(t)]) continue;
    queued[b] = 1;
    order.push_back(b);
  }
  const long count = static_cast<long>(order.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long q = 0; q < count; ++q) {
    const std::size_t i = order[static_cast<std::size_t>(q)];
    Block& b = blocks_[i];
    const std::unique_ptr<EntryBlock> e = entry_block(entries, b);
    if (mirror[i] >= 0) {
      Block& t = blocks_[static_cast<std::size_t>(mirror[i])];
      b.dense.resize(b.m, b.k);
      t.dense.resize(t.m, t.k);
      if (e->all_and_transpose(b.dense.data(), t.dense.data())) {
        hold(b);
        hold(t);
        continue;
      }
      fill(t, *entry_block(entries, t), 0, options);
    }
    fill(b, *e, 0, options);
  }
}

std::vector<std::ptrdiff_t> HMatrix::mirrors() const {
  std::vector<std::ptrdiff_t> mirror(blocks_.size(), -1);
  if (symmetric_ || rows_ != cols_) return mirror;
  std::map<std::pair<int, int>, std::size_t> dense;
  for (std::size_t b = 0; b < blocks_.size(); ++b)
    if (!blocks_[b].low_rank) dense[{blocks_[b].row_cluster, blocks_[b].col_cluster}] = b;
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const Block& x = blocks_[b];
    if (x.low_rank || x.row_cluster == x.col_cluster) continue;
    const auto t = dense.find({x.col_cluster, x.row_cluster});
    if (t != dense.end()) mirror[b] = static_cast<std::ptrdiff_t>(t->second);
  }
  return mirror;
}

void HMatrix::plan(const HMatrixOptions& options) {
  if (!(options.eta > 0) || !(options.tol > 0) || options.leaf_size < 1 || options.product_threads < 0)
    throw std::invalid_argument("HMatrix: need eta > 0, tol > 0, leaf_size >= 1, product_threads >= 0");
  if (options.symmetric && rows_ != cols_)
    throw std::invalid_argument("HMatrix: a symmetric matrix needs one cluster tree for rows and columns");
  symmetric_ = options.symmetric;
  collect(*rows_, *cols_, 0, 0, options.eta, options.min_distance, symmetric_, row_begin_, row_end_, blocks_,
          options.split_to_leaves);
}

std::vector<std::size_t> HMatrix::build_order() const {
  // Largest blocks first, so that the dynamic schedule ends with small ones.
  std::vector<std::size_t> order(blocks_.size());
  for (std::size_t b = 0; b < order.size(); ++b) order[b] = b;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return blocks_[a].m + blocks_[a].k > blocks_[b].m + blocks_[b].k;
  });
  return order;
}

std::unique_ptr<EntryBlock> HMatrix::entry_block(const EntrySource& entries, const Block& b) const {
  return entries.block(rows_->permutation().data() + b.r0, b.m, cols_->permutation().data() + b.c0, b.k);
}

void HMatrix::fill(Block& b, const EntryBlock& e, int which, const HMatrixOptions& options) const {
  const Index m = b.m, k = b.k;
  if (!b.low_rank) {
    b.dense.resize(m, k);
    if (which == 0)
      e.all(b.dense.data());
    else
      e.companion_all(which, b.dense.data());
  } else {
    if (which == 0) {
      const Slice row = [&e](Index i, double* out) { e.row(i, out); };
      const Slice column = [&e](Index j, double* out) { e.column(j, out); };
      if (!e.low_rank(options.tol, b.factors)) b.factors = aca(m, k, row, column, options.tol, std::min(m, k));
    } else if (!e.companion_low_rank(which, options.tol, b.factors)) {
      Eigen::MatrixXd A(m, k);
      e.companion_all(which, A.data());
      b.factors = LowRank{A, Eigen::MatrixXd::Identity(k, k)};
    }
    recompress(b.factors, options.tol);
    if (b.factors.rank() * (m + k) >= m * k) {  // dense is smaller
      b.dense = b.factors.U * b.factors.V.transpose();
      b.factors = LowRank{};
      b.low_rank = false;
    }
  }
  hold(b);
}

void HMatrix::hold(Block& b) const {
  const Index r0 = restricted_ ? std::max(b.r0, row_begin_) : b.r0;
  const Index r1 = restricted_ ? std::min(b.r0 + b.m, row_end_) : b.r0 + b.m;
  if (r0 != b.r0 || r1 != b.r0 + b.m) {
    if (b.low_rank)
      b.factors.U = Eigen::MatrixXd(b.factors.U.middleRows(r0 - b.r0, r1 - r0));
    else
      b.dense = Eigen::MatrixXd(b.dense.middleRows(r0 - b.r0, r1 - r0));
    b.r0 = r0;
    b.m = r1 - r0;
  }
  if (!single_) return;
  if (b.low_rank) {
    b.u_single = b.factors.U.cast<float>();
    b.v_single = b.factors.V.cast<float>();
    b.factors = LowRank{};
  } else {
    b.dense_single = b.dense.cast<float>();
    b.dense = Eigen::MatrixXd();
  }
}

std::vector<std::shared_ptr<const HMatrix>> HMatrix::family(std::shared_ptr<const ClusterTree> rows,
                                                            std::shared_ptr<const ClusterTree> cols,
                                                            const EntrySource& entries, int count,
                                                            const HMatrixOptions& options,
                                                            const std::vector<Index>& row_bounds) {
  if (count < 1) throw std::invalid_argument("HMatrix::family: need count >= 1");
  const std::vector<Index> bounds = row_bounds.empty() && options.comm && options.comm->size >= 1
                                        ? distributed_row_bounds(*rows, *cols, options, options.comm->size)
                                        : row_bounds;
  std::vector<std::shared_ptr<HMatrix>> out;
  for (int w = 0; w < count; ++w) {
    out.push_back(std::shared_ptr<HMatrix>(new HMatrix(rows, cols, options, bounds, Unfilled{})));
    out.back()->plan(options);
  }
  const HMatrix& first = *out.front();
  const std::vector<std::size_t> order = first.build_order();
  const long n = static_cast<long>(order.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long q = 0; q < n; ++q) {
    const std::size_t b = order[static_cast<std::size_t>(q)];
    // the block before fill() of the first matrix cuts it to the local rows
    const std::unique_ptr<EntryBlock> e = first.entry_block(entries, first.blocks_[b]);
    for (int w = 0; w < count; ++w)
      out[static_cast<std::size_t>(w)]->fill(out[static_cast<std::size_t>(w)]->blocks_[b], *e, w, options);
  }
  return {out.begin(), out.end()};
}

void HMatrix::accumulate(const Eigen::MatrixXd& Xp, Index in0, Index out0, bool transpose, Eigen::MatrixXd& Yp) const {
  const Index nrhs = Xp.cols();
  const int threads = product_threads_ > 0 ? product_threads_ : omp_get_max_threads();
  std::vector<Eigen::MatrixXd> partial(static_cast<std::size_t>(threads));
  const long count = static_cast<long>(blocks_.size());
#pragma omp parallel num_threads(threads)
  {
    Eigen::MatrixXd& Y = partial[static_cast<std::size_t>(omp_get_thread_num())];
    Y.setZero(Yp.rows(), nrhs);
    std::vector<double> z;  // single storage: a low-rank block's V^T x
#pragma omp for schedule(dynamic, 4)
    for (long q = 0; q < count; ++q) {
      const Block& b = blocks_[static_cast<std::size_t>(q)];
      // symmetric: an off-diagonal block also stands for its transpose below the diagonal
      const bool both = symmetric_ && b.row_cluster != b.col_cluster;
      for (int pass = 0; pass < (both ? 2 : 1); ++pass) {
        const bool tr = pass == 1 ? !transpose : transpose;
        const Index i0 = tr ? b.r0 : b.c0, n_in = tr ? b.m : b.k;
        const Index o0 = tr ? b.c0 : b.r0, n_o = tr ? b.k : b.m;
        const auto x = Xp.middleRows(i0 - (tr ? in0 : 0), n_in);
        auto y = Y.middleRows(o0 - (tr ? 0 : out0), n_o);
        if (single_) {
          accumulate_single(b, tr, x, y, z);
        } else if (!b.low_rank) {
          if (tr)
            y.noalias() += b.dense.transpose() * x;
          else
            y.noalias() += b.dense * x;
        } else if (b.factors.rank() > 0) {
          const Eigen::MatrixXd& in_f = tr ? b.factors.U : b.factors.V;
          const Eigen::MatrixXd& out_f = tr ? b.factors.V : b.factors.U;
          const Eigen::MatrixXd z = in_f.transpose() * x;
          y.noalias() += out_f * z;
        }
      }
    }
  }
  Yp = std::move(partial[0]);
  for (std::size_t t = 1; t < partial.size(); ++t) Yp += partial[t];
}

Eigen::MatrixXd HMatrix::apply_local(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  check_rows(X.rows(), cols_->size(), "apply_local");
  if (symmetric_) throw std::logic_error("HMatrix::apply_local: symmetric storage; use apply_partial");
  Eigen::MatrixXd Yp(row_end_ - row_begin_, X.cols());
  accumulate(permuted(X, *cols_), 0, row_begin_, false, Yp);
  return Yp;
}

Eigen::MatrixXd HMatrix::apply_partial(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) const {
  const ClusterTree& in_tree = transpose ? *rows_ : *cols_;
  const ClusterTree& out_tree = transpose ? *cols_ : *rows_;
  check_rows(X.rows(), in_tree.size(), "apply_partial");
  Eigen::MatrixXd Yp(out_tree.size(), X.cols());
  accumulate(permuted(X, in_tree), 0, 0, transpose, Yp);
  return Yp;
}

Eigen::MatrixXd HMatrix::apply(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) const {
  const ClusterTree& out_tree = transpose ? *cols_ : *rows_;
  check_rows(X.rows(), (transpose ? *rows_ : *cols_).size(), "apply");
  const bool whole = row_begin_ == 0 && row_end_ == rows_->size();
  if (!comm_) {
    if (!whole) throw std::logic_error("HMatrix::apply: a row-restricted matrix needs its communicator");
    return unpermuted(apply_partial(X, transpose), out_tree);
  }
  if (!transpose && !symmetric_) return unpermuted(comm_->allgather(apply_local(X), row_counts_), *rows_);
  const std::vector<Index>& counts = transpose ? col_counts_ : row_counts_;
  return unpermuted(comm_->allreduce(apply_partial(X, transpose), counts), out_tree);
}

Eigen::MatrixXd HMatrix::to_dense() const {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows(), cols());
  const std::vector<Index>& rp = rows_->permutation();
  const std::vector<Index>& cp = cols_->permutation();
  for (const Block& b : blocks_) {
    const Eigen::MatrixXd D = block_entries(b, single_, Eigen::all, Eigen::all);
    for (Index c = 0; c < b.k; ++c)
      for (Index r = 0; r < b.m; ++r)
        A(rp[static_cast<std::size_t>(b.r0 + r)], cp[static_cast<std::size_t>(b.c0 + c)]) = D(r, c);
    if (symmetric_ && b.row_cluster != b.col_cluster)
      for (Index c = 0; c < b.k; ++c)
        for (Index r = 0; r < b.m; ++r)
          A(cp[static_cast<std::size_t>(b.c0 + c)], rp[static_cast<std::size_t>(b.r0 + r)]) = D(r, c);
  }
  return A;
}

template <typename Scalar>
Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> HMatrix::principal_submatrix(
    const std::vector<Index>& indices) const {
  using Dense = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  const Index m = static_cast<Index>(indices.size());
  if (rows() != cols()) throw std::invalid_argument("HMatrix::principal_submatrix: the matrix is not square");
  // The block is written in the trees' order first: the selected rows (columns) of a block are
  // consecutive there, so each block lands as one contiguous sub-block (the scattered writes
  // of the callers' order missed the cache on every entry: 25 s for 16,129^2 entries), then
  // put into the callers' order in place, one column at a time.
  std::vector<Index> row_rank(static_cast<std::size_t>(rows()), -1), col_rank(row_rank);
  std::vector<Index> inverse_rows(static_cast<std::size_t>(rows())), inverse_cols(inverse_rows);
  const std::vector<Index>& rp = rows_->permutation();
  const std::vector<Index>& cp = cols_->permutation();
  for (std::size_t i = 0; i < rp.size(); ++i) inverse_rows[static_cast<std::size_t>(rp[i])] = static_cast<Index>(i);
  for (std::size_t i = 0; i < cp.size(); ++i) inverse_cols[static_cast<std::size_t>(cp[i])] = static_cast<Index>(i);
  for (const Index i : indices) {
    if (i < 0 || i >= rows()) throw std::invalid_argument("HMatrix::principal_submatrix: an index is out of range");
    Index& mark = row_rank[static_cast<std::size_t>(inverse_rows[static_cast<std::size_t>(i)])];
    if (mark != -1) throw std::invalid_argument("HMatrix::principal_submatrix: an index appears twice");
    mark = 0;
    col_rank[static_cast<std::size_t>(inverse_cols[static_cast<std::size_t>(i)])] = 0;
  }
  // rank = the place of a selected tree position among the selected ones, in the trees' order
  for (std::vector<Index>* rank : {&row_rank, &col_rank}) {
    Index next = 0;
    for (Index& r : *rank)
      if (r == 0) r = next++;
  }
  Dense A = Dense::Zero(m, m);
  std::vector<Index> r_local, c_local;
  for (const Block& b : blocks_) {
    r_local.clear(), c_local.clear();
    for (Index r = 0; r < b.m; ++r)
      if (row_rank[static_cast<std::size_t>(b.r0 + r)] >= 0) r_local.push_back(r);
    if (r_local.empty()) continue;
    for (Index c = 0; c < b.k; ++c)
      if (col_rank[static_cast<std::size_t>(b.c0 + c)] >= 0) c_local.push_back(c);
    if (c_local.empty()) continue;
    const Index r_first = row_rank[static_cast<std::size_t>(b.r0 + r_local.front())];
    const Index c_first = col_rank[static_cast<std::size_t>(b.c0 + c_local.front())];
    const Index nr = static_cast<Index>(r_local.size()), nc = static_cast<Index>(c_local.size());
    const Eigen::MatrixXd D = block_entries(b, single_, r_local, c_local);
    A.block(r_first, c_first, nr, nc) = D.template cast<Scalar>();
    // symmetric storage has one tree: row and column ranks agree
    if (symmetric_ && b.row_cluster != b.col_cluster)
      A.block(c_first, r_first, nc, nr) = D.transpose().template cast<Scalar>();
  }
  // to the callers' order: A(a, b) <- A(row_of[a], col_of[b])
  std::vector<Index> row_of(static_cast<std::size_t>(m)), col_of(row_of);
  for (Index a = 0; a < m; ++a) {
    const auto i = static_cast<std::size_t>(indices[static_cast<std::size_t>(a)]);
    row_of[static_cast<std::size_t>(a)] = row_rank[static_cast<std::size_t>(inverse_rows[i])];
    col_of[static_cast<std::size_t>(a)] = col_rank[static_cast<std::size_t>(inverse_cols[i])];
  }
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> column(m);
  for (Index j = 0; j < m; ++j) {
    column = A.col(j);
    A.col(j) = column(row_of);
  }
  std::vector<bool> placed(static_cast<std::size_t>(m), false);
  for (Index start = 0; start < m; ++start) {  // the column permutation, cycle by cycle
    if (placed[static_cast<std::size_t>(start)]) continue;
    column = A.col(start);
    Index j = start;
    for (;;) {
      placed[static_cast<std::size_t>(j)] = true;
      const Index from = col_of[static_cast<std::size_t>(j)];
      if (from == start) {
        A.col(j) = column;
        break;
      }
      A.col(j) = A.col(from);
      j = from;
    }
  }
  return A;
}

template Eigen::MatrixXd HMatrix::principal_submatrix<double>(const std::vector<Index>&) const;
template Eigen::MatrixXf HMatrix::principal_submatrix<float>(const std::vector<Index>&) const;

std::size_t HMatrix::nbytes() const {
  std::size_t doubles = 0, singles = 0;
  for (const Block& b : blocks_) {
    doubles += static_cast<std::size_t>(b.dense.size() + b.factors.U.size() + b.factors.V.size());
    singles += static_cast<std::size_t>(b.dense_single.size() + b.u_single.size() + b.v_single.size());
  }
  return doubles * sizeof(double) + singles * sizeof(float) +
         (rows_->permutation().size() + cols_->permutation().size()) * sizeof(Index) + blocks_.size() * sizeof(Block);
}

Index HMatrix::max_rank() const {
  Index r = 0;
  for (const Block& b : blocks_) r = std::max(r, b.rank());
  return r;
}

}  // namespace bem
