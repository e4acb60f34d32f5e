#include "bem/operator_entries.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "bem/far_field.hpp"
#include "bem/log_integrals.hpp"

namespace bem {

namespace {

constexpr double kInvPi = 0.318309886183790671537767526745;

/// Panel and local shape of the two terms of a dof.
struct Terms {
  Index panel[2];
  int shape[2];
};

Terms terms(Space space, Index i, Index n) {
  if (space == Space::P0) return {{i, i}, {0, 1}};
  return {{(i + n - 1) % n, i}, {1, 0}};
}

std::vector<Index> sorted_panels(Space space, const Index* dofs, Index m, Index n, std::vector<Index> panels) {
  panels.clear();
  if (m == 1) {  // one dof (a row or column of ACA): two panels, or one for P0
    const Terms t = terms(space, dofs[0], n);
    panels.push_back(std::min(t.panel[0], t.panel[1]));
    if (t.panel[0] != t.panel[1]) panels.push_back(std::max(t.panel[0], t.panel[1]));
    return panels;
  }
  panels.reserve(static_cast<std::size_t>(2 * m));
  for (Index r = 0; r < m; ++r) {
    const Terms t = terms(space, dofs[r], n);
    panels.push_back(t.panel[0]);
    panels.push_back(t.panel[1]);
  }
  std::sort(panels.begin(), panels.end());
  panels.erase(std::unique(panels.begin(), panels.end()), panels.end());
  return panels;
}

Index position(const std::vector<Index>& sorted, Index panel) {
  return static_cast<Index>(std::lower_bound(sorted.begin(), sorted.end(), panel) - sorted.begin());
}

}  // namespace

OperatorEntries::OperatorEntries(const Polygon& polygon, Kernel kernel, Space rows, Space cols)
    : polygon_(polygon), kernel_(kernel), rows_(rows), cols_(cols) {
  if (kernel == Kernel::SingleLayer && rows != cols)
    throw std::invalid_argument("OperatorEntries: V_h needs the same row and column space");
  if (kernel == Kernel::DoubleLayer && cols != Space::P1)
    throw std::invalid_argument("OperatorEntries: K_h has P1 columns");
}

DofSet OperatorEntries::dofs(Space space, const Index* dofs, Index m) const {
  DofSet d;
  dofs_into(space, dofs, m, d);
  return d;
}

void OperatorEntries::dofs_into(Space space, const Index* dofs, Index m, DofSet& d) const {
  const Index n = polygon_.size();
  d.panels = sorted_panels(space, dofs, m, n, std::move(d.panels));
  d.position.resize(static_cast<std::size_t>(2 * m));
  d.shape.resize(static_cast<std::size_t>(2 * m));
  for (Index r = 0; r < m; ++r) {
    const Terms t = terms(space, dofs[r], n);
    for (int e = 0; e < 2; ++e) {
      d.position[static_cast<std::size_t>(2 * r + e)] = position(d.panels, t.panel[e]);
      d.shape[static_cast<std::size_t>(2 * r + e)] = t.shape[e];
    }
  }
  d.arrays.assign(polygon_, d.panels.data(), d.panels.size());
}

void OperatorEntries::block(const Index* I, Index m, const Index* J, Index k, double* out, Index ld) const {
  block(dofs(rows_, I, m), dofs(cols_, J, k), out, ld);
}

void OperatorEntries::block(const DofSet& R, const DofSet& C, double* out, Index ld) const {
  const Index n = polygon_.size();
  const bool with_k = kernel_ == Kernel::DoubleLayer;
  const std::vector<Index>& P = R.panels;
  const std::vector<Index>& Q = C.panels;
  const std::size_t np = P.size(), nq = Q.size();
  // table[(a * 2 + b) * np * nq + ip * nq + iq]: block [a][b] of (test P[ip], trial Q[iq]),
  // with the factor -1/pi (V) or 1/pi (K).
  // Per-thread scratch (rows and columns of ACA call this often with small sets; fresh
  // zero-filled vectors cost more than the integrals). Every entry is written before use.
  thread_local std::vector<double> table, store;
  thread_local std::vector<int> points;
  if (table.size() < 4 * np * nq) table.resize(4 * np * nq);
  auto at = [&](int a, int b, std::size_t ip, std::size_t iq) -> double& {
    return table[(static_cast<std::size_t>(2 * a + b) * np + ip) * nq + iq];
  };
  const double scale = with_k ? kInvPi : -kInvPi;
  PairBlocks B;
  if (np <= nq || !with_k) {
    // Test panel by test panel against all trial panels, far pairs in vector batches.
    // For V with few trial panels (a column) the roles swap: v is symmetric,
    // v_pq[a][b] = v_qp[b][a].
    const bool swap = np > nq;
    const std::vector<Index>& outer = swap ? Q : P;
    const std::vector<Index>& inner = swap ? P : Q;
    const std::size_t ni = inner.size();
    const PanelArrays& arrays = swap ? R.arrays : C.arrays;
    if (store.size() < 4 * ni) store.resize(4 * ni);
    if (points.size() < ni) points.resize(ni);
    PairBlockColumns col;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        col.v[a][b] = store.data() + (2 * a + b) * ni;
        col.kij[a][b] = col.v[a][b];
      }
    for (std::size_t io = 0; io < outer.size(); ++io) {
      const Panel& po = polygon_.panel(outer[io]);
      FarBatches far([&](int p, const Index* js, int m) {
        far_blocks_batch(po, arrays, js, m, p, !with_k, with_k, col, 1.0, 1.0);
      });
      far_field_points(po, arrays, 0, static_cast<Index>(ni), points.data());
      for (std::size_t ii = 0; ii < ni; ++ii) {
        const Index q = inner[ii];
        const PairRelation rel = panel_relation(outer[io], q, n);
        const Panel& pq = polygon_.panel(q);
        const int p = rel == PairRelation::Separated ? points[ii] : 0;
        if (p > 0) {
          far.push(p, static_cast<Index>(ii));
          continue;
        }
        pair_blocks(po, pq, rel, with_k, B);
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b) col.v[a][b][ii] = with_k ? B.kij[a][b] : B.v[a][b];
      }
      far.finish();
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
          for (std::size_t ii = 0; ii < ni; ++ii) {
            const double value = scale * col.v[a][b][ii];
            if (swap)
              at(b, a, ii, io) = value;
            else
              at(a, b, io, ii) = value;
          }
    }
  } else {
    // K with few trial panels (a column): the double-layer kernel carries the normal of
    // the trial panel, so the far pairs go in batches over the test panels with kji.
    if (store.size() < 4 * np) store.resize(4 * np);
    PairBlockColumns col;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) col.kij[a][b] = store.data() + (2 * a + b) * np;
    for (std::size_t iq = 0; iq < nq; ++iq) {
      const Panel& pq = polygon_.panel(Q[iq]);
      FarBatches far([&](int p, const Index* js, int m) { far_kji_batch(pq, R.arrays, js, m, p, col, 1.0); });
      for (std::size_t ip = 0; ip < np; ++ip) {
        const Panel& pp = polygon_.panel(P[ip]);
        const PairRelation rel = panel_relation(P[ip], Q[iq], n);
        const int p = rel == PairRelation::Separated ? far_field_points(pp, pq) : 0;
        if (p > 0) {
          far.push(p, static_cast<Index>(ip));
          continue;
        }
        pair_blocks(pp, pq, rel, true, B);
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b) col.kij[a][b][ip] = B.kij[a][b];
      }
      far.finish();
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
          for (std::size_t ip = 0; ip < np; ++ip) at(a, b, ip, iq) = scale * col.kij[a][b][ip];
    }
  }
  const Index m = R.size(), k = C.size();
  for (Index r = 0; r < m; ++r) {
    const std::size_t ip[2] = {static_cast<std::size_t>(R.position[static_cast<std::size_t>(2 * r)]),
                               static_cast<std::size_t>(R.position[static_cast<std::size_t>(2 * r + 1)])};
    const int sr[2] = {R.shape[static_cast<std::size_t>(2 * r)], R.shape[static_cast<std::size_t>(2 * r + 1)]};
    for (Index c = 0; c < k; ++c) {
      double sum = 0.0;
      for (int e = 0; e < 2; ++e)
        for (int f = 0; f < 2; ++f)
          sum += at(sr[e], C.shape[static_cast<std::size_t>(2 * c + f)], ip[e],
                    static_cast<std::size_t>(C.position[static_cast<std::size_t>(2 * c + f)]));
      out[r + c * ld] = sum;
    }
  }
}

namespace {

class PreparedBlock : public EntryBlock {
 public:
  PreparedBlock(const OperatorEntries& e, const Index* I, Index m, const Index* J, Index k)
      : e_(e), I_(I), J_(J), rows_(e.dofs(e.row_space(), I, m)), cols_(e.dofs(e.col_space(), J, k)) {}
  void row(Index i, double* out) const override {
    e_.dofs_into(e_.row_space(), I_ + i, 1, one_);
    e_.block(one_, cols_, out, 1);
  }
  void column(Index j, double* out) const override {
    e_.dofs_into(e_.col_space(), J_ + j, 1, one_);
    e_.block(rows_, one_, out, rows_.size());
  }
  void all(double* out) const override { e_.block(rows_, cols_, out, rows_.size()); }

 private:
  const OperatorEntries& e_;
  const Index *I_, *J_;
  DofSet rows_, cols_;
  mutable DofSet one_;  ///< a single row or column, storage reused (one thread per block)
};

}  // namespace

std::unique_ptr<EntryBlock> OperatorEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<PreparedBlock>(*this, I, m, J, k);
}

}  // namespace bem
