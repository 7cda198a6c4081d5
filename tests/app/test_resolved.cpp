// The resolved structure (docs/resolved.md): micro.structure lays out copies
// of a generated cell as a wall and strikes it; macro.resolved runs it beside
// its macro twin and compares them. A reduced case (2 x 1 x 1 small cells,
// a few thousand steps), as CI runs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "../support/run_gabion.hpp"
#include "../support/small_cell.hpp"
#include "bridge/output.hpp"

namespace {

using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::summaryOf;
using gabion::testing::writeFile;

// The boulder's momentum along x: m (v_end - v_0) = -(integral of the
// structure's force on it) over the series of the run in `dir` (trapezoids
// at 0.1 ms; gravity acts across x). The force is the one each sample read:
// the rule's error is of the order of the change within a sample, a few %
// of the momentum m v0.
void expectMomentumIsImpulse(const std::filesystem::path& dir, double mass, double v0) {
  const gabion::bridge::H5Reader h(dir / "result.h5");
  const auto t = h.read("/curves/impact/time_s"), f = h.read("/curves/impact/force_N"),
             v = h.read("/curves/impact/boulder_velocity_m_s");
  ASSERT_GT(t.size(), 10u);
  double impulse = 0.0;
  for (std::size_t k = 1; k < t.size(); ++k) impulse += 0.5 * (f[k] + f[k - 1]) * (t[k] - t[k - 1]);
  EXPECT_NEAR(mass * (v.front() - v.back()), impulse, 0.03 * mass * v0);
}

// The small cell made into dir/cell/ (cell.h5), and laws for it: the
// illustrative ones scaled to its 0.3 m edge (a hybrid's macro part only
// needs plausible ones); null if the cell could not be made.
nlohmann::json smallCellAndLaws(const std::filesystem::path& dir) {
  writeFile(dir / "cell.json", gabion::testing::smallCellCase());
  const auto made = runGabion("run -q " + (dir / "cell.json").string() + " -o " + (dir / "cell").string());
  EXPECT_EQ(made.exit_code, 0) << made.output;
  if (made.exit_code != 0) return nullptr;
  nlohmann::json laws =
      nlohmann::json::parse(std::ifstream(std::string(GABION_SOURCE_DIR) + "/cases/laws/illustrative.json"));
  for (auto& [name, m] : laws["materials"].items())
    m["edge_m"] = 0.3, m["mass_kg"] = m["mass_kg"].get<double>() * 0.216;
  return laws;
}

// Runs each case `dir`/<name>.json into `dir`/<name>/.
void runEach(const std::filesystem::path& dir, const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    const auto r = runGabion("run -q " + (dir / (name + ".json")).string() + " -o " + (dir / name).string());
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.output;
  }
}

// `bad` written into `dir` is refused by `gabion check` (exit 2), the
// message naming `pointer`.
void expectRefused(const std::filesystem::path& dir, const nlohmann::json& bad, const std::string& pointer) {
  writeFile(dir / "bad.json", bad.dump());
  const auto out = runGabion("check " + (dir / "bad.json").string());
  EXPECT_EQ(out.exit_code, 2) << out.output;
  EXPECT_NE(out.output.find(pointer), std::string::npos) << out.output;
}

// A hybrid macro.impact case on small cells (smallCellAndLaws' laws.json
// and cell): a wall of `cells`, its struck cell resolved alone, struck at
// 8 m/s after a set 0.01 s settling, 0.02 s of impact.
nlohmann::json struckCellResolved(const std::vector<int>& cells) {
  return {{"format", "gabion.case/1"},
          {"kind", "macro.impact"},
          {"law_file", "laws.json"},
          {"structure", {{"cells", cells}, {"material", {{"front", "front"}, {"core", "front"}}}}},
          {"boulder", {{"diameter_m", 0.25}, {"density_kg_m3", 2600}, {"velocity_m_s", 8}}},
          {"resolve",
           {{"cell", "cell/cell.h5"},
            {"within_m", 0.0},
            {"settle", {{"duration_s", 0.01}, {"until_at_rest", false}}},
            {"run", {{"duration_s", 0.02}}}}}};
}

// Runs `gabion <args>` into `killed`, kills it (SIGKILL) once its settling
// has written a checkpoint, and resumes it to the end: the resumed run
// says it continued the settling from there (its output into `said`).
void killInTheSettlingAndResume(const std::string& args, const std::filesystem::path& killed,
                                std::string* said = nullptr) {
  const std::string out = gabion::testing::signalWhenThere(args, killed / "settle" / "checkpoint" / "state.h5", "KILL");
  ASSERT_NE(out.find("exit=137"), std::string::npos) << out;
  const auto resumed = runGabion("run --resume " + killed.string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("micro.structure settle: continuing from the checkpoint"), std::string::npos)
      << resumed.output;
  if (said) *said = resumed.output;
}

const char* kStructure = R"({"format": "gabion.case/1", "kind": "micro.structure", "cell": "cell/cell.h5",
 "structure": {"cells": [2, 1, 1]}, "boulder": {"diameter_m": 0.25, "velocity_m_s": 8},
 "settle": {"duration_s": 0.01, "until_at_rest": false}, "run": {"duration_s": 0.03}})";

TEST(ResolvedStructure, TwoCellsStruckBeforeTheirMacroTwin) {
  const auto dir = scratchDir("resolved");
  writeFile(dir / "cell.json", gabion::testing::smallCellCase());
  ASSERT_EQ(runGabion("run -q " + (dir / "cell.json").string() + " -o " + (dir / "cell").string()).exit_code, 0);

  // The resolved structure alone.
  writeFile(dir / "structure.json", kStructure);
  const auto r = runGabion("run -q " + (dir / "structure.json").string() + " -o " + (dir / "structure").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json s = summaryOf(dir / "structure");
  EXPECT_EQ(s["cells"], nlohmann::json({2, 1, 1}));
  EXPECT_TRUE(s["touched"].get<bool>());
  EXPECT_GT(s["peak_force_N"].get<double>(), 0.0);
  EXPECT_GT(s["max_penetration_m"].get<double>(), 0.0);
  EXPECT_GE(s["max_front_face_displacement_m"].get<double>(), s["max_back_face_displacement_m"].get<double>())
      << "the struck layer moves more than the one held by the back support";
  EXPECT_LT(std::fabs(s["energy"]["balance_rel_error"].get<double>()), 0.05);
  EXPECT_TRUE(s.contains("settle"));
  // Cells made standing alone, stacked, slump under their weight at first
  // (their nettings take the fill's push the generation box took): after
  // 0.01 s (a set time: until_at_rest false) the stack still comes down,
  // and the run says it was struck in motion (46 mm/s at the test's
  // writing, against the 10 mm/s of at rest).
  EXPECT_GT(s["settle"]["descent_speed_m_s"].get<double>(), 0.01);
  EXPECT_FALSE(s["settled"].get<bool>());
  ASSERT_FALSE(s["warnings"].empty());
  EXPECT_NE(s["warnings"].dump().find("still settling"), std::string::npos) << s["warnings"].dump();
  // (a cell's largest move along x is at least the front face's)
  EXPECT_GE(s["max_cell_displacement_x_m"].get<double>(), s["max_front_face_displacement_m"].get<double>());
  EXPECT_GE(s["max_cell_displacement_across_m"].get<double>(), 0.0);
  expectMomentumIsImpulse(dir / "structure", s["boulder_mass_kg"].get<double>(), 8.0);
  // The contact's end above the boulder's weight: from the same first
  // contact as contact_duration_s (1 % of the peak), to the last sample of
  // the impact's force above m g, as its curve in result.h5 shows.
  {
    const gabion::bridge::H5Reader h5(dir / "structure" / "result.h5");
    const std::vector<double> t = h5.read("/curves/impact/time_s"), f = h5.read("/curves/impact/force_N");
    ASSERT_EQ(t.size(), f.size());
    const double peak = *std::max_element(f.begin(), f.end()), weight = s["boulder_mass_kg"].get<double>() * 9.81;
    double last_1 = NAN, last_weight = NAN;
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (f[k] > 0.01 * peak) last_1 = t[k];
      if (f[k] > weight) last_weight = t[k];
    }
    ASSERT_TRUE(std::isfinite(last_1) && std::isfinite(last_weight)) << "weight " << weight << " N, peak " << peak;
    const double above_weight = s["contact_duration_above_weight_s"].get<double>();
    EXPECT_GT(above_weight, 0.0);
    EXPECT_NEAR(s["contact_duration_s"].get<double>() - above_weight, last_1 - last_weight, 1e-12);
  }

  // Bad input is named before anything runs.
  {
    nlohmann::json c = nlohmann::json::parse(kStructure);
    c["boulder"]["aim_point_m"] = {5.0, 0.1};
    writeFile(dir / "off.json", c.dump());
    const auto bad = runGabion("check " + (dir / "off.json").string());
    EXPECT_EQ(bad.exit_code, 2) << bad.output;
    EXPECT_NE(bad.output.find("/boulder/aim_point_m"), std::string::npos) << bad.output;
    c = nlohmann::json::parse(kStructure);
    c["structure"]["cells"] = {20, 20, 20};
    writeFile(dir / "huge.json", c.dump());
    const auto huge = runGabion("check " + (dir / "huge.json").string());
    EXPECT_EQ(huge.exit_code, 2) << huge.output;
    EXPECT_NE(huge.output.find("/structure/cells"), std::string::npos) << huge.output;
  }

  // Beside its macro twin (laws for 0.5 m cells: the twin is not this
  // structure, and the run says so).
  writeFile(dir / "resolved.json", R"({"format": "gabion.case/1", "kind": "macro.resolved",
 "law_file": ")" + std::string(GABION_SOURCE_DIR) +
                                       R"(/cases/laws/illustrative.json", "cell": "cell/cell.h5",
 "structure": {"cells": [2, 1, 1], "material": {"front": "front", "core": "core", "front_depth_cells": 1}},
 "boulder": {"diameter_m": 0.25, "velocity_m_s": 8},
 "resolved": {"settle": {"duration_s": 0.01, "until_at_rest": false}, "run": {"duration_s": 0.03}},
 "hybrid": {"within_m": [0]}})");
  const auto both = runGabion("run " + (dir / "resolved.json").string() + " -o " + (dir / "both").string());
  ASSERT_EQ(both.exit_code, 0) << both.output;
  EXPECT_NE(both.output.find("resolved against its macro twin"), std::string::npos) << both.output;
  const nlohmann::json b = summaryOf(dir / "both");
  for (const char* key : {"peak_force_N", "max_penetration_m", "contact_duration_s", "max_back_face_displacement_m"}) {
    const double a = b[key].get<double>(), m = b["macro_twin"][key].get<double>();
    EXPECT_GT(a, 0.0) << key;
    EXPECT_DOUBLE_EQ(b["relative_error"][key].get<double>(), (m - a) / a) << key;
  }
  EXPECT_DOUBLE_EQ(b["peak_force_N"].get<double>(), summaryOf(dir / "both" / "resolved")["peak_force_N"].get<double>());
  EXPECT_DOUBLE_EQ(b["macro_twin"]["peak_force_N"].get<double>(),
                   summaryOf(dir / "both" / "macro_twin")["peak_force_N"].get<double>());
  EXPECT_GT(b["speed_up"].get<double>(), 1.0);
  // (the laws' cell is not this one; the wall, settled 0.01 s, was struck coming down)
  ASSERT_EQ(b["warnings"].size(), 2u) << b["warnings"].dump();
  EXPECT_NE(b["warnings"][0].get<std::string>().find("not the same structure"), std::string::npos);
  EXPECT_NE(b["warnings"][1].get<std::string>().find("before it came to rest"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "both" / "resolved_vs_macro.png"));
  // And the hybrid with the struck cell resolved, on the same keys.
  ASSERT_EQ(b["hybrids"].size(), 1u);
  const nlohmann::json& h = b["hybrids"][0];
  ASSERT_EQ(h["status"], "ok") << h.dump();
  EXPECT_EQ(h["resolved_cells"], 1);
  const nlohmann::json hs = summaryOf(dir / "both" / "hybrid_0");
  for (const char* key : {"peak_force_N", "max_penetration_m", "contact_duration_above_weight_s"}) {
    const double a = b[key].get<double>(), m = hs[key].get<double>();
    ASSERT_GT(a, 0.0) << key;
    EXPECT_DOUBLE_EQ(h["relative_error"][key].get<double>(), (m - a) / a) << key;
  }
  // (the contact above the weight: resolved and hybrids alone, the twin's boulder has none along x)
  EXPECT_FALSE(b["relative_error"].contains("contact_duration_above_weight_s"));
  EXPECT_GT(h["speed_up"].get<double>(), 0.0);
  EXPECT_NE(both.output.find("hybrid within 0 m"), std::string::npos) << both.output;
}

