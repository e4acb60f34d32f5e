#pragma once
// Adaptive cross approximation with partial pivoting (Bebendorf 2000) and recompression
// (docs/design/hmatrix.md). A block A (m x n) of an asymptotically smooth kernel is
// approximated by A ~ U V^T from O(rank) of its rows and columns:
//   step k: residual row i_k, pivot j_k = argmax |row|, residual column j_k,
//           u_k = column, v_k = row / row[j_k], next row = argmax |u_k| (unused rows);
//   stop when |u_k| |v_k| <= tol |U V^T|_F (the Frobenius norm updated in O(k(m+n))).
// Zero residual rows (exact zeros of the double-layer kernel on straight sides) move the
// pivot to the next unused row; the stop is confirmed on a few sampled rows and columns
// (a sampled residual that fails the test becomes the next pivot), which catches the
// classical failure of partial pivoting on blocks with unseen non-smooth parts.
#include <Eigen/Dense>
#include <functional>
#include <vector>

#include "bem/geometry.hpp"

namespace bem {

/// A ~ U V^T, U (m x r), V (n x r).
struct LowRank {
  Eigen::MatrixXd U, V;
  Index rank() const { return U.cols(); }
};

/// f(index, out): the row (length n) or column (length m) `index` of the block into out.
using Slice = std::function<void(Index, double*)>;

/// ACA of the m x n block with entries given by its rows and columns.
LowRank aca(Index m, Index n, const Slice& row, const Slice& column, double tol, Index max_rank);

/// Truncates A = U V^T to the smallest rank r with sum_{i > r} sigma_i^2 <= tol^2 |A|_F^2
/// (QR of U and V, SVD of R_U R_V^T).
void recompress(LowRank& a, double tol);

/// The first index i of from, from + 1, ... (cyclically, modulo used.size()) with !used[i],
/// or -1 when every index is used: the next pivot row the ACAs try after a zero one.
Index next_unused(const std::vector<char>& used, Index from);

}  // namespace bem
