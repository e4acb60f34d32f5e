#pragma once
// Adaptive cross approximation of a block whose rows and columns come in groups (the d
// components of a node of the Lame operators, lame_polygon_entries.hpp), and the EntrySource
// that approximates every admissible block so with its stop confirmed on several samples (the
// double layer of a polygon, boundary_operators.hpp).
//
// Why not aca.hpp as it is: the blocks of two clusters on one straight line (the sides of
// a polygon) are block-diagonal in the components there (g = t t^T has g_xy = 0 when t is
// a coordinate axis; the log part is diagonal anyway), and partial pivoting, which moves to
// the row of the largest entry of the last column, then never leaves the component it
// started in: it stops with the other component's half of the block unseen unless the
// one sampled row or column happens to fall on it (seen: a 3.5 % error of the whole V_h on
// an L-shape of 1,200 nodes). Here every pivot row brings the other rows of its group
// (the other components of its node) along, each with its own pivot column, and the stop
// is tested on the crosses of the whole group; the sampled confirmation takes a whole
// group of columns and of rows. Otherwise as aca(): partial pivoting, the next row that of
// the largest entry of the last column, stop when the crosses of a group satisfy
// |sum u v^T|_F <= tol |U V^T|_F.
#include <memory>
#include <vector>

#include "bem/aca.hpp"
#include "bem/hmatrix.hpp"

namespace bem {

/// ACA of the m x n block given by its rows and columns; row_group[i] (column_group[j])
/// names the group of row i (column j): any integers, equal within a group. The stop is
/// confirmed on `samples` random groups of columns and of rows.
LowRank grouped_aca(Index m, Index n, const std::vector<Index>& row_group, const std::vector<Index>& column_group,
                    const Slice& row, const Slice& column, double tol, Index max_rank, int samples = 1);

/// An EntrySource whose admissible blocks are approximated by grouped_aca with every row
/// and column its own group and `samples` confirmations, the rest as `source`'s (which must
/// outlive it). For the Laplace double layer K_h of a polygon with straight sides
/// (layer_hmatrix, boundary_operators.hpp; the Lame operator's K_L, lame_steklov.hpp): its
/// kernel vanishes between two panels on one line, so the block of two clusters that both
/// hold nodes of two nearly parallel sides (a thin polygon) is [[0, A], [B, 0]] in those
/// rows and columns, and aca()'s partial pivoting stays in one half while its single sampled
/// row and column miss the other with probability about 1/4: on the thin 10 degree triangle
/// (test::dart, 801 and 2,001 nodes) many blocks lost half their norm (relative error
/// 1/sqrt(2)), K_h's H-matrix 2.8e-2 and the Laplace S_h 2.1e-3 and 1.4e-3 off. With 8
/// samples of each, as the tests' tol of 1e-10 asks (docs/design/lame_bem.md).
class SampledAcaEntries : public EntrySource {
 public:
  SampledAcaEntries(const EntrySource& source, int samples) : source_(source), samples_(samples) {}
  std::unique_ptr<EntryBlock> block(const Index* I, Index m, const Index* J, Index k) const override;

 private:
  const EntrySource& source_;
  int samples_;
};

}  // namespace bem