// By default the stack settles until it is at rest: the settling ends at the
// first sample, past settle.duration_s, where the centre of mass came down
// slower than 10 mm/s over the settling's last fifth, as its own series
// (the gravity potential's fall over weight and time) shows. Killed in the
// settling and resumed, the run settles and strikes the same wall: the
// samples the criterion reads are part of the checkpoint.
TEST(ResolvedStructure, SettlesUntilAtRestAndResumesToTheSameWall) {
  const auto dir = scratchDir("resolved_at_rest");
  writeFile(dir / "cell.json", gabion::testing::smallCellCase());
  ASSERT_EQ(runGabion("run -q " + (dir / "cell.json").string() + " -o " + (dir / "cell").string()).exit_code, 0);
  nlohmann::json c = nlohmann::json::parse(kStructure);
  c["settle"] = {{"duration_s", 0.05}};
  c["run"]["duration_s"] = 0.005;
  writeFile(dir / "structure.json", c.dump());
  const std::string args = "run -q " + (dir / "structure.json").string() + " -o ";
  const auto r = runGabion(args + (dir / "whole").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json s = summaryOf(dir / "whole");
  const nlohmann::json& settle = s["settle"];
  EXPECT_EQ(settle["ended_by"], "test") << "at rest before settle.longest_s (1 s)";
  EXPECT_TRUE(settle["until_at_rest"].get<bool>());
  const double at = settle["duration_s"].get<double>(), descent = settle["descent_speed_m_s"].get<double>();
  EXPECT_GE(at, 0.05);
  EXPECT_LT(at, 1.0);
  EXPECT_LE(descent, 0.01);
  EXPECT_TRUE(s["settled"].get<bool>());
  EXPECT_EQ(s["warnings"].dump().find("still settling"), std::string::npos) << s["warnings"].dump();
  {
    // Its cost, estimated before it ran: the settling (at most longest_s)
    // and the impact, each with its own outputs; no fewer steps than it
    // took, files within a few times what it wrote (the settling written
    // as the settling, not at the impact's snapshot interval).
    const nlohmann::json& e = s["estimate"];
    EXPECT_EQ(e["runs"], 2);
    EXPECT_GE(e["steps"].get<double>(), settle["steps"].get<double>() + s["steps"].get<double>());
    const double written = static_cast<double>(std::filesystem::file_size(dir / "whole" / "result.h5") +
                                               std::filesystem::file_size(dir / "whole" / "settle" / "result.h5"));
    EXPECT_GE(e["output_bytes"].get<double>(), 0.5 * written);
    EXPECT_LE(e["output_bytes"].get<double>(), 4.0 * written);
  }
  {
    // The criterion from the settling's own series: met at its last sample
    // and at no earlier one past the shortest time.
    const gabion::bridge::H5Reader h(dir / "whole" / "settle" / "result.h5");
    const auto t = h.read("/series/time_s"), u = h.read("/series/gravity_potential_J");
    const double weight = 2.0 * summaryOf(dir / "whole")["cell_mass_kg"].get<double>() * 9.81;
    const auto speed = [&](std::size_t n) {  // (over the first n samples' last fifth)
      const std::size_t k = std::min(n - 2, (4 * n) / 5);
      return (u[k] - u[n - 1]) / (weight * (t[n - 1] - t[k]));
    };
    ASSERT_GT(t.size(), 10u);
    EXPECT_NEAR(speed(t.size()), descent, 1e-9);
    // (how far the stack came down: the potential's fall over the weight)
    EXPECT_NEAR(settle["centre_of_mass_drop_m"].get<double>(), (u.front() - u.back()) / weight, 1e-9);
    EXPECT_GT(settle["centre_of_mass_drop_m"].get<double>(), 0.0);
    // (its bodies' speed at the end: from their kinetic energy over their mass)
    const double rms = settle["rms_speed_m_s"].get<double>();
    EXPECT_NEAR(rms, std::sqrt(2.0 * settle["energy"]["kinetic_translational_J"].get<double>() * 9.81 / weight), 1e-9);
    EXPECT_GT(rms, 0.0);
    EXPECT_LT(rms, 0.5);
    // (the struck cell, on the base, came down a little: the aim, its laid-out
    // mid-height by default, is that much higher above its blocks)
    EXPECT_LT(std::fabs(settle["struck_cell_drop_m"].get<double>()), 0.02);
    EXPECT_TRUE(std::isfinite(settle["aim_above_struck_cell_m"].get<double>()));
    for (std::size_t n = 2; n + 1 < t.size(); ++n) {
      if (t[n - 1] + 1e-4 >= 0.05) {
        ASSERT_GT(speed(n), 0.01) << "at rest already at t = " << t[n - 1];
      }
    }
  }
  {
    // At rest also by the bodies' speed: asked for half the rms speed the
    // plain settling ended at, it settles longer, and ends below that bound
    // or, at settle.longest_s, says it was still moving. And aimed at the
    // settled cell: the boulder comes that much lower than laid out.
    const double rms = settle["rms_speed_m_s"].get<double>(), bound = 0.5 * rms;
    nlohmann::json still = c;
    still["settle"]["at_rest_rms_speed_m_s"] = bound;
    still["settle"]["longest_s"] = at + 0.2;
    still["settle"]["aim"] = "settled_cell";
    writeFile(dir / "still.json", still.dump());
    const auto rs = runGabion("run -q " + (dir / "still.json").string() + " -o " + (dir / "still").string());
    ASSERT_EQ(rs.exit_code, 0) << rs.output;
    const nlohmann::json ss = summaryOf(dir / "still");
    EXPECT_GT(ss["settle"]["duration_s"].get<double>(), at);
    EXPECT_EQ(ss["settle"]["at_rest_rms_speed_m_s"].get<double>(), bound);
    if (ss["settle"]["ended_by"] == "test") {
      EXPECT_LE(ss["settle"]["rms_speed_m_s"].get<double>(), bound);
      EXPECT_TRUE(ss["settled"].get<bool>());
    } else {
      EXPECT_GT(ss["settle"]["rms_speed_m_s"].get<double>(), bound);
      EXPECT_FALSE(ss["settled"].get<bool>());
      // (still moving, or, where it ended coming down, still settling)
      EXPECT_NE(ss["warnings"].dump().find("was still "), std::string::npos) << ss["warnings"].dump();
    }
    const double drop = ss["settle"]["struck_cell_drop_m"].get<double>(), laid_z = s["aim_point_m"][1].get<double>();
    EXPECT_GT(drop, 0.0);
    EXPECT_EQ(ss["settle"]["aim_lowered_m"].get<double>(), drop);
    EXPECT_NEAR(ss["aim_point_m"][1].get<double>(), laid_z - drop, 1e-12);
    EXPECT_EQ(ss["aim_point_m"][0], s["aim_point_m"][0]);
    // (the aim above the settled cell as the laid-out aim was above the laid-out cell)
    EXPECT_NEAR(ss["settle"]["aim_above_struck_cell_m"].get<double>(),
                settle["aim_above_struck_cell_m"].get<double>() - settle["struck_cell_drop_m"].get<double>(), 1e-12);
    // (the boulder, the largest body, starts at that height)
    const gabion::bridge::H5Reader h(dir / "still" / "result.h5");
    const auto radius = h.read("/bodies/radius_m"), pos = h.read("/bodies/position_m");
    const std::size_t b = static_cast<std::size_t>(std::max_element(radius.begin(), radius.end()) - radius.begin());
    EXPECT_NEAR(pos[3 * b + 2], laid_z - drop, 1e-9);
  }
  {
    // The settling's own local damping (settle.local_damping), for the
    // settling alone: at 0 the settling's bodies lose nothing to it, and the
    // impact, with the materials' own (the rock's 0.1), does; 1 or more is
    // refused, naming the field.
    nlohmann::json undamped = c;
    undamped["settle"]["local_damping"] = 0.0;
    undamped["settle"]["longest_s"] = at;
    writeFile(dir / "undamped.json", undamped.dump());
    const auto ru = runGabion("run -q " + (dir / "undamped.json").string() + " -o " + (dir / "undamped").string());
    ASSERT_EQ(ru.exit_code, 0) << ru.output;
    const nlohmann::json su = summaryOf(dir / "undamped");
    EXPECT_EQ(su["settle"]["local_damping"].get<double>(), 0.0);
    EXPECT_EQ(su["settle"]["energy"]["local_damping_dissipation_J"].get<double>(), 0.0);
    EXPECT_GT(settle["energy"]["local_damping_dissipation_J"].get<double>(), 0.0);  // (the plain settling's)
    EXPECT_GT(su["energy"]["local_damping_dissipation_J"].get<double>(), 0.0);
    EXPECT_FALSE(s["settle"].contains("local_damping"));
    undamped["settle"]["local_damping"] = 1.0;
    writeFile(dir / "overdamped.json", undamped.dump());
    const auto bad = runGabion("check " + (dir / "overdamped.json").string());
    EXPECT_EQ(bad.exit_code, 2) << bad.output;
    EXPECT_NE(bad.output.find("/settle/local_damping: must be in [0, 1)"), std::string::npos) << bad.output;
  }
  // Killed in the settling (after its first checkpoint), resumed.
  const auto killed = dir / "killed";
  ASSERT_NO_FATAL_FAILURE(
      killInTheSettlingAndResume(args + killed.string() + " --set run.checkpoint_every_s=0.05", killed));
  const nlohmann::json k = summaryOf(killed);
  EXPECT_EQ(k["settle"]["duration_s"], settle["duration_s"]);
  {
    // Its wall time counts the killed run's settling up to its checkpoint:
    // the settling's, carried up to the structure's whole time.
    const double before = k["settle"].value("wall_time_before_resume_s", 0.0);
    EXPECT_GT(before, 0.0);
    EXPECT_EQ(k.value("wall_time_before_resume_s", 0.0), before);
    EXPECT_EQ(k["wall_time_s"].get<double>(), k["wall_time_this_process_s"].get<double>() + before);
  }
  EXPECT_EQ(k["settle"]["descent_speed_m_s"], settle["descent_speed_m_s"]);
  for (const char* key : {"peak_force_N", "max_penetration_m", "max_back_face_displacement_m"})
    EXPECT_EQ(k[key], s[key]) << key;
  const gabion::bridge::H5Reader a(dir / "whole" / "result.h5"), b(killed / "result.h5");
  for (const char* name : {"/bodies/position_m", "/curves/impact/force_N"})
    EXPECT_EQ(a.read(name), b.read(name)) << name;
  EXPECT_FALSE(std::filesystem::exists(killed / "settle" / "checkpoint")) << "an ended run keeps no state";

  // Stopped (SIGINT) in the impact, once the settling has ended: the
  // settling's end is kept, and the resumed run takes it from there instead
  // of settling again, then goes on with the impact: the same wall struck.
  {
    const auto late = dir / "late";
    const std::string out = gabion::testing::signalWhenThere(args + late.string(), late / "result.h5.part", "INT");
    ASSERT_NE(out.find("exit=130"), std::string::npos) << out;
    ASSERT_TRUE(std::filesystem::exists(late / "settle" / "checkpoint" / "state.h5"))
        << "the settling's end is kept while the run is not over";
    {
      // The checkpoints on disk then, the settling's kept end and the
      // impact's own, are within the estimate's, which counts every
      // stage's checkpoint as it would be at the stage's end (the impact's
      // here holds its state and no rows yet).
      double on_disk = 0.0;
      for (const auto& d : {late / "settle" / "checkpoint", late / "checkpoint"})
        for (const auto& f : std::filesystem::recursive_directory_iterator(d))
          if (f.is_regular_file()) on_disk += static_cast<double>(f.file_size());
      const double announced = s["estimate"]["checkpoint_bytes"].get<double>();
      EXPECT_GE(announced, on_disk);
      EXPECT_LE(announced, 3.0 * on_disk);
    }
    const auto resumed = runGabion("run --resume " + late.string());
    ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
    EXPECT_NE(resumed.output.find("micro.structure settle: taking its end from the checkpoint"), std::string::npos)
        << resumed.output;
    EXPECT_NE(resumed.output.find("micro.structure: continuing from the checkpoint"), std::string::npos)
        << resumed.output;
    EXPECT_FALSE(std::filesystem::exists(late / "settle" / "checkpoint")) << "removed once the run is over";
    const nlohmann::json l = summaryOf(late);
    EXPECT_EQ(l["settle"]["energy"], settle["energy"]);
    EXPECT_EQ(l["settle"]["duration_s"], settle["duration_s"]);
    // (its settling's time is the stopped run's, carried by the kept end)
    EXPECT_GT(l["settle"]["wall_time_before_resume_s"].get<double>(), 0.0);
    for (const char* key : {"peak_force_N", "max_penetration_m", "max_back_face_displacement_m"})
      EXPECT_EQ(l[key], s[key]) << key;
    const gabion::bridge::H5Reader c2(late / "result.h5");
    for (const char* name : {"/bodies/position_m", "/curves/impact/force_N"})
      EXPECT_EQ(a.read(name), c2.read(name)) << name;
    EXPECT_EQ(gabion::bridge::H5Reader(dir / "whole" / "settle" / "result.h5").read("/bodies/position_m"),
              gabion::bridge::H5Reader(late / "settle" / "result.h5").read("/bodies/position_m"))
        << "the settling's result file, rewritten from its kept end";
  }

  // A longest settling shorter than the shortest is refused, named.
  c["settle"] = {{"duration_s", 0.2}, {"longest_s", 0.1}};
  expectRefused(dir, c, "/settle/longest_s");
}

// The mean x of the blocks of cell `slot` (blocks_per_cell each, after the
// spheres) at the first and last snapshot of the run in `dir`.
std::pair<double, double> cellX(const std::filesystem::path& dir, std::size_t slot, std::size_t blocks_per_cell) {
  const gabion::bridge::H5Reader h(dir / "result.h5");
  const auto t = h.read("/bodies/time_s"), x = h.read("/bodies/position_m");
  const std::size_t bodies = x.size() / (3 * t.size());
  const std::size_t first_block = bodies - 2 * blocks_per_cell;  // (two cells' blocks close the body list)
  double x0 = 0.0, x1 = 0.0;
  for (std::size_t b = 0; b < blocks_per_cell; ++b) {
    const std::size_t k = first_block + slot * blocks_per_cell + b;
    x0 += x[3 * k], x1 += x[3 * ((t.size() - 1) * bodies + k)];
  }
  return {x0 / blocks_per_cell, x1 / blocks_per_cell};
}

// Neighbouring cells laced once they have landed (lacing.at_s): two cells
// side by side, free at the back, the boulder striking the first. The
// lacing joins their facing edges where they landed (the small cell's
// upper ones, laid out at the cell's extent, land after about 0.1 s), and
// the settling goes on from there, its time counted from the start.
// Laced, the cell beside the struck one is dragged back with it (34 mm at
// the test's writing) and holds the struck one back; unlaced only friction
// between the nettings drags it (7 mm).
TEST(ResolvedStructure, LacedCellsDragTheirNeighbourAlong) {
  const auto dir = scratchDir("resolved_laced");
  writeFile(dir / "cell.json", gabion::testing::smallCellCase());
  ASSERT_EQ(runGabion("run -q " + (dir / "cell.json").string() + " -o " + (dir / "cell").string()).exit_code, 0);
  nlohmann::json c = nlohmann::json::parse(kStructure);
  c["structure"] = {{"cells", {1, 2, 1}}, {"support", {{"back", "none"}}}};
  c["boulder"]["aim_face_fraction"] = {0.25, 0.5};
  c["settle"] = {{"duration_s", 0.12}, {"until_at_rest", false}};
  c["run"]["duration_s"] = 0.1;
  writeFile(dir / "plain.json", c.dump());
  c["lacing"] = {{"at_s", 0.1}};
  writeFile(dir / "laced.json", c.dump());
  ASSERT_NO_FATAL_FAILURE(runEach(dir, {"plain", "laced"}));
  const nlohmann::json plain = summaryOf(dir / "plain"), laced = summaryOf(dir / "laced");
  EXPECT_FALSE(plain.contains("lacing"));
  const nlohmann::json& l = laced["lacing"];
  EXPECT_EQ(l["faces_laced"], 1);
  EXPECT_GE(l["links"].get<int>(), 10) << l.dump();
  EXPECT_NEAR(l["landed_in_s"].get<double>(), 0.1, 1e-4);
  // (the landing's steps and the rest's make the unlaced settling's, but for rounding at the split)
  EXPECT_NEAR(l["landing_steps"].get<double>() + laced["settle"]["steps"].get<double>(),
              plain["settle"]["steps"].get<double>(), 2.0);
  EXPECT_TRUE(std::filesystem::exists(dir / "laced" / "landing" / "result.h5"));
  EXPECT_EQ(laced["estimate"]["runs"], 3) << "the landing, the rest of the settling, the impact";
  EXPECT_EQ(plain["estimate"]["runs"], 2);
  // (the same steps, but for rounding at the split)
  EXPECT_NEAR(laced["estimate"]["steps"].get<double>(), plain["estimate"]["steps"].get<double>(), 2.0);
  // (the settling's time from the landing's start: the same 0.12 s as unlaced)
  EXPECT_NEAR(laced["settle"]["duration_s"].get<double>(), plain["settle"]["duration_s"].get<double>(), 1e-4);
  EXPECT_TRUE(laced["touched"].get<bool>());
  // The neighbour (cell 1, along y) moves back along x.
  const std::size_t bpc = summaryOf(dir / "cell")["blocks"].get<std::size_t>();
  const auto [p0, p1] = cellX(dir / "plain", 1, bpc);
  const auto [l0, l1] = cellX(dir / "laced", 1, bpc);
  const auto [s0, s1] = cellX(dir / "laced", 0, bpc);
  const auto [q0, q1] = cellX(dir / "plain", 0, bpc);
  EXPECT_GT(l1 - l0, 2.5 * (p1 - p0)) << "laced " << l1 - l0 << " m against " << p1 - p0 << " m unlaced";
  EXPECT_LT(s1 - s0, q1 - q0) << "the struck cell, laced, moves back less";
  EXPECT_GT(s1 - s0, 0.1) << "the struck cell moves back";

  // Killed in the settling after the lacing, resumed: the landing is
  // taken from the end it kept, the settling goes on from its checkpoint,
  // and the wall stands as the whole run's stood when the boulder came
  // (struck for 0.01 s only: the impact's first snapshot and its forces
  // over that time).
  const auto killed = dir / "killed";
  std::string said;
  ASSERT_NO_FATAL_FAILURE(
      killInTheSettlingAndResume("run -q " + (dir / "laced.json").string() + " -o " + killed.string() +
                                     " --set run.checkpoint_every_s=0.005 --set run.duration_s=0.01",
                                 killed, &said));
  EXPECT_NE(said.find("micro.structure landing: taking its end from the checkpoint"), std::string::npos) << said;
  EXPECT_FALSE(std::filesystem::exists(killed / "landing" / "checkpoint")) << "an ended run keeps no state";
  EXPECT_EQ(summaryOf(killed)["lacing"], l);
  EXPECT_EQ(summaryOf(killed)["settle"]["energy"], laced["settle"]["energy"]);
  const gabion::bridge::H5Reader a(dir / "laced" / "result.h5"), b(killed / "result.h5");
  const auto whole = a.read("/bodies/position_m"), again = b.read("/bodies/position_m");
  const std::size_t snapshot = whole.size() / a.read("/bodies/time_s").size();
  ASSERT_GE(again.size(), snapshot);
  EXPECT_TRUE(std::equal(again.begin(), again.begin() + static_cast<std::ptrdiff_t>(snapshot), whole.begin()));
  const auto f_whole = a.read("/curves/impact/force_N"), f_again = b.read("/curves/impact/force_N");
  ASSERT_GT(f_again.size(), 50u);
  ASSERT_GE(f_whole.size(), f_again.size());
  // (all but the last sample, taken at the shorter run's last step)
  EXPECT_TRUE(std::equal(f_again.begin(), f_again.end() - 1, f_whole.begin()));

  // Laced after the settling ends: refused, naming the field.
  c["lacing"]["at_s"] = 0.12;
  expectRefused(dir, c, "/lacing/at_s");
}

// Lacing pulled tight (lacing.pull_N): two small cells side by side, laced
// as laid out, the layout's gap between their facing edges closing as each
// lacing wire slides through its loops under the pull's tension until the
// settling ends (or its nodes come to two node radii apart). The wires'
// lengths shrink (`lacing/pulled_tight`), the cells stand closer than
// laced without the pull, and the wall is struck with the wires tied where
// they got to. Without a settling to pull it in, the pull is refused.
TEST(ResolvedStructure, LacingPulledTightDrawsTheCellsTogether) {
  const auto dir = scratchDir("resolved_pulled");
  writeFile(dir / "cell.json", gabion::testing::smallCellCase());
  ASSERT_EQ(runGabion("run -q " + (dir / "cell.json").string() + " -o " + (dir / "cell").string()).exit_code, 0);
  nlohmann::json c = nlohmann::json::parse(kStructure);
  c["structure"] = {{"cells", {1, 2, 1}}};
  c["settle"] = {{"duration_s", 0.06}, {"until_at_rest", false}};
  c["run"]["duration_s"] = 0.003;
  c["lacing"] = {{"at_s", 0.0}};
  writeFile(dir / "laced.json", c.dump());
  c["lacing"]["pull_N"] = 300.0;
  writeFile(dir / "pulled.json", c.dump());
  ASSERT_NO_FATAL_FAILURE(runEach(dir, {"laced", "pulled"}));
  const nlohmann::json laced = summaryOf(dir / "laced"), pulled = summaryOf(dir / "pulled");
  EXPECT_FALSE(laced["lacing"].contains("pulled_tight"));
  const nlohmann::json& l = pulled["lacing"];
  EXPECT_EQ(l["pull_N"], 300.0);
  ASSERT_TRUE(l.contains("pulled_tight")) << l.dump();
  const nlohmann::json& t = l["pulled_tight"];
  EXPECT_LT(t["mean_settled_m"].get<double>(), t["mean_laced_m"].get<double>() - 0.002) << t.dump();
  EXPECT_GE(t["least_settled_m"].get<double>(), l["shortest_m"].get<double>());
  // The cells' centres along y when the boulder came (the impact's first snapshot).
  const std::size_t bpc = summaryOf(dir / "cell")["blocks"].get<std::size_t>();
  const auto gap = [&](const char* name) {
    const gabion::bridge::H5Reader h(dir / name / "result.h5");
    const auto times = h.read("/bodies/time_s"), x = h.read("/bodies/position_m");
    const std::size_t bodies = x.size() / (3 * times.size()), first = bodies - 2 * bpc;
    double y[2] = {0.0, 0.0};
    for (std::size_t cell = 0; cell < 2; ++cell)
      for (std::size_t b = 0; b < bpc; ++b) y[cell] += x[3 * (first + cell * bpc + b) + 1] / static_cast<double>(bpc);
    return y[1] - y[0];
  };
  EXPECT_LT(gap("pulled"), gap("laced") - 0.001)
      << "pulled " << gap("pulled") << " m apart against " << gap("laced") << " m laced without the pull";
  EXPECT_LT(std::fabs(pulled["energy"]["balance_rel_error"].get<double>()), 0.05);
  EXPECT_LT(std::fabs(pulled["settle"]["energy"]["balance_rel_error"].get<double>()), 0.05);
  // Pulled with no settling to pull it in: refused, naming the field.
  c["settle"]["duration_s"] = 0.0;
  expectRefused(dir, c, "/lacing/pull_N");
}

// Lacing a cell that has no netting (two spheres saved as a cell, no links)
// is refused before anything runs, naming the field and the cell; without
// lacing the same case passes its check.
TEST(ResolvedStructure, LacingACellWithoutANettingIsRefused) {
  const auto dir = scratchDir("resolved_no_netting");
  writeFile(dir / "make.json", R"({"format": "gabion.case/1", "kind": "micro.scene", "gravity_m_s2": [0, 0, -9.81],
 "materials": {"rock": {"density_kg_m3": 2600, "normal_stiffness_N_m": 1e6, "shear_stiffness_N_m": 2.5e5,
               "friction": 0.5}},
 "spheres": [{"center_m": [0, 0, 0.05], "radius_m": 0.02, "material": "rock"},
             {"center_m": [0.03, 0, 0.1], "radius_m": 0.02, "material": "rock"}],
 "walls": [{"point_m": [0, 0, 0], "normal": [0, 0, 1], "material": "rock"}],
 "save_cell": true, "run": {"duration_s": 0.05}})");
  ASSERT_EQ(runGabion("run -q " + (dir / "make.json").string() + " -o " + (dir / "made").string()).exit_code, 0);
  nlohmann::json c = {{"format", "gabion.case/1"},
                      {"kind", "micro.structure"},
                      {"cell", "made/cell.h5"},
                      {"structure", {{"cells", {1, 2, 1}}}},
                      {"boulder", {{"diameter_m", 0.05}, {"velocity_m_s", 2}}},
                      {"settle", {{"duration_s", 0.01}, {"until_at_rest", false}}},
                      {"run", {{"duration_s", 0.01}}}};
  writeFile(dir / "plain.json", c.dump());
  const auto plain = runGabion("check " + (dir / "plain.json").string());
  EXPECT_EQ(plain.exit_code, 0) << plain.output;
  c["lacing"] = {{"at_s", 0.0}};
  expectRefused(dir, c, "/lacing: the cell");
  writeFile(dir / "laced.json", c.dump());
  const auto run = runGabion("run -q " + (dir / "laced.json").string() + " -o " + (dir / "laced").string());
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("has no netting to lace"), std::string::npos) << run.output;
}

