// Checkpoints of fine-DEM runs (micro/checkpoint.hpp): an engine loaded from
// a checkpoint steps on exactly as the one saved; saving changes nothing; a
// run killed (SIGKILL) or stopped (SIGINT) and resumed gives the arrays of a
// run never stopped, bit for bit, for a scene and for a whole cell
// generation (blocks, bending wires, servo and vibrating plates, stages).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../support/run_gabion.hpp"
#include "../support/small_cell.hpp"
#include "bridge/output.hpp"
#include "bridge/state_archive.hpp"
#include "micro/engine.hpp"
#include "micro_test_util.hpp"

namespace {

using gabion::bridge::H5Reader;
using gabion::bridge::H5Writer;
using gabion::bridge::StateArchive;
using gabion::micro::Engine;
using gabion::micro::StepStatus;
using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::signalWhenThere;
using gabion::testing::summaryOf;
using gabion::testing::writeFile;

std::uint64_t digest(Engine& e) {
  StateArchive d = StateArchive::digesting();
  e.archive(d);
  return d.digest();
}

void steps(Engine& e, int from, int to) {
  for (int n = from; n < to; ++n) ASSERT_EQ(e.step(n % 50 == 0), StepStatus::Ok) << e.failure();
}

TEST(MicroCheckpoint, AnEngineLoadedFromACheckpointStepsOnAsTheOneSaved) {
  const auto dir = scratchDir("checkpoint_engine");
  const gabion::micro::Scene scene = gabion::micro::test::everyStage();
  for (const int threads : {1, 2}) {
    const auto file = dir / ("state_" + std::to_string(threads) + ".h5");
    Engine a(scene, threads), c(scene, threads);
    const double dt = 0.2 * a.criticalDt();
    a.setDt(dt), c.setDt(dt);
    steps(a, 0, 700);
    {
      H5Writer w(file);
      StateArchive s = StateArchive::saving(w);
      a.archive(s);
      w.commit();
    }
    const std::uint64_t at_save = digest(a);
    steps(a, 700, 1500);
    steps(c, 0, 1500);
    // Saving changed nothing: the engine that never saved is where the saved one is.
    EXPECT_EQ(digest(a), digest(c)) << threads << " threads";

    Engine b(scene, threads);
    b.setDt(dt);
    const H5Reader r(file);
    StateArchive l = StateArchive::loading(r, file.string());
    b.archive(l);
    EXPECT_EQ(digest(b), at_save);
    EXPECT_EQ(b.steps(), 700);
    // A field a newer build adds is not in this file: has() says so, and
    // only when loading (a part then keeps its fallback).
    EXPECT_FALSE(l.has("no_such_field"));
    EXPECT_FALSE(l.group("links").has("no_such_field"));
    EXPECT_TRUE(StateArchive::digesting().has("no_such_field"));
    steps(b, 700, 1500);
    EXPECT_EQ(digest(b), digest(a)) << threads << " threads: the loaded engine went its own way";
    EXPECT_EQ(b.time(), a.time());
    EXPECT_EQ(b.energy().balance_rel_error, a.energy().balance_rel_error);
    EXPECT_EQ(b.linkEvents().size(), a.linkEvents().size());

    // A state saved before the first step (no neighbour list yet: a run
    // stopped at once) loads as well.
    {
      Engine fresh(scene, threads), loaded(scene, threads);
      fresh.setDt(dt), loaded.setDt(dt);
      const auto zero = dir / ("zero_" + std::to_string(threads) + ".h5");
      {
        H5Writer w(zero);
        StateArchive s = StateArchive::saving(w);
        fresh.archive(s);
        w.commit();
      }
      const H5Reader z(zero);
      StateArchive lz = StateArchive::loading(z, zero.string());
      loaded.archive(lz);
      steps(loaded, 0, 1500);
      EXPECT_EQ(digest(loaded), digest(c)) << threads << " threads, from step 0";
    }

    // A state of another thread count (its row partitions) is refused.
    Engine other(scene, threads == 1 ? 2 : 1);
    StateArchive again = StateArchive::loading(r, file.string());
    EXPECT_ANY_THROW(other.archive(again));
  }
}

// Every dataset the two result files share a name for, compared bit for bit.
void expectSameArrays(const std::filesystem::path& a, const std::filesystem::path& b,
                      const std::vector<std::string>& datasets) {
  const H5Reader x(a), y(b);
  for (const std::string& d : datasets) {
    ASSERT_TRUE(x.has(d)) << a << " " << d;
    ASSERT_TRUE(y.has(d)) << b << " " << d;
    EXPECT_EQ(x.dims(d), y.dims(d)) << d;
    const auto u = x.read(d), v = y.read(d);
    ASSERT_EQ(u.size(), v.size()) << d;
    std::size_t differ = 0;
    for (std::size_t k = 0; k < u.size(); ++k) differ += u[k] == v[k] || (u[k] != u[k] && v[k] != v[k]) ? 0 : 1;
    EXPECT_EQ(differ, 0u) << d << ": " << differ << " of " << u.size() << " values differ";
  }
}

const std::vector<std::string> kSceneArrays = {"/bodies/time_s",
                                               "/bodies/position_m",
                                               "/bodies/velocity_m_s",
                                               "/bodies/angular_velocity_rad_s",
                                               "/series/time_s",
                                               "/series/kinetic_translational_J",
                                               "/series/total_J",
                                               "/series/balance_rel_error",
                                               "/series/contacts",
                                               "/series/walls/catch_plate/position_m",
                                               "/series/walls/side_servo/force_N",
                                               "/links/broken/time_s",
                                               "/links/broken/link",
                                               "/links/ends",
                                               "/links/intact/0"};

TEST(MicroCheckpoint, AKilledOrStoppedSceneResumesToTheSameArrays) {
  const auto dir = scratchDir("checkpoint_scene");
  const std::string scene = std::string(GABION_SOURCE_DIR) + "/cases/micro_net_and_plates.json";
  const std::string args = "run -q " + scene + " --set run.duration_s=4 -o ";
  ASSERT_EQ(runGabion(args + (dir / "whole").string()).exit_code, 0);
  {
    const nlohmann::json s = summaryOf(dir / "whole");
    ASSERT_GT(s.at("broken_links").get<int>(), 0) << "the scene should break links (their events are state)";
    EXPECT_EQ(s.at("checkpoints"), 0);  // (the default interval, ten minutes, is longer than the run)
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "whole" / "checkpoint"));

