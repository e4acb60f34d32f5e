#include "bem/lame_surface_entries.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "bem/aca.hpp"
#include "bem/block3.hpp"
#include "bem/far_points.hpp"
#include "bem/surface_entries.hpp"

namespace bem {

namespace {

/// The coefficients of the header's formulas: 2 U = cu (a3 g I + R), A = a1 R + a0 g I.
struct Coefficients {
  double mu, cu, a3, a1, a0;
  explicit Coefficients(const Lame& m)
      : mu(m.mu),
        cu(1.0 / (4.0 * m.mu * (1.0 - m.nu))),
        a3(3.0 - 4.0 * m.nu),
        a1(1.0 / (2.0 * (1.0 - m.nu))),
        a0((1.0 - 2.0 * m.nu) / (2.0 * (1.0 - m.nu))) {}
};

/// The moment channels of the far pass: 0: g, 1..6: R_kl for (k, l) = (0, 0), (1, 1), (2, 2),
/// (0, 1), (0, 2), (1, 2) (PairMoments' order of surface_operators.cpp).
constexpr int kChannel[3][3] = {{1, 4, 5}, {4, 2, 6}, {5, 6, 3}};

/// The blocks of one pair of a test triangle (hats i, curls ci) and a trial triangle (hats j,
/// curls cj) from the moments m(c, a, b) (channel c, test basis a, trial basis b; 3: the
/// constant). Each writes through add(i, j, B).
struct PairBlocks {
  const Coefficients& c;
  /// 2 U's block cu (a3 g_ij I + R_ij).
  template <class Moment>
  void single_layer(const Moment& m, int i, int j, Block& B) const {
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) B[k][l] = c.cu * ((k == l ? c.a3 * m(0, i, j) : 0.0) + m(kChannel[k][l], i, j));
  }
  /// A's block a1 R_ab + a0 g_ab I.
  template <class Moment>
  void companion(const Moment& m, int a, int b, Block& B) const {
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) B[k][l] = c.a1 * m(kChannel[k][l], a, b) + (k == l ? c.a0 * m(0, a, b) : 0.0);
  }
  /// Z's block -mu g33 ci cj^T + 2 mu [ci]_x A33 [cj]_x, given A33 and the cross matrices.
  void hypersingular(double g33, const Block& A33, Vec3 ci, Vec3 cj, const Block& Ci, const Block& Cj, Block& B) const {
    Block T, S;
    product(A33, Cj, T);
    product(Ci, T, S);
    const double a[3] = {ci.x, ci.y, ci.z}, b[3] = {cj.x, cj.y, cj.z};
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) B[k][l] = -c.mu * g33 * a[k] * b[l] + 2.0 * c.mu * S[k][l];
  }
};

/// The surface curls of a triangle's hats (by local vertex) and their cross matrices.
struct Curls {
  Vec3 c[3];
  Block A[3];
  explicit Curls(const Triangle& t) {
    for (int j = 0; j < 3; ++j) {
      c[j] = surface_curl(t, j);
      cross_matrix(c[j], A[j]);
    }
  }
};

/// The calling thread's CPU seconds (the entries' times are summed over the threads, and a
/// thread descheduled on a loaded machine does not count).
double thread_seconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// The row points summed at once by the far pass of the dense blocks (LameBlock::accumulate).
constexpr int kWidth = 8;

/// The scalar parts of V_h's and Z's far factors (V_L, D^T g D) are recompressed to this fraction
/// of the blocks' tol before they join A's (LameBlock::far_factors).
constexpr double kPartTolerance = 0.1;

/// A vector block's rank against the point ACA's rank of g (the choice between the cross
/// approximation and the dense sum of an admissible block, LameBlock::far_factors).
constexpr Index kRankRatio = 3;

