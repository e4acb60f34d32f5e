#include "bem/grouped_aca.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace bem {

namespace {

/// The members of each group: index i's group is members_[start_[g], start_[g + 1]) with
/// g = of_[i].
class Groups {
 public:
  explicit Groups(const std::vector<Index>& group) : of_(group.size()) {
    std::vector<std::pair<Index, Index>> order(group.size());  // (group, index)
    for (std::size_t i = 0; i < group.size(); ++i) order[i] = {group[i], static_cast<Index>(i)};
    std::sort(order.begin(), order.end());
    for (std::size_t k = 0; k < order.size(); ++k) {
      if (k == 0 || order[k].first != order[k - 1].first) start_.push_back(k);
      members_.push_back(order[k].second);
      of_[static_cast<std::size_t>(order[k].second)] = start_.size() - 1;
    }
    start_.push_back(order.size());
  }
  /// The members of i's group, i first, into out.
  void with(Index i, std::vector<Index>& out) const {
    out.assign(1, i);
    const std::size_t g = of_[static_cast<std::size_t>(i)];
    for (std::size_t k = start_[g]; k < start_[g + 1]; ++k)
      if (members_[k] != i) out.push_back(members_[k]);
  }

 private:
  std::vector<Index> members_;
  std::vector<std::size_t> start_, of_;
};

/// x^T y and |x| as plain loops (Eigen's AVX-512 reductions draw GCC 12's false
/// -Wmaybe-uninitialized warnings).
template <class A, class B>
double dot(const A& x, const B& y) {
  double s = 0.0;
  for (Index i = 0; i < x.size(); ++i) s += x(i) * y(i);
  return s;
}
template <class A>
double norm(const A& x) {
  return std::sqrt(dot(x, x));
}

/// The crosses found so far, U V^T (columns of m and n values in buffers of the calling
/// thread, kept from call to call: fresh large allocations for every block cost more in
/// page faults than the arithmetic, about 12 % of a set-up).
class Crosses {
 public:
  Crosses(Index m, Index n) : m_(m), n_(n), U_(buffer(0)), V_(buffer(1)) {}
  Index rank() const { return k_; }
  /// r := r - (U V^T)(i, :) and gr := V^T r (c := c - (U V^T)(:, j), gc := U^T c): one
  /// pass over the factor, chunk by chunk (the projections give add()'s cross term).
  void residual_row(Index i, Eigen::VectorXd& r, Eigen::VectorXd& gr) const { subtract(V_, n_, U_, m_, i, r, gr); }
  void residual_column(Index j, Eigen::VectorXd& c, Eigen::VectorXd& gc) const { subtract(U_, m_, V_, n_, j, c, gc); }
  /// Adds c (r / pivot)^T for the residual column c and row r of the last residual_column
  /// and residual_row (projections gc, gr) and updates |U V^T|_F^2; returns |c| |r / pivot|.
  double add(const Eigen::VectorXd& c, const Eigen::VectorXd& r, double pivot, const Eigen::VectorXd& gc,
             const Eigen::VectorXd& gr) {
    if (U_.size() < static_cast<std::size_t>((k_ + 1) * m_)) U_.resize(static_cast<std::size_t>(2 * (k_ + 1) * m_));
    if (V_.size() < static_cast<std::size_t>((k_ + 1) * n_)) V_.resize(static_cast<std::size_t>(2 * (k_ + 1) * n_));
    double cross = 0.0;
    for (Index l = 0; l < k_; ++l) cross += gc(l) * gr(l);
    cross /= pivot;
    const double uv = std::sqrt(dot(c, c) * dot(r, r)) / std::abs(pivot);
    norm2_ += uv * uv + 2.0 * cross;
    std::copy_n(c.data(), m_, U_.data() + k_ * m_);
    double* v = V_.data() + k_ * n_;
    for (Index q = 0; q < n_; ++q) v[q] = r(q) / pivot;
    ++k_;
    return uv;
  }
  double norm() const { return std::sqrt(std::max(norm2_, 0.0)); }
  Eigen::Map<const Eigen::VectorXd> last_u() const { return u(k_ - 1); }
  LowRank result() const {
    return LowRank{Eigen::Map<const Eigen::MatrixXd>(U_.data(), m_, k_),
                   Eigen::Map<const Eigen::MatrixXd>(V_.data(), n_, k_)};
  }

