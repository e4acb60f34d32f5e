#include "bem/sparse_cholesky.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <new>
#include <stdexcept>
#include <string>

// Fortran LAPACK/BLAS symbols (LP64), as in linear_algebra.cpp.
extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m, const int* n,
            const double* alpha, const double* a, const int* lda, double* b, const int* ldb, std::size_t, std::size_t,
            std::size_t, std::size_t);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha, const double* a,
            const int* lda, const double* beta, double* c, const int* ldc, std::size_t, std::size_t);
void dtrsv_(const char* uplo, const char* trans, const char* diag, const int* n, const double* a, const int* lda,
            double* x, const int* incx, std::size_t, std::size_t, std::size_t);
void dgemv_(const char* trans, const int* m, const int* n, const double* alpha, const double* a, const int* lda,
            const double* x, const int* incx, const double* beta, double* y, const int* incy, std::size_t);
}

namespace bem {

namespace {

/// Fronts of at most this many rows are factored by plain loops, and supernodes of at
/// most kSmallBlock columns solved by them (a LAPACK or BLAS call costs more there).
constexpr std::size_t kSmallFront = 24;
constexpr Index kSmallBlock = 16;
/// Relaxed supernodes: widths up to which a child block is merged into its parent
/// always, while explicit zeros are at most 20 % of the block, or at most 5 %.
constexpr std::size_t kRelaxSmall = 8, kRelaxMedium = 16, kRelaxLarge = 64;

/// One triangle of P A P^T in compressed form: entry (r, c) of P A P^T with r > c
/// (strictly lower) or r >= c (lower with the diagonal), filed under r (`by_row`) or c.
struct Triangle {
  std::vector<std::size_t> start;  ///< the entries of line i: start[i] .. start[i+1]-1
  std::vector<Index> other;        ///< the other index of every entry
  std::vector<double> value;       ///< empty unless asked for
};

Triangle triangle(Index n, const std::int64_t* indptr, const std::int64_t* indices, const double* data,
                  const std::vector<Index>& inverse, bool by_row, bool diagonal) {
  Triangle t;
  t.start.assign(static_cast<std::size_t>(n) + 1, 0);
  auto for_each = [&](auto&& visit) {
    for (Index i = 0; i < n; ++i)
      for (std::int64_t p = indptr[i]; p < indptr[i + 1]; ++p) {
        const Index r = inverse[static_cast<std::size_t>(i)], c = inverse[static_cast<std::size_t>(indices[p])];
        if (r > c || (diagonal && r == c)) visit(by_row ? r : c, by_row ? c : r, p);
      }
  };
  for_each([&](Index line, Index, std::int64_t) { ++t.start[static_cast<std::size_t>(line) + 1]; });
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) t.start[i + 1] += t.start[i];
  t.other.resize(t.start.back());
  if (data) t.value.resize(t.start.back());
  std::vector<std::size_t> next(t.start.begin(), t.start.end() - 1);
  for_each([&](Index line, Index other, std::int64_t p) {
    const std::size_t q = next[static_cast<std::size_t>(line)]++;
    t.other[q] = other;
    if (data) t.value[q] = data[p];
  });
  return t;
}

/// The elimination tree of P A P^T (Liu's algorithm with path compression): parent[j],
/// or -1 for a root. `lower` holds the strictly lower triangle by rows.
std::vector<Index> elimination_tree(Index n, const Triangle& lower) {
  std::vector<Index> parent(static_cast<std::size_t>(n), -1), ancestor(static_cast<std::size_t>(n), -1);
  for (Index k = 0; k < n; ++k)
    for (std::size_t p = lower.start[static_cast<std::size_t>(k)]; p < lower.start[static_cast<std::size_t>(k) + 1];
         ++p) {
      for (Index j = lower.other[p]; j != -1 && j < k;) {
        const Index next = ancestor[static_cast<std::size_t>(j)];
        ancestor[static_cast<std::size_t>(j)] = k;
        if (next == -1) parent[static_cast<std::size_t>(j)] = k;
        j = next;
      }
    }
  return parent;
}

/// A postorder of the forest `parent`: post[i] is the i-th node visited.
std::vector<Index> postorder(const std::vector<Index>& parent) {
  const std::size_t n = parent.size();
  std::vector<Index> head(n, -1), next(n, -1), post, stack;
  post.reserve(n);
  for (std::size_t j = n; j-- > 0;)  // children in increasing order
    if (parent[j] != -1) {
      next[j] = head[static_cast<std::size_t>(parent[j])];
      head[static_cast<std::size_t>(parent[j])] = static_cast<Index>(j);
    }
  for (std::size_t root = 0; root < n; ++root) {
    if (parent[root] != -1) continue;
    stack.push_back(static_cast<Index>(root));
    while (!stack.empty()) {
      const Index top = stack.back();
      const Index child = head[static_cast<std::size_t>(top)];
      if (child == -1) {
        post.push_back(top);
        stack.pop_back();
      } else {
        head[static_cast<std::size_t>(top)] = next[static_cast<std::size_t>(child)];
        stack.push_back(child);
      }
    }
  }
  return post;
}

/// n doubles, uninitialised, on transparent huge pages where the system allows them
/// (madvise mode): the factor is written once, and on 4 KiB pages the kernel's page
/// faults cost more than the numeric factorisation (docs/design/preconditioners.md).
SparseCholesky::Buffer huge_page_buffer(std::size_t n) {
  constexpr std::size_t page = std::size_t{2} << 20;
  const std::size_t bytes = std::max(page, (n * sizeof(double) + page - 1) / page * page);
  void* p = std::aligned_alloc(page, bytes);
  if (p == nullptr) throw std::bad_alloc();
  madvise(p, bytes, MADV_HUGEPAGE);  // advice only: an error leaves ordinary pages
  return SparseCholesky::Buffer(static_cast<double*>(p));
}

int blas_int(Index v) {
  if (v > 2147483647) throw std::invalid_argument("sparse Cholesky: a frontal matrix too large for LP64 BLAS");
  return static_cast<int>(v);
}

/// The partial Cholesky factorisation of the m x m front F (column-major, lower
/// triangle): F11 = L11 L11^T, L21 = F21 L11^{-T}, F22 := F22 - L21 L21^T, in place.
/// Small fronts by plain loops (a LAPACK call costs more than their arithmetic), large
/// ones by dpotrf, dtrsm and dsyrk. False if F11 is not positive definite.
bool partial_cholesky(double* F, std::size_t m, std::size_t k) {
  if (m <= kSmallFront) {
    for (std::size_t c = 0; c < k; ++c) {
      double* column = F + c * m;
      if (!(column[c] > 0.0)) return false;
      const double pivot = std::sqrt(column[c]);
      for (std::size_t i = c; i < m; ++i) column[i] /= pivot;
      for (std::size_t j = c + 1; j < m; ++j) {
        double* target = F + j * m;
        const double ljc = column[j];
        for (std::size_t i = j; i < m; ++i) target[i] -= column[i] * ljc;
      }
    }
    return true;
  }
  const int K = blas_int(static_cast<Index>(k)), M = blas_int(static_cast<Index>(m)), R = M - K;
  int info = 0;
  dpotrf_("L", &K, F, &M, &info, 1);
  if (info != 0) return false;
  if (R > 0) {
    const double one = 1.0, minus_one = -1.0;
    dtrsm_("R", "L", "T", "N", &R, &K, &one, F, &M, F + k, &M, 1, 1, 1, 1);
    dsyrk_("L", "N", &R, &K, &minus_one, F + k, &M, &one, F + k + k * m, &M, 1, 1);
  }
  return true;
}

}  // namespace

