#pragma once
/// \file
/// A case run as one part of a longer job (a pipeline stage, either half of
/// macro.resolved), in a folder of its own: its case.json written, read back
/// and checked, run, and its summary.json written. The caller writes the
/// folder's manifest once it is done with the folder.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "bridge/run.hpp"

namespace gabion::app {

struct SubCase {
  nlohmann::json summary;  ///< as written to summary.json (with "case")
  bridge::RunOutcome::Status status = bridge::RunOutcome::Status::Ok;
  std::string message;  ///< why it failed
  double wall_time_s = 0.0;
};

/// Runs `case_value` into `dir` (made if missing) with `parent`'s threads
/// and progress, its kind checked to be `expected_kind` unless empty.
/// `progress_context` leads its progress line (RunContext). Throws
/// InputError for a case that does not check.
SubCase runSubCase(const nlohmann::json& case_value, const std::string& expected_kind, const bridge::RunContext& parent,
                   const std::filesystem::path& dir, std::function<std::string(double)> progress_context = {});

}  // namespace gabion::app
