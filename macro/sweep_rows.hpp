#pragma once
/// \file
/// A sweep's rows as they finish: `rows.jsonl` in the output folder, one JSON
/// line per point, appended and closed as each point ends. A killed sweep
/// keeps the rows it finished; run again into the same folder (or
/// `gabion run --resume OUTDIR`) it takes them and runs only the rest, and
/// writes the table an uninterrupted run writes (each point is run on its own
/// model: the same point gives the same row).
///
/// The first line is the header: {"format": "gabion.sweep_rows/1", "case":
/// the effective case without its description, "points": N}. A log written
/// for another case (or another grid) is started afresh. A torn last line
/// (a kill while it was written) is cut off.
#include <cstddef>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>

#include "macro/impact.hpp"

namespace gabion::macro {

class SweepRows {
 public:
  /// Opens (or starts) `file` for a sweep of `points` points of `case_value`.
  SweepRows(std::filesystem::path file, const nlohmann::json& case_value, std::size_t points);
  /// The rows finished by earlier runs, by point index.
  const std::map<std::size_t, ImpactResult>& done() const { return done_; }
  /// Appends the row of point `index` (thread-safe; throws WriteError).
  void append(std::size_t index, const ImpactResult& r);

 private:
  std::filesystem::path file_;
  std::map<std::size_t, ImpactResult> done_;
  std::mutex mutex_;
};

}  // namespace gabion::macro