SparseCholesky::SparseCholesky(Index n, const Eigen::Ref<const Indices>& indptr_ref,
                               const Eigen::Ref<const Indices>& indices_ref,
                               const Eigen::Ref<const Eigen::VectorXd>& data_ref,
                               const Eigen::Ref<const Indices>& ordering, Index n_schur) {
  const std::int64_t *indptr = indptr_ref.data(), *indices = indices_ref.data();
  if (n < 0 || indptr_ref.size() != n + 1 || indptr[0] != 0 || indptr[n] != indices_ref.size() ||
      indices_ref.size() != data_ref.size())
    throw std::invalid_argument("sparse Cholesky: the CSR arrays do not describe an n x n matrix");
  for (Index i = 0; i < n; ++i)
    if (indptr[i + 1] < indptr[i]) throw std::invalid_argument("sparse Cholesky: indptr must not decrease");
  for (Index p = 0; p < indices_ref.size(); ++p)
    if (indices[p] < 0 || indices[p] >= n) throw std::invalid_argument("sparse Cholesky: a column index out of range");
  if (ordering.size() != n) throw std::invalid_argument("sparse Cholesky: the ordering must have n entries");
  if (n_schur < 0 || n_schur > n) throw std::invalid_argument("sparse Cholesky: n_schur must be in 0..n");
  const std::size_t N = static_cast<std::size_t>(n);
  const Index n_h = n - n_schur;  // the rows eliminated sparsely (H), then S
  const std::size_t NH = static_cast<std::size_t>(n_h);
  std::vector<Index> inverse(N, -1);
  for (Index i = 0; i < n; ++i) {
    const std::int64_t old = ordering[i];
    if (old < 0 || old >= n || inverse[static_cast<std::size_t>(old)] != -1)
      throw std::invalid_argument("sparse Cholesky: the ordering is not a permutation of 0..n-1");
    inverse[static_cast<std::size_t>(old)] = i;
  }

  // The elimination tree in the caller's ordering, then H's part postordered (a column
  // whose parent is in S is a root of H's forest); S stays last, in the caller's order.
  std::vector<Index> parent;
  {
    std::vector<Index> tree =
        elimination_tree(n, triangle(n, indptr, indices, nullptr, inverse, /*by_row=*/true, /*diagonal=*/false));
    tree.resize(NH);
    for (Index& p : tree)
      if (p >= n_h) p = -1;
    const std::vector<Index> post = postorder(tree);
    std::vector<Index> position(NH);
    for (std::size_t i = 0; i < NH; ++i) position[static_cast<std::size_t>(post[i])] = static_cast<Index>(i);
    perm_.resize(N);
    parent.resize(NH);
    for (std::size_t i = 0; i < NH; ++i) {
      const Index old = post[i];
      perm_[i] = ordering[old];
      const Index p = tree[static_cast<std::size_t>(old)];
      parent[i] = p == -1 ? -1 : position[static_cast<std::size_t>(p)];
    }
    for (std::size_t i = NH; i < N; ++i) perm_[i] = ordering[static_cast<Index>(i)];
    for (std::size_t i = 0; i < N; ++i) inverse[static_cast<std::size_t>(perm_[i])] = static_cast<Index>(i);
  }
  const Triangle lower = triangle(n, indptr, indices, data_ref.data(), inverse, /*by_row=*/false, /*diagonal=*/true);

  // Symbolic: the row structure of every column (its own rows below the diagonal and its
  // children's, merged; the children's structures are the top of a stack in postorder),
  // kept only for the first column of each supernode. Column j continues the supernode of
  // j - 1 when j - 1 is its only child and has one more row (the same structure).
  std::vector<Index> children(NH, 0);
  for (std::size_t j = 0; j < NH; ++j)
    if (parent[j] != -1) ++children[static_cast<std::size_t>(parent[j])];
  std::vector<std::vector<Index>> stack;
  std::vector<Index> mark(N, -1);
  Index previous_count = 0;  // rows of column j - 1's structure, its diagonal included
  for (Index j = 0; j < n_h; ++j) {
    const std::size_t J = static_cast<std::size_t>(j);
    std::vector<Index> structure;
    for (std::size_t p = lower.start[J]; p < lower.start[J + 1]; ++p) {
      const Index r = lower.other[p];
      if (r != j && mark[static_cast<std::size_t>(r)] != j) {
        mark[static_cast<std::size_t>(r)] = j;
        structure.push_back(r);
      }
    }
    for (Index c = 0; c < children[J]; ++c) {
      for (const Index r : stack.back())
        if (r != j && mark[static_cast<std::size_t>(r)] != j) {
          mark[static_cast<std::size_t>(r)] = j;
          structure.push_back(r);
        }
      stack.pop_back();
    }
    const Index count = static_cast<Index>(structure.size()) + 1;
    const bool continues = j > 0 && parent[J - 1] == j && children[J] == 1 && previous_count == count + 1;
    previous_count = count;
    if (!continues) {
      first_.push_back(j);
      rows_at_.push_back(rows_.size());
      rows_.push_back(j);
      const std::size_t at = rows_.size();
      rows_.insert(rows_.end(), structure.begin(), structure.end());
      std::sort(rows_.begin() + static_cast<std::ptrdiff_t>(at), rows_.end());
    }
    if (parent[J] != -1) stack.push_back(std::move(structure));
  }
  first_.push_back(n_h);
  rows_at_.push_back(rows_.size());
  amalgamate(parent);

  // Numeric: the fronts in postorder. Front s (m x m, column-major) gathers A's columns of
  // the supernode and its children's update matrices (extend-add), factors its k x k
  // block, and leaves the (m - k) x (m - k) Schur complement on the update stack, or,
  // from a root of H's forest (its rows all in S), adds it to S's Schur complement.
  const std::size_t S = first_.size() - 1;
  values_at_.resize(S + 1);
  values_at_[0] = 0;
  std::vector<Index> supernode_of(N), child_supernodes(S, 0);
  for (std::size_t s = 0; s < S; ++s) {
    const std::size_t k = static_cast<std::size_t>(first_[s + 1] - first_[s]), m = rows_at_[s + 1] - rows_at_[s];
    values_at_[s + 1] = values_at_[s] + m * k;
    largest_front_ = std::max(largest_front_, m);
    for (Index j = first_[s]; j < first_[s + 1]; ++j) supernode_of[static_cast<std::size_t>(j)] = static_cast<Index>(s);
  }
  for (std::size_t s = 0; s < S; ++s) {
    const Index p = parent[static_cast<std::size_t>(first_[s + 1] - 1)];
    if (p != -1) ++child_supernodes[static_cast<std::size_t>(supernode_of[static_cast<std::size_t>(p)])];
  }
  values_ = huge_page_buffer(values_at_[S]);
  Buffer front = huge_page_buffer(largest_front_ * largest_front_);
  std::vector<double> updates;
  std::vector<std::size_t> update_at;     // where each stacked update begins
  std::vector<std::size_t> update_owner;  // the supernode it came from
  std::vector<Index> local(N, -1);
  schur_ = Eigen::MatrixXd::Zero(n_schur, n_schur);  // its lower triangle, then symmetrised
  for (std::size_t col = NH; col < N; ++col)
    for (std::size_t p = lower.start[col]; p < lower.start[col + 1]; ++p)
      schur_(lower.other[p] - n_h, static_cast<Index>(col) - n_h) += lower.value[p];
  for (std::size_t s = 0; s < S; ++s) {
    const Index f = first_[s];
    const std::size_t k = static_cast<std::size_t>(first_[s + 1] - f), m = rows_at_[s + 1] - rows_at_[s];
    const Index* rows = rows_.data() + rows_at_[s];
    for (std::size_t i = 0; i < m; ++i) local[static_cast<std::size_t>(rows[i])] = static_cast<Index>(i);
    std::fill(front.get(), front.get() + m * m, 0.0);
    for (std::size_t c = 0; c < k; ++c) {
      const std::size_t col = static_cast<std::size_t>(f) + c;
      for (std::size_t p = lower.start[col]; p < lower.start[col + 1]; ++p)
        front[static_cast<std::size_t>(local[static_cast<std::size_t>(lower.other[p])]) + c * m] += lower.value[p];
    }
    for (Index c = 0; c < child_supernodes[s]; ++c) {
      const std::size_t child = update_owner.back(), at = update_at.back();
      const std::size_t kc = static_cast<std::size_t>(first_[child + 1] - first_[child]);
      const std::size_t mu = rows_at_[child + 1] - rows_at_[child] - kc;
      const Index* urows = rows_.data() + rows_at_[child] + kc;
      for (std::size_t jj = 0; jj < mu; ++jj) {
        double* column = front.get() + static_cast<std::size_t>(local[static_cast<std::size_t>(urows[jj])]) * m;
        const double* u = updates.data() + at + jj * mu;
        for (std::size_t ii = jj; ii < mu; ++ii) column[local[static_cast<std::size_t>(urows[ii])]] += u[ii];
      }
      updates.resize(at);
      update_at.pop_back();
      update_owner.pop_back();
    }
    if (!partial_cholesky(front.get(), m, k))
      throw NotPositiveDefinite("sparse Cholesky: the matrix is not positive definite (at row " +
                                std::to_string(perm_[static_cast<std::size_t>(f)]) + " or after)");
    std::copy(front.get(), front.get() + m * k, values_.get() + values_at_[s]);
    if (m > k && parent[static_cast<std::size_t>(first_[s + 1] - 1)] == -1) {
      const Index* urows = rows + k;
      for (std::size_t jj = 0; jj < m - k; ++jj)
        for (std::size_t ii = jj; ii < m - k; ++ii)
          schur_(urows[ii] - n_h, urows[jj] - n_h) += front[k + ii + (k + jj) * m];
    } else if (m > k) {
      const std::size_t mu = m - k, at = updates.size();
      updates.resize(at + mu * mu);
      for (std::size_t jj = 0; jj < mu; ++jj)
        std::copy(front.get() + k + jj + (k + jj) * m, front.get() + m + (k + jj) * m,
                  updates.begin() + static_cast<std::ptrdiff_t>(at + jj + jj * mu));
      update_at.push_back(at);
      update_owner.push_back(s);
    }
  }
  if (n_schur > 0) {
    schur_ = schur_.selfadjointView<Eigen::Lower>();
    schur_factor_.compute(schur_);
    if (schur_factor_.info() != Eigen::Success)
      throw NotPositiveDefinite("sparse Cholesky: the matrix is not positive definite (in the Schur complement)");
  }
}

