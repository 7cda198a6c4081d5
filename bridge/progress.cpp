#include <cstdio>

#include "bridge/run.hpp"

namespace gabion::bridge {

Progress::Progress(bool enabled, std::string label, double delay_s)
    : enabled_(enabled), label_(std::move(label)), delay_s_(delay_s) {}

Progress::Progress(const RunContext& ctx, std::string label, double delay_s)
    : enabled_(ctx.progress), label_(std::move(label)), context_(ctx.progress_context), delay_s_(delay_s) {}

void Progress::update(double done, double total, long long steps) {
  if (!enabled_ || (++calls_ & 63u) != 0) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (elapsed < delay_s_ || std::chrono::duration<double>(now - last_).count() < 0.25) return;
  last_ = now;
  const double frac = total > 0 ? done / total : 0.0;
  const double eta = frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
  const std::string context = context_ ? context_(eta) + " " : std::string();
  std::fprintf(stdout, "\r%s%s %5.1f %%  t = %.4g / %.4g  %.3g steps/s  ETA %.0f s   ", context.c_str(), label_.c_str(),
               100.0 * frac, done, total, static_cast<double>(steps) / elapsed, eta);
  std::fflush(stdout);
  printed_ = true;
}

void Progress::finish() {
  if (printed_) {
    std::fprintf(stdout, "\n");
    std::fflush(stdout);
    printed_ = false;
  }
}

}  // namespace gabion::bridge
