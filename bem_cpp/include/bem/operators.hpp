#pragma once
// Dense Galerkin matrices of the boundary integral operators of docs/method.md section 2
// (factor-2 convention) on a closed polygon:
//   V_h[i, j] = <V psi_j, psi_i>   = -(1/pi) int int log|x - y| psi_j(y) psi_i(x)
//   K_h[i, j] = <K v_j, psi_i>     =  (1/pi) int int (x - y).n_y/|x - y|^2 v_j(y) psi_i(x)
//   W_h       = D^T V0_h D          (Maue's identity, docs/method.md section 9)
//   M_h[i, j] = <v_j, psi_i>
// v_j: continuous piecewise linear hat of node j (P1 trace); psi_i: flux basis, the P1
// hat of node i ("p1") or the indicator of panel i ("p0"); D: arc-length derivative of
// the hats (panel i: -1/h_i at its start node, +1/h_i at its end node).
#include <optional>

#include "bem/geometry.hpp"

namespace bem {

/// Flux space: continuous piecewise linear (P1) or piecewise constant on panels (P0).
/// Both have n degrees of freedom on a closed polygon with n nodes.
enum class Space { P0, P1 };

/// Which matrices one assembly pass produces (all from the same panel-pair loop).
struct OperatorRequest {
  std::optional<Space> single_layer;  ///< V_h with rows and columns in this space
  std::optional<Space> double_layer;  ///< K_h with rows in this space, columns P1
  bool hypersingular = false;         ///< W_h (P1)
  /// If false, the symmetric V_h and W_h are returned with only their upper triangle
  /// set (the lower one is unspecified), which is all LAPACK's Cholesky and rank-k
  /// update read; saves two O(n^2) passes.
  bool full_symmetric = true;
};

struct Operators {
  Matrix single_layer, double_layer, hypersingular;  ///< empty if not requested
};

/// One OpenMP-parallel pass over the panels i: the local 2x2 blocks of the pairs (i, j)
/// (log_integrals.hpp) are stored by columns j and added to the rows owned by panel i
/// only (rows i and i+1; panels are processed in two colours so no two threads share a
/// row). V and W = D^T V0 D use the pairs j >= i, the mirrored pairs follow from
/// symmetry (a band and column 0 need it); K uses all pairs, the pairs j < i with the
/// double-layer kernel only (no logarithm). Far pairs are evaluated in vector batches.
Operators assemble(const Polygon& polygon, const OperatorRequest& request);

Matrix single_layer(const Polygon& polygon, Space space);
/// Rows: flux space, columns: P1 trace.
Matrix double_layer(const Polygon& polygon, Space space);
/// P1 x P1, via Maue's identity W_h = D^T V0_h D.
Matrix hypersingular(const Polygon& polygon);
/// Rows: `space`, columns: P1 (P0: n x n P0-by-P1 mass, P1: the P1 Gram matrix).
Matrix mass(const Polygon& polygon, Space space);
/// K := K + scale * M(space) in place (M is banded: no dense mass matrix is formed).
void add_mass(const Polygon& polygon, Space space, double scale, Matrix& K);

/// The n x n zero matrix, first touched in parallel (the page faults are shared out among
/// the threads that then fill it).
Matrix parallel_zeros(Index n);

// The same on raw nodes, validated by the Polygon constructor (used by the bindings).
Matrix single_layer(const Eigen::Ref<const Points>& nodes, Space space);
Matrix double_layer(const Eigen::Ref<const Points>& nodes, Space space);
Matrix hypersingular(const Eigen::Ref<const Points>& nodes);
Matrix mass(const Eigen::Ref<const Points>& nodes, Space space);

}  // namespace bem