void SparseCholesky::amalgamate(const std::vector<Index>& parent) {
  // A supernode absorbs the one before it (columns first_[s-1] .. first_[s]-1) when that
  // is its child in the elimination tree: the merged block's rows are the child's columns
  // and the parent's rows (the child's other rows are among them), so only explicit zeros
  // are added. Merged while small, or while the zeros stay a small share of the block.
  std::vector<Index> first, rows;
  std::vector<std::size_t> rows_at;
  std::size_t zeros = 0;  // explicit zeros in the block being grown
  auto entries = [](std::size_t m, std::size_t k) { return m * k - k * (k - 1) / 2; };
  for (std::size_t s = 0; s + 1 < first_.size(); ++s) {
    const Index f = first_[s], l = first_[s + 1];
    const std::size_t k = static_cast<std::size_t>(l - f), m = rows_at_[s + 1] - rows_at_[s];
    const Index up = f > 0 ? parent[static_cast<std::size_t>(f - 1)] : -1;
    if (!first.empty() && up >= f && up < l) {  // the block before is a child
      const std::size_t kc = static_cast<std::size_t>(f - first.back()), mc = rows.size() - rows_at.back();
      const std::size_t width = k + kc, merged = entries(m + kc, width);
      const std::size_t new_zeros = zeros + merged - entries(mc, kc) - entries(m, k);
      if (width <= kRelaxSmall || (width <= kRelaxMedium && 5 * new_zeros <= merged) ||
          (width <= kRelaxLarge && 20 * new_zeros <= merged)) {
        rows.resize(rows_at.back() + kc);  // the child's columns, then the parent's rows
        rows.insert(rows.end(), rows_.begin() + static_cast<std::ptrdiff_t>(rows_at_[s]),
                    rows_.begin() + static_cast<std::ptrdiff_t>(rows_at_[s + 1]));
        zeros = new_zeros;
        continue;
      }
    }
    first.push_back(f);
    rows_at.push_back(rows.size());
    rows.insert(rows.end(), rows_.begin() + static_cast<std::ptrdiff_t>(rows_at_[s]),
                rows_.begin() + static_cast<std::ptrdiff_t>(rows_at_[s + 1]));
    zeros = 0;
  }
  first.push_back(first_.back());
  rows_at.push_back(rows.size());
  first_ = std::move(first);
  rows_at_ = std::move(rows_at);
  rows_ = std::move(rows);
}

