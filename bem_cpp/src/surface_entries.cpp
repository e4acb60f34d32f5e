#include "bem/surface_entries.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "bem/far_points.hpp"

namespace bem {

namespace {

class SurfaceBlock : public EntryBlock {
 public:
  SurfaceBlock(const Surface& s, const PairIntegrator& integrator, const SurfaceNearField* near, SurfaceKernel kernel,
               Space rows, Space cols, const Index* I, Index m, const Index* J, Index k, bool companion)
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
        col_parts_(parts(s, cols, J, k)),
        companion_(companion),
        near_(near) {
    if (near == nullptr) return;
    const bool dl = kernel == SurfaceKernel::DoubleLayer;
    near_rows_ = dl                                       ? &near->double_layer()
                 : kernel == SurfaceKernel::Hypersingular ? &near->hypersingular()
                                                          : &near->single_layer(rows);
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
  /// With the near field apart: the far pairs as Q_r^T A Q_c, A the point kernel of the far
  /// pairs (zero on the near ones), the near pairs from the sparse near field.
  void all(double* out) const override {
    Eigen::Map<Eigen::MatrixXd> result(out, m_, k_);
    if (!near_rows_) {
      result.setZero();
      for (const Part& r : row_parts_)
        for (const Part& c : col_parts_) add(r, c, out, 1, m_);
      return;
    }
    project(far_kernel(), kernel_ == SurfaceKernel::Hypersingular, result);
    for (Index p = 0; p < m_; ++p) add_near(*near_rows_, I_[p], col_position_, out + p, m_);
  }

  /// Far blocks: every triangle pair is evaluated by the far rule (the block's entries are
  /// Q_r^T A Q_c with A the kernel at the far-rule points, weights included), so ACA runs on
  /// A, one kernel evaluation per entry, and the factors are projected to the dofs.
  /// The double layer's A vanishes between coplanar points (flat faces), a structure on
  /// which ACA's partial pivoting can miss whole sub-blocks (on the cube: products 2e-4 off
  /// at any tol). In a block where a row and a column triangle share a plane, ACA runs on
  /// the sub-blocks between different planes only (split_by_plane).
  bool low_rank(double tol, LowRank& out) const override {
    if (!far_pairs_only()) return false;
    prepare_points();
    const bool dl = kernel_ == SurfaceKernel::DoubleLayer;
    const Planes planes = dl ? this->planes() : Planes::Distinct;
    if (planes == Planes::One) {  // n_y . (x - y) = 0
      out.U.resize(m_, 0);
      out.V.resize(k_, 0);
      return true;
    }
    const PointKernel kernel{*rp_, *cp_, dl ? PointKernelKind::DoubleLayer : PointKernelKind::SingleLayer};
    // the projection sums about 10 point rows into a dof row: 0.3 tol (0.1 tol gave the same
    // products to 10 % at 1.1x the time, docs/design/bem3d.md)
    const double point_tol = 0.3 * tol;
    LowRank factors;
    if (planes == Planes::Shared) {
      factors = split_by_plane(kernel, point_tol);
    } else {
      const Slice row = [&kernel](Index p, double* o) { kernel.row(p, o); };
      const Slice column = [&kernel](Index q, double* o) { kernel.column(q, o); };
      factors = aca(rp_->size(), cp_->size(), row, column, point_tol, std::min(rp_->size(), cp_->size()));
    }
    project(factors, kernel_ == SurfaceKernel::Hypersingular, out);
    if (companion_) point_factors_ = std::move(factors);
    return true;
  }

  /// The hypersingular companion of the single layer (SurfaceEntries with_hypersingular): the
  /// same point kernel, projected by the curls.
  void companion_all(int which, double* out) const override {
    check_companion(which);
    Eigen::Map<Eigen::MatrixXd> result(out, m_, k_);
    if (!near_rows_) {
      result.setZero();
      for (const Part& r : row_parts_)
        for (const Part& c : col_parts_) add(r, c, out, 1, m_, true);
      return;
    }
    project(far_kernel(), true, result);
    for (Index p = 0; p < m_; ++p) add_near(near_->hypersingular(), I_[p], col_position_, out + p, m_);
  }
  bool companion_low_rank(int which, double /*tol*/, LowRank& out) const override {
    check_companion(which);
    if (!point_factors_) return false;  // low_rank() found near pairs: compress companion_all
    project(*point_factors_, true, out);
    return true;
  }

 private:
  /// A at the far-rule points with the near pairs' 9 x 9 parts zero (they are in the near
  /// field), computed once for the block and its companion.
  const Eigen::MatrixXd& far_kernel() const {
    if (far_kernel_.size() > 0) return far_kernel_;
    prepare_points();
    const PointKernel kernel{
        *rp_, *cp_,
        kernel_ == SurfaceKernel::DoubleLayer ? PointKernelKind::DoubleLayer : PointKernelKind::SingleLayer};
    const Index n = triangle_rule(kFarGaussPoints).size();
    far_kernel_.resize(rp_->size(), cp_->size());
    for (Index q = 0; q < cp_->size(); ++q) kernel.column(q, far_kernel_.col(q).data());
    for (std::size_t b = 0; b < col_parts_.size(); ++b) {
      const Triangle& tb = s_.triangle(col_parts_[b].triangle);
      for (std::size_t a = 0; a < row_parts_.size(); ++a)
        if (!PairIntegrator::far(s_.triangle(row_parts_[a].triangle), tb))
          far_kernel_.block(static_cast<Index>(a) * n, static_cast<Index>(b) * n, n, n).setZero();
    }
    return far_kernel_;
  }
  enum class Planes { Distinct, Shared, One };
  /// The largest distance of a triangle's centroid from the origin (the offsets' scale).
  double scale() const {
    double scale = 0.0;
    for (const Part& p : row_parts_) scale = std::max(scale, norm(s_.triangle(p.triangle).c));
    for (const Part& p : col_parts_) scale = std::max(scale, norm(s_.triangle(p.triangle).c));
    return scale;
  }
  /// The plane of a part's triangle: its normal and offset over `scale`, to 1e-8.
  std::array<long long, 4> plane_key(const Part& p, double scale) const {
    const Triangle& T = s_.triangle(p.triangle);
    auto q = [](double v) { return static_cast<long long>(std::llround(v * 1e8)); };
    return {q(T.n.x), q(T.n.y), q(T.n.z), q(dot(T.n, T.c) / (scale + 1e-300))};
  }
  /// Whether a triangle of the rows and one of the columns lie in one plane (Shared), or all
  /// triangles of both in the same plane (One: the double layer's block is zero); normals
  /// and offsets compared to 1e-8 relative (a polyhedron's faces, whose triangles' normals
  /// differ by round-off).
  Planes planes() const {
    const double scale = this->scale();
    std::set<std::array<long long, 4>> rows, cols;
    for (const Part& p : row_parts_) rows.insert(plane_key(p, scale));
    for (const Part& p : col_parts_) cols.insert(plane_key(p, scale));
    if (rows.size() == 1 && rows == cols) return Planes::One;
    for (const auto& k : cols)
      if (rows.count(k)) return Planes::Shared;
    return Planes::Distinct;
  }
  /// The double layer's point factors of a block in which a row and a column triangle share
  /// a plane. A vanishes between the points of one plane, so ACA runs on the sub-blocks
  /// without such zeros - the rows of each plane p of both sides against the columns off p,
  /// and the rows on no column plane against every column - and their factors, zero outside
  /// their rows and columns, are stacked.
  LowRank split_by_plane(const PointKernel& kernel, double tol) const {
    const double scale = this->scale();
    std::map<std::array<long long, 4>, int> ids;
    auto plane_of = [&](const std::vector<Part>& parts) {
      std::vector<int> plane;  // per far point: its triangle's plane
      const int n = triangle_rule(kFarGaussPoints).size();
      for (const Part& p : parts)
        plane.insert(plane.end(), static_cast<std::size_t>(n),
                     ids.emplace(plane_key(p, scale), static_cast<int>(ids.size())).first->second);
      return plane;
    };
    const std::vector<int> row_plane = plane_of(row_parts_), col_plane = plane_of(col_parts_);
    const std::set<int> col_planes(col_plane.begin(), col_plane.end());
    const Index m = rp_->size(), n = cp_->size();
    std::vector<LowRank> pieces;
    std::vector<std::vector<Index>> piece_rows, piece_cols;
    std::vector<double> full_row(static_cast<std::size_t>(n)), full_column(static_cast<std::size_t>(m));
    // group -1: the rows on no column plane, against every column
    std::set<int> groups{-1};
    for (int p : row_plane)
      if (col_planes.count(p)) groups.insert(p);
    for (int g : groups) {
      std::vector<Index> R, C;
      for (Index i = 0; i < m; ++i) {
        const int p = row_plane[static_cast<std::size_t>(i)];
        if (g < 0 ? col_planes.count(p) == 0 : p == g) R.push_back(i);
      }
      for (Index j = 0; j < n; ++j)
        if (col_plane[static_cast<std::size_t>(j)] != g) C.push_back(j);
      if (R.empty() || C.empty()) continue;
      const Slice row = [&](Index i, double* o) {
        kernel.row(R[static_cast<std::size_t>(i)], full_row.data());
        for (std::size_t c = 0; c < C.size(); ++c) o[c] = full_row[static_cast<std::size_t>(C[c])];
      };
      const Slice column = [&](Index j, double* o) {
        kernel.column(C[static_cast<std::size_t>(j)], full_column.data());
        for (std::size_t r = 0; r < R.size(); ++r) o[r] = full_column[static_cast<std::size_t>(R[r])];
      };
      const Index rows = static_cast<Index>(R.size()), cols = static_cast<Index>(C.size());
      pieces.push_back(aca(rows, cols, row, column, tol, std::min(rows, cols)));
      piece_rows.push_back(std::move(R));
      piece_cols.push_back(std::move(C));
    }
    Index rank = 0;
    for (const LowRank& piece : pieces) rank += piece.rank();
    LowRank out{Eigen::MatrixXd::Zero(m, rank), Eigen::MatrixXd::Zero(n, rank)};
    Index at = 0;
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      const LowRank& piece = pieces[k];
      for (std::size_t r = 0; r < piece_rows[k].size(); ++r)
        out.U.row(piece_rows[k][r]).segment(at, piece.rank()) = piece.U.row(static_cast<Index>(r));
      for (std::size_t c = 0; c < piece_cols[k].size(); ++c)
        out.V.row(piece_cols[k][c]).segment(at, piece.rank()) = piece.V.row(static_cast<Index>(c));
      at += piece.rank();
    }
    return out;  // recompressed after the projection (HMatrix::fill), at the dofs' size
  }
  void check_companion(int which) const {
    if (which != 1 || !companion_)
      throw std::logic_error("SurfaceBlock: only the single layer has a companion, the hypersingular operator");
  }
  /// The far-rule points of both sides, with the maps of the matrices asked for.
  void prepare_points() const {
    if (rp_) return;
    const bool values = kernel_ != SurfaceKernel::Hypersingular;
    const bool curls = kernel_ == SurfaceKernel::Hypersingular || companion_;
    const TriangleRule& rule = triangle_rule(kFarGaussPoints);
    rp_ = std::make_unique<FarPoints>(s_, row_parts_, m_, values, curls, rule);
    cp_ = std::make_unique<FarPoints>(s_, col_parts_, k_, values, curls, rule);
  }
  /// Q_r^T A Q_c with the values' maps, or sum_d C_r[d]^T A_t C_c[d] with the curls, A_t the
  /// sums of A over each triangle pair's points (the curls are constant on a triangle: 81
  /// times fewer entries to project).
  void project(const Eigen::MatrixXd& A, bool curls, Eigen::Map<Eigen::MatrixXd>& out) const {
    if (!curls) {
      const Eigen::MatrixXd AQ = A * cp_->values[0];
      out = rp_->values[0].transpose() * AQ;
      return;
    }
    const Eigen::MatrixXd pairs =
        sum_over_parts(sum_over_parts(A, rp_->per_part).transpose(), cp_->per_part).transpose();
    out.setZero();
    for (std::size_t d = 0; d < rp_->curls.size(); ++d) {
      const Eigen::MatrixXd AC = pairs * cp_->curls[d];
      out += rp_->curls[d].transpose() * AC;
    }
  }
  /// The point factors projected to the dofs: the maps side by side (the three curl
  /// components, from the factors summed over each triangle's points: rank 3r, recompressed
  /// by the H-matrix to its rank).
  void project(const LowRank& points, bool curls, LowRank& out) const {
    if (!curls) {
      out.U = rp_->values[0].transpose() * points.U;
      out.V = cp_->values[0].transpose() * points.V;
      return;
    }
    const Eigen::MatrixXd U = sum_over_parts(points.U, rp_->per_part), V = sum_over_parts(points.V, cp_->per_part);
    const Index rank = points.rank(), maps = static_cast<Index>(rp_->curls.size());
    out.U.resize(m_, maps * rank);
    out.V.resize(k_, maps * rank);
    for (Index d = 0; d < maps; ++d) {
      out.U.middleCols(d * rank, rank) = rp_->curls[static_cast<std::size_t>(d)].transpose() * U;
      out.V.middleCols(d * rank, rank) = cp_->curls[static_cast<std::size_t>(d)].transpose() * V;
    }
  }
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
  void add(const Part& r, const Part& c, double* out, Index row_stride, Index col_stride,
           bool companion = false) const {
    if (near_rows_ && !PairIntegrator::far(s_.triangle(r.triangle), s_.triangle(c.triangle))) return;
    PairIntegrals L;
    const bool dl = kernel_ == SurfaceKernel::DoubleLayer;
    const bool w = companion || kernel_ == SurfaceKernel::Hypersingular;
    integrator_.integrate(r.triangle, c.triangle, dl, L);
    const Triangle &tr = s_.triangle(r.triangle), &tc = s_.triangle(c.triangle);
    for (int a = 0; a < r.count; ++a)
      for (int b = 0; b < c.count; ++b) {
        const double v = dl  ? L.K[r.basis[a]][c.basis[b]]
                         : w ? L.V[3][3] * dot(surface_curl(tr, r.basis[a]), surface_curl(tc, c.basis[b]))
                             : L.V[r.basis[a]][c.basis[b]];
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
  bool companion_ = false;  ///< the hypersingular companion (single layer only)
  const SurfaceNearField* near_ = nullptr;
  const RowSparse* near_rows_ = nullptr;  ///< near part by rows, and by columns
  const RowSparse* near_cols_ = nullptr;
  std::unordered_map<Index, Index> row_position_, col_position_;  ///< dof -> position in the block
  // computed once per block, shared with the companion
  mutable std::unique_ptr<FarPoints> rp_, cp_;
  mutable Eigen::MatrixXd far_kernel_;
  mutable std::optional<LowRank> point_factors_;  ///< the ACA factors on the points (companion only)
};

}  // namespace

SurfaceEntries::SurfaceEntries(const Surface& surface, SurfaceKernel kernel, Space rows, Space cols,
                               std::shared_ptr<const SurfaceNearField> near, bool with_hypersingular)
    : surface_(surface),
      integrator_(surface),
      kernel_(kernel),
      rows_(rows),
      cols_(cols),
      near_(std::move(near)),
      with_hypersingular_(with_hypersingular) {
  if (with_hypersingular && (kernel != SurfaceKernel::SingleLayer || rows != Space::P1 || cols != Space::P1))
    throw std::invalid_argument("SurfaceEntries: the hypersingular companion is that of the P1 single layer");
  if (kernel == SurfaceKernel::DoubleLayer && cols != Space::P1)
    throw std::invalid_argument("SurfaceEntries: the double layer acts on the P1 trace");
  if (kernel == SurfaceKernel::Hypersingular && (rows != Space::P1 || cols != Space::P1))
    throw std::invalid_argument("SurfaceEntries: the hypersingular operator is P1 x P1");
  if (near_ && rows != cols) throw std::invalid_argument("SurfaceEntries: the near field is P0 x P0 or P1 x P1");
}

std::unique_ptr<EntryBlock> SurfaceEntries::block(const Index* I, Index m, const Index* J, Index k) const {
  return std::make_unique<SurfaceBlock>(surface_, integrator_, near_.get(), kernel_, rows_, cols_, I, m, J, k,
                                        with_hypersingular_);
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
