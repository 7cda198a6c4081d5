#pragma once
/// \file
/// The calibration loop for expensive objectives (a DEM run per evaluation):
/// a seeded Latin-hypercube population evaluated in parallel, then several
/// local NLopt searches started from its best points, also in parallel. Every
/// evaluation is appended to a JSON-lines log (evaluations.jsonl) as soon as it
/// ends, so an interrupted calibration resumes where it stopped: evaluations
/// found in the log are re-used, not re-run. A failed evaluation (exception,
/// NaN, numerical failure) is logged with its message and scores a penalty.
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bridge/run.hpp"
#include "fitting/optimizer.hpp"

namespace gabion::fitting {

/// One logged evaluation.
struct EvaluationRecord {
  long long id = 0;                ///< order in which it was started (this session and earlier ones)
  std::vector<double> parameters;  ///< physical units
  double error = 0.0;              ///< objective value (penalty when failed)
  double time_s = 0.0;             ///< wall time of the evaluation (s)
  bool ok = true;                  ///< false: threw, returned NaN or the run failed
  std::string message;             ///< why it failed
};

/// The JSON-lines log of a calibration: a header line {"format":
/// "gabion.evaluations/1", "case_sha256", "parameters"} then one line per
/// evaluation {"id", "parameters", "error", "time_s", "status", "message"}.
/// A truncated last line (a run killed while writing) is ignored.
class EvaluationLog {
 public:
  /// Opens `file`. With `resume`, existing records are loaded; a log written for
  /// another case (other `case_sha256` or parameter names) is an InputError. Without
  /// `resume` the log starts empty.
  EvaluationLog(std::filesystem::path file, std::string case_sha256, std::vector<std::string> parameter_names,
                bool resume);
  /// The logged record with exactly these parameters, if any (thread-safe).
  bool find(const std::vector<double>& parameters, EvaluationRecord& out) const;
  /// Appends a record and flushes it to disk (thread-safe).
  void append(const EvaluationRecord& r);
  /// Number of records loaded from an earlier session.
  std::size_t resumed() const { return resumed_; }
  long long nextId();
  std::vector<EvaluationRecord> records() const;
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
  mutable std::mutex mutex_;
  std::map<std::vector<double>, EvaluationRecord> records_;
  std::size_t resumed_ = 0;
  long long next_id_ = 0;
};

/// Evaluates the objective at `parameters` (physical units). `scratch` is an
/// empty folder of its own (the evaluation may write there; it is removed after
/// unless kept). Called from several threads at once; may throw.
using Evaluator = std::function<double(const std::vector<double>& parameters, const std::filesystem::path& scratch)>;

/// Settings of the loop (case key "search", docs/fitting.md).
struct CalibrationSettings {
  std::size_t initial_samples = 8;  ///< Latin-hypercube points evaluated first, in parallel
  std::size_t starts = 2;           ///< local searches from the best distinct samples, in parallel
  std::string local_algorithm = "LN_BOBYQA";
  int local_max_evaluations = 40;  ///< per local search
  double xtol_rel = 1e-3;          ///< relative tolerance on the unit-box parameters
  unsigned long seed = 1;
  int threads = 1;                     ///< parallel evaluations
  double penalty = 1e6;                ///< error given to a failed evaluation
  long long max_new_evaluations = -1;  ///< stop after this many fresh evaluations (-1: no limit); re-run to resume
  bool keep_evaluation_folders = false;
};

/// What the loop found.
struct CalibrationResult {
  std::vector<double> best;  ///< best parameters (physical units)
  double best_error = 0.0;
  long long new_evaluations = 0;     ///< run in this session
  long long reused_evaluations = 0;  ///< answered from the log
  long long failed_evaluations = 0;  ///< failed, this session or logged
  bool interrupted = false;          ///< stopped by max_new_evaluations
  std::vector<std::string> local_status;
  double wall_time_s = 0.0;
};

/// The population the loop starts from: the seeded Latin-hypercube samples
/// in physical units, in the order the loop evaluates them. Evaluated
/// elsewhere (a fit.micro case's rows) and logged, they are taken from the
/// log as the loop's own.
std::vector<std::vector<double>> initialPopulation(const std::vector<Parameter>& params,
                                                   const CalibrationSettings& settings);

/// Runs the loop. Evaluation folders are made under `scratch_root`.
CalibrationResult calibrate(const std::vector<Parameter>& params, const Evaluator& evaluate,
                            const CalibrationSettings& settings, EvaluationLog& log,
                            const std::filesystem::path& scratch_root, bridge::Progress* progress = nullptr);

}  // namespace gabion::fitting
