// How long one cache line takes to go from one core to another and back
// (docs/performance.md, settling benchmark, What is timed and Results):
// two threads, pinned to CPUs A and B, pass a counter back and forth
// through one atomic on its own cache line.
// Every hand-over moves the line between the two cores' caches, as a
// worker pool's start and join do, and as the contact stage's force
// buffers and the integrator's neighbouring ranges do at each step. Prints
// the round trip in ns, best of several batches. Not a test: a measurement.
//   build/bench/bench_core_round_trip [--cpus A,B] [--trips N] [--batches K]
// Two cores that share a cache level exchange a line in tens of ns; on a
// virtual machine whose two CPUs lie on separate dies, in hundreds, and
// every step of a two-thread run pays it several times.
// Then how fast the two CPUs compute together against one alone
// (independent multiply-adds, no memory): about 1 for two idle cores; well
// below for the two hardware threads of one core, which share its
// arithmetic units, or for cores that other work on the host slows (a
// virtual machine's two CPUs can be any of these, and a two-thread run then
// gains little). Then each CPU alone reading memory (random reads over a
// 16 MiB table, more than a core's own caches hold): B's speed over A's. A host's other work can slow one
// CPU's memory side (a shared cache, the memory path) while its arithmetic
// runs at full speed: the settling run at N = 5,000 was seen 30 % slower on
// one of the two CPUs than on the other, and a one-thread run then depends
// on which of them it lands on. One line each; the second starts "CPUs A
// and B computing together", the third "CPUs A and B alone, reading memory".
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <thread>
#include <vector>

namespace {

struct alignas(64) Line {
  std::atomic<long> value{0};
};

bool pin(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

// Independent multiply-add chains, enough to keep a core's arithmetic units
// busy (no memory traffic); seconds taken, the result into `sink`.
double computeFor(long rounds, double& sink) {
  constexpr int kChains = 64;
  double a[kChains];
  for (int k = 0; k < kChains; ++k) a[k] = 1.0 + 0.01 * k;
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < rounds; ++i)
    for (double& x : a) x = x * 0.9999999 + 1e-9;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const double x : a) sink += x;
  return s;
}

// Speed of CPUs a and b computing at once over that of a alone (best of
// three each: the slower of the two at once).
double togetherOverAlone(int cpu_a, int cpu_b) {
  constexpr long kRounds = 5000000;
  double sink = 0.0, alone = std::numeric_limits<double>::infinity(), both = alone;
  for (int r = 0; r < 3; ++r) {
    double t = 0.0;
    std::thread one([&] { pin(cpu_a), t = computeFor(kRounds, sink); });
    one.join();
    alone = std::min(alone, t);
  }
  for (int r = 0; r < 3; ++r) {
    std::atomic<int> ready{0};
    double ta = 0.0, tb = 0.0, sink_b = 0.0;
    const auto run = [&](int cpu, double& t, double& out) {
      pin(cpu);
      ready.fetch_add(1);
      while (ready.load() < 2) {
      }
      t = computeFor(kRounds, out);
    };
    std::thread x([&] { run(cpu_a, ta, sink); });
    std::thread y([&] { run(cpu_b, tb, sink_b); });
    x.join(), y.join();
    sink += sink_b;
    both = std::min(both, std::max(ta, tb));
  }
  if (sink == 0.0) std::printf(" ");  // (keeps the arithmetic)
  return alone / both;
}