/// argmax |x[i]| over unused i (the first of equal ones), -1 if none.
Index unused_argmax(const double* x, Index n, const std::vector<char>& used) {
  Index best = -1;
  double top = -1.0;
  for (Index i = 0; i < n; ++i) {
    const double a = std::abs(x[i]);
    if (!used[static_cast<std::size_t>(i)] && a > top) {
      top = a;
      best = i;
    }
  }
  return best;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Near field

LameSurfaceNearField::LameSurfaceNearField(const Surface& s, const Lame& lame, const std::vector<char>& triangles) {
  check_medium(lame);
  const Coefficients c(lame);
  const PairBlocks blocks{c};
  const Index n = s.vertices();
  const std::vector<std::vector<Index>> near = near_pairs(s, triangles);
  // the vertex pairs of the upper parts (rows: tau's vertices, columns: sigma's, tau <= sigma)
  std::vector<std::vector<Index>> lists(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(dynamic, 64)
  for (Index i = 0; i < n; ++i) {
    std::vector<Index>& l = lists[static_cast<std::size_t>(i)];
    for (Index t : s.star(i))
      for (Index u : near[static_cast<std::size_t>(t)])
        for (Index v : s.triangle(u).v) l.push_back(v);
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
  }
  // vector CSR: row 3 i + k holds the columns 3 j + l of row i's list, entry
  // 9 ptr[i] + 3 k len_i + 3 (position of j) + l
  std::vector<Index> ptr(static_cast<std::size_t>(n) + 1, 0);
  for (Index i = 0; i < n; ++i)
    ptr[static_cast<std::size_t>(i) + 1] =
        ptr[static_cast<std::size_t>(i)] + static_cast<Index>(lists[static_cast<std::size_t>(i)].size());
  const std::size_t nnz = 9 * static_cast<std::size_t>(ptr.back());
  std::vector<double> hv(nnz, 0.0), hy(nnz, 0.0), hyt(nnz, 0.0), hz(nnz, 0.0);
  auto at = [&](Index i, Index j, int k, int l) {
    const std::vector<Index>& li = lists[static_cast<std::size_t>(i)];
    const Index p = std::lower_bound(li.begin(), li.end(), j) - li.begin();
    const Index len = static_cast<Index>(li.size());
    return static_cast<std::size_t>(9 * ptr[static_cast<std::size_t>(i)] + 3 * k * len + 3 * p + l);
  };
  auto add = [&](std::vector<double>& h, Index i, Index j, double scale, const Block& B) {
    const std::size_t base = at(i, j, 0, 0);
    const std::size_t len = lists[static_cast<std::size_t>(i)].size();
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l)
        h[base + 3 * static_cast<std::size_t>(k) * len + static_cast<std::size_t>(l)] += scale * B[k][l];
  };
  const PairIntegrator integrator(s);
  for_each_triangle_by_colour(s, [&](Index tau) {
    const Triangle& ta = s.triangle(tau);
    const Curls ca(ta);
    PairMoments L;
    // moments by channel (0: G, 1..6: R_kl in PairMoments' order)
    auto moment = [&L](int ch, int a, int b) {
      constexpr int kk[7] = {0, 0, 1, 2, 0, 0, 1}, ll[7] = {0, 0, 1, 2, 1, 2, 2};
      return ch == 0 ? L.G[a][b] : L.R[kk[ch]][ll[ch]][a][b];
    };
    Block B, A33, T;
    for (Index sigma : near[static_cast<std::size_t>(tau)]) {
      integrator.moments(tau, sigma, false, L);
      const Triangle& tb = s.triangle(sigma);
      const Curls cb(tb);
      const double half = sigma == tau ? 0.5 : 1.0;
      blocks.companion(moment, 3, 3, A33);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          blocks.single_layer(moment, i, j, B);
          add(hv, ta.v[i], tb.v[j], half, B);
          blocks.hypersingular(L.G[3][3], A33, ca.c[i], cb.c[j], ca.A[i], cb.A[j], B);
          add(hz, ta.v[i], tb.v[j], half, B);
        }
      // Y: test hat i of tau, trial hat j of sigma: A[i][3] [c_j]_x
      for (int i = 0; i < 3; ++i) {
        blocks.companion(moment, i, 3, T);
        for (int j = 0; j < 3; ++j) {
          product(T, cb.A[j], B);
          add(hy, ta.v[i], tb.v[j], 1.0, B);
        }
      }
      if (sigma == tau) continue;
      // the pair (sigma, tau): test hat i of sigma, trial hat j of tau: A[3][i] [c_j]_x,
      // kept transposed in the rows of tau's vertices
      for (int i = 0; i < 3; ++i) {
        blocks.companion(moment, 3, i, T);
        for (int j = 0; j < 3; ++j) {
          product(T, ca.A[j], B);
          Block Bt;
          for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l) Bt[l][k] = B[k][l];
          add(hyt, ta.v[j], tb.v[i], 1.0, Bt);
        }
      }
    }
  });
  // the CSR structure
  RowSparse pattern(3 * n, 3 * n);
  pattern.resizeNonZeros(static_cast<Index>(nnz));
  Index* outer = pattern.outerIndexPtr();
  Index* inner = pattern.innerIndexPtr();
  for (Index i = 0; i < n; ++i) {
    const std::vector<Index>& li = lists[static_cast<std::size_t>(i)];
    const Index len = static_cast<Index>(li.size());
    for (int k = 0; k < 3; ++k) {
      const Index row0 = 9 * ptr[static_cast<std::size_t>(i)] + 3 * k * len;
      outer[3 * i + k] = row0;
      for (Index p = 0; p < len; ++p)
        for (int l = 0; l < 3; ++l) inner[row0 + 3 * p + l] = 3 * li[static_cast<std::size_t>(p)] + l;
    }
  }
  outer[3 * n] = static_cast<Index>(nnz);
  auto matrix = [&](const std::vector<double>& values) {
    RowSparse A = pattern;
    std::copy(values.begin(), values.end(), A.valuePtr());
    return A;
  };
  {
    const RowSparse H = matrix(hv);
    v_ = RowSparse(H + RowSparse(H.transpose()));
  }
  {
    const RowSparse H = matrix(hz);
    z_ = RowSparse(H + RowSparse(H.transpose()));
  }
  y_ = RowSparse(matrix(hy) + RowSparse(matrix(hyt).transpose()));
}

std::size_t LameSurfaceNearField::nbytes() const {
  std::size_t b = 0;
  for (const RowSparse* A : {&v_, &y_, &z_})
    b += static_cast<std::size_t>(A->nonZeros()) * (sizeof(double) + sizeof(Index)) +
         static_cast<std::size_t>(A->rows() + 1) * sizeof(Index);
  return b;
}

// ---------------------------------------------------------------------------------------
// Cache

namespace {

/// Moves the block of `key` out of `blocks` into `block` and forgets it: false if none.
template <typename Blocks, typename Block>
bool take_block(Blocks& blocks, const LameSurfaceBlockCache::Key& key, Block& block) {
  const auto it = blocks.find(key);
  if (it == blocks.end()) return false;
  block = std::move(it->second);
  blocks.erase(it);
  return true;
}

}  // namespace

void LameSurfaceBlockCache::put_dense(const Key& key, Eigen::MatrixXd block) {
  std::lock_guard<std::mutex> lock(mutex_);
  dense_[key] = std::move(block);
}

void LameSurfaceBlockCache::put_low_rank(const Key& key, LowRank block) {
  std::lock_guard<std::mutex> lock(mutex_);
  low_rank_[key] = std::move(block);
}

bool LameSurfaceBlockCache::take_dense(const Key& key, Eigen::MatrixXd& block) {
  std::lock_guard<std::mutex> lock(mutex_);
  return take_block(dense_, key, block);
}

bool LameSurfaceBlockCache::take_low_rank(const Key& key, LowRank& block) {
  std::lock_guard<std::mutex> lock(mutex_);
  return take_block(low_rank_, key, block);
}

void LameSurfaceBlockCache::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  dense_.clear();
  low_rank_.clear();
}

// ---------------------------------------------------------------------------------------
// Grouped ACA

