#pragma once
/// \file
/// Running a scene as a case: the engine stepped to the run's duration with
/// its series, snapshots, link tables, energy ledger and stage profile
/// written to result.h5 / result.xdmf, and the summary every micro case
/// kind shares (docs/micro.md, Output). The lab tests and the netting test
/// are scenes with hooks: series of their own, an end of their own.
#include <filesystem>
#include <functional>
#include <string>

#include "bridge/output.hpp"
#include "bridge/run.hpp"
#include "bridge/state_archive.hpp"
#include "micro/engine.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// What a case kind adds to the scene run (micro.scene adds nothing).
struct SceneRunHooks {
  std::string label = "micro.scene";  ///< shown on the progress line
  /// Once the engine is built, before the first step (also of a resumed
  /// run, before its checkpoint loads): e.g. the driver of its Driven walls.
  std::function<void(Engine&)> start;
  /// After each series sample (engine state after the step that started at t).
  std::function<void(const Engine&, double t)> record;
  /// After each series sample, before `done`: the test steers its walls
  /// (Engine::setWallProgram), e.g. to unload and reload.
  std::function<void(Engine&)> control;
  /// After each series sample: true when the test is over (the run ends
  /// there with ended_by = "test").
  std::function<bool(const Engine&)> done;
  /// Before the result file is committed: the kind's own datasets.
  std::function<void(const Engine&, bridge::H5Writer&)> write;
  /// The kind's own state (its curves, its phase), into or out of a
  /// checkpoint (micro/checkpoint.hpp): a kind whose hooks keep state must
  /// list it here, or a resumed run would not be the run it continues.
  std::function<void(bridge::StateArchive&)> archive;
  /// At the end of a run that did not fail, with the scene the engine was
  /// built from (e.g. to take its state, micro/cell/cell_file.hpp stateScene).
  std::function<void(const Engine&, const Scene&)> end;
  /// A stage of a longer run (micro.structure's landing and settling): at
  /// its end, if it did not fail, its state is saved as a checkpoint and
  /// kept, so that the longer run, stopped in a later stage and resumed,
  /// takes this stage's end from it (the same arrays, `end` called on the
  /// engine loaded) instead of running it again. The kind removes it when
  /// the whole run is over (removeKeptEnd).
  bool keep_end = false;
};

/// Removes the end state a stage run into `outdir` kept (keep_end).
void removeKeptEnd(const std::filesystem::path& outdir);

/// The step to use: run.dt_s if given (refused above the critical step unless
/// run.allow_dt_above_critical, the error naming `file`), else
/// run.dt_safety x critical.
double chooseDt(const Scene& scene, double critical, const std::string& file);

/// What running `scene` at step `dt` costs (bridge/cost.hpp): its bodies
/// (block members one by one), steps, snapshots and series samples.
bridge::Estimate sceneEstimate(const Scene& scene, double dt);

/// The most steps a run may take: more is an input error before it starts
/// (a 1e-200 m radius, a duration of centuries).
constexpr double kMaxSteps = 1e10;

/// Runs the scene into ctx.outdir; the outcome holds the shared summary.
bridge::RunOutcome runScene(Scene scene, const std::string& file, const bridge::RunContext& ctx,
                            const SceneRunHooks& hooks = {});

}  // namespace gabion::micro
