#include "bridge/cost.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "bridge/units.hpp"

namespace gabion::bridge {

namespace {
// One run: its size and steps; the kinds' rates fill the rest.
Estimate oneRun(double bodies, double steps, double snapshots) {
  Estimate e;
  e.bodies = bodies;
  e.steps = steps;
  e.body_steps = bodies * steps;
  e.runs = 1;
  e.snapshots = snapshots;
  return e;
}

// (1 while the scene fits the cache, then 1 + growth per e-fold of bodies)
double cacheFactor(double bodies, double growth) {
  return bodies > kMicroCacheBodies ? 1.0 + growth * std::log(bodies / kMicroCacheBodies) : 1.0;
}
}  // namespace

double microSecondsPerBodyStep(double bodies) {
  return kMicroSecondsPerBodyStep * cacheFactor(bodies, kMicroBodyStepGrowth);
}

double microSecondsPerLinkSubstep(double bodies) {
  return kMicroSecondsPerLinkSubstep * cacheFactor(bodies, kMicroLinkSubstepGrowth);
}

Estimate microRun(double bodies, double steps, double snapshots, double snapshot_records, double series,
                  double link_substeps) {
  Estimate e = oneRun(bodies, steps, snapshots);
  e.memory_bytes = kBaseBytes + kMicroBytesPerBody * bodies;
  // (the series: about 40 columns of doubles)
  e.output_bytes = kMicroSnapshotBytesPerBody * snapshot_records * snapshots + 40.0 * 8.0 * series;
  // (saved on a signal if not before: the state, and the rows so far, at most the run's)
  e.checkpoint_bytes = kMicroCheckpointBytesPerBody * bodies + e.output_bytes;
  e.wall_time_s =
      microSecondsPerBodyStep(bodies) * e.body_steps + microSecondsPerLinkSubstep(bodies) * link_substeps * steps;
  return e;
}

Estimate macroRun(double cells, double steps, double samples) {
  Estimate e = oneRun(cells, steps, samples);
  // (the recording is held until the run ends: 14 series of doubles)
  e.memory_bytes = kBaseBytes + kMacroBytesPerCell * cells + 14.0 * 8.0 * samples;
  e.output_bytes = 14.0 * 8.0 * samples + 100.0 * cells;
  e.wall_time_s = kMacroSecondsPerCellStep * e.body_steps;
  return e;
}

void addRun(Estimate& to, const Estimate& run) {
  to.bodies = std::max(to.bodies, run.bodies);
  to.steps += run.steps;
  to.body_steps += run.body_steps;
  to.runs += run.runs;
  to.snapshots += run.snapshots;
  to.memory_bytes = std::max(to.memory_bytes, run.memory_bytes);
  to.output_bytes += run.output_bytes;
  to.checkpoint_bytes = std::max(to.checkpoint_bytes, run.checkpoint_bytes);
  to.wall_time_s += run.wall_time_s;
  to.partial = to.partial || run.partial;
}

Estimate times(const Estimate& one, double runs) {
  Estimate e = one;
  e.steps *= runs;
  e.body_steps *= runs;
  e.runs = static_cast<std::size_t>(std::llround(static_cast<double>(one.runs) * runs));
  e.snapshots *= runs;
  e.output_bytes *= runs;
  e.wall_time_s *= runs;
  return e;
}

namespace {
std::string bytes(double b) {
  if (b >= 1e9) return showNumber(b / 1e9, 3) + " GB";
  if (b >= 1e6) return showNumber(b / 1e6, 3) + " MB";
  return showNumber(b / 1e3, 3) + " kB";
}
std::string duration(double s) {
  if (s >= 2.0 * 86400.0) return showNumber(s / 86400.0, 3) + " days";
  if (s >= 2.0 * 3600.0) return showNumber(s / 3600.0, 3) + " h";
  if (s >= 120.0) return showNumber(s / 60.0, 3) + " min";
  return showNumber(s, 2) + " s";
}
double physicalMemory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

std::string count(double n) {
  if (n < 1e9) return std::to_string(std::llround(n));
  return showNumber(n, 3);
}
}  // namespace

std::string describe(const Estimate& e) {
  std::ostringstream os;
  os << count(e.bodies) << " bodies, at most " << count(e.steps) << " steps";
  if (e.runs > 1) os << " over " << e.runs << " runs";
  os << ", up to " << duration(e.wall_time_s) << " on one thread, " << bytes(e.memory_bytes) << " of memory, "
     << bytes(e.output_bytes) << " of files";
  if (e.checkpoint_bytes > 0.0) os << " (and up to " << bytes(e.checkpoint_bytes) << " of checkpoints while it runs)";
  if (e.partial) os << " (and what cannot be costed before it runs)";
  return os.str();
}

std::string overLimits(const Estimate& e, const std::filesystem::path& outdir) {
  std::ostringstream why;
  if (e.wall_time_s > kMaxWallTimeS) why << "it may take " << duration(e.wall_time_s) << ", more than a day";
  const double memory = physicalMemory();
  if (memory > 0.0 && e.memory_bytes > kMaxMemoryFraction * memory)
    why << (why.tellp() > 0 ? "; " : "") << "it needs " << bytes(e.memory_bytes) << " of memory, more than "
        << showNumber(100.0 * kMaxMemoryFraction, 2) << " % of this machine's " << bytes(memory);
  std::error_code ec;
  std::filesystem::path probe = outdir;
  while (!probe.empty() && !std::filesystem::exists(probe, ec)) probe = probe.parent_path();
  const auto space = std::filesystem::space(probe.empty() ? std::filesystem::path(".") : probe, ec);
  const double disk = e.output_bytes + e.checkpoint_bytes;
  if (!ec && disk > static_cast<double>(space.available))
    why << (why.tellp() > 0 ? "; " : "") << "it writes " << bytes(e.output_bytes) << " of files"
        << (e.checkpoint_bytes > 0.0 ? " and up to " + bytes(e.checkpoint_bytes) + " of checkpoints" : "")
        << ", and the disk of " << outdir.string() << " has " << bytes(static_cast<double>(space.available)) << " free";
  return why.str();
}

}  // namespace gabion::bridge
