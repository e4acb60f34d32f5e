#pragma once
// The communication of a distributed operator (docs/design/hmatrix.md, "Under MPI"):
// two collectives on row blocks, given as functions so that bem_cpp does not link MPI
// (the Python wrapper implements them with mpi4py; the GoogleTests with threads). Every
// rank calls them in the same order with the same counts.
#include <Eigen/Dense>
#include <functional>
#include <memory>
#include <vector>

#include "bem/geometry.hpp"

namespace bem {

struct Communicator {
  int rank = 0, size = 1;
  /// (sum counts, k): the (counts[rank], k) blocks of all ranks stacked in rank order
  /// (MPI_Allgatherv). The result is the same on every rank.
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd& local, const std::vector<Index>& counts)> allgather;
  /// (sum counts, k): the sum over the ranks of the (sum counts, k) partial sums, with the
  /// same bits on every rank. On 2 ranks an MPI_Allreduce gives that (each entry is one
  /// addition, and IEEE addition is commutative); on more the order of the additions may
  /// differ between ranks, so MPI_Reduce_scatter forms each entry on one rank (the rows
  /// `counts`) and MPI_Allgatherv copies it.
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd& partial, const std::vector<Index>& counts)> allreduce;
};

/// The sum over the ranks of `comm` of the (m, k) blocks `partial`, each entry of which
/// one rank alone holds (the others hold 0 there: e.g. a principal submatrix of a
/// distributed HMatrix, whose blocks no two ranks share), so that the sum is exact in any
/// order; the rows are reduced in even shares (Communicator::allreduce). Without a
/// communicator of more than one rank: `partial` itself. Collective.
inline Eigen::MatrixXd sum_of_held_entries(const std::shared_ptr<const Communicator>& comm,
                                           const Eigen::MatrixXd& partial) {
  if (!comm || comm->size == 1) return partial;
  const Index m = partial.rows();
  std::vector<Index> counts(static_cast<std::size_t>(comm->size), m / comm->size);
  for (Index r = 0; r < m % comm->size; ++r) ++counts[static_cast<std::size_t>(r)];
  return comm->allreduce(partial, counts);
}

}  // namespace bem
