#include "bem/lame_polygon_entries.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "bem/far_field.hpp"
#include "bem/grouped_aca.hpp"
#include "bem/lame_polygon.hpp"
#include "bem/log_integrals.hpp"

// glibc's vector log (libmvec), as in far_field.cpp: the far-field loops call it vectorised.
extern "C" {
#pragma omp declare simd notinbranch
double log(double x) noexcept;
}

namespace bem {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// The moments of a panel pair: kL (log), kX (D_xx), kY (D_xy), each for the shapes a, b.
constexpr int kL = 0, kX = 1, kY = 2, kMoments = 12;
constexpr int slab(int moment, int a, int b) { return 4 * moment + 2 * a + b; }

/// The far pairs (pi, panel js[k]), k < m <= kFarBatch, by the tensor Gauss rule with p
/// points per panel, vectorised over k: the 12 moments (shape a on pi, b on panel js[k])
/// stored to out[slab][js[k]].
void far_moments_batch(const Panel& pi, const PanelArrays& panels, const Index* js, int m, int p,
                       double* const (&out)[kMoments]) {
  constexpr int B = kFarBatch;
  const GaussRule& g = gauss_legendre(p);
  double ox[kMaxFarPoints][B], oy[kMaxFarPoints][B], w0[kMaxFarPoints][B], w1[kMaxFarPoints][B];
  for (int k = 0; k < m; ++k) {
    const std::size_t j = static_cast<std::size_t>(js[k]);
    const double hj = panels.h[j];
    const double dx0 = pi.a.x - panels.ax[j], dy0 = pi.a.y - panels.ay[j];
    for (int b = 0; b < p; ++b) {  // a_i - y_b and the shape weights of point b
      const double xb = g.x[static_cast<std::size_t>(b)], wb = g.w[static_cast<std::size_t>(b)];
      ox[b][k] = dx0 - xb * hj * panels.tx[j];
      oy[b][k] = dy0 - xb * hj * panels.ty[j];
      w0[b][k] = wb * (1.0 - xb) * hj;
      w1[b][k] = wb * xb * hj;
    }
  }
  double acc[kMoments][B];
  for (int a = 0; a < p; ++a) {
    const double xa = g.x[static_cast<std::size_t>(a)], wa = g.w[static_cast<std::size_t>(a)];
    const double si = xa * pi.h, wi0 = wa * (1.0 - xa) * pi.h, wi1 = wa * xa * pi.h;
    const double sx = si * pi.t.x, sy = si * pi.t.y;
    // inner sums over the points of panel j, shape weights w0 (start) and w1 (end)
    double l0[B], l1[B], x0[B], x1[B], y0[B], y1[B];
#pragma omp simd
    for (int k = 0; k < m; ++k) l0[k] = l1[k] = x0[k] = x1[k] = y0[k] = y1[k] = 0.0;
    for (int b = 0; b < p; ++b) {
      const double* oxb = ox[b];
      const double* oyb = oy[b];
      const double* w0b = w0[b];
      const double* w1b = w1[b];
#pragma omp simd
      for (int k = 0; k < m; ++k) {
        const double rx = oxb[k] + sx, ry = oyb[k] + sy;
        const double r2 = rx * rx + ry * ry;
        const double f = 0.5 * log(r2), inv = 1.0 / r2;
        const double gxx = rx * rx * inv, gxy = rx * ry * inv;
        l0[k] += w0b[k] * f;
        l1[k] += w1b[k] * f;
        x0[k] += w0b[k] * gxx;
        x1[k] += w1b[k] * gxx;
        y0[k] += w0b[k] * gxy;
        y1[k] += w1b[k] * gxy;
      }
    }
    if (a == 0) {
#pragma omp simd
      for (int k = 0; k < m; ++k)
        for (int s = 0; s < kMoments; ++s) acc[s][k] = 0.0;
    }
    // slab (moment, a, b) += the weight of shape a at this point of pi times the inner sum
    // of the moment against shape b
    const double* const inner[3][2] = {{l0, l1}, {x0, x1}, {y0, y1}};
    const double wi[2] = {wi0, wi1};
    for (int moment = kL; moment <= kY; ++moment)
      for (int sa = 0; sa < 2; ++sa)
        for (int sb = 0; sb < 2; ++sb) {
          double* const out_s = acc[slab(moment, sa, sb)];
          const double* const in = inner[moment][sb];
          const double w = wi[sa];
#pragma omp simd
          for (int k = 0; k < m; ++k) out_s[k] += w * in[k];
        }
  }
  for (int s = 0; s < kMoments; ++s)
    for (int k = 0; k < m; ++k) out[s][js[k]] = acc[s][k];
}

/// gauss_thresholds() (log_integrals.hpp) for the quadrature tolerance q.
std::array<double, kMaxGaussPoints + 1> thresholds(double q) {
  std::array<double, kMaxGaussPoints + 1> t{};
  for (int p = 1; p <= kMaxGaussPoints; ++p) {
    const double rho = std::pow(q, -1.0 / (2.0 * p));
    t[static_cast<std::size_t>(p)] = 0.5 * (rho - 1.0 / rho);
  }
  return t;
}

}  // namespace