LowRank grouped_point_aca(Index points_r, Index points_c, const std::function<void(Index, double*)>& row_group,
                          const std::function<void(Index, double*)>& column_group, double tol, Index max_rank) {
  // Inside, rows and columns are numbered component-major (row k Pr + p, column l Pc + q),
  // so that the kernel's rows and columns are written and the residuals updated with unit
  // strides; the factors are returned point-major (rows 3 p + k).
  const Index Pr = points_r, Pc = points_c, M = 3 * Pr, N = 3 * Pc;
  max_rank = std::min({max_rank, M, N});
  Index capacity = std::max<Index>(std::min<Index>(max_rank, 96), 1);
  Eigen::MatrixXd U(M, capacity), V(N, capacity);
  // R: the residual rows of the current row point (N x 3) and GR = V_k^T R; C: residual columns
  // (M x s) and GC = U_k^T C (the cross terms of |U V^T|_F)
  Eigen::MatrixXd R(N, 3), GR(capacity, 3), C(M, 3), GC(capacity, 3);
  Index k = 0;
  double norm2 = 0.0;
  std::vector<char> point_used(static_cast<std::size_t>(Pr), 0), col_used(static_cast<std::size_t>(N), 0);
  std::vector<double> buffer(static_cast<std::size_t>(9 * Pr));
  std::uint64_t seed =
      0x9E3779B97F4A7C15ULL ^ (static_cast<std::uint64_t>(M) * 1315423911ULL + static_cast<std::uint64_t>(N));
  auto random_index = [&seed](Index size) {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<Index>((seed >> 33) % static_cast<std::uint64_t>(size));
  };
  // Y (rows x s) -= F_k W with W(t, c) = G(index[c], t), and GY = F_k^T Y afterwards, chunk by
  // chunk of rows (F_k read once for both; a product with a few columns as Eigen's gemm would
  // pack F_k first, which costs as much)
  auto subtract = [&k](Eigen::MatrixXd& Y, Index s, Eigen::MatrixXd& GY, const Eigen::MatrixXd& F,
                       const Eigen::MatrixXd& G, const Index* index) {
    constexpr Index kChunk = 128;
    const Index rows = Y.rows();
    GY.topLeftCorner(k, 3).setZero();
    for (Index r0 = 0; r0 < rows; r0 += kChunk) {
      const Index len = std::min(kChunk, rows - r0);
      // unused columns (s < 3) are computed on scratch columns of Y and ignored
      double *y0 = Y.col(0).data() + r0, *y1 = Y.col(1).data() + r0, *y2 = Y.col(2).data() + r0;
      for (Index t = 0; t < k; ++t) {
        const double* f = F.col(t).data() + r0;
        const double w0 = G(index[0], t), w1 = s > 1 ? G(index[1], t) : 0.0, w2 = s > 2 ? G(index[2], t) : 0.0;
#pragma omp simd
        for (Index c = 0; c < len; ++c) {
          y0[c] -= f[c] * w0;
          y1[c] -= f[c] * w1;
          y2[c] -= f[c] * w2;
        }
      }
      for (Index t = 0; t < k; ++t) {
        const double* f = F.col(t).data() + r0;
        double s0 = 0.0, s1 = 0.0, s2 = 0.0;
#pragma omp simd reduction(+ : s0, s1, s2)
        for (Index c = 0; c < len; ++c) {
          s0 += f[c] * y0[c];
          s1 += f[c] * y1[c];
          s2 += f[c] * y2[c];
        }
        GY(t, 0) += s0;
        GY(t, 1) += s1;
        GY(t, 2) += s2;
      }
    }
  };
  auto residual_rows = [&](Index p) {
    row_group(p, R.data());  // R(l Pc + q, kk): out[kk * N + l Pc + q]
    const Index rows[3] = {p, Pr + p, 2 * Pr + p};
    subtract(R, 3, GR, V, U, rows);
  };
  // the residual columns `cols` (s <= 3 of them) before the crosses of the current group
  auto residual_columns = [&](const Index* cols, Index s) {
    Index evaluated = -1;
    for (Index t = 0; t < s; ++t) {
      const Index q = cols[t] % Pc, l = cols[t] / Pc;
      if (q != evaluated) {
        column_group(q, buffer.data());  // [(3 l + k) Pr + p]: column l Pc + q at row k Pr + p
        evaluated = q;
      }
      C.col(t) = Eigen::Map<const Eigen::VectorXd>(buffer.data() + l * M, M);
    }
    for (Index t = s; t < 3; ++t) C.col(t).setZero();
    subtract(C, s, GC, U, V, cols);
  };
  auto next_point = [&]() {  // the unused point of the largest entry of the last u
    Index best = -1;
    double top = -1.0;
    const auto u = U.col(k - 1);
    for (Index p = 0; p < Pr; ++p) {
      if (point_used[static_cast<std::size_t>(p)]) continue;
      const double a = std::max({std::abs(u(p)), std::abs(u(Pr + p)), std::abs(u(2 * Pr + p))});
      if (a > top) {
        top = a;
        best = p;
      }
    }
    return best;
  };
  auto next_unused = [&](Index from) {
    for (Index d = 0; d < Pr; ++d) {
      const Index p = (from + d) % Pr;
      if (!point_used[static_cast<std::size_t>(p)]) return p;
    }
    return Index{-1};
  };
  Eigen::MatrixXd Vg(N, 3), gv(capacity, 3);  // the group's v and V_k^T v
  Index p = Pr / 2;
  int zero_groups = 0;
  while (k < max_rank) {
    bool stop = false;
    if (p >= 0) {
      residual_rows(p);
      point_used[static_cast<std::size_t>(p)] = 1;
      // the group's pivots on its residual rows alone (each cross's u at the rows of p is the
      // residual row's entry at the pivot column), their residual columns in one pass below
      Index cols[3], s = 0;
      if (gv.rows() < U.cols()) gv.resize(U.cols(), 3);
      for (int kk = 0; kk < 3 && k + s < max_rank; ++kk) {
        const Index j = unused_argmax(R.col(kk).data(), N, col_used);
        if (j < 0 || R(j, kk) == 0.0) continue;
        const double pivot = R(j, kk);
        Vg.col(s) = R.col(kk) / pivot;
        if (k > 0) gv.col(s) = GR.col(kk).head(k) / pivot;  // V_k^T v
        const Eigen::RowVector3d up = R.row(j);
        R.noalias() -= Vg.col(s) * up;
        if (k > 0) GR.topRows(k).noalias() -= gv.col(s).head(k) * up;
        col_used[static_cast<std::size_t>(j)] = 1;
        cols[s++] = j;
      }
      if (s == 0) {
        p = ++zero_groups > 3 ? -1 : next_unused(p + Pr / 3 + 1);
        stop = p < 0;
      } else {
        zero_groups = 0;
        residual_columns(cols, s);
        // u_t = the residual column after the group's crosses before t, and U_k^T u_t
        for (Index t = 1; t < s; ++t)
          for (Index t0 = 0; t0 < t; ++t0) {
            const double w = Vg(cols[t], t0);
            C.col(t).noalias() -= w * C.col(t0);
            if (k > 0) GC.col(t).head(k).noalias() -= w * GC.col(t0).head(k);
          }
        if (k + s > U.cols()) {
          const Index grown = std::max(2 * U.cols(), k + s);
          U.conservativeResize(Eigen::NoChange, grown);
          V.conservativeResize(Eigen::NoChange, grown);
          GR.conservativeResize(grown, Eigen::NoChange);
          GC.conservativeResize(grown, Eigen::NoChange);
          gv.conservativeResize(grown, Eigen::NoChange);
        }
        bool small = true;
        for (Index t = 0; t < s; ++t) {
          const auto u = C.col(t);
          const auto v = Vg.col(t);
          // |S + u v^T|^2 = |S|^2 + 2 u^T S v + |u|^2 |v|^2, S = the crosses so far
          double cross = k > 0 ? GC.col(t).head(k).dot(gv.col(t).head(k)) : 0.0;
          for (Index t0 = 0; t0 < t; ++t0) cross += C.col(t0).dot(u) * Vg.col(t0).dot(v);
          norm2 += u.squaredNorm() * v.squaredNorm() + 2.0 * cross;
          if (u.norm() * v.norm() > tol * std::sqrt(std::max(norm2, 0.0))) small = false;
        }
        U.middleCols(k, s) = C.leftCols(s);
        V.middleCols(k, s) = Vg.leftCols(s);
        k += s;
        stop = small;
        p = next_point();
        if (p < 0) stop = true;
      }
    } else {
      stop = true;
    }
    if (!stop || k >= max_rank) continue;
    // confirm on a sampled column group and row group
    const double norm = std::sqrt(std::max(norm2, 0.0));
    bool found = false;
    const Index q = random_index(Pc), sample[3] = {q, Pc + q, 2 * Pc + q};
    residual_columns(sample, 3);
    for (int l = 0; l < 3 && !found; ++l) {
      const auto c = C.col(l);
      if (c.norm() * std::sqrt(static_cast<double>(N)) > tol * norm && c.cwiseAbs().maxCoeff() > 0) {
        Index r;
        c.cwiseAbs().maxCoeff(&r);
        if (!point_used[static_cast<std::size_t>(r % Pr)]) {
          p = r % Pr;
          found = true;
        }
      }
    }
    if (!found) {
      const Index pr = next_unused(random_index(Pr));
      if (pr >= 0) {
        residual_rows(pr);
        for (int kk = 0; kk < 3 && !found; ++kk)
          if (R.col(kk).norm() * std::sqrt(static_cast<double>(M)) > tol * norm &&
              R.col(kk).cwiseAbs().maxCoeff() > 0) {
            p = pr;
            found = true;
          }
      }
    }
    if (!found) break;
    zero_groups = 0;
  }
  LowRank out;
  out.U.resize(M, k);
  out.V.resize(N, k);
  for (Index t = 0; t < k; ++t) {
    for (Index a = 0; a < Pr; ++a)
      for (int c = 0; c < 3; ++c) out.U(3 * a + c, t) = U(c * Pr + a, t);
    for (Index a = 0; a < Pc; ++a)
      for (int c = 0; c < 3; ++c) out.V(3 * a + c, t) = V(c * Pc + a, t);
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Blocks

struct LameSurfaceEntries::Data {
  const Surface& s;
  Coefficients c;
  Kind kind;
  std::shared_ptr<const LameSurfaceNearField> near;
  std::shared_ptr<LameSurfaceBlockCache> cache;
  Eigen::Matrix<double, Eigen::Dynamic, 4> L;  ///< the hats' values (and 1) at the far rule's points
  mutable std::atomic<long> dense_ns{0}, low_rank_ns{0};
  Data(const Surface& surface, const Lame& m, Kind k, std::shared_ptr<const LameSurfaceNearField> n,
       std::shared_ptr<LameSurfaceBlockCache> ch)
      : s(surface), c(m), kind(k), near(std::move(n)), cache(std::move(ch)), L(basis_values(far_rule())) {}
};

namespace {

using Key = LameSurfaceBlockCache::Key;
using Data = LameSurfaceEntries::Data;

/// out (3 m x r) += the vector factor F (3 P x r, rows 3 p + k) projected on the parts' hats.
void hat_vector(const std::vector<Part>& parts, const Eigen::Matrix<double, Eigen::Dynamic, 4>& L,
                const Eigen::MatrixXd& F, Eigen::Ref<Eigen::MatrixXd> out) {
  const Index n = L.rows();
  for (Index t = 0; t < F.cols(); ++t) {
    const double* f = F.col(t).data();
    double* o = out.col(t).data();
    for (std::size_t a = 0; a < parts.size(); ++a, f += 3 * n) {
      double m[3][3] = {};  // [basis][component]
      for (Index q = 0; q < n; ++q)
        for (int b = 0; b < 3; ++b) {
          const double l = L(q, b);
          m[b][0] += l * f[3 * q];
          m[b][1] += l * f[3 * q + 1];
          m[b][2] += l * f[3 * q + 2];
        }
      const Part& part = parts[a];
      for (int d = 0; d < part.count; ++d)
        for (int k = 0; k < 3; ++k) o[3 * part.position[d] + k] += m[part.basis[d]][k];
    }
  }
}

/// (3 parts x r): the sums of a vector factor (rows 3 p + k) over each part's n points.
Eigen::MatrixXd sums_vector(const Eigen::MatrixXd& F, Index n) {
  const Index parts = F.rows() / (3 * n);
  Eigen::MatrixXd out(3 * parts, F.cols());
  for (Index t = 0; t < F.cols(); ++t) {
    const double* f = F.col(t).data();
    for (Index a = 0; a < parts; ++a) {
      double s[3] = {0.0, 0.0, 0.0};
      for (Index q = 0; q < n; ++q)
        for (int k = 0; k < 3; ++k) s[k] += f[3 * (a * n + q) + k];
      for (int k = 0; k < 3; ++k) out(3 * a + k, t) = s[k];
    }
  }
  return out;
}

/// (3 m x r): for each part a and each hat d of it (its position pos, c its surface curl),
/// the rows 3 pos + (0..2) of the result += add(c, a) (3 x r).
template <typename Add>
Eigen::MatrixXd by_hat_curls(const Surface& s, const std::vector<Part>& parts, Index m, Index r, Add add) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(3 * m, r);
  for (std::size_t a = 0; a < parts.size(); ++a) {
    const Part& part = parts[a];
    const Triangle& T = s.triangle(part.triangle);
    for (int d = 0; d < part.count; ++d)
      add(surface_curl(T, part.basis[d]), static_cast<Index>(a), out.middleRows(3 * part.position[d], 3));
  }
  return out;
}

/// D^T S: out (3 m x r), row 3 pos + k += c_k S(a, :), c the curl of the part's hat.
Eigen::MatrixXd divergence_map(const Surface& s, const std::vector<Part>& parts, Index m, const Eigen::MatrixXd& S) {
  return by_hat_curls(s, parts, m, S.cols(), [&S](const Vec3& c, Index a, auto rows) {
    rows.row(0) += c.x * S.row(a);
    rows.row(1) += c.y * S.row(a);
    rows.row(2) += c.z * S.row(a);
  });
}

/// Cx^T T: out (3 m x r), rows 3 pos + (0..2) += -c x T(3 a + (0..2), :).
Eigen::MatrixXd curl_map(const Surface& s, const std::vector<Part>& parts, Index m, const Eigen::MatrixXd& T) {
  return by_hat_curls(s, parts, m, T.cols(), [&T](const Vec3& c, Index a, auto rows) {
    const Index i = 3 * a;
    // -(c x t) = t x c
    rows.row(0) += c.z * T.row(i + 1) - c.y * T.row(i + 2);
    rows.row(1) += c.x * T.row(i + 2) - c.z * T.row(i);
    rows.row(2) += c.y * T.row(i) - c.x * T.row(i + 1);
  });
}

/// F kron I_3: (m x r) -> (3 m x 3 r), entry (3 i + k, 3 t + k) = F(i, t).
Eigen::MatrixXd kron3(const Eigen::MatrixXd& F) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(3 * F.rows(), 3 * F.cols());
  for (Index t = 0; t < F.cols(); ++t)
    for (int k = 0; k < 3; ++k)
      for (Index i = 0; i < F.rows(); ++i) out(3 * i + k, 3 * t + k) = F(i, t);
  return out;
}

/// A row block of two factors side by side.
Eigen::MatrixXd beside(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) {
  Eigen::MatrixXd out(A.rows(), A.cols() + B.cols());
  out << A, B;
  return out;
}

class LameBlock : public EntryBlock {
 public:
  LameBlock(const Data& d, const Index* I, Index m, const Index* J, Index k) : d_(d), I_(I), J_(J), m_(m), k_(k) {
    if (m % 3 != 0 || k % 3 != 0) throw std::logic_error("LameSurfaceEntries: a block of partial vertices");
    for (Index a = 0; a < m; a += 3) row_nodes_.push_back(I[a] / 3);
    for (Index a = 0; a < k; a += 3) col_nodes_.push_back(J[a] / 3);
    for (Index a = 0; a < m; ++a)
      if (I[a] != 3 * row_nodes_[static_cast<std::size_t>(a / 3)] + a % 3)
        throw std::logic_error("LameSurfaceEntries: a block of partial vertices");
    for (Index a = 0; a < k; ++a)
      if (J[a] != 3 * col_nodes_[static_cast<std::size_t>(a / 3)] + a % 3)
        throw std::logic_error("LameSurfaceEntries: a block of partial vertices");
    mn_ = m / 3;
    kn_ = k / 3;
    row_parts_ = parts(d.s, Space::P1, row_nodes_.data(), mn_);
    col_parts_ = parts(d.s, Space::P1, col_nodes_.data(), kn_);
  }

  void row(Index i, double* out) const override {
    const Eigen::MatrixXd& A = first_dense();
    for (Index j = 0; j < k_; ++j) out[j] = A(i, j);
  }
  void column(Index j, double* out) const override {
    const Eigen::MatrixXd& A = first_dense();
    for (Index i = 0; i < m_; ++i) out[i] = A(i, j);
  }
  void all(double* out) const override {
    Eigen::Map<Eigen::MatrixXd> result(out, m_, k_);
    if (d_.kind == LameSurfaceEntries::Kind::DoubleLayer && d_.cache) {
      Eigen::MatrixXd Y;
      if (d_.cache->take_dense(key(false), Y)) {
        result = Y;
        return;
      }
    }
    result = first_dense();
    if (d_.kind == LameSurfaceEntries::Kind::SingleLayer && d_.cache) cache_dense();
  }
  bool all_and_transpose(double* out, double* transposed) const override {
    if (d_.kind != LameSurfaceEntries::Kind::DoubleLayer) return false;
    Eigen::Map<Eigen::MatrixXd> a(out, m_, k_), b(transposed, k_, m_);
    if (d_.cache) {
      Eigen::MatrixXd Y, Yt;
      if (d_.cache->take_dense(key(false), Y) && d_.cache->take_dense(key(true), Yt)) {
        a = Y;
        b = Yt;
        return true;
      }
    }
    dense(false, true, true);
    a = Y_;
    b = Yt_;
    return true;
  }
  bool low_rank(double tol, LowRank& out) const override {
    if (!far_pairs_only()) return false;
    if (d_.kind == LameSurfaceEntries::Kind::DoubleLayer) {
      if (d_.cache && d_.cache->take_low_rank(key(false), out)) return true;
      far_factors(tol, false);
      recompress(Yf_, tol);  // as the cached blocks (the same factors with or without the cache)
      out = std::move(Yf_);
      return true;
    }
    far_factors(tol, true);
    out = std::move(Vf_);
    if (d_.cache) {
      // kept recompressed (as Y's H-matrix will hold them): the cache then holds no more than Y
      recompress(Yf_, tol);
      d_.cache->put_low_rank(key(false), std::move(Yf_));
      if (I_ != J_) {
        recompress(Ytf_, tol);
        d_.cache->put_low_rank(key(true), std::move(Ytf_));
      }
    }
    return true;
  }
  void companion_all(int which, double* out) const override {
    check_companion(which);
    if (!dense_done_) dense(true, false, false);
    Eigen::Map<Eigen::MatrixXd>(out, m_, k_) = Z_;
  }
  bool companion_low_rank(int which, double /*tol*/, LowRank& out) const override {
    check_companion(which);
    if (!factors_done_) return false;
    out = std::move(Zf_);
    return true;
  }

 private:
  Key key(bool mirrored) const { return mirrored ? Key{J_, k_, I_, m_} : Key{I_, m_, J_, k_}; }
  void check_companion(int which) const {
    if (which != 1 || d_.kind != LameSurfaceEntries::Kind::SingleLayer)
      throw std::logic_error("LameSurfaceEntries: only the single layer has a companion, Z");
  }
  /// The dense block of matrix 0 (V_h or Y), computed once.
  const Eigen::MatrixXd& first_dense() const {
    const bool single = d_.kind == LameSurfaceEntries::Kind::SingleLayer;
    if (!dense_done_) dense(single, !single || d_.cache != nullptr, single && d_.cache != nullptr);
    return single ? V_ : Y_;
  }
  void cache_dense() const {
    d_.cache->put_dense(key(false), std::move(Y_));
    if (I_ != J_) d_.cache->put_dense(key(true), std::move(Yt_));
  }

  /// Whether every triangle pair of the block is far (as SurfaceBlock's).
  bool far_pairs_only() const {
    Box br, bc;
    double radius = 0.0;
    for (const Part& p : row_parts_) {
      const Triangle& T = d_.s.triangle(p.triangle);
      for (const Vec3& v : T.p) br.add(v);
      radius = std::max(radius, T.radius);
    }
    for (const Part& p : col_parts_) {
      const Triangle& T = d_.s.triangle(p.triangle);
      for (const Vec3& v : T.p) bc.add(v);
      radius = std::max(radius, T.radius);
    }
    if (br.distance(bc) >= far_distance(radius)) return true;
    for (const Part& p : row_parts_)
      for (const Part& q : col_parts_)
        if (!PairIntegrator::far(d_.s.triangle(p.triangle), d_.s.triangle(q.triangle))) return false;
    return true;
  }

  /// The dense blocks: V_h and Z (with_vz), Y (with_y) and the mirrored Y(s, t) (with_yt):
  /// the far pairs by the far rule, summed in one pass over the point pairs, then the near
  /// field added. Returns the thread's seconds spent.
  double dense(bool with_vz, bool with_y, bool with_yt) const {
    const double t0 = thread_seconds();
    with_yt = with_yt && I_ != J_;
    if (with_vz) {
      V_.setZero(m_, k_);
      Z_.setZero(m_, k_);
    }
    if (with_y) Y_.setZero(m_, k_);
    if (with_yt) Yt_.setZero(k_, m_);
    far_dense(with_vz, with_y, with_yt);
    const LameSurfaceNearField& near = *d_.near;
    std::unordered_map<Index, Index> rows, cols;
    for (Index p = 0; p < m_; ++p) rows[I_[p]] = p;
    for (Index q = 0; q < k_; ++q) cols[J_[q]] = q;
    auto add_near = [](const RowSparse& A, const Index* dofs, Index count,
                       const std::unordered_map<Index, Index>& position, Eigen::MatrixXd& out) {
      for (Index p = 0; p < count; ++p)
        for (RowSparse::InnerIterator it(A, dofs[p]); it; ++it) {
          const auto c = position.find(it.col());
          if (c != position.end()) out(p, c->second) += it.value();
        }
    };
    if (with_vz) {
      add_near(near.single_layer(), I_, m_, cols, V_);
      add_near(near.hypersingular(), I_, m_, cols, Z_);
    }
    if (with_y) add_near(near.double_layer(), I_, m_, cols, Y_);
    if (with_yt) add_near(near.double_layer(), J_, k_, rows, Yt_);
    if (I_ == J_ && with_y) Yt_ = Y_;
    dense_done_ = true;
    const double seconds = thread_seconds() - t0;
    d_.dense_ns += static_cast<long>(1e9 * seconds);
    return seconds;
  }

  /// The far pairs' part of the dense blocks: per column triangle b, the seven kernels (g and
  /// R_kl) between every row point and b's points summed against b's hats and 1 (vectorised
  /// over the row points), then per far row triangle a reduced against a's hats and 1: the
  /// moments of the pair, from which the blocks of lame_surface.hpp follow.
  void far_dense(bool with_vz, bool with_y, bool with_yt) const {
    constexpr int n = kFarRulePoints;
    const TriangleRule& rule = far_rule();
    const Eigen::Matrix<double, Eigen::Dynamic, 4>& L = d_.L;
    const FarPoints rp(d_.s, row_parts_, mn_, false, rule), cp(d_.s, col_parts_, kn_, false, rule);
    // the row points padded to a multiple of the vector width (weight 0, far away)
    const Index P = rp.size(), P8 = (P + kWidth - 1) / kWidth * kWidth;
    std::vector<double> rx(static_cast<std::size_t>(P8), 1e30), ry(rx), rz(rx), rw(static_cast<std::size_t>(P8), 0.0);
    std::copy(rp.x.begin(), rp.x.end(), rx.begin());
    std::copy(rp.y.begin(), rp.y.end(), ry.begin());
    std::copy(rp.z.begin(), rp.z.end(), rz.begin());
    std::copy(rp.w.begin(), rp.w.end(), rw.begin());
    Eigen::MatrixXd AL(P8, 21);
    const PairBlocks blocks{d_.c};
    std::vector<Curls> row_curls;
    row_curls.reserve(row_parts_.size());
    for (const Part& a : row_parts_) row_curls.emplace_back(d_.s.triangle(a.triangle));
    Eigen::Matrix<double, 4, n> La;
    Eigen::Matrix<double, 4, 21> Mab;
    double M[7][4][4];  // [channel][test basis, 3: 1][trial basis, 3: 1] of the pair
    auto moment = [&M](int ch, int a, int b) { return M[ch][a][b]; };
    Block B, A33, T;
    for (std::size_t b = 0; b < col_parts_.size(); ++b) {
      const Part& cb = col_parts_[b];
      const Triangle& tb = d_.s.triangle(cb.triangle);
      const Curls curls_b(tb);
      accumulate(rx.data(), ry.data(), rz.data(), rw.data(), P8, cp, static_cast<Index>(b) * n, L, AL.data());
      for (std::size_t a = 0; a < row_parts_.size(); ++a) {
        const Part& ra = row_parts_[a];
        if (!PairIntegrator::far(d_.s.triangle(ra.triangle), tb)) continue;
        for (int i = 0; i < 3; ++i)
          for (int q = 0; q < n; ++q) La(i, q) = i < ra.count ? L(q, ra.basis[i]) : 0.0;
        La.row(3).setOnes();
        Mab.noalias() = La * AL.middleRows(static_cast<Index>(a) * n, n);
        // the trial side's hats in the block and its constant (the sum of its three barycentrics)
        for (int ch = 0; ch < 7; ++ch)
          for (int i = 0; i < 4; ++i) {
            for (int j = 0; j < cb.count; ++j) M[ch][i][j] = Mab(i, 3 * ch + cb.basis[j]);
            M[ch][i][3] = Mab(i, 3 * ch) + Mab(i, 3 * ch + 1) + Mab(i, 3 * ch + 2);
          }
        const Curls& curls_a = row_curls[a];
        if (with_vz) {
          blocks.companion(moment, 3, 3, A33);
          for (int i = 0; i < ra.count; ++i)
            for (int j = 0; j < cb.count; ++j) {
              blocks.single_layer(moment, i, j, B);
              add(V_, ra.position[i], cb.position[j], B);
              const int ia = ra.basis[i], jb = cb.basis[j];
              blocks.hypersingular(M[0][3][3], A33, curls_a.c[ia], curls_b.c[jb], curls_a.A[ia], curls_b.A[jb], B);
              add(Z_, ra.position[i], cb.position[j], B);
            }
        }
        if (with_y)
          for (int i = 0; i < ra.count; ++i) {
            blocks.companion(moment, i, 3, T);
            for (int j = 0; j < cb.count; ++j) {
              product(T, curls_b.A[cb.basis[j]], B);
              add(Y_, ra.position[i], cb.position[j], B);
            }
          }
        if (with_yt)
          for (int j = 0; j < cb.count; ++j) {
            blocks.companion(moment, 3, j, T);
            for (int i = 0; i < ra.count; ++i) {
              product(T, curls_a.A[ra.basis[i]], B);
              add(Yt_, cb.position[j], ra.position[i], B);
            }
          }
      }
    }
  }
  static void add(Eigen::MatrixXd& A, Index p, Index q, const Block& B) {
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) A(3 * p + k, 3 * q + l) += B[k][l];
  }
  /// AL(p, 3 c + beta) = sum over the points q of the column triangle (its n points from q0)
  /// of K_c(p, q) lambda_beta(q), for the P8 (padded) row points p (weights included; K_0 = g,
  /// K_1..6 = R_kl): kWidth row points at a time, their 21 sums kept in registers over q.
  static void accumulate(const double* rx, const double* ry, const double* rz, const double* rw, Index P8,
                         const FarPoints& c, Index q0, const Eigen::Matrix<double, Eigen::Dynamic, 4>& L, double* AL) {
    constexpr int n = kFarRulePoints;
    for (Index p0 = 0; p0 < P8; p0 += kWidth) {
      double acc[21][kWidth] = {};
      for (int q = 0; q < n; ++q) {
        const std::size_t j = static_cast<std::size_t>(q0 + q);
        const double x = c.x[j], y = c.y[j], z = c.z[j], w = kInvTwoPi * c.w[j];
        const double l0 = L(q, 0), l1 = L(q, 1), l2 = L(q, 2);
#pragma omp simd
        for (int v = 0; v < kWidth; ++v) {
          const Index p = p0 + v;
          const double dx = rx[p] - x, dy = ry[p] - y, dz = rz[p] - z;
          const double s = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
          const double g = w * rw[p] * s, h = g * s * s;
          const double k[7] = {g, h * dx * dx, h * dy * dy, h * dz * dz, h * dx * dy, h * dx * dz, h * dy * dz};
          for (int ch = 0; ch < 7; ++ch) {
            acc[3 * ch][v] += k[ch] * l0;
            acc[3 * ch + 1][v] += k[ch] * l1;
            acc[3 * ch + 2][v] += k[ch] * l2;
          }
        }
      }
      for (int col = 0; col < 21; ++col)
        for (int v = 0; v < kWidth; ++v) AL[col * P8 + p0 + v] = acc[col][v];
    }
  }

  /// The admissible block's factors: V_h and Z (with_v) and Y, Y(s, t), from ACA of the point
  /// kernels g and A (grouped). A block whose ranks would not pay (A's rank, about 3 times g's,
  /// at least m k / (m + k): held dense after the recompression anyway) is summed densely
  /// instead, by the far pass of the dense blocks (cheaper than the cross approximation there),
  /// and handed over as D = D I (recompressed by HMatrix::fill as any factors).
  void far_factors(double tol, bool with_v) const {
    const double t0 = thread_seconds();
    constexpr int n = kFarRulePoints;
    const TriangleRule& rule = far_rule();
    const FarPoints rp(d_.s, row_parts_, mn_, false, rule), cp(d_.s, col_parts_, kn_, false, rule);
    const double point_tol = LameSurfaceEntries::kPointTolerance * tol;
    const Index Pr = rp.size(), Pc = cp.size();
    const double a1 = d_.c.a1, a0 = d_.c.a0, mu = d_.c.mu;
    const PointKernel kernel{rp, cp, PointKernelKind::SingleLayer};
    const Slice row = [&kernel](Index i, double* o) { kernel.row(i, o); };
    const Slice column = [&kernel](Index j, double* o) { kernel.column(j, o); };
    const LowRank G = aca(Pr, Pc, row, column, point_tol, std::min(Pr, Pc));
    if (static_cast<double>(kRankRatio * G.rank() * (m_ + k_)) >= static_cast<double>(m_) * static_cast<double>(k_)) {
      const double summed = dense(with_v, true, true);
      auto identity = [](const Eigen::MatrixXd& D) {
        LowRank f;
        f.U = D;
        f.V = Eigen::MatrixXd::Identity(D.cols(), D.cols());
        return f;
      };
      if (with_v) {
        Vf_ = identity(V_);
        Zf_ = identity(Z_);
      }
      Yf_ = identity(Y_);
      Ytf_ = identity(Yt_);
      factors_done_ = true;
      d_.low_rank_ns += static_cast<long>(1e9 * (thread_seconds() - t0 - summed));
      return;
    }
    // A's rows of point p: out[(3 k + l) Pc + q]; its columns of point q: out[(3 l + k) Pr + p]
    // (A(p, q) is symmetric, so both are the same loop over the other side's points)
    auto group = [a1, a0](const FarPoints& here, Index i, const FarPoints& there, double* out) {
      const std::size_t s0 = static_cast<std::size_t>(i);
      const double x = here.x[s0], y = here.y[s0], z = here.z[s0], w = kInvTwoPi * here.w[s0];
      const double *tx = there.x.data(), *ty = there.y.data(), *tz = there.z.data(), *tw = there.w.data();
      const Index n = there.size();
      double *o00 = out, *o01 = out + n, *o02 = out + 2 * n, *o10 = out + 3 * n, *o11 = out + 4 * n, *o12 = out + 5 * n,
             *o20 = out + 6 * n, *o21 = out + 7 * n, *o22 = out + 8 * n;
#pragma omp simd
      for (Index q = 0; q < n; ++q) {
        const double dx = x - tx[q], dy = y - ty[q], dz = z - tz[q];
        const double s = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
        const double g = w * tw[q] * s, h = a1 * g * s * s, d = a0 * g;
        const double xy = h * dx * dy, xz = h * dx * dz, yz = h * dy * dz;
        o00[q] = h * dx * dx + d;
        o11[q] = h * dy * dy + d;
        o22[q] = h * dz * dz + d;
        o01[q] = o10[q] = xy;
        o02[q] = o20[q] = xz;
        o12[q] = o21[q] = yz;
      }
    };
    const auto rows = [&](Index p, double* out) { group(rp, p, cp, out); };
    const auto columns = [&](Index q, double* out) { group(cp, q, rp, out); };
    const LowRank A = grouped_point_aca(Pr, Pc, rows, columns, point_tol, std::min(3 * Pr, 3 * Pc));
    const Index r = A.rank();
    Eigen::MatrixXd QAr = Eigen::MatrixXd::Zero(3 * mn_, r), QAc = Eigen::MatrixXd::Zero(3 * kn_, r);
    hat_vector(row_parts_, d_.L, A.U, QAr);
    hat_vector(col_parts_, d_.L, A.V, QAc);
    const Eigen::MatrixXd SAr = sums_vector(A.U, n), SAc = sums_vector(A.V, n);
    const Eigen::MatrixXd CAc = curl_map(d_.s, col_parts_, kn_, SAc), CAr = curl_map(d_.s, row_parts_, mn_, SAr);
    Yf_.U = QAr;
    Yf_.V = CAc;
    Ytf_.U = QAc;
    Ytf_.V = CAr;
    if (with_v) {
      // V_L's and D^T g D's factors at the dofs recompressed first (to tol / 10 of their own
      // norms): V_L kron I then adds three times the rank the dofs need, not the points'
      const Index rg = G.rank();
      LowRank VL{Eigen::MatrixXd::Zero(mn_, rg), Eigen::MatrixXd::Zero(kn_, rg)};
      add_values_transpose_product(row_parts_, rule, G.U, VL.U);
      add_values_transpose_product(col_parts_, rule, G.V, VL.V);
      recompress(VL, kPartTolerance * tol);
      Vf_.U = beside(kron3(VL.U), QAr) / (2.0 * mu);
      Vf_.V = beside(kron3(VL.V), QAc);
      const Eigen::MatrixXd Sgr = sum_over_parts(G.U, n), Sgc = sum_over_parts(G.V, n);
      LowRank DL{divergence_map(d_.s, row_parts_, mn_, Sgr), divergence_map(d_.s, col_parts_, kn_, Sgc)};
      recompress(DL, kPartTolerance * tol);
      Zf_.U = beside(-mu * DL.U, -2.0 * mu * CAr);
      Zf_.V = beside(DL.V, CAc);
    }
    factors_done_ = true;
    d_.low_rank_ns += static_cast<long>(1e9 * (thread_seconds() - t0));
  }

  const Data& d_;
  const Index *I_, *J_;
  Index m_, k_, mn_ = 0, kn_ = 0;
  std::vector<Index> row_nodes_, col_nodes_;
  std::vector<Part> row_parts_, col_parts_;
  mutable Eigen::MatrixXd V_, Z_, Y_, Yt_;
  mutable bool dense_done_ = false, factors_done_ = false;
  mutable LowRank Vf_, Zf_, Yf_, Ytf_;
};

}  // namespace

LameSurfaceEntries::LameSurfaceEntries(const Surface& surface, const Lame& m, Kind kind,
                                       std::shared_ptr<const LameSurfaceNearField> near,
                                       std::shared_ptr<LameSurfaceBlockCache> cache) {
  check_medium(m);
  if (!near) throw std::invalid_argument("LameSurfaceEntries: need the near field");
  data_ = std::make_shared<Data>(surface, m, kind, std::move(near), std::move(cache));
}

std::unique_ptr<EntryBlock> LameSurfaceEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<LameBlock>(*data_, I, m, J, k);
}

LameSurfaceTimes LameSurfaceEntries::times() const {
  return {data_->dense_ns.load() * 1e-9, data_->low_rank_ns.load() * 1e-9};
}

ClusterTree lame_surface_cluster_tree(const Surface& s, Index leaf_size) {
  return surface_cluster_tree(s, Space::P1, leaf_size).expanded(3);
}

}  // namespace bem
