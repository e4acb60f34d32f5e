#include "bem/lame_surface_steklov.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <vector>

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

LameSurfaceOperators::LameSurfaceOperators(const Surface& s, const Lame& m, const HMatrixOptions& options)
    : mu_(m.mu), comm_(options.comm) {
  HMatrixOptions o = options;
  o.min_distance = far_distance(s);
  auto tree1 = std::make_shared<const ClusterTree>(surface_cluster_tree(s, Space::P1, o.leaf_size));
  auto tree3 = std::make_shared<const ClusterTree>(lame_surface_cluster_tree(s, o.leaf_size));
  // distributed: the near pairs of this rank's rows alone (V_h, Z symmetric, Y on the
  // vector tree; K_L, and W_L symmetric, on the scalar one), the matrices then built on
  // the same row bounds
  const std::vector<Index> rows_vz = surface_row_bounds(*tree3, o, true), rows_y = surface_row_bounds(*tree3, o, false);
  const std::vector<Index> rows_k = surface_row_bounds(*tree1, o, false), rows_w = surface_row_bounds(*tree1, o, true);
  const std::vector<char> mine = rank_triangles(
      s, o, {{tree3.get(), rows_vz}, {tree3.get(), rows_y}, {tree1.get(), rows_k}, {tree1.get(), rows_w}});
  auto t0 = std::chrono::steady_clock::now();
  const auto near = std::make_shared<const LameSurfaceNearField>(s, m, mine);
  const auto laplace_near = std::make_shared<const SurfaceNearField>(s, false, mine);
  info_.near_field_seconds = seconds_since(t0);
  info_.nbytes_near = near->nbytes();
  const auto cache = std::make_shared<LameSurfaceBlockCache>();

  t0 = std::chrono::steady_clock::now();
  o.symmetric = true;
  const LameSurfaceEntries vz(s, m, LameSurfaceEntries::Kind::SingleLayer, near, cache);
  const auto VZ = HMatrix::family(tree3, tree3, vz, 2, o, rows_vz);
  V_ = VZ[0];
  Z_ = VZ[1];
  info_.single_layer_seconds = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  o.symmetric = false;
  const LameSurfaceEntries y(s, m, LameSurfaceEntries::Kind::DoubleLayer, near, cache);
  Y_ = std::make_shared<const HMatrix>(tree3, tree3, y, o, rows_y);
  cache->clear();
  KL_ = std::make_shared<const HMatrix>(
      tree1, tree1, SurfaceEntries(s, SurfaceKernel::DoubleLayer, Space::P1, Space::P1, laplace_near), o, rows_k);
  info_.double_layer_seconds = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  o.symmetric = true;
  WL_ = std::make_shared<const HMatrix>(
      tree1, tree1, SurfaceEntries(s, SurfaceKernel::Hypersingular, Space::P1, Space::P1, laplace_near), o, rows_w);
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

Eigen::MatrixXd LameSurfaceOperators::hypersingular_block(const std::vector<Index>& nodes) const {
  const Index k = static_cast<Index>(nodes.size()), n = WL_->rows();
  for (const Index i : nodes)
    if (i < 0 || i >= n)
      throw std::invalid_argument("LameSurfaceOperators::hypersingular_block: a node is out of range");
  std::vector<Index> dofs(static_cast<std::size_t>(3 * k));
  for (Index a = 0; a < k; ++a)
    for (int c = 0; c < 3; ++c) dofs[static_cast<std::size_t>(3 * a + c)] = 3 * nodes[static_cast<std::size_t>(a)] + c;
  // every entry comes from one block of one rank: the sums are exact, in any order
  Eigen::MatrixXd block = sum_of_held_entries(comm_, Z_->principal_submatrix<double>(dofs));
  const Eigen::MatrixXd laplace = sum_of_held_entries(comm_, WL_->principal_submatrix<double>(nodes));
  const double s = 2.0 * mu_;
  for (Index b = 0; b < k; ++b)
    for (Index a = 0; a < k; ++a)
      for (int c = 0; c < 3; ++c) block(3 * a + c, 3 * b + c) += s * laplace(a, b);
  return block;
}

Eigen::MatrixXd LameSurfaceOperators::double_layer(const Eigen::Ref<const Eigen::MatrixXd>& X, bool transpose) const {
  Eigen::MatrixXd out = Y_->apply(X, transpose);
  out += kron3_apply(*KL_, X, transpose);
  return out;
}

namespace {

/// (n, 3 k) -> (3 n, k) and back, node-major (the columns c k + j: component c of column j).
Eigen::MatrixXd components(const Eigen::MatrixXd& X) {
  const Index k = X.cols(), n = X.rows() / 3;
  Eigen::MatrixXd S(n, 3 * k);
  for (Index j = 0; j < k; ++j)
    for (int c = 0; c < 3; ++c)
      for (Index i = 0; i < n; ++i) S(i, c * k + j) = X(3 * i + c, j);
  return S;
}

Eigen::MatrixXd nodes(const Eigen::MatrixXd& S) {
  const Index k = S.cols() / 3, n = S.rows();
  Eigen::MatrixXd X(3 * n, k);
  for (Index j = 0; j < k; ++j)
    for (int c = 0; c < 3; ++c)
      for (Index i = 0; i < n; ++i) X(3 * i + c, j) = S(i, c * k + j);
  return X;
}

/// The scalar preconditioner's parts: the P1 Gram matrix's factor and W_L.
struct Calderon {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> mass;
  std::shared_ptr<const LameSurfaceOperators> operators;
  double scale = 1.0;
};

}  // namespace

LameSteklovParts lame_surface_steklov_parts(const Surface& s, const Lame& m, Space flux,
                                            const SteklovOptions& options) {
  if (flux != Space::P1)
    throw std::invalid_argument("LameSteklovOperator: the 3D operator has flux P1 only (P0 is not implemented)");
  LameSteklovParts parts;
  parts.dimension = 3;
  const Index n = s.vertices();
  parts.traces = 3 * n;
  auto ops = std::make_shared<const LameSurfaceOperators>(s, m, options.hmatrix);
  parts.single_layer = ops->single_layer();
  parts.hypersingular = [ops](const Eigen::MatrixXd& X) { return ops->hypersingular(X); };
  parts.double_layer = [ops](const Eigen::MatrixXd& X, bool transpose) { return ops->double_layer(X, transpose); };
  parts.hypersingular_block = [ops](const std::vector<Index>& nodes) { return ops->hypersingular_block(nodes); };

  const auto t0 = std::chrono::steady_clock::now();
  // M_h = Gram kron I_3, and the scalar Gram matrix's factor for C0
  std::vector<Eigen::Triplet<double>> gram, vector_gram;
  for (const Triangle& T : s.triangles())
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const double value = T.area / 12.0 * (a == b ? 2.0 : 1.0);
        gram.emplace_back(T.v[a], T.v[b], value);
        for (int c = 0; c < 3; ++c) vector_gram.emplace_back(3 * T.v[a] + c, 3 * T.v[b] + c, value);
      }
  Eigen::SparseMatrix<double> G(n, n);
  G.setFromTriplets(gram.begin(), gram.end());
  parts.mass.resize(3 * n, 3 * n);
  parts.mass.setFromTriplets(vector_gram.begin(), vector_gram.end());
  auto calderon = std::make_shared<Calderon>();
  calderon->mass.compute(G);
  if (calderon->mass.info() != Eigen::Success)
    throw std::runtime_error("LameSteklovOperator: the P1 Gram matrix is not positive definite");
  calderon->operators = ops;
  calderon->scale = 6.0 * m.mu * (1.0 - m.nu) / (3.5 - 4.0 * m.nu);
  parts.preconditioner = [calderon](const Eigen::MatrixXd& R) {
    const Eigen::MatrixXd Y = calderon->mass.solve(components(R));
    const Eigen::MatrixXd Z = calderon->operators->laplace_hypersingular().apply(Y);
    return nodes(calderon->scale * calderon->mass.solve(Z));
  };
  // Q: the translations, the rotations about the vertices' centroid, the normal field (the
  // area-weighted mean of the triangles' normals at a vertex)
  Vec3 centre{0.0, 0.0, 0.0};
  for (Index i = 0; i < n; ++i) centre = centre + s.vertex(i);
  centre = (1.0 / static_cast<double>(n)) * centre;
  std::vector<Vec3> normal(static_cast<std::size_t>(n), Vec3{0.0, 0.0, 0.0});
  for (const Triangle& T : s.triangles())
    for (Index v : T.v) normal[static_cast<std::size_t>(v)] = normal[static_cast<std::size_t>(v)] + T.area * T.n;
  Eigen::MatrixXd& Q = parts.deflation;
  Q = Eigen::MatrixXd::Zero(3 * n, 7);
  for (Index i = 0; i < n; ++i) {
    const Vec3 x = s.vertex(i) - centre;
    const Vec3 v = normal[static_cast<std::size_t>(i)];
    const double length = norm(v);
    for (int c = 0; c < 3; ++c) Q(3 * i + c, c) = 1.0;
    // e_c x x
    Q(3 * i + 1, 3) = -x.z;
    Q(3 * i + 2, 3) = x.y;
    Q(3 * i, 4) = x.z;
    Q(3 * i + 2, 4) = -x.x;
    Q(3 * i, 5) = -x.y;
    Q(3 * i + 1, 5) = x.x;
    Q(3 * i, 6) = v.x / length;
    Q(3 * i + 1, 6) = v.y / length;
    Q(3 * i + 2, 6) = v.z / length;
  }

  LameSteklovInfo& info = parts.info;
  const LameSurfaceInfo& i = ops->info();
  info.preconditioner_seconds = seconds_since(t0);
  info.near_field_seconds = i.near_field_seconds;
  info.single_layer_seconds = i.single_layer_seconds;
  info.double_layer_seconds = i.double_layer_seconds;
  info.hypersingular_seconds = i.hypersingular_seconds;
  info.far_field_cpu_seconds = i.low_rank_cpu_seconds;
  info.max_rank = i.max_rank;
  info.nbytes_v = i.nbytes_v;
  info.nbytes_k = i.nbytes_k;
  info.nbytes_w = i.nbytes_w;
  info.nbytes_preconditioner =
      static_cast<std::size_t>(G.nonZeros()) * (sizeof(double) + sizeof(int)) +
      static_cast<std::size_t>(calderon->mass.matrixL().nestedExpression().nonZeros()) * (sizeof(double) + sizeof(int));
  return parts;
}

std::unique_ptr<LameSteklovOperator> lame_surface_steklov_operator(VerticesRef vertices, TrianglesRef triangles,
                                                                   const Lame& m, Space flux,
                                                                   const SteklovOptions& options) {
  if (!(options.solver_tol > 0) || options.max_iterations < 1)
    throw std::invalid_argument("LameSteklovOperator: need solver_tol > 0, max_iterations >= 1");
  const auto t0 = std::chrono::steady_clock::now();
  LameSteklovParts parts = lame_surface_steklov_parts(Surface(vertices, triangles), m, flux, options);
  parts.info.setup_seconds = seconds_since(t0);
  return std::make_unique<LameSteklovOperator>(std::move(parts), options);
}
}  // namespace bem
