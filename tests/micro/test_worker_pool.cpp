// The engine's fork-join pool: every partition of every job runs exactly
// once, whichever thread claims it, for any thread and partition count.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "micro/worker_pool.hpp"

namespace {

using gabion::micro::WorkerPool;

TEST(WorkerPool, EveryPartitionOfEveryJobRunsOnce) {
  for (const int threads : {1, 2, 3, 4})
    for (const int per_thread : {1, 4}) {
      const int parts = threads * per_thread;
      WorkerPool pool(threads, parts);
      ASSERT_EQ(pool.size(), parts);
      ASSERT_EQ(pool.threads(), threads);
      std::vector<std::atomic<long>> runs(static_cast<std::size_t>(parts));
      for (auto& r : runs) r.store(0);
      constexpr long kJobs = 10000;
      for (long j = 0; j < kJobs; ++j) {
        std::atomic<int> seen{0};
        pool.run([&](int t, int thread) {
          ASSERT_GE(t, 0);
          ASSERT_LT(t, parts);
          ASSERT_GE(thread, 0);
          ASSERT_LT(thread, threads);
          // uneven work, so that threads finish in varying order
          volatile double x = 1.0;
          for (long k = 0; k < (j + t) % 7 * 50; ++k) x = x * 1.000001;
          seen.fetch_or(1 << t);
          runs[static_cast<std::size_t>(t)].fetch_add(1);
        });
        // run() returns only when all partitions are done
        ASSERT_EQ(seen.load(), (1 << parts) - 1) << "job " << j << ", " << threads << " threads";
      }
      for (int t = 0; t < parts; ++t) EXPECT_EQ(runs[static_cast<std::size_t>(t)].load(), kJobs) << "partition " << t;
    }
}

// A thread held up (a slower core) hands its partitions over: the other
// thread takes the tail of its share, from the end.
TEST(WorkerPool, AHeldUpThreadsPartitionsAreTakenOver) {
  WorkerPool pool(2, 8);
  std::vector<int> by(8, -1);
  std::atomic<bool> started{false};
  pool.run([&](int t, int thread) {
    if (thread == 1 && !started.exchange(true)) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    // thread 0 waits (5 s at most) until thread 1 is held up in its first partition
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (thread == 0 && t == 0 && !started.load() && std::chrono::steady_clock::now() < until)
      std::this_thread::yield();
    by[static_cast<std::size_t>(t)] = thread;
  });
  if (!started.load()) GTEST_SKIP() << "the worker thread did not start within 5 s";
  // thread 1 owns 4..7 and is held in 4; thread 0 runs its own 0..3, then 7, 6, 5
  EXPECT_EQ(by, (std::vector<int>{0, 0, 0, 0, 1, 0, 0, 0}));
}

// Jobs far apart in time (the workers have blocked in between) still run
// every partition once.
TEST(WorkerPool, WorkersWakeUpAfterBlocking) {
  WorkerPool pool(2);
  for (int j = 0; j < 3; ++j) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // longer than the spin and poll phases
    std::atomic<int> mask{0};
    pool.run([&](int t, int) { mask.fetch_or(1 << t); });
    EXPECT_EQ(mask.load(), 3);
  }
}

}  // namespace
