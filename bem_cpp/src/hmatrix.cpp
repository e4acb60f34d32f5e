#include "bem/hmatrix.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include <omp.h>

namespace bem {

namespace {

void collect(const ClusterTree& rows, const ClusterTree& cols, int t, int s, double eta,
             bool upper, std::vector<HMatrix::Block>& out) {
  const Cluster& ct = rows.cluster(t);
  const Cluster& cs = cols.cluster(s);
  // Symmetric: cluster ranges are nested or disjoint, so t starting after s (disjoint)
  // puts the whole subtree of (t, s) below the block diagonal.
  if (upper && ct.begin > cs.begin && ct.begin >= cs.end) return;
  const bool adm = admissible(ct.box, cs.box, eta);
  if (adm || ct.leaf() || cs.leaf()) {
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
  for (int a : ct.children)
    for (int c : cs.children) collect(rows, cols, a, c, eta, upper, out);
}

}  // namespace

HMatrix::HMatrix(std::shared_ptr<const ClusterTree> rows, std::shared_ptr<const ClusterTree> cols,
                 const EntrySource& entries, const HMatrixOptions& options)
    : rows_(std::move(rows)), cols_(std::move(cols)), symmetric_(options.symmetric),
      product_threads_(options.product_threads) {
  if (!(options.eta > 0) || !(options.tol > 0) || options.leaf_size < 1 || options.product_threads < 0)
    throw std::invalid_argument("HMatrix: need eta > 0, tol > 0, leaf_size >= 1, product_threads >= 0");
  if (symmetric_ && rows_ != cols_)
    throw std::invalid_argument("HMatrix: a symmetric matrix needs one cluster tree for rows and columns");
  collect(*rows_, *cols_, 0, 0, options.eta, symmetric_, blocks_);
  const Index* rp = rows_->permutation().data();
  const Index* cp = cols_->permutation().data();
  // Largest blocks first, so that the dynamic schedule ends with small ones.
  std::vector<std::size_t> order(blocks_.size());
  for (std::size_t b = 0; b < order.size(); ++b) order[b] = b;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return blocks_[a].m + blocks_[a].k > blocks_[b].m + blocks_[b].k;
  });
  const long count = static_cast<long>(order.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long q = 0; q < count; ++q) {
    Block& b = blocks_[order[static_cast<std::size_t>(q)]];
    const Index* I = rp + b.r0;
    const Index* J = cp + b.c0;
    const std::unique_ptr<EntryBlock> e = entries.block(I, b.m, J, b.k);
    if (!b.low_rank) {
      b.dense.resize(b.m, b.k);
      e->all(b.dense.data());
      continue;
    }
    const Slice row = [&e](Index i, double* out) { e->row(i, out); };
    const Slice column = [&e](Index j, double* out) { e->column(j, out); };
    b.factors = aca(b.m, b.k, row, column, options.tol, std::min(b.m, b.k));
    recompress(b.factors, options.tol);
    if (b.factors.rank() * (b.m + b.k) >= b.m * b.k) {  // dense is smaller
      b.dense = b.factors.U * b.factors.V.transpose();
      b.factors = LowRank{};
      b.low_rank = false;
    }
  }
}

Eigen::MatrixXd HMatrix::apply(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) const {
  const ClusterTree& in_tree = transpose ? *rows_ : *cols_;
  const ClusterTree& out_tree = transpose ? *cols_ : *rows_;
  if (X.rows() != in_tree.size())
    throw std::invalid_argument("HMatrix::apply: X has " + std::to_string(X.rows()) +
                                " rows, expected " + std::to_string(in_tree.size()));
  const Index nrhs = X.cols(), n_out = out_tree.size();
  Eigen::MatrixXd Xp(X.rows(), nrhs);
  const std::vector<Index>& pin = in_tree.permutation();
  for (Index r = 0; r < X.rows(); ++r) Xp.row(r) = X.row(pin[static_cast<std::size_t>(r)]);
  const int threads = product_threads_ > 0 ? product_threads_ : omp_get_max_threads();
  std::vector<Eigen::MatrixXd> partial(static_cast<std::size_t>(threads));
  const long count = static_cast<long>(blocks_.size());
#pragma omp parallel num_threads(threads)
  {
    Eigen::MatrixXd& Y = partial[static_cast<std::size_t>(omp_get_thread_num())];
    Y.setZero(n_out, nrhs);
#pragma omp for schedule(dynamic, 4)
    for (long q = 0; q < count; ++q) {
      const Block& b = blocks_[static_cast<std::size_t>(q)];
      // symmetric: an off-diagonal block also stands for its transpose below the diagonal
      const bool both = symmetric_ && b.r0 != b.c0;
      for (int pass = 0; pass < (both ? 2 : 1); ++pass) {
        const bool tr = pass == 1 ? !transpose : transpose;
        const Index in0 = tr ? b.r0 : b.c0, n_in = tr ? b.m : b.k;
        const Index out0 = tr ? b.c0 : b.r0, n_o = tr ? b.k : b.m;
        const auto x = Xp.middleRows(in0, n_in);
        auto y = Y.middleRows(out0, n_o);
        if (!b.low_rank) {
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
  for (std::size_t t = 1; t < partial.size(); ++t) partial[0] += partial[t];
  Eigen::MatrixXd Y(n_out, nrhs);
  const std::vector<Index>& pout = out_tree.permutation();
  for (Index r = 0; r < n_out; ++r) Y.row(pout[static_cast<std::size_t>(r)]) = partial[0].row(r);
  return Y;
}

Eigen::MatrixXd HMatrix::to_dense() const {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows(), cols());
  const std::vector<Index>& rp = rows_->permutation();
  const std::vector<Index>& cp = cols_->permutation();
  for (const Block& b : blocks_) {
    const Eigen::MatrixXd D = b.low_rank ? Eigen::MatrixXd(b.factors.U * b.factors.V.transpose()) : b.dense;
    for (Index c = 0; c < b.k; ++c)
      for (Index r = 0; r < b.m; ++r)
        A(rp[static_cast<std::size_t>(b.r0 + r)], cp[static_cast<std::size_t>(b.c0 + c)]) = D(r, c);
    if (symmetric_ && b.r0 != b.c0)
      for (Index c = 0; c < b.k; ++c)
        for (Index r = 0; r < b.m; ++r)
          A(cp[static_cast<std::size_t>(b.c0 + c)], rp[static_cast<std::size_t>(b.r0 + r)]) = D(r, c);
  }
  return A;
}

std::size_t HMatrix::nbytes() const {
  std::size_t entries = 0;
  for (const Block& b : blocks_)
    entries += static_cast<std::size_t>(b.dense.size() + b.factors.U.size() + b.factors.V.size());
  return entries * sizeof(double) +
         (rows_->permutation().size() + cols_->permutation().size()) * sizeof(Index) +
         blocks_.size() * sizeof(Block);
}

Index HMatrix::max_rank() const {
  Index r = 0;
  for (const Block& b : blocks_) r = std::max(r, b.factors.rank());
  return r;
}

}  // namespace bem
