#pragma once
/// \file
/// `gabion submit slurm`: the rows of a case as a Slurm job array. Each array
/// task runs a bundle of rows (`gabion run --resume OUTDIR --rows SPEC`) into
/// their per-row folders; `gabion collect OUTDIR` then makes the table. The
/// batch script and its list of bundles are kept in OUTDIR/slurm/, to be
/// read, edited and resubmitted with sbatch.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "bridge/rows.hpp"

namespace gabion::app {

struct SlurmOptions {
  std::string partition, time, mem, account;  ///< passed to sbatch as given (empty: the cluster's default)
  std::vector<std::string> extra;             ///< further #SBATCH lines, e.g. "--qos=short"
  std::size_t rows_per_task = 0;              ///< 0: from the rows' estimated cost and task_target_s
  double task_target_s = 600.0;               ///< wall time aimed at per task when bundling
  std::size_t max_array_tasks = 1000;         ///< Slurm's MaxArraySize (1001 by default) less one
  int max_parallel = 0;                       ///< --array=...%K: tasks running at once (0: no limit)
  int cpus_per_task = 1;                      ///< threads of each task
  bool submit = true;                         ///< false: write the script only (--dry-run)
};

struct SlurmSubmission {
  std::filesystem::path script, tasks_file;
  std::size_t tasks = 0, rows = 0, rows_per_task = 0;
  double estimated_task_s = 0.0;  ///< the longest bundle's estimate
  std::string job_id;             ///< empty when not submitted
};

/// Bundles `rows` of `plan` (consecutive rows, rows_per_task each), writes
/// OUTDIR/slurm/job-<n>.sh and job-<n>.tasks (n: the next free number, so
/// earlier submissions' scripts stay) and, unless !options.submit, submits
/// the script with `sbatch --parsable`. Throws InputError when sbatch is
/// missing or refuses the script (its message; the script stays).
SlurmSubmission submitSlurm(const bridge::RowPlan& plan, const std::vector<std::size_t>& rows,
                            const std::filesystem::path& outdir, const std::filesystem::path& gabion_binary,
                            const SlurmOptions& options);

}  // namespace gabion::app
