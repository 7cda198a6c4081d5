#include "micro/worker_pool.hpp"

#include <algorithm>
#include <chrono>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace gabion::micro {

namespace {
// A waiting thread first spins (kSpin: longer than the gap between two
// parallel stages of a step), then keeps polling but yields its core to any
// other runnable thread (kPoll: longer than the serial parts of a neighbour
// list rebuild), and only then blocks. Blocking is expensive on a virtual
// machine: waking an idle vCPU takes tens of microseconds, during which the
// caller does the sleeping worker's partition too. Yielding keeps a shared
// core useful to the other jobs on it.
constexpr std::chrono::microseconds kSpin{50};
constexpr std::chrono::microseconds kPoll{2000};

inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

// Spins, then polls with yields, until done() or kSpin + kPoll has passed;
// returns done().
template <class Done>
bool spinFor(Done done) {
  const auto start = std::chrono::steady_clock::now();
  const auto spin_until = start + kSpin, poll_until = start + kSpin + kPoll;
  for (unsigned k = 1;; ++k) {
    if (done()) return true;
    cpuRelax();
    if ((k & 31u) == 0 && std::chrono::steady_clock::now() > spin_until) break;
  }
  for (;;) {
    if (done()) return true;
    std::this_thread::yield();
    if (std::chrono::steady_clock::now() > poll_until) return done();
  }
}
}  // namespace

WorkerPool::WorkerPool(int threads, int partitions)
    : threads_(threads < 1 ? 1 : threads),
      partitions_(std::min(std::max(partitions, threads_), 0xffff)),  // (a share's ends are 16 bits)
      shares_(new Share[static_cast<std::size_t>(threads_)]) {
  for (int t = 1; t < threads_; ++t) workers_.emplace_back([this, t] { workerLoop(t); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_.store(true, std::memory_order_release);
    generation_.fetch_add(1, std::memory_order_acq_rel);
  }
  wake_.notify_all();
  for (auto& w : workers_) w.join();
}

bool WorkerPool::drain(int self, std::uint64_t generation) {
  // The caller publishes job_ and pending_ before it bumps generation_
  // (release); a worker reads generation_ (acquire) before it comes here. A
  // worker still here from an earlier job finds every share stamped with a
  // later job, and claims nothing.
  // Thread self runs its own share from the front, then takes what is left
  // of the others' from their ends (a faster core takes over the tail of a
  // slower one's share), going round from the thread before it. The
  // partitions it ran are counted off pending_ at once at the end: one
  // exchange of that shared line per thread and job.
  const auto gen = static_cast<std::uint32_t>(generation);
  const auto P = static_cast<std::uint32_t>(partitions_), T = static_cast<std::uint32_t>(threads_);
  int ran = 0;
  for (std::uint32_t k = 0; k < T; ++k) {
    const std::uint32_t u = (static_cast<std::uint32_t>(self) + T - k) % T;
    std::atomic<std::uint64_t>& state = shares_[u].state;
    std::uint64_t s = state.load(std::memory_order_acquire);
    for (;;) {
      const auto d = static_cast<std::int32_t>(static_cast<std::uint32_t>(s >> 32) - gen);
      if (d > 0) break;  // a later job's
      // (d < 0: not opened in this job yet, the whole share)
      std::uint32_t first = d < 0 ? P * u / T : static_cast<std::uint32_t>(s >> 16) & 0xffffu;
      std::uint32_t end = d < 0 ? P * (u + 1) / T : static_cast<std::uint32_t>(s) & 0xffffu;
      if (first >= end) break;
      const std::uint32_t t = k == 0 ? first++ : --end;
      const std::uint64_t next = std::uint64_t{gen} << 32 | std::uint64_t{first} << 16 | end;
      if (!state.compare_exchange_weak(s, next, std::memory_order_acq_rel, std::memory_order_acquire)) continue;
      (*job_.load(std::memory_order_acquire))(static_cast<int>(t), self);
      ++ran;
      s = next;  // (a failed exchange below reloads it)
    }
  }
  return ran > 0 && pending_.fetch_sub(ran, std::memory_order_acq_rel) == ran;
}

void WorkerPool::run(const std::function<void(int, int)>& job) {
  if (threads_ == 1) {
    for (int t = 0; t < partitions_; ++t) job(t, 0);
    return;
  }
  // Order matters: job_ and pending_ are published by the release of the
  // generation bump; shares open only with the new generation.
  pending_.store(partitions_, std::memory_order_relaxed);
  job_.store(&job, std::memory_order_relaxed);
  std::uint64_t generation = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation = generation_.fetch_add(1, std::memory_order_acq_rel) + 1;
  }
  wake_.notify_all();
  drain(0, generation);
  const auto done = [this] { return pending_.load(std::memory_order_acquire) == 0; };
  if (spinFor(done)) return;
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, done);
}

void WorkerPool::workerLoop(int self) {
  std::uint64_t seen = 0;
  for (;;) {
    const auto fresh = [&] { return generation_.load(std::memory_order_acquire) != seen; };
    if (!spinFor(fresh)) {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, fresh);
    }
    seen = generation_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_acquire)) return;
    if (drain(self, seen)) {
      // This worker finished the job's last partition: wake the caller if it
      // blocks (under the mutex, so the wake-up cannot fall between its test
      // of pending_ and its wait).
      std::lock_guard<std::mutex> lock(mutex_);
      done_.notify_one();
    }
  }
}

}  // namespace gabion::micro
