#include "micro/worker_pool.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

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
      shares_(new Share[static_cast<std::size_t>(threads_)]),
      ran_(new Ran[static_cast<std::size_t>(threads_)]) {
  for (int u = 0; u < threads_; ++u)
    ran_[static_cast<std::size_t>(u)].list.reserve(static_cast<std::size_t>(partitions_));
  share_begin_.resize(static_cast<std::size_t>(threads_) + 1);
  for (int u = 0; u <= threads_; ++u)
    share_begin_[static_cast<std::size_t>(u)] = static_cast<std::uint32_t>(partitions_ * u / threads_);
  for (int t = 1; t < threads_; ++t) workers_.emplace_back([this, t] { workerLoop(t); });
}

void WorkerPool::setShares(const std::vector<int>& begin) {
  if (begin.size() != share_begin_.size() || begin.front() != 0 || begin.back() != partitions_)
    throw std::invalid_argument("WorkerPool::setShares: threads + 1 boundaries from 0 to the partitions");
  for (std::size_t u = 0; u + 1 < begin.size(); ++u)
    if (begin[u + 1] <= begin[u]) throw std::invalid_argument("WorkerPool::setShares: an empty share");
  // (no job runs: the next one's generation bump publishes them)
  for (std::size_t u = 0; u < begin.size(); ++u) share_begin_[u] = static_cast<std::uint32_t>(begin[u]);
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
  const auto T = static_cast<std::uint32_t>(threads_);
  std::vector<int>& ran = ran_[static_cast<std::size_t>(self)].list;
  ran.clear();
  const bool tails = take_tails_.load(std::memory_order_relaxed);
  for (std::uint32_t k = 0; k < T; ++k) {
    const std::uint32_t u = (static_cast<std::uint32_t>(self) + T - k) % T;
    std::atomic<std::uint64_t>& state = shares_[u].state;
    std::uint64_t s = state.load(std::memory_order_acquire);
    bool mine = k == 0;  // its own share, or one it opened in this job
    for (;;) {
      const auto d = static_cast<std::int32_t>(static_cast<std::uint32_t>(s >> 32) - gen);
      if (d > 0) break;                      // a later job's
      if (d == 0 && !mine && !tails) break;  // its owner has started it and runs it to the end
      // (d < 0: not opened in this job yet, the whole share)
      std::uint32_t first = d < 0 ? share_begin_[u] : static_cast<std::uint32_t>(s >> 16) & 0xffffu;
      std::uint32_t end = d < 0 ? share_begin_[u + 1] : static_cast<std::uint32_t>(s) & 0xffffu;
      if (first >= end) break;
      const std::uint32_t t = k == 0 ? first++ : --end;
      const std::uint64_t next = std::uint64_t{gen} << 32 | std::uint64_t{first} << 16 | end;
      if (!state.compare_exchange_weak(s, next, std::memory_order_acq_rel, std::memory_order_acquire)) continue;
      mine = mine || d < 0;
      (*job_.load(std::memory_order_acquire))(static_cast<int>(t), self);
      ran.push_back(static_cast<int>(t));
      s = next;  // (a failed exchange below reloads it)
    }
  }
  if (ran.empty()) return false;
  if (then_ != nullptr) (*then_)(self, ran);
  const auto n = static_cast<int>(ran.size());
  return pending_.fetch_sub(n, std::memory_order_acq_rel) == n;
}

void WorkerPool::run(const std::function<void(int, int)>& job, bool take_tails, const Then& then) {
  if (threads_ == 1) {
    std::vector<int>& ran = ran_[0].list;
    ran.clear();
    for (int t = 0; t < partitions_; ++t) job(t, 0), ran.push_back(t);
    if (then) then(0, ran);
    return;
  }
  // Order matters: job_, then_ and pending_ are published by the release of
  // the generation bump; shares open only with the new generation.
  pending_.store(partitions_, std::memory_order_relaxed);
  then_ = then ? &then : nullptr;
  job_.store(&job, std::memory_order_relaxed);
  take_tails_.store(take_tails, std::memory_order_relaxed);
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

std::vector<int> sharesForSpeeds(const std::vector<double>& speed, const std::vector<int>& current, int partitions,
                                 double gain) {
  const int T = static_cast<int>(speed.size());
  double total = 0.0;
  for (const double v : speed) total += v;
  if (T < 2 || partitions < T || !(total > 0.0) || !std::isfinite(total)) return current;
  for (const double v : speed)
    if (!(v > 0.0)) return current;
  std::vector<int> begin(static_cast<std::size_t>(T) + 1, 0);
  begin.back() = partitions;
  double acc = 0.0;
  for (int u = 1; u < T; ++u) {
    acc += speed[static_cast<std::size_t>(u) - 1];
    const auto b = static_cast<int>(std::lround(partitions * acc / total));
    begin[static_cast<std::size_t>(u)] =
        std::clamp(b, begin[static_cast<std::size_t>(u) - 1] + 1, partitions - (T - u));
  }
  // the job ends with its slowest share
  const auto span = [&](const std::vector<int>& b) {
    double worst = 0.0;
    for (std::size_t u = 0; u + 1 < b.size(); ++u) worst = std::max(worst, (b[u + 1] - b[u]) / speed[u]);
    return worst;
  };
  if (current.size() != begin.size()) return begin;
  return span(begin) < (1.0 - gain) * span(current) ? begin : current;
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