 private:
  static std::vector<double>& buffer(int which) {
    thread_local std::vector<double> b[2];  // one ACA at a time per thread
    return b[which];
  }
  Eigen::Map<const Eigen::VectorXd> u(Index l) const { return {U_.data() + l * m_, m_}; }
  /// y := y - F w, g := F^T y (after), F the len x k_ factor, w_l = other(at, l).
  void subtract(const std::vector<double>& F, Index len, const std::vector<double>& other, Index other_len, Index at,
                Eigen::VectorXd& y, Eigen::VectorXd& g) const {
    g.setZero(std::max<Index>(k_, 1));
    if (k_ == 0) return;
    w_.resize(static_cast<std::size_t>(k_));
    for (Index l = 0; l < k_; ++l)
      w_[static_cast<std::size_t>(l)] = other[static_cast<std::size_t>(l * other_len + at)];
    constexpr Index kChunk = 256;  // rows of the factor: 256 x k doubles stay in the cache
    double* yd = y.data();
    for (Index r0 = 0; r0 < len; r0 += kChunk) {
      const Index r1 = std::min(len, r0 + kChunk);
      for (Index l = 0; l < k_; ++l) {
        const double* f = F.data() + l * len;
        const double wl = w_[static_cast<std::size_t>(l)];
#pragma omp simd
        for (Index q = r0; q < r1; ++q) yd[q] -= wl * f[q];
      }
      for (Index l = 0; l < k_; ++l) {
        const double* f = F.data() + l * len;
        double sum = 0.0;
#pragma omp simd reduction(+ : sum)
        for (Index q = r0; q < r1; ++q) sum += f[q] * yd[q];
        g(l) += sum;
      }
    }
  }
  Index m_, n_;
  std::vector<double>& U_;
  std::vector<double>& V_;
  Index k_ = 0;
  double norm2_ = 0.0;
  mutable std::vector<double> w_;
};

/// argmax |x[i]| over the unused i (the first of equal ones); -1 if all are used.
template <class X>
Index unused_argmax(const X& x, const std::vector<char>& used) {
  Index best = -1;
  double top = -1.0;
  for (Index i = 0; i < x.size(); ++i)
    if (!used[static_cast<std::size_t>(i)] && std::abs(x(i)) > top) {
      top = std::abs(x(i));
      best = i;
    }
  return best;
}

constexpr int kZeroGroupTries = 3;  // consecutive groups without a cross before the samples decide

}  // namespace