  // SIGKILL after the first checkpoint (one every 50 ms of wall time).
  const auto killed = dir / "killed";
  const std::string out = signalWhenThere(args + killed.string() + " --set run.checkpoint_every_s=0.05",
                                          killed / "checkpoint" / "state.h5", "KILL");
  ASSERT_NE(out.find("exit=137"), std::string::npos) << out;
  const auto resumed = runGabion("run --resume " + killed.string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("continuing from the checkpoint of step"), std::string::npos) << resumed.output;
  EXPECT_GT(summaryOf(killed).at("resumed_from_step").get<long long>(), 0);
  EXPECT_FALSE(std::filesystem::exists(killed / "checkpoint")) << "a run that ended keeps no checkpoint";
  expectSameArrays(dir / "whole" / "result.h5", killed / "result.h5", kSceneArrays);
  EXPECT_EQ(summaryOf(killed).at("energy"), summaryOf(dir / "whole").at("energy"));

  // SIGINT: the run saves its state where it stops, says how to go on, and continues from there.
  const auto stopped = dir / "stopped";
  const std::string stop = signalWhenThere(args + stopped.string(), stopped / "result.h5.part", "INT");
  ASSERT_NE(stop.find("exit=130"), std::string::npos) << stop;
  EXPECT_NE(stop.find("gabion run --resume continues it"), std::string::npos) << stop;
  EXPECT_EQ(summaryOf(stopped).at("status"), "interrupted");
  ASSERT_TRUE(std::filesystem::exists(stopped / "checkpoint" / "state.h5"));
  const double stepped_before = summaryOf(stopped).at("step_loop_wall_time_s").get<double>();
  const auto again = runGabion("run -q --resume " + stopped.string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  expectSameArrays(dir / "whole" / "result.h5", stopped / "result.h5", kSceneArrays);
  // Its wall time is the whole run's: the stopped run's stepping (up to its
  // checkpoint, within that run's step loop) and the resumed process's.
  {
    const nlohmann::json s = summaryOf(stopped);
    const double before = s.at("wall_time_before_resume_s").get<double>();
    EXPECT_GT(before, 0.0);
    EXPECT_LE(before, stepped_before);
    EXPECT_EQ(s.at("wall_time_s").get<double>(), s.at("wall_time_this_process_s").get<double>() + before);
  }
  EXPECT_FALSE(summaryOf(dir / "whole").contains("wall_time_before_resume_s"));

  // Another case into a folder with a checkpoint: not continued (it is not
  // this run's), and replaced by this run's end.
  const auto other = dir / "other";
  const std::string o = signalWhenThere(args + other.string(), other / "result.h5.part", "INT");
  ASSERT_NE(o.find("exit=130"), std::string::npos) << o;
  const auto fresh = runGabion("run " + scene + " --set run.duration_s=0.5 -o " + other.string());
  ASSERT_EQ(fresh.exit_code, 0) << fresh.output;
  EXPECT_EQ(fresh.output.find("continuing from the checkpoint"), std::string::npos) << fresh.output;
  EXPECT_NE(fresh.output.find("is of another run (case, threads or version): starting from the beginning"),
            std::string::npos)
      << fresh.output;
  EXPECT_FALSE(summaryOf(other).contains("resumed_from_step"));
  EXPECT_FALSE(std::filesystem::exists(other / "checkpoint"));
}

TEST(MicroCheckpoint, AKilledCellGenerationResumesToTheSameCell) {
  const auto dir = scratchDir("checkpoint_cell");
  nlohmann::json cell = nlohmann::json::parse(gabion::testing::smallCellCase());
  writeFile(dir / "cell.json", cell.dump());
  ASSERT_EQ(runGabion("run -q " + (dir / "cell.json").string() + " -o " + (dir / "whole").string()).exit_code, 0);
  cell["run"]["checkpoint_every_s"] = 0.2;
  writeFile(dir / "checkpointed.json", cell.dump());
  // Killed in the vibration stage (the fill ended; the stage's own folder has the checkpoint).
  const auto killed = dir / "killed";
  const std::string out = signalWhenThere("run -q " + (dir / "checkpointed.json").string() + " -o " + killed.string(),
                                          killed / "vibration" / "checkpoint" / "state.h5", "KILL");
  ASSERT_NE(out.find("exit=137"), std::string::npos) << out;
  const auto resumed = runGabion("run --resume " + killed.string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("micro.cell vibration: continuing from the checkpoint"), std::string::npos)
      << resumed.output;
  expectSameArrays(dir / "whole" / "cell.h5", killed / "cell.h5",
                   {"/blocks/position_m", "/blocks/orientation", "/blocks/velocity_m_s", "/spheres/center_m",
                    "/spheres/velocity_m_s", "/links/beam_moment_N_m", "/links/beam_shear_N"});
  for (const char* stage : {"vibration", "closing", "standing"})
    expectSameArrays(dir / "whole" / stage / "result.h5", killed / stage / "result.h5",
                     {"/bodies/position_m", "/series/time_s", "/series/total_J", "/series/elastic_link_J"});
  const nlohmann::json a = summaryOf(dir / "whole"), b = summaryOf(killed);
  EXPECT_EQ(a.at("porosity"), b.at("porosity"));
  EXPECT_EQ(a.at("porosity_after_vibration"), b.at("porosity_after_vibration"));
}

}  // namespace
