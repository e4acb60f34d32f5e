#pragma once
// Emulated MPI ranks for the GoogleTests of the distributed operators: the ranks are threads
// joined by an in-process Communicator (communicator.hpp).
#include <gtest/gtest.h>

#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>
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

/// The bytes of the H-matrices V, V0, K and W of an operator's info.
template <class Info>
std::size_t hmatrix_bytes(const Info& i) {
  return i.nbytes_v + i.nbytes_v0 + i.nbytes_k + i.nbytes_w;
}

/// What the operator of each emulated rank gave (index: the rank): S_h Y, the flux of Y, the
/// iterations of that flux's CG and the bytes of its H-matrices (V, V0, K, W).
struct RankRuns {
  std::vector<Eigen::MatrixXd> apply, flux;
  std::vector<int> iterations;
  std::vector<std::size_t> bytes;
};

/// On `size` threads, one emulated rank each: the operator make(comm) (a pointer to a
/// Steklov-Poincare operator, comm the rank's communicator) applied to Y, and its flux of Y.
template <class Make>
RankRuns run_on_ranks(int size, const Eigen::MatrixXd& Y, Make make) {
  ThreadGroup group(size);
  const std::size_t n = static_cast<std::size_t>(size);
  RankRuns runs{std::vector<Eigen::MatrixXd>(n), std::vector<Eigen::MatrixXd>(n), std::vector<int>(n),
                std::vector<std::size_t>(n)};
  std::vector<std::thread> ranks;
  for (int r = 0; r < size; ++r)
    ranks.emplace_back([&, r] {
      const std::size_t k = static_cast<std::size_t>(r);
      const auto S = make(group.communicator(r));
      runs.apply[k] = S->apply(Y);
      runs.flux[k] = S->flux(Y);
      runs.iterations[k] = S->last_iterations();
      runs.bytes[k] = hmatrix_bytes(S->info());
    });
  for (std::thread& t : ranks) t.join();
  return runs;
}

/// The distributed operators' agreement with the serial one (S_h Y = ref, flux ref_flux after
/// `iterations` CG iterations, `whole` H-matrix bytes): every rank within `tol` (relative) of
/// the serial results with the same iterations and the same bits as rank 0, on one rank the
/// serial bits (`serial_bits_on_one`), and at most bytes_factor * whole / size bytes a rank.
inline void expect_serial_results(const RankRuns& runs, const Eigen::MatrixXd& ref, const Eigen::MatrixXd& ref_flux,
                                  int iterations, std::size_t whole, double tol, bool serial_bits_on_one,
                                  double bytes_factor) {
  const std::size_t size = runs.apply.size();
  auto relative = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); };
  if (size == 1 && serial_bits_on_one) {
    EXPECT_EQ((runs.apply[0] - ref).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((runs.flux[0] - ref_flux).cwiseAbs().maxCoeff(), 0.0);
  }
  for (std::size_t r = 0; r < size; ++r) {
    EXPECT_LT(relative(runs.apply[r], ref), tol);
    EXPECT_LT(relative(runs.flux[r], ref_flux), tol);
    EXPECT_EQ(runs.iterations[r], iterations);
    // every rank has the same bits (collectives formed on one rank each)
    EXPECT_EQ((runs.apply[r] - runs.apply[0]).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((runs.flux[r] - runs.flux[0]).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_LE(static_cast<double>(runs.bytes[r]),
              bytes_factor * static_cast<double>(whole) / static_cast<double>(size));
  }
}

}  // namespace bem::test
