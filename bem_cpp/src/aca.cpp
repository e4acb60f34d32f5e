#include "bem/aca.hpp"

#include "bem/linear_algebra.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace bem {

namespace {

/// argmax |x[i]| over i < n with !used[i] (the first of equal ones); -1 if all are used.
/// The absolute value of a finite double orders as its bits do as an integer, so the
/// largest key and then its first index are integer max and min reductions, which
/// vectorise (a comparison of doubles with an index does not).
Index unused_argmax(const double* x, Index n, const std::vector<char>& used) {
  constexpr std::int64_t kAbs = 0x7FFFFFFFFFFFFFFF;
  auto key = [x, &used](Index i) {
    std::int64_t bits;
    std::memcpy(&bits, x + i, sizeof bits);
    return used[static_cast<std::size_t>(i)] ? std::int64_t{-1} : bits & kAbs;
  };
  std::int64_t top = -1;
  for (Index i = 0; i < n; ++i) {
    const std::int64_t k = key(i);
    top = k > top ? k : top;
  }
  if (top < 0) return -1;
  Index first = n;
  for (Index i = 0; i < n; ++i) {
    const Index at = key(i) == top ? i : n;
    first = at < first ? at : first;
  }
  return first;
}

/// The crosses u_k v_k^T found so far, as the columns of two matrices (grown by doubling),
/// so that the residuals and the norm update are matrix-vector products.
class Cross {
 public:
  /// capacity: the columns held before the first doubling.
  Cross(Index m, Index n, const Slice& row, const Slice& column, Index capacity)
      : m_(m),
        n_(n),
        row_(row),
        column_(column),
        row_used_(m, 0),
        col_used_(n, 0),
        U_(m, std::max<Index>(capacity, 1)),
        V_(n, std::max<Index>(capacity, 1)),
        r_(n),
        c_(m) {}

  /// The residual of row i (of column j), in a buffer of the Cross kept until the next call.
  const Eigen::VectorXd& residual_row(Index i) {
    row_(i, r_.data());
    subtract(V_, U_.row(i), r_, gr_);
    return r_;
  }
  const Eigen::VectorXd& residual_column(Index j) {
    column_(j, c_.data());
    subtract(U_, V_.row(j), c_, gc_);
    return c_;
  }
  /// Adds u v^T, u the last residual column and v the last residual row over `pivot`, and
  /// updates |U V^T|_F^2 (the cross term from the products taken with the residuals).
  void add(double pivot) {
    if (k_ == U_.cols()) {
      U_.conservativeResize(Eigen::NoChange, 2 * k_);
      V_.conservativeResize(Eigen::NoChange, 2 * k_);
    }
    U_.col(k_) = c_;
    V_.col(k_) = r_ / pivot;
    const auto v = V_.col(k_);
    const double cross = k_ > 0 ? gc_.head(k_).dot(gr_.head(k_)) / pivot : 0.0;
    norm2_ += c_.squaredNorm() * v.squaredNorm() + 2.0 * cross;
    ++k_;
  }
  double norm() const { return std::sqrt(std::max(norm2_, 0.0)); }
  Index rank() const { return k_; }
  auto last_u() const { return U_.col(k_ - 1); }
  auto last_v() const { return V_.col(k_ - 1); }
  std::vector<char>& row_used() { return row_used_; }
  std::vector<char>& col_used() { return col_used_; }

  LowRank result() const {
    LowRank a;
    a.U = U_.leftCols(k_);
    a.V = V_.leftCols(k_);
    return a;
  }

 private:
  Index m_, n_;
  const Slice& row_;
  const Slice& column_;
  std::vector<char> row_used_, col_used_;
  /// y -= F_k w (F_k: the first k_ columns of F, w: the k_ first entries of `row`) and
  /// g = F_k^T y, row chunk by row chunk, so that F_k is read once for both products (the
  /// factors of the large blocks are larger than the cache).
  template <typename Row>
  void subtract(const Eigen::MatrixXd& F, const Row& row, Eigen::VectorXd& y, Eigen::VectorXd& g) {
    if (k_ == 0) return;
    constexpr Index kChunk = 128;  // rows: 128 x 32 doubles fit the first-level cache
    w_ = row.head(k_).transpose();
    const auto w = w_.head(k_);
    if (g.size() < k_) g.resize(F.cols());
    g.head(k_).setZero();
    for (Index r0 = 0; r0 < y.size(); r0 += kChunk) {
      const Index rows = std::min(kChunk, y.size() - r0);
      const auto Fc = F.block(r0, 0, rows, k_);
      auto yc = y.segment(r0, rows);
      yc.noalias() -= Fc * w;
      g.head(k_).noalias() += Fc.transpose() * yc;
    }
  }
  Eigen::MatrixXd U_, V_;
  Eigen::VectorXd r_, c_;    ///< the last residual row and column
  Eigen::VectorXd gr_, gc_;  ///< V_k^T r_ and U_k^T c_
  Eigen::VectorXd w_;        ///< subtract's row
  Index k_ = 0;
  double norm2_ = 0.0;
};

constexpr int kSamples = 1;       // sampled rows and columns confirming the stop
constexpr int kZeroRowTries = 3;  // consecutive zero rows before the samples decide

}  // namespace