// The hybrid: a macro.impact case with "resolve". The struck front cell is
// resolved; the cell behind it is a macro node whose front face is a plate
// in the fine scene. The work the plate does on the bodies and the work its
// force does on the node cancel to round-off; both parts together keep
// their energy; the boulder's momentum is the impulse of the force on it.
TEST(HybridStructure, StruckCellResolvedTheCellBehindAMacroNode) {
  const auto dir = scratchDir("hybrid");
  nlohmann::json laws = smallCellAndLaws(dir);
  ASSERT_FALSE(laws.is_null());
  writeFile(dir / "laws.json", laws.dump());
  nlohmann::json c = {{"format", "gabion.case/1"},
                      {"kind", "macro.impact"},
                      {"law_file", "laws.json"},
                      {"structure", {{"cells", {2, 1, 1}}, {"material", {{"front", "front"}, {"core", "core"}}}}},
                      {"boulder", {{"diameter_m", 0.25}, {"density_kg_m3", 2600}, {"velocity_m_s", 8}}},
                      {"resolve",
                       {{"cell", "cell/cell.h5"},
                        {"within_m", 0.0},
                        {"settle", {{"duration_s", 0.01}}},
                        {"run", {{"duration_s", 0.03}}}}}};
  writeFile(dir / "hybrid.json", c.dump());
  const auto r = runGabion("run " + (dir / "hybrid.json").string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 of 2 cells resolved"), std::string::npos) << r.output;
  const nlohmann::json s = summaryOf(dir / "out");
  const nlohmann::json& h = s["hybrid"];
  EXPECT_EQ(h["below"], "plates");
  EXPECT_EQ(h["resolved_cells"], nlohmann::json::parse("[[0, 0, 0]]"));
  ASSERT_EQ(h["interfaces"].size(), 1u);
  EXPECT_EQ(h["interfaces"][0]["axis"], "x");
  EXPECT_EQ(h["interfaces"][0]["side"], 1);
  EXPECT_EQ(h["macro_nodes"], 1);
  const double to_macro = h["work_on_macro_part_J"].get<double>();
  EXPECT_GT(to_macro, 0.0) << "the struck cell pushed the node behind it";
  EXPECT_NEAR(h["work_on_fine_part_J"].get<double>(), -to_macro, 1e-9 * to_macro);
  EXPECT_LT(std::fabs(h["balance_rel_error"].get<double>()), 0.02);
  EXPECT_GT(s["max_back_face_displacement_m"].get<double>(), 0.0) << "the macro node moved";
  // Each part's faces apart, the summary's the larger of the two: the
  // resolved cell is the front one, the back cell the macro node.
  ASSERT_TRUE(s.contains("max_face_displacement_by_part_m"));
  const nlohmann::json& parts = s["max_face_displacement_by_part_m"];
  for (const char* face : {"front", "back"})
    EXPECT_EQ(s[std::string("max_") + face + "_face_displacement_m"].get<double>(),
              std::max(parts[face]["fine"].get<double>(), parts[face]["macro"].get<double>()))
        << face;
  EXPECT_EQ(parts["back"]["macro"], s["max_back_face_displacement_m"]) << "the back cell is the macro node";
  // That node stands for its cell's front face (the plate behind the struck
  // cell moves with it); against the fixed back support its cell's centre,
  // which the back face measures everywhere else, moves half as far.
  {
    const gabion::bridge::H5Reader h5(dir / "out" / "result.h5");
    const std::vector<double> plate = h5.read("/series/walls/interface_0_x_plus/position_m");
    ASSERT_GT(plate.size(), 30u);
    double moved = 0.0;
    for (std::size_t q = 0; q < plate.size(); q += 3) moved = std::max(moved, plate[q] - plate[0]);
    EXPECT_GT(moved, 0.0);
    // (to 1e-3: the plate moves by the node's velocity times each step,
    // a little off the node's own integrated displacement)
    EXPECT_NEAR(parts["back"]["macro"].get<double>(), 0.5 * moved, 1e-3 * moved);
  }
  EXPECT_EQ(parts["back"]["fine"].get<double>(), 0.0) << "no resolved cell on the back face";
  EXPECT_TRUE(s["touched"].get<bool>());
  expectMomentumIsImpulse(dir / "out", s["boulder_mass_kg"].get<double>(), 8.0);
  // Bad input, named before anything runs.
  const auto refused = [&](const nlohmann::json& bad, const std::string& pointer) { expectRefused(dir, bad, pointer); };
  nlohmann::json bad = c;
  bad["resolve"]["within_m"] = 5.0;
  refused(bad, "/resolve/within_m");  // (the whole structure: larger than it)
  bad = c;
  bad["resolve"]["depth"] = "whole";  // (the struck cell and the one behind it: the whole 2 x 1 x 1 wall)
  refused(bad, "/resolve/within_m");
  bad = c;
  bad["resolve"]["depth"] = "all";
  refused(bad, "/resolve/depth");
  // Through the depth: on a 2 x 2 x 1 wall struck on a front cell, the
  // cell behind it is resolved too, so the fine part holds twice the
  // bodies, the boulder once (2 of 4 cells, against 1).
  const auto bodies = [&](const nlohmann::json& cs) {
    writeFile(dir / "wide.json", cs.dump());
    const auto out = runGabion("check " + (dir / "wide.json").string());
    EXPECT_EQ(out.exit_code, 0) << out.output;
    const auto at = out.output.find(" bodies");
    const auto from = out.output.rfind(' ', at - 1);
    return at == std::string::npos || from == std::string::npos ? 0.0
                                                                : std::stod(out.output.substr(from + 1, at - from - 1));
  };
  nlohmann::json wide = c;
  wide["structure"]["cells"] = {2, 2, 1};
  const double reach = bodies(wide);
  wide["resolve"]["depth"] = "whole";
  EXPECT_GT(reach, 0.0);
  EXPECT_DOUBLE_EQ(bodies(wide) - 1.0, 2.0 * (reach - 1.0));
  // The layers behind with a reach of their own: on a 2 x 3 x 1 wall struck
  // on its middle front cell, the front row within 0.25 m (3 cells) and,
  // behind it, the struck cell's alone (4 of 6 cells, against 3 within
  // reach); or the struck cell alone in front and the row behind it (4
  // cells again, the macro cells of the front layer in front of resolved
  // ones). Without depth "whole" it is refused.
  nlohmann::json row = c;
  row["structure"]["cells"] = {2, 3, 1};
  row["resolve"]["within_m"] = 0.25;
  const double front_row = bodies(row);
  row["resolve"]["depth"] = "whole";
  row["resolve"]["behind_within_m"] = 0.0;
  EXPECT_DOUBLE_EQ(bodies(row) - 1.0, 4.0 / 3.0 * (front_row - 1.0));
  nlohmann::json wider_behind = row;
  wider_behind["resolve"]["within_m"] = 0.0;
  wider_behind["resolve"]["behind_within_m"] = 0.25;
  EXPECT_DOUBLE_EQ(bodies(wider_behind) - 1.0, 4.0 / 3.0 * (front_row - 1.0));
  {  // (and it runs: the two cells behind macro front cells face them through a plate each)
    nlohmann::json cs = wider_behind;
    cs["resolve"]["settle"] = {{"duration_s", 0.02}, {"until_at_rest", false}};
    cs["resolve"]["run"] = {{"duration_s", 0.002}};
    writeFile(dir / "behind.json", cs.dump());
    const auto run = runGabion("run -q " + (dir / "behind.json").string() + " -o " + (dir / "behind").string());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const nlohmann::json behind = summaryOf(dir / "behind")["hybrid"];
    EXPECT_EQ(behind["resolved_cells"].size(), 4u);
    EXPECT_EQ(behind["behind_within_m"], 0.25);
    int in_front = 0;
    for (const auto& face : behind["interfaces"]) in_front += face["axis"] == "x" && face["side"] == -1 ? 1 : 0;
    EXPECT_EQ(in_front, 2);
    EXPECT_LT(std::fabs(behind["balance_rel_error"].get<double>()), 0.02);
  }
  bad = row;
  bad["resolve"]["depth"] = "reach";
  refused(bad, "/resolve/behind_within_m");
  // Below: on a 2 x 1 x 2 wall struck on its upper front cell, the cell under
  // it is resolved too (2 cells, against 1); on a wall one cell high,
  // nothing is below.
  nlohmann::json column = c;
  column["structure"]["cells"] = {2, 1, 2};
  const double alone = bodies(column);
  column["resolve"]["below"] = "cells";
  EXPECT_DOUBLE_EQ(bodies(column) - 1.0, 2.0 * (alone - 1.0));
  wide["resolve"]["below"] = "cells";
  EXPECT_DOUBLE_EQ(bodies(wide) - 1.0, 2.0 * (reach - 1.0));
  bad = c;
  bad["resolve"]["below"] = "all";
  refused(bad, "/resolve/below");
  bad = c;
  bad["resolve"]["above"] = "heavy";
  refused(bad, "/resolve/above");
  bad = c;
  bad["resolve"]["beside"] = "slide";
  refused(bad, "/resolve/beside");
  // (a hybrid whose part settles for a set 0.05 s and is struck for 2 ms,
  // with resolve/KEY VALUE, into dir/NAME_VALUE: its folder and summary)
  const auto settledVariant = [&](nlohmann::json cs, const std::string& key, const std::string& value,
                                  const std::string& name) {
    cs["resolve"][key] = value;
    cs["resolve"]["settle"] = {{"duration_s", 0.05}, {"until_at_rest", false}};
    cs["resolve"]["run"] = {{"duration_s", 0.002}};
    writeFile(dir / (name + ".json"), cs.dump());
    const auto out = dir / (name + "_" + value);
    const auto run = runGabion("run -q " + (dir / (name + ".json")).string() + " -o " + out.string());
    EXPECT_EQ(run.exit_code, 0) << run.output;
    const nlohmann::json sm = summaryOf(out);
    EXPECT_EQ(sm["hybrid"][key], value);
    return std::make_pair(out, sm);
  };
  // Above: on a 1 x 1 x 2 column struck on its lower cell, the plate over
  // it stands for the macro cell above. With above "weight" it is a servo
  // pressing with that cell's weight W: its speed down is 0.5 m/s x (W -
  // F) / W, so over the settling's last 40 % (the cell still coming down
  // under it) its mean force F is W (1 - v / 0.5 m/s) for its mean speed v
  // (to 2 % of W: the speed is the last step's force's), and more than a
  // plate standing still, which carries less than half of W (the cell
  // comes down from it). How much of W it carries turns on how fast the
  // cell under it sinks, which is the draw's: 0.6 W in the portable
  // build, 0.18 W natively, where the cell's top sinks at 0.41 m/s.
  double weight = 0.0;  // (the cell's, netting included: the run's cell_mass_kg)
  // A plate's settling, from the series of a run in `out`: over the last
  // 40 % its mean force along z (N, as the bodies press it) and mean height
  // below the laid-out one (m), its speed down (m/s), and its descent at the end.
  struct Settling {
    double force = 0.0, descent = 0.0, speed = 0.0, end = 0.0;
  };
  const auto plateSettling = [&](const std::filesystem::path& out, const std::string& wall) {
    const gabion::bridge::H5Reader h5(out / "settle" / "result.h5");
    const std::vector<double> t = h5.read("/series/time_s"), f = h5.read("/series/walls/" + wall + "/force_N"),
                              z = h5.read("/series/walls/" + wall + "/position_m");
    const std::size_t n = t.size(), k = 6 * n / 10;
    Settling l;
    if (n < 10 || f.size() != 3 * n || z.size() != 3 * n) {
      ADD_FAILURE() << "no series of " << wall;
      return l;
    }
    for (std::size_t q = k; q < n; ++q) {
      l.force += f[3 * q + 2] / static_cast<double>(n - k);
      l.descent += (z[2] - z[3 * q + 2]) / static_cast<double>(n - k);
    }
    l.speed = (z[3 * k + 2] - z[3 * (n - 1) + 2]) / (t[n - 1] - t[k]);
    l.end = z[2] - z[3 * (n - 1) + 2];
    return l;
  };
  const auto upperPlate = [&](const std::string& above, double& speed) {
    nlohmann::json col = c;
    col["structure"]["cells"] = {1, 1, 2};
    col["boulder"]["aim_point_m"] = {0.15, 0.15};
    const auto [out, sc] = settledVariant(col, "above", above, "column");
    weight = sc["cell_mass_kg"].get<double>() * 9.81;
    const Settling l = plateSettling(out, "interface_0_z_plus");
    speed = l.speed;
    return l.force;
  };
  double speed = 0.0;
  const double pressed = upperPlate("weight", speed);
  EXPECT_GT(speed, 0.0) << "the plate came down";
  EXPECT_NEAR(pressed, weight * (1.0 - speed / 0.5), 0.02 * weight) << "speed " << speed;
  const double held = upperPlate("fixed", speed);
  EXPECT_LT(held, 0.5 * weight);
  EXPECT_EQ(speed, 0.0);
  EXPECT_GT(pressed, held + 0.1 * weight)
      << "pressing with the weight, " << pressed << " N against " << held << " N standing still";
  // Beside: the plate behind the struck cell (it stands for the macro cell
  // there) comes down with the cell's blocks while they settle, by what
  // they came down (settle/struck_cell_drop_m); standing still, it stays.
  const auto plateDescent = [&](const std::string& beside, double& drop) {
    const auto [out, ss] = settledVariant(c, "beside", beside, "side");
    drop = ss["settle"]["struck_cell_drop_m"].get<double>();
    const std::vector<double> p =
        gabion::bridge::H5Reader(out / "settle" / "result.h5").read("/series/walls/interface_0_x_plus/position_m");
    return p.size() >= 6 ? p[2] - p[p.size() - 1] : NAN;
  };
  double drop = 0.0;
  EXPECT_EQ(plateDescent("fixed", drop), 0.0);
  const double descent = plateDescent("follow", drop);
  EXPECT_GT(drop, 1e-4) << "the cell came down";
  EXPECT_NEAR(descent, drop, 1e-3 * drop);
  // In plane: with in_plane "follow" that plate moves along y and z as the
  // cell's blocks do (their mean, the settling's last snapshot against its
  // first: the blocks are its last bodies), and stands still along x, its
  // normal; standing still in its plane (above), it stays.
  {
    const auto [out, ss] = settledVariant(c, "in_plane", "follow", "plane");
    EXPECT_EQ(ss["hybrid"]["in_plane"], "follow");
    const gabion::bridge::H5Reader h5(out / "settle" / "result.h5");
    const std::vector<double> p = h5.read("/series/walls/interface_0_x_plus/position_m"),
                              x = h5.read("/bodies/position_m");
    const std::vector<std::size_t> shape = h5.dims("/bodies/position_m"), blocks = h5.dims("/blocks/orientation");
    ASSERT_EQ(shape.size(), 3u);
    ASSERT_EQ(blocks.size(), 3u);
    ASSERT_GE(p.size(), 6u);
    const std::size_t frames = shape[0], n = shape[1], nb = blocks[1];
    ASSERT_GE(frames, 2u);
    double moved[3] = {0.0, 0.0, 0.0};
    for (std::size_t b = n - nb; b < n; ++b)
      for (int a = 0; a < 3; ++a)
        moved[a] += (x[3 * ((frames - 1) * n + b) + a] - x[3 * b + a]) / static_cast<double>(nb);
    const std::size_t last = p.size() - 3;
    EXPECT_EQ(p[last], p[0]) << "along its normal it stands still";
    const double in_plane = std::hypot(moved[1], moved[2]);
    EXPECT_GT(in_plane, 1e-4) << "the cell moved in the plate's plane";
    for (int a = 1; a < 3; ++a) EXPECT_NEAR(p[last + a] - p[a], moved[a], 1e-3 * in_plane) << "axis " << a;
  }
  // Free: the plate behind slides along y (x is its normal, z it does not
  // take) with the bodies' push: 0.5 m/s per cell weight W of push, so its
  // move is the integral of 0.5 F_y / W over the settling (the series'
  // trapezoid: the push is sampled every 0.1 ms, the plate moved every step).
  {
    const auto [out, ss] = settledVariant(c, "in_plane", "free", "plane");
    EXPECT_EQ(ss["hybrid"]["in_plane"], "free");
    const double w = ss["cell_mass_kg"].get<double>() * 9.81;
    const gabion::bridge::H5Reader h5(out / "settle" / "result.h5");
    const std::vector<double> t = h5.read("/series/time_s"), p = h5.read("/series/walls/interface_0_x_plus/position_m"),
                              f = h5.read("/series/walls/interface_0_x_plus/force_N");
    ASSERT_EQ(p.size(), 3 * t.size());
    ASSERT_EQ(f.size(), 3 * t.size());
    const std::size_t last = t.size() - 1;
    double integral = 0.0;
    for (std::size_t q = 1; q <= last; ++q)
      integral += 0.5 * (t[q] - t[q - 1]) * 0.5 * (f[3 * q + 1] + f[3 * (q - 1) + 1]) / w;
    EXPECT_EQ(p[3 * last], p[0]) << "along its normal it stands still";
    EXPECT_EQ(p[3 * last + 2], p[2]) << "along z it stands still";
    EXPECT_GT(std::fabs(integral), 1e-7) << "it was pushed along y";
    EXPECT_NEAR(p[3 * last + 1] - p[1], integral, 0.1 * std::fabs(integral));
  }
  bad = c;
  bad["resolve"]["in_plane"] = "slide";
  refused(bad, "/resolve/in_plane");
  // Below: on a 1 x 1 x 2 column struck on its upper cell, the plate under
  // it stands for the macro cell below. With below "gives" (that cell's
  // axial law made linear and soft here, k = 1e5 N/m, so that the weight W
  // of a cell shortens it a few mm) the plate comes down at
  // 0.5 m/s x (F - k d) / W while the cell presses it with F above k times
  // its descent d: over the settling's last 40 % (the cell still coming
  // down on it) its mean force F is k d + W v / 0.5 for its mean descent d
  // and speed v (to 2 % of W: the speed is the last step's force's), and
  // it carries more than half of W. Standing still, it does not come down.
  {
    nlohmann::json soft = laws;
    soft["materials"]["front"]["axial"] = {{"model", "bilinear"},          {"stiffness_N_m", 1e5},
                                           {"yield_force_N", 1e6},         {"hardening_stiffness_N_m", 3e4},
                                           {"lockup_shortening_m", 0.125}, {"lockup_stiffness_N_m", 1e8}};
    writeFile(dir / "soft_laws.json", soft.dump());
    nlohmann::json col = c;
    col["law_file"] = "soft_laws.json";
    col["structure"]["cells"] = {1, 1, 2};
    col["boulder"]["aim_point_m"] = {0.15, 0.45};
    const auto lowerPlate = [&](const std::string& below) {
      const auto [out, sc] = settledVariant(col, "below", below, "stack");
      weight = sc["cell_mass_kg"].get<double>() * 9.81;
      Settling l = plateSettling(out, "interface_1_z_minus");
      l.force = -l.force;  // (the bodies press it down)
      return l;
    };
    const Settling gives = lowerPlate("gives");
    EXPECT_GT(gives.end, 1e-3) << "the plate came down";
    EXPECT_GT(gives.force, 0.5 * weight);
    EXPECT_NEAR(gives.force, 1e5 * gives.descent + weight * gives.speed / 0.5, 0.02 * weight)
        << "descent " << gives.descent << " speed " << gives.speed;
    EXPECT_EQ(lowerPlate("plates").end, 0.0);
    // With below "lid" the plate stands where the lid of the cell below
    // would, lidClearance under that cell's extent (settle/
    // plates_under_lowered_m), and stays there: the cell on it comes down
    // further than on a plate at the extent, towards the lid (in the
    // settling's 0.05 s, by at least half of what it can fall freely in
    // that time, or of the clearance where that is less).
    const auto plateHeight = [&](const std::filesystem::path& out) {
      const std::vector<double> z =
          gabion::bridge::H5Reader(out / "settle" / "result.h5").read("/series/walls/interface_1_z_minus/position_m");
      return std::make_pair(z.size() >= 6 ? z[2] : NAN, z.size() >= 6 ? z[z.size() - 1] : NAN);
    };
    const std::filesystem::path at_extent = dir / "stack_plates";  // (lowerPlate("plates")'s run)
    const nlohmann::json extent_summary = summaryOf(at_extent);
    const auto [at_lid, lid_summary] = settledVariant(col, "below", "lid", "stack");
    ASSERT_TRUE(lid_summary["settle"].contains("plates_under_lowered_m"));
    EXPECT_FALSE(extent_summary["settle"].contains("plates_under_lowered_m"));
    const double lowered = lid_summary["settle"]["plates_under_lowered_m"].get<double>();
    EXPECT_GT(lowered, 0.005) << "the small cell's lid is uneven too";
    EXPECT_LT(lowered, 0.5 * 0.3) << "less than half the cell";
    const auto [extent_start, extent_end] = plateHeight(at_extent);
    const auto [lid_start, lid_end] = plateHeight(at_lid);
    EXPECT_NEAR(extent_start - lid_start, lowered, 1e-12);
    EXPECT_EQ(lid_end, lid_start) << "the plate stands still";
    const double further = lid_summary["settle"]["struck_cell_drop_m"].get<double>() -
                           extent_summary["settle"]["struck_cell_drop_m"].get<double>();
    EXPECT_GT(further, 0.5 * std::min(lowered, 0.5 * 9.81 * 0.05 * 0.05)) << "the cell on it came down further";
    bad = col;
    bad["resolve"]["below"] = "soft";
    refused(bad, "/resolve/below");
  }
  bad = c;
  bad["run"] = {{"kinematics", "3d"}};
  refused(bad, "/run");
  bad = c;
  bad["boulder"]["velocity_m_s"] = {8, 1, 0};
  refused(bad, "/boulder");
  bad = c;
  bad["resolve"]["boulder"] = {{"velocity_m_s", 3}};
  refused(bad, "/resolve/boulder");
}

// A resolved cell laced to its plates (lacing.to_plates) drags the macro
// node beside it: on a 1 x 2 x 1 wall struck on one cell, resolved alone,
// the plate on its side face stands for the other cell's netting. Unlaced,
// only friction on that plate pulls the macro node back along x, and lets
// go once the struck cell slides past (93 N on average over the impact's
// last fifth, of a 1.5 kN peak); laced, the wires tied to points riding
// the plate keep pulling (0.79 kN), as the laced wall's neighbour is pulled
// (ResolvedStructure.LacedCellsDragTheirNeighbourAlong): the plate's
// impulse along x doubles (12.6 against 6.5 N s) and the node, held by its
// law against the fixed back, moves further (the friction's share turns on
// the draw: natively the impulses are 12.8 against 8.9 N s, and the test
// asks for a quarter more). The plate's force reaches
// the node a step late (the wires act after it moved), the interface's two
// sides still the same products, and the balance within its bound. Laced
// as to a neighbouring copy of the cell (plate_partners "neighbour_face"),
// the face gets fewer wires than one per edge node. A structure resolved
// whole has no plates: to_plates there is refused, and plate_partners
// without it, or of an unknown kind.
TEST(HybridStructure, ACellLacedToItsPlatesDragsTheMacroNodeBeside) {
  const auto dir = scratchDir("hybrid_laced_plates");
  nlohmann::json laws = smallCellAndLaws(dir);
  ASSERT_FALSE(laws.is_null());
  writeFile(dir / "laws.json", laws.dump());
  nlohmann::json c = struckCellResolved({1, 2, 1});
  c["run"] = {{"duration_s", 0.03}};  // (the macro run: the impact's length is resolve.run's)
  writeFile(dir / "plain.json", c.dump());
  c["resolve"]["lacing"] = {{"at_s", 0.0}, {"to_plates", true}};
  writeFile(dir / "laced.json", c.dump());
  c["resolve"]["lacing"]["plate_partners"] = "neighbour_face";
  writeFile(dir / "as_neighbour.json", c.dump());
  ASSERT_NO_FATAL_FAILURE(runEach(dir, {"plain", "laced", "as_neighbour"}));
  const nlohmann::json plain = summaryOf(dir / "plain"), laced = summaryOf(dir / "laced");
  const nlohmann::json& l = laced["lacing"];
  EXPECT_EQ(l["faces_laced"], 0) << "one resolved cell: no two to lace";
  EXPECT_EQ(l["to_plates"], true);
  EXPECT_EQ(l["plate_partners"], "edge_nodes");
  EXPECT_EQ(l["plates_laced"], 1);
  EXPECT_GE(l["links_to_plates"].get<int>(), 5) << l.dump();
  // Laced as to a neighbouring copy of the cell (its stand-in the cell's
  // own opposite face, one pitch over): laced as laid out, every edge node
  // of this small cell's face finds its partner on the copy within reach,
  // one wire each, as with one per edge node (which partners, and where,
  // Lacing.AFaceLacedToAPlateAsToItsNeighbourGetsTheNeighboursWires).
  const nlohmann::json as_neighbour = summaryOf(dir / "as_neighbour");
  const nlohmann::json& n = as_neighbour["lacing"];
  EXPECT_EQ(n["plate_partners"], "neighbour_face");
  EXPECT_EQ(n["links_to_plates"], l["links_to_plates"]) << n.dump() << l.dump();
  EXPECT_EQ(n["edge_nodes_unlaced_at_plates"], 0);
  ASSERT_EQ(laced["hybrid"]["interfaces"].size(), 1u);
  EXPECT_EQ(laced["hybrid"]["interfaces"][0]["axis"], "y");
  // The macro node beside (front and back layer at once) moves back along x.
  const auto macroMove = [](const nlohmann::json& s) {
    return s["max_face_displacement_by_part_m"]["front"]["macro"].get<double>();
  };
  EXPECT_GT(macroMove(laced), macroMove(plain))
      << "laced " << macroMove(laced) << " m against " << macroMove(plain) << " m unlaced";
  EXPECT_GT(macroMove(plain), 0.0);
  EXPECT_GT(macroMove(as_neighbour), macroMove(plain))
      << "laced as to a neighbour " << macroMove(as_neighbour) << " m against " << macroMove(plain) << " m unlaced";
  const auto impulse = [&](const char* name) {  // (the plate's, along x, over the impact: N s)
    const gabion::bridge::H5Reader h5(dir / name / "result.h5");
    const std::vector<double> t = h5.read("/series/time_s"), f = h5.read("/series/walls/interface_1_y_minus/force_N");
    double sum = 0.0;
    for (std::size_t k = 1; k < t.size() && 3 * k < f.size(); ++k)
      sum += 0.5 * (f[3 * k] + f[3 * k - 3]) * (t[k] - t[k - 1]);
    return sum;
  };
  EXPECT_GT(impulse("laced"), 1.25 * impulse("plain"))
      << "laced " << impulse("laced") << " N s against " << impulse("plain") << " N s unlaced";
  EXPECT_GT(impulse("plain"), 0.0);
  const nlohmann::json& h = laced["hybrid"];
  const double to_macro = std::fabs(h["work_on_macro_part_J"].get<double>());
  EXPECT_NEAR(h["work_on_fine_part_J"].get<double>(), -h["work_on_macro_part_J"].get<double>(), 1e-9 * to_macro);
  EXPECT_LT(std::fabs(h["balance_rel_error"].get<double>()), 0.02);
  // Whole: no plates.
  nlohmann::json whole = {{"format", "gabion.case/1"},
                          {"kind", "micro.structure"},
                          {"cell", "cell/cell.h5"},
                          {"structure", {{"cells", {1, 2, 1}}}},
                          {"boulder", {{"diameter_m", 0.25}, {"velocity_m_s", 8}}},
                          {"settle", {{"duration_s", 0.01}, {"until_at_rest", false}}},
                          {"lacing", {{"at_s", 0.0}, {"to_plates", true}}},
                          {"run", {{"duration_s", 0.01}}}};
  expectRefused(dir, whole, "/lacing/to_plates");
  whole["lacing"] = {{"at_s", 0.0}, {"plate_partners", "neighbour_face"}};
  expectRefused(dir, whole, "/lacing/plate_partners");
  whole["lacing"] = {{"at_s", 0.0}, {"to_plates", true}, {"plate_partners", "nearest"}};
  expectRefused(dir, whole, "/lacing/plate_partners");
  // In macro.resolved the lacing to the plates goes to the hybrids alone.
  writeFile(dir / "both.json", R"({"format": "gabion.case/1", "kind": "macro.resolved", "law_file": "laws.json",
 "cell": "cell/cell.h5", "structure": {"cells": [1, 2, 1], "material": {"front": "front", "core": "front"}},
 "boulder": {"diameter_m": 0.25, "velocity_m_s": 8},
 "resolved": {"settle": {"duration_s": 0.01, "until_at_rest": false}, "run": {"duration_s": 0.03},
              "lacing": {"at_s": 0, "to_plates": true, "plate_partners": "neighbour_face"}},
 "hybrid": {"within_m": [0]}})");
  const auto both = runGabion("check " + (dir / "both.json").string());
  EXPECT_EQ(both.exit_code, 0) << both.output;
}

