#include "bem/surface_entries.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace bem {

namespace {

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

class SurfaceBlock : public EntryBlock {
 public:
  SurfaceBlock(const Surface& s, const PairIntegrator& integrator, SurfaceKernel kernel, Space rows, Space cols,
               const Index* I, Index m, const Index* J, Index k)
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
        col_parts_(parts(s, cols, J, k)) {}

  void row(Index i, double* out) const override {
    std::fill(out, out + k_, 0.0);
    const std::vector<Part> own = parts(s_, rows_, I_ + i, 1);
    for (const Part& r : own)
      for (const Part& c : col_parts_) add(r, c, out, 0, 1);
  }
  void column(Index j, double* out) const override {
    std::fill(out, out + m_, 0.0);
    const std::vector<Part> own = parts(s_, cols_, J_ + j, 1);
    for (const Part& r : row_parts_)
      for (const Part& c : own) add(r, c, out, 1, 0);
  }
  void all(double* out) const override {
    std::fill(out, out + m_ * k_, 0.0);
    for (const Part& r : row_parts_)
      for (const Part& c : col_parts_) add(r, c, out, 1, m_);
  }

 private:
  /// out[row_stride * row position + col_stride * column position] += the pair's entries.
  void add(const Part& r, const Part& c, double* out, Index row_stride, Index col_stride) const {
    PairIntegrals L;
    const bool dl = kernel_ == SurfaceKernel::DoubleLayer;
    integrator_.integrate(r.triangle, c.triangle, dl, L);
    for (int a = 0; a < r.count; ++a)
      for (int b = 0; b < c.count; ++b) {
        const double v = dl ? L.K[r.basis[a]][c.basis[b]] : L.V[r.basis[a]][c.basis[b]];
        out[row_stride * r.position[a] + col_stride * c.position[b]] += v;
      }
  }
  const Surface& s_;
  const PairIntegrator& integrator_;
  SurfaceKernel kernel_;
  Space rows_, cols_;
  const Index *I_, *J_;
  Index m_, k_;
  std::vector<Part> row_parts_, col_parts_;
};

}  // namespace

SurfaceEntries::SurfaceEntries(const Surface& surface, SurfaceKernel kernel, Space rows, Space cols)
    : surface_(surface), integrator_(surface), kernel_(kernel), rows_(rows), cols_(cols) {
  if (kernel == SurfaceKernel::DoubleLayer && cols != Space::P1)
    throw std::invalid_argument("SurfaceEntries: the double layer acts on the P1 trace");
}

std::unique_ptr<EntryBlock> SurfaceEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<SurfaceBlock>(surface_, integrator_, kernel_, rows_, cols_, I, m, J, k);
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
