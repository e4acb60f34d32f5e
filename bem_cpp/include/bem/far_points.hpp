#pragma once
// Far-field blocks as point kernels (surface_entries.hpp, surface_potential_operator.hpp): a
// block whose triangle pairs (or point-triangle pairs) all take one fixed rule has the
// entries Q_r^T A Q_c, A the kernel between the rule's points (weights included) and Q the
// basis functions at them, so ACA runs on A (one kernel evaluation per entry, vectorised
// over points stored by coordinate) and its factors are projected onto the dofs.
#include <Eigen/Sparse>
#include <cmath>
#include <vector>

#include "bem/surface.hpp"
#include "bem/surface_operators.hpp"
#include "bem/surface_quadrature.hpp"

namespace bem {

constexpr double kInvTwoPi = 0.5 / M_PI;  // 2 G(r) = 1 / (2 pi r), the factor-2 convention

/// A triangle of a block's row or column supports, with the dofs it carries there: the
/// local basis index (0..2 barycentric, 3 constant) and the position in the block.
struct Part {
  Index triangle;
  int count = 0;
  int basis[3] = {0, 0, 0};
  Index position[3] = {0, 0, 0};
};

/// The parts of the dofs `dofs[0..k)` of `space`, one per triangle (sorted by triangle).
std::vector<Part> parts(const Surface& s, Space space, const Index* dofs, Index k);

/// The points of `rule` on the triangles of `parts` (by coordinate, so that the kernel
/// loops below vectorise), with weights (the rule's weight times twice the area: the
/// physical measure) and normals; a function of the points goes to the block's dofs by the
/// basis values (add_values_transpose_product). Or target points themselves (weight 1, no
/// normal, no maps: the rows of a potential).
struct FarPoints {
  std::vector<double> x, y, z, nx, ny, nz, w;
  /// parts x dofs: the three components of the surface curls of the basis functions (the
  /// hypersingular operator by Nedelec's identity W = sum_c C_c^T V0 C_c), constant on a
  /// triangle: the map of the points is the points' sum over each part's `per_part` points
  /// (consecutive, part by part) followed by these (see sum_over_parts).
  std::vector<Eigen::SparseMatrix<double>> curls;
  Index per_part = 1;

  FarPoints(const Surface& s, const std::vector<Part>& parts, Index dofs, bool with_curls, const TriangleRule& rule);
  FarPoints(const Vertices& points, const Index* I, Index m);
  Index size() const { return static_cast<Index>(w.size()); }
};

/// The sums of the rows of A (points x k) over each part's `per_part` consecutive points:
/// (parts x k).
Eigen::MatrixXd sum_over_parts(const Eigen::Ref<const Eigen::MatrixXd>& A, Index per_part);

/// The basis values at the points of `rule` (rule points x 4): column a < 3 the barycentric
/// coordinate a (P1), column 3 the constant 1 (P0).
Eigen::Matrix<double, Eigen::Dynamic, 4> basis_values(const TriangleRule& rule);

/// out += Q^T A with Q the basis values of `parts` at the rule's points (points x dofs),
/// without forming it:
/// row `position` of out gains, for each dof of a part, the sum over the part's points
/// (rule.size() consecutive rows of A, part by part) of its basis value times A's row.
/// A (parts x rule points, k), out (dofs, k).
void add_values_transpose_product(const std::vector<Part>& parts, const TriangleRule& rule,
                                  const Eigen::Ref<const Eigen::MatrixXd>& A, Eigen::Ref<Eigen::MatrixXd> out);

/// The point kernels: 2 G = 1 / (2 pi r) (single layer), 2 dG/dn_y = n_y . (x - y) / (2 pi r^3)
/// (double layer, the normal of the column point).
enum class PointKernelKind { SingleLayer, DoubleLayer };

/// The kernel of `kind` at d = x - y (n: the normal at y), without the weights.
template <PointKernelKind kind>
inline double point_kernel(double dx, double dy, double dz, double nx, double ny, double nz) {
  const double s = 1.0 / std::sqrt(dx * dx + dy * dy + dz * dz);
  if constexpr (kind == PointKernelKind::SingleLayer) return s;
  return (dx * nx + dy * ny + dz * nz) * s * s * s;
}

/// A point kernel between the far-rule points of a block's rows (r) and columns (c), weights
/// included.
struct PointKernel {
  const FarPoints& r;
  const FarPoints& c;
  PointKernelKind kind;

  /// out[q] = A(p, q) for every column point q.
  void row(Index p, double* out) const {
    switch (kind) {
      case PointKernelKind::SingleLayer:
        return row<PointKernelKind::SingleLayer>(p, out);
      case PointKernelKind::DoubleLayer:
        return row<PointKernelKind::DoubleLayer>(p, out);
    }
  }
  /// out[p] = A(p, q) for every row point p.
  void column(Index q, double* out) const { column(q, 0, r.size(), out); }
  /// out[p] = A(p, q) for the row points p in [begin, end).
  void column(Index q, Index begin, Index end, double* out) const {
    switch (kind) {
      case PointKernelKind::SingleLayer:
        return column<PointKernelKind::SingleLayer>(q, begin, end, out);
      case PointKernelKind::DoubleLayer:
        return column<PointKernelKind::DoubleLayer>(q, begin, end, out);
    }
  }

 private:
  template <PointKernelKind kind>
  void row(Index p, double* out) const {
    const std::size_t i = static_cast<std::size_t>(p);
    const double x = r.x[i], y = r.y[i], z = r.z[i], w = kInvTwoPi * r.w[i];
    for (Index q = 0; q < c.size(); ++q)
      out[q] = w * c.w[q] * point_kernel<kind>(x - c.x[q], y - c.y[q], z - c.z[q], c.nx[q], c.ny[q], c.nz[q]);
  }
  template <PointKernelKind kind>
  void column(Index q, Index begin, Index end, double* out) const {
    const std::size_t j = static_cast<std::size_t>(q);
    const double x = c.x[j], y = c.y[j], z = c.z[j], w = kInvTwoPi * c.w[j];
    const double nx = c.nx[j], ny = c.ny[j], nz = c.nz[j];
    for (Index p = begin; p < end; ++p)
      out[p] = w * r.w[p] * point_kernel<kind>(r.x[p] - x, r.y[p] - y, r.z[p] - z, nx, ny, nz);
  }
};

}  // namespace bem
