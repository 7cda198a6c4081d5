// Macro speed: (1) one 0.2 s boulder impact on a 1,000-cell wall (10 x 10 x 10
// cells, x-only, illustrative laws) on one core; (2) a 10,000-point sweep on
// the same wall with `threads` worker threads, through the macro.sweep case
// kind (files included). Prints wall times beside the run's energy balance
// error. Run from the repository root:
//   build/bench/bench_macro_impact [cases/laws/illustrative.json] [threads] [sweep points]
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"
#include "bridge/run.hpp"
#include "macro/case_reader.hpp"
#include "macro/impact.hpp"
#include "macro/runs.hpp"

using namespace gabion;
using nlohmann::json;

namespace {

json wallCase(const std::string& law, int nx, int ny, int nz, double duration_s, const std::string& kinematics) {
  return {{"format", "gabion.case/1"},
          {"kind", "macro.impact"},
          {"law_file", std::filesystem::absolute(law).string()},
          {"structure",
           {{"cells", {nx, ny, nz}}, {"material", {{"front", "front"}, {"core", "core"}, {"front_depth_cells", 1}}}}},
          {"boulder", {{"diameter_m", 0.5}, {"density_kg_m3", 2600}, {"velocity_m_s", 20}}},
          {"run", {{"duration_s", duration_s}, {"time_step_fraction", 0.25}, {"kinematics", kinematics}}}};
}

// CPU time of this thread (s): on a shared, loaded machine it is what the run
// would take on a free core.
double threadCpu() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double seconds(std::chrono::steady_clock::time_point a) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

void impactTable(const std::string& law) {
  std::printf("%-12s %-7s %6s %7s %10s %10s %11s %14s %12s\n", "wall", "kin", "cells", "steps", "median_ms", "min_ms",
              "cpu_med_ms", "ns/cell-step", "balance_err");
  for (const char* kin : {"x-only", "3d"})
    for (int n : {5, 10, 15}) {
      const bridge::JsonDocument doc(wallCase(law, n, n, n, 0.2, kin), "bench");
      macro::ImpactCase c = macro::readImpactCase(doc, false);
      const macro::Structure s = macro::buildCaseStructure(doc, c);
      macro::resolveAims(doc, c, s);
      c.run.relax = false;
      std::vector<double> times, cpu;
      macro::ImpactResult r;
      for (int rep = 0; rep < 7; ++rep) {
        const auto t0 = std::chrono::steady_clock::now();
        const double c0 = threadCpu();
        macro::Model model(s, c.run.kinematics);
        r = macro::runImpact(model, c.impacts.front(), c.run, 0, nullptr);
        times.push_back(seconds(t0));
        cpu.push_back(threadCpu() - c0);
      }
      std::sort(times.begin(), times.end());
      std::sort(cpu.begin(), cpu.end());
      const double med = times[times.size() / 2];
      std::printf("%2dx%2dx%-6d %-7s %6zu %7lld %10.2f %10.2f %11.2f %14.2f %12.2e\n", n, n, n, kin, s.nodeCount(),
                  r.steps, 1e3 * med, 1e3 * times.front(), 1e3 * cpu[cpu.size() / 2],
                  1e9 * med / (static_cast<double>(r.steps) * s.nodeCount()), r.balance_rel_error);
      std::fflush(stdout);
    }
}

void sweep(const std::string& law, int threads, int points) {
  json c = wallCase(law, 10, 10, 10, 0.2, "x-only");
  c["kind"] = "macro.sweep";
  // velocity x mass grid of `points` points.
  const int nm = 10, nv = std::max(1, points / nm);
  c["sweep"] = {{"velocity_m_s", {{"from", 5}, {"to", 30}, {"count", nv}}},
                {"mass_kg", {{"from", 100}, {"to", 1000}, {"count", nm}}},
                {"chart", true}};
  const bridge::JsonDocument doc(c, "bench-sweep");
  bridge::RunContext ctx;
  ctx.outdir = std::filesystem::temp_directory_path() / "gabion_bench_macro_sweep";
  // (afresh: a folder with the rows of an earlier run of this sweep would be resumed, not run)
  std::filesystem::remove_all(ctx.outdir);
  std::filesystem::create_directories(ctx.outdir);
  ctx.threads = threads;
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  const auto out = macro::runSweepCase(doc, ctx);
  const double wall = seconds(t0);
  const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;  // all threads
  std::printf(
      "sweep: %d points (10x10x10 wall, each to its outcome), %d threads: %.1f s wall (%.1f points/s), %.1f s CPU "
      "(all threads), failed %s, outcomes %s, max balance error %.2e, files in %s\n",
      nm * nv, threads, wall, nm * nv / wall, cpu, out.results.at("failed_points").dump().c_str(),
      out.results.at("outcomes").dump().c_str(), out.results.at("balance_rel_error").get<double>(),
      ctx.outdir.string().c_str());
}

}  // namespace

int main(int argc, char** argv) {
  const std::string law = argc > 1 ? argv[1] : "cases/laws/illustrative.json";
  const int threads = argc > 2 ? std::atoi(argv[2]) : 2;
  const int points = argc > 3 ? std::atoi(argv[3]) : 10000;
  impactTable(law);
  if (points > 0) sweep(law, threads, points);
  return 0;
}
