#pragma once
/// \file
/// What a run will cost, before it runs: the rates measured on the
/// reference machine (2 cores, docs/performance.md), the cost of one micro
/// or macro run from its size, and the limits past which `gabion run`
/// refuses a case unless `--force` (docs/getting-started.md, "Cost").
#include <filesystem>
#include <string>

#include "bridge/run.hpp"

namespace gabion::bridge {

/// Fine DEM: seconds per body-step on one thread, bytes of memory per body
/// (27,000 spheres: 19 MB above the process's base), bytes per body per
/// snapshot record in result.h5 (position, velocity, angular velocity).
constexpr double kMicroSecondsPerBodyStep = 2.8e-8;
constexpr double kMicroBytesPerBody = 1000.0;
constexpr double kMicroSnapshotBytesPerBody = 100.0;
/// Fine DEM: bytes per body of a checkpoint's engine state (bodies,
/// contact histories, neighbour list, links), on top of the result rows it
/// copies: 174 MB for the 494,911 bodies of the 54-cell wall laced (351 a
/// body), rounded up (docs/getting-started.md, What a run will cost).
constexpr double kMicroCheckpointBytesPerBody = 400.0;
/// Fine DEM: seconds per link per sub-step of the link nodes, on one thread,
/// on top of the body-steps (a cell's 1,578 links at 8 sub-steps: 0.28 ms a
/// step of its confined compression).
constexpr double kMicroSecondsPerLinkSubstep = 2.2e-8;
/// Both rates hold while the scene's bodies fit the core's cache, up to
/// about kMicroCacheBodies block members and spheres (one cell); past that
/// each grows by its factor per e-fold of bodies: measured on one thread
/// (the stage table of `gabion run --threads 1`), a cell's confined
/// compression (9,129 bodies) gives 28 ns a body-step and 22 ns a link
/// sub-step; the resolved 12-cell wall (110,000) 67 and 31 ns; the 54-cell
/// wall (493,000) 79 and 38 ns (docs/getting-started.md, What a run will
/// cost). The estimate so comes within 5 % of both walls' step loops.
constexpr double kMicroCacheBodies = 1e4;
constexpr double kMicroBodyStepGrowth = 0.51;
constexpr double kMicroLinkSubstepGrowth = 0.18;
/// The seconds per body-step and per link sub-step on one thread, in a
/// scene of `bodies` bodies.
double microSecondsPerBodyStep(double bodies);
double microSecondsPerLinkSubstep(double bodies);
/// Structure scale: seconds per cell-step (a 1,000-cell impact, 525 steps,
/// 9.4 ms) and bytes per cell (measured on 1e6 cells).
constexpr double kMacroSecondsPerCellStep = 1.8e-8;
constexpr double kMacroBytesPerCell = 450.0;
/// The process itself (libraries, the case).
constexpr double kBaseBytes = 20e6;

/// One fine DEM run of `bodies` bodies (block members one by one: what
/// the time goes with), `steps` steps, `snapshots` snapshots of
/// `snapshot_records` records each (a block is one record), and `series`
/// samples of the scalar series; `link_substeps`: links times the link
/// nodes' sub-steps per step.
Estimate microRun(double bodies, double steps, double snapshots, double snapshot_records, double series,
                  double link_substeps = 0.0);
/// One structure impact on `cells` cells, at most `steps` steps, recording
/// `samples` samples of its 14 series.
Estimate macroRun(double cells, double steps, double samples);
/// Adds a run that follows `to` in the same process: steps, body-steps,
/// runs, snapshots, files and time add up; bodies, memory and checkpoints
/// are the larger (a run removes its checkpoint as it ends).
void addRun(Estimate& to, const Estimate& run);
/// `runs` copies of `one`, run in turn.
Estimate times(const Estimate& one, double runs);

/// "7,920 bodies, at most 48,000 steps, about 16 s on one thread, 40 MB of
/// memory, 120 MB of files (and up to 9 MB of checkpoints while it runs)".
std::string describe(const Estimate& e);

/// The limits: a run is refused (unless --force) past one day on one thread,
/// past 80 % of the machine's memory, or with more files and checkpoints
/// than the free space of the output folder's disk.
constexpr double kMaxWallTimeS = 24.0 * 3600.0;
constexpr double kMaxMemoryFraction = 0.8;
/// Beyond these the run says what it will cost before it starts.
constexpr double kAnnounceWallTimeS = 600.0;
constexpr double kAnnounceBytes = 1e9;

/// Why `e` is past a limit on this machine for a run into `outdir` (empty:
/// it is not).
std::string overLimits(const Estimate& e, const std::filesystem::path& outdir);

}  // namespace gabion::bridge
