#pragma once
// Emulated MPI ranks for the GoogleTests of the distributed operators: the ranks are threads
// joined by an in-process Communicator (communicator.hpp).
#include <gtest/gtest.h>

#include <condition_variable>
#include <memory>
#include <mutex>
#include <vector>

#include "bem/communicator.hpp"

namespace bem::test {

/// The collectives of `size` threads (each thread one rank), through shared slots.
class ThreadGroup {
 public:
  explicit ThreadGroup(int size) : size_(size), slots_(static_cast<std::size_t>(size)) {}

  std::shared_ptr<const Communicator> communicator(int rank) {
    auto c = std::make_shared<Communicator>();
    c->rank = rank;
    c->size = size_;
    c->allgather = [this, rank](const Eigen::MatrixXd& local, const std::vector<Index>& counts) {
      slots_[static_cast<std::size_t>(rank)] = local;
      barrier();
      Index n = 0;
      for (Index c : counts) n += c;
      Eigen::MatrixXd out(n, local.cols());
      Index r0 = 0;
      for (int r = 0; r < size_; ++r) {
        EXPECT_EQ(slots_[static_cast<std::size_t>(r)].rows(), counts[static_cast<std::size_t>(r)]);
        out.middleRows(r0, counts[static_cast<std::size_t>(r)]) = slots_[static_cast<std::size_t>(r)];
        r0 += counts[static_cast<std::size_t>(r)];
      }
      barrier();
      return out;
    };
    c->allreduce = [this, rank](const Eigen::MatrixXd& partial, const std::vector<Index>&) {
      slots_[static_cast<std::size_t>(rank)] = partial;
      barrier();
      Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(partial.rows(), partial.cols());
      for (int r = 0; r < size_; ++r) sum += slots_[static_cast<std::size_t>(r)];  // rank order
      barrier();
      return sum;
    };
    return c;
  }

 private:
  void barrier() {
    std::unique_lock<std::mutex> lock(mutex_);
    const long generation = generation_;
    if (++waiting_ == size_) {
      waiting_ = 0;
      ++generation_;
      cv_.notify_all();
    } else {
      cv_.wait(lock, [&] { return generation_ != generation; });
    }
  }
  int size_;
  std::vector<Eigen::MatrixXd> slots_;
  std::mutex mutex_;
  std::condition_variable cv_;
  int waiting_ = 0;
  long generation_ = 0;
};

}  // namespace bem::test
