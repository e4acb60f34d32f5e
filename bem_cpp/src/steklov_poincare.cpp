#include "bem/steklov_poincare.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "bem/linear_algebra.hpp"

namespace bem {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

void factorise_single_layer(Matrix& V) {
  const int info = cholesky_in_place(V);
  if (info != 0)
    throw std::invalid_argument(
        "V_h is not positive definite (Cholesky failed at column " + std::to_string(info) +
        "): the logarithmic capacity of Gamma is >= 1, where V is not elliptic (diam(Omega) < 1 "
        "is sufficient for ellipticity); rescale the geometry so that its diameter is below 1");
}

Matrix steklov_poincare(const Polygon& polygon, Space flux, StageTimes* times) {
  using clock = std::chrono::steady_clock;
  auto t0 = clock::now();
  OperatorRequest request;
  request.single_layer = flux;
  request.double_layer = flux;
  request.hypersingular = true;
  request.full_symmetric = false;  // LAPACK reads the upper triangles of V_h and W_h only
  Operators ops = assemble(polygon, request);
  Matrix& A = ops.double_layer;
  add_mass(polygon, flux, -1.0, A);  // A = K_h - M_h
  if (times) times->assembly = seconds_since(t0);

  t0 = clock::now();
  factorise_single_layer(ops.single_layer);
  if (times) times->cholesky = seconds_since(t0);

  t0 = clock::now();
  lower_solve_in_place(ops.single_layer, A);  // A := L^{-1}(K_h - M_h)
  if (times) times->triangular_solve = seconds_since(t0);

  t0 = clock::now();
  Matrix& S = ops.hypersingular;
  add_gram_symmetric(A, 0.5, S);  // S = 1/2 (W_h + Y^T Y)
  if (times) times->rank_update = seconds_since(t0);
  return std::move(S);
}

Vector exterior_flux(const Polygon& polygon, const Eigen::Ref<const Vector>& dirichlet, double a, Space flux) {
  if (dirichlet.size() != polygon.size())
    throw std::invalid_argument("dirichlet: expected " + std::to_string(polygon.size()) +
                                " nodal values (one per node), got " + std::to_string(dirichlet.size()));
  if (!dirichlet.allFinite() || !std::isfinite(a))
    throw std::invalid_argument("dirichlet: values and a must be finite");
  OperatorRequest request;
  request.single_layer = flux;
  request.double_layer = flux;
  request.full_symmetric = false;
  Operators ops = assemble(polygon, request);
  add_mass(polygon, flux, -1.0, ops.double_layer);
  Vector psi = ops.double_layer * (dirichlet.array() - a).matrix();
  factorise_single_layer(ops.single_layer);
  cholesky_solve_in_place(ops.single_layer, psi);
  return psi;
}

Matrix steklov_poincare(const Eigen::Ref<const Points>& nodes, Space flux) {
  return steklov_poincare(Polygon(nodes), flux);
}

std::pair<Matrix, StageTimes> steklov_poincare_timed(const Eigen::Ref<const Points>& nodes, Space flux) {
  StageTimes times;
  Matrix S = steklov_poincare(Polygon(nodes), flux, &times);
  return {std::move(S), times};
}

Vector exterior_flux(const Eigen::Ref<const Points>& nodes, const Eigen::Ref<const Vector>& dirichlet, double a,
                     Space flux) {
  return exterior_flux(Polygon(nodes), dirichlet, a, flux);
}

}  // namespace bem
