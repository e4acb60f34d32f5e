#include "bem/lame_surface_steklov.hpp"

#include <algorithm>
#include <chrono>

#include "bem/lame_surface_entries.hpp"
#include "bem/surface_entries.hpp"

namespace bem {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

Eigen::MatrixXd kron3_apply(const HMatrix& A, const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) {
  const Index k = X.cols(), n = X.rows() / 3;
  Eigen::MatrixXd S(n, 3 * k);  // column c k + j: component c of column j
  for (Index j = 0; j < k; ++j)
    for (int c = 0; c < 3; ++c)
      for (Index i = 0; i < n; ++i) S(i, c * k + j) = X(3 * i + c, j);
  const Eigen::MatrixXd T = A.apply(S, transpose);
  Eigen::MatrixXd Y(3 * T.rows(), k);
  for (Index j = 0; j < k; ++j)
    for (int c = 0; c < 3; ++c)
      for (Index i = 0; i < T.rows(); ++i) Y(3 * i + c, j) = T(i, c * k + j);
  return Y;
}

LameSurfaceOperators::LameSurfaceOperators(const Surface& s, const Lame& m, const HMatrixOptions& options) : mu_(m.mu) {
  HMatrixOptions o = options;
  o.min_distance = far_distance(s);
  auto t0 = std::chrono::steady_clock::now();
  const auto near = std::make_shared<const LameSurfaceNearField>(s, m);
  const auto laplace_near = std::make_shared<const SurfaceNearField>(s, false);
  info_.near_field_seconds = seconds_since(t0);
  info_.nbytes_near = near->nbytes();
  auto tree1 = std::make_shared<const ClusterTree>(surface_cluster_tree(s, Space::P1, o.leaf_size));
  auto tree3 = std::make_shared<const ClusterTree>(lame_surface_cluster_tree(s, o.leaf_size));
  const auto cache = std::make_shared<LameSurfaceBlockCache>();

  t0 = std::chrono::steady_clock::now();
  o.symmetric = true;
  const LameSurfaceEntries vz(s, m, LameSurfaceEntries::Kind::SingleLayer, near, cache);
  const auto VZ = HMatrix::family(tree3, tree3, vz, 2, o);
  V_ = VZ[0];
  Z_ = VZ[1];
  info_.single_layer_seconds = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  o.symmetric = false;
  const LameSurfaceEntries y(s, m, LameSurfaceEntries::Kind::DoubleLayer, near, cache);
  Y_ = std::make_shared<const HMatrix>(tree3, tree3, y, o);
  cache->clear();
  KL_ = std::make_shared<const HMatrix>(
      tree1, tree1, SurfaceEntries(s, SurfaceKernel::DoubleLayer, Space::P1, Space::P1, laplace_near), o);
  info_.double_layer_seconds = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  o.symmetric = true;
  WL_ = std::make_shared<const HMatrix>(
      tree1, tree1, SurfaceEntries(s, SurfaceKernel::Hypersingular, Space::P1, Space::P1, laplace_near), o);
  info_.hypersingular_seconds = seconds_since(t0);

  const LameSurfaceTimes tv = vz.times(), ty = y.times();
  info_.dense_cpu_seconds = tv.dense + ty.dense;
  info_.low_rank_cpu_seconds = tv.low_rank + ty.low_rank;
  info_.nbytes_v = V_->nbytes();
  info_.nbytes_k = Y_->nbytes() + KL_->nbytes();
  info_.nbytes_w = Z_->nbytes() + WL_->nbytes();
  info_.max_rank = std::max({V_->max_rank(), Z_->max_rank(), Y_->max_rank(), KL_->max_rank(), WL_->max_rank()});
}

Eigen::MatrixXd LameSurfaceOperators::hypersingular(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  Eigen::MatrixXd out = Z_->apply(X);
  out += 2.0 * mu_ * kron3_apply(*WL_, X);
  return out;
}

Eigen::MatrixXd LameSurfaceOperators::double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) const {
  Eigen::MatrixXd out = Y_->apply(X, transpose);
  out += kron3_apply(*KL_, X, transpose);
  return out;
}

}  // namespace bem
