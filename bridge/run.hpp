#pragma once
/// \file
/// The contract between the `gabion` command line and the modules that run
/// cases. Each module registers the case kinds it runs (`micro.scene`,
/// `macro.impact`, `fit`, ...) as CaseKind entries; the app dispatches on the
/// case's "kind", writes summary.json and maps outcomes to exit codes.
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"

namespace gabion::bridge {

class RowPlan;        // bridge/rows.hpp
class RemoteWorkers;  // bridge/rows.hpp

/// What a run gets from the command line.
struct RunContext {
  std::filesystem::path outdir;  ///< existing output folder
  int threads = 1;               ///< --threads
  bool progress = false;         ///< show the progress
  /// stdout is a log, not a terminal: the progress as a plain line every
  /// `progress_log_interval_s` (from then on), not one line rewritten in place.
  bool progress_log = false;
  double progress_log_interval_s = 60.0;
  std::filesystem::path case_file;  ///< for provenance and messages
  /// A digest of the effective case (its JSON after --set): a checkpoint
  /// left in outdir is continued only by a run of the same case.
  std::string case_digest;
  /// The kind may free the case document's parsed value once it has read it
  /// (JsonDocument::releaseValue; a large particle case would otherwise keep
  /// its DOM beside the engine). The caller then keeps its own copy.
  bool may_release_case = false;
  /// Set by a caller that runs this case as one part of a longer job (the
  /// pipeline): given the remaining time of this run as its progress line
  /// estimates it, returns the job's own words (its stage, rank, ETA) that
  /// the line starts with. Called from the thread that shows the progress.
  std::function<std::string(double run_eta_s)> progress_context;
  /// Other processes that run this case's tasks (MPI ranks, under `mpirun`);
  /// null: the run uses its own threads.
  RemoteWorkers* workers = nullptr;
};

/// Reports the progress of a long run as one line on a terminal
/// (simulated time, steps/s, ETA), or into a log as a plain line a minute
/// (RunContext::progress_log). Silent when disabled; it also waits `delay_s`
/// (a log: its interval, a minute) before the first line so that short runs
/// print nothing.
class Progress {
 public:
  Progress() = default;
  Progress(bool enabled, std::string label, double delay_s = 2.0);
  /// Enabled as ctx.progress, the line led by ctx.progress_context's words.
  Progress(const RunContext& ctx, std::string label, double delay_s = 2.0);
  /// `done` and `total` in any unit (simulated seconds, evaluations); `steps`
  /// is the count the rate is given in. Cheap: checks the clock every 64 calls.
  void update(double done, double total, long long steps);
  /// Ends the line (if one was printed).
  void finish();
  bool enabled() const { return enabled_; }