// Across: a wall one cell deep and three wide, struck on its middle cell,
// resolved alone; its side faces meet the macro cells beside it. With
// across "gives" (their axial law made linear, k), the plates on those
// faces move out, away from the struck cell, as its fill bulges sideways:
// never back, by what the summary says, and farther for a softer law; the
// work the bodies do on them is the macro cells' (dissipated), so the
// interface still balances. Fixed, they do not move across x.
TEST(HybridStructure, PlatesAcrossXGiveAsTheMacroCellsLaw) {
  const auto dir = scratchDir("hybrid_across");
  nlohmann::json laws = smallCellAndLaws(dir);
  ASSERT_FALSE(laws.is_null());
  nlohmann::json c = struckCellResolved({1, 3, 1});
  // (a run with the beside cells' axial law linear at k and the plates
  // across x as `across`: its summary, and the side plates' largest y
  // moves out of the series, checked never to come back)
  struct Run {
    nlohmann::json s;
    double out_minus = 0.0, out_plus = 0.0;
  };
  const auto run = [&](double k, const std::string& across) {
    const std::string name = across + "_" + std::to_string(static_cast<long>(k));
    laws["materials"]["front"]["axial"] = {{"model", "bilinear"},          {"stiffness_N_m", k},
                                           {"yield_force_N", 1e6},         {"hardening_stiffness_N_m", 0.3 * k},
                                           {"lockup_shortening_m", 0.125}, {"lockup_stiffness_N_m", 1e8}};
    writeFile(dir / (name + "_laws.json"), laws.dump());
    nlohmann::json cs = c;
    cs["law_file"] = name + "_laws.json";
    cs["resolve"]["across"] = across;
    writeFile(dir / (name + ".json"), cs.dump());
    const auto out = runGabion("run -q " + (dir / (name + ".json")).string() + " -o " + (dir / name).string());
    EXPECT_EQ(out.exit_code, 0) << out.output;
    Run r;
    if (out.exit_code != 0) return r;
    r.s = summaryOf(dir / name);
    const gabion::bridge::H5Reader h5(dir / name / "result.h5");
    for (const auto& [wall, sign, moved] : {std::make_tuple("interface_1_y_minus", -1.0, &r.out_minus),
                                            std::make_tuple("interface_1_y_plus", 1.0, &r.out_plus)}) {
      const std::vector<double> p = h5.read(std::string("/series/walls/") + wall + "/position_m");
      EXPECT_GT(p.size(), 30u) << wall;
      for (std::size_t q = 3; q < p.size(); q += 3) {
        EXPECT_GE(sign * (p[q + 1] - p[q - 2]), 0.0) << wall << " came back at sample " << q / 3;
        *moved = std::max(*moved, sign * (p[q + 1] - p[1]));
      }
    }
    return r;
  };
  const Run soft = run(2e4, "gives");
  ASSERT_TRUE(soft.s.is_object());
  const nlohmann::json& h = soft.s["hybrid"];
  EXPECT_EQ(h["across"], "gives");
  EXPECT_GT(soft.out_minus, 1e-4) << "the fill pushed the plate out";
  EXPECT_GT(soft.out_plus, 1e-4);
  // (the two y plates' moves, as the summary has them at the run's end: the
  // series' last sample may come up to 0.1 ms before it, during which each
  // plate moves 0.05 mm at most, at the servo's 0.5 m/s)
  double reported = 0.0;
  for (const auto& f : h["interfaces"])
    if (f["axis"] == "y") reported += f["moved_across_m"].get<double>();
  EXPECT_LE(soft.out_minus + soft.out_plus, reported + 1e-12);
  EXPECT_NEAR(reported, soft.out_minus + soft.out_plus, 2 * 0.5 * 1e-4);
  const double into = h["work_into_cells_across_J"].get<double>();
  EXPECT_GT(into, 0.0);
  EXPECT_LT(std::fabs(h["interface_mismatch_J"].get<double>()), 1e-9 * into);
  EXPECT_LT(std::fabs(h["balance_rel_error"].get<double>()), 0.02);
  // A cell a hundred times stiffer gives a fraction of that (the soft
  // one's plates move at the servo's top speed for much of the impact).
  const Run stiff = run(2e6, "gives");
  ASSERT_TRUE(stiff.s.is_object());
  EXPECT_LT(stiff.out_minus + stiff.out_plus, 0.5 * (soft.out_minus + soft.out_plus)) << "a stiffer cell gives less";
  EXPECT_GT(stiff.out_minus + stiff.out_plus, 0.0);
  const Run fixed = run(2e4, "fixed");
  ASSERT_TRUE(fixed.s.is_object());
  EXPECT_EQ(fixed.out_minus + fixed.out_plus, 0.0);
  EXPECT_EQ(fixed.s["hybrid"]["work_into_cells_across_J"].get<double>(), 0.0);
  for (const auto& f : fixed.s["hybrid"]["interfaces"]) EXPECT_FALSE(f.contains("moved_across_m"));
  nlohmann::json bad = c;
  bad["law_file"] = "fixed_20000_laws.json";
  bad["resolve"]["across"] = "slide";
  expectRefused(dir, bad, "/resolve/across");
}

