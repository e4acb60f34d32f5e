#include "bem/lame_steklov.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "bem/boundary_operators.hpp"
#include "bem/calderon_preconditioner.hpp"
#include "bem/lame_polygon_entries.hpp"
#include "bem/linear_algebra.hpp"

namespace bem {

namespace {

constexpr double kDifferencedTolFactor = 0.1;
constexpr double kSinglePrecisionMinTol = 1e-6;  // as the surfaces' (bem_cpp/defaults.py)

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// x^T y as a plain loop (Eigen's AVX-512 reductions draw GCC 12's false
/// -Wmaybe-uninitialized warnings).
template <class A, class B>
double dot(const A& x, const B& y) {
  double s = 0.0;
  for (Index i = 0; i < x.size(); ++i) s += x(i) * y(i);
  return s;
}

/// (D_h X)(2 p + l) = (X(2 (p + 1) + l) - X(2 p + l)) / h_p: P1 vector -> P0 vector.
Eigen::MatrixXd derivative(const Eigen::VectorXd& h, const Eigen::MatrixXd& X) {
  const Index n = h.size();
  Eigen::MatrixXd DX(2 * n, X.cols());
  for (Index p = 0; p < n; ++p) {
    const Index p1 = (p + 1) % n;
    DX.middleRows(2 * p, 2) = (X.middleRows(2 * p1, 2) - X.middleRows(2 * p, 2)) / h(p);
  }
  return DX;
}

/// D_h^T Z: (D_h^T Z)(2 j + l) = Z(2 (j - 1) + l)/h_(j-1) - Z(2 j + l)/h_j.
Eigen::MatrixXd derivative_transposed(const Eigen::VectorXd& h, const Eigen::MatrixXd& Z) {
  const Index n = h.size();
  Eigen::MatrixXd Y(2 * n, Z.cols());
  for (Index j = 0; j < n; ++j) {
    const Index jm = (j + n - 1) % n;
    Y.middleRows(2 * j, 2) = Z.middleRows(2 * jm, 2) / h(jm) - Z.middleRows(2 * j, 2) / h(j);
  }
  return Y;
}

/// (R kron I_n) Z, R = [[0, -1], [1, 0]] on each node's pair (transpose: R^T).
Eigen::MatrixXd rotate(const Eigen::MatrixXd& Z, bool transpose) {
  Eigen::MatrixXd out(Z.rows(), Z.cols());
  const double s = transpose ? -1.0 : 1.0;
  for (Index p = 0; 2 * p < Z.rows(); ++p) {
    out.row(2 * p) = -s * Z.row(2 * p + 1);
    out.row(2 * p + 1) = s * Z.row(2 * p);
  }
  return out;
}

/// Node-major (2 m, k) -> (m, 2 k): component 0's columns, then component 1's.
Eigen::MatrixXd split(const Eigen::MatrixXd& X) {
  const Index k = X.cols(), m = X.rows() / 2;
  Eigen::MatrixXd S(m, 2 * k);
  for (Index j = 0; j < k; ++j)
    for (Index i = 0; i < m; ++i) {
      S(i, j) = X(2 * i, j);
      S(i, k + j) = X(2 * i + 1, j);
    }
  return S;
}

/// The inverse of split.
Eigen::MatrixXd join(const Eigen::MatrixXd& S) {
  const Index k = S.cols() / 2, m = S.rows();
  Eigen::MatrixXd X(2 * m, k);
  for (Index j = 0; j < k; ++j)
    for (Index i = 0; i < m; ++i) {
      X(2 * i, j) = S(i, j);
      X(2 * i + 1, j) = S(i, k + j);
    }
  return X;
}

/// (A kron I_2) X for a scalar H-matrix A (transpose: A^T kron I_2), node-major X.
Eigen::MatrixXd kron_apply(const HMatrix& A, const Eigen::MatrixXd& X, bool transpose) {
  return join(A.apply(split(X), transpose));
}

/// The flux-space deflation basis: the rigid motions e_x, e_y, x -> (-y, x) and the normal
/// field, at the nodes (P1: the normal the mean of the two panels') or panel midpoints (P0).
Eigen::MatrixXd deflation_basis(const Polygon& polygon, Space flux) {
  const Index n = polygon.size();
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(2 * n, 4);
  for (Index i = 0; i < n; ++i) {
    const Panel& p = polygon.panel(i);
    const Vec2 x = flux == Space::P1 ? p.a : p.m;
    const Vec2 nu = flux == Space::P1 ? 0.5 * (polygon.panel((i + n - 1) % n).n + p.n) : p.n;
    Q(2 * i, 0) = 1.0;
    Q(2 * i + 1, 1) = 1.0;
    Q(2 * i, 2) = -x.y;
    Q(2 * i + 1, 2) = x.x;
    Q(2 * i, 3) = nu.x;
    Q(2 * i + 1, 3) = nu.y;
  }
  return Q;
}

/// M_h (flux x P1) kron I_2: P1 the Gram matrix h/6 [[2, 1], [1, 2]], P0 h/2 at both nodes.
Eigen::SparseMatrix<double> vector_mass(const Polygon& polygon, Space flux) {
  const Index n = polygon.size();
  std::vector<Eigen::Triplet<double>> g;
  for (Index i = 0; i < n; ++i) {
    const double h = polygon.panel(i).h;
    const Index i1 = (i + 1) % n;
    for (int c = 0; c < 2; ++c) {
      if (flux == Space::P1) {
        g.emplace_back(2 * i + c, 2 * i + c, h / 3.0);
        g.emplace_back(2 * i1 + c, 2 * i1 + c, h / 3.0);
        g.emplace_back(2 * i + c, 2 * i1 + c, h / 6.0);
        g.emplace_back(2 * i1 + c, 2 * i + c, h / 6.0);
      } else {
        g.emplace_back(2 * i + c, 2 * i + c, h / 2.0);
        g.emplace_back(2 * i + c, 2 * i1 + c, h / 2.0);
      }
    }
  }
  Eigen::SparseMatrix<double> M(2 * n, 2 * n);
  M.setFromTriplets(g.begin(), g.end());
  return M;
}

}  // namespace

LameSteklovParts lame_polygon_steklov_parts(const Polygon& polygon, const Lame& m, Space flux,
                                            const SteklovOptions& options) {
  kelvin_like(m, LameKernel::SingleLayer);  // validates the medium
  LameSteklovParts parts;
  parts.dimension = 2;
  parts.traces = 2 * polygon.size();
  LameSteklovInfo& info = parts.info;
  const HMatrixOptions& o = options.hmatrix;
  // The matrices whose products are differenced by D_h (X0 and Y of flux P1; V_h and V0_L of
  // flux P0 in W_h and K_h) at tol / 10: D_h^T E D_h amplifies an error E of relative size
  // tol in the constant-like part of a block by about 8 (measured, circle n = 800: W_h's
  // product error 2.8e-10 at tol 1e-10 on X0, 5.3e-11 at 1e-11 for 6 % more bytes).
  HMatrixOptions tight = o;
  tight.tol = kDifferencedTolFactor * o.tol;
  // the node trees of the vector matrices with half the leaf size: leaves of leaf_size dofs
  const Index node_leaf = std::max<Index>(1, o.leaf_size / 2);
  auto node1 = std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon, Space::P1, node_leaf));
  auto node0 = std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon, Space::P0, node_leaf));
  auto vec1 = std::make_shared<const ClusterTree>(node1->expanded(2));
  auto vec0 = std::make_shared<const ClusterTree>(node0->expanded(2));
  auto tree1 = std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon, Space::P1, o.leaf_size));
  auto tree0 = std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon, Space::P0, o.leaf_size));
  auto tree_flux = flux == Space::P1 ? tree1 : tree0;
  auto vec_flux = flux == Space::P1 ? vec1 : vec0;
  const Eigen::VectorXd h = polygon.lengths();
  LameEntryTimes tv, tw, ty;

  auto t0 = std::chrono::steady_clock::now();
  const std::shared_ptr<const HMatrix> V =
      lame_hmatrix(polygon, m, LameKernel::SingleLayer, flux, vec_flux, vec_flux, tight, &tv);
  parts.single_layer = V;
  info.single_layer_seconds = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  // K_L with the stop of ACA confirmed on sampled rows and columns (layer_hmatrix)
  const std::shared_ptr<const HMatrix> KL = layer_hmatrix(polygon, Kernel::DoubleLayer, flux, tree_flux, tree1, o);
  if (flux == Space::P1) {
    const std::shared_ptr<const HMatrix> Y =
        lame_hmatrix(polygon, m, LameKernel::DoubleLayer, Space::P1, vec1, vec0, tight, &ty);
    info.double_layer_seconds = seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    const std::shared_ptr<const HMatrix> X0 =
        lame_hmatrix(polygon, m, LameKernel::Hypersingular, Space::P0, vec0, vec0, tight, &tw);
    info.hypersingular_seconds = seconds_since(t0);
    parts.hypersingular = [X0, h](const Eigen::MatrixXd& X) {
      return derivative_transposed(h, X0->apply(derivative(h, X)));
    };
    parts.double_layer = [Y, KL, h](const Eigen::MatrixXd& X, bool transpose) {
      Eigen::MatrixXd out = kron_apply(*KL, X, transpose);
      if (transpose)
        out += derivative_transposed(h, Y->apply(X, true));
      else
        out += Y->apply(derivative(h, X));
      return out;
    };
    info.nbytes_w = X0->nbytes();
    info.nbytes_k = Y->nbytes() + KL->nbytes();
    info.max_rank = std::max({V->max_rank(), X0->max_rank(), Y->max_rank(), KL->max_rank()});
  } else {
    info.double_layer_seconds = seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    const std::shared_ptr<const HMatrix> VL =
        layer_hmatrix(polygon, Kernel::SingleLayer, Space::P0, tree0, tree0, tight);
    info.hypersingular_seconds = seconds_since(t0);
    // X0 = a V + b V0_L kron I, Y = (2 mu V - V0_L kron I) R
    const double a = 4.0 * m.mu * m.mu, b = -2.0 * m.mu * (1.0 - 2.0 * m.nu) / (1.0 - m.nu), mu = m.mu;
    parts.hypersingular = [V, VL, h, a, b](const Eigen::MatrixXd& X) {
      const Eigen::MatrixXd DX = derivative(h, X);
      return derivative_transposed(h, a * V->apply(DX) + b * kron_apply(*VL, DX, false));
    };
    parts.double_layer = [V, VL, KL, h, mu](const Eigen::MatrixXd& X, bool transpose) {
      Eigen::MatrixXd out = kron_apply(*KL, X, transpose);
      if (transpose) {
        out += derivative_transposed(h, rotate(2.0 * mu * V->apply(X) - kron_apply(*VL, X, false), true));
      } else {
        const Eigen::MatrixXd RDX = rotate(derivative(h, X), false);
        out += 2.0 * mu * V->apply(RDX) - kron_apply(*VL, RDX, false);
      }
      return out;
    };
    info.nbytes_v0 = VL->nbytes();
    info.nbytes_k = KL->nbytes();
    info.max_rank = std::max({V->max_rank(), VL->max_rank(), KL->max_rank()});
  }
  info.nbytes_v = V->nbytes();

  // the preconditioner: s (C_L - 1 1^T) kron I_2, C_L the scalar Calderon preconditioner
  t0 = std::chrono::steady_clock::now();
  HMatrixOptions loose = o;
  loose.tol = options.preconditioner_tol;
  // a preconditioner needs a few digits: its matrix in single precision (half the bytes and
  // about half the time of its products) once its tolerance is far above float's round-off
  loose.single_precision = loose.tol >= kSinglePrecisionMinTol;
  std::shared_ptr<const HMatrix> V0_loose;
  if (flux == Space::P1) V0_loose = layer_hmatrix(polygon, Kernel::SingleLayer, Space::P0, tree0, tree0, loose);
  const auto calderon = std::make_shared<const CalderonPreconditioner>(polygon, flux, V0_loose, loose);
  const double s = 8.0 * m.mu * (1.0 - m.nu) / (3.0 - 4.0 * m.nu);
  parts.preconditioner = [calderon, s](const Eigen::MatrixXd& R) {
    const Eigen::MatrixXd S = split(R);
    Eigen::MatrixXd Z = calderon->apply(S);
    for (Index j = 0; j < S.cols(); ++j) Z.col(j).array() -= dot(S.col(j), Eigen::VectorXd::Ones(S.rows()));
    return join(s * Z);
  };
  parts.deflation = deflation_basis(polygon, flux);
  parts.mass = vector_mass(polygon, flux);
  info.preconditioner_seconds = seconds_since(t0);
  info.nbytes_preconditioner = calderon->nbytes() + (V0_loose ? V0_loose->nbytes() : 0);

  info.near_field_seconds = tv.dense + tw.dense + ty.dense;
  info.far_field_cpu_seconds = tv.low_rank + tw.low_rank + ty.low_rank;
  return parts;
}