Index next_unused(const std::vector<char>& used, Index from) {
  const Index m = static_cast<Index>(used.size());
  for (Index d = 0; d < m; ++d) {
    const Index i = (from + d) % m;
    if (!used[static_cast<std::size_t>(i)]) return i;
  }
  return -1;
}

LowRank aca(Index m, Index n, const Slice& row, const Slice& column, double tol, Index max_rank) {
  max_rank = std::min({max_rank, m, n});
  // room for the ranks of the surface blocks' point kernels (20 to 45 at tol 3e-7) without
  // growing; larger ranks double it
  Cross x(m, n, row, column, std::min<Index>(max_rank, 32));
  std::uint64_t seed =
      0x9E3779B97F4A7C15ULL ^ (static_cast<std::uint64_t>(m) * 1315423911ULL + static_cast<std::uint64_t>(n));
  auto random_index = [&seed](Index size) {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<Index>((seed >> 33) % static_cast<std::uint64_t>(size));
  };
  Index i = m / 2;
  int zero_rows = 0;
  while (x.rank() < max_rank) {
    bool stop = false;
    if (i >= 0) {
      const Eigen::VectorXd& r = x.residual_row(i);
      x.row_used()[static_cast<std::size_t>(i)] = 1;
      const Index j = unused_argmax(r.data(), n, x.col_used());
      if (j < 0 || r(j) == 0.0) {
        i = ++zero_rows > kZeroRowTries ? -1 : next_unused(x.row_used(), i + m / 3 + 1);
        stop = i < 0;
      } else {
        zero_rows = 0;
        x.residual_column(j);
        x.col_used()[static_cast<std::size_t>(j)] = 1;
        x.add(r(j));
        stop = x.last_u().norm() * x.last_v().norm() <= tol * x.norm();
        i = unused_argmax(x.last_u().data(), m, x.row_used());
        if (i < 0) stop = true;
      }
    } else {
      stop = true;
    }
    if (!stop) continue;
    // Confirm on sampled columns and rows: a residual whose norm, scaled to the block,
    // fails the test gives the next cross.
    bool found = false;
    for (int s = 0; s < kSamples && !found && x.rank() < max_rank; ++s) {
      const Index j = random_index(n);
      const Eigen::VectorXd& c = x.residual_column(j);
      if (c.norm() * std::sqrt(static_cast<double>(n)) > tol * x.norm() && c.cwiseAbs().maxCoeff() > 0) {
        Index p;
        c.cwiseAbs().maxCoeff(&p);
        const Eigen::VectorXd& r = x.residual_row(p);
        if (r(j) == 0.0) continue;
        x.row_used()[static_cast<std::size_t>(p)] = 1;
        x.col_used()[static_cast<std::size_t>(j)] = 1;
        x.add(r(j));
        found = true;
      }
      const Index q = random_index(m);
      if (found || x.rank() >= max_rank) break;
      const Eigen::VectorXd& r = x.residual_row(q);
      if (r.norm() * std::sqrt(static_cast<double>(m)) > tol * x.norm() && r.cwiseAbs().maxCoeff() > 0) {
        Index p;
        r.cwiseAbs().maxCoeff(&p);
        if (x.residual_column(p)(q) == 0.0) continue;
        x.row_used()[static_cast<std::size_t>(q)] = 1;
        x.col_used()[static_cast<std::size_t>(p)] = 1;
        x.add(r(p));
        found = true;
      }
    }
    if (!found) break;
    zero_rows = 0;
    i = unused_argmax(x.last_u().data(), m, x.row_used());
  }
  return x.result();
}

void recompress(LowRank& a, double tol) {
  const Index k = a.rank(), m = a.U.rows(), n = a.V.rows();
  if (k == 0) return;
  Eigen::HouseholderQR<Eigen::MatrixXd> qu(a.U), qv(a.V);
  const Index ku = std::min(m, k), kv = std::min(n, k);
  const Eigen::MatrixXd ru = qu.matrixQR().topRows(ku).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd rv = qv.matrixQR().topRows(kv).triangularView<Eigen::Upper>();
  const ThinSvd svd = thin_svd(ru * rv.transpose());
  const Eigen::VectorXd& s = svd.s;
  const double total = s.squaredNorm();
  Index r = s.size();
  double tail = 0.0;
  while (r > 0 && tail + s(r - 1) * s(r - 1) <= tol * tol * total) {
    tail += s(r - 1) * s(r - 1);
    --r;
  }
  // Q [X; 0] by the Householder reflectors applied to the r columns, not Q formed (m x k)
  a.U.setZero(m, r);
  a.U.topRows(ku) = svd.U.leftCols(r) * s.head(r).asDiagonal();
  a.U.applyOnTheLeft(qu.householderQ());
  a.V.setZero(n, r);
  a.V.topRows(kv) = svd.V.leftCols(r);
  a.V.applyOnTheLeft(qv.householderQ());
}

}  // namespace bem
