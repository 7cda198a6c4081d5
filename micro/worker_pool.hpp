#pragma once
/// \file
/// A tiny fork-join pool for the engine's parallel stages. Work is split
/// into fixed partitions (partition t always goes to worker t), so results
/// that are reduced in partition order are identical from run to run for the
/// same thread count. Workers spin briefly, then yield, while waiting: a DEM
/// step lasts tens of microseconds, far below a condition-variable wake-up.
#include <atomic>
#include <functional>
#include <thread>
#include <vector>

namespace gabion::micro {

class WorkerPool {
 public:
  /// `threads` >= 1 workers in all, the calling thread being worker 0.
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return threads_; }
  /// Runs job(t) for t = 0 .. size()-1 (t = 0 on the calling thread) and
  /// returns when all are done.
  void run(const std::function<void(int)>& job);

 private:
  void workerLoop(int t);
  int threads_;
  std::vector<std::thread> workers_;
  const std::function<void(int)>* job_ = nullptr;
  std::atomic<unsigned> generation_{0};
  std::atomic<int> pending_{0};
  std::atomic<bool> stop_{false};
};

}  // namespace gabion::micro
