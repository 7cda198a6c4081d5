#pragma once
/// \file
/// The clock of the engine's stage profile. It is read seven times a step,
/// and a step of a small netting lasts a few microseconds: steady_clock
/// (a system call's worth of work, through the vDSO) took 6 % of such a
/// step. On x86-64 the profile counts the processor's time-stamp counter
/// (constant-rate on the processors Gabion runs on) and converts the counts
/// to seconds against steady_clock over the clock's life; elsewhere it
/// counts steady_clock's own ticks.
#include <chrono>
#include <cstdint>
#if defined(__x86_64__)
#include <x86intrin.h>
#endif

namespace gabion::micro {

class TickClock {
 public:
  TickClock() : t0_(std::chrono::steady_clock::now()), c0_(now()) {}

  /// The count now.
  static std::uint64_t now() {
#if defined(__x86_64__)
    return __rdtsc();
#else
    return static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
#endif
  }

  /// Seconds per count, as measured since the clock was made (0 before any
  /// count went by).
  double secondsPerTick() const {
    const std::uint64_t counts = now() - c0_;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    return counts > 0 ? s / static_cast<double>(counts) : 0.0;
  }

 private:
  std::chrono::steady_clock::time_point t0_;
  std::uint64_t c0_;
};

}  // namespace gabion::micro