LameSteklovOperator::LameSteklovOperator(const Eigen::Ref<const Points>& nodes, const Lame& m, Space flux,
                                         const SteklovOptions& options)
    : LameSteklovOperator(
          [&] {
            if (!(options.solver_tol > 0) || !(options.preconditioner_tol > 0) || options.max_iterations < 1)
              throw std::invalid_argument(
                  "LameSteklovOperator: need solver_tol > 0, preconditioner_tol > 0, max_iterations >= 1");
            const auto t0 = std::chrono::steady_clock::now();
            LameSteklovParts parts = lame_polygon_steklov_parts(Polygon(nodes), m, flux, options);
            parts.info.setup_seconds = seconds_since(t0);
            return parts;
          }(),
          options) {}

LameSteklovOperator::LameSteklovOperator(LameSteklovParts parts, const SteklovOptions& options)
    : parts_(std::move(parts)), options_(options) {
  if (!(options.solver_tol > 0) || options.max_iterations < 1)
    throw std::invalid_argument("LameSteklovOperator: need solver_tol > 0, max_iterations >= 1");
  const Index N = parts_.single_layer ? parts_.single_layer->rows() : 0;
  if (N < 1 || parts_.traces < 1 || parts_.mass.rows() != N || parts_.mass.cols() != parts_.traces ||
      parts_.deflation.rows() != N || !parts_.hypersingular || !parts_.double_layer || !parts_.preconditioner)
    throw std::invalid_argument("LameSteklovOperator: the parts do not fit together");
  const auto t0 = std::chrono::steady_clock::now();
  // (Q^T V Q)^{-1}, one product (collective)
  const Eigen::MatrixXd& Q = parts_.deflation;
  const Eigen::MatrixXd VQ = parts_.single_layer->apply(Q);
  const Index r = Q.cols();
  Matrix QVQ(r, r);  // symmetrised
  for (Index a = 0; a < r; ++a)
    for (Index b = 0; b < r; ++b) QVQ(a, b) = 0.5 * (dot(Q.col(a), VQ.col(b)) + dot(Q.col(b), VQ.col(a)));
  if (cholesky_in_place(QVQ) != 0)
    throw std::invalid_argument(
        "LameSteklovOperator: V_h is not positive definite on the rigid motions (Gamma is beyond the critical "
        "scale of the elastic single layer, lame_polygon.hpp single_layer_critical_scale); rescale the geometry");
  deflation_inverse_.resize(r, r);
  for (Index a = 0; a < r; ++a) {
    Vector e = Vector::Unit(r, a);
    cholesky_solve_in_place(QVQ, e);
    deflation_inverse_.col(a) = e;
  }
  solver_ = std::make_unique<SingleLayerSolver>(parts_.single_layer,
                                                [this](const Eigen::MatrixXd& R) { return precondition(R); });
  LameSteklovInfo& info = parts_.info;
  const double seconds = seconds_since(t0);
  info.preconditioner_seconds += seconds;
  info.setup_seconds += seconds;
  info.nbytes_preconditioner += static_cast<std::size_t>(parts_.mass.nonZeros()) * (sizeof(double) + sizeof(int)) +
                                static_cast<std::size_t>(Q.size() + deflation_inverse_.size()) * sizeof(double);
}