// Small blocks (most of them, at the leaves of the tree) by plain loops; large ones by
// BLAS (dtrsv, dgemv).
void SparseCholesky::forward(double* y, double* work) const {
  const int one = 1;
  const double d_one = 1.0, d_zero = 0.0;
  const std::size_t S = first_.size() - 1;
  for (std::size_t s = 0; s < S; ++s) {  // L z = y
    const Index f = first_[s], k = first_[s + 1] - f, m = static_cast<Index>(rows_at_[s + 1] - rows_at_[s]);
    const double* L = values_.get() + values_at_[s];
    const Index* rows = rows_.data() + rows_at_[s];
    double* x = y + f;
    if (k <= kSmallBlock) {  // one scattered update per row
      for (Index c = 0; c < k; ++c) {
        const double* column = L + c * m;
        const double xc = (x[c] /= column[c]);
        for (Index i = c + 1; i < k; ++i) x[i] -= column[i] * xc;
      }
      for (Index i = k; i < m; ++i) {
        double sum = 0.0;
        for (Index c = 0; c < k; ++c) sum += L[i + c * m] * x[c];
        y[rows[i]] -= sum;
      }
      continue;
    }
    const int K = static_cast<int>(k), M = static_cast<int>(m), R = M - K;
    dtrsv_("L", "N", "N", &K, L, &M, x, &one, 1, 1, 1);
    if (R > 0) {
      dgemv_("N", &R, &K, &d_one, L + k, &M, x, &one, &d_zero, work, &one, 1);
      for (Index i = k; i < m; ++i) y[rows[i]] -= work[i - k];
    }
  }
}

