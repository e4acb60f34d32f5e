#pragma once
// The communication of a distributed operator (docs/design/hmatrix.md, "Under MPI"):
// two collectives on row blocks, given as functions so that bem_cpp does not link MPI
// (the Python wrapper implements them with mpi4py; the GoogleTests with threads). Every
// rank calls them in the same order with the same counts.
#include <Eigen/Dense>
#include <functional>
#include <vector>

#include "bem/geometry.hpp"

namespace bem {

struct Communicator {
  int rank = 0, size = 1;
  /// (sum counts, k): the (counts[rank], k) blocks of all ranks stacked in rank order
  /// (MPI_Allgatherv). The result is the same on every rank.
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd& local, const std::vector<Index>& counts)> allgather;
  /// (counts[rank], k): this rank's rows of the sum over the ranks of the (sum counts, k)
  /// partial sums (MPI_Reduce_scatter). Each entry of the sum is formed on its own rank
  /// only, so that allgather of the pieces gives every rank the same bits (MPI_Allreduce
  /// does not promise that).
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd& partial, const std::vector<Index>& counts)>
      reduce_scatter;
};

}  // namespace bem
