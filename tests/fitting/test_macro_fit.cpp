// The `fit.macro` case through the gabion command line: the impact law of a
// macro case identified from the histories of its own runs (the truth must
// come back), and bad input named by its key before anything runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <random>

#include "bridge/law_file.hpp"
#include "bridge/output.hpp"
#include "tests/support/run_gabion.hpp"

namespace gabion::fitting {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::runGabion;

const fs::path kCases = fs::path(GABION_SOURCE_DIR) / "cases";

// A 2 x 1 x 1 macro.impact case with the illustrative laws embedded, the front
// material's impact law a softening law with a rate term of coefficient
// `rate` and peak `peak`.
json smallWall(double peak, double rate) {
  json laws = json::parse(std::ifstream(kCases / "laws" / "illustrative.json"));
  json& imp = laws["materials"]["front"]["impact"];
  imp = {{"model", "softening"},
         {"stiffness_N_m", 2e6},
         {"yield_force_N", peak},
         {"softening_onset_m", 0.03},
         {"softening_stiffness_N_m", 4e6},
         {"residual_force_N", 8e3},
         {"rate_coefficient_N_s2_m2", rate},
         {"lockup_shortening_m", 0.2},
         {"lockup_stiffness_N_m", 2e7}};
  return {{"format", "gabion.case/1"},
          {"kind", "macro.impact"},
          {"laws", {{"materials", laws["materials"]}}},
          {"structure",
           {{"cells", {2, 1, 1}},
            {"material", {{"front", "front"}, {"core", "core"}}},
            {"support", {{"back", "fixed"}, {"ground", "none"}}}}},
          {"boulder", {{"diameter_m", 0.5}, {"density_kg_m3", 2600}, {"velocity_m_s", 8}}},
          {"run", {{"kinematics", "x-only"}, {"duration_s", 0.1}}}};
}

json history(const fs::path& h5, const std::string& quantity) {
  return {{"quantity", quantity},
          {"file", h5.string()},
          {"x_dataset", "/series/time_s"},
          {"y_dataset", "/series/" + quantity}};
}

json fitCase(const fs::path& truth_dir) {
  const std::string imp = "laws.materials.front.impact.";
  json scenarios = json::array();
  for (int v : {6, 10}) {
    const fs::path h5 = truth_dir / ("v" + std::to_string(v)) / "result.h5";
    scenarios.push_back({{"name", std::to_string(v) + " m/s"},
                         {"set", {{"boulder.velocity_m_s", v}}},
                         {"curves", {history(h5, "boulder_force_N"), history(h5, "penetration_m")}}});
  }
  return {{"format", "gabion.case/1"},
          {"kind", "fit.macro"},
          {"seed", 1},
          {"macro_case", "wall.json"},
          {"parameters",
           {{{"name", "peak"}, {"set", imp + "yield_force_N"}, {"bounds", {2e4, 2e5}}},
            {{"name", "rate coefficient"}, {"set", imp + "rate_coefficient_N_s2_m2"}, {"bounds", {10, 5000}}}}},
          {"scenarios", scenarios},
          {"optimizer", {{"global", "GN_ISRES"}, {"global_max_evaluations", 600}, {"local_max_evaluations", 400}}}};
}

// The histories of the wall with peak 60 kN and c = 800 kg/m at 6 and 10 m/s
// (the peak's overstress 29 and 80 kN) give those values back to 1 %: the
// objective sees each run's force and penetration against time from first
// contact, and nothing else.
TEST(FitMacro, TheImpactLawComesBackFromItsOwnHistories) {
  const fs::path dir = testing::scratchDir("fit_macro_recovery");
  std::ofstream(dir / "truth.json") << smallWall(6e4, 800.0).dump(2);
  for (int v : {6, 10}) {
    const auto r =
        runGabion("run " + (dir / "truth.json").string() + " -q --set boulder.velocity_m_s=" + std::to_string(v) +
                  " -o " + (dir / ("v" + std::to_string(v))).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  // The case the fit starts from has other values; the fit sets them.
  std::ofstream(dir / "wall.json") << smallWall(1e5, 100.0).dump(2);
  std::ofstream(dir / "fit.json") << fitCase(dir).dump(2);
  const auto r = runGabion("run " + (dir / "fit.json").string() + " -q -o " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto law = bridge::loadLawFile(dir / "out" / "law.json");
  const auto& imp = law.materials.at("front").impact;
  EXPECT_NEAR(imp.yield_force_N, 6e4, 0.01 * 6e4);
  EXPECT_NEAR(imp.rate_coefficient_N_s2_m2, 800.0, 0.01 * 800.0);
  // The rest of the law is the macro case's.
  EXPECT_EQ(imp.softening_onset_m, 0.03);
  const auto base = bridge::loadLawFile(kCases / "laws" / "illustrative.json");
  EXPECT_EQ(law.materials.at("core").axial.yield_force_N, base.materials.at("core").axial.yield_force_N);
  const json summary = json::parse(std::ifstream(dir / "out" / "summary.json"));
  const json& res = summary.contains("results") ? summary["results"] : summary;
  EXPECT_LT(res["nrms"].get<double>(), 1e-3);
  EXPECT_EQ(res["scenarios"].size(), 2u);
  EXPECT_EQ(res["plots"].size(), 4u);
  EXPECT_TRUE(fs::exists(dir / "out" / "fit_macro_2_boulder_force_N.png"));
  // Noise-free histories: the 95 % intervals are there, hold the value and
  // are narrow (0.1 % of it).
  for (const auto& p : res["parameters"]) {
    ASSERT_TRUE(p["jacobian_95"].is_array()) << p.dump();
    const double v = p["value"].get<double>(), lo = p["jacobian_95"][0].get<double>(),
                 hi = p["jacobian_95"][1].get<double>();
    EXPECT_LE(lo, v);
    EXPECT_GE(hi, v);
    EXPECT_LT(hi - lo, 1e-3 * v) << p.dump();
  }
}

// The same histories with Gaussian noise of 2 % of each history's largest
// value (seeded): the linearised 95 % intervals hold the truth, and their
// width is of the order the noise gives (not zero, not the bounds).
TEST(FitMacro, IntervalsHoldTheTruthOnNoisyHistories) {
  const fs::path dir = testing::scratchDir("fit_macro_noise");
  std::ofstream(dir / "truth.json") << smallWall(6e4, 800.0).dump(2);
  std::ofstream(dir / "wall.json") << smallWall(1e5, 100.0).dump(2);
  std::mt19937_64 rng(20261127);
  std::normal_distribution<double> noise(0.0, 1.0);
  json fit = fitCase(dir);
  for (int i = 0; i < 2; ++i) {
    const int v = i == 0 ? 6 : 10;
    const fs::path run = dir / ("v" + std::to_string(v));
    ASSERT_EQ(runGabion("run " + (dir / "truth.json").string() + " -q --set boulder.velocity_m_s=" + std::to_string(v) +
                        " -o " + run.string())
                  .exit_code,
              0);
    const bridge::H5Reader h5(run / "result.h5");
    const auto t = h5.read("/series/time_s");
    const auto f = h5.read("/series/boulder_force_N"), pen = h5.read("/series/penetration_m");
    const double fmax = *std::max_element(f.begin(), f.end()), pmax = *std::max_element(pen.begin(), pen.end());
    const fs::path csv = dir / ("noisy_" + std::to_string(v) + ".csv");
    std::ofstream out(csv);
    out.precision(12);
    out << "time_s,boulder_force_N,penetration_m\n";
    // (zero before the contact, as measured: the contact is where the force leaves zero)
    const auto contact =
        static_cast<std::size_t>(std::find_if(f.begin(), f.end(), [](double x) { return x > 0; }) - f.begin());
    for (std::size_t k = 0; k < t.size(); ++k) {
      const bool after = k >= contact;
      out << t[k] << "," << (after ? f[k] + 0.02 * fmax * noise(rng) : 0.0) << ","
          << (after ? pen[k] + 0.02 * pmax * noise(rng) : 0.0) << "\n";
    }
    fit["scenarios"][i]["curves"] = {{{"quantity", "boulder_force_N"}, {"file", csv.string()}},
                                     {{"quantity", "penetration_m"}, {"file", csv.string()}}};
  }
  std::ofstream(dir / "fit.json") << fit.dump(2);
  const auto r = runGabion("run " + (dir / "fit.json").string() + " -q -o " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json summary = json::parse(std::ifstream(dir / "out" / "summary.json"));
  const json& res = summary.contains("results") ? summary["results"] : summary;
  const double truth[] = {6e4, 800.0};
  for (std::size_t k = 0; k < 2; ++k) {
    const json& p = res["parameters"][k];
    ASSERT_TRUE(p["jacobian_95"].is_array()) << p.dump();
    const double lo = p["jacobian_95"][0].get<double>(), hi = p["jacobian_95"][1].get<double>();
    EXPECT_LE(lo, truth[k]) << p.dump();
    EXPECT_GE(hi, truth[k]) << p.dump();
    EXPECT_GT(hi - lo, 1e-4 * truth[k]) << p.dump();
    EXPECT_LT(hi - lo, 0.2 * truth[k]) << p.dump();
  }
}

// A parameter the histories cannot see (the impact law of the core
// material, which no front cell has): no intervals for any, and the answer
// and the summary's `intervals_note` say why, naming that parameter.
TEST(FitMacro, AParameterTheHistoriesDoNotSeeIsNamed) {
  const fs::path dir = testing::scratchDir("fit_macro_unseen");
  std::ofstream(dir / "truth.json") << smallWall(6e4, 800.0).dump(2);
  for (int v : {6, 10})
    ASSERT_EQ(runGabion("run " + (dir / "truth.json").string() + " -q --set boulder.velocity_m_s=" + std::to_string(v) +
                        " -o " + (dir / ("v" + std::to_string(v))).string())
                  .exit_code,
              0);
  std::ofstream(dir / "wall.json") << smallWall(1e5, 100.0).dump(2);
  json fit = fitCase(dir);
  fit["parameters"].push_back(
      {{"name", "core peak"}, {"set", "laws.materials.core.impact.yield_force_N"}, {"bounds", {2e4, 2e5}}});
  fit["optimizer"] = {{"global", "GN_ISRES"}, {"global_max_evaluations", 300}, {"local_max_evaluations", 200}};
  std::ofstream(dir / "fit.json") << fit.dump(2);
  const auto r = runGabion("run " + (dir / "fit.json").string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no 95 % intervals: the curves do not determine every parameter"), std::string::npos)
      << r.output;
  const json summary = json::parse(std::ifstream(dir / "out" / "summary.json"));
  const json& res = summary.contains("results") ? summary["results"] : summary;
  ASSERT_TRUE(res.contains("intervals_note")) << res.dump();
  EXPECT_NE(res["intervals_note"].get<std::string>().find("mostly core peak"), std::string::npos)
      << res["intervals_note"];
  for (const auto& p : res["parameters"]) EXPECT_TRUE(p["jacobian_95"].is_null()) << p.dump();

  // With profile-likelihood intervals asked for, every parameter has one:
  // the two the histories see hold their truth, and the unseen one's reach
  // both of its bounds (the misfit never grows along it).
  fit["uncertainty"] = {{"profile", true}};
  std::ofstream(dir / "fit.json") << fit.dump(2);
  const auto rp = runGabion("run " + (dir / "fit.json").string() + " -o " + (dir / "out_profile").string());
  ASSERT_EQ(rp.exit_code, 0) << rp.output;
  EXPECT_NE(rp.output.find("no linearised 95 % intervals (the profile ones above)"), std::string::npos) << rp.output;
  const json sp = json::parse(std::ifstream(dir / "out_profile" / "summary.json"));
  const json& rs = sp.contains("results") ? sp["results"] : sp;
  EXPECT_GT(rs["profile_evaluations"].get<int>(), 0);
  const double truth[] = {6e4, 800.0};
  for (std::size_t k = 0; k < 3; ++k) {
    const json& p = rs["parameters"][k];
    ASSERT_TRUE(p["profile_95"].is_array()) << p.dump();
    const double lo = p["profile_95"][0].get<double>(), hi = p["profile_95"][1].get<double>();
    if (k < 2) {
      EXPECT_LE(lo, truth[k]) << p.dump();
      EXPECT_GE(hi, truth[k]) << p.dump();
      EXPECT_FALSE(p["profile_at_bound"].get<bool>()) << p.dump();
    } else {
      EXPECT_TRUE(p["profile_at_bound"].get<bool>()) << p.dump();
      EXPECT_EQ(lo, 2e4) << p.dump();
      EXPECT_EQ(hi, 2e5) << p.dump();
    }
  }
}

// Bad input exits 2 and names the fit case's key before anything runs.
TEST(FitMacro, BadInputNamesTheKey) {
  const fs::path dir = testing::scratchDir("fit_macro_bad");
  std::ofstream(dir / "wall.json") << smallWall(6e4, 800.0).dump(2);
  std::ofstream(dir / "v6.csv") << "time_s,boulder_force_N\n0,0\n0.001,1000\n0.002,3000\n0.003,2000\n0.004,500\n";
  const auto expect = [&](json c, const std::string& what) {
    std::ofstream(dir / "fit.json") << c.dump(2);
    const auto r = runGabion("check " + (dir / "fit.json").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(what), std::string::npos) << r.output;
  };
  json good = {{"format", "gabion.case/1"},
               {"kind", "fit.macro"},
               {"macro_case", "wall.json"},
               {"parameters", {{{"set", "laws.materials.front.impact.yield_force_N"}, {"bounds", {2e4, 2e5}}}}},
               {"scenarios",
                {{{"set", {{"boulder.velocity_m_s", 6}}},
                  {"curves", {{{"quantity", "boulder_force_N"}, {"file", (dir / "v6.csv").string()}}}}}}}};
  std::ofstream(dir / "fit.json") << good.dump(2);
  ASSERT_EQ(runGabion("check " + (dir / "fit.json").string()).exit_code, 0);
  json c = good;
  c["parameters"][0]["set"] = "laws.materials.front.impact.no_such_key";
  expect(c, "/parameters/0/set");
  c = good;
  c["parameters"][0]["set"] = "laws.materials.front.impact.residual_force_N";
  c["parameters"][0]["bounds"] = {-2e4, -1e4};  // a residual force below 0
  expect(c, "/parameters/0/set");
  c = good;
  c["scenarios"][0]["set"] = {{"boulder.no_such_key", 6}};
  expect(c, "/scenarios/0/set/boulder.no_such_key");
  c = good;
  c["scenarios"][0]["curves"][0]["quantity"] = "speed";
  expect(c, "/scenarios/0/curves/0/quantity");
  c = good;
  c["macro_case"] = "fit.json";
  expect(c, "fit.macro runs a macro.impact case");
}

}  // namespace
}  // namespace gabion::fitting