// The wall one cell deep and three wide again, its middle cell resolved:
// with macro_motion "xy" the macro nodes beside it move along y as well as
// x (3-D kinematics held in z), so the plates on its side faces follow them
// out as its fill bulges sideways: each plate's y move is its node's (the
// summary's largest macro y move). The nodes take the change of the
// plates' forces since the impact's start (the settled forces are the
// macro part's pre-stress), and the pre-stress's work on their moves
// closes the interface's balance. "xyz" frees z too. With "x" (the
// default) the plates do not move across x and the nodes take the whole
// forces; a value other than the three is refused, naming the field.
TEST(HybridStructure, MacroNodesAlongXAndYCarryThePlatesBeside) {
  const auto dir = scratchDir("hybrid_xy");
  nlohmann::json laws = smallCellAndLaws(dir);
  ASSERT_FALSE(laws.is_null());
  writeFile(dir / "laws.json", laws.dump());
  nlohmann::json c = struckCellResolved({1, 3, 1});
  const auto run = [&](const std::string& motion) {
    nlohmann::json cs = c;
    cs["resolve"]["macro_motion"] = motion;
    writeFile(dir / (motion + ".json"), cs.dump());
    const auto out = runGabion("run -q " + (dir / (motion + ".json")).string() + " -o " + (dir / motion).string());
    EXPECT_EQ(out.exit_code, 0) << out.output;
    return out.exit_code == 0 ? summaryOf(dir / motion) : nlohmann::json();
  };
  // The side plates' largest y move out of the series (m; + away from the struck cell).
  const auto movedOut = [&](const std::string& motion, const char* wall, double sign) {
    const gabion::bridge::H5Reader h5(dir / motion / "result.h5");
    const std::vector<double> p = h5.read(std::string("/series/walls/") + wall + "/position_m");
    EXPECT_GT(p.size(), 30u) << wall;
    double moved = 0.0;
    for (std::size_t q = 3; q < p.size(); q += 3) moved = std::max(moved, sign * (p[q + 1] - p[1]));
    return moved;
  };
  const auto balanced = [](const nlohmann::json& h) {
    const double to_macro = std::fabs(h["work_on_macro_part_J"].get<double>());
    EXPECT_GT(to_macro, 0.0);
    const double pre = std::fabs(h["prestress_work_J"].get<double>());
    EXPECT_LT(std::fabs(h["interface_mismatch_J"].get<double>()), 1e-9 * (to_macro + pre));
    EXPECT_LT(std::fabs(h["balance_rel_error"].get<double>()), 0.02);
  };
  for (const std::string motion : {"xy", "xyz"}) {
    SCOPED_TRACE(motion);
    const nlohmann::json s = run(motion);
    ASSERT_TRUE(s.is_object());
    const nlohmann::json& h = s["hybrid"];
    EXPECT_EQ(h["macro_motion"], motion);
    const double minus = movedOut(motion, "interface_1_y_minus", -1.0);
    const double plus = movedOut(motion, "interface_1_y_plus", 1.0);
    EXPECT_GT(minus, 1e-5) << "the fill pushed the macro node beside it out";
    EXPECT_GT(plus, 1e-5);
    // (the series samples every 0.1 ms: the node's largest move may fall
    // between two, and the plate moves by the node's velocity times each
    // step, a little off its integrated displacement)
    const double largest = h["macro_max_y_move_m"].get<double>();
    EXPECT_LE(std::max(minus, plus), largest * (1.0 + 1e-3));
    EXPECT_GT(std::max(minus, plus), 0.9 * largest);
    if (motion == "xy")
      EXPECT_EQ(h["macro_max_z_move_m"].get<double>(), 0.0);
    else
      EXPECT_GT(h["macro_max_z_move_m"].get<double>(), 0.0);
    balanced(h);
  }
  const nlohmann::json x = run("x");
  ASSERT_TRUE(x.is_object());
  const nlohmann::json& h = x["hybrid"];
  EXPECT_EQ(h["macro_motion"], "x");
  EXPECT_EQ(h["macro_max_y_move_m"].get<double>(), 0.0);
  EXPECT_EQ(h["prestress_work_J"].get<double>(), 0.0);
  EXPECT_EQ(movedOut("x", "interface_1_y_minus", -1.0) + movedOut("x", "interface_1_y_plus", 1.0), 0.0);
  balanced(h);
  // Two cells stacked, the upper one struck and resolved: the plate under
  // it carries its weight from the settling on, which the macro cell below
  // holds as pre-stress; the weight's work on that cell's moves closes the
  // interface's balance.
  nlohmann::json stacked = struckCellResolved({1, 1, 2});
  stacked["boulder"]["aim_point_m"] = {0.15, 0.45};
  stacked["resolve"]["macro_motion"] = "xyz";
  writeFile(dir / "stacked.json", stacked.dump());
  const auto out = runGabion("run -q " + (dir / "stacked.json").string() + " -o " + (dir / "stacked").string());
  ASSERT_EQ(out.exit_code, 0) << out.output;
  const nlohmann::json st = summaryOf(dir / "stacked");
  ASSERT_EQ(st["hybrid"]["interfaces"].size(), 1u);
  EXPECT_EQ(st["hybrid"]["interfaces"][0]["axis"], "z");
  const double weight = -st["hybrid"]["interfaces"][0]["force_settled_N"][2].get<double>();
  EXPECT_GT(weight, 0.0) << "the resolved cell stands on the plate";
  EXPECT_NE(st["hybrid"]["prestress_work_J"].get<double>(), 0.0) << "the settled weight is pre-stress";
  EXPECT_GT(st["hybrid"]["macro_max_z_move_m"].get<double>(), 0.0);
  balanced(st["hybrid"]);
  nlohmann::json bad = c;
  bad["resolve"]["macro_motion"] = "yz";
  expectRefused(dir, bad, "/resolve/macro_motion");
}

