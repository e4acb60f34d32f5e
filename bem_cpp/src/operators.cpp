#include "bem/operators.hpp"

#include <algorithm>
#include <vector>

#include <omp.h>

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

/// n x n zero matrix, first touched in parallel (the page faults are shared out).
Matrix zeros(Index n) {
  Matrix A(n, n);
#pragma omp parallel for schedule(static)
  for (Index r = 0; r < n; ++r) A.row(r).setZero();
  return A;
}

/// row[j] += s (start[j] + end[j - 1]) for j in [i, n) (end[i - 1] taken as 0), and
/// row[0] += s end[n - 1]: adds the blocks of the pairs (i, j >= i), stored by columns
/// j, for the start node j and the end node j + 1 of panel j.
void add_shifted(double* row, double s, const double* start, const double* end, Index i, Index n) {
  row[i] += s * start[i];
#pragma omp simd
  for (Index j = i + 1; j < n; ++j) row[j] += s * (start[j] + end[j - 1]);
  row[0] += s * end[n - 1];
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

/// K += T^T, by pairs of square tiles (I, J), (J, I) owned by one thread.
void add_transpose_in_place(const Matrix& T, Matrix& K) {
  const Index n = K.rows(), nb = (n + kTile - 1) / kTile;
#pragma omp parallel for schedule(dynamic, 1)
  for (Index I = 0; I < nb; ++I) {
    const Index r0 = I * kTile, r1 = std::min(n, r0 + kTile);
    for (Index J = I; J < nb; ++J) {
      const Index c0 = J * kTile, c1 = std::min(n, c0 + kTile);
      if (I == J) {
        double tile[kTile][kTile];  // T's diagonal tile, before K is changed
        for (Index r = r0; r < r1; ++r)
          for (Index c = c0; c < c1; ++c) tile[r - r0][c - c0] = T(r, c);
        for (Index r = r0; r < r1; ++r)
          for (Index c = c0; c < c1; ++c) K(r, c) += tile[c - c0][r - r0];
        continue;
      }
      for (Index r = r0; r < r1; ++r) {
        const double* t_row = &T(r, 0);
        double* k_row = &K(r, 0);
        for (Index c = c0; c < c1; ++c) {
          k_row[c] += T(c, r);
          K(c, r) += t_row[c];
        }
      }
    }
  }
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
  const auto& thresholds = gauss_thresholds();
  // Per thread: the blocks of all pairs (i, j >= i) of the current panel i, by columns j.
  std::vector<std::vector<double>> column_store(static_cast<std::size_t>(omp_get_max_threads()));

  for_each_panel_coloured(n, [&](Index i) {
    std::vector<double>& store = column_store[static_cast<std::size_t>(omp_get_thread_num())];
    store.resize(static_cast<std::size_t>(12 * n));
    PairBlockColumns col;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        col.v[a][b] = store.data() + (0 + 2 * a + b) * n;
        col.kij[a][b] = store.data() + (4 + 2 * a + b) * n;
        col.kji[a][b] = store.data() + (8 + 2 * a + b) * n;
      }

    // 1. Blocks of every pair (i, j >= i); far pairs are queued by number of Gauss
    //    points and evaluated in vector batches.
    const Panel& pi = polygon.panel(i);
    Index queue[kMaxFarPoints + 1][kFarBatch];
    int queued[kMaxFarPoints + 1] = {};
    auto flush = [&](int p) {
      far_blocks_batch(pi, arrays, queue[p], queued[p], p, with_k, col);
      queued[p] = 0;
    };
    PairBlocks B;
    for (Index j = i; j < n; ++j) {
      const Panel& pj = polygon.panel(j);
      const PairRelation rel = relation(i, j, n);
      const int p = rel == PairRelation::Separated ? far_field_points(pi, pj, thresholds) : 0;
      if (p > 0) {
        queue[p][queued[p]++] = j;
        if (queued[p] == kFarBatch) flush(p);
        continue;
      }
      pair_blocks(pi, pj, rel, with_k, B);
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) {
          col.v[a][b][j] = B.v[a][b];
          if (with_k) {
            col.kij[a][b][j] = B.kij[a][b];
            col.kji[a][b][j] = B.kji[a][b];
          }
        }
    }
    for (int p = 1; p <= kMaxFarPoints; ++p)
      if (queued[p] > 0) flush(p);

    // 2. Add them to the rows of panel i (its start node i and end node i1). The block
    //    of pair (i, j) meets columns j (start of j) and j1 = j + 1 (end of j, 0 for
    //    j = n - 1). The coincident pair counts half in U (U + U^T doubles it) and has
    //    no mirrored part in T.
    const Index i1 = (i + 1) % n;
    double* const* v = &col.v[0][0];  // v[2a + b]
    if (v_p1 || need_v0) {
      // Coincident block halved once, used by U and (doubled back) by V0.
      for (int k = 0; k < 4; ++k) v[k][i] *= 0.5;
    }
    if (v_p1) {
      add_shifted(U.row(i).data(), -kInvPi, v[0], v[1], i, n);
      add_shifted(U.row(i1).data(), -kInvPi, v[2], v[3], i, n);
    }
    if (need_v0) {
      double* r = V0.row(i).data();
#pragma omp simd
      for (Index j = i; j < n; ++j) r[j] = -kInvPi * (v[0][j] + v[1][j] + v[2][j] + v[3][j]);
      r[i] *= 2.0;
    }
    if (with_k) {
      double* const* kij = &col.kij[0][0];
      double* const* kji = &col.kji[0][0];
      for (int k = 0; k < 4; ++k) kji[k][i] = 0.0;  // the pair (i, i) is not mirrored
      if (k_p1) {
        add_shifted(Kup.row(i).data(), kInvPi, kij[0], kij[1], i, n);
        add_shifted(Kup.row(i1).data(), kInvPi, kij[2], kij[3], i, n);
        // T[node a of i, node b of j] += kji[b][a]
        add_shifted(T.row(i).data(), kInvPi, kji[0], kji[2], i, n);
        add_shifted(T.row(i1).data(), kInvPi, kji[1], kji[3], i, n);
      } else {
        // P0 rows: K[i, node b of j] += sum_a kij[a][b]; T[node a of i, j] += sum_b kji[b][a]
#pragma omp simd
        for (Index j = i; j < n; ++j) {
          kij[0][j] += kij[2][j];
          kij[1][j] += kij[3][j];
        }
        add_shifted(Kup.row(i).data(), kInvPi, kij[0], kij[1], i, n);
        double* t0 = T.row(i).data();
        double* t1 = T.row(i1).data();
#pragma omp simd
        for (Index j = i; j < n; ++j) {
          t0[j] += kInvPi * (kji[0][j] + kji[2][j]);
          t1[j] += kInvPi * (kji[1][j] + kji[3][j]);
        }
      }
    }
  });

  Operators ops;
  if (v_p1) {
    complete_upper_from_pairs(U);
    if (request.full_symmetric) mirror_upper_in_place(U);
    ops.single_layer = std::move(U);
  }
  if (with_k) {
    add_transpose_in_place(T, Kup);
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