KelvinLike kelvin_like(const Lame& m, LameKernel kernel) {
  check_medium(m);
  const double c = 1.0 / (4.0 * kPi * m.mu * (1.0 - m.nu));
  switch (kernel) {
    case LameKernel::SingleLayer:
      return {-(3.0 - 4.0 * m.nu) * c, c, false};
    case LameKernel::Hypersingular:
      return {-4.0 * m.mu * m.mu * c, 4.0 * m.mu * m.mu * c, false};
    case LameKernel::DoubleLayer:
      return {-2.0 * m.mu * (1.0 - 2.0 * m.nu) * c, 2.0 * m.mu * c, true};
  }
  throw std::invalid_argument("kelvin_like: unknown kernel");
}

LamePolygonEntries::LamePolygonEntries(const Polygon& polygon, const Lame& m, LameKernel kernel, Space rows)
    : polygon_(polygon),
      scalar_(polygon, Kernel::SingleLayer, Space::P0, Space::P0),
      coef_(kelvin_like(m, kernel)),
      rows_(rows),
      cols_(kernel == LameKernel::SingleLayer ? rows : Space::P0) {
  if (kernel == LameKernel::Hypersingular && rows != Space::P0)
    throw std::invalid_argument("LamePolygonEntries: X0 of W_h has P0 rows and columns");
}

