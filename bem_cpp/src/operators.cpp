#include "bem/operators.hpp"

#include <algorithm>
#include <vector>

#include <omp.h>

#include "bem/far_field.hpp"
#include "bem/log_integrals.hpp"

namespace bem {

namespace {

constexpr double kInvPi = 0.318309886183790671537767526745;
constexpr Index kTile = 32;

/// Adds the blocks of the pairs (i, j), j in [j0, n), stored by columns j, to a row:
/// the value for the start node of panel j goes to column j, the one for its end node to
/// column j + 1 (0 for j = n - 1): row[j] += start[j] + end[j - 1] for j in [j0, n)
/// (end[j0 - 1] taken as 0, or end[n - 1] if j0 = 0), row[0] += end[n - 1] if j0 > 0.
void add_shifted(double* row, const double* start, const double* end, Index j0, Index n) {
  row[j0] += start[j0] + (j0 == 0 ? end[n - 1] : 0.0);
#pragma omp simd
  for (Index j = j0 + 1; j < n; ++j) row[j] += start[j] + end[j - 1];
  if (j0 > 0) row[0] += end[n - 1];
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

}  // namespace

Matrix parallel_zeros(Index n) {
  Matrix A(n, n);
#pragma omp parallel for schedule(static)
  for (Index r = 0; r < n; ++r) A.row(r).setZero();
  return A;
}

Operators assemble(const Polygon& polygon, const OperatorRequest& request) {
  const Index n = polygon.size();
  const bool v_p1 = request.single_layer == Space::P1;
  const bool v_p0 = request.single_layer == Space::P0;
  const bool w = request.hypersingular;
  const bool k_p1 = request.double_layer == Space::P1;
  const bool k_p0 = request.double_layer == Space::P0;
  const bool with_v = v_p1 || v_p0 || w;
  const bool with_k = k_p1 || k_p0;

  // V and W (symmetric) from the pairs (i, j >= i): U for V (P1) and UW for
  // W = D^T V0 D accumulate the blocks in the rows of panel i, the mirrored pairs
  // follow from symmetry (complete_upper_from_pairs); V0 (P0) is written directly on
  // its upper triangle. K (not symmetric) from all pairs (i, j): the pairs j < i need
  // only the double-layer kernel, which is cheap (no logarithm).
  Matrix U, V0, UW, K;
  if (v_p1) U = parallel_zeros(n);
  if (v_p0) V0.resize(n, n);
  if (w) UW = parallel_zeros(n);
  if (with_k) K = parallel_zeros(n);

  const PanelArrays arrays(polygon);
  const Vector h = polygon.lengths();
  // Per thread: the blocks of the pairs (i, j) of the current panel i by columns j, and
  // the number of far-field Gauss points of each pair.
  const auto threads = static_cast<std::size_t>(omp_get_max_threads());
  std::vector<std::vector<double>> column_store(threads);
  std::vector<std::vector<int>> points_store(threads);

  for_each_panel_coloured(n, [&](Index i) {
    const auto thread = static_cast<std::size_t>(omp_get_thread_num());
    std::vector<double>& store = column_store[thread];
    store.resize(static_cast<std::size_t>(9 * n));
    points_store[thread].resize(static_cast<std::size_t>(n));
    int* points = points_store[thread].data();
    PairBlockColumns col;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        col.v[a][b] = store.data() + (2 * a + b) * n;
        col.kij[a][b] = store.data() + (4 + 2 * a + b) * n;
      }
    double* z = store.data() + 8 * n;  // scratch column

    // 1. Blocks of the pairs (i, j) for j in [j0, j1), with the factors -1/pi (V) and
    //    1/pi (K) of the operators: far pairs are queued by number of Gauss points and
    //    evaluated in vector batches, the others one by one.
    const Panel& pi = polygon.panel(i);
    const Index i1 = (i + 1) % n;
    auto compute = [&](Index j0, Index j1, bool v, bool k) {
      far_field_points(pi, arrays, j0, j1, points);
      FarBatches far(
          [&](int p, const Index* js, int m) { far_blocks_batch(pi, arrays, js, m, p, v, k, col, -kInvPi, kInvPi); });
      PairBlocks B;
      for (Index j = j0; j < j1; ++j) {
        const PairRelation rel = panel_relation(i, j, n);
        const int p = rel == PairRelation::Separated ? points[j] : 0;
        if (p > 0) {
          far.push(p, j);
          continue;
        }
        pair_blocks(pi, polygon.panel(j), rel, k, B);
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b) {
            if (v) col.v[a][b][j] = -kInvPi * B.v[a][b];
            if (k) col.kij[a][b][j] = kInvPi * B.kij[a][b];
          }
      }
      far.finish();
    };
    if (with_v || with_k) compute(i, n, with_v, with_k);
    if (with_k) compute(0, i, false, true);

    // 2. Add them to the rows of panel i: its start node i and end node i1.
    double* const* v = &col.v[0][0];  // v[2a + b]
    if (with_v) {
      // The pair (i, i) is mirrored onto itself: it counts half in U and UW.
      for (int k = 0; k < 4; ++k) v[k][i] *= 0.5;
    }
    if (v_p1) {
      add_shifted(U.row(i).data(), v[0], v[1], i, n);
      add_shifted(U.row(i1).data(), v[2], v[3], i, n);
    }
    if (v_p0) {
      double* r = V0.row(i).data();
#pragma omp simd
      for (Index j = i; j < n; ++j) r[j] = v[0][j] + v[1][j] + v[2][j] + v[3][j];
      r[i] *= 2.0;
    }
    if (w) {
      // W = sum over pairs of V0[i, j] D_i^T D_j, D_i = (-1/h_i, +1/h_i) on the nodes of
      // panel i: rows i and i1 get -+ (z[j] - z[j-1]), z[j] = V0[i, j]/(h_i h_j).
      const double* hj = h.data();
      const double s = 1.0 / h(i);
#pragma omp simd
      for (Index j = i; j < n; ++j) z[j] = s * (v[0][j] + v[1][j] + v[2][j] + v[3][j]) / hj[j];
      double* r0 = UW.row(i).data();
      double* r1 = UW.row(i1).data();
      r0[i] += z[i];
      r1[i] -= z[i];
#pragma omp simd
      for (Index j = i + 1; j < n; ++j) {
        r0[j] += z[j] - z[j - 1];
        r1[j] -= z[j] - z[j - 1];
      }
      r0[0] -= z[n - 1];
      r1[0] += z[n - 1];
    }
    if (k_p1) {
      add_shifted(K.row(i).data(), col.kij[0][0], col.kij[0][1], 0, n);
      add_shifted(K.row(i1).data(), col.kij[1][0], col.kij[1][1], 0, n);
    }
    if (k_p0) {
      // P0 row of panel i: K[i, node b of j] += sum_a kij[a][b].
#pragma omp simd
      for (Index j = 0; j < n; ++j) {
        col.kij[0][0][j] += col.kij[1][0][j];
        col.kij[0][1][j] += col.kij[1][1][j];
      }
      add_shifted(K.row(i).data(), col.kij[0][0], col.kij[0][1], 0, n);
    }
  });

  Operators ops;
  if (v_p1) {
    complete_upper_from_pairs(U);
    if (request.full_symmetric) mirror_upper_in_place(U);
    ops.single_layer = std::move(U);
  }
  if (v_p0) {
    if (request.full_symmetric) mirror_upper_in_place(V0);
    ops.single_layer = std::move(V0);
  }
  if (w) {
    complete_upper_from_pairs(UW);
    if (request.full_symmetric) mirror_upper_in_place(UW);
    ops.hypersingular = std::move(UW);
  }
  if (with_k) ops.double_layer = std::move(K);
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

Matrix single_layer(const Eigen::Ref<const Points>& nodes, Space space) { return single_layer(Polygon(nodes), space); }
Matrix double_layer(const Eigen::Ref<const Points>& nodes, Space space) { return double_layer(Polygon(nodes), space); }
Matrix hypersingular(const Eigen::Ref<const Points>& nodes) { return hypersingular(Polygon(nodes)); }
Matrix mass(const Eigen::Ref<const Points>& nodes, Space space) { return mass(Polygon(nodes), space); }

}  // namespace bem
