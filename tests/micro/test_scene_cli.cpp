// The micro.scene case through the `gabion` binary: input errors (exit 2
// naming the field), refused and forced time steps, numerical failure
// (exit 3), determinism and the result files.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../support/run_gabion.hpp"
#include "bridge/output.hpp"

namespace {

using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::writeFile;

// A small valid scene: a column of spheres on a floor inside a box, one
// block, one moving wall (the lid coming down).
std::string scene(const std::string& spheres_extra = "", const std::string& run_extra = "",
                  const std::string& material_extra = "") {
  std::string s = R"({"format": "gabion.case/1", "kind": "micro.scene", "gravity_m_s2": [0, 0, -9.81],
 "materials": {"rock": {"density_kg_m3": 2500, "normal_stiffness_N_m": 1e5, "shear_stiffness_N_m": 2.5e4,
                        "friction": 0.5, "viscous_damping_ratio": 0.1)" +
                  material_extra + R"(}},
 "spheres": [)";
  for (int k = 0; k < 27; ++k) {
    const double x = 0.03 + 0.025 * (k % 3), y = 0.03 + 0.025 * ((k / 3) % 3), z = 0.02 + 0.025 * (k / 9);
    s += (k ? ", " : "") + std::string("{\"center_m\": [") + std::to_string(x) + ", " + std::to_string(y) + ", " +
         std::to_string(z) + "], \"radius_m\": 0.01, \"material\": \"rock\"" + (k == 0 ? spheres_extra : "") + "}";
  }
  s += R"(],
 "blocks": [{"material": "rock", "position_m": [0.055, 0.055, 0.12], "orientation": [1, 0, 0, 0],
             "spheres": [{"center_m": [0, 0, 0], "radius_m": 0.01}, {"center_m": [0.012, 0, 0], "radius_m": 0.008}]}],
 "walls": [{"point_m": [0, 0, 0], "normal": [0, 0, 1], "material": "rock"},
           {"point_m": [0, 0, 0], "normal": [1, 0, 0], "material": "rock"},
           {"point_m": [0.11, 0, 0], "normal": [-1, 0, 0], "material": "rock"},
           {"point_m": [0, 0, 0], "normal": [0, 1, 0], "material": "rock"},
           {"point_m": [0, 0.11, 0], "normal": [0, -1, 0], "material": "rock"},
           {"name": "lid", "point_m": [0, 0, 0.16], "normal": [0, 0, -1], "material": "rock", "velocity_m_s": [0, 0, -0.2]}],
 "run": {"duration_s": 0.1, "output_interval_s": 0.01)" +
       run_extra + R"(}})";
  return s;
}

struct BadCase {
  std::string name, text, pointer;
};

TEST(MicroSceneCli, ValidSceneRunsAndWritesResults) {
  const auto dir = scratchDir("micro_scene_ok");
  writeFile(dir / "case.json", scene());
  const auto r = runGabion("run " + (dir / "case.json").string() + " -q -o " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  gabion::bridge::H5Reader h5(dir / "out" / "result.h5");
  const auto dims = h5.dims("/bodies/position_m");  // t = 0, every 0.01 s, and the end
  ASSERT_EQ(dims.size(), 3u);
  EXPECT_GE(dims[0], 11u);
  EXPECT_LE(dims[0], 12u);
  EXPECT_EQ(dims[1], 28u);
  EXPECT_EQ(h5.dims("/bodies/radius_m"), (std::vector<std::size_t>{28}));
  const auto n = h5.dims("/series/time_s")[0];
  // walls' series go under their names (unnamed ones: wall_<index>)
  EXPECT_EQ(h5.dims("/series/walls/lid/force_N"), (std::vector<std::size_t>{n, 3}));
  EXPECT_EQ(h5.dims("/series/walls/wall_0/force_N"), (std::vector<std::size_t>{n, 3}));
  const auto lid = h5.read("/series/walls/lid/position_m");
  EXPECT_NEAR(h5.read("/series/walls/lid/displacement_m")[3 * (n - 1) + 2], -0.2 * h5.read("/series/time_s")[n - 1],
              1e-12);
  EXPECT_NEAR(lid[3 * (n - 1) + 2], 0.16 - 0.2 * h5.read("/series/time_s")[n - 1], 1e-12);
  EXPECT_TRUE(h5.has("/series/balance_rel_error"));
  EXPECT_TRUE(h5.has("/blocks/orientation"));
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "result.xdmf"));
}

// Without --quiet a run ends with the timing table (every stage, with two
// threads the partitions' balance); --quiet leaves it out. The same numbers
// are in summary.json's profile.
TEST(MicroSceneCli, RunReportsWhereTheTimeWentUnlessQuiet) {
  const auto dir = scratchDir("micro_scene_report");
  writeFile(dir / "case.json", scene());
  const auto r = runGabion("run " + (dir / "case.json").string() + " --threads 2 -o " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("step loop: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("threads busy"), std::string::npos) << r.output;
  for (const char* stage : {"neighbours", "contacts", "walls", "integrate", "energy", "other"})
    EXPECT_NE(r.output.find(std::string("  ") + stage + " "), std::string::npos) << stage << "\n" << r.output;
  std::ifstream in(dir / "out" / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  ASSERT_TRUE(summary.contains("profile"));
  EXPECT_EQ(summary["profile"]["thread_busy_time_s"]["contacts"].size(), 2u);
  EXPECT_GT(summary["profile"]["stage_wall_time_s"]["contacts"].get<double>(), 0.0);
  const auto q = runGabion("run " + (dir / "case.json").string() + " -q -o " + (dir / "out2").string());
  ASSERT_EQ(q.exit_code, 0) << q.output;
  EXPECT_EQ(q.output.find("step loop: "), std::string::npos) << q.output;
}

TEST(MicroSceneCli, BadInputsExit2NamingTheField) {
  const auto dir = scratchDir("micro_scene_bad");
  std::string missing = scene();
  missing.replace(missing.find("\"friction\": 0.5,"), 16, "");
  std::string wrong_type = scene();
  wrong_type.replace(wrong_type.find("\"duration_s\": 0.1"), 17, "\"duration_s\": \"long\"");
  std::string zero_mass = scene();
  zero_mass.replace(zero_mass.find("\"density_kg_m3\": 2500"), 21, "\"density_kg_m3\": 0");
  std::string nan = scene();
  nan.replace(nan.find("\"gravity_m_s2\": [0, 0, -9.81]"), 29, "\"gravity_m_s2\": [0, 0, NaN]");
  std::string bad_material = scene(", \"material\": \"steel\"");
  const auto withPairs = [](const std::string& pairs) {
    std::string t = scene();
    t.insert(t.find("\"run\":"), "\"contact_pairs\": " + pairs + ",\n ");
    return t;
  };
  const std::vector<BadCase> cases = {
      {"missing", missing, "/materials/rock/friction"},
      {"unknown", scene(", \"colour\": \"red\""), "/spheres/0/colour"},
      {"wrong_type", wrong_type, "/run/duration_s"},
      {"negative_radius", scene(", \"radius_m\": -0.01"), "/spheres/0/radius_m"},
      {"zero_mass", zero_mass, "/materials/rock/density_kg_m3"},
      {"nan", nan, ""},  // not valid JSON: the parser names the line
      {"unknown_run_key", scene("", ", \"dt_safty\": 0.1"), "/run/dt_safty"},
      {"bad_overlap", scene("", ", \"max_overlap_ratio\": 2"), "/run/max_overlap_ratio"},
      {"bad_damping", scene("", "", ", \"local_damping\": 1.5"), "/materials/rock/local_damping"},
      {"pair_material", withPairs(R"([{"materials": ["rock", "steel"], "friction": 0.2}])"),
       "/contact_pairs/0/materials/1"},
      {"pair_cap", withPairs(R"([{"materials": ["rock", "rock"], "normal_force_limit_N": "never"}])"),
       "/contact_pairs/0/normal_force_limit_N"},
      {"pair_names", withPairs(R"([{"materials": ["rock"]}])"), "/contact_pairs/0/materials"},
  };
  for (const auto& c : cases) {
    std::string text = c.text;
    if (c.name == "negative_radius") {  // a duplicate key would hide the first: replace the value instead
      text = scene();
      text.replace(text.find("\"radius_m\": 0.01"), 16, "\"radius_m\": -0.01");
    }
    const auto file = dir / (c.name + ".json");
    writeFile(file, text);
    for (const std::string& cmd : std::vector<std::string>{"check ", "run -q -o " + (dir / "out").string() + " "}) {
      const auto r = runGabion(cmd + file.string());
      EXPECT_EQ(r.exit_code, 2) << c.name << ": " << r.output;
      EXPECT_NE(r.output.find(file.filename().string()), std::string::npos) << c.name << ": " << r.output;
      if (!c.pointer.empty()) {
        EXPECT_NE(r.output.find(c.pointer), std::string::npos) << c.name << ": " << r.output;
      }
    }
  }
  const auto r = runGabion("run " + (dir / "does_not_exist.json").string() + " -q");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("does_not_exist.json"), std::string::npos) << r.output;
}

TEST(MicroSceneCli, TimeStepAboveCriticalIsRefusedUnlessForced) {
  const auto dir = scratchDir("micro_scene_dt");
  writeFile(dir / "case.json", scene("", ", \"dt_s\": 0.01"));
  const auto r = runGabion("run " + (dir / "case.json").string() + " -q -o " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/run/dt_s"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("critical"), std::string::npos) << r.output;
  // Forced far above critical (30x), the pack blows up: exit 3 naming step,
  // time and bodies, and the files written so far stay.
  writeFile(dir / "forced.json", scene("", ", \"dt_s\": 0.01, \"allow_dt_above_critical\": true"));
  const auto f = runGabion("run " + (dir / "forced.json").string() + " -q -o " + (dir / "out2").string());
  EXPECT_EQ(f.exit_code, 3) << f.output;
  EXPECT_NE(f.output.find("step "), std::string::npos) << f.output;
  EXPECT_NE(f.output.find("t = "), std::string::npos) << f.output;
  EXPECT_TRUE(f.output.find("sphere ") != std::string::npos || f.output.find("block ") != std::string::npos)
      << f.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out2" / "result.h5"));
  EXPECT_TRUE(std::filesystem::exists(dir / "out2" / "summary.json"));
}

// Two spheres closing at 1,000 m/s would pass through each other between two
// steps (0.032 m a step each, radii 0.01 m) and the run would say ok with
// no contact: a body moving more than the smallest radius in one step is a
// numerical failure that names it. At 10 m/s they meet, touch and bounce
// back (the step then moves them 0.3 mm, well below their radius).
TEST(MicroSceneCli, BodiesTooFastForTheStepAreTunnellingNotOk) {
  const auto dir = scratchDir("micro_scene_tunnel");
  const auto pair = [](double v) {
    return R"({"format": "gabion.case/1", "kind": "micro.scene", "gravity_m_s2": [0, 0, 0],
 "materials": {"m": {"density_kg_m3": 2500, "normal_stiffness_N_m": 1e5, "shear_stiffness_N_m": 2.5e4, "friction": 0.5}},
 "spheres": [{"center_m": [0, 0, 0], "radius_m": 0.01, "material": "m", "velocity_m_s": [)" +
           std::to_string(v) + R"(, 0, 0]},
             {"center_m": [0.1, 0, 0], "radius_m": 0.01, "material": "m", "velocity_m_s": [)" +
           std::to_string(-v) + R"(, 0, 0]}],
 "run": {"duration_s": 0.01, "series_interval_s": 6.472086375185664e-05}})";
  };
  writeFile(dir / "fast.json", pair(500.0));
  auto r = runGabion("run " + (dir / "fast.json").string() + " -q -o " + (dir / "fast").string());
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("tunnelling: sphere"), std::string::npos) << r.output;
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(dir / "fast" / "summary.json"))["step_status"], "tunnelling");

  writeFile(dir / "slow.json", pair(5.0));
  r = runGabion("run " + (dir / "slow.json").string() + " -q -o " + (dir / "slow").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const gabion::bridge::H5Reader h5(dir / "slow" / "result.h5");
  const auto contacts = h5.read("/series/contacts");
  EXPECT_GT(*std::max_element(contacts.begin(), contacts.end()), 0.0) << "the spheres touched";
}

// A step that underflows (a radius of 1e-200 m) or a run of more than 1e10
// steps is refused before it starts, with the step and the step count; it
// does not run as "0 steps, ok" nor start on centuries.
TEST(MicroSceneCli, RunsOfZeroOrCountlessStepsAreRefused) {
  const auto dir = scratchDir("micro_scene_steps");
  writeFile(dir / "case.json", scene());
  auto r = runGabion("check " + (dir / "case.json").string() +
                     R"( --set 'spheres=[{"center_m": [0.05, 0.05, 0.05], "radius_m": 1e-200, "material": "rock"}]')");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/run/duration_s: the time step would be 0 s"), std::string::npos) << r.output;
  r = runGabion("run " + (dir / "case.json").string() + " -q -o " + (dir / "long").string() +
                " --set run.duration_s=3e8");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("steps for 3e+08 s: more than 1e+10"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "long"));
}

// A stiffness of 1e-300 N/m: the ball sinks into the floor and the run stops
// on the overlap, with every energy a number. Before, the mixing rule
// 2 k1 k2 / (k1 + k2) underflowed to 0 and the stored energy F^2 / 2k was
// written as null; a ledger that is not finite now stops the run (exit 3,
// non_finite, the term named: test EnergyLedger.NamesItsFirstNonFiniteTerm).
TEST(MicroSceneCli, AnUnderflowingStiffnessGivesNumbersNotNulls) {
  const auto dir = scratchDir("micro_scene_soft");
  writeFile(dir / "soft.json", R"({"format": "gabion.case/1", "kind": "micro.scene", "gravity_m_s2": [0, 0, -9.81],
 "materials": {"m": {"density_kg_m3": 2500, "normal_stiffness_N_m": 1e-300, "shear_stiffness_N_m": 2.5e4, "friction": 0.5}},
 "walls": [{"name": "floor", "point_m": [0, 0, 0], "normal": [0, 0, 1], "material": "m"}],
 "spheres": [{"center_m": [0, 0, 0.2], "radius_m": 0.01, "material": "m"}],
 "run": {"duration_s": 0.5}})");
  const auto r = runGabion("run " + (dir / "soft.json").string() + " -q -o " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 3) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "out" / "summary.json"));
  EXPECT_EQ(summary["step_status"], "overlap");
  for (const auto& [name, value] : summary["energy"].items()) EXPECT_TRUE(value.is_number()) << name << " " << value;
}

TEST(MicroSceneCli, SameCaseSameThreadsGivesIdenticalArrays) {
  const auto dir = scratchDir("micro_scene_det");
  writeFile(dir / "case.json", scene());
  for (const int threads : {1, 2}) {
    std::vector<std::vector<double>> runs;
    for (int k = 0; k < 2; ++k) {
      const auto out = dir / ("out" + std::to_string(threads) + std::to_string(k));
      const auto r = runGabion("run " + (dir / "case.json").string() + " -q --threads " + std::to_string(threads) +
                               " -o " + out.string());
      ASSERT_EQ(r.exit_code, 0) << r.output;
      gabion::bridge::H5Reader h5(out / "result.h5");
      std::vector<double> all;
      for (const char* d :
           {"/bodies/position_m", "/bodies/velocity_m_s", "/series/total_J", "/series/walls/wall_0/force_N"}) {
        const auto v = h5.read(d);
        all.insert(all.end(), v.begin(), v.end());
      }
      runs.push_back(all);
    }
    ASSERT_EQ(runs[0].size(), runs[1].size());
    EXPECT_TRUE(runs[0] == runs[1]) << "threads " << threads;
  }
}

}  // namespace