LowRank grouped_aca(Index m, Index n, const std::vector<Index>& row_group, const std::vector<Index>& column_group,
                    const Slice& row, const Slice& column, double tol, Index max_rank, int samples) {
  if (static_cast<Index>(row_group.size()) != m || static_cast<Index>(column_group.size()) != n)
    throw std::invalid_argument("grouped_aca: one group per row and per column");
  max_rank = std::min({max_rank, m, n});
  const Groups rows(row_group), cols(column_group);
  Crosses x(m, n);
  std::vector<char> row_used(static_cast<std::size_t>(m), 0), col_used(static_cast<std::size_t>(n), 0);
  Eigen::VectorXd r(n), c(m), gr, gc;
  std::vector<Index> group;
  std::uint64_t seed =
      0x9E3779B97F4A7C15ULL ^ (static_cast<std::uint64_t>(m) * 1315423911ULL + static_cast<std::uint64_t>(n));
  auto random_index = [&seed](Index size) {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<Index>((seed >> 33) % static_cast<std::uint64_t>(size));
  };
  // The cross of residual row i with its largest unused entry's column (0 if none):
  // returns |u| |v|, or -1 if the residual row is zero.
  auto cross_of_row = [&](Index i) -> double {
    row(i, r.data());
    x.residual_row(i, r, gr);
    row_used[static_cast<std::size_t>(i)] = 1;
    const Index j = unused_argmax(r, col_used);
    if (j < 0 || r(j) == 0.0) return -1.0;
    column(j, c.data());
    x.residual_column(j, c, gc);
    col_used[static_cast<std::size_t>(j)] = 1;
    return x.add(c, r, r(j), gc, gr);
  };
  // The same from column j (the pivot row is its largest entry's); -1 if it is zero.
  auto cross_of_column = [&](Index j) -> double {
    column(j, c.data());
    x.residual_column(j, c, gc);
    const Index i = unused_argmax(c, row_used);
    if (i < 0 || c(i) == 0.0) return -1.0;
    row(i, r.data());
    x.residual_row(i, r, gr);
    if (r(j) == 0.0) return -1.0;
    row_used[static_cast<std::size_t>(i)] = 1;
    col_used[static_cast<std::size_t>(j)] = 1;
    return x.add(c, r, r(j), gc, gr);
  };

  Index i = m / 2;
  int empty_groups = 0;
  while (x.rank() < max_rank) {
    bool stop = false;
    if (i >= 0) {
      double group2 = 0.0;
      int added = 0;
      rows.with(i, group);
      for (Index k : group) {
        if (row_used[static_cast<std::size_t>(k)] || x.rank() >= max_rank) continue;
        const double uv = cross_of_row(k);
        if (uv < 0) continue;
        group2 += uv * uv;
        ++added;
      }
      if (added == 0) {
        i = ++empty_groups > kZeroGroupTries ? -1 : next_unused(row_used, i + m / 3 + 1);
        stop = i < 0;
      } else {
        empty_groups = 0;
        stop = std::sqrt(group2) <= tol * x.norm();
        i = unused_argmax(x.last_u(), row_used);
        if (i < 0) stop = true;
      }
    } else {
      stop = true;
    }
    if (!stop || x.rank() >= max_rank) continue;
    // Confirm on `samples` sampled groups of columns and of rows, alternately: a residual
    // whose norm, scaled to the block, fails the test gives the next cross.
    bool found = false;
    // whether residual row (by_row) or column k, its norm scaled to the block, fails the test
    auto fails = [&](bool by_row, Index k) {
      if (by_row) {
        row(k, r.data());
        x.residual_row(k, r, gr);
        return norm(r) * std::sqrt(static_cast<double>(m)) > tol * x.norm();
      }
      column(k, c.data());
      x.residual_column(k, c, gc);
      return norm(c) * std::sqrt(static_cast<double>(n)) > tol * x.norm();
    };
    for (int s = 0; s < samples && !found && x.rank() < max_rank; ++s)
      for (const bool by_row : {false, true}) {  // a group of columns, then one of rows
        (by_row ? rows : cols).with(random_index(by_row ? m : n), group);
        for (Index k : group) {
          if (found || x.rank() >= max_rank) break;
          if (!fails(by_row, k)) continue;
          found = (by_row ? cross_of_row(k) : cross_of_column(k)) >= 0;
        }
      }
    if (!found) break;
    empty_groups = 0;
    i = unused_argmax(x.last_u(), row_used);
  }
  return x.result();
}

namespace {

class SampledAcaBlock : public EntryBlock {
 public:
  SampledAcaBlock(std::unique_ptr<EntryBlock> block, Index m, Index k, int samples)
      : block_(std::move(block)), m_(m), k_(k), samples_(samples) {}
  void row(Index i, double* out) const override { block_->row(i, out); }
  void column(Index j, double* out) const override { block_->column(j, out); }
  void all(double* out) const override { block_->all(out); }
  bool all_and_transpose(double* out, double* transposed) const override {
    return block_->all_and_transpose(out, transposed);
  }
  bool low_rank(double tol, LowRank& out) const override {
    std::vector<Index> rg(static_cast<std::size_t>(m_)), cg(static_cast<std::size_t>(k_));
    for (Index r = 0; r < m_; ++r) rg[static_cast<std::size_t>(r)] = r;
    for (Index c = 0; c < k_; ++c) cg[static_cast<std::size_t>(c)] = c;
    const Slice row = [this](Index i, double* o) { block_->row(i, o); };
    const Slice column = [this](Index j, double* o) { block_->column(j, o); };
    out = grouped_aca(m_, k_, rg, cg, row, column, tol, std::min(m_, k_), samples_);
    return true;
  }

 private:
  std::unique_ptr<EntryBlock> block_;
  Index m_, k_;
  int samples_;
};

}  // namespace

std::unique_ptr<EntryBlock> SampledAcaEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<SampledAcaBlock>(source_.block(I, m, J, k), m, k, samples_);
}

}  // namespace bem
