// The rows of a case run every way Gabion runs them (bridge/rows.hpp): here
// on threads, as --rows slices into per-row folders gathered by `gabion
// collect`, on MPI ranks. Every way gives the local run's table, bit for bit.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "bridge/output.hpp"
#include "tests/support/run_gabion.hpp"

namespace {

namespace fs = std::filesystem;
using gabion::testing::runCommand;
using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::summaryOf;

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// 4 speeds x 3 masses x 2 aim points: 24 rows of the default wall.
const std::string kSweep = std::string(GABION_SOURCE_DIR) + "/cases/macro_sweep.json --set sweep.velocity_m_s.count=4";

// The two tables are the same: sweep.csv byte for byte, result.h5's columns
// value for value (an HDF5 file's bytes hold its times).
void expectSameTable(const fs::path& a, const fs::path& b) {
  EXPECT_EQ(readText(a / "sweep.csv"), readText(b / "sweep.csv"));
  const gabion::bridge::H5Reader x(a / "result.h5"), y(b / "result.h5");
  for (const char* column :
       {"index", "velocity_m_s", "mass_kg", "aim_y_m", "failed", "peak_force_N", "max_penetration_m",
        "contact_duration_s", "max_back_face_displacement_m", "plastic_energy_J", "outcome"}) {
    const auto u = x.read(std::string("/table/") + column), v = y.read(std::string("/table/") + column);
    ASSERT_EQ(u.size(), v.size()) << column;
    for (std::size_t i = 0; i < u.size(); ++i)
      EXPECT_TRUE(u[i] == v[i] || (std::isnan(u[i]) && std::isnan(v[i]))) << column << "[" << i << "]";
  }
}

int lines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n' ? 1 : 0;
  return n;
}

}  // namespace

