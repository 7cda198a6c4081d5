#include "micro/worker_pool.hpp"

namespace gabion::micro {

WorkerPool::WorkerPool(int threads) : threads_(threads < 1 ? 1 : threads) {
  for (int t = 1; t < threads_; ++t) workers_.emplace_back([this, t] { workerLoop(t); });
}

WorkerPool::~WorkerPool() {
  stop_.store(true, std::memory_order_release);
  generation_.fetch_add(1, std::memory_order_acq_rel);
  for (auto& w : workers_) w.join();
}

void WorkerPool::run(const std::function<void(int)>& job) {
  if (threads_ == 1) {
    job(0);
    return;
  }
  job_ = &job;
  pending_.store(threads_ - 1, std::memory_order_release);
  generation_.fetch_add(1, std::memory_order_acq_rel);
  job(0);
  unsigned spins = 0;
  while (pending_.load(std::memory_order_acquire) != 0)
    if (++spins > 2000) std::this_thread::yield();
}

void WorkerPool::workerLoop(int t) {
  unsigned seen = 0;
  for (;;) {
    unsigned spins = 0;
    unsigned g;
    while ((g = generation_.load(std::memory_order_acquire)) == seen)
      if (++spins > 2000) std::this_thread::yield();
    seen = g;
    if (stop_.load(std::memory_order_acquire)) return;
    (*job_)(t);
    pending_.fetch_sub(1, std::memory_order_acq_rel);
  }
}

}  // namespace gabion::micro
