#include "bem/surface_entries.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace bem {

namespace {

constexpr double kInvTwoPi = 0.5 / M_PI;  // 2 G(r) = 1 / (2 pi r), the factor-2 convention

/// A triangle of a block's row or column supports, with the dofs it carries there: the
/// local basis index (0..2 barycentric, 3 constant) and the position in the block.
struct Part {
  Index triangle;
  int count = 0;
  int basis[3] = {0, 0, 0};
  Index position[3] = {0, 0, 0};
};

/// The parts of the dofs `dofs[0..k)` of `space`, one per triangle.
std::vector<Part> parts(const Surface& s, Space space, const Index* dofs, Index k) {
  std::vector<std::pair<Index, std::pair<int, Index>>> items;  // (triangle, (basis, position))
  for (Index p = 0; p < k; ++p) {
    const Index d = dofs[p];
    if (space == Space::P0) {
      items.push_back({d, {3, p}});
    } else {
      for (Index t : s.star(d)) {
        const Triangle& T = s.triangle(t);
        const int a = static_cast<int>(std::find(T.v.begin(), T.v.end(), d) - T.v.begin());
        items.push_back({t, {a, p}});
      }
    }
  }
  std::sort(items.begin(), items.end());
  std::vector<Part> out;
  for (const auto& [t, bp] : items) {
    if (out.empty() || out.back().triangle != t) out.push_back(Part{t, 0, {0, 0, 0}, {0, 0, 0}});
    Part& q = out.back();
    q.basis[q.count] = bp.first;
    q.position[q.count] = bp.second;
    ++q.count;
  }
  return out;
}

/// The far rule's points of the triangles of `parts`, with weights (the rule's weight times
/// twice the area: the physical measure) and normals, and the basis values Q that take a
/// function of the points to the block's dofs: dof value = sum_p Q(p, dof) f(p).
struct FarPoints {
  std::vector<Vec3> x, n;
  std::vector<double> w;
  struct Entry {
    Index point, position;
    double value;
  };
  std::vector<Entry> Q;

  FarPoints(const Surface& s, const std::vector<Part>& parts) {
    const TriangleRule& r = triangle_rule(kFarGaussPoints);
    for (const Part& part : parts) {
      const Triangle& T = s.triangle(part.triangle);
      for (int q = 0; q < r.size(); ++q) {
        const std::size_t k = static_cast<std::size_t>(q);
        const double lambda[4] = {1.0 - r.s[k] - r.t[k], r.s[k], r.t[k], 1.0};
        const Index p = static_cast<Index>(x.size());
        x.push_back(T.p[0] + r.s[k] * (T.p[1] - T.p[0]) + r.t[k] * (T.p[2] - T.p[0]));
        n.push_back(T.n);
        w.push_back(2.0 * T.area * r.w[k]);
        for (int a = 0; a < part.count; ++a) Q.push_back({p, part.position[a], lambda[part.basis[a]]});
      }
    }
  }
  Index size() const { return static_cast<Index>(x.size()); }
  /// Q^T F: the rows of F (one per point) summed into the block's dofs.
  Eigen::MatrixXd project(const Eigen::MatrixXd& F, Index dofs) const {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(dofs, F.cols());
    for (const Entry& e : Q) out.row(e.position) += e.value * F.row(e.point);
    return out;
  }
};

class SurfaceBlock : public EntryBlock {
 public:
  SurfaceBlock(const Surface& s, const PairIntegrator& integrator, const SurfaceNearField* near, SurfaceKernel kernel,
               Space rows, Space cols, const Index* I, Index m, const Index* J, Index k)
      : s_(s),
        integrator_(integrator),
        kernel_(kernel),
        rows_(rows),
        cols_(cols),
        I_(I),
        J_(J),
        m_(m),
        k_(k),
        row_parts_(parts(s, rows, I, m)),
        col_parts_(parts(s, cols, J, k)) {
    if (near == nullptr) return;
    const bool dl = kernel == SurfaceKernel::DoubleLayer;
    near_rows_ = dl ? &near->double_layer() : &near->single_layer(rows);
    near_cols_ = dl ? &near->double_layer_transpose() : near_rows_;
    for (Index p = 0; p < m; ++p) row_position_[I[p]] = p;
    for (Index q = 0; q < k; ++q) col_position_[J[q]] = q;
  }

  void row(Index i, double* out) const override {
    std::fill(out, out + k_, 0.0);
    const std::vector<Part> own = parts(s_, rows_, I_ + i, 1);
    for (const Part& r : own)
      for (const Part& c : col_parts_) add(r, c, out, 0, 1);
    if (near_rows_) add_near(*near_rows_, I_[i], col_position_, out, 1);
  }
  void column(Index j, double* out) const override {
    std::fill(out, out + m_, 0.0);
    const std::vector<Part> own = parts(s_, cols_, J_ + j, 1);
    for (const Part& r : row_parts_)
      for (const Part& c : own) add(r, c, out, 1, 0);
    if (near_cols_) add_near(*near_cols_, J_[j], row_position_, out, 1);
  }
  void all(double* out) const override {
    std::fill(out, out + m_ * k_, 0.0);
    for (const Part& r : row_parts_)
      for (const Part& c : col_parts_) add(r, c, out, 1, m_);
    if (near_rows_)
      for (Index p = 0; p < m_; ++p) add_near(*near_rows_, I_[p], col_position_, out + p, m_);
  }