void LameSteklovOperator::check_rows(Index rows, Index expected) const {
  if (rows != expected)
    throw std::invalid_argument("LameSteklovOperator: X has " + std::to_string(rows) + " rows, expected " +
                                std::to_string(expected));
}

Eigen::MatrixXd LameSteklovOperator::hypersingular(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  check_rows(X.rows(), size());
  return parts_.hypersingular(X);
}

Eigen::MatrixXd LameSteklovOperator::hypersingular_block(const std::vector<Index>& nodes) const {
  if (!holds_hypersingular())
    throw std::logic_error("LameSteklovOperator: W_h is not held on the nodes (a polygon's operator)");
  return parts_.hypersingular_block(nodes);
}

Eigen::MatrixXd LameSteklovOperator::double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) const {
  check_rows(X.rows(), transpose ? parts_.single_layer->rows() : size());
  return parts_.double_layer(X, transpose);
}

Eigen::MatrixXd LameSteklovOperator::precondition(const Eigen::MatrixXd& R) const {
  const Eigen::MatrixXd& Q = parts_.deflation;
  Eigen::MatrixXd Z = parts_.preconditioner(R);
  // + Q (Q^T V Q)^{-1} Q^T R, column by column (Q has a few columns)
  const Index r = Q.cols();
  Eigen::VectorXd c(r), a(r);
  for (Index j = 0; j < R.cols(); ++j) {
    for (Index i = 0; i < r; ++i) c(i) = dot(Q.col(i), R.col(j));
    a.noalias() = deflation_inverse_ * c;
    for (Index i = 0; i < r; ++i) Z.col(j) += a(i) * Q.col(i);
  }
  return Z;
}

