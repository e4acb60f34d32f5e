#include "bem/surface_entries.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
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
  }

  void row(Index i, double* out) const override { line(true, i, out); }
  void column(Index j, double* out) const override { line(false, j, out); }
  /// With the near field apart: the far pairs as Q_r^T A Q_c, A the point kernel of the far
  /// pairs (zero on the near ones; the double layer's pair by pair, double_layer_all), the
  /// near pairs from the sparse near field.
  void all(double* out) const override {
    Eigen::Map<Eigen::MatrixXd> result(out, m_, k_);
    if (!near_rows_) {
      result.setZero();
      for (const Part& r : row_parts_)
        for (const Part& c : col_parts_) add(r, c, out, 1, m_);
      return;
    }
    if (kernel_ == SurfaceKernel::DoubleLayer) {
      double_layer_all(out, nullptr);
    } else if (kernel_ == SurfaceKernel::SingleLayer) {
      single_layer_far(out);
    } else {
      single_layer_far(nullptr);
      project_pairs(result);
    }
    for (Index p = 0; p < m_; ++p) add_near(*near_rows_, I_[p], col_positions(), out + p, m_);
  }
  /// The double layer's block and its mirror K(J, I) from one pass over the point pairs
  /// (double_layer_all), each with its near pairs.
  bool all_and_transpose(double* out, double* transposed) const override {
    if (kernel_ != SurfaceKernel::DoubleLayer || !near_rows_ || rows_ != cols_) return false;
    double_layer_all(out, transposed);
    for (Index p = 0; p < m_; ++p) add_near(*near_rows_, I_[p], col_positions(), out + p, m_);
    for (Index q = 0; q < k_; ++q) add_near(*near_rows_, J_[q], row_positions(), transposed + q, k_);
    return true;
  }

  /// Far blocks: every triangle pair is evaluated by the far rule (the block's entries are
  /// Q_r^T A Q_c with A the kernel at the far-rule points, weights included), so ACA runs on
  /// A, one kernel evaluation per entry, and the factors are projected to the dofs.
  /// The double layer's A vanishes between coplanar points (flat faces), a structure on
  /// which ACA's partial pivoting can miss whole sub-blocks (on the cube: products 2e-4 off
  /// at any tol): double_layer_low_rank.
  bool low_rank(double tol, LowRank& out) const override {
    if (!far_pairs_only()) return false;
    // the projection sums about 10 point rows into a dof row: 0.3 tol (0.1 tol gave the same
    // products to 10 % at 1.1x the time, docs/design/bem3d.md)
    const double point_tol = 0.3 * tol;
    if (kernel_ == SurfaceKernel::DoubleLayer) {
      double_layer_low_rank(point_tol, out);
      return true;
    }
    prepare_points();
    const PointKernel kernel{*rp_, *cp_, PointKernelKind::SingleLayer};
    LowRank factors = aca(kernel, point_tol);
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
    if (far_pairs_.size() == 0) single_layer_far(nullptr);  // all() computed them otherwise
    project_pairs(result);
    for (Index p = 0; p < m_; ++p) add_near(near_->hypersingular(), I_[p], col_positions(), out + p, m_);
  }
  bool companion_low_rank(int which, double /*tol*/, LowRank& out) const override {
    check_companion(which);
    if (!point_factors_) return false;  // low_rank() found near pairs: compress companion_all
    project(*point_factors_, true, out);
    return true;
  }

 private:
  /// The single layer's far pairs in one pass over the point pairs, without the block's
  /// point matrix: per column part b, the kernel between every row point and b's points
  /// summed against the values of b's hats (A Lambda_b, vectorised over the rows) and, with
  /// the hypersingular companion, over b's points (A 1); then each far row part a adds
  /// Lambda_a^T A Lambda_b to its dofs' entries of `out` (m x k, unless null) and 1^T A 1 to
  /// far_pairs_(a, b), the sums the surface curls project (project_pairs). The near pairs
  /// are left out of both (they are in the near field).
  void single_layer_far(double* out) const {
    constexpr int n = kFarRulePoints;
    prepare_points();
    const Eigen::Matrix<double, n, 4> L = basis_values(far_rule());
    const bool sums = companion_ || kernel_ == SurfaceKernel::Hypersingular;
    const Index parts = static_cast<Index>(row_parts_.size());
    Eigen::Matrix<double, Eigen::Dynamic, 4> AL(rp_->size(), 4);  // b's three hats, and 1
    Eigen::Map<Eigen::MatrixXd> result(out, out ? m_ : 0, out ? k_ : 0);
    result.setZero();
    if (sums) far_pairs_.setZero(parts, static_cast<Index>(col_parts_.size()));
    for (std::size_t b = 0; b < col_parts_.size(); ++b) {
      const Part& cb = col_parts_[b];
      const Triangle& tb = s_.triangle(cb.triangle);
      AL.setZero();
      for (int q = 0; q < n; ++q) {
        double l[4];  // the values of b's hats at its point q (zero for hats not in the block), 1
        for (int j = 0; j < 3; ++j) l[j] = j < cb.count ? L(q, cb.basis[j]) : 0.0;
        l[3] = 1.0;
        const Index c = static_cast<Index>(b) * n + q;
        if (sums)
          accumulate_single_layer<true>(*rp_, *cp_, c, l, AL);
        else
          accumulate_single_layer<false>(*rp_, *cp_, c, l, AL);
      }
      for (Index a = 0; a < parts; ++a) {
        const Part& ra = row_parts_[static_cast<std::size_t>(a)];
        if (!PairIntegrator::far(s_.triangle(ra.triangle), tb)) continue;
        if (sums) far_pairs_(a, static_cast<Index>(b)) = AL.col(3).segment(a * n, n).sum();
        if (!out) continue;
        for (int i = 0; i < ra.count; ++i)
          for (int j = 0; j < cb.count; ++j)
            result(ra.position[i], cb.position[j]) += L.col(ra.basis[i]).dot(AL.col(j).segment(a * n, n));
      }
    }
  }
  /// AL(p, j) += l[j] A(p, c) for every row point p, j < 3 (and j = 3 with `sums`), A the
  /// single layer's point kernel (weights included) at the column point c.
  template <bool sums>
  static void accumulate_single_layer(const FarPoints& r, const FarPoints& c, Index q, const double* l,
                                      Eigen::Matrix<double, Eigen::Dynamic, 4>& AL) {
    const std::size_t j = static_cast<std::size_t>(q);
    const double x = c.x[j], y = c.y[j], z = c.z[j], w = kInvTwoPi * c.w[j];
    const double l0 = l[0], l1 = l[1], l2 = l[2];
    double *a0 = AL.col(0).data(), *a1 = AL.col(1).data(), *a2 = AL.col(2).data(), *a3 = AL.col(3).data();
    const double *rx = r.x.data(), *ry = r.y.data(), *rz = r.z.data(), *rw = r.w.data();
    const Index points = r.size();
#pragma omp simd
    for (Index p = 0; p < points; ++p) {
      const double dx = rx[p] - x, dy = ry[p] - y, dz = rz[p] - z;
      const double k = w * rw[p] / std::sqrt(dx * dx + dy * dy + dz * dz);
      a0[p] += l0 * k;
      a1[p] += l1 * k;
      a2[p] += l2 * k;
      if constexpr (sums) a3[p] += k;
    }
  }
  /// ACA on a point kernel to `tol`.
  static LowRank aca(const PointKernel& kernel, double tol) {
    const Slice row = [&kernel](Index p, double* o) { kernel.row(p, o); };
    const Slice column = [&kernel](Index q, double* o) { kernel.column(q, o); };
    const Index m = kernel.r.size(), n = kernel.c.size();
    return bem::aca(m, n, row, column, tol, std::min(m, n));
  }
  /// The planes of the parts' triangles (triangle_planes), sorted, each once.
  std::vector<int> planes_of(const std::vector<Part>& parts) const {
    std::vector<int> out;
    for (const Part& p : parts) out.push_back(integrator_.planes()[static_cast<std::size_t>(p.triangle)]);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  int plane(const Part& p) const { return integrator_.planes()[static_cast<std::size_t>(p.triangle)]; }
  /// The double layer's factors (at the dofs) of a far block. A block whose triangles all
  /// lie in one plane is zero (n_y . (x - y) = 0). In a block in which a row and a column
  /// triangle share a plane, ACA runs on the sub-blocks without such zeros - the rows of
  /// each plane p of both sides against the columns off p, and the rows on no column plane
  /// against every column - each on the points of its own parts, and the factors of each
  /// sub-block, projected to the dofs, stand side by side (recompressed by HMatrix::fill).
  /// Otherwise ACA runs on the whole point kernel.
  void double_layer_low_rank(double tol, LowRank& out) const {
    const std::vector<int> row_planes = planes_of(row_parts_), col_planes = planes_of(col_parts_);
    out.U.setZero(m_, 0);
    out.V.setZero(k_, 0);
    if (row_planes.size() == 1 && row_planes == col_planes) return;
    std::vector<int> shared;
    std::set_intersection(row_planes.begin(), row_planes.end(), col_planes.begin(), col_planes.end(),
                          std::back_inserter(shared));
    const TriangleRule& rule = far_rule();
    std::vector<LowRank> pieces;
    std::vector<std::vector<Part>> piece_rows, piece_cols;
    auto add_piece = [&](std::vector<Part> R, std::vector<Part> C) {
      if (R.empty() || C.empty()) return;
      const FarPoints rp(s_, R, m_, false, rule), cp(s_, C, k_, false, rule);
      pieces.push_back(aca(PointKernel{rp, cp, PointKernelKind::DoubleLayer}, tol));
      piece_rows.push_back(std::move(R));
      piece_cols.push_back(std::move(C));
    };
    if (shared.empty()) {
      add_piece(row_parts_, col_parts_);
    } else {
      // group -1: the rows on no column plane, against every column
      std::vector<Part> R;
      for (const Part& p : row_parts_)
        if (!std::binary_search(col_planes.begin(), col_planes.end(), plane(p))) R.push_back(p);
      add_piece(std::move(R), col_parts_);
      for (int g : shared) {
        std::vector<Part> Rg, Cg;
        for (const Part& p : row_parts_)
          if (plane(p) == g) Rg.push_back(p);
        for (const Part& p : col_parts_)
          if (plane(p) != g) Cg.push_back(p);
        add_piece(std::move(Rg), std::move(Cg));
      }
    }
    Index rank = 0;
    for (const LowRank& piece : pieces) rank += piece.rank();
    out.U.setZero(m_, rank);
    out.V.setZero(k_, rank);
    Index at = 0;
    for (std::size_t p = 0; p < pieces.size(); ++p) {
      const Index r = pieces[p].rank();
      add_values_transpose_product(piece_rows[p], rule, pieces[p].U, out.U.middleCols(at, r));
      add_values_transpose_product(piece_cols[p], rule, pieces[p].V, out.V.middleCols(at, r));
      at += r;
    }
  }
  /// The double layer's dense block with the near field apart: each triangle pair (a, b)
  /// that is far and in two planes (coplanar pairs are zero, the near pairs are in the near
  /// field) adds Lambda^T A_ab Lambda, A_ab its 7 x 7 point kernel and Lambda the basis
  /// values at the rule's points, to its dofs' entries - no point matrix of the block, no
  /// maps. The row parts sorted by plane, the row points off b's plane are at most two
  /// ranges, on which the kernel runs column by column (vectorised), summed at once against
  /// the values of b's hats. With `transposed` (k x m), also the mirrored block K(J, I):
  /// between the same points its kernel is -n_x . (x - y) / r^3, from the same 1 / r^3.
  void double_layer_all(double* out, double* transposed) const {
    constexpr int n = kFarRulePoints;
    const TriangleRule& rule = far_rule();
    const Eigen::Matrix<double, n, 4> L = basis_values(rule);
    std::vector<Part> rows = row_parts_;
    std::stable_sort(rows.begin(), rows.end(), [this](const Part& a, const Part& b) { return plane(a) < plane(b); });
    const FarPoints rp(s_, rows, m_, false, rule), cp(s_, col_parts_, k_, false, rule);
    const Index parts = static_cast<Index>(rows.size()), points = rp.size();
    // the kernel's rows summed against the values of b's (up to three) hats: A Lambda_b, and
    // the mirror's
    Eigen::Matrix<double, Eigen::Dynamic, 3> AL(points, 3), BL(transposed ? points : 0, 3);
    Eigen::Map<Eigen::MatrixXd> result(out, m_, k_);
    result.setZero();
    if (transposed) Eigen::Map<Eigen::MatrixXd>(transposed, k_, m_).setZero();
    for (std::size_t b = 0; b < col_parts_.size(); ++b) {
      const Part& cb = col_parts_[b];
      const Triangle& tb = s_.triangle(cb.triangle);
      const int pb = plane(cb);
      // the row parts [first, last) in b's plane
      const Index first =
          std::lower_bound(rows.begin(), rows.end(), pb, [this](const Part& p, int v) { return plane(p) < v; }) -
          rows.begin();
      Index last = first;
      while (last < parts && plane(rows[static_cast<std::size_t>(last)]) == pb) ++last;
      const std::pair<Index, Index> ranges[2] = {{0, first}, {last, parts}};
      double l[n][3];  // the values of b's hats at its points (zero for hats not in the block)
      for (int q = 0; q < n; ++q)
        for (int j = 0; j < 3; ++j) l[q][j] = j < cb.count ? L(q, cb.basis[j]) : 0.0;
      for (const auto& [a0, a1] : ranges) {
        if (a0 == a1) continue;
        const Index p0 = a0 * n, p1 = a1 * n;
        AL.middleRows(p0, p1 - p0).setZero();
        if (transposed) BL.middleRows(p0, p1 - p0).setZero();
        for (int q = 0; q < n; ++q) {
          const Index c = static_cast<Index>(b) * n + q;
          if (transposed)
            accumulate<true>(rp, cp, c, l[q], p0, p1, AL, BL);
          else
            accumulate<false>(rp, cp, c, l[q], p0, p1, AL, BL);
        }
        for (Index a = a0; a < a1; ++a) {
          const Part& ra = rows[static_cast<std::size_t>(a)];
          if (!PairIntegrator::far(s_.triangle(ra.triangle), tb)) continue;
          for (int i = 0; i < ra.count; ++i) {
            const double* la = L.col(ra.basis[i]).data();
            for (int j = 0; j < cb.count; ++j) {
              const double* al = AL.col(j).data() + a * n;
              double e = 0.0;
              for (int p = 0; p < n; ++p) e += la[p] * al[p];
              result(ra.position[i], cb.position[j]) += e;
              if (!transposed) continue;
              const double* bl = BL.col(j).data() + a * n;
              e = 0.0;
              for (int p = 0; p < n; ++p) e += la[p] * bl[p];
              transposed[cb.position[j] + k_ * ra.position[i]] += e;
            }
          }
        }
      }
    }
  }
  /// AL(p, j) += l[j] K(p, c) for the row points p in [p0, p1), K the double layer's point
  /// kernel (weights included) at the column point c; with `mirror`, BL(p, j) += l[j] times
  /// the mirrored kernel (the row point's normal, the sign turned).
  template <bool mirror>
  static void accumulate(const FarPoints& r, const FarPoints& c, Index q, const double* l, Index p0, Index p1,
                         Eigen::Matrix<double, Eigen::Dynamic, 3>& AL, Eigen::Matrix<double, Eigen::Dynamic, 3>& BL) {
    const std::size_t j = static_cast<std::size_t>(q);
    const double x = c.x[j], y = c.y[j], z = c.z[j], w = kInvTwoPi * c.w[j];
    const double nx = c.nx[j], ny = c.ny[j], nz = c.nz[j];
    const double l0 = l[0], l1 = l[1], l2 = l[2];
    double *a0 = AL.col(0).data(), *a1 = AL.col(1).data(), *a2 = AL.col(2).data();
    double *b0 = BL.col(0).data(), *b1 = BL.col(1).data(), *b2 = BL.col(2).data();
    const double *rx = r.x.data(), *ry = r.y.data(), *rz = r.z.data(), *rw = r.w.data();
    const double *rnx = r.nx.data(), *rny = r.ny.data(), *rnz = r.nz.data();
#pragma omp simd
    for (Index p = p0; p < p1; ++p) {
      const double dx = rx[p] - x, dy = ry[p] - y, dz = rz[p] - z;
      const double s = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
      const double s3 = w * rw[p] * s * s * s;
      const double k = (dx * nx + dy * ny + dz * nz) * s3;
      a0[p] += l0 * k;
      a1[p] += l1 * k;
      a2[p] += l2 * k;
      if constexpr (mirror) {
        const double t = -(dx * rnx[p] + dy * rny[p] + dz * rnz[p]) * s3;
        b0[p] += l0 * t;
        b1[p] += l1 * t;
        b2[p] += l2 * t;
      }
    }
  }
  void check_companion(int which) const {
    if (which != 1 || !companion_)
      throw std::logic_error("SurfaceBlock: only the single layer has a companion, the hypersingular operator");
  }
  /// The far-rule points of both sides, with the curls' maps when W is asked for.
  void prepare_points() const {
    if (rp_) return;
    const bool curls = kernel_ == SurfaceKernel::Hypersingular || companion_;
    rp_ = std::make_unique<FarPoints>(s_, row_parts_, m_, curls, far_rule());
    cp_ = std::make_unique<FarPoints>(s_, col_parts_, k_, curls, far_rule());
  }
  /// out = sum_d C_r[d]^T P C_c[d], P = far_pairs_ (single_layer_far): the hypersingular
  /// block's far part by Nedelec's identity (the curls are constant on a triangle, so the
  /// point kernel enters through its sums over each pair's points only).
  void project_pairs(Eigen::Map<Eigen::MatrixXd>& out) const {
    out.setZero();
    for (std::size_t d = 0; d < rp_->curls.size(); ++d) {
      const Eigen::MatrixXd PC = far_pairs_ * cp_->curls[d];
      out += rp_->curls[d].transpose() * PC;
    }
  }
  /// The point factors projected to the dofs: the maps side by side (the three curl
  /// components, from the factors summed over each triangle's points: rank 3r, recompressed
  /// by the H-matrix to its rank).
  void project(const LowRank& points, bool curls, LowRank& out) const {
    if (!curls) {
      out.U.setZero(m_, points.rank());
      out.V.setZero(k_, points.rank());
      add_values_transpose_product(row_parts_, far_rule(), points.U, out.U);
      add_values_transpose_product(col_parts_, far_rule(), points.V, out.V);
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
  /// dof -> position in the block, of the rows and of the columns (built when first asked:
  /// the low-rank blocks need none).
  /// Row i of the block (by_row: A(I[i], J)) or column i (A(I, J[i])) into out: the pairs
  /// of the far field with the parts of its own dof, then its near part.
  void line(bool by_row, Index i, double* out) const {
    std::fill(out, out + (by_row ? k_ : m_), 0.0);
    const std::vector<Part> own = by_row ? parts(s_, rows_, I_ + i, 1) : parts(s_, cols_, J_ + i, 1);
    for (const Part& r : by_row ? own : row_parts_)
      for (const Part& c : by_row ? col_parts_ : own) add(r, c, out, by_row ? 0 : 1, by_row ? 1 : 0);
    const RowSparse* near = by_row ? near_rows_ : near_cols_;
    if (near) add_near(*near, by_row ? I_[i] : J_[i], by_row ? col_positions() : row_positions(), out, 1);
  }
  const std::unordered_map<Index, Index>& row_positions() const {
    if (row_position_.empty())
      for (Index p = 0; p < m_; ++p) row_position_[I_[p]] = p;
    return row_position_;
  }
  const std::unordered_map<Index, Index>& col_positions() const {
    if (col_position_.empty())
      for (Index q = 0; q < k_; ++q) col_position_[J_[q]] = q;
    return col_position_;
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
  mutable std::unordered_map<Index, Index> row_position_, col_position_;  ///< row_positions, col_positions
  // computed once per block, shared with the companion
  mutable std::unique_ptr<FarPoints> rp_, cp_;
  mutable Eigen::MatrixXd far_pairs_;             ///< single_layer_far's sums over the far pairs' points
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
