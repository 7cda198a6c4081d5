// The command line's contract: version, exit code 2 with a message naming the
// file and the field for bad input, and nothing written for a rejected case.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "bridge/output.hpp"
#include "tests/support/run_gabion.hpp"

using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::writeFile;

TEST(Cli, Version) {
  const auto r = runGabion("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("gabion "), std::string::npos);
}

TEST(Cli, BadInputsExitTwoAndNameTheField) {
  const auto dir = scratchDir("cli_bad");
  struct Case {
    const char* name;
    const char* text;  // nullptr: the file is not created
    const char* expected;
  };
  const Case cases[] = {
      {"missing_file", nullptr, "file does not exist"},
      {"not_json", "{ \"format\": ", "invalid JSON"},
      {"not_object", "[1, 2]", "top level must be a JSON object"},
      {"no_format", "{\"kind\": \"micro.scene\"}", "/format: missing required key"},
      {"wrong_format", "{\"format\": \"gabion.case/9\", \"kind\": \"x\"}", "/format: expected 'gabion.case/1'"},
      {"unknown_kind", "{\"format\": \"gabion.case/1\", \"kind\": \"no.such.kind\"}", "/kind: unknown case kind"},
      {"number_overflow", "{\"format\": \"gabion.case/1\", \"kind\": \"macro.impact\", \"x\": 1e400}",
       "number overflow parsing '1e400'"},
  };
  for (const auto& c : cases) {
    const auto path = dir / (std::string(c.name) + ".json");
    if (c.text != nullptr) writeFile(path, c.text);
    const auto r = runGabion("check " + path.string());
    EXPECT_EQ(r.exit_code, 2) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find(path.string()), std::string::npos) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.name << ": " << r.output;
    const auto out = dir / (std::string("out_") + c.name);
    const auto rr = runGabion("run " + path.string() + " -q -o " + out.string());
    EXPECT_EQ(rr.exit_code, 2) << c.name;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.name << ": a rejected case must write nothing";
  }
}