void LamePolygonEntries::node_blocks(const DofSet& R, const DofSet& C, double* out,
                                     const std::array<double, kMaxGaussPoints + 1>* y) const {
  const Index n = polygon_.size();
  const std::vector<Index>& P = R.panels;
  const std::vector<Index>& Q = C.panels;
  const std::size_t np = P.size(), nq = Q.size();
  // Moments of the pairs (outer panel, inner panel), the outer side the one with fewer
  // panels (L and D are symmetric: the pair (q, p) with shapes (b, a) is (p, q) with (a, b)):
  // table[(s * no + io) * ni + ii], s = slab(moment, shape on outer, shape on inner).
  const bool swap = np > nq;
  const std::vector<Index>& outer = swap ? Q : P;
  const std::vector<Index>& inner = swap ? P : Q;
  const std::size_t no = outer.size(), ni = inner.size();
  const PanelArrays& arrays = swap ? R.arrays : C.arrays;
  thread_local std::vector<double> table;
  thread_local std::vector<int> points;
  if (table.size() < kMoments * no * ni) table.resize(kMoments * no * ni);
  if (points.size() < ni) points.resize(ni);
  PairBlocks lap;
  DirectionBlocks dir;
  for (std::size_t io = 0; io < no; ++io) {
    const Panel& po = polygon_.panel(outer[io]);
    double* rows[kMoments];
    for (int s = 0; s < kMoments; ++s) rows[s] = table.data() + (s * no + io) * ni;
    FarBatches far([&](int p, const Index* js, int m) { far_moments_batch(po, arrays, js, m, p, rows); });
    far_field_points(po, arrays, 0, static_cast<Index>(ni), points.data(), y ? *y : gauss_thresholds());
    for (std::size_t ii = 0; ii < ni; ++ii) {
      const PairRelation rel = panel_relation(outer[io], inner[ii], n);
      const int p = rel == PairRelation::Separated ? points[ii] : 0;
      if (p > 0) {
        far.push(p, static_cast<Index>(ii));
        continue;
      }
      const Panel& pq = polygon_.panel(inner[ii]);
      pair_blocks(po, pq, rel, false, lap);
      direction_blocks(po, pq, rel, dir);
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) {
          rows[slab(kL, a, b)][ii] = lap.v[a][b];
          rows[slab(kX, a, b)][ii] = dir.xx[a][b];
          rows[slab(kY, a, b)][ii] = dir.xy[a][b];
        }
    }
    far.finish();
  }
  // The sums over the shape terms of each pair of nodes: the table's strides for (row
  // panel, column panel) and for the shapes (a on the row panel, b on the column panel).
  const std::size_t plane = no * ni;
  const std::size_t s_row = swap ? 1 : ni, s_col = swap ? ni : 1;
  const std::size_t s_a = swap ? plane : 2 * plane, s_b = swap ? 2 * plane : plane;
  const double* hp = R.arrays.h.data();
  const double* hq = C.arrays.h.data();
  const Index m = R.size(), k = C.size();
  const double ca = coef_.a, cb = coef_.b;
  for (Index r = 0; r < m; ++r) {
    std::size_t base[2];
    double hr[2];
    for (int e = 0; e < 2; ++e) {
      const std::size_t ip = static_cast<std::size_t>(R.position[static_cast<std::size_t>(2 * r + e)]);
      base[e] = ip * s_row + static_cast<std::size_t>(R.shape[static_cast<std::size_t>(2 * r + e)]) * s_a;
      hr[e] = 0.25 * hp[ip];
    }
    for (Index c = 0; c < k; ++c) {
      double L = 0, X = 0, Y = 0, quarter = 0;
      for (int f = 0; f < 2; ++f) {
        const std::size_t iq = static_cast<std::size_t>(C.position[static_cast<std::size_t>(2 * c + f)]);
        const std::size_t col =
            iq * s_col + static_cast<std::size_t>(C.shape[static_cast<std::size_t>(2 * c + f)]) * s_b;
        for (int e = 0; e < 2; ++e) {
          const double* t = table.data() + base[e] + col;
          L += t[slab(kL, 0, 0) * plane];
          X += t[slab(kX, 0, 0) * plane];
          Y += t[slab(kY, 0, 0) * plane];
          quarter += hr[e] * hq[iq];
        }
      }
      // a L I + b D, D = [[X, Y], [Y, quarter - X]]; rotated: times R = [[0, -1], [1, 0]]
      const double b00 = ca * L + cb * X, b01 = cb * Y, b11 = ca * L + cb * (quarter - X);
      double* o = out + 4 * (r * k + c);
      if (!coef_.rotate) {
        o[0] = b00, o[1] = b01, o[2] = b01, o[3] = b11;
      } else {
        o[0] = b01, o[1] = -b00, o[2] = b11, o[3] = -b01;
      }
    }
  }
}

void LamePolygonEntries::block(const Index* I, Index m, const Index* J, Index k, double* out, Index ld) const {
  std::unique_ptr<EntryBlock> b = block(I, m, J, k);
  Eigen::MatrixXd A(m, k);
  b->all(A.data());
  for (Index c = 0; c < k; ++c)
    for (Index r = 0; r < m; ++r) out[r + c * ld] = A(r, c);
}

