// The macro case kinds through the library and the `gabion` binary: the
// default wall (convergence, the paper's Fig. 13 trend, repeated impacts),
// the energy balance of every macro case in cases/, sweeps, and bad input.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <tuple>

#include "bridge/json_reader.hpp"
#include "bridge/output.hpp"
#include "macro/case_reader.hpp"
#include "macro/impact.hpp"
#include "tests/support/run_gabion.hpp"

using namespace gabion::macro;
using gabion::bridge::JsonDocument;
using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::writeFile;
using nlohmann::json;

namespace {

const std::string kSource = GABION_SOURCE_DIR;
const std::string kWallCase = kSource + "/cases/wall_impact.json";

struct DefaultWall {
  ImpactCase c;
  Structure s;
  DefaultWall() {
    const JsonDocument doc = JsonDocument::load(kWallCase);
    c = readImpactCase(doc, false);
    s = buildCaseStructure(doc, c);
    resolveAims(doc, c, s);
    c.run.relax = false;
  }
  ImpactResult run(double speed, double fraction = 0.1, double duration = 0.05) const {
    Model model(s, c.run.kinematics);
    BoulderSpec b = c.impacts.front();
    b.velocity_m_s = b.velocity_m_s.normalized() * speed;
    RunSettings r = c.run;
    r.time_step_fraction = fraction;
    r.duration_s = duration;
    return runImpact(model, b, r, 0, nullptr);
  }
};

json readJson(const std::filesystem::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

}  // namespace

// Results converge as dt decreases: the change halves (or better) with each
// halving of dt, and the two finest agree within 0.5 %.
TEST(MacroDefaultWall, ConvergesAsTimeStepDecreases) {
  const DefaultWall wall;
  std::vector<ImpactResult> r;
  for (double f : {0.8, 0.4, 0.2, 0.1}) {
    r.push_back(wall.run(20.0, f));
    ASSERT_TRUE(r.back().ok) << r.back().message;
  }
  auto check = [&](const char* name, auto get) {
    const double d1 = std::abs(get(r[1]) - get(r[0])), d3 = std::abs(get(r[3]) - get(r[2]));
    EXPECT_LT(d3, 0.6 * d1 + 1e-12 * std::abs(get(r[3]))) << name;
    EXPECT_NEAR(get(r[2]), get(r[3]), 0.005 * std::abs(get(r[3]))) << name;
  };
  check("peak force", [](const ImpactResult& x) { return x.peak_force_N; });
  check("penetration", [](const ImpactResult& x) { return x.max_penetration_m; });
  check("duration", [](const ImpactResult& x) { return x.contact_duration_s; });
  check("plastic energy", [](const ImpactResult& x) { return x.plastic_J; });
  EXPECT_LT(r[3].balance_rel_error, r[0].balance_rel_error);
}

// The paper's Fig. 13: the same boulder at several energies; the peak force
// rises strongly with the velocity, the duration of the impact barely changes.
TEST(MacroDefaultWall, Fig13PeakForceRisesDurationStays) {
  const DefaultWall wall;
  std::vector<ImpactResult> r;
  for (double v : {8.0, 15.0, 20.0, 30.0}) {
    r.push_back(wall.run(v));
    ASSERT_TRUE(r.back().ok) << r.back().message;
  }
  for (std::size_t i = 1; i < r.size(); ++i) EXPECT_GT(r[i].peak_force_N, r[i - 1].peak_force_N);
  const double force_ratio = r.back().peak_force_N / r.front().peak_force_N;
  const double duration_ratio = r.back().contact_duration_s / r.front().contact_duration_s;
  EXPECT_GT(force_ratio, 2.0);                      // 8 -> 30 m/s: peak force more than doubles
  EXPECT_LT(std::abs(duration_ratio - 1.0), 0.35);  // duration within 35 %
  EXPECT_GT(force_ratio - 1.0, 3.0 * std::abs(duration_ratio - 1.0));
}

// The wave an impact sends through the wall reaches the back face after a
// slow boulder has left: the impact is not over before the back face has
// stopped moving further, so its largest displacement grows smoothly with
// the energy (ending the impact with the boulder's departure gave 0.25 mm
// at 8.5 m/s against 2.8 mm at 9 m/s).
TEST(MacroDefaultWall, BackFaceMaximumWaitsForTheWaveThroughTheWall) {
  const DefaultWall wall;
  std::vector<ImpactResult> r;
  for (double v : {7.0, 8.0, 8.5, 9.0, 10.0, 11.0}) {
    r.push_back(wall.run(v, 0.25));
    ASSERT_TRUE(r.back().ok) << r.back().message;
  }
  // (7 -> 11 m/s: the energy 2.5 times; the back face rises 20 %, a tenth per step at most)
  for (std::size_t i = 1; i < r.size(); ++i) {
    const double ratio = r[i].max_back_face_displacement_m / r[i - 1].max_back_face_displacement_m;
    EXPECT_GT(ratio, 1.0) << "impact " << i;
    EXPECT_LT(ratio, 1.1) << "impact " << i << ": " << r[i].max_back_face_displacement_m << " after "
                          << r[i - 1].max_back_face_displacement_m;
  }
}

// Repeated impacts on the damaged wall: the plastic state grows with every
// impact, and the hardened face answers the same boulder with a higher peak force.
TEST(MacroDefaultWall, RepeatedImpactsAccumulateDamage) {
  DefaultWall wall;
  Model model(wall.s, wall.c.run.kinematics);
  RunSettings run = wall.c.run;
  run.duration_s = 0.05;
  run.relax = true;
  auto plastic_state = [&] {
    double sum = 0.0;
    for (double u : model.axialPlastic()) sum += u;
    for (double u : model.frontPlastic()) sum += u;
    return sum;
  };
  std::vector<ImpactResult> r;
  std::vector<double> state{plastic_state()};
  for (int i = 0; i < 3; ++i) {
    r.push_back(runImpact(model, wall.c.impacts.front(), run, i, nullptr));
    ASSERT_TRUE(r.back().ok) << r.back().message;
    EXPECT_TRUE(r.back().relax_converged);
    state.push_back(plastic_state());
    EXPECT_GT(state[static_cast<std::size_t>(i) + 1], state[static_cast<std::size_t>(i)]);
    EXPECT_LT(r.back().balance_rel_error, 0.005);
  }
  EXPECT_GT(r[1].peak_force_N, r[0].peak_force_N);
  EXPECT_LT(r[1].plastic_J, r[0].plastic_J);  // less left to yield: more of the energy is given back
}

// Every macro case in cases/ runs and balances its energy within 0.5 %.
TEST(MacroCases, EveryCaseBalancesEnergy) {
  const auto dir = scratchDir("macro_cases");
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kSource + "/cases")) {
    if (entry.path().extension() != ".json") continue;
    const json c = readJson(entry.path());
    const std::string kind = c.value("kind", "");
    if (kind.rfind("macro.", 0) != 0) continue;
    // (a fine DEM wall beside its macro twin, from the pipeline's files: tests/app/test_resolved.cpp)
    // (and a hybrid of one: the same files and test)
    if (kind == "macro.resolved" || c.contains("resolve")) continue;
    const auto out = dir / entry.path().stem();
    const auto r = runGabion("run " + entry.path().string() + " -q --threads 2 -o " + out.string());
    ASSERT_EQ(r.exit_code, 0) << entry.path() << ": " << r.output;
    const json s = readJson(out / "summary.json");
    EXPECT_EQ(s.at("status"), "ok") << entry.path();
    EXPECT_LT(s.at("balance_rel_error").get<double>(), 0.005) << entry.path();
    ++n;
  }
  EXPECT_GE(n, 2);
}