void SparseCholesky::backward(double* y, double* work) const {
  const int one = 1;
  const double d_one = 1.0, d_minus_one = -1.0;
  const std::size_t S = first_.size() - 1;
  for (std::size_t s = S; s-- > 0;) {  // L^T x = z
    const Index f = first_[s], k = first_[s + 1] - f, m = static_cast<Index>(rows_at_[s + 1] - rows_at_[s]);
    const double* L = values_.get() + values_at_[s];
    const Index* rows = rows_.data() + rows_at_[s];
    double* x = y + f;
    if (k <= kSmallBlock) {  // one gather per row
      for (Index i = k; i < m; ++i) work[i - k] = y[rows[i]];
      for (Index c = k; c-- > 0;) {
        const double* column = L + c * m;
        double sum = x[c];
        for (Index i = c + 1; i < k; ++i) sum -= column[i] * x[i];
        for (Index i = k; i < m; ++i) sum -= column[i] * work[i - k];
        x[c] = sum / column[c];
      }
      continue;
    }
    const int K = static_cast<int>(k), M = static_cast<int>(m), R = M - K;
    if (R > 0) {
      for (Index i = k; i < m; ++i) work[i - k] = y[rows[i]];
      dgemv_("T", &R, &K, &d_minus_one, L + k, &M, work, &one, &d_one, x, &one, 1);
    }
    dtrsv_("L", "T", "N", &K, L, &M, x, &one, 1, 1, 1);
  }
}

