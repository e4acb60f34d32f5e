#pragma once
// Adaptive cross approximation of a block of a vector kernel (the Lame operators: d dofs
// per node, lame_polygon_entries.hpp), whose rows and columns come in groups (the d
// components of a node).
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
#include <vector>

#include "bem/aca.hpp"

namespace bem {

/// ACA of the m x n block given by its rows and columns; row_group[i] (column_group[j])
/// names the group of row i (column j): any integers, equal within a group.
LowRank grouped_aca(Index m, Index n, const std::vector<Index>& row_group, const std::vector<Index>& column_group,
                    const Slice& row, const Slice& column, double tol, Index max_rank);

}  // namespace bem
