// What does one parallel stage of the micro engine's worker pool cost?
// Times an empty WorkerPool::run and runs whose two partitions do about 65 us
// of arithmetic each, against one such partition run serially.
// docs/micro.md (Speed) quotes it.
//   g++ -O2 -std=c++17 -I. bench/machine/pool_overhead.cpp micro/worker_pool.cpp -pthread -o /tmp/pool_overhead
//   /tmp/pool_overhead
#include <atomic>
#include <chrono>
#include <cstdio>

#include "micro/worker_pool.hpp"

namespace {
double seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}
void arithmetic() {
  volatile double x = 1.0;
  for (int k = 0; k < 20000; ++k) x = x * 1.0000001;
}
}  // namespace

int main() {
  gabion::micro::WorkerPool pool(2);
  std::atomic<long> sink{0};
  for (int rep = 0; rep < 3; ++rep) {
    constexpr int kEmpty = 100000, kBusy = 20000;
    auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kEmpty; ++i) pool.run([&](int t, int) { sink += t; });
    auto t1 = std::chrono::steady_clock::now();
    std::printf("empty run: %.2f us\n", seconds(t0, t1) / kEmpty * 1e6);
    t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kBusy; ++i) pool.run([&](int t, int) { arithmetic(), sink += t; });
    t1 = std::chrono::steady_clock::now();
    for (int i = 0; i < kBusy; ++i) arithmetic();
    const auto t2 = std::chrono::steady_clock::now();
    std::printf("two busy partitions: %.2f us per run; one partition serially: %.2f us\n",
                seconds(t0, t1) / kBusy * 1e6, seconds(t1, t2) / kBusy * 1e6);
  }
  return 0;
}