// A 2 x 1 x 1 wall, its struck cell resolved, the macro cell behind it: with
// joint "law" the plate between them gives, towards the macro cell, as the
// joint law closes (closure c1 (F / 1 kN)^b): by what the summary says, more
// for a softer joint, the work into the joint dissipated so that the
// interface still balances. With joint "none" nothing closes; "law" without
// a joint in the law file is refused, naming the field.
TEST(HybridStructure, PlatesOnXFacesGiveAsTheJointCloses) {
  const auto dir = scratchDir("hybrid_joint");
  nlohmann::json laws = smallCellAndLaws(dir);
  ASSERT_FALSE(laws.is_null());
  nlohmann::json c = struckCellResolved({2, 1, 1});
  const auto run = [&](double c1_m, const std::string& joint) {
    const std::string name = joint + "_" + std::to_string(static_cast<long>(1e6 * c1_m));
    nlohmann::json l = laws;
    if (c1_m > 0.0)
      l["materials"]["front"]["joint"] = {{"model", "power"}, {"closure_at_1kN_m", c1_m}, {"exponent", 0.6}};
    writeFile(dir / (name + "_laws.json"), l.dump());
    nlohmann::json cs = c;
    cs["law_file"] = name + "_laws.json";
    cs["resolve"]["joint"] = joint;
    writeFile(dir / (name + ".json"), cs.dump());
    const auto out = runGabion("run -q " + (dir / (name + ".json")).string() + " -o " + (dir / name).string());
    EXPECT_EQ(out.exit_code, 0) << out.output;
    return out.exit_code == 0 ? summaryOf(dir / name) : nlohmann::json();
  };
  const auto closed = [](const nlohmann::json& s) {
    double sum = 0.0;
    for (const auto& f : s["hybrid"]["interfaces"])
      if (f.contains("joint_closed_m")) sum += f["joint_closed_m"].get<double>();
    return sum;
  };
  const nlohmann::json soft = run(5e-3, "law");
  ASSERT_TRUE(soft.is_object());
  const nlohmann::json& h = soft["hybrid"];
  EXPECT_EQ(h["joint"], "law");
  EXPECT_GT(closed(soft), 1e-4) << "the struck cell pushed the joint closed";
  const double into = h["work_into_joints_J"].get<double>();
  EXPECT_GT(into, 0.0);
  EXPECT_LT(std::fabs(h["interface_mismatch_J"].get<double>()), 1e-9 * into);
  EXPECT_LT(std::fabs(h["balance_rel_error"].get<double>()), 0.02);
  const nlohmann::json stiff = run(5e-5, "law");
  ASSERT_TRUE(stiff.is_object());
  EXPECT_LT(closed(stiff), 0.5 * closed(soft)) << "a stiffer joint closes less";
  EXPECT_GT(closed(stiff), 0.0);
  const nlohmann::json none = run(5e-3, "none");
  ASSERT_TRUE(none.is_object());
  EXPECT_EQ(none["hybrid"]["work_into_joints_J"].get<double>(), 0.0);
  for (const auto& f : none["hybrid"]["interfaces"]) EXPECT_FALSE(f.contains("joint_closed_m"));
  nlohmann::json bad = c;
  bad["law_file"] = "laws_without_joint.json";
  writeFile(dir / "laws_without_joint.json", laws.dump());
  bad["resolve"]["joint"] = "law";
  expectRefused(dir, bad, "/resolve/joint");
}

