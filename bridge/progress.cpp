#include <algorithm>
#include <cstdio>

#include "bridge/run.hpp"

namespace gabion::bridge {

Progress::Progress(bool enabled, std::string label, double delay_s)
    : enabled_(enabled), label_(std::move(label)), delay_s_(delay_s) {}

Progress::Progress(const RunContext& ctx, std::string label, double delay_s)
    : enabled_(ctx.progress),
      log_(ctx.progress_log),
      interval_s_(ctx.progress_log ? ctx.progress_log_interval_s : 0.25),  // (a terminal's: 4 times a second)
      label_(std::move(label)),
      context_(ctx.progress_context),
      delay_s_(ctx.progress_log ? std::max(delay_s, ctx.progress_log_interval_s) : delay_s) {}

void Progress::update(double done, double total, long long steps) {
  if (!enabled_ || (++calls_ & 63u) != 0) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (elapsed < delay_s_ || std::chrono::duration<double>(now - last_).count() < interval_s_) return;
  last_ = now;
  const double frac = total > 0 ? done / total : 0.0;
  const double eta = frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
  const std::string context = context_ ? context_(eta) + " " : std::string();
  std::fprintf(stdout, "%s%s%s %5.1f %%  t = %.4g / %.4g  %.3g steps/s  ETA %.0f s%s", log_ ? "" : "\r",
               context.c_str(), label_.c_str(), 100.0 * frac, done, total, static_cast<double>(steps) / elapsed, eta,
               log_ ? "\n" : "   ");
  std::fflush(stdout);
  printed_ = !log_;
}

void Progress::finish() {
  if (printed_) {
    std::fprintf(stdout, "\n");
    std::fflush(stdout);
    printed_ = false;
  }
}

}  // namespace gabion::bridge
