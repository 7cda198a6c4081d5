#pragma once
/// \file
/// A tiny fork-join pool for the engine's parallel stages. Work is split
/// into fixed partitions 0 .. size()-1, several per thread; the result of
/// partition t may depend on t but never on which thread runs it, and
/// results reduced in partition order are identical from run to run for the
/// same partition count.
/// Thread t (the caller is 0) owns a contiguous share of the partitions and
/// claims them first, in order, so that a partition stays on one core from
/// stage to stage and step to step (its particles stay in that core's
/// cache); then it claims the others' still unclaimed, from the end of
/// their shares. A core that runs slower (a virtual CPU whose host core is
/// busy elsewhere) thus hands the tail of its share to a faster one, and a
/// worker that the OS has not scheduled yet does not hold the caller up.
/// The shares start even; the caller may resize them between jobs
/// (setShares) to the threads' measured speeds, so that a slower core's
/// tail is not taken over, and its data moved between caches, at every job.
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
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace gabion::micro {

class WorkerPool {
 public:
  /// `threads` >= 1 threads in all, the calling thread included, running
  /// `partitions` partitions per job (at least one per thread).
  explicit WorkerPool(int threads, int partitions = 1);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  /// Partitions per job.
  int size() const { return partitions_; }
  /// Threads, the caller included.
  int threads() const { return threads_; }
  /// First partition of thread u's share (u = 0 .. threads()); share u is
  /// shareBegin(u) .. shareBegin(u + 1) - 1.
  int shareBegin(int u) const { return static_cast<int>(share_begin_[static_cast<std::size_t>(u)]); }
  /// Sets the shares (between jobs): `begin` has threads() + 1 entries, 0
  /// first, size() last, each share at least one partition.
  void setShares(const std::vector<int>& begin);
  /// Runs job(t, thread) once for each partition t = 0 .. size()-1, on
  /// whichever threads claim them first (the calling thread takes part,
  /// as thread 0), and returns when all are done. With take_tails, a
  /// thread done with its own share takes what is left of another's, from
  /// its end; without, only a share whose owner has not started it, whole.
  /// With a `then`, each thread that ran partitions of the job then calls
  /// then(thread, ran) with them, in the order it ran them, once it finds
  /// none left to claim (every partition is then claimed, if not
  /// finished), and run() returns when every such call has returned. A
  /// `then` may wait for other partitions of the job to finish: they all
  /// run without waiting for anything.
  using Then = std::function<void(int, const std::vector<int>&)>;
  void run(const std::function<void(int, int)>& job, bool take_tails = true, const Then& then = {});

 private:
  void workerLoop(int self);
  /// Claims and runs the partitions of job `generation` still unclaimed,
  /// thread `self`'s own first; returns true if this call finished the last one.
  bool drain(int self, std::uint64_t generation);
  int threads_, partitions_;
  std::vector<std::thread> workers_;
  std::atomic<const std::function<void(int, int)>*> job_{nullptr};
  const Then* then_ = nullptr;  // published with job_
  // shares_[u]: what is left of thread u's share in the current job, one
  // word: (job generation mod 2^32) << 32 | first << 16 | end. Its owner
  // claims from the front, the others from the end, each by a
  // compare-exchange; whoever comes first in a job opens it to the whole
  // share (a word of an earlier job). One cache line each: a thread claiming
  // its own pulls no other thread's line.
  struct alignas(64) Share {
    std::atomic<std::uint64_t> state{0};
  };
  std::unique_ptr<Share[]> shares_;
  // Per thread (one cache line each): the partitions it ran in this job.
  struct alignas(64) Ran {
    std::vector<int> list;
  };
  std::unique_ptr<Ran[]> ran_;
  std::vector<std::uint32_t> share_begin_;    // thread u's share: share_begin_[u] .. share_begin_[u + 1] - 1
  std::atomic<int> pending_{0};               // partitions not finished yet
  std::atomic<std::uint64_t> generation_{0};  // bumped (under mutex_) for each job
  std::atomic<bool> stop_{false};
  std::atomic<bool> take_tails_{true};
  std::mutex mutex_;
  std::condition_variable wake_;  // workers: a new generation
  std::condition_variable done_;  // caller: pending_ reached 0
};

/// A pause in a spin-wait loop (lets the core's other hardware thread run).
inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

/// Shares of `partitions` partitions among threads of the given speeds
/// (partitions per unit time, all > 0) that end a job together: share
/// boundaries at the speeds' cumulative sums, rounded, each share at least
/// one partition. Returns `current` (threads + 1 boundaries) unless the new
/// shares' slowest one ends at least `gain` sooner than the current's (a
/// margin against the noise of the measured speeds: a share that moves
/// moves its partitions' data between the cores' caches).
std::vector<int> sharesForSpeeds(const std::vector<double>& speed, const std::vector<int>& current, int partitions,
                                 double gain = 0.05);

}  // namespace gabion::micro