Eigen::MatrixXd SparseCholesky::permuted(const Eigen::Ref<const Eigen::MatrixXd>& B, bool back) const {
  const Index n = size();
  if (B.rows() != n) throw std::invalid_argument("sparse Cholesky: the right-hand side has the wrong number of rows");
  Eigen::MatrixXd Y(n, B.cols());
  for (Index c = 0; c < B.cols(); ++c)
    for (Index i = 0; i < n; ++i) {
      const Index p = perm_[static_cast<std::size_t>(i)];
      if (back)
        Y(p, c) = B(i, c);
      else
        Y(i, c) = B(p, c);
    }
  return Y;
}

Eigen::MatrixXd SparseCholesky::solve(const Eigen::Ref<const Eigen::MatrixXd>& B) const {
  Eigen::MatrixXd Y = permuted(B, false);
  const Index n_h = first_.back(), n_schur = size() - n_h;
  std::vector<double> work(largest_front_);
  for (Index c = 0; c < Y.cols(); ++c) {
    forward(Y.col(c).data(), work.data());
    if (n_schur > 0) Y.col(c).tail(n_schur) = schur_factor_.solve(Y.col(c).tail(n_schur));
    backward(Y.col(c).data(), work.data());
  }
  return permuted(Y, true);
}

Eigen::MatrixXd SparseCholesky::eliminate(const Eigen::Ref<const Eigen::MatrixXd>& B) const {
  Eigen::MatrixXd Y = permuted(B, false);
  std::vector<double> work(largest_front_);
  for (Index c = 0; c < Y.cols(); ++c) forward(Y.col(c).data(), work.data());
  return permuted(Y, true);
}

Eigen::MatrixXd SparseCholesky::back_substitute(const Eigen::Ref<const Eigen::MatrixXd>& W) const {
  Eigen::MatrixXd Y = permuted(W, false);
  std::vector<double> work(largest_front_);
  for (Index c = 0; c < Y.cols(); ++c) backward(Y.col(c).data(), work.data());
  return permuted(Y, true);
}

}  // namespace bem