Eigen::MatrixXd LameSteklovOperator::flux(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol) const {
  check_rows(X.rows(), size());
  const Eigen::MatrixXd A = parts_.double_layer(X, false) - parts_.mass * X;
  Eigen::MatrixXd Psi;
  try {
    last_iterations_ = solver_->solve(A, Psi, std::max(solver_tol, options_.solver_tol), options_.max_iterations);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument(
        "LameSteklovOperator: V_h is not positive definite (CG found p^T V p <= 0): Gamma is beyond the critical "
        "scale of the elastic single layer (lame_polygon.hpp single_layer_critical_scale); rescale the geometry");
  }
  return Psi;
}

Eigen::MatrixXd LameSteklovOperator::apply(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol) const {
  check_rows(X.rows(), size());
  if (X.isZero(0.0)) {  // S 0 = 0 without the products (X is the same on every rank)
    last_iterations_ = 0;
    return Eigen::MatrixXd::Zero(X.rows(), X.cols());
  }
  const Eigen::MatrixXd Psi = flux(X, solver_tol);
  Eigen::MatrixXd Y = parts_.hypersingular(X);
  Y += parts_.double_layer(Psi, true) - parts_.mass.transpose() * Psi;
  return 0.5 * Y;
}

std::size_t LameSteklovOperator::nbytes() const {
  const LameSteklovInfo& i = parts_.info;
  return i.nbytes_v + i.nbytes_v0 + i.nbytes_k + i.nbytes_w + i.nbytes_preconditioner;
}

}  // namespace bem