 private:
  bool enabled_ = false;
  bool log_ = false;
  double interval_s_ = 0.25;  ///< between two lines
  bool printed_ = false;
  std::string label_;
  std::function<std::string(double)> context_;
  double delay_s_ = 2.0;
  unsigned calls_ = 0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_ = start_;
};

/// What a run gives back. `results` is merged into summary.json.
struct RunOutcome {
  /// Interrupted: SIGINT or SIGTERM asked it to stop (bridge/interrupt.hpp);
  /// what it wrote so far stays.
  enum class Status { Ok, NumericalFailure, Interrupted };
  Status status = Status::Ok;
  std::string message;  ///< why it failed (step, time, bodies)
  /// A short account for the person at the terminal of how the run went
  /// (e.g. where the time went), printed by the app after the answer unless
  /// --quiet; everything in it is also in `results`. Empty: nothing.
  std::string report;
  /// The run's answer in a few lines (the verdict, the fitted parameters,
  /// the capacity), printed after the list of result files even with
  /// --quiet; everything in it is also in `results`. Empty: nothing.
  std::string answer;
  nlohmann::json results = nlohmann::json::object();
};

/// What a case will cost, estimated before it runs from its settings and
/// input files: steps are an upper bound where a run may end early (a test
/// that stops at its target, an impact that ends when the boulder stops).
/// Summed over every run of the case (bridge/cost.hpp: the rates, the
/// limits and the sum).
struct Estimate {
  double bodies = 0.0;        ///< bodies (micro: spheres, block members one by one; macro: cells) of its largest run
  double steps = 0.0;         ///< time steps, over its runs
  double body_steps = 0.0;    ///< bodies x steps, over its runs: what its wall time scales with
  std::size_t runs = 0;       ///< engine runs (variants x replicates, sweep points, evaluations)
  double snapshots = 0.0;     ///< body snapshots or series samples written, over its runs
  double memory_bytes = 0.0;  ///< peak memory of the process
  double output_bytes = 0.0;  ///< result files
  /// the checkpoints on disk at one time while it runs (a micro run's state
  /// and the result rows written so far, micro/checkpoint.hpp; removed as
  /// its runs end): the largest run's, or a structure's stages' together,
  /// whose landing and settling keep their ends until its impact is over
  double checkpoint_bytes = 0.0;
  double wall_time_s = 0.0;  ///< on one thread, at the rates measured on the reference machine
  bool partial = false;      ///< some of its work cannot be costed before it runs (a pipeline's lab tests)
};

/// The results' key with the wall-clock seconds that runs stopped by a
/// signal spent before the checkpoints a resumed run continued from (summed
/// over its stages). The summary's `wall_time_s` adds them to the process's
/// own time, so that a run resumed once or many times reports the time of
/// the whole run (`wall_time_this_process_s`: the process's alone).
inline constexpr const char* kWallTimeBeforeResume = "wall_time_before_resume_s";

/// The summary's wall time of a run whose process took `process_s` and
/// gave `results`: the process's, plus what its resumed checkpoints carried.
inline double wholeWallTime(double process_s, const nlohmann::json& results) {
  const auto it = results.find(kWallTimeBeforeResume);
  return process_s + (it != results.end() && it->is_number() ? it->get<double>() : 0.0);
}

/// The summary's "status": "ok", "numerical_failure" or "interrupted".
inline const char* statusName(RunOutcome::Status s) {
  switch (s) {
    case RunOutcome::Status::Ok:
      return "ok";
    case RunOutcome::Status::NumericalFailure:
      return "numerical_failure";
    case RunOutcome::Status::Interrupted:
      return "interrupted";
  }
  return "unknown";
}

/// One case kind: `check` parses and validates everything without running
/// (throws InputError); `run` parses, runs and writes result files into
/// ctx.outdir. Both must read every key they accept from the document; the
/// app calls JsonDocument::finish() to reject the keys nobody read.
struct CaseKind {
  CaseKind(std::string kind_, std::string description_, std::function<void(const JsonDocument&)> check_,
           std::function<RunOutcome(const JsonDocument&, const RunContext&)> run_,
           std::function<std::optional<Estimate>(const JsonDocument&)> estimate_ = {},
           std::function<std::shared_ptr<const RowPlan>(const JsonDocument&)> rows_ = {},
           std::function<std::function<nlohmann::json(const nlohmann::json&)>(const JsonDocument&)> serve_ = {})
      : kind(std::move(kind_)),
        description(std::move(description_)),
        check(std::move(check_)),
        run(std::move(run_)),
        estimate(std::move(estimate_)),
        rows(std::move(rows_)),
        serve(std::move(serve_)) {}
  std::string kind;
  std::string description;
  std::function<void(const JsonDocument&)> check;
  std::function<RunOutcome(const JsonDocument&, const RunContext&)> run;
  /// Its cost before it runs (absent, or nullopt: not known, e.g. a cell
  /// that is not generated yet). Throws InputError as check does.
  std::function<std::optional<Estimate>(const JsonDocument&)> estimate;
  /// Absent, or the case's independent rows (a sweep's points): the app can
  /// then run a slice of them (`--rows`), collect them (`gabion collect`),
  /// submit them as a Slurm job array and hand them to MPI ranks. Throws
  /// InputError as check does.
  std::function<std::shared_ptr<const RowPlan>(const JsonDocument&)> rows;
  /// Absent, or (a kind whose run sends tasks of its own to ctx.workers: a
  /// calibration's evaluations) the answerer of those tasks on an MPI worker
  /// rank, made once from the same case. A kind of rows needs none: its
  /// workers run rows. Throws InputError as check does.
  std::function<std::function<nlohmann::json(const nlohmann::json&)>(const JsonDocument&)> serve;
};

}  // namespace gabion::bridge