// `gabion rows` lists the rows; slices run into per-row folders; a collect
// before every slice ran names the missing rows and the one command that
// runs exactly those; after it, the collected table is the local run's.
TEST(Rows, SlicesCollectedGiveTheLocalTable) {
  const auto dir = scratchDir("rows_slices");
  const auto listed = runGabion("rows " + kSweep);
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  ASSERT_EQ(lines(listed.output), 24) << listed.output;
  const auto first = nlohmann::json::parse(listed.output.substr(0, listed.output.find('\n')));
  EXPECT_EQ(first.at("index"), 0);
  EXPECT_DOUBLE_EQ(first.at("parameters").at("velocity_m_s").get<double>(), 5.0);
  EXPECT_DOUBLE_EQ(first.at("parameters").at("mass_kg").get<double>(), 100.0);

  ASSERT_EQ(runGabion("run " + kSweep + " -q --threads 2 -o " + (dir / "local").string()).exit_code, 0);
  const fs::path sliced = dir / "sliced";
  auto r = runGabion("run " + kSweep + " -q --rows 0:10 -o " + sliced.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rows 0:10: 10 run, 0 failed"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_regular_file(sliced / "rows" / "9" / "row.json"));
  EXPECT_FALSE(fs::exists(sliced / "summary.json")) << "a slice writes no table";
  r = runGabion("run --resume " + sliced.string() + " -q --rows 10:12,14:17,20");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // Rows 12, 13, 17-19 and 21-23 have not run: collect says so and exits 4.
  r = runGabion("collect " + sliced.string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  const std::string abs = fs::absolute(sliced).string();
  EXPECT_NE(r.output.find("gabion: 8 rows missing: 12:14,17:20,21:24"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gabion run --resume " + abs + " --rows 12:14,17:20,21:24"), std::string::npos) << r.output;
  auto summary = summaryOf(sliced);
  EXPECT_EQ(summary.at("status"), "ok");
  EXPECT_EQ(summary.at("rows").at("missing"), 8);
  EXPECT_EQ(summary.at("missing_points"), 8);
  EXPECT_NE(readText(sliced / "sweep.csv").find(",missing,"), std::string::npos);
  const auto row = nlohmann::json::parse(std::ifstream(sliced / "rows" / "20" / "row.json"));
  EXPECT_EQ(row.at("format"), "gabion.row/1");
  EXPECT_EQ(row.at("index"), 20);
  EXPECT_TRUE(row.at("result").at("ok").get<bool>());

  r = runGabion("run --resume " + sliced.string() + " -q --rows missing");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rows 12:14,17:20,21:24: 8 run"), std::string::npos) << r.output;
  r = runGabion("collect " + sliced.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rows: 24 of 24 done"), std::string::npos) << r.output;
  summary = summaryOf(sliced);
  EXPECT_EQ(summary.at("rows").at("where"), "collected");
  EXPECT_EQ(summary.at("rows").at("missing"), 0);
  expectSameTable(dir / "local", sliced);
  // The collected folder's manifest lists the rows it was made from.
  EXPECT_NE(readText(sliced / "manifest.json").find("rows/23/row.json"), std::string::npos);

  // A local run into the folder takes every row found there and runs none.
  r = runGabion("run --resume " + sliced.string() + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(summaryOf(sliced).at("rows").at("reused"), 24);
  expectSameTable(dir / "local", sliced);
}

// A row with a bad parameter (an aim point off the wall) is recorded as
// failed with its message in the collected table; the others complete, and
// `--rows failed` selects exactly it.
TEST(Rows, AFailedRowIsRecordedAndTheOthersComplete) {
  const auto dir = scratchDir("rows_failed");
  const std::string sweep = std::string(GABION_SOURCE_DIR) +
                            "/cases/macro_sweep.json --set sweep.velocity_m_s.count=2 --set sweep.mass_kg=[170] "
                            "--set 'sweep.aim_point_m=[[2.75,1.75],[40,1.75]]'";
  auto r = runGabion("run " + sweep + " -q --rows 0:4 -o " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rows 0:4: 4 run, 2 failed"), std::string::npos) << r.output;
  r = runGabion("collect " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rows: 4 of 4 done, 2 failed (rows 2:4)"), std::string::npos) << r.output;
  const std::string csv = readText(dir / "sweep.csv");
  EXPECT_NE(csv.find("failed,,,,,,,,,\"aim point outside the front face of this structure\""), std::string::npos)
      << csv;
  const auto summary = summaryOf(dir);
  EXPECT_EQ(summary.at("failed_points"), 2);
  EXPECT_EQ(summary.at("rows").at("failed"), 2);
  EXPECT_NE(r.output.find("to run the failed rows again: gabion run --resume " + fs::absolute(dir).string() +
                          " --rows 2:4; then gabion collect"),
            std::string::npos)
      << r.output;
  r = runGabion("run --resume " + dir.string() + " -q --rows failed");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rows 2:4: 2 run, 2 failed"), std::string::npos) << r.output;

  // With rows missing too, collect names both, and the command for both.
  fs::remove_all(dir / "rows" / "0");
  r = runGabion("collect " + dir.string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("gabion: 1 row missing: 0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(the failed rows too:      --rows 0,2:4 in either command)"), std::string::npos) << r.output;
}

// A calibration's population (its Latin-hypercube samples) as rows: run in
// slices, collected into the evaluation log, where the resumed calibration
// takes them as its own and ends where a local calibration ends.
TEST(Rows, ACalibrationPopulationAsRowsIsTheLoopsOwn) {
  const auto dir = scratchDir("rows_fit");
  const std::string fit = std::string(GABION_SOURCE_DIR) + "/cases/fit_micro_wall.json";
  ASSERT_EQ(runGabion("run " + fit + " -q -o " + (dir / "local").string()).exit_code, 0);
  const auto listed = runGabion("rows " + fit);
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_EQ(lines(listed.output), 6) << listed.output;  // (search.initial_samples)

  const fs::path pop = dir / "population";
  ASSERT_EQ(runGabion("run " + fit + " -q --rows 0:4 -o " + pop.string()).exit_code, 0);
  auto r = runGabion("collect " + pop.string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("fit.micro population: 4 of 6 samples evaluated (0 failed)"), std::string::npos) << r.output;
  ASSERT_EQ(runGabion("run --resume " + pop.string() + " -q --rows missing").exit_code, 0);
  r = runGabion("collect " + pop.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("the search goes on from them: gabion run --resume"), std::string::npos) << r.output;
  EXPECT_EQ(summaryOf(pop).at("population").at("added_to_log"), 2);  // (the first four were logged before)

  r = runGabion("run --resume " + pop.string() + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto a = summaryOf(dir / "local").at("fit_micro"), b = summaryOf(pop).at("fit_micro");
  EXPECT_EQ(b.at("resumed_from_log"), 6);
  EXPECT_EQ(a.at("parameters"), b.at("parameters"));
  EXPECT_EQ(a.at("misfit"), b.at("misfit"));
  EXPECT_EQ(a.at("new_evaluations").get<int>() - 6, b.at("new_evaluations").get<int>());
}

// A design search's pieces (per front material and height, the bisection
// over the thickness) as rows: collected, the design, its sections, margins,
// residual capacity and capacity chart are the local run's.
TEST(Rows, ADesignSearchAsRowsGivesTheLocalDesign) {
  const auto dir = scratchDir("rows_design");
  const std::string design = std::string(GABION_SOURCE_DIR) + "/cases/macro_design.json";
  ASSERT_EQ(runGabion("run " + design + " -q --threads 2 -o " + (dir / "local").string()).exit_code, 0);
  const auto listed = runGabion("rows " + design);
  ASSERT_EQ(lines(listed.output), 14) << listed.output;  // (2 front materials x heights 2 to 8)
  const fs::path rows = dir / "rows";
  ASSERT_EQ(runGabion("run " + design + " -q --rows 0:7 -o " + rows.string()).exit_code, 0);
  auto r = runGabion("collect " + rows.string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("the search is not complete (7 of 14 rows missing): no section chosen"), std::string::npos)
      << r.output;
  EXPECT_TRUE(summaryOf(rows).at("design").is_null());
  ASSERT_EQ(runGabion("run --resume " + rows.string() + " -q --rows missing").exit_code, 0);
  r = runGabion("collect " + rows.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto a = summaryOf(dir / "local"), b = summaryOf(rows);
  ASSERT_FALSE(a.at("design").is_null());
  for (const char* key : {"design", "sections", "governing_criterion", "residual_capacity_impacts",
                          "capacity_vs_thickness", "impacts_run", "answer"})
    EXPECT_EQ(a.value(key, nlohmann::json()), b.value(key, nlohmann::json())) << key;
}

TEST(Rows, BadSelectionsAndFoldersAreRefused) {
  const auto dir = scratchDir("rows_bad");
  struct Case {
    std::string args, message;
  };
  const fs::path out = dir / "out";
  for (const Case& c : std::vector<Case>{
           {"run " + kSweep + " --rows 5:3 -o " + out.string(), "'5:3': rows A:B need A < B <= 24"},
           {"run " + kSweep + " --rows 24 -o " + out.string(), "row 24 does not exist: the case has 24 rows, 0 to 23"},
           {"run " + kSweep + " --rows 1-3 -o " + out.string(), "expected rows as A:B"},
           {"run " + std::string(GABION_SOURCE_DIR) + "/cases/wall_impact.json --rows 0:1 -o " + out.string(),
            "--rows: a macro.impact case is one run, not a set of rows (cases of rows: micro.cc, "},
           {"collect " + (dir / "nothing").string(), "no such file: the folder holds no run"},
           {"submit slurm " + kSweep, "submit slurm: give the output folder (-o) the tasks share"},
           {"submit slurm --resume " + out.string() + " " + kSweep, "give no case file with it"},
       }) {
    const auto r = runGabion(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.args << "\n" << r.output;
  }
  // Where Slurm is not installed, the script is written and the way to
  // submit it named.
  const auto no_slurm = runCommand("PATH=/nonexistent " + std::string(GABION_BINARY) + " submit slurm " + kSweep +
                                   " -o " + (dir / "no_slurm").string());
  EXPECT_EQ(no_slurm.exit_code, 2) << no_slurm.output;
  EXPECT_NE(no_slurm.output.find("sbatch is not on this machine's PATH: submit the script on the cluster's login node"),
            std::string::npos)
      << no_slurm.output;
  EXPECT_TRUE(fs::is_regular_file(dir / "no_slurm" / "slurm" / "job-1.sh"));

  // Rows of another case are not added to a folder's rows.
  ASSERT_EQ(runGabion("run " + kSweep + " -q --rows 0 -o " + out.string()).exit_code, 0);
  const auto r = runGabion("run " + kSweep + " --set run.duration_s=0.04 --rows 1 -o " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("this folder holds the rows of another case"), std::string::npos) << r.output;
}

// mpirun on three ranks: rank 0 hands the rows out to the ranks (itself too) and
// writes the table; it is the serial run's, bit for bit. A slice runs on
// the ranks too.
TEST(Rows, ASweepOnMpiRanksGivesTheSerialTable) {
#ifndef GABION_MPIEXEC
  GTEST_SKIP() << "this build has no MPI (scripts/deps.sh installs libopenmpi-dev; build again)";
#else
  const auto dir = scratchDir("rows_mpi");
  const std::string mpirun = std::string(GABION_MPIEXEC) + " --allow-run-as-root --oversubscribe -np 3 ";
  ASSERT_EQ(runGabion("run " + kSweep + " -q -o " + (dir / "serial").string()).exit_code, 0);
  auto r = runCommand(mpirun + GABION_BINARY + " run " + kSweep + " -q -o " + (dir / "mpi").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto summary = summaryOf(dir / "mpi");
  EXPECT_EQ(summary.at("rows").at("where"), "mpi");
  EXPECT_EQ(summary.at("rows").at("workers"), 3);  // (rank 0 works too)
  EXPECT_EQ(summary.at("rows").at("run"), 24);
  expectSameTable(dir / "serial", dir / "mpi");

  r = runCommand(mpirun + GABION_BINARY + " run " + kSweep + " -q --rows 0:24 -o " + (dir / "slices").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(runGabion("collect " + (dir / "slices").string()).exit_code, 0);
  expectSameTable(dir / "serial", dir / "slices");

  // Bad input under mpirun ends every rank with exit 2 (the worker ranks are
  // told to stop; none waits for tasks that will not come).
  for (const std::string& args : {std::string("run nowhere.json"), std::string("run --no-such-option")}) {
    r = runCommand("timeout 60 " + mpirun + GABION_BINARY + " " + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
  }

  // A calibration's evaluations on the workers: the same evaluations, the
  // same log entries and the same fitted parameters as on one thread.
  const std::string fit = std::string(GABION_SOURCE_DIR) + "/cases/fit_micro_wall.json --set resume=false -q -o ";
  ASSERT_EQ(runGabion("run " + fit + (dir / "fit_serial").string()).exit_code, 0);
  r = runCommand(mpirun + GABION_BINARY + " run " + fit + (dir / "fit_mpi").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto a = summaryOf(dir / "fit_serial").at("fit_micro"), b = summaryOf(dir / "fit_mpi").at("fit_micro");
  EXPECT_EQ(a.at("parameters"), b.at("parameters"));
  EXPECT_EQ(a.at("misfit"), b.at("misfit"));
  EXPECT_EQ(a.at("new_evaluations"), b.at("new_evaluations"));
  const auto evaluations = [](const fs::path& log) {  // (in the order they ended, which threads change)
    std::set<std::string> out;
    std::ifstream in(log);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      auto j = nlohmann::json::parse(line);
      out.insert(nlohmann::json{j.at("parameters"), j.at("error"), j.at("status")}.dump());
    }
    return out;
  };
  const auto serial = evaluations(dir / "fit_serial" / "evaluations.jsonl");
  EXPECT_GT(serial.size(), 20u);
  EXPECT_EQ(serial, evaluations(dir / "fit_mpi" / "evaluations.jsonl"));

  // A design search's pieces on the ranks: the design and every section of
  // a run on one thread.
  const std::string design = std::string(GABION_SOURCE_DIR) + "/cases/macro_design.json -q -o ";
  ASSERT_EQ(runGabion("run " + design + (dir / "design_serial").string()).exit_code, 0);
  r = runCommand(mpirun + GABION_BINARY + " run " + design + (dir / "design_mpi").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* key : {"design", "sections", "residual_capacity_impacts", "capacity_vs_thickness"})
    EXPECT_EQ(summaryOf(dir / "design_serial").at(key), summaryOf(dir / "design_mpi").at(key)) << key;
#endif
}

namespace {

// A one-node Slurm cluster on localhost for one test (scripts/slurm_local.sh),
// stopped when the test ends; `why` says what kept it from starting.
struct LocalSlurm {
  fs::path dir;
  std::string why;
  explicit LocalSlurm(const fs::path& d) : dir(d) {
    const std::string script = std::string(GABION_SOURCE_DIR) + "/scripts/slurm_local.sh";
    auto r = runCommand(script + " install");
    if (r.exit_code != 0) {
      why = r.output;
      return;
    }
    r = runCommand(script + " start " + dir.string() + " 2>/dev/null");
    if (r.exit_code != 0) {
      why = runCommand(script + " start " + dir.string()).output;
      return;
    }
    setenv("SLURM_CONF", (dir / "slurm.conf").c_str(), 1);
  }
  ~LocalSlurm() {
    if (why.empty()) runCommand(std::string(GABION_SOURCE_DIR) + "/scripts/slurm_local.sh stop " + dir.string());
  }
  // Waits until the job has left the queue (at most two minutes).
  static bool waitFor(const std::string& job) {
    for (int i = 0; i < 1200; ++i) {
      const auto q = runCommand("squeue -h -j " + job);
      if (q.exit_code != 0 || q.output.find_first_not_of(" \n") == std::string::npos) return true;
      usleep(100000);
    }
    return false;
  }
};

std::string jobIdOf(const std::string& output) {
  const auto at = output.find("submitted: job ");
  if (at == std::string::npos) return "";
  std::istringstream in(output.substr(at + 15));
  std::string id;
  in >> id;
  return id;
}

}  // namespace

// A sweep submitted to Slurm as a job array of bundles of rows, one task
// cancelled on purpose before it starts, then one killed while it runs:
// collect names the missing rows, one command resubmits exactly those, and
// the collected table is the local run's.
TEST(Rows, ASweepAsASlurmArrayGivesTheLocalTable) {
  const auto dir = scratchDir("rows_slurm");
  LocalSlurm slurm(dir / "cluster");
  if (!slurm.why.empty()) GTEST_SKIP() << "no Slurm cluster on localhost: " << slurm.why;
  ASSERT_EQ(runGabion("run " + kSweep + " -q -o " + (dir / "local").string()).exit_code, 0);
  const fs::path out = dir / "array";
  auto r = runGabion("submit slurm " + kSweep + " -o " + out.string() + " --rows-per-task 5 --max-parallel 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("24 rows in 5 array tasks of up to 5 rows"), std::string::npos) << r.output;
  const std::string job = jobIdOf(r.output);
  ASSERT_FALSE(job.empty()) << r.output;
  // The last task (rows 20-23) is cancelled before its turn comes.
  ASSERT_EQ(runCommand("scancel " + job + "_4").exit_code, 0);
  ASSERT_TRUE(LocalSlurm::waitFor(job)) << runCommand("squeue").output;
  const std::string script = readText(out / "slurm" / "job-1.sh");
  EXPECT_NE(script.find("#SBATCH --array=0-4%1"), std::string::npos) << script;
  EXPECT_EQ(readText(out / "slurm" / "job-1.tasks"), "0:5\n5:10\n10:15\n15:20\n20:24\n");

  r = runGabion("collect " + out.string());
  ASSERT_EQ(r.exit_code, 4) << r.output;
  const std::string abs = fs::absolute(out).string();
  EXPECT_NE(r.output.find("gabion submit slurm --resume " + abs + " --rows 20:24"), std::string::npos) << r.output;

  r = runGabion("submit slurm --resume " + abs + " --rows missing");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("4 rows in 1 array task of up to 4 rows"), std::string::npos) << r.output;
  ASSERT_TRUE(LocalSlurm::waitFor(jobIdOf(r.output)));
  EXPECT_TRUE(fs::is_regular_file(out / "slurm" / "job-2.sh")) << "the first script is kept";
  r = runGabion("collect " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectSameTable(dir / "local", out);
  const auto row = nlohmann::json::parse(std::ifstream(out / "rows" / "0" / "row.json"));
  EXPECT_FALSE(row.at("host").get<std::string>().empty());

  // A running task killed (scancel: SIGTERM) keeps the rows it finished; the
  // rest of its bundle is missing, and resubmitted alone.
  const std::string big = std::string(GABION_SOURCE_DIR) + "/cases/macro_sweep.json --set sweep.velocity_m_s.count=200";
  ASSERT_EQ(runGabion("run " + big + " -q --threads 2 -o " + (dir / "local_big").string()).exit_code, 0);
  const fs::path killed = dir / "killed";
  r = runGabion("submit slurm " + big + " -o " + killed.string() + " --rows-per-task 600 --max-parallel 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string big_job = jobIdOf(r.output);
  const auto rowsDone = [&] {
    std::error_code ec;
    if (!fs::is_directory(killed / "rows", ec)) return 0;
    return static_cast<int>(std::distance(fs::directory_iterator(killed / "rows", ec), fs::directory_iterator()));
  };
  for (int i = 0; i < 1200 && rowsDone() < 50; ++i) usleep(50000);
  ASSERT_GE(rowsDone(), 50) << "the first task did not start";
  ASSERT_EQ(runCommand("scancel " + big_job + "_0").exit_code, 0);
  ASSERT_TRUE(LocalSlurm::waitFor(big_job)) << runCommand("squeue").output;
  r = runGabion("collect " + killed.string());
  ASSERT_EQ(r.exit_code, 4) << "the task ended before it was killed: " << r.output;
  const int kept = rowsDone();
  EXPECT_GE(kept, 650) << "the second task ran whole, and the first kept its rows";
  EXPECT_LT(kept, 1200);
  r = runGabion("submit slurm --resume " + killed.string() + " --rows missing");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(LocalSlurm::waitFor(jobIdOf(r.output))) << runCommand("squeue").output;
  r = runGabion("collect " + killed.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expectSameTable(dir / "local_big", killed);
}
