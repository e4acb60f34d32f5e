#include "bem/steklov_operator.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "bem/boundary_operators.hpp"

namespace bem {

SteklovPoincareOperator::SteklovPoincareOperator(const Eigen::Ref<const Points>& nodes, Space flux,
                                                 const SteklovOptions& options)
    : polygon_(nodes), flux_(flux), options_(options) {
  if (!(options.solver_tol > 0) || !(options.preconditioner_tol > 0) || options.max_iterations < 1)
    throw std::invalid_argument("SteklovPoincareOperator: need solver_tol > 0, max_iterations >= 1");
  const auto t0 = std::chrono::steady_clock::now();
  const HMatrixOptions& o = options.hmatrix;
  auto tree0 = std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon_, Space::P0, o.leaf_size));
  auto tree1 = std::make_shared<const ClusterTree>(ClusterTree::for_space(polygon_, Space::P1, o.leaf_size));
  auto tree_flux = flux == Space::P0 ? tree0 : tree1;
  V0_ = layer_hmatrix(polygon_, Kernel::SingleLayer, Space::P0, tree0, tree0, o);
  V_ = flux == Space::P0 ? V0_ : layer_hmatrix(polygon_, Kernel::SingleLayer, Space::P1, tree1, tree1, o);
  K_ = layer_hmatrix(polygon_, Kernel::DoubleLayer, flux, tree_flux, tree1, o);
  HMatrixOptions loose = o;
  loose.tol = options.preconditioner_tol;
  preconditioner_ = std::make_unique<CalderonPreconditioner>(polygon_, flux, V0_, loose);
  const CalderonPreconditioner* c = preconditioner_.get();
  solver_ = std::make_unique<SingleLayerSolver>(V_, [c](const Eigen::MatrixXd& R) { return c->apply(R); });
  info_.setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  info_.max_rank = std::max({V_->max_rank(), V0_->max_rank(), K_->max_rank()});
  info_.nbytes_v = V_->nbytes();
  info_.nbytes_v0 = flux == Space::P0 ? 0 : V0_->nbytes();
  info_.nbytes_k = K_->nbytes();
  info_.nbytes_preconditioner = preconditioner_->nbytes();
}

Eigen::MatrixXd SteklovPoincareOperator::double_layer_minus_mass(const Eigen::Ref<const Eigen::MatrixXd>& X,
                                                                 bool transpose) const {
  // (K - M) X or (K - M)^T X; M (rows: flux space, columns: P1) is banded.
  Eigen::MatrixXd Y = K_->apply(X, transpose);
  const Index n = size();
  for (Index i = 0; i < n; ++i) {
    const double h = polygon_.panel(i).h;
    const Index i1 = (i + 1) % n;
    if (flux_ == Space::P0) {  // M[i, i] = M[i, i1] = h_i/2
      if (!transpose) {
        Y.row(i) -= 0.5 * h * (X.row(i) + X.row(i1));
      } else {
        Y.row(i) -= 0.5 * h * X.row(i);
        Y.row(i1) -= 0.5 * h * X.row(i);
      }
    } else {  // symmetric: h/6 [[2, 1], [1, 2]] on nodes i, i1
      Y.row(i) -= h / 6.0 * (2.0 * X.row(i) + X.row(i1));
      Y.row(i1) -= h / 6.0 * (X.row(i) + 2.0 * X.row(i1));
    }
  }
  return Y;
}

Eigen::MatrixXd SteklovPoincareOperator::flux(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol) const {
  if (X.rows() != size()) throw std::invalid_argument("SteklovPoincareOperator: X must have n rows");
  const Eigen::MatrixXd A = double_layer_minus_mass(X, false);
  Eigen::MatrixXd Psi;
  last_iterations_ = solver_->solve(A, Psi, std::max(solver_tol, options_.solver_tol), options_.max_iterations);
  return Psi;
}

Eigen::MatrixXd SteklovPoincareOperator::apply(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol) const {
  if (X.rows() != size())
    throw std::invalid_argument("SteklovPoincareOperator: X has " + std::to_string(X.rows()) + " rows, expected " +
                                std::to_string(size()));
  const Index n = size();
  // W X = D^T V0 D X, (D X)_i = (X_{i+1} - X_i)/h_i on panel i.
  Eigen::MatrixXd DX(n, X.cols());
  for (Index i = 0; i < n; ++i) DX.row(i) = (X.row((i + 1) % n) - X.row(i)) / polygon_.panel(i).h;
  const Eigen::MatrixXd Z = V0_->apply(DX);
  Eigen::MatrixXd Y(n, X.cols());
  for (Index j = 0; j < n; ++j) {
    const Index jm = (j + n - 1) % n;
    Y.row(j) = Z.row(jm) / polygon_.panel(jm).h - Z.row(j) / polygon_.panel(j).h;
  }
  Y += double_layer_minus_mass(flux(X, solver_tol), true);
  return 0.5 * Y;
}

std::size_t SteklovPoincareOperator::nbytes() const {
  return info_.nbytes_v + info_.nbytes_v0 + info_.nbytes_k + info_.nbytes_preconditioner;
}

}  // namespace bem
