// The engine's fork-join pool: every partition of every job runs exactly
// once, whichever thread claims it, for any thread and partition count.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

#include "micro/worker_pool.hpp"

namespace {

using gabion::micro::WorkerPool;

TEST(WorkerPool, EveryPartitionOfEveryJobRunsOnce) {
  for (const int threads : {1, 2, 3, 4})
    for (const int per_thread : {1, 4})
      for (const bool take_tails : {true, false}) {
        const int parts = threads * per_thread;
        WorkerPool pool(threads, parts);
        if (per_thread > 1 && threads > 1) {  // uneven shares: thread 0 one partition, the last thread the rest
          std::vector<int> begin(static_cast<std::size_t>(threads) + 1);
          for (int u = 1; u < threads; ++u) begin[static_cast<std::size_t>(u)] = u;
          begin.back() = parts;
          pool.setShares(begin);
        }
        ASSERT_EQ(pool.size(), parts);
        ASSERT_EQ(pool.threads(), threads);
        std::vector<std::atomic<long>> runs(static_cast<std::size_t>(parts));
        for (auto& r : runs) r.store(0);
        constexpr long kJobs = 10000;
        for (long j = 0; j < kJobs; ++j) {
          std::atomic<int> seen{0};
          pool.run(
              [&](int t, int thread) {
                ASSERT_GE(t, 0);
                ASSERT_LT(t, parts);
                ASSERT_GE(thread, 0);
                ASSERT_LT(thread, threads);
                // uneven work, so that threads finish in varying order
                volatile double x = 1.0;
                for (long k = 0; k < (j + t) % 7 * 50; ++k) x = x * 1.000001;
                seen.fetch_or(1 << t);
                runs[static_cast<std::size_t>(t)].fetch_add(1);
              },
              take_tails);
          // run() returns only when all partitions are done
          ASSERT_EQ(seen.load(), (1 << parts) - 1) << "job " << j << ", " << threads << " threads";
        }
        for (int t = 0; t < parts; ++t) EXPECT_EQ(runs[static_cast<std::size_t>(t)].load(), kJobs) << "partition " << t;
      }
}

// With a follow-up, each thread that ran partitions is handed them after
// the last one it claimed: together the lists hold
// every partition once, and run() returns only when every follow-up has.
// A follow-up may wait for partitions other threads still run (here: each
// waits until its partitions and the one before each are done), as the
// engine's moves wait for the contacts of the partitions that reach into
// theirs; no wait can hang, since every partition is claimed by then.
TEST(WorkerPool, FollowUpsGetEachThreadsPartitionsAndMayWaitForOthers) {
  for (const int threads : {1, 2, 3})
    for (const bool take_tails : {true, false}) {
      const int parts = 4 * threads;
      WorkerPool pool(threads, parts);
      std::vector<std::atomic<long>> done(static_cast<std::size_t>(parts));
      for (auto& d : done) d.store(0);
      for (long j = 1; j <= 3000; ++j) {
        std::vector<std::atomic<int>> ran_by(static_cast<std::size_t>(parts)), handed(static_cast<std::size_t>(parts));
        for (int t = 0; t < parts; ++t)
          ran_by[static_cast<std::size_t>(t)].store(-1), handed[static_cast<std::size_t>(t)].store(0);
        std::atomic<int> followed{0};
        const WorkerPool::Then then = [&](int thread, const std::vector<int>& ran) {
          for (const int t : ran) {
            ASSERT_EQ(ran_by[static_cast<std::size_t>(t)].load(), thread) << "partition " << t;
            handed[static_cast<std::size_t>(t)].fetch_add(1);
            for (const int u : {t - 1, t})
              if (u >= 0)
                while (done[static_cast<std::size_t>(u)].load(std::memory_order_acquire) != j)
                  gabion::micro::cpuRelax();
          }
          followed.fetch_add(static_cast<int>(ran.size()));
        };
        pool.run(
            [&](int t, int thread) {
              volatile double x = 1.0;
              for (long k = 0; k < (j * 7 + t) % 5 * 40; ++k) x = x * 1.000001;
              ran_by[static_cast<std::size_t>(t)].store(thread);
              done[static_cast<std::size_t>(t)].store(j, std::memory_order_release);
            },
            take_tails, then);
        ASSERT_EQ(followed.load(), parts) << "job " << j << ", " << threads << " threads";
        for (int t = 0; t < parts; ++t) ASSERT_EQ(handed[static_cast<std::size_t>(t)].load(), 1) << "partition " << t;
      }
    }
}

// Runs one job on a pool of two threads in which thread 1 is held up
// (100 ms) in the first partition it runs, and thread 0 starts only once
// thread 1 is held (5 s at most); returns which thread ran each partition,
// or nothing if the worker did not start within those 5 s.
std::vector<int> runWithThreadOneHeldUp(WorkerPool& pool, bool take_tails) {
  std::vector<int> by(static_cast<std::size_t>(pool.size()), -1);
  std::atomic<bool> started{false};
  pool.run(
      [&](int t, int thread) {
        if (thread == 1 && !started.exchange(true)) std::this_thread::sleep_for(std::chrono::milliseconds(100));
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
        while (thread == 0 && t == 0 && !started.load() && std::chrono::steady_clock::now() < until)
          std::this_thread::yield();
        by[static_cast<std::size_t>(t)] = thread;
      },
      take_tails);
  if (!started.load()) return {};
  return by;
}

// A thread held up (a slower core) hands its partitions over: the other
// thread takes the tail of its share, from the end.
TEST(WorkerPool, AHeldUpThreadsPartitionsAreTakenOver) {
  WorkerPool pool(2, 8);
  const std::vector<int> by = runWithThreadOneHeldUp(pool, true);
  if (by.empty()) GTEST_SKIP() << "the worker thread did not start within 5 s";
  // thread 1 owns 4..7 and is held in 4; thread 0 runs its own 0..3, then 7, 6, 5
  EXPECT_EQ(by, (std::vector<int>{0, 0, 0, 0, 1, 0, 0, 0}));
}

// Without taking over tails, a share its owner has started is left to it,
// however long it takes.
TEST(WorkerPool, AStartedShareIsLeftToItsOwner) {
  WorkerPool pool(2, 8);
  const std::vector<int> by = runWithThreadOneHeldUp(pool, false);
  if (by.empty()) GTEST_SKIP() << "the worker thread did not start within 5 s";
  EXPECT_EQ(by, (std::vector<int>{0, 0, 0, 0, 1, 1, 1, 1}));
}

// The shares follow setShares: thread 1 owns 6 and 7, held up in 6; thread 0
// runs 0 .. 5, then takes 7 (tails) or leaves it (no tails).
TEST(WorkerPool, SharesFollowSetShares) {
  for (const bool take_tails : {true, false}) {
    WorkerPool pool(2, 8);
    pool.setShares({0, 6, 8});
    EXPECT_EQ(pool.shareBegin(1), 6);
    const std::vector<int> by = runWithThreadOneHeldUp(pool, take_tails);
    if (by.empty()) GTEST_SKIP() << "the worker thread did not start within 5 s";
    EXPECT_EQ(by, (std::vector<int>{0, 0, 0, 0, 0, 0, 1, take_tails ? 0 : 1})) << "take_tails " << take_tails;
  }
  WorkerPool pool(2, 8);
  EXPECT_THROW(pool.setShares({0, 8, 8}), std::invalid_argument);  // an empty share
  EXPECT_THROW(pool.setShares({0, 4}), std::invalid_argument);     // not threads + 1 boundaries
  EXPECT_THROW(pool.setShares({1, 4, 8}), std::invalid_argument);
}

// Shares from the threads' speeds: boundaries at the speeds' cumulative
// sums, at least one partition each, kept unless the slowest share ends at
// least 5 % sooner.
TEST(WorkerPool, SharesForSpeeds) {
  using gabion::micro::sharesForSpeeds;
  const std::vector<int> even{0, 4, 8};
  EXPECT_EQ(sharesForSpeeds({1.0, 1.0}, even, 8), even);
  EXPECT_EQ(sharesForSpeeds({2.0, 1.0}, even, 8), (std::vector<int>{0, 5, 8}));  // 5.33 rounded
  EXPECT_EQ(sharesForSpeeds({1.0, 3.0}, even, 8), (std::vector<int>{0, 2, 8}));
  EXPECT_EQ(sharesForSpeeds({1000.0, 1.0}, even, 8), (std::vector<int>{0, 7, 8}));  // one partition at least
  // 1.1 : 1 gives 4.19 -> 4: no change; 1.3 : 1 gives 4.52 -> 5, whose slowest share (5 / 1.3 = 3.85)
  // ends 3.8 % sooner than 4 / 1: under the 5 % margin, kept
  EXPECT_EQ(sharesForSpeeds({1.1, 1.0}, even, 8), even);
  EXPECT_EQ(sharesForSpeeds({1.3, 1.0}, even, 8), even);
  EXPECT_EQ(sharesForSpeeds({1.3, 1.0}, even, 8, 0.03), (std::vector<int>{0, 5, 8}));
  // back from an uneven split when the speeds even out
  EXPECT_EQ(sharesForSpeeds({1.0, 1.0}, {0, 6, 8}, 8), even);
  // three threads, the middle one half as fast: 12 partitions at 4.8, 7.2 -> 5, 7
  EXPECT_EQ(sharesForSpeeds({1.0, 0.5, 1.0}, {0, 4, 8, 12}, 12), (std::vector<int>{0, 5, 7, 12}));
  // unmeasured (a thread that ran nothing) or non-finite speeds: kept
  EXPECT_EQ(sharesForSpeeds({1.0, 0.0}, even, 8), even);
  EXPECT_EQ(sharesForSpeeds({1.0, std::nan("")}, even, 8), even);
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
