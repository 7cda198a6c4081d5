#pragma once
/// \file
/// A tiny fork-join pool for the engine's parallel stages. Work is split
/// into fixed partitions 0 .. size()-1; the result of partition t may depend
/// on t but never on which thread runs it, and results reduced in partition
/// order are identical from run to run for the same thread count.
/// Partitions are claimed from a shared counter by the caller and the
/// workers alike, so a worker that the OS has not scheduled yet (another job
/// on the cores) does not hold the caller up: the caller runs its partition.
/// Waiting threads spin for a few tens of microseconds (a DEM step stage
/// lasts about that long, far below a wake-up from sleep), then block on a
/// condition variable, so an idle or oversubscribed pool burns no CPU.
#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace gabion::micro {

class WorkerPool {
 public:
  /// `threads` >= 1 threads in all, the calling thread included.
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return threads_; }
  /// Runs job(t) once for each partition t = 0 .. size()-1, on whichever
  /// threads claim them first (the calling thread takes part), and returns
  /// when all are done.
  void run(const std::function<void(int)>& job);

 private:
  void workerLoop();
  /// Claims and runs partitions of the current job until none is left;
  /// returns true if this call finished the last one.
  bool drain();
  int threads_;
  std::vector<std::thread> workers_;
  std::atomic<const std::function<void(int)>*> job_{nullptr};
  std::atomic<int> next_{0};      // next partition to claim (>= threads_: none left)
  std::atomic<int> pending_{0};   // partitions not finished yet
  std::atomic<unsigned> generation_{0};  // bumped (under mutex_) for each job
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable wake_;  // workers: a new generation
  std::condition_variable done_;  // caller: pending_ reached 0
};

}  // namespace gabion::micro