namespace {

/// The nodes (panels) of a set of vector dofs, each once, and per dof its node's place
/// and its component.
struct NodeMap {
  std::vector<Index> nodes, place;
  std::vector<int> component;
  NodeMap(const Index* dofs, Index m) : place(static_cast<std::size_t>(m)), component(static_cast<std::size_t>(m)) {
    bool paired = m % 2 == 0;  // the clusters of an expanded tree: (2 u, 2 u + 1) in turn
    for (Index r = 0; paired && r < m; r += 2) paired = dofs[r] % 2 == 0 && dofs[r + 1] == dofs[r] + 1;
    if (paired) {
      nodes.resize(static_cast<std::size_t>(m / 2));
      for (Index r = 0; r < m; ++r) {
        nodes[static_cast<std::size_t>(r / 2)] = dofs[r] / 2;
        place[static_cast<std::size_t>(r)] = r / 2;
        component[static_cast<std::size_t>(r)] = static_cast<int>(r % 2);
      }
      return;
    }
    std::vector<std::pair<Index, Index>> order(static_cast<std::size_t>(m));  // (node, dof position)
    for (Index r = 0; r < m; ++r) order[static_cast<std::size_t>(r)] = {dofs[r] / 2, r};
    std::sort(order.begin(), order.end());
    for (const auto& [u, r] : order) {
      if (nodes.empty() || nodes.back() != u) nodes.push_back(u);
      place[static_cast<std::size_t>(r)] = static_cast<Index>(nodes.size()) - 1;
      component[static_cast<std::size_t>(r)] = static_cast<int>(dofs[r] % 2);
    }
  }
  Index size() const { return static_cast<Index>(nodes.size()); }
};

/// A vector from a pool of the calling thread, given back with its capacity on destruction:
/// the row and column caches of every block would otherwise be fresh allocations whose
/// pages fault in each time.
template <class T>
class Pooled {
 public:
  Pooled() {
    std::vector<std::vector<T>>& p = pool();
    if (!p.empty()) {
      v_ = std::move(p.back());
      p.pop_back();
    }
    v_.clear();
  }
  ~Pooled() { pool().push_back(std::move(v_)); }
  Pooled(const Pooled&) = delete;
  Pooled& operator=(const Pooled&) = delete;
  std::vector<T>& operator*() { return v_; }
  std::vector<T>* operator->() { return &v_; }

 private:
  static std::vector<std::vector<T>>& pool() {
    thread_local std::vector<std::vector<T>> p;
    return p;
  }
  std::vector<T> v_;
};

class LameBlock : public EntryBlock {
 public:
  LameBlock(const LamePolygonEntries& e, const Index* I, Index m, const Index* J, Index k)
      : e_(e),
        I_(I),
        J_(J),
        m_(m),
        k_(k),
        rmap_(I, m),
        cmap_(J, k),
        rows_(e.nodes(e.row_space(), rmap_.nodes.data(), rmap_.size())),
        cols_(e.nodes(e.col_space(), cmap_.nodes.data(), cmap_.size())) {}

  void row(Index i, double* out) const override { line(true, i, out); }
  void column(Index j, double* out) const override { line(false, j, out); }

  /// ACA with the components of a node as a group (grouped_aca.hpp).
  bool low_rank(double tol, LowRank& out) const override {
    std::vector<Index> rg(static_cast<std::size_t>(m_)), cg(static_cast<std::size_t>(k_));
    for (Index r = 0; r < m_; ++r) rg[static_cast<std::size_t>(r)] = I_[r] / 2;
    for (Index c = 0; c < k_; ++c) cg[static_cast<std::size_t>(c)] = J_[c] / 2;
    far_rule_ = thresholds(std::max(kQuadratureTolerance, 1e-3 * tol));
    const Slice row = [this](Index i, double* o) { this->row(i, o); };
    const Slice column = [this](Index j, double* o) { this->column(j, o); };
    out = grouped_aca(m_, k_, rg, cg, row, column, tol, std::min(m_, k_));
    return true;
  }

  void all(double* out) const override {
    const auto t0 = std::chrono::steady_clock::now();
    const Index nr = rows_.size(), nc = cols_.size();
    scratch_->resize(static_cast<std::size_t>(4 * nr * nc));
    e_.node_blocks(rows_, cols_, scratch_->data());
    for (Index c = 0; c < k_; ++c) {
      const Index pc = cmap_.place[static_cast<std::size_t>(c)];
      const int lc = cmap_.component[static_cast<std::size_t>(c)];
      for (Index r = 0; r < m_; ++r)
        out[r + c * m_] =
            (*scratch_)[static_cast<std::size_t>(4 * (rmap_.place[static_cast<std::size_t>(r)] * nc + pc) +
                                                 2 * rmap_.component[static_cast<std::size_t>(r)] + lc)];
    }
    e_.count(true, elapsed(t0));
  }

