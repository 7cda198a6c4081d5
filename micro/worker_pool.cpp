#include "micro/worker_pool.hpp"

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

WorkerPool::WorkerPool(int threads)
    : threads_(threads < 1 ? 1 : threads),
      claimed_(new std::atomic<std::uint64_t>[static_cast<std::size_t>(threads_)]) {
  for (int t = 0; t < threads_; ++t) claimed_[static_cast<std::size_t>(t)].store(0, std::memory_order_relaxed);
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
  // worker still here from an earlier job finds every partition claimed by
  // that job or a later one, and claims nothing.
  bool finished_last = false;
  for (int k = 0; k < threads_; ++k) {
    const int t = (self + k) % threads_;
    std::atomic<std::uint64_t>& c = claimed_[static_cast<std::size_t>(t)];
    std::uint64_t seen = c.load(std::memory_order_relaxed);
    if (seen >= generation || !c.compare_exchange_strong(seen, generation, std::memory_order_acq_rel)) continue;
    (*job_.load(std::memory_order_acquire))(t);
    finished_last = pending_.fetch_sub(1, std::memory_order_acq_rel) == 1;
  }
  return finished_last;
}

void WorkerPool::run(const std::function<void(int)>& job) {
  if (threads_ == 1) {
    job(0);
    return;
  }
  // Order matters: job_ and pending_ are published by the release of the
  // generation bump; partitions are claimable only with the new generation.
  pending_.store(threads_, std::memory_order_relaxed);
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