  /// Far blocks: every triangle pair is evaluated by the far rule (the block's entries are
  /// Q_r^T A Q_c with A the kernel at the far-rule points, weights included), so ACA runs on
  /// A, one kernel evaluation per entry, and the factors are projected to the dofs.
  bool low_rank(double tol, LowRank& out) const override {
    if (!far_pairs_only()) return false;
    const FarPoints r(s_, row_parts_), c(s_, col_parts_);
    const bool dl = kernel_ == SurfaceKernel::DoubleLayer;
    auto entry = [&](Index p, Index q) {
      const Vec3 d = r.x[static_cast<std::size_t>(p)] - c.x[static_cast<std::size_t>(q)];
      const double r2 = dot(d, d);
      const double g = r.w[static_cast<std::size_t>(p)] * c.w[static_cast<std::size_t>(q)] * kInvTwoPi / std::sqrt(r2);
      return dl ? g * dot(d, c.n[static_cast<std::size_t>(q)]) / r2 : g;
    };
    const Slice row = [&](Index p, double* o) {
      for (Index q = 0; q < c.size(); ++q) o[q] = entry(p, q);
    };
    const Slice column = [&](Index q, double* o) {
      for (Index p = 0; p < r.size(); ++p) o[p] = entry(p, q);
    };
    // the projection sums about 10 point rows into a dof row: a tenth of the tolerance
    const LowRank points = aca(r.size(), c.size(), row, column, 0.1 * tol, std::min(r.size(), c.size()));
    out.U = r.project(points.U, m_);
    out.V = c.project(points.V, k_);
    return true;
  }

 private:
  /// Whether every triangle pair of the block is far (PairIntegrator::far): from the boxes
  /// of the two sides when they are far_distance of their largest triangle apart (centroids
  /// at least the boxes' distance apart), pair by pair otherwise.
  bool far_pairs_only() const {
    Box br, bc;
    double radius = 0.0;
    for (const Part& p : row_parts_) {
      const Triangle& T = s_.triangle(p.triangle);
      for (const Vec3& v : T.p) br.add(v);
      radius = std::max(radius, T.radius);
    }
    for (const Part& p : col_parts_) {
      const Triangle& T = s_.triangle(p.triangle);
      for (const Vec3& v : T.p) bc.add(v);
      radius = std::max(radius, T.radius);
    }
    if (br.distance(bc) >= far_distance(radius)) return true;
    for (const Part& p : row_parts_)
      for (const Part& q : col_parts_)
        if (!PairIntegrator::far(s_.triangle(p.triangle), s_.triangle(q.triangle))) return false;
    return true;
  }
  /// out[row_stride * row position + col_stride * column position] += the pair's entries
  /// (far pairs only when the near field holds the others).
  void add(const Part& r, const Part& c, double* out, Index row_stride, Index col_stride) const {
    if (near_rows_ && !PairIntegrator::far(s_.triangle(r.triangle), s_.triangle(c.triangle))) return;
    PairIntegrals L;
    const bool dl = kernel_ == SurfaceKernel::DoubleLayer;
    integrator_.integrate(r.triangle, c.triangle, dl, L);
    for (int a = 0; a < r.count; ++a)
      for (int b = 0; b < c.count; ++b) {
        const double v = dl ? L.K[r.basis[a]][c.basis[b]] : L.V[r.basis[a]][c.basis[b]];
        out[row_stride * r.position[a] + col_stride * c.position[b]] += v;
      }
  }
  /// out[stride * position[j]] += A(i, j) for the entries of row i of A in the block.
  static void add_near(const RowSparse& A, Index i, const std::unordered_map<Index, Index>& position, double* out,
                       Index stride) {
    for (RowSparse::InnerIterator it(A, i); it; ++it) {
      const auto p = position.find(it.col());
      if (p != position.end()) out[stride * p->second] += it.value();
    }
  }
  const Surface& s_;
  const PairIntegrator& integrator_;
  SurfaceKernel kernel_;
  Space rows_, cols_;
  const Index *I_, *J_;
  Index m_, k_;
  std::vector<Part> row_parts_, col_parts_;
  const RowSparse* near_rows_ = nullptr;  ///< near part by rows, and by columns
  const RowSparse* near_cols_ = nullptr;
  std::unordered_map<Index, Index> row_position_, col_position_;  ///< dof -> position in the block
};

}  // namespace

SurfaceEntries::SurfaceEntries(const Surface& surface, SurfaceKernel kernel, Space rows, Space cols,
                               std::shared_ptr<const SurfaceNearField> near)
    : surface_(surface), integrator_(surface), kernel_(kernel), rows_(rows), cols_(cols), near_(std::move(near)) {
  if (kernel == SurfaceKernel::DoubleLayer && cols != Space::P1)
    throw std::invalid_argument("SurfaceEntries: the double layer acts on the P1 trace");
  if (near_ && rows != cols) throw std::invalid_argument("SurfaceEntries: the near field is P0 x P0 or P1 x P1");
}

std::unique_ptr<EntryBlock> SurfaceEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<SurfaceBlock>(surface_, integrator_, near_.get(), kernel_, rows_, cols_, I, m, J, k);
}

ClusterTree surface_cluster_tree(const Surface& s, Space space, Index leaf_size) {
  const Index n = dofs(s, space);
  Matrix points(n, 3);
  std::vector<Box> supports(static_cast<std::size_t>(n));
  auto add_triangle = [&](Box& b, Index t) {
    for (const Vec3& p : s.triangle(t).p) b.add(p);
  };
  for (Index i = 0; i < n; ++i) {
    Box& b = supports[static_cast<std::size_t>(i)];
    const Vec3 p = space == Space::P0 ? s.triangle(i).c : s.vertex(i);
    points.row(i) << p.x, p.y, p.z;
    if (space == Space::P0)
      add_triangle(b, i);
    else
      for (Index t : s.star(i)) add_triangle(b, t);
  }
  return ClusterTree(points, supports, leaf_size);
}

}  // namespace bem
