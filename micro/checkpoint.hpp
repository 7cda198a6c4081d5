#pragma once
/// \file
/// Checkpoints of a scene run (micro/scene_run.hpp): every
/// run.checkpoint_every_s of wall-clock time, and when SIGINT or SIGTERM
/// stops it, a run saves its whole state in OUTDIR/checkpoint/:
///
/// - `state.h5`: the engine's state (Engine::archive: bodies in their current
///   order, contact histories, neighbour list, walls, links, energy ledger),
///   the run loop's series, and the case kind's own state (its curves, its
///   phase), one dataset per field (bridge/state_archive.hpp);
/// - `snapshots/<k>.h5`: the snapshot rows streamed into result.h5 since the
///   previous checkpoint (segment k), so that a resumed run rebuilds its
///   result file without keeping them in memory.
///
/// A run of the same case (`gabion run --resume OUTDIR`, or the same case
/// and thread count into OUTDIR) finds the checkpoint, checks that it is of
/// this run (a digest of the case, of the engine's initial state and of the
/// run's step plan), and continues from it: its arrays are those of a run
/// that was never stopped, bit for bit. A run that ends (ok or failed)
/// removes its checkpoint. A checkpoint never forces anything on the run
/// (no neighbour-list rebuild, no change of step): saving one leaves the
/// results unchanged.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "bridge/output.hpp"
#include "bridge/state_archive.hpp"
#include "micro/engine.hpp"

namespace gabion::micro {

/// The snapshot rows (and integer tables) a run streams into its result
/// file, and the segments that keep them for a resume.
class SnapshotLog {
 public:
  explicit SnapshotLog(bridge::H5Writer& h5) : h5_(h5) {}
  /// H5Writer::appendRow, recorded.
  void appendRow(const std::string& dataset, const std::vector<double>& row, const std::vector<std::size_t>& row_dims,
                 const std::string& unit);
  /// H5Writer::writeInts, recorded.
  void writeInts(const std::string& dataset, const std::vector<long long>& values,
                 const std::vector<std::size_t>& dims);
  /// Copies what was written since the last seal into segment file `file`
  /// (written atomically), read back from the result file.
  void seal(const std::filesystem::path& file);
  std::size_t segments() const { return segments_; }
  /// Writes the segments' rows and tables into the result file, in the
  /// order they were first written; `segment(k)` is the path of segment k.
  void replay(const std::function<std::filesystem::path(std::size_t)>& segment);
  /// What was written and sealed, into or out of a checkpoint.
  void archive(bridge::StateArchive& a);

 private:
  struct Rows {
    std::string name, unit;
    std::vector<std::size_t> row_dims;
    std::size_t rows = 0, sealed = 0;
  };
  struct Table {
    std::string name;
    std::vector<std::size_t> dims;
    std::size_t segment = 0;  ///< the segment that holds it (segments_ until sealed)
  };
  bridge::H5Writer& h5_;
  std::vector<Rows> rows_;  // in the order of their first row
  std::vector<Table> tables_;
  std::size_t segments_ = 0;
};

class Checkpoints {
 public:
  /// Checkpoints of a run into `dir` every `every_s` seconds of wall-clock
  /// time (0: only when a signal stops the run). `identity`: a digest of
  /// what makes the run (runIdentity).
  Checkpoints(std::filesystem::path dir, double every_s, std::uint64_t identity);
  /// Whether a periodic checkpoint is due (the interval has passed since the
  /// run started or since the last one).
  bool due() const;
  /// What `dir` holds: no checkpoint, one of another run (another case,
  /// thread count or version: left unused, and replaced by this run's
  /// first), or one of this run.
  enum class Found { None, Other, Ours };
  Found find() const;
  /// Saves the state: the snapshot rows since the last checkpoint, then
  /// state.h5 with the engine's state and `loop`'s (the run's own fields).
  void save(Engine& engine, SnapshotLog& log, const std::function<void(bridge::StateArchive&)>& loop);
  /// Loads the checkpoint into an engine built from the same scene, replays
  /// its snapshots into the log's result file, and loads `loop`'s fields.
  void load(Engine& engine, SnapshotLog& log, const std::function<void(bridge::StateArchive&)>& loop);
  /// Removes the checkpoint (the run ended and its result is written).
  void remove();
  const std::filesystem::path& dir() const { return dir_; }
  std::size_t saved() const { return saved_; }

 private:
  std::filesystem::path state() const { return dir_ / "state.h5"; }
  std::filesystem::path segment(std::size_t k) const;
  std::filesystem::path dir_;
  double every_s_;
  std::uint64_t identity_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
  std::size_t saved_ = 0;
};

/// The digest that ties a checkpoint to its run: the case (its digest),
/// what the run adds to it (`label`, e.g. a cell stage; the step plan), and
/// the engine's state as built (Engine::archive hashed), which also covers
/// the number of threads.
std::uint64_t runIdentity(const std::string& case_digest, const std::string& label, Engine& engine,
                          const std::vector<double>& plan);

}  // namespace gabion::micro
