#pragma once
/// \file
/// A tiny fork-join pool for the engine's parallel stages. Work is split
/// into fixed partitions 0 .. size()-1; the result of partition t may depend
/// on t but never on which thread runs it, and results reduced in partition
/// order are identical from run to run for the same thread count.
/// Thread t (the caller is 0) first claims partition t, so that a partition
/// stays on one core from stage to stage and step to step (its particles stay
/// in that core's cache); then it claims any partition still unclaimed, so a
/// worker that the OS has not scheduled yet (another job on the cores) does
/// not hold the caller up: the caller runs its partition too.
/// Waiting threads spin for a few tens of microseconds, poll with yields for
/// a few milliseconds, then block on a condition variable, so an idle or
/// oversubscribed pool burns no CPU (micro/worker_pool.cpp).
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
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
  void workerLoop(int self);
  /// Claims and runs the partitions of job `generation` still unclaimed,
  /// partition `self` first; returns true if this call finished the last one.
  bool drain(int self, std::uint64_t generation);
  int threads_;
  std::vector<std::thread> workers_;
  std::atomic<const std::function<void(int)>*> job_{nullptr};
  // claimed_[t]: the last job (generation) whose partition t was claimed;
  // claiming is a compare-exchange from an older generation.
  std::unique_ptr<std::atomic<std::uint64_t>[]> claimed_;
  std::atomic<int> pending_{0};               // partitions not finished yet
  std::atomic<std::uint64_t> generation_{0};  // bumped (under mutex_) for each job
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable wake_;  // workers: a new generation
  std::condition_variable done_;  // caller: pending_ reached 0
};

}  // namespace gabion::micro
