#include "bem/single_layer_solver.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace bem {

SingleLayerSolver::SingleLayerSolver(std::shared_ptr<const HMatrix> V, Preconditioner preconditioner)
    : V_(std::move(V)), preconditioner_(std::move(preconditioner)) {
  if (!V_ || V_->rows() != V_->cols()) throw std::invalid_argument("SingleLayerSolver: V must be square");
}

int SingleLayerSolver::solve(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::MatrixXd& X, double tol,
                             int max_iterations) const {
  const Index n = V_->rows(), nrhs = B.cols();
  if (B.rows() != n) throw std::invalid_argument("SingleLayerSolver::solve: B has the wrong number of rows");
  X.setZero(n, nrhs);
  Eigen::MatrixXd R = B;
  const Eigen::VectorXd target = tol * B.colwise().norm().transpose();
  std::vector<char> active(static_cast<std::size_t>(nrhs));
  Index n_active = 0;
  for (Index j = 0; j < nrhs; ++j) {
    active[static_cast<std::size_t>(j)] = B.col(j).norm() > 0;
    n_active += active[static_cast<std::size_t>(j)];
  }
  Eigen::MatrixXd Z = preconditioner_(R), P = Z;
  Eigen::VectorXd rz = R.cwiseProduct(Z).colwise().sum().transpose();
  int it = 0;
  while (n_active > 0) {
    if (it >= max_iterations)
      throw std::runtime_error("SingleLayerSolver: CG did not converge in " + std::to_string(max_iterations) +
                               " iterations");
    ++it;
    const Eigen::MatrixXd Q = V_->apply(P);
    for (Index j = 0; j < nrhs; ++j) {
      if (!active[static_cast<std::size_t>(j)]) continue;
      const double pq = P.col(j).dot(Q.col(j));
      if (!(pq > 0))
        throw std::invalid_argument(
            "V_h is not positive definite (CG found p^T V p <= 0): the logarithmic capacity of Gamma "
            "is >= 1, where V is not elliptic (diam(Omega) < 1 is sufficient for ellipticity); rescale "
            "the geometry so that its diameter is below 1");
      const double alpha = rz(j) / pq;
      X.col(j) += alpha * P.col(j);
      R.col(j) -= alpha * Q.col(j);
      if (R.col(j).norm() <= target(j)) {
        active[static_cast<std::size_t>(j)] = 0;
        --n_active;
        P.col(j).setZero();
        R.col(j).setZero();
      }
    }
    if (n_active == 0) break;
    Z = preconditioner_(R);
    for (Index j = 0; j < nrhs; ++j) {
      if (!active[static_cast<std::size_t>(j)]) continue;
      const double rz_new = R.col(j).dot(Z.col(j));
      P.col(j) = Z.col(j) + (rz_new / rz(j)) * P.col(j);
      rz(j) = rz_new;
    }
  }
  return it;
}

}  // namespace bem
