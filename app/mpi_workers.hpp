#pragma once
/// \file
/// Running one case on several MPI ranks (`mpirun -np N gabion run CASE`):
/// rank 0 runs the case and hands its tasks (a sweep's rows) to whichever
/// rank comes free, itself included: master–worker, so a slow row holds up
/// only its own rank. A worker rank runs each task as the serial run would
/// and sends its result back. The results are the serial run's.
///
/// Without MPI support in the build (GABION_HAVE_MPI off), a run started by
/// mpirun on more than one rank is refused: every rank would run the whole
/// case into the same folder.
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "bridge/rows.hpp"

namespace gabion::app {

/// The MPI environment of this process: initialised when the process was
/// started by mpirun (or srun) on more than one rank, finalised when it ends.
class MpiSession {
 public:
  MpiSession(int& argc, char**& argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  /// True when this process is a worker (a rank other than 0).
  bool worker() const { return size_ > 1 && rank_ != 0; }
  /// The ranks announced by the launcher's environment (1 when none), read
  /// before MPI starts: a build without MPI refuses more than one.
  static int launcherSize();
  /// Whether this build can run on MPI ranks.
  static bool available();

 private:
  int rank_ = 0, size_ = 1;
  bool initialised_ = false;
};

/// A task's answer, from the case's own code on a worker.
using TaskHandler = std::function<nlohmann::json(const nlohmann::json& task)>;

/// On a worker: answers rank 0's tasks with `handler` until rank 0 says stop.
/// A handler that throws answers with its message (the task fails on rank 0).
void serveTasks(const MpiSession& session, const TaskHandler& handler);

/// On rank 0: the ranks that run tasks, as bridge::RemoteWorkers. Destroying
/// it tells every worker rank to stop, however rank 0's run ended.
class RankPool : public bridge::RemoteWorkers {
 public:
  /// Rank 0 works too: a task goes to `handler` on the calling thread when
  /// rank 0 is not running one already (size() then counts rank 0).
  virtual void workHere(TaskHandler handler) = 0;
};
std::unique_ptr<RankPool> workerRanks(const MpiSession& session);

}  // namespace gabion::app
