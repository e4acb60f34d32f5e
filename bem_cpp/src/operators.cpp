#include "bem/operators.hpp"

#include <algorithm>
#include <cstdint>
#include <vector>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "bem/log_integrals.hpp"

namespace bem {

namespace {

constexpr double kInvPi = 0.318309886183790671537767526745;
constexpr Index kTile = 32;

PairRelation relation(Index i, Index j, Index n) {
  if (j == i) return PairRelation::Coincident;
  if (j == i + 1) return PairRelation::EndToStart;
  if (i == 0 && j == n - 1) return PairRelation::StartToEnd;
  return PairRelation::Separated;
}

/// n x n matrix, zero, first touched in parallel (pages spread over the threads) and,
/// on Linux, backed by transparent huge pages where available: fewer page faults and
/// TLB misses in the transposing passes.
Matrix zeros(Index n) {
  Matrix A(n, n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t huge = std::uintptr_t{1} << 21;
  const auto begin = reinterpret_cast<std::uintptr_t>(A.data());
  const auto end = begin + static_cast<std::uintptr_t>(A.size()) * sizeof(double);
  const std::uintptr_t first = (begin + huge - 1) & ~(huge - 1), last = end & ~(huge - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#endif
#pragma omp parallel for schedule(static)
  for (Index r = 0; r < n; ++r) A.row(r).setZero();
  return A;
}

/// Calls f(i) for every panel i, in parallel, such that panels processed at the same
/// time never share a node: even panels, then odd panels, then the last panel if n is
/// odd (it shares node 0 with panel 0). f(i) may then write rows i and i+1 freely.
template <class F>
void for_each_panel_coloured(Index n, F&& f) {
  const Index n_even = n / 2;  // even panels, without panel n - 1 when n is odd
  const Index n_odd = n / 2;
#pragma omp parallel
  {
    // Panel i carries n - i pairs: dynamic scheduling balances the triangle.
#pragma omp for schedule(dynamic, 1)
    for (Index k = 0; k < n_even; ++k) f(2 * k);
#pragma omp for schedule(dynamic, 1)
    for (Index k = 0; k < n_odd; ++k) f(2 * k + 1);
#pragma omp single
    if (n % 2 == 1) f(n - 1);
  }
}

/// Applies f(r, c) to all r < c, tile by tile, in parallel; tiles (I, J) and (J, I)
/// belong to one thread, so f may touch (r, c) and (c, r).
template <class F>
void for_each_upper_tiled(Index n, F&& f) {
  const Index nb = (n + kTile - 1) / kTile;
#pragma omp parallel for schedule(dynamic, 1)
  for (Index I = 0; I < nb; ++I)
    for (Index J = I; J < nb; ++J)
      for (Index r = I * kTile; r < std::min(n, (I + 1) * kTile); ++r)
        for (Index c = std::max(J * kTile, r + 1); c < std::min(n, (J + 1) * kTile); ++c) f(r, c);
}

void mirror_upper_in_place(Matrix& A) {
  for_each_upper_tiled(A.rows(), [&A](Index r, Index c) { A(c, r) = A(r, c); });
}

/// U holds sum_{pairs i <= j} of the P1 blocks (the diagonal pairs halved) in rows of
/// panel i. V = U + U^T; U's lower triangle is zero except on the subdiagonal and in
/// column 0 (the hat of node 0 also lives on panel n-1), so V's upper triangle needs
/// O(n) corrections only.
void complete_upper_from_pairs(Matrix& U) {
  const Index n = U.rows();
  for (Index r = 0; r < n; ++r) U(r, r) *= 2.0;
  for (Index r = 0; r + 1 < n; ++r) U(r, r + 1) += U(r + 1, r);
  for (Index c = 2; c < n; ++c) U(0, c) += U(c, 0);
}

/// W = D^T V0 D (upper triangle; V0 read from its upper triangle):
/// W[r, c] = Z[r, c] - Z[r, c-1] - Z[r-1, c] + Z[r-1, c-1], Z[i, j] = V0[i, j]/(h_i h_j),
/// indices mod n.
void maue_upper(const Vector& h, const Matrix& V0, Matrix& W) {
  const Index n = V0.rows();
  auto z = [&](Index i, Index j) {
    i = (i + n) % n;
    j = (j + n) % n;
    return (i <= j ? V0(i, j) : V0(j, i)) / (h(i) * h(j));
  };
#pragma omp parallel for schedule(dynamic, 16)
  for (Index r = 0; r < n; ++r) {
    if (r == 0) {
      for (Index c = 0; c < n; ++c) W(0, c) = z(0, c) - z(0, c - 1) - z(-1, c) + z(-1, c - 1);
      continue;
    }
    // Interior of the row: all four entries in the upper triangle, no wrap-around.
    W(r, r) = z(r, r) - z(r, r - 1) - z(r - 1, r) + z(r - 1, r - 1);
    const double hr = 1.0 / h(r), hq = 1.0 / h(r - 1);
    for (Index c = r + 1; c < n; ++c) {
      const double hc = 1.0 / h(c), hp = 1.0 / h(c - 1);
      W(r, c) = hr * (hc * V0(r, c) - hp * V0(r, c - 1)) - hq * (hc * V0(r - 1, c) - hp * V0(r - 1, c - 1));
    }
  }
}

}  // namespace

Operators assemble(const Polygon& polygon, const OperatorRequest& request) {
  const Index n = polygon.size();
  const bool v_p1 = request.single_layer == Space::P1;
  const bool v_p0 = request.single_layer == Space::P0;
  const bool need_v0 = v_p0 || request.hypersingular;
  const bool k_p1 = request.double_layer == Space::P1;
  const bool k_p0 = request.double_layer == Space::P0;
  const bool with_k = k_p1 || k_p0;

  // U: P1 single layer from the pairs (i, j >= i); V0: P0 single layer (upper
  // triangle); Kup: pairs (i, j >= i) of K; T: transposed contributions of pairs (j, i).
  Matrix U, V0, Kup, T;
  if (v_p1) U = zeros(n);
  if (need_v0) V0.resize(n, n);
  if (with_k) {
    Kup = zeros(n);
    T = zeros(n);
  }

  const PanelArrays arrays(polygon);
  for_each_panel_coloured(n, [&](Index i) {
    const Panel& pi = polygon.panel(i);
    const Index i1 = (i + 1) % n;
    auto scatter = [&](Index j, const PairBlocks& B) {
      const Index j1 = (j + 1) % n;
      if (v_p1) {
        const double w = j == i ? -0.5 * kInvPi : -kInvPi;  // diagonal pairs count twice
        U(i, j) += w * B.v[0][0];
        U(i, j1) += w * B.v[0][1];
        U(i1, j) += w * B.v[1][0];
        U(i1, j1) += w * B.v[1][1];
      }
      if (need_v0) V0(i, j) = -kInvPi * (B.v[0][0] + B.v[0][1] + B.v[1][0] + B.v[1][1]);
      if (k_p1) {
        Kup(i, j) += kInvPi * B.kij[0][0];
        Kup(i, j1) += kInvPi * B.kij[0][1];
        Kup(i1, j) += kInvPi * B.kij[1][0];
        Kup(i1, j1) += kInvPi * B.kij[1][1];
        if (j != i) {  // T[node a of i, node b of j] += kji[b][a]
          T(i, j) += kInvPi * B.kji[0][0];
          T(i, j1) += kInvPi * B.kji[1][0];
          T(i1, j) += kInvPi * B.kji[0][1];
          T(i1, j1) += kInvPi * B.kji[1][1];
        }
      }
      if (k_p0) {
        Kup(i, j) += kInvPi * (B.kij[0][0] + B.kij[1][0]);
        Kup(i, j1) += kInvPi * (B.kij[0][1] + B.kij[1][1]);
        if (j != i) {  // T[node a of i, panel j] += sum_b kji[b][a]
          T(i, j) += kInvPi * (B.kji[0][0] + B.kji[1][0]);
          T(i1, j) += kInvPi * (B.kji[0][1] + B.kji[1][1]);
        }
      }
    };
    // Far pairs are queued by number of Gauss points and evaluated in vector batches.
    Index queue[kMaxFarPoints + 1][kFarBatch];
    int queued[kMaxFarPoints + 1] = {};
    PairBlocks batch[kFarBatch];
    auto flush = [&](int p) {
      far_blocks_batch(pi, arrays, queue[p], queued[p], p, with_k, batch);
      for (int k = 0; k < queued[p]; ++k) scatter(queue[p][k], batch[k]);
      queued[p] = 0;
    };
    PairBlocks B;
    for (Index j = i; j < n; ++j) {
      const Panel& pj = polygon.panel(j);
      const PairRelation rel = relation(i, j, n);
      const int p = rel == PairRelation::Separated ? far_field_points(pi, pj) : 0;
      if (p == 0) {
        pair_blocks(pi, pj, rel, with_k, B);
        scatter(j, B);
        continue;
      }
      queue[p][queued[p]++] = j;
      if (queued[p] == kFarBatch) flush(p);
    }
    for (int p = 1; p <= kMaxFarPoints; ++p)
      if (queued[p] > 0) flush(p);
  });

  Operators ops;
  if (v_p1) {
    complete_upper_from_pairs(U);
    if (request.full_symmetric) mirror_upper_in_place(U);
    ops.single_layer = std::move(U);
  }
  if (with_k) {
    // K = Kup + T^T: both are zero below the subdiagonal except in column 0.
    for_each_upper_tiled(n, [&](Index r, Index c) {
      Kup(r, c) += T(c, r);
      Kup(c, r) += T(r, c);
    });
    for (Index r = 0; r < n; ++r) Kup(r, r) += T(r, r);
    ops.double_layer = std::move(Kup);
  }
  if (request.hypersingular) {
    Matrix W = with_k ? std::move(T) : Matrix(n, n);  // T's storage is free again
    maue_upper(polygon.lengths(), V0, W);
    if (request.full_symmetric) mirror_upper_in_place(W);
    ops.hypersingular = std::move(W);
  }
  if (v_p0) {
    if (request.full_symmetric) mirror_upper_in_place(V0);
    ops.single_layer = std::move(V0);
  }
  return ops;
}

Matrix single_layer(const Polygon& polygon, Space space) {
  OperatorRequest r;
  r.single_layer = space;
  return std::move(assemble(polygon, r).single_layer);
}

Matrix double_layer(const Polygon& polygon, Space space) {
  OperatorRequest r;
  r.double_layer = space;
  return std::move(assemble(polygon, r).double_layer);
}

Matrix hypersingular(const Polygon& polygon) {
  OperatorRequest r;
  r.hypersingular = true;
  return std::move(assemble(polygon, r).hypersingular);
}

Matrix mass(const Polygon& polygon, Space space) {
  Matrix M = Matrix::Zero(polygon.size(), polygon.size());
  add_mass(polygon, space, 1.0, M);
  return M;
}

void add_mass(const Polygon& polygon, Space space, double scale, Matrix& K) {
  const Index n = polygon.size();
  for (Index i = 0; i < n; ++i) {
    const double h = scale * polygon.panel(i).h;
    const Index i1 = (i + 1) % n;
    if (space == Space::P0) {  // int_{panel i} hat_i = int_{panel i} hat_{i+1} = h/2
      K(i, i) += 0.5 * h;
      K(i, i1) += 0.5 * h;
    } else {  // element mass matrix h/6 [[2, 1], [1, 2]]
      K(i, i) += h / 3.0;
      K(i1, i1) += h / 3.0;
      K(i, i1) += h / 6.0;
      K(i1, i) += h / 6.0;
    }
  }
}

Matrix single_layer(const Eigen::Ref<const Points>& nodes, Space space) {
  return single_layer(Polygon(nodes), space);
}
Matrix double_layer(const Eigen::Ref<const Points>& nodes, Space space) {
  return double_layer(Polygon(nodes), space);
}
Matrix hypersingular(const Eigen::Ref<const Points>& nodes) { return hypersingular(Polygon(nodes)); }
Matrix mass(const Eigen::Ref<const Points>& nodes, Space space) { return mass(Polygon(nodes), space); }

}  // namespace bem
