// The engine's fork-join pool: every partition of every job runs exactly
// once, whichever thread claims it, for any thread count.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "micro/worker_pool.hpp"

namespace {

using gabion::micro::WorkerPool;

TEST(WorkerPool, EveryPartitionOfEveryJobRunsOnce) {
  for (const int threads : {1, 2, 3, 4}) {
    WorkerPool pool(threads);
    ASSERT_EQ(pool.size(), threads);
    std::vector<std::atomic<long>> runs(static_cast<std::size_t>(threads));
    for (auto& r : runs) r.store(0);
    constexpr long kJobs = 20000;
    for (long j = 0; j < kJobs; ++j) {
      std::atomic<int> seen{0};
      pool.run([&](int t) {
        ASSERT_GE(t, 0);
        ASSERT_LT(t, threads);
        // uneven work, so that threads finish in varying order
        volatile double x = 1.0;
        for (long k = 0; k < (j + t) % 7 * 50; ++k) x = x * 1.000001;
        seen.fetch_or(1 << t);
        runs[static_cast<std::size_t>(t)].fetch_add(1);
      });
      // run() returns only when all partitions are done
      ASSERT_EQ(seen.load(), (1 << threads) - 1) << "job " << j << ", " << threads << " threads";
    }
    for (int t = 0; t < threads; ++t) EXPECT_EQ(runs[static_cast<std::size_t>(t)].load(), kJobs) << "partition " << t;
  }
}

// Jobs far apart in time (the workers have blocked in between) still run
// every partition once.
TEST(WorkerPool, WorkersWakeUpAfterBlocking) {
  WorkerPool pool(2);
  for (int j = 0; j < 3; ++j) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // longer than the spin and poll phases
    std::atomic<int> mask{0};
    pool.run([&](int t) { mask.fetch_or(1 << t); });
    EXPECT_EQ(mask.load(), 3);
  }
}

}  // namespace
