// Why the settling benchmark's integration does not scale on two threads
// (docs/performance.md, "Two threads at N = 5,000"): the integrator's
// pass over 21 arrays of N doubles (the free spheres' kick and drift, the
// displacement test), stepped with a barrier between steps, timed per
// thread in three layouts:
//   one     one thread over all N (the one-thread run);
//   halves  two threads, each over its half of the same arrays (as the
//           engine's workers share the particle store);
//   own     two threads, each over arrays of its own of N/2.
// Prints ns per particle-step for each thread. Not a test: a measurement.
//   build/bench/bench_stream_halves [--n N] [--steps S] [--aligned] [--gap G]
// --aligned allocates every array on a page boundary (the same offset in
// every page), as large std::vectors are; --gap leaves G doubles unused
// between the two halves.
// With --aligned and N a multiple of 16 (--n 5008) the halves meet on a
// whole cache line, and run as fast as arrays of their own; with N = 5,000
// the halves share one line of each array, which both threads write at
// every step. That is why the engine's store is line-aligned and its
// workers' ranges are cut at multiples of eight particles
// (micro/particles.hpp, lineStart in micro/engine.cpp).
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

namespace {

constexpr int kArrays = 21;

struct Arrays {
  std::vector<double*> a;
  std::vector<void*> owned;
  Arrays(std::size_t n, bool aligned) {
    for (int k = 0; k < kArrays; ++k) {
      void* p = nullptr;
      if (aligned) {
        if (posix_memalign(&p, 4096, n * sizeof(double)) != 0) std::abort();
      } else {
        p = std::malloc(n * sizeof(double));
      }
      owned.push_back(p);
      a.push_back(static_cast<double*>(p));
      for (std::size_t i = 0; i < n; ++i) a.back()[i] = 1.0 + 1e-3 * static_cast<double>(k);
    }
  }
  ~Arrays() {
    for (void* p : owned) std::free(p);
  }
  Arrays(const Arrays&) = delete;
  Arrays& operator=(const Arrays&) = delete;
};

// One step over [b, e): kick and drift of position x (0-2), velocity v (3-5)
// and angular velocity w (6-8) under force f (9-11) and torque t (12-14),
// and the largest displacement from x0 (15-17); 18-20 untouched (the
// other fields of the store). The integrator's arithmetic and traffic.
[[gnu::noinline]] double pass(double* const* a, std::size_t b, std::size_t e) {
  double* __restrict x = a[0];
  double* __restrict y = a[1];
  double* __restrict z = a[2];
  double* __restrict vx = a[3];
  double* __restrict vy = a[4];
  double* __restrict vz = a[5];
  double* __restrict wx = a[6];
  double* __restrict wy = a[7];
  double* __restrict wz = a[8];
  const double* __restrict fx = a[9];
  const double* __restrict fy = a[10];
  const double* __restrict fz = a[11];
  const double* __restrict tx = a[12];
  const double* __restrict ty = a[13];
  const double* __restrict tz = a[14];
  const double* __restrict x0 = a[15];
  const double* __restrict y0 = a[16];
  const double* __restrict z0 = a[17];
  constexpr double dt = 1e-6, im = 1e-2, ii = 1e-1;
  double d2 = 0.0;
#pragma omp simd reduction(max : d2)
  for (std::size_t i = b; i < e; ++i) {
    vx[i] += dt * im * fx[i], vy[i] += dt * im * fy[i], vz[i] += dt * im * fz[i];
    x[i] += dt * vx[i], y[i] += dt * vy[i], z[i] += dt * vz[i];
    const double ex = x[i] - x0[i], ey = y[i] - y0[i], ez = z[i] - z0[i];
    d2 = std::max(d2, ex * ex + ey * ey + ez * ez);
  }
#pragma omp simd
  for (std::size_t i = b; i < e; ++i) wx[i] += dt * ii * tx[i], wy[i] += dt * ii * ty[i], wz[i] += dt * ii * tz[i];
  return d2;
}

// Runs `threads` threads for `steps` steps, thread t over arrays[t] in
// [range[t].first, range[t].second), a spin barrier between steps; returns
// each thread's time in the pass (s).
std::vector<double> run(int threads, const std::vector<const Arrays*>& arrays,
                        const std::vector<std::pair<std::size_t, std::size_t>>& range, int steps) {
  std::atomic<int> arrived{0};
  std::vector<double> busy(static_cast<std::size_t>(threads) * 8, 0.0), sink(busy.size(), 0.0);
  const auto work = [&](int t) {
    const auto k = static_cast<std::size_t>(t);
    for (int s = 0; s < steps; ++s) {
      const auto start = std::chrono::steady_clock::now();
      sink[8 * k] += pass(arrays[k]->a.data(), range[k].first, range[k].second);
      busy[8 * k] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      arrived.fetch_add(1);
      while (arrived.load() < (s + 1) * threads) {
      }
    }
  };
  std::vector<std::thread> others;
  for (int t = 1; t < threads; ++t) others.emplace_back(work, t);
  work(0);
  for (auto& th : others) th.join();
  std::vector<double> out;
  for (int t = 0; t < threads; ++t) out.push_back(busy[8 * static_cast<std::size_t>(t)]);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t n = 5000, gap = 0;
  int steps = 20000;
  bool aligned = false;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--n" && k + 1 < argc) {
      n = std::strtoul(argv[++k], nullptr, 10);
    } else if (a == "--steps" && k + 1 < argc) {
      steps = std::atoi(argv[++k]);
    } else if (a == "--gap" && k + 1 < argc) {
      gap = std::strtoul(argv[++k], nullptr, 10);
    } else if (a == "--aligned") {
      aligned = true;
    } else {
      std::fprintf(stderr, "usage: bench_stream_halves [--n N] [--steps S] [--aligned] [--gap G]\n");
      return 2;
    }
  }
  const std::size_t half = n / 2;
  const auto report = [&](const char* layout, const std::vector<double>& busy, std::size_t per_thread) {
    std::printf("%-7s", layout);
    for (std::size_t t = 0; t < busy.size(); ++t)
      std::printf("  thread %zu: %.2f ns/particle-step", t, 1e9 * busy[t] / steps / static_cast<double>(per_thread));
    std::printf("\n");
  };
  std::printf("%d arrays of %zu doubles%s, %d steps, halves %zu doubles apart\n", kArrays, n,
              aligned ? " (page-aligned)" : "", steps, gap);
  {
    const Arrays all(n + gap, aligned);
    report("one", run(1, {&all}, {{0, n}}, steps), n);
    report("halves", run(2, {&all, &all}, {{0, half}, {half + gap, n + gap}}, steps), half);
  }
  const Arrays mine(half, aligned), yours(half, aligned);
  report("own", run(2, {&mine, &yours}, {{0, half}, {0, half}}, steps), half);
  return 0;
}