 private:
  /// Row i of the block (by_row) or column i, from the cached rows (columns) of both
  /// components of its node.
  void line(bool by_row, Index i, double* out) const {
    const auto t0 = std::chrono::steady_clock::now();
    const NodeMap& own = by_row ? rmap_ : cmap_;
    const Index count = by_row ? k_ : m_;
    const Index p = own.place[static_cast<std::size_t>(i)];
    const double* both = by_row ? cached(rmap_, p, cols_, cmap_, k_, true, *row_slot_, *row_store_)
                                : cached(cmap_, p, rows_, rmap_, m_, false, *col_slot_, *col_store_);
    std::copy_n(both + own.component[static_cast<std::size_t>(i)] * count, count, out);
    e_.count(false, elapsed(t0));
  }
  static long elapsed(std::chrono::steady_clock::time_point t0) {
    return static_cast<long>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
  }
  /// Both components' rows (row: true) or columns of the node at place p of `own` against
  /// all dofs of the other side (`other`, `omap`, `count` dofs), computed once:
  /// out[c * count + q] for component c.
  const double* cached(const NodeMap& own, Index p, const DofSet& other, const NodeMap& omap, Index count, bool row,
                       std::vector<Index>& slot, std::vector<double>& store) const {
    if (slot.empty()) slot.assign(static_cast<std::size_t>(own.size()), -1);
    Index& s = slot[static_cast<std::size_t>(p)];
    if (s < 0) {
      const Index u = own.nodes[static_cast<std::size_t>(p)];
      e_.nodes_into(row ? e_.row_space() : e_.col_space(), &u, 1, one_);
      scratch_->resize(static_cast<std::size_t>(4 * other.size()));
      const std::array<double, kMaxGaussPoints + 1>* y = far_rule_[1] > 0 ? &far_rule_ : nullptr;
      if (row)
        e_.node_blocks(one_, other, scratch_->data(), y);
      else
        e_.node_blocks(other, one_, scratch_->data(), y);
      s = static_cast<Index>(store.size());
      store.resize(store.size() + static_cast<std::size_t>(2 * count));
      double* both = store.data() + s;
      for (int comp = 0; comp < 2; ++comp)
        for (Index q = 0; q < count; ++q) {
          const Index at = omap.place[static_cast<std::size_t>(q)];
          const int oc = omap.component[static_cast<std::size_t>(q)];
          // node_blocks: [own node][other node][row component][column component]
          both[comp * count + q] =
              (*scratch_)[static_cast<std::size_t>(4 * at + (row ? 2 * comp + oc : 2 * oc + comp))];
        }
    }
    return store.data() + s;
  }
  const LamePolygonEntries& e_;
  const Index *I_, *J_;
  Index m_, k_;
  NodeMap rmap_, cmap_;
  DofSet rows_, cols_;
  // one thread per block: the single-node set, the scratch and the computed rows / columns
  mutable DofSet one_;
  mutable Pooled<double> scratch_, row_store_, col_store_;
  mutable Pooled<Index> row_slot_, col_slot_;
  /// the thresholds of the far rule of ACA's rows and columns (zero: the dense assembly's)
  mutable std::array<double, kMaxGaussPoints + 1> far_rule_{};
};

}  // namespace

std::unique_ptr<EntryBlock> LamePolygonEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<LameBlock>(*this, I, m, J, k);
}

std::shared_ptr<const HMatrix> lame_hmatrix(const Polygon& polygon, const Lame& m, LameKernel kernel, Space rows,
                                            std::shared_ptr<const ClusterTree> row_tree,
                                            std::shared_ptr<const ClusterTree> col_tree, const HMatrixOptions& o,
                                            LameEntryTimes* times) {
  const LamePolygonEntries entries(polygon, m, kernel, rows);
  HMatrixOptions options = o;
  options.symmetric = kernel != LameKernel::DoubleLayer;
  auto H = std::make_shared<const HMatrix>(std::move(row_tree), std::move(col_tree), entries, options);
  if (times) {
    times->dense = entries.dense_seconds();
    times->low_rank = entries.low_rank_seconds();
  }
  return H;
}

}  // namespace bem