// The same wall with the plate behind the struck cell cut into 3 x 3 tiles
// (joint_tiles 3), each giving by its share of the joint law: a tile
// carrying F closes as the whole face would under 9 F. Each tile is its own
// plate (named, in the series) and its own interface in the summary. The
// tiles give apart (the fill's force chains load them unevenly) and each
// moves with the macro node plus its own closure; no tile closes past what
// the law gives at 9 times the largest force it carried (the servo follows
// the law from below), and the one carrying most at the end closes past
// what the whole face's law gives at twice its largest force (the share);
// the interface still balances.
TEST(HybridStructure, JointTilesEachGiveByTheirShareOfTheLaw) {
  const auto dir = scratchDir("hybrid_joint_tiles");
  nlohmann::json laws = smallCellAndLaws(dir);
  ASSERT_FALSE(laws.is_null());
  const double c1 = 5e-3, b = 0.6;
  laws["materials"]["front"]["joint"] = {{"model", "power"}, {"closure_at_1kN_m", c1}, {"exponent", b}};
  writeFile(dir / "laws.json", laws.dump());
  nlohmann::json c = struckCellResolved({2, 1, 1});
  c["resolve"]["joint"] = "law";
  c["resolve"]["joint_tiles"] = 3;
  writeFile(dir / "tiles.json", c.dump());
  const auto out = runGabion("run -q " + (dir / "tiles.json").string() + " -o " + (dir / "tiles").string());
  ASSERT_EQ(out.exit_code, 0) << out.output;
  const nlohmann::json s = summaryOf(dir / "tiles");
  const nlohmann::json& h = s["hybrid"];
  EXPECT_EQ(h["joint_tiles"], 3);
  const gabion::bridge::H5Reader h5(dir / "tiles" / "result.h5");
  // Each tile: its closure (summary), the largest and the last push on it,
  // and its x move less its closure at the end (series).
  struct Tile {
    double closed = 0.0, largest = 0.0, last = 0.0, node = 0.0;
  };
  std::map<std::pair<int, int>, Tile> tile;  // by (u, v)
  for (const auto& f : h["interfaces"]) {
    if (f["axis"] != "x") continue;
    ASSERT_TRUE(f.contains("tile")) << f.dump();
    const int u = f["tile"][0], v = f["tile"][1];
    const std::string wall = "/series/walls/interface_0_x_plus_tile_" + std::to_string(u) + "_" + std::to_string(v);
    const std::vector<double> force = h5.read(wall + "/force_N"), moved = h5.read(wall + "/displacement_m");
    ASSERT_GT(force.size(), 30u) << wall;
    Tile t;
    t.closed = f["joint_closed_m"].get<double>();
    for (std::size_t q = 0; q < force.size(); q += 3) t.largest = std::max(t.largest, force[q]);  // (+x: the push)
    t.last = force[force.size() - 3];
    t.node = moved[moved.size() - 3] - t.closed;
    tile[{u, v}] = t;
  }
  ASSERT_EQ(tile.size(), 9u);
  // The law at a force (N) on the whole face: closure c1 (F / 1 kN)^b.
  const auto law = [&](double force) { return force > 0.0 ? c1 * std::pow(force / 1e3, b) : 0.0; };
  double least = 1.0, most = 0.0;
  const Tile* loaded = nullptr;
  const double centre = tile[{1, 1}].node;
  for (const auto& [uv, t] : tile) {
    EXPECT_GE(t.closed, 0.0);
    // (the series' samples every 0.1 ms may miss the largest push by a
    // little: 2 % of it)
    EXPECT_LE(t.closed, law(9.0 * 1.02 * t.largest) + 1e-6) << uv.first << " " << uv.second;
    // (all with the node: the series' last sample is up to 0.1 ms before
    // the run's end, when the summary's closures are taken, in which a
    // tile closes 0.2 mm at most at its servo's 2 m/s and the node moves
    // less)
    EXPECT_NEAR(t.node, centre, 3e-4) << uv.first << " " << uv.second;
    least = std::min(least, t.closed), most = std::max(most, t.closed);
    if (!loaded || t.last > loaded->last) loaded = &t;
  }
  EXPECT_GT(most, 2.0 * least) << "the tiles give apart";
  ASSERT_NE(loaded, nullptr);
  // (the whole face's law would hold it below law(1.02 x its largest push))
  EXPECT_GT(loaded->closed, law(2.0 * loaded->largest))
      << "a tile closes by its share of the law, not the whole face's";
  const double into = h["work_into_joints_J"].get<double>();
  EXPECT_GT(into, 0.0);
  EXPECT_LT(std::fabs(h["interface_mismatch_J"].get<double>()), 1e-9 * into);
  EXPECT_LT(std::fabs(h["balance_rel_error"].get<double>()), 0.02);
  nlohmann::json bad = c;
  bad["resolve"]["joint_tiles"] = 6;
  expectRefused(dir, bad, "/resolve/joint_tiles");
  bad["resolve"]["joint_tiles"] = 0;
  expectRefused(dir, bad, "/resolve/joint_tiles");
  bad["resolve"]["joint_tiles"] = 2;
  bad["resolve"]["joint"] = "none";
  expectRefused(dir, bad, "/resolve/joint_tiles");
}

}  // namespace
