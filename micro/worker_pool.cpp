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

WorkerPool::WorkerPool(int threads) : threads_(threads < 1 ? 1 : threads) {
  next_.store(threads_, std::memory_order_relaxed);
  for (int t = 1; t < threads_; ++t) workers_.emplace_back([this] { workerLoop(); });
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

bool WorkerPool::drain() {
  bool finished_last = false;
  for (;;) {
    // acquire: pairs with the release store of next_ in run(), so job_ and
    // pending_ of this job are visible.
    const int t = next_.fetch_add(1, std::memory_order_acq_rel);
    if (t >= threads_) return finished_last;
    (*job_.load(std::memory_order_acquire))(t);
    finished_last = pending_.fetch_sub(1, std::memory_order_acq_rel) == 1;
  }
}

void WorkerPool::run(const std::function<void(int)>& job) {
  if (threads_ == 1) {
    job(0);
    return;
  }
  // Order matters: a worker still claiming from the previous job only sees
  // next_ >= threads_ until the release store below publishes this job.
  pending_.store(threads_, std::memory_order_relaxed);
  job_.store(&job, std::memory_order_relaxed);
  next_.store(0, std::memory_order_release);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.fetch_add(1, std::memory_order_acq_rel);
  }
  wake_.notify_all();
  drain();
  const auto done = [this] { return pending_.load(std::memory_order_acquire) == 0; };
  if (spinFor(done)) return;
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, done);
}

void WorkerPool::workerLoop() {
  unsigned seen = 0;
  for (;;) {
    const auto fresh = [&] { return generation_.load(std::memory_order_acquire) != seen; };
    if (!spinFor(fresh)) {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, fresh);
    }
    seen = generation_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_acquire)) return;
    if (drain()) {
      // This worker finished the job's last partition: wake the caller if it
      // blocks (under the mutex, so the wake-up cannot fall between its test
      // of pending_ and its wait).
      std::lock_guard<std::mutex> lock(mutex_);
      done_.notify_one();
    }
  }
}

}  // namespace gabion::micro
