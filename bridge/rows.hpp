#pragma once
/// \file
/// Cases whose work is a set of independent rows: the points of a sweep,
/// and any set of runs whose result depends on its row alone. One contract
/// runs them every way Gabion can, and every way ends in the same table:
/// - here, on threads (`gabion run CASE`): each row is logged to rows.jsonl
///   as it ends, so a stopped run resumes where it stopped;
/// - on MPI ranks (`mpirun -np N gabion run CASE`): rank 0 hands rows out
///   to the others as they come free (RemoteWorkers) and logs them;
/// - as slices (`gabion run CASE --rows 0:100 -o OUTDIR`, one Slurm array
///   task each): each row into its own folder OUTDIR/rows/<i>/row.json,
///   gathered by `gabion collect OUTDIR`.
///
/// Files (docs/formats.md, "Rows"):
/// - rows.jsonl: {"format": "gabion.rows/1", "case_digest", "rows": N}, then
///   one line per finished row {"index", "wall_time_s", "result"};
/// - rows/<i>/row.json: {"format": "gabion.row/1", "case_digest", "index",
///   "row", "wall_time_s", "host", "result"}.
/// A row's "result" is {"ok": true, ...} (what the kind's table shows) or
/// {"ok": false, "message": why}: a row that failed is a result, recorded in
/// the table with its message, and the other rows go on.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"
#include "bridge/run.hpp"

namespace gabion::bridge {

/// How the rows of a case were run, for its summary ("rows").
struct RowStats {
  std::size_t run = 0;       ///< rows run by this process or its workers
  std::size_t reused = 0;    ///< rows found finished in the output folder
  std::size_t missing = 0;   ///< rows with no result (a collect before every task ended)
  std::size_t failed = 0;    ///< rows whose result is a failure
  double wall_time_s = 0.0;  ///< spent running rows here
  int workers = 1;           ///< threads, or MPI worker ranks
  std::string where;         ///< "threads", "mpi" or "collected"
};

/// A value computed the first time it is asked for, once, whatever the
/// thread: what a RowPlan needs only for costS (only `gabion submit` asks),
/// so that a plan made to run rows does not pay for costing them.
template <class T>
class Lazy {
 public:
  explicit Lazy(std::function<T()> make) : make_(std::move(make)) {}
  const T& operator()() const {
    std::call_once(once_, [this] { value_ = make_(); });
    return value_;
  }

 private:
  std::function<T()> make_;
  mutable std::once_flag once_;
  mutable T value_{};
};

/// The independent rows of one case, prepared once (a sweep's structures
/// built) and then run in any order, on any thread or process.
class RowPlan {
 public:
  virtual ~RowPlan() = default;
  /// Number of rows.
  virtual std::size_t size() const = 0;
  /// Row `i` as a row table shows it: {"parameters": {...}, "seed": n or null}.
  virtual nlohmann::json describe(std::size_t i) const = 0;
  /// Runs row `i` (thread-safe): its result, {"ok": true, ...} or {"ok":
  /// false, "message"}. It depends on `i` alone. ctx.outdir is the case's
  /// output folder, where a row may write folders of its own (a lab test's
  /// replicate); ctx.threads is 1. May throw for a row that cannot run (the
  /// runner records it as failed); WriteError is the host's trouble and
  /// stops the run.
  virtual nlohmann::json run(std::size_t i, const RunContext& ctx) const = 0;
  /// Estimated wall time of row `i` on one thread (s): bundles rows into tasks.
  virtual double costS(std::size_t i) const = 0;
  /// Writes the case's tables and charts into ctx.outdir from every row's
  /// result (nullopt: not run), and returns its summary results.
  virtual RunOutcome assemble(const std::vector<std::optional<nlohmann::json>>& results, const RowStats& stats,
                              const RunContext& ctx) const = 0;
};

/// Processes that run tasks for this one (MPI ranks, app/mpi_workers.cpp).
class RemoteWorkers {
 public:
  virtual ~RemoteWorkers() = default;
  /// Number of workers.
  virtual int size() const = 0;
  /// Sends `task` to a free worker and waits for its answer. Thread-safe: up
  /// to size() callers are served at once. A task that threw on its worker
  /// throws std::runtime_error here with the worker's message.
  virtual nlohmann::json call(const nlohmann::json& task) = 0;
};

/// The digest that ties rows to their case: the effective case without its
/// "description" (a reworded description keeps the rows).
std::string rowsDigest(const nlohmann::json& case_value);

/// The results found in `outdir` for `rows` rows of the case of `digest`:
/// its rows.jsonl, then its per-row folders (a folder's result is taken over
/// the log's: it comes from an explicit rerun). A log of another case is
/// ignored; a row folder of another case is an InputError naming it (two
/// cases' rows in one folder would mix). Notes each file read (manifest).
std::vector<std::optional<nlohmann::json>> findRowResults(const std::filesystem::path& outdir,
                                                          const std::string& digest, std::size_t rows);

/// Parses a selection of rows: "A:B" (rows A to B-1), "i", comma-separated
/// lists of them, and the words "missing" (rows without a result in
/// `known`) and "failed" (rows whose result failed). Sorted, without
/// duplicates. Throws InputError naming `source` (the option).
std::vector<std::size_t> selectRows(const std::string& spec, const std::vector<std::optional<nlohmann::json>>& known,
                                    const std::string& source);

/// The compact selection of sorted `rows` ("0:10,12"), as selectRows reads it.
std::string rowSpec(const std::vector<std::size_t>& rows);

/// Runs a case of rows to its end here: rows found finished in ctx.outdir
/// are taken; the rest run on ctx.threads threads, or on ctx.workers when
/// given, each logged to rows.jsonl as it ends; then the plan assembles the
/// table. After SIGINT or SIGTERM the rows not started are left out (the
/// outcome says interrupted; a rerun into the folder finishes them).
RunOutcome runRows(const RowPlan& plan, const JsonDocument& doc, const RunContext& ctx);

/// Runs the rows `which` here, each into OUTDIR/rows/<i>/row.json; no table
/// (`gabion collect` makes it). Safe beside other processes running other
/// rows into the same folder.
RunOutcome runRowSlice(const RowPlan& plan, const JsonDocument& doc, const std::vector<std::size_t>& which,
                       const RunContext& ctx);

/// Assembles the table from the rows that ctx.outdir holds; rows not found
/// are marked missing (`gabion collect`).
RunOutcome collectRows(const RowPlan& plan, const JsonDocument& doc, const RunContext& ctx);

/// Runs a bundle of rows for a worker: task {"rows": [i, ...], "outdir",
/// "case_digest"} -> {"results": [...], "wall_time_s": [...]}, each row as
/// runRows runs it here.
nlohmann::json runRowBundle(const RowPlan& plan, const nlohmann::json& task);

/// The row table of a case: one JSON line per row {"index", "parameters",
/// "seed", "case_digest"} (`gabion rows CASE`).
std::string rowTable(const RowPlan& plan, const JsonDocument& doc);

}  // namespace gabion::bridge
