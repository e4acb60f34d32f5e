#pragma once
// Test polygons shared by the GoogleTest files.
#include <cmath>

#include "bem/geometry.hpp"
#include "bem/operator_entries.hpp"
#include "bem/steklov_operator.hpp"

namespace bem::test {

inline Points circle(Index n, double radius = 0.4) {
  Points X(n, 2);
  for (Index k = 0; k < n; ++k) {
    const double t = 2.0 * M_PI * static_cast<double>(k) / static_cast<double>(n);
    X(k, 0) = radius * std::cos(t);
    X(k, 1) = radius * std::sin(t);
  }
  return X;
}

/// Square [-s, s]^2 with m panels per side.
inline Points square(Index m, double s = 0.3) {
  Points X(4 * m, 2);
  const double c[4][2] = {{-s, -s}, {s, -s}, {s, s}, {-s, s}};
  for (int side = 0; side < 4; ++side)
    for (Index k = 0; k < m; ++k) {
      const double w = static_cast<double>(k) / static_cast<double>(m);
      const int e = (side + 1) % 4;
      X(side * m + k, 0) = (1 - w) * c[side][0] + w * c[e][0];
      X(side * m + k, 1) = (1 - w) * c[side][1] + w * c[e][1];
    }
  return X;
}

/// L-shape: the square [-s, s]^2 without its upper right quarter, k panels per length s,
/// moved to the centre o.
inline Points l_shape(Index k, double s = 0.3, Vec2 o = {0.0, 0.0}) {
  const double c[6][2] = {{o.x - s, o.y - s}, {o.x + s, o.y - s}, {o.x + s, o.y},
                          {o.x, o.y},         {o.x, o.y + s},     {o.x - s, o.y + s}};
  const Index per[6] = {2 * k, k, k, k, k, 2 * k};
  Points X(8 * k, 2);
  Index row = 0;
  for (int side = 0; side < 6; ++side)
    for (Index j = 0; j < per[side]; ++j) {
      const double w = static_cast<double>(j) / static_cast<double>(per[side]);
      const int e = (side + 1) % 6;
      X(row, 0) = (1 - w) * c[side][0] + w * c[e][0];
      X(row, 1) = (1 - w) * c[side][1] + w * c[e][1];
      ++row;
    }
  return X;
}

/// A thin triangle with a 10 degree angle at the origin and its two long sides graded
/// quadratically towards it (neighbouring lengths up to 1:3, 1:20 across the apex): sharp
/// adjacent pairs, unequal lengths and near pairs of the quadrature. k panels per long side.
inline Points dart(Index k) {
  const double L = 0.6, a = 5.0 * M_PI / 180.0;
  const Vec2 B{L * std::cos(a), -L * std::sin(a)}, C{L * std::cos(a), L * std::sin(a)};
  Points X(2 * k + 1, 2);
  Index row = 0;
  for (Index j = 0; j < k; ++j) {  // origin -> B
    const double w = std::pow(static_cast<double>(j) / static_cast<double>(k), 2);
    X.row(row++) << w * B.x, w * B.y;
  }
  X.row(row++) << B.x, B.y;
  for (Index j = 0; j < k; ++j) {  // C -> origin (the base B -> C is one panel)
    const double w = std::pow(1.0 - static_cast<double>(j) / static_cast<double>(k), 2);
    X.row(row++) << w * C.x, w * C.y;
  }
  return X;
}

/// Scalar matrix kron I_2 (node-major vector dofs).
/// The Steklov-Poincare operators' options at the H-matrix tolerance tol with leaves of
/// leaf_size and admissibility eta: preconditioner 1e-4, V solves to tol / 1000, the
/// products on one thread (a shared machine).
/// f(polygon, rows, kernel) for the circle of 600 panels and the square of 150 a side, each
/// with P0 and P1 rows and the single- and double-layer kernels: the cases of the H-matrix
/// tests of the 2D operators.
template <typename F>
void for_each_operator_case(F&& f) {
  for (const Points& X : {circle(600), square(150)}) {
    const Polygon poly(X);
    for (Space s : {Space::P0, Space::P1})
      for (Kernel kernel : {Kernel::SingleLayer, Kernel::DoubleLayer}) f(poly, s, kernel);
  }
}

inline SteklovOptions steklov_options(double tol, Index leaf_size, double eta) {
  SteklovOptions o{};
  o.hmatrix.leaf_size = leaf_size;
  o.hmatrix.eta = eta;
  o.hmatrix.tol = tol;
  o.hmatrix.product_threads = 1;
  o.preconditioner_tol = 1e-4;
  o.solver_tol = 1e-3 * tol;
  o.max_iterations = 1000;
  return o;
}

/// The entries A(d i + c, d j + c) of component c of a matrix with d dofs a node (node-major).
inline Eigen::MatrixXd component(const Eigen::MatrixXd& A, int d, int c) {
  return A(Eigen::seq(c, Eigen::last, d), Eigen::seq(c, Eigen::last, d));
}

inline Matrix kron2(const Matrix& A) {
  Matrix B = Matrix::Zero(2 * A.rows(), 2 * A.cols());
  for (Index r = 0; r < A.rows(); ++r)
    for (Index c = 0; c < A.cols(); ++c) B(2 * r, 2 * c) = B(2 * r + 1, 2 * c + 1) = A(r, c);
  return B;
}

}  // namespace bem::test
