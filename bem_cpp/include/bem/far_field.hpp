#pragma once
// Far-field panel pairs in vector batches (src/far_field.cpp): the tensor Gauss rule of
// far_blocks (log_integrals.hpp) evaluated for many panels j of one panel i at once,
// with the loop over j vectorised; used by the assembly (operators.cpp).
#include <utility>
#include <vector>

#include "bem/geometry.hpp"
#include "bem/log_integrals.hpp"

namespace bem {

/// Panel data as structure of arrays, for the vectorised far-field kernel.
struct PanelArrays {
  PanelArrays() = default;
  explicit PanelArrays(const Polygon& polygon);
  /// The panels panels[k], k < m, of the polygon, as entries k (reuses the storage).
  void assign(const Polygon& polygon, const Index* panels, std::size_t m);
  std::vector<double> ax, ay, tx, ty, nx, ny, h, mx, my;
};

/// far_field_points(pi, panel j, y) (log_integrals.hpp) for j in [j0, j1), vectorised, into
/// points[j]; y the thresholds of the rule (the dense assembly's by default).
void far_field_points(const Panel& pi, const PanelArrays& panels, Index j0, Index j1, int* points,
                      const std::array<double, kMaxGaussPoints + 1>& y = gauss_thresholds());

/// Largest batch of far-field pairs evaluated together.
constexpr int kFarBatch = 32;

/// The far pairs of one panel or point, queued by their number of Gauss points p and
/// handed to `evaluate(p, js, m)` (the m <= kFarBatch queued indices js, all of p points)
/// whenever kFarBatch of one p are queued, and the rest by finish(): the batches of
/// far_blocks_batch, far_kji_batch, far_point_sum and their like.
template <typename Evaluate>
class FarBatches {
 public:
  explicit FarBatches(Evaluate evaluate) : evaluate_(std::move(evaluate)) {}
  /// Queue the pair `index` of 1 <= p <= kMaxFarPoints points.
  void push(int p, Index index) {
    queue_[p][queued_[p]++] = index;
    if (queued_[p] == kFarBatch) flush(p);
  }
  /// Evaluate every pair still queued.
  void finish() {
    for (int p = 1; p <= kMaxFarPoints; ++p)
      if (queued_[p] > 0) flush(p);
  }

 private:
  void flush(int p) {
    evaluate_(p, static_cast<const Index*>(queue_[p]), queued_[p]);
    queued_[p] = 0;
  }
  Evaluate evaluate_;
  Index queue_[kMaxFarPoints + 1][kFarBatch];
  int queued_[kMaxFarPoints + 1] = {};
};

/// Blocks v and kij of the pairs (i, j) for one panel i, stored by columns j:
/// v[a][b][j], kij[a][b][j].
struct PairBlockColumns {
  double* v[2][2];
  double* kij[2][2];
};

/// far_blocks for the pairs (pi, panel js[k]), k < m <= kFarBatch, all with the same
/// number of points p <= kMaxFarPoints, vectorised over k (src/far_field.cpp): v if
/// with_v, kij if with_k (kij alone needs no logarithm), stored times v_scale and
/// k_scale to out.v/kij[.][.][js[k]].
void far_blocks_batch(const Panel& pi, const PanelArrays& panels, const Index* js, int m, int p, bool with_v,
                      bool with_k, const PairBlockColumns& out, double v_scale = 1.0, double k_scale = 1.0);

/// kji of far_blocks for the pairs (pi, panel js[k]) (double-layer kernel with the normal
/// of pi, test panel js[k], trial pi), stored times k_scale to out.kij[b][a][js[k]] with b
/// the shape on panel js[k], a the shape on pi: the column of K_h for a trial panel pi.
void far_kji_batch(const Panel& pi, const PanelArrays& panels, const Index* js, int m, int p,
                   const PairBlockColumns& out, double k_scale = 1.0);

/// Gauss points of point_panel_moments for the point z and every panel j (0: near,
/// closed form), vectorised, into points[j].
void point_far_field_points(Vec2 z, const PanelArrays& panels, int* points);

/// sum over k < m <= kFarBatch of the point-panel integrals of panel j = js[k] seen from
/// z (Gauss rule with p points, all p equal), weighted per panel:
///   sum_k l0[j] int log|z-y| phi_0 + l1[j] int log|z-y| phi_1
///       + d0[j] int (z-y).n/|z-y|^2 phi_0 + d1[j] int (z-y).n/|z-y|^2 phi_1.
double far_point_sum(Vec2 z, const PanelArrays& panels, const Index* js, int m, int p, const double* l0,
                     const double* l1, const double* d0, const double* d1);

}  // namespace bem
