#include "bem/surface_steklov.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace bem {

SurfaceSteklovOperator::SurfaceSteklovOperator(VerticesRef vertices, TrianglesRef triangles,
                                               const SteklovOptions& options)
    : surface_(vertices, triangles), options_(options) {
  if (!(options.solver_tol > 0) || options.max_iterations < 1)
    throw std::invalid_argument("SurfaceSteklovOperator: need solver_tol > 0, max_iterations >= 1");
  const auto t0 = std::chrono::steady_clock::now();
  HMatrixOptions o = options.hmatrix;
  o.min_distance = far_distance(surface_);
  auto tree1 = std::make_shared<const ClusterTree>(surface_cluster_tree(surface_, Space::P1, o.leaf_size));
  // the near pairs integrated once for the three matrices (distributed: those of this
  // rank's rows of V_h, W_h (symmetric) and K_h alone, the matrices then built on the
  // same row bounds)
  const auto t1 = std::chrono::steady_clock::now();
  const std::vector<Index> rows_vw = surface_row_bounds(*tree1, o, true), rows_k = surface_row_bounds(*tree1, o, false);
  const auto near = std::make_shared<const SurfaceNearField>(
      surface_, false, rank_triangles(surface_, o, {{tree1.get(), rows_vw}, {tree1.get(), rows_k}}));
  info_.near_field_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  o.symmetric = true;
  // V and W from one ACA of the single-layer kernel per block
  const auto t2 = std::chrono::steady_clock::now();
  const auto VW = HMatrix::family(
      tree1, tree1, SurfaceEntries(surface_, SurfaceKernel::SingleLayer, Space::P1, Space::P1, near, true), 2, o,
      rows_vw);
  V_ = VW[0];
  W_ = VW[1];
  const auto t3 = std::chrono::steady_clock::now();
  o.symmetric = false;
  K_ = std::make_shared<const HMatrix>(
      tree1, tree1, SurfaceEntries(surface_, SurfaceKernel::DoubleLayer, Space::P1, Space::P1, near), o, rows_k);
  const auto t4 = std::chrono::steady_clock::now();
  info_.single_layer_seconds = std::chrono::duration<double>(t3 - t2).count();
  info_.double_layer_seconds = std::chrono::duration<double>(t4 - t3).count();
  const Index n = surface_.vertices(), m = surface_.size();
  std::vector<Eigen::Triplet<double>> mass;
  double area = 0.0;
  for (Index t = 0; t < m; ++t) {
    const Triangle& T = surface_.triangle(t);
    area += T.area;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) mass.emplace_back(T.v[a], T.v[b], T.area / 12.0 * (a == b ? 2.0 : 1.0));
  }
  M_.resize(n, n);
  M_.setFromTriplets(mass.begin(), mass.end());
  mass_factor_.compute(M_);
  if (mass_factor_.info() != Eigen::Success)
    throw std::runtime_error("SurfaceSteklovOperator: the P1 Gram matrix is not positive definite");
  c_ = M_ * Eigen::VectorXd::Ones(n);
  alpha_ = 1.0 / (2.0 * std::sqrt(area / (4.0 * M_PI)) * area);
  solver_ = std::make_unique<SingleLayerSolver>(V_, [this](const Eigen::MatrixXd& R) { return precondition(R); });
  info_.setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  info_.max_rank = std::max({V_->max_rank(), W_->max_rank(), K_->max_rank()});
  info_.nbytes_v = V_->nbytes();
  info_.nbytes_w = W_->nbytes();
  info_.nbytes_k = K_->nbytes();
  info_.nbytes_preconditioner =
      static_cast<std::size_t>(M_.nonZeros()) * (sizeof(double) + sizeof(int)) +
      static_cast<std::size_t>(mass_factor_.matrixL().nestedExpression().nonZeros()) * (sizeof(double) + sizeof(int));
}

Eigen::MatrixXd SurfaceSteklovOperator::hypersingular(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  return W_->apply(X);
}

Eigen::MatrixXd SurfaceSteklovOperator::hypersingular_block(const std::vector<Index>& indices) const {
  // every entry comes from one block of one rank: the sum is exact, in any order
  return sum_of_held_entries(options_.hmatrix.comm, W_->principal_submatrix<double>(indices));
}

Eigen::MatrixXf SurfaceSteklovOperator::hypersingular_block_single(const std::vector<Index>& indices) const {
  const std::shared_ptr<const Communicator>& comm = options_.hmatrix.comm;
  if (!comm || comm->size == 1) return W_->principal_submatrix<float>(indices);
  return hypersingular_block(indices).cast<float>();
}

Eigen::MatrixXd SurfaceSteklovOperator::precondition(const Eigen::MatrixXd& R) const {
  const Eigen::MatrixXd Y = mass_factor_.solve(R);
  Eigen::MatrixXd Z = hypersingular(Y);
  Z += alpha_ * c_ * (c_.transpose() * Y);
  return mass_factor_.solve(Z);
}

Eigen::MatrixXd SurfaceSteklovOperator::single_layer(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  if (X.rows() != size())
    throw std::invalid_argument("SurfaceSteklovOperator: X has " + std::to_string(X.rows()) + " rows, expected " +
                                std::to_string(size()));
  return V_->apply(X);
}

Eigen::MatrixXd SurfaceSteklovOperator::double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  if (X.rows() != size())
    throw std::invalid_argument("SurfaceSteklovOperator: X has " + std::to_string(X.rows()) + " rows, expected " +
                                std::to_string(size()));
  return K_->apply(X);
}

Eigen::MatrixXd SurfaceSteklovOperator::flux(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol) const {
  if (X.rows() != size())
    throw std::invalid_argument("SurfaceSteklovOperator: X has " + std::to_string(X.rows()) + " rows, expected " +
                                std::to_string(size()));
  const Eigen::MatrixXd A = K_->apply(X) - M_ * X;
  Eigen::MatrixXd Psi;
  last_iterations_ = solver_->solve(A, Psi, std::max(solver_tol, options_.solver_tol), options_.max_iterations);
  return Psi;
}

Eigen::MatrixXd SurfaceSteklovOperator::apply(const Eigen::Ref<const Eigen::MatrixXd>& X, double solver_tol) const {
  if (X.rows() == size() && X.isZero(0.0)) {  // S 0 = 0 without four products (X is the same on every rank)
    last_iterations_ = 0;
    return Eigen::MatrixXd::Zero(X.rows(), X.cols());
  }
  const Eigen::MatrixXd Psi = flux(X, solver_tol);
  Eigen::MatrixXd Y = hypersingular(X);
  Y += K_->apply(Psi, true) - M_ * Psi;  // M symmetric
  return 0.5 * Y;
}

std::size_t SurfaceSteklovOperator::nbytes() const {
  return info_.nbytes_v + info_.nbytes_w + info_.nbytes_k + info_.nbytes_preconditioner;
}

}  // namespace bem