// The summary and the result files of an impact; --set and --law.
TEST(MacroCli, ImpactOutputsSetAndLawOverride) {
  const auto dir = scratchDir("macro_cli");
  auto r = runGabion("run " + kWallCase + " -q -o " + (dir / "a").string() + " --set boulder.velocity_m_s=25");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(dir / "a" / "summary.json");
  const double mass = 2600.0 * 4.0 / 3.0 * M_PI * 0.25 * 0.25 * 0.25;
  EXPECT_NEAR(s.at("input_energy_J").get<double>(), 0.5 * mass * 25.0 * 25.0, 1e-6);
  for (const char* key : {"peak_force_N", "max_penetration_m", "contact_duration_s", "rebound_velocity_m_s",
                          "max_back_face_displacement_m", "kinetic_energy_J", "elastic_energy_J", "plastic_energy_J",
                          "friction_energy_J", "balance_rel_error"})
    EXPECT_TRUE(s.contains(key)) << key;
  gabion::bridge::H5Reader h5(dir / "a" / "result.h5");
  const auto t = h5.read("/series/time_s");
  EXPECT_EQ(h5.read("/series/boulder_force_N").size(), t.size());
  EXPECT_EQ(h5.dims("/snapshots/displacement_m").size(), 3u);
  EXPECT_TRUE(std::filesystem::exists(dir / "a" / "result.xdmf"));

  // A law file with twice the impact stiffness through --law: a different, stiffer answer.
  json law = readJson(kSource + "/cases/laws/illustrative.json");
  for (auto& [name, m] : law["materials"].items())
    m["impact"]["stiffness_N_m"] = 2 * m["impact"]["stiffness_N_m"].get<double>();
  writeFile(dir / "stiff.json", law.dump());
  r = runGabion("run " + kWallCase + " -q -o " + (dir / "b").string() + " --set boulder.velocity_m_s=25 --law " +
                (dir / "stiff.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s2 = readJson(dir / "b" / "summary.json");
  EXPECT_GT(s2.at("peak_force_N").get<double>(), s.at("peak_force_N").get<double>());
  // The verdict is printed, --quiet or not.
  EXPECT_NE(r.output.find("macro.impact: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(s2.at("outcome").get<std::string>()), std::string::npos) << r.output;

  // --law is the case's law file from the start: a law with other material
  // names passes check and runs once the structure names them ...
  json one = law;
  one["materials"] = {{"limestone_cell", law["materials"]["front"]}};
  writeFile(dir / "one.json", one.dump());
  const std::string names =
      " --set structure.material.front=limestone_cell --set structure.material.core=limestone_cell";
  r = runGabion("check " + kWallCase + " --law " + (dir / "one.json").string() + names);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = runGabion("run " + kWallCase + " -q -o " + (dir / "c").string() + " --law " + (dir / "one.json").string() +
                names);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // ... and a name it lacks is an input error naming the key and the law
  // file, before anything is written.
  r = runGabion("run " + kWallCase + " -q -o " + (dir / "d").string() + " --law " + (dir / "one.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/structure/material/front"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("one.json"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "d"));
  // A kind that reads no laws refuses --law.
  r = runGabion("check " + kSource + "/cases/micro_cc.json --law " + (dir / "one.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("reads no laws"), std::string::npos) << r.output;
  // A macro case that names no laws yet takes them from --law.
  nlohmann::json bare = nlohmann::json::parse(std::ifstream(kWallCase));
  bare.erase("law_file");
  std::ofstream(dir / "bare.json") << bare.dump(2);
  r = runGabion("check " + (dir / "bare.json").string() + " --law " + kSource + "/cases/laws/illustrative.json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// Repeated impacts through a case: per-impact results in the summary.
TEST(MacroCli, RepeatedImpactsInSummary) {
  const auto dir = scratchDir("macro_repeat");
  json c = readJson(kWallCase);
  c["law_file"] = kSource + "/cases/laws/illustrative.json";
  c["impacts"] = json::array({json::object(), {{"velocity_m_s", 25}}, {{"aim_point_m", {1.75, 1.75}}}});
  c["run"]["duration_s"] = 0.05;
  writeFile(dir / "repeat.json", c.dump());
  const auto r = runGabion("run " + (dir / "repeat.json").string() + " -q -o " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(dir / "out" / "summary.json");
  ASSERT_EQ(s.at("impacts").size(), 3u);
  ASSERT_EQ(s.at("per_impact_peak_force_N").size(), 3u);
  ASSERT_EQ(s.at("per_impact_max_penetration_m").size(), 3u);
  EXPECT_LT(s.at("balance_rel_error").get<double>(), 0.005);
  EXPECT_FALSE(s.contains("warnings")) << s.dump();

  // A relaxation cut short says so, in the answer and in the summary's
  // warnings, naming the impact.
  c["run"]["relax_max_steps"] = 10;
  writeFile(dir / "short.json", c.dump());
  const auto r2 = runGabion("run " + (dir / "short.json").string() + " -q -o " + (dir / "short").string());
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  EXPECT_NE(r2.output.find("warning: the structure was not at rest after 10 steps"), std::string::npos) << r2.output;
  const json w = readJson(dir / "short" / "summary.json").at("warnings");
  ASSERT_EQ(w.size(), 3u) << w.dump();
  EXPECT_EQ(w[0].get<std::string>().rfind("impact 0: the structure was not at rest", 0), 0u) << w.dump();
  // A perforated structure is not relaxed at all (its outcome says why): no warning.
  c["impacts"] = json::array({{{"velocity_m_s", 60}}});
  writeFile(dir / "through.json", c.dump());
  const auto r3 = runGabion("run " + (dir / "through.json").string() + " -q -o " + (dir / "through").string());
  ASSERT_EQ(r3.exit_code, 0) << r3.output;
  const json s3 = readJson(dir / "through" / "summary.json");
  EXPECT_EQ(s3.at("impacts").at(0).at("outcome"), "perforated") << s3.dump();
  EXPECT_FALSE(s3.contains("warnings")) << s3.dump();
  EXPECT_EQ(r3.output.find("warning:"), std::string::npos) << r3.output;
}

// A sweep: rows in grid order whatever the thread count; failed points are
// rows with a message, not a failed run.
TEST(MacroCli, SweepIsDeterministicAndRecordsFailures) {
  const auto dir = scratchDir("macro_sweep");
  json c = readJson(kSource + "/cases/macro_sweep.json");
  c["law_file"] = kSource + "/cases/laws/illustrative.json";
  c["sweep"] = {{"velocity_m_s", {8, 20}},
                {"mass_kg", {170, 400}},
                {"aim_point_m", {{2.75, 1.75}, {99.0, 1.0}}},
                {"cells", {{4, 11, 7}, {3, 7, 5}}},
                {"chart", false}};
  writeFile(dir / "sweep.json", c.dump());
  std::string csv[2];
  for (int t = 0; t < 2; ++t) {
    const auto out = dir / ("out" + std::to_string(t));
    const auto r = runGabion("run " + (dir / "sweep.json").string() + " -q --threads " + std::to_string(t + 1) +
                             " -o " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(out / "sweep.csv");
    csv[t].assign(std::istreambuf_iterator<char>(in), {});
    const json s = readJson(out / "summary.json");
    EXPECT_EQ(s.at("points"), 16);
    EXPECT_EQ(s.at("failed_points"), 8);  // the aim (99, 1) misses both walls
    gabion::bridge::H5Reader h5(out / "result.h5");
    EXPECT_EQ(h5.read("/table/peak_force_N").size(), 16u);
  }
  EXPECT_EQ(csv[0], csv[1]);
  EXPECT_NE(csv[0].find("aim point outside the front face"), std::string::npos);
}

// A boulder is a sphere of one density: any two of diameter, mass and
// density give the third, and a sweep over mass changes the diameter at the
// boulder's density (a 2,000 kg boulder of 0.5 m would be 30 t/m3), or with
// keep_diameter the density.
TEST(MacroCli, BoulderMassDiameterAndDensityAgree) {
  const auto dir = scratchDir("macro_boulder");
  json c = readJson(kSource + "/cases/macro_sweep.json");
  c["law_file"] = kSource + "/cases/laws/illustrative.json";
  c["boulder"] = {{"mass_kg", 1000.0 * M_PI / 6.0 * 2.6}, {"density_kg_m3", 2600}, {"velocity_m_s", 10}};  // 1 m
  c["sweep"] = {
      {"velocity_m_s", {10}}, {"mass_kg", {2600.0 * M_PI / 6.0 * 0.125, 2600.0 * M_PI / 6.0 * 8.0}}, {"chart", false}};
  writeFile(dir / "sweep.json", c.dump());
  auto r = runGabion("run " + (dir / "sweep.json").string() + " -q -o " + (dir / "a").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::vector<double> d = gabion::bridge::H5Reader(dir / "a" / "result.h5").read("/table/boulder_diameter_m");
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NEAR(d[0], 0.5, 1e-9);  // 170 kg at 2,600 kg/m3
  EXPECT_NEAR(d[1], 2.0, 1e-9);  // 8 times the mass: twice the diameter
  c["sweep"]["keep_diameter"] = true;
  writeFile(dir / "keep.json", c.dump());
  r = runGabion("run " + (dir / "keep.json").string() + " -q -o " + (dir / "b").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  d = gabion::bridge::H5Reader(dir / "b" / "result.h5").read("/table/boulder_diameter_m");
  EXPECT_NEAR(d[0], 1.0, 1e-9);
  EXPECT_NEAR(d[1], 1.0, 1e-9);
}

// The capacity query (cases/macro_capacity.json) against a fine sweep of the
// same wall: every swept impact below the capacity meets the criteria, every
// one above the bracket (capacity x (1 + tolerance)) fails one. A range in
// which nothing meets them is an answer naming the criterion, not a failure.
TEST(MacroCli, CapacityAgreesWithAFineSweep) {
  const auto dir = scratchDir("macro_capacity");
  json c = readJson(kSource + "/cases/macro_capacity.json");
  c["law_file"] = kSource + "/cases/laws/illustrative.json";
  writeFile(dir / "capacity.json", c.dump());
  auto r = runGabion("run " + (dir / "capacity.json").string() + " -q -o " + (dir / "cap").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json cap = readJson(dir / "cap" / "summary.json");
  ASSERT_TRUE(cap.at("converged").get<bool>());
  const double e_cap = cap.at("capacity_energy_J").get<double>(), tol = c["capacity"]["tolerance"].get<double>();
  const double pen_max = c["capacity"]["criteria"]["max_penetration_m"].get<double>();
  const double back_max = c["capacity"]["criteria"]["max_back_face_displacement_m"].get<double>();

  json sw = c;
  sw["kind"] = "macro.sweep";
  sw.erase("capacity");
  sw["sweep"] = {{"velocity_m_s", {{"from", 2}, {"to", 60}, {"count", 59}}}, {"chart", false}};
  writeFile(dir / "sweep.json", sw.dump());
  r = runGabion("run " + (dir / "sweep.json").string() + " -q -o " + (dir / "sweep").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const gabion::bridge::H5Reader h5(dir / "sweep" / "result.h5");
  const auto energy = h5.read("/table/impact_energy_J"), outcome = h5.read("/table/outcome"),
             pen = h5.read("/table/max_penetration_m"), back = h5.read("/table/max_back_face_displacement_m");
  int below = 0, above = 0;
  for (std::size_t i = 0; i < energy.size(); ++i) {
    const bool held = outcome[i] == 0.0 || outcome[i] == 1.0;  // stopped or rebounded
    const bool met = held && pen[i] <= pen_max && back[i] <= back_max;
    if (energy[i] <= e_cap) {
      EXPECT_TRUE(met) << energy[i] << " J";
      ++below;
    }
    if (energy[i] >= e_cap * (1.0 + tol)) {
      EXPECT_FALSE(met) << energy[i] << " J";
      ++above;
    }
  }
  EXPECT_GT(below, 10);
  EXPECT_GT(above, 10);

  c["capacity"]["range"] = {50, 60};
  writeFile(dir / "none.json", c.dump());
  r = runGabion("run " + (dir / "none.json").string() + " -q -o " + (dir / "none").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json none = readJson(dir / "none" / "summary.json");
  EXPECT_TRUE(none.at("capacity_energy_J").is_null());
  EXPECT_EQ(none.at("governing_criterion"), "back_face");  // 50 m/s: back face 7.3x its limit, penetration 1.8x

  for (const auto& [name, edit, pointer] :
       std::vector<std::tuple<std::string, std::function<void(json&)>, std::string>>{
           {"inverted",
            [](json& x) {
              x["capacity"]["range"] = {40, 20};
            },
            "/capacity/range"},
           {"limit", [](json& x) { x["capacity"]["criteria"]["max_penetration_m"] = -1; },
            "/capacity/criteria/max_penetration_m"}}) {
    json bad = c;
    edit(bad);
    writeFile(dir / (name + ".json"), bad.dump());
    const auto b = runGabion("check " + (dir / (name + ".json")).string());
    EXPECT_EQ(b.exit_code, 2) << name << ": " << b.output;
    EXPECT_NE(b.output.find(pointer), std::string::npos) << name << ": " << b.output;
  }
}

// Bad input exits with 2 and names the file and the field.
TEST(MacroCli, BadInputNamesTheField) {
  const auto dir = scratchDir("macro_bad");
  const json base = readJson(kWallCase);
  struct Bad {
    const char* name;
    std::function<void(json&)> edit;
    const char* pointer;
  };
  const std::vector<Bad> bad = {
      {"unknown_key", [](json& c) { c["structure"]["cellz"] = 3; }, "/structure/cellz"},
      {"negative_mass",
       [](json& c) {
         c["boulder"].erase("density_kg_m3");
         c["boulder"]["mass_kg"] = -1;
       },
       "/boulder/mass_kg"},
      {"bad_cells",
       [](json& c) {
         c["structure"]["cells"] = {4, 0, 7};
       },
       "/structure/cells"},
      {"oblique_x_only",
       [](json& c) {
         c["boulder"]["velocity_m_s"] = {20, 5, 0};
       },
       "/boulder/velocity_m_s"},
      {"aim_outside",
       [](json& c) {
         c["boulder"]["aim_point_m"] = {20, 1};
       },
       "/boulder/aim_point_m"},
      {"unknown_material", [](json& c) { c["structure"]["material"]["core"] = "granite"; }, "/structure/material/core"},
      // (an impact that could run 1.3e14 steps and record petabytes is refused with its cost)
      {"endless", [](json& c) { c["run"]["duration_s"] = 1e9; }, "/run/duration_s"},
      // (1e9 cells would take 450 GB: refused before anything is allocated)
      {"huge",
       [](json& c) {
         c["structure"]["cells"] = {1000, 1000, 1000};
       },
       "/structure/cells"},
      {"endless_max", [](json& c) { c["run"]["max_duration_s"] = 1e7; }, "/run/max_duration_s"},
      {"no_laws", [](json& c) { c.erase("law_file"); }, "/law_file"},
      {"bad_kinematics", [](json& c) { c["run"]["kinematics"] = "2d"; }, "/run/kinematics"},
      {"boulder_disagrees", [](json& c) { c["boulder"]["mass_kg"] = 2000; }, "/boulder/density_kg_m3"},
      {"boulder_underdetermined", [](json& c) { c["boulder"].erase("density_kg_m3"); }, "/boulder"},
  };
  for (const auto& b : bad) {
    json c = base;
    c["law_file"] = kSource + "/cases/laws/illustrative.json";
    b.edit(c);
    const auto path = dir / (std::string(b.name) + ".json");
    writeFile(path, c.dump());
    const auto r = runGabion("check " + path.string());
    EXPECT_EQ(r.exit_code, 2) << b.name << ": " << r.output;
    EXPECT_NE(r.output.find(path.string()), std::string::npos) << b.name << ": " << r.output;
    EXPECT_NE(r.output.find(b.pointer), std::string::npos) << b.name << ": " << r.output;
  }
  // A bad law file: the law file and its field are named.
  json law = readJson(kSource + "/cases/laws/illustrative.json");
  law["materials"]["front"]["axial"]["stiffness_N_m"] = -5;
  writeFile(dir / "bad_law.json", law.dump());
  const auto r =
      runGabion("run " + kWallCase + " -q -o " + (dir / "x").string() + " --law " + (dir / "bad_law.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad_law.json"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("/materials/front/axial/stiffness_N_m"), std::string::npos) << r.output;
}

// A time step above the critical one is a numerical failure: exit 3.
TEST(MacroCli, TimeStepAboveCriticalExitsThree) {
  const auto dir = scratchDir("macro_dt");
  const auto r = runGabion("run " + kWallCase + " -q -o " + (dir / "o").string() + " --set run.time_step_s=0.05");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("critical time step"), std::string::npos) << r.output;
}

// cases/macro_design.json on smaller bounds, its law file by absolute path
// (the copy is written elsewhere), without the capacity chart.
namespace {
json smallDesignCase(const json& thickness_cells, const json& height_cells) {
  json c = readJson(kSource + "/cases/macro_design.json");
  c["law_file"] = kSource + "/cases/laws/illustrative.json";
  c["design"]["thickness_cells"] = thickness_cells;
  c["design"]["height_cells"] = height_cells;
  c["design"]["capacity_chart"] = false;
  return c;
}
}  // namespace

// macro.design (cases/macro_design.json on smaller bounds): the bisection
// over the thickness returns the section exhaustive enumeration finds; the
// chosen section holds its design impacts (residual capacity at least the
// number asked) and the next thinner one of its height and material does not.
TEST(MacroCli, DesignBisectionAgreesWithExhaustiveEnumeration) {
  const auto dir = scratchDir("macro_design");
  json c = smallDesignCase({2, 7}, {2, 4});
  json answers[2];
  int k = 0;
  for (const char* search : {"bisection", "exhaustive"}) {
    c["design"]["search"] = search;
    writeFile(dir / (std::string(search) + ".json"), c.dump());
    const auto r = runGabion("run " + (dir / (std::string(search) + ".json")).string() + " -q --threads 2 -o " +
                             (dir / search).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    answers[k++] = readJson(dir / search / "summary.json");
  }
  const json& b = answers[0].at("design");
  const json& e = answers[1].at("design");
  ASSERT_FALSE(b.is_null());
  EXPECT_EQ(b.at("thickness_cells"), e.at("thickness_cells"));
  EXPECT_EQ(b.at("height_cells"), e.at("height_cells"));
  EXPECT_EQ(b.at("front_material"), e.at("front_material"));
  EXPECT_EQ(b.at("margins"), e.at("margins"));
  EXPECT_LT(answers[0].at("sections_evaluated").get<int>(), answers[1].at("sections_evaluated").get<int>());
  EXPECT_GE(answers[0].at("residual_capacity_impacts").get<int>(), c["design"]["criteria"]["impacts"].get<int>());
  for (const auto& s : answers[1].at("sections")) {  // nothing cheaper holds
    if (s.at("met").get<bool>()) {
      EXPECT_GE(s.at("cells").get<int>(), b.at("cells").get<int>());
    }
  }
  bool thinner_checked = false;
  for (const auto& s : answers[1].at("sections"))
    if (s.at("height_cells") == b.at("height_cells") && s.at("front_material") == b.at("front_material") &&
        s.at("thickness_cells").get<int>() == b.at("thickness_cells").get<int>() - 1) {
      EXPECT_FALSE(s.at("met").get<bool>());
      thinner_checked = true;
    }
  EXPECT_TRUE(thinner_checked);
}

// Criteria that no section in the bounds meets give an answer naming the
// criterion (exit 0, no design); a table of impacts with probabilities and
// an acceptance probability below 1 accept a section that fails the rarest
// impact; bad bounds, materials and tables are input errors naming the field.
TEST(MacroCli, DesignAnswersImpossibleCriteriaAndRefusesBadBounds) {
  const auto dir = scratchDir("macro_design_bad");
  json c = smallDesignCase({2, 3}, {3, 3});
  c["design"]["criteria"]["max_back_face_displacement_m"] = 1e-6;
  writeFile(dir / "none.json", c.dump());
  auto r = runGabion("run " + (dir / "none.json").string() + " -q -o " + (dir / "none").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  json none = readJson(dir / "none" / "summary.json");
  EXPECT_TRUE(none.at("design").is_null());
  EXPECT_EQ(none.at("governing_criterion"), "back_face");
  EXPECT_NE(none.at("answer").get<std::string>().find("no section"), std::string::npos);

  // Two impacts: the design one (90 %) and a rare fast one (10 %) that the
  // 2-cell section cannot hold.
  json t = c;
  t["design"]["criteria"] = {{"max_back_face_displacement_m", 0.02}, {"max_penetration_m", 0.25}};
  t["design"]["front_materials"] = {"front"};
  t["design"]["thickness_cells"] = {2, 6};
  t["boulder"]["velocity_m_s"] = 15;
  t["impacts"] = {{{"probability", 0.9}}, {{"velocity_m_s", 28}, {"probability", 0.1}}};
  int thickness[2];
  for (int i = 0; i < 2; ++i) {
    t["design"]["acceptance_probability"] = i == 0 ? 1.0 : 0.85;
    writeFile(dir / "table.json", t.dump());
    r = runGabion("run " + (dir / "table.json").string() + " -q -o " + (dir / ("table" + std::to_string(i))).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const json s = readJson(dir / ("table" + std::to_string(i)) / "summary.json");
    ASSERT_FALSE(s.at("design").is_null()) << s.at("answer");
    thickness[i] = s.at("design").at("thickness_cells").get<int>();
    if (i == 1) {
      EXPECT_NEAR(s.at("design").at("probability_met").get<double>(), 0.9, 1e-12);
      for (const auto& [name, margin] : s.at("design").at("margins").items())  // (over the impacts it holds)
        EXPECT_GE(margin.get<double>(), 0.0) << name;
    }
  }
  EXPECT_LT(thickness[1], thickness[0]);

  writeFile(dir / "impacts.csv", "velocity_m_s,probability\n15,0.5\n20,abc\n");
  struct Bad {
    const char* name;
    std::function<void(json&)> edit;
    const char* where;
  };
  const std::vector<Bad> bad = {
      {"inverted",
       [](json& x) {
         x["design"]["thickness_cells"] = {6, 2};
       },
       "/design/thickness_cells"},
      {"zero",
       [](json& x) {
         x["design"]["height_cells"] = {0, 3};
       },
       "/design/height_cells"},
      {"material",
       [](json& x) {
         x["design"]["front_materials"] = {"front", "granite"};
       },
       "/design/front_materials/1"},
      {"probabilities",
       [](json& x) {
         x["impacts"] = {{{"probability", 0.5}}, {{"probability", 0.2}}};
       },
       "/impacts"},
      {"csv", [&](json& x) { x["impacts_csv"] = (dir / "impacts.csv").string(); }, "line 3, column 2 (probability)"},
      {"aim",
       [](json& x) {
         x["boulder"]["aim_point_m"] = {2.75, 9.0};
       },
       "/boulder/aim_point_m"}};
  for (const auto& b : bad) {
    json x = c;
    b.edit(x);
    writeFile(dir / (std::string(b.name) + ".json"), x.dump());
    const auto out = runGabion("check " + (dir / (std::string(b.name) + ".json")).string());
    EXPECT_EQ(out.exit_code, 2) << b.name << ": " << out.output;
    EXPECT_NE(out.output.find(b.where), std::string::npos) << b.name << ": " << out.output;
  }
}