// Command-line mistakes are bad input too (exit 2, not the parser's own
// codes), as is an output folder that cannot be made or a --set value
// beyond double; --help and --version exit 0.
TEST(Cli, CommandLineMistakesExitTwo) {
  const auto dir = scratchDir("cli_mistakes");
  const std::string wall = std::string(GABION_SOURCE_DIR) + "/cases/wall_impact.json";
  writeFile(dir / "a_file", "x");
  const struct {
    std::string args, expected;
  } cases[] = {
      {"run", "gabion run: give a case file, or --resume OUTDIR"},
      {"run " + wall + " --threads 0", "--threads"},
      {"run " + wall + " --no-such-option", "--no-such-option"},
      {"no-such-command", "A subcommand is required"},
      {"run " + wall + " -q -o " + (dir / "a_file" / "out").string(), "cannot make the output folder (-o)"},
      {"run " + wall + " -q -o " + (dir / "o").string() + " --set boulder.velocity_m_s=1e400",
       "--set 'boulder.velocity_m_s=1e400': number overflow"},
  };
  for (const auto& c : cases) {
    const auto r = runGabion(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << ": " << r.output;
  }
  EXPECT_EQ(runGabion("--help").exit_code, 0);
  EXPECT_EQ(runGabion("run --help").exit_code, 0);
}

// `gabion plot`: the standard figure of a structure impact's result file, as
// PNG beside it or as the SVG asked for; a file with nothing to draw (or none
// at all) exits 2 naming it.
TEST(Cli, PlotDrawsTheStandardFigureOfAResult) {
  const auto dir = scratchDir("cli_plot");
  auto r = runGabion("run " + std::string(GABION_SOURCE_DIR) + "/cases/wall_impact.json -q -o " +
                     (dir / "wall").string() + " --set boulder.velocity_m_s=10");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = runGabion("plot " + (dir / "wall" / "result.h5").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream png(dir / "wall" / "result.png", std::ios::binary);
  std::string head(8, '\0');
  png.read(head.data(), 8);
  EXPECT_EQ(head, std::string("\x89PNG\r\n\x1a\n", 8));
  r = runGabion("plot " + (dir / "wall" / "result.h5").string() + " -o " + (dir / "force.svg").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream svg(dir / "force.svg");
  const std::string text((std::istreambuf_iterator<char>(svg)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("<svg"), std::string::npos);
  EXPECT_GT(text.size(), 2000u);

  for (const std::string& bad : {(dir / "none.h5").string(), (dir / "wall" / "summary.json").string()}) {
    r = runGabion("plot " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find(bad), std::string::npos) << r.output;
  }
}

// SIGINT (or SIGTERM) stops a run cleanly: it ends with 128 + the signal,
// says where it stopped, and leaves a summary with status "interrupted"
// beside the result file written so far (not an empty folder). A sweep
// lists every point, those not run marked so.
TEST(Cli, InterruptStopsTheRunAndKeepsWhatItWrote) {
  const auto dir = scratchDir("cli_interrupt");
  const std::string source = GABION_SOURCE_DIR;
  // (a fill of blocks that runs for tens of seconds; stopped half a second
  // after its stepping began, when its result file was opened: a loaded
  // machine may take longer than that to set it up)
  const std::string part = (dir / "fill" / "result.h5.part").string();
  const auto r = gabion::testing::runCommand("sh -c '" + std::string(GABION_BINARY) + " run " + source +
                                             "/cases/micro_block_fill.json -q -o " + (dir / "fill").string() +
                                             " & p=$!; while [ ! -e " + part +
                                             " ] && kill -0 $p 2>/dev/null; do sleep 0.01; done; sleep 0.5; "
                                             "kill -INT $p; wait $p; echo exit=$?'");
  EXPECT_NE(r.output.find("exit=130"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("interrupted by SIGINT at step"), std::string::npos) << r.output;
  std::ifstream in(dir / "fill" / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary.at("status"), "interrupted");
  EXPECT_EQ(summary.at("ended_by"), "interrupt");
  // The result file was closed whole: it opens, and its series reach the step the signal stopped.
  const gabion::bridge::H5Reader h5(dir / "fill" / "result.h5");
  const auto time = h5.read("/series/time_s");
  ASSERT_FALSE(time.empty());
  // (the last series sample: within one series interval, 5 ms in this case, of the last step)
  const double stopped_at = summary.at("steps").get<double>() * summary.at("dt_s").get<double>();
  EXPECT_GT(stopped_at, 0.0);
  EXPECT_NEAR(time.back(), stopped_at, 0.0051);
  EXPECT_FALSE(h5.read("/bodies/position_m").empty());

  // A sweep of 60,000 points (minutes), stopped by SIGTERM once it has
  // logged some rows.
  const std::string rows = (dir / "sweep" / "rows.jsonl").string();
  const auto w = gabion::testing::runCommand(
      "sh -c '" + std::string(GABION_BINARY) + " run " + source + "/cases/macro_sweep.json -q -o " +
      (dir / "sweep").string() + " --set sweep.velocity_m_s.count=10000 & p=$!; while [ $(cat " + rows +
      " 2>/dev/null | wc -l) -lt 10 ] && kill -0 $p 2>/dev/null; do sleep 0.02; done; kill -TERM $p; wait $p; echo "
      "exit=$?'");
  EXPECT_NE(w.output.find("exit=143"), std::string::npos) << w.output;
  std::ifstream sin(dir / "sweep" / "summary.json");
  const auto sweep = nlohmann::json::parse(sin);
  EXPECT_EQ(sweep.at("status"), "interrupted");
  EXPECT_EQ(sweep.at("points"), 60000);
  std::ifstream csv(dir / "sweep" / "sweep.csv");
  const std::string table((std::istreambuf_iterator<char>(csv)), std::istreambuf_iterator<char>());
  EXPECT_NE(table.find("not run: interrupted by SIGTERM"), std::string::npos);
  EXPECT_NE(table.find(",ok,"), std::string::npos) << "the points run before the signal are in the table";
}

// A reused output folder: the run lists the files it wrote, and counts the
// older ones instead of passing them off as its results.
TEST(Cli, AReusedOutputFolderListsOnlyThisRunsFiles) {
  const auto dir = scratchDir("cli_reused_out");
  std::filesystem::create_directories(dir / "out");
  writeFile(dir / "out" / "stale_table.csv", "left by an earlier run\n");
  std::filesystem::last_write_time(dir / "out" / "stale_table.csv",
                                   std::filesystem::file_time_type::clock::now() - std::chrono::hours(1));
  const auto r =
      runGabion("run " + std::string(GABION_SOURCE_DIR) + "/cases/wall_impact.json -q -o " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("  summary.json"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("stale_table.csv"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(and 1 older file, not from this run)"), std::string::npos) << r.output;
}

// A write that fails (here past a file-size limit, as on a full disk) ends
// the run with exit 1 and a message naming the file and the room left, not
// a crash: HDF5 crashed closing such a file (SIGSEGV). The folder keeps the
// earlier run's complete files, byte for byte, and no temporary file.
TEST(Cli, AFailedWriteEndsTheRunWithAMessageAndKeepsTheEarlierFiles) {
  const auto dir = scratchDir("cli_full_disk");
  const std::string run = std::string(GABION_BINARY) + " run " + std::string(GABION_SOURCE_DIR) +
                          "/cases/wall_impact.json -q -o " + (dir / "out").string();
  ASSERT_EQ(gabion::testing::runCommand(run).exit_code, 0);
  const auto read = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string h5 = read(dir / "out" / "result.h5"), summary = read(dir / "out" / "summary.json");
  ASSERT_GT(h5.size(), 100000u);
  // 100 blocks of 512 bytes: the result (about 300 kB) does not fit.
  const auto r = gabion::testing::runCommand("sh -c 'ulimit -f 100; " + run + "'");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cannot write " + (dir / "out" / "result.h5").string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(ulimit -f)"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("H5Dclose failed\n"), std::string::npos) << "HDF5's own printing stays quiet: " << r.output;
  EXPECT_EQ(read(dir / "out" / "result.h5"), h5);
  EXPECT_EQ(read(dir / "out" / "summary.json"), summary);
  for (const auto& entry : std::filesystem::directory_iterator(dir / "out"))
    EXPECT_NE(entry.path().extension(), ".part") << entry.path();
}

// An output folder is committed as a set: manifest.json, written last,
// lists this run's files with their sizes, and `plot` reads only what it
// lists. A run killed in a reused folder leaves no manifest, so the earlier
// run's files there are no longer taken for results.
TEST(Cli, AnOutputFolderIsCommittedAsASet) {
  const auto dir = scratchDir("cli_manifest");
  const std::string source = GABION_SOURCE_DIR;
  const auto out = dir / "out";
  ASSERT_EQ(runGabion("run " + source + "/cases/wall_impact.json -q -o " + out.string()).exit_code, 0);
  const auto manifest = nlohmann::json::parse(std::ifstream(out / "manifest.json"));
  EXPECT_EQ(manifest.at("format"), "gabion.manifest/1");
  EXPECT_EQ(manifest.at("status"), "ok");
  std::set<std::string> listed;
  for (const auto& f : manifest.at("files")) {
    listed.insert(f.at("path").get<std::string>());
    EXPECT_EQ(f.at("bytes").get<std::uintmax_t>(), std::filesystem::file_size(out / f.at("path").get<std::string>()));
  }
  EXPECT_EQ(listed, (std::set<std::string>{"result.h5", "result.xdmf", "run.json", "summary.json"}));
  EXPECT_EQ(runGabion("plot " + (out / "result.h5").string()).exit_code, 0);

  // A file the run did not write is not read as its result.
  std::filesystem::copy_file(out / "result.h5", out / "other.h5");
  auto r = runGabion("plot " + (out / "other.h5").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("other.h5: not listed in " + (out / "manifest.json").string()), std::string::npos)
      << r.output;

  // A run killed in the folder: the manifest is gone with the set it vouched for.
  // (killed once it writes its result, not after a set time: on a loaded
  // machine a second was not always enough for it to start)
  const std::string killed = gabion::testing::signalWhenThere(
      "run " + source + "/cases/micro_block_fill.json -q -o " + out.string(), out / "result.h5.part", "KILL");
  EXPECT_NE(killed.find("exit=137"), std::string::npos) << killed;
  EXPECT_FALSE(std::filesystem::exists(out / "manifest.json"));
  r = runGabion("plot " + (out / "result.h5").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no manifest.json beside it or above it"), std::string::npos) << r.output;
}

// Every case is costed before it runs. Past the limits (a day on one thread,
// 80 % of the memory, the disk's free space) it is refused with exit 2 and
// the estimate, nothing written; --force runs it, saying what it will cost.
TEST(Cli, ACaseOverTheCostLimitsIsRefusedUnlessForced) {
  const auto dir = scratchDir("cli_cost");
  const std::string fill = std::string(GABION_SOURCE_DIR) + "/cases/micro_block_fill.json";
  auto r = runGabion("check " + fill);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cost: 7920 bodies, at most 47995 steps"), std::string::npos) << r.output;

  // 2e4 s of the fill: 6.4e8 steps of 7,920 bodies, 39 hours.
  const std::string longer =
      " --set run.duration_s=2e4 --set run.output_interval_s=1e4 --set run.series_interval_s=1e4";
  r = runGabion("run " + fill + " -q -o " + (dir / "refused").string() + longer);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("refused before it starts: it may take 39.4 h, more than a day"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--force"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "refused"));

  r = gabion::testing::runCommand("sh -c '" + std::string(GABION_BINARY) + " run " + fill + " -q --force -o " +
                                  (dir / "forced").string() + longer +
                                  " & p=$!; sleep 2; kill -INT $p; wait $p; echo exit=$?'");
  EXPECT_NE(r.output.find("exit=130"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gabion: this run: 7920 bodies, at most 639926762 steps, up to 39.4 h"), std::string::npos)
      << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "forced" / "summary.json"));
  EXPECT_EQ(summary.at("status"), "interrupted");
  EXPECT_NEAR(summary.at("estimate").at("wall_time_s").get<double>(), 1.42e5, 0.01e5);
}

// A sweep killed with SIGKILL keeps the rows it finished (rows.jsonl);
// `gabion run --resume OUTDIR` runs only the rest, and its table is the
// uninterrupted run's, bit for bit.
TEST(Cli, AKilledSweepResumesToTheSameTable) {
  const auto dir = scratchDir("cli_sweep_resume");
  const std::string run = std::string(GABION_BINARY) + " run " + std::string(GABION_SOURCE_DIR) +
                          "/cases/macro_sweep.json -q --threads 2 --set sweep.velocity_m_s.count=400 -o ";
  ASSERT_EQ(gabion::testing::runCommand(run + (dir / "whole").string()).exit_code, 0);
  const auto killed = dir / "killed";
  const auto rows = (killed / "rows.jsonl").string();
  const auto r = gabion::testing::runCommand(
      "sh -c '" + run + killed.string() + " & p=$!; while [ $(cat " + rows +
      " 2>/dev/null | wc -l) -lt 100 ]; do sleep 0.02; done; kill -KILL $p; wait $p; echo exit=$?'");
  ASSERT_NE(r.output.find("exit=137"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(killed / "manifest.json"));

  const auto resumed = runGabion("run --resume " + killed.string() + " -q");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const auto summary = nlohmann::json::parse(std::ifstream(killed / "summary.json"));
  const auto reused = summary.at("points_reused").get<long long>();
  EXPECT_GE(reused, 99);
  EXPECT_LT(reused, summary.at("points").get<long long>()) << "the kill came after the sweep ended";
  const gabion::bridge::H5Reader a(dir / "whole" / "result.h5"), b(killed / "result.h5");
  for (const char* column : {"velocity_m_s", "mass_kg", "peak_force_N", "max_penetration_m", "contact_duration_s",
                             "max_back_face_displacement_m", "plastic_energy_J", "outcome"}) {
    const auto x = a.read(std::string("/table/") + column), y = b.read(std::string("/table/") + column);
    ASSERT_EQ(x.size(), y.size()) << column;
    for (std::size_t i = 0; i < x.size(); ++i)
      EXPECT_TRUE(x[i] == y[i] || (std::isnan(x[i]) && std::isnan(y[i]))) << column << "[" << i << "]";
  }
  const auto read = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  EXPECT_EQ(read(dir / "whole" / "sweep.csv"), read(killed / "sweep.csv"));

  // --resume continues a run as it was: no case, --set or -o beside it.
  const auto bad = runGabion("run cases/macro_sweep.json --resume " + killed.string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--resume continues a run as it was started"), std::string::npos) << bad.output;
}