// Seconds per random read of a table of 16 MiB, on `cpu` alone (best of
// five passes of a million reads; the table is filled on that CPU).
double readTime(int cpu) {
  double t = std::numeric_limits<double>::infinity();
  std::thread one([&] {
    pin(cpu);
    constexpr std::size_t kN = std::size_t{1} << 21, kReads = std::size_t{1} << 20;
    std::vector<double> table(kN);
    std::vector<std::uint32_t> at(kReads);
    for (std::size_t i = 0; i < kN; ++i) table[i] = static_cast<double>(i);
    for (std::size_t i = 0; i < kReads; ++i) at[i] = static_cast<std::uint32_t>((i * 2654435761u) % kN);
    double sink = 0.0;
    for (int pass = 0; pass < 6; ++pass) {
      const auto start = std::chrono::steady_clock::now();
      for (const std::uint32_t k : at) sink += table[k];
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (pass > 0) t = std::min(t, s / static_cast<double>(kReads));  // (the first warms the table)
    }
    if (sink == 0.0) std::printf(" ");  // (keeps the reads)
  });
  one.join();
  return t;
}

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "bench_core_round_trip: %s\nusage: bench_core_round_trip [--cpus A,B] [--trips N] [--batches K]\n", why);
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  int cpu_a = 0, cpu_b = 1;
  long trips = 200000;
  int batches = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) usage(("missing value after " + arg).c_str());
    const char* v = argv[++i];
    if (arg == "--cpus") {
      if (std::sscanf(v, "%d,%d", &cpu_a, &cpu_b) != 2 || cpu_a < 0 || cpu_b < 0 || cpu_a == cpu_b)
        usage("--cpus wants two different CPU numbers, A,B");
    } else if (arg == "--trips") {
      trips = std::atol(v);
      if (trips < 1000) usage("--trips wants at least 1000");
    } else if (arg == "--batches") {
      batches = std::atoi(v);
      if (batches < 1) usage("--batches wants at least 1");
    } else {
      usage(("unknown option " + arg).c_str());
    }
  }

  if (std::thread::hardware_concurrency() < 2) {
    std::fprintf(stderr, "bench_core_round_trip: one CPU only: nothing to measure\n");
    return 1;
  }
  Line line;
  std::atomic<int> partner_state{0};  // 1: pinned, 2: could not pin
  constexpr long kStop = -1;          // the caller could not pin: the partner leaves
  // The partner answers each odd value with the next even one. Both
  // threads are pinned before the first hand-over: unpinned on one CPU,
  // each hand-over would wait for a time slice.
  std::thread partner([&] {
    const bool pinned = pin(cpu_b);
    partner_state.store(pinned ? 1 : 2);
    if (!pinned) return;
    const long last = 2 * trips * batches;
    for (long expect = 1; expect < last; expect += 2) {
      long seen;
      while ((seen = line.value.load(std::memory_order_acquire)) != expect)
        if (seen == kStop) return;
      line.value.store(expect + 1, std::memory_order_release);
    }
  });
  const bool pinned_a = pin(cpu_a);
  while (partner_state.load() == 0) {
  }
  if (!pinned_a || partner_state.load() != 1) {
    line.value.store(kStop, std::memory_order_release);
    partner.join();
    std::fprintf(stderr, "bench_core_round_trip: could not pin to CPUs %d and %d (not both online?)\n", cpu_a, cpu_b);
    return 1;
  }
  double best = std::numeric_limits<double>::infinity(), worst = 0.0;
  long v = 0;
  for (int b = 0; b < batches; ++b) {
    const auto start = std::chrono::steady_clock::now();
    for (long k = 0; k < trips; ++k) {
      line.value.store(++v, std::memory_order_release);
      ++v;
      while (line.value.load(std::memory_order_acquire) != v) {
      }
    }
    const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count() /
                      static_cast<double>(trips);
    best = std::min(best, ns);
    worst = std::max(worst, ns);
  }
  partner.join();
  std::printf("cache-line round trip between CPUs %d and %d: %.0f ns (best of %d batches of %ld; worst %.0f ns)\n",
              cpu_a, cpu_b, best, batches, trips, worst);
  std::printf("CPUs %d and %d computing together: %.2f of the speed of one alone\n", cpu_a, cpu_b,
              togetherOverAlone(cpu_a, cpu_b));
  const double read_a = readTime(cpu_a), read_b = readTime(cpu_b);
  std::printf("CPUs %d and %d alone, reading memory: CPU %d at %.2f of CPU %d's speed (%.2f and %.2f ns a read)\n",
              cpu_a, cpu_b, cpu_b, read_a / read_b, cpu_a, 1e9 * read_a, 1e9 * read_b);
  return 0;
}
