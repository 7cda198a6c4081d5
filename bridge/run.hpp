#pragma once
/// \file
/// The contract between the `gabion` command line and the modules that run
/// cases. Each module registers the case kinds it runs (`micro.scene`,
/// `macro.impact`, `fit`, ...) as CaseKind entries; the app dispatches on the
/// case's "kind", writes summary.json and maps outcomes to exit codes.
#include <chrono>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"

namespace gabion::bridge {

/// Reports the progress of a long run as one line on a terminal
/// (simulated time, steps/s, ETA). Silent when disabled; it also waits
/// `delay_s` before the first line so that short runs print nothing.
class Progress {
 public:
  Progress() = default;
  Progress(bool enabled, std::string label, double delay_s = 2.0);
  /// `done` and `total` in any unit (simulated seconds, evaluations); `steps`
  /// is the count the rate is given in. Cheap: checks the clock every 64 calls.
  void update(double done, double total, long long steps);
  /// Ends the line (if one was printed).
  void finish();
  bool enabled() const { return enabled_; }

 private:
  bool enabled_ = false;
  bool printed_ = false;
  std::string label_;
  double delay_s_ = 2.0;
  unsigned calls_ = 0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_ = start_;
};

/// What a run gets from the command line.
struct RunContext {
  std::filesystem::path outdir;                   ///< existing output folder
  std::optional<std::filesystem::path> law_file;  ///< --law override (macro cases)
  int threads = 1;                                ///< --threads
  bool progress = false;                          ///< show a progress line
  std::filesystem::path case_file;                ///< for provenance and messages
  /// The kind may free the case document's parsed value once it has read it
  /// (JsonDocument::releaseValue; a large particle case would otherwise keep
  /// its DOM beside the engine). The caller then keeps its own copy.
  bool may_release_case = false;
};

/// What a run gives back. `results` is merged into summary.json.
struct RunOutcome {
  enum class Status { Ok, NumericalFailure };
  Status status = Status::Ok;
  std::string message;  ///< why it failed (step, time, bodies)
  /// A short account for the person at the terminal (e.g. where the time
  /// went), printed by the app after the list of result files unless
  /// --quiet; everything in it is also in `results`. Empty: nothing.
  std::string report;
  nlohmann::json results = nlohmann::json::object();
};

/// One case kind: `check` parses and validates everything without running
/// (throws InputError); `run` parses, runs and writes result files into
/// ctx.outdir. Both must read every key they accept from the document; the
/// app calls JsonDocument::finish() to reject the keys nobody read.
struct CaseKind {
  std::string kind;
  std::string description;
  std::function<void(const JsonDocument&)> check;
  std::function<RunOutcome(const JsonDocument&, const RunContext&)> run;
};

}  // namespace gabion::bridge
