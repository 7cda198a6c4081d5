#include "app/slurm.hpp"

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"

namespace gabion::app {

namespace fs = std::filesystem;

namespace {

// A word for a shell script, in single quotes.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Runs a command line; its output (stdout and stderr) and exit code.
std::pair<int, std::string> capture(const std::string& command_line) {
  std::string out;
  FILE* p = popen((command_line + " 2>&1").c_str(), "r");
  if (p == nullptr) return {-1, "cannot start: " + command_line};
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), p) != nullptr) out += buf.data();
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace

SlurmSubmission submitSlurm(const bridge::RowPlan& plan, const std::vector<std::size_t>& rows, const fs::path& outdir,
                            const fs::path& gabion_binary, const SlurmOptions& o) {
  SlurmSubmission s;
  s.rows = rows.size();
  if (rows.empty()) throw bridge::InputError(outdir.string(), "", "no rows to submit: every selected row is done");
  // Bundles: enough rows per task that a task runs about task_target_s (a
  // task's start costs the scheduler seconds), and no more tasks than an
  // array may hold.
  double total_s = 0.0;
  for (std::size_t i : rows) total_s += plan.costS(i);
  const double mean_s = total_s / static_cast<double>(rows.size());
  std::size_t per = o.rows_per_task;
  if (per == 0) per = static_cast<std::size_t>(std::max(1.0, std::floor(o.task_target_s / std::max(mean_s, 1e-9))));
  per = std::max(per, (rows.size() + o.max_array_tasks - 1) / o.max_array_tasks);
  per = std::min(per, rows.size());
  s.rows_per_task = per;
  std::ostringstream tasks;
  for (std::size_t k = 0; k < rows.size(); k += per) {
    const std::vector<std::size_t> bundle(rows.begin() + static_cast<long>(k),
                                          rows.begin() + static_cast<long>(std::min(rows.size(), k + per)));
    double cost = 0.0;
    for (std::size_t i : bundle) cost += plan.costS(i);
    s.estimated_task_s = std::max(s.estimated_task_s, cost);
    tasks << bridge::rowSpec(bundle) << "\n";
    ++s.tasks;
  }

  const fs::path dir = fs::absolute(outdir) / "slurm";
  std::error_code ec;
  fs::create_directories(dir / "logs", ec);
  if (ec) throw bridge::InputError(dir.string(), "", "cannot make the folder of the batch script: " + ec.message());
  int n = 1;
  while (fs::exists(dir / ("job-" + std::to_string(n) + ".sh"))) ++n;
  s.script = dir / ("job-" + std::to_string(n) + ".sh");
  s.tasks_file = dir / ("job-" + std::to_string(n) + ".tasks");
  bridge::writeTextAtomic(s.tasks_file, tasks.str());

  std::ostringstream sh;
  sh << "#!/bin/bash\n"
     << "# Written by `gabion submit slurm`: rows of the case in " << fs::absolute(outdir).string() << "/run.json\n"
     << "# as a job array, one line of " << s.tasks_file.filename().string() << " (a bundle of rows) per task.\n"
     << "# Each task writes its rows to rows/<row>/row.json; `gabion collect` makes the table.\n"
     << "# Edit and resubmit with: sbatch " << s.script.string() << "\n"
     << "#SBATCH --job-name=gabion-" << fs::absolute(outdir).filename().string() << "\n"
     << "#SBATCH --array=0-" << s.tasks - 1 << (o.max_parallel > 0 ? "%" + std::to_string(o.max_parallel) : "") << "\n"
     << "#SBATCH --output=" << (dir / "logs").string() << "/%A_%a.out\n"
     << "#SBATCH --ntasks=1\n"
     << "#SBATCH --cpus-per-task=" << o.cpus_per_task << "\n";
  if (!o.partition.empty()) sh << "#SBATCH --partition=" << o.partition << "\n";
  if (!o.time.empty()) sh << "#SBATCH --time=" << o.time << "\n";
  if (!o.mem.empty()) sh << "#SBATCH --mem=" << o.mem << "\n";
  if (!o.account.empty()) sh << "#SBATCH --account=" << o.account << "\n";
  for (const std::string& e : o.extra) sh << "#SBATCH " << e << "\n";
  sh << "set -euo pipefail\n"
     << "rows=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" " << quoted(s.tasks_file.string()) << ")\n"
     << "exec " << quoted(fs::absolute(gabion_binary).string()) << " run --resume "
     << quoted(fs::absolute(outdir).string()) << " --rows \"$rows\" --threads \"${SLURM_CPUS_PER_TASK:-1}\" -q\n";
  bridge::writeTextAtomic(s.script, sh.str());
  fs::permissions(s.script, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add, ec);
  if (!o.submit) return s;

  const auto [code, out] = capture("sbatch --parsable " + quoted(s.script.string()));
  if (code == 127 || out.find("not found") != std::string::npos)
    throw bridge::InputError(s.script.string(), "",
                             "sbatch is not on this machine's PATH: submit the script on the cluster's login node "
                             "with `sbatch " +
                                 s.script.string() + "`");
  if (code != 0) throw bridge::InputError(s.script.string(), "", "sbatch refused the script: " + out);
  // --parsable prints "jobid" or "jobid;cluster", perhaps after warnings.
  std::istringstream lines(out);
  std::string line;
  while (std::getline(lines, line))
    if (!line.empty() && std::isdigit(static_cast<unsigned char>(line[0])) != 0)
      s.job_id = line.substr(0, line.find(';'));
  if (s.job_id.empty()) throw bridge::InputError(s.script.string(), "", "sbatch gave no job id: " + out);
  return s;
}

}  // namespace gabion::app
