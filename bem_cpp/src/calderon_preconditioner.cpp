#include "bem/calderon_preconditioner.hpp"

#include <Eigen/Sparse>
#include <stdexcept>
#include <vector>

#include "bem/operator_entries.hpp"

namespace bem {

namespace {

/// W Y = D^T V0 D Y on a closed mesh with panel lengths h, (D Y)_p = (Y_{p+1} - Y_p)/h_p.
Eigen::MatrixXd maue(const HMatrix& V0, const Eigen::VectorXd& h, const Eigen::MatrixXd& Y) {
  const Index n = h.size();
  Eigen::MatrixXd DY(n, Y.cols());
  for (Index p = 0; p < n; ++p) DY.row(p) = (Y.row((p + 1) % n) - Y.row(p)) / h(p);
  const Eigen::MatrixXd Z = V0.apply(DY);
  Eigen::MatrixXd W(n, Y.cols());
  for (Index j = 0; j < n; ++j) {
    const Index jm = (j + n - 1) % n;
    W.row(j) = Z.row(jm) / h(jm) - Z.row(j) / h(j);
  }
  return W;
}

}  // namespace

CalderonPreconditioner::CalderonPreconditioner(const Polygon& polygon, Space flux, std::shared_ptr<const HMatrix> V0,
                                               const HMatrixOptions& refined)
    : flux_(flux), n_(polygon.size()) {
  const Index n = n_;
  std::vector<Eigen::Triplet<double>> g;
  if (flux == Space::P1) {
    if (!V0 || V0->rows() != n) throw std::invalid_argument("CalderonPreconditioner: P0 H-matrix V0 needed");
    V0_ = std::move(V0);
    h_ = polygon.lengths();
    for (Index i = 0; i < n; ++i) {  // P1 Gram matrix h/6 [[2, 1], [1, 2]]
      const double h = h_(i);
      const Index i1 = (i + 1) % n;
      g.emplace_back(i, i, h / 3.0);
      g.emplace_back(i1, i1, h / 3.0);
      g.emplace_back(i, i1, h / 6.0);
      g.emplace_back(i1, i, h / 6.0);
    }
  } else {
    Points X(2 * n, 2);
    for (Index i = 0; i < n; ++i) {
      const Panel& p = polygon.panel(i);
      X(2 * i, 0) = p.a.x;
      X(2 * i, 1) = p.a.y;
      X(2 * i + 1, 0) = p.m.x;
      X(2 * i + 1, 1) = p.m.y;
    }
    refined_ = std::make_unique<Polygon>(X);
    h_ = refined_->lengths();
    auto tree = std::make_shared<const ClusterTree>(ClusterTree::for_space(*refined_, Space::P0, refined.leaf_size));
    const OperatorEntries e(*refined_, Kernel::SingleLayer, Space::P0, Space::P0);
    HMatrixOptions symmetric = refined;
    symmetric.symmetric = true;
    V0_ = std::make_shared<const HMatrix>(tree, tree, e, symmetric);
    // G[j, i] = int_{panel j} dual_i: 3 h_i/4 (j = i), h_j/8 (j = i -+ 1).
    for (Index i = 0; i < n; ++i) {
      const double h = polygon.panel(i).h;
      g.emplace_back(i, i, 0.75 * h);
      g.emplace_back(i, (i + 1) % n, 0.125 * h);
      g.emplace_back(i, (i + n - 1) % n, 0.125 * h);
    }
  }
  Eigen::SparseMatrix<double> G(n, n);
  G.setFromTriplets(g.begin(), g.end());
  // G = diag(scale) T, T symmetric cyclic tridiagonal and strictly diagonally dominant:
  // P1 the Gram matrix ((h_{i-1} + h_i)/3 against h/6 beside it), P0 (3/4 against 1/8).
  Eigen::VectorXd lower(n), diag(n), upper(n);
  scale_ = flux == Space::P1 ? Eigen::VectorXd::Ones(n) : polygon.lengths();
  for (Index i = 0; i < n; ++i) {
    lower(i) = G.coeff(i, (i + n - 1) % n) / scale_(i);
    diag(i) = G.coeff(i, i) / scale_(i);
    upper(i) = G.coeff(i, (i + 1) % n) / scale_(i);
  }
  T_ = CyclicTridiagonal(lower, diag, upper);
  c_ = Eigen::RowVectorXd::Ones(n) * G;  // c_i = int t_i = column sums of G
}

Eigen::MatrixXd CalderonPreconditioner::hypersingular(const Eigen::MatrixXd& Y) const {
  Eigen::MatrixXd W;
  if (flux_ == Space::P1) {
    W = maue(*V0_, h_, Y);
  } else {
    // dual_i = phi_{m_i} + (phi_{node i} + phi_{node i+1})/2 in the refined hats.
    const Index n = n_;
    Eigen::MatrixXd Yr(2 * n, Y.cols());
    for (Index i = 0; i < n; ++i) {
      Yr.row(2 * i) = 0.5 * (Y.row((i + n - 1) % n) + Y.row(i));
      Yr.row(2 * i + 1) = Y.row(i);
    }
    const Eigen::MatrixXd Wr = maue(*V0_, h_, Yr);
    W.resize(n, Y.cols());
    for (Index i = 0; i < n; ++i) W.row(i) = Wr.row(2 * i + 1) + 0.5 * (Wr.row(2 * i) + Wr.row((2 * i + 2) % (2 * n)));
  }
  W += c_ * (c_.transpose() * Y);
  return W;
}

Eigen::MatrixXd CalderonPreconditioner::apply(const Eigen::Ref<const Eigen::MatrixXd>& R) const {
  const Eigen::MatrixXd Y = T_.solve(scale_.asDiagonal().inverse() * R);  // G^{-1} R
  const Eigen::MatrixXd Z = hypersingular(Y);
  return scale_.asDiagonal().inverse() * T_.solve(Z);  // G^{-T} Z
}

std::size_t CalderonPreconditioner::nbytes() const {
  const std::size_t own = T_.nbytes() + static_cast<std::size_t>(scale_.size() + c_.size()) * sizeof(double);
  return own + (flux_ == Space::P0 ? V0_->nbytes() : 0);
}

}  // namespace bem
