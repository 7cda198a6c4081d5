#pragma once
/// \file
/// Independent tasks (the rows of a sweep, sections of a design search) on
/// worker threads: each task writes only its own slot, so the results do not
/// depend on the thread count. The calling thread works too and reports the
/// progress. An exception in a task is rethrown on the calling thread once
/// every thread has stopped (the remaining tasks are skipped).
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "bridge/run.hpp"

namespace gabion::bridge {

template <class Task>
void runParallel(std::size_t n, int threads, Progress& progress, const Task& task) {
  std::atomic<std::size_t> next{0}, done{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&](bool report) {
    for (std::size_t i = next++; i < n; i = next++) {
      try {
        task(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;
      }
      ++done;
      if (report)
        progress.update(static_cast<double>(done.load()), static_cast<double>(n), static_cast<long long>(done.load()));
    }
  };
  const int nthreads = std::max(1, std::min<int>(threads, static_cast<int>(n)));
  std::vector<std::thread> pool;
  for (int t = 1; t < nthreads; ++t) pool.emplace_back(work, false);
  work(true);
  for (auto& th : pool) th.join();
  progress.finish();
  if (error) std::rethrow_exception(error);
}

}  // namespace gabion::bridge
