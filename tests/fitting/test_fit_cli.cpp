// The `fit` case through the gabion command line: bad curve data exits with
// code 2 and names the file, line and column; a good case writes a valid
// law.json with provenance, plots and the summary entries.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "bridge/law_file.hpp"
#include "tests/support/run_gabion.hpp"

namespace gabion::fitting {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::runGabion;

const fs::path kData = fs::path(GABION_TEST_DATA_DIR) / "fitting";
const fs::path kCases = fs::path(GABION_SOURCE_DIR) / "cases";

// A fit case of the impact law of material "cell" (the others from the
// example base law): the candidate `models` on `curves`, no lock-up within
// the curves (strain 0.5), ISRES with `evaluations` global evaluations.
json impactFitCase(const json& models, const json& curves, int evaluations) {
  return {
      {"format", "gabion.case/1"},
      {"kind", "fit"},
      {"seed", 1},
      {"material", {{"name", "cell"}}},
      {"base_law", {{"file", (kCases / "data/fit/illustrative_law.json").string()}, {"material", "limestone_cell"}}},
      {"lockup", {{"strain", 0.5}}},
      {"optimizer", {{"global", "GN_ISRES"}, {"global_max_evaluations", evaluations}}},
      {"impact",
       {{"models", models},
        {"curves", curves},
        {"bounds", {{"stiffness_N_m", {1e5, 1e9}}, {"yield_force_N", {1e3, 1e6}}}}}}};
}

// A fit case of the axial law from one CSV curve, completed by the example base law.
fs::path writeAxialCase(const fs::path& dir, const fs::path& csv) {
  const json c = {
      {"format", "gabion.case/1"},
      {"kind", "fit"},
      {"material", {{"name", "cell"}}},
      {"base_law", {{"file", (kCases / "data/fit/illustrative_law.json").string()}, {"material", "limestone_cell"}}},
      {"axial",
       {{"curves", {{{"file", csv.string()}}}},
        {"bounds",
         {{"stiffness_N_m", {1e5, 1e8}}, {"yield_force_N", {1e3, 1e6}}, {"hardening_stiffness_N_m", {0, 1e6}}}}}}};
  const fs::path file = dir / "case.json";
  std::ofstream(file) << c.dump(2);
  return file;
}

TEST(FitCli, BadCurveDataExitsTwoNamingFileLineAndColumn) {
  const auto dir = testing::scratchDir("fit_cli_bad");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"empty.csv", "empty file"},
      {"non_numeric.csv", "line 4, column 2 (force_N): not a number"},
      {"unsorted.csv", "line 5, column 1 (displacement_m): unsorted"},
      {"nan.csv", "line 5, column 2 (force_N): value is not finite"},
      {"wrong_units.csv", "line 1, column 1 (displacement_mm): column 'displacement_mm' has the wrong unit"},
      {"too_short.csv", "curve too short"}};
  for (const auto& [file, message] : cases) {
    const auto c = writeAxialCase(dir, kData / file);
    for (const char* cmd : {"check", "run"}) {
      const auto r = runGabion(std::string(cmd) + " " + c.string() +
                               (std::string(cmd) == "run" ? " -q -o " + (dir / "out").string() : ""));
      EXPECT_EQ(r.exit_code, 2) << file << ": " << r.output;
      EXPECT_NE(r.output.find(file), std::string::npos) << r.output;
      EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
    }
  }
}

TEST(FitCli, CaseErrorsNameThePointer) {
  const auto dir = testing::scratchDir("fit_cli_pointer");
  json c = json::parse(std::ifstream(kCases / "fit_lab_cc.json"));
  c["base_law"]["file"] = (kCases / "data/fit/illustrative_law.json").string();
  for (auto& curve : c["axial"]["curves"]) curve["file"] = (kCases / curve["file"].get<std::string>()).string();
  for (auto& curve : c["lateral"]["curves"]) curve["file"] = (kCases / curve["file"].get<std::string>()).string();
  c["optimizer"]["local"] = "LN_MAGIC";
  std::ofstream(dir / "c.json") << c.dump();
  auto r = runGabion("check " + (dir / "c.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("/optimizer/local"), std::string::npos) << r.output;
  c["optimizer"]["local"] = "LN_BOBYQA";
  c["axial"]["bounds"]["stiffness_N_m"] = {1e6, 1e5};
  std::ofstream(dir / "c.json") << c.dump();
  r = runGabion("check " + (dir / "c.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("/axial/bounds/stiffness_N_m"), std::string::npos) << r.output;
  c["axial"]["bounds"]["stiffness_N_m"] = {1e5, 1e8};
  c["axial"]["curves"][0]["velocity_m_s"] = 3;  // not a key of axial curves
  std::ofstream(dir / "c.json") << c.dump();
  r = runGabion("check " + (dir / "c.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("/axial/curves/0/velocity_m_s"), std::string::npos) << r.output;
}

TEST(FitCli, ExampleCaseWritesLawSummaryAndPlots) {
  const auto out = testing::scratchDir("fit_cli_run");
  const auto r = runGabion("run " + (kCases / "fit_cell_laws.json").string() + " -q -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto law = bridge::loadLawFile(out / "law.json");  // validates gabion.law/2
  const auto& m = law.materials.at("limestone_cell");
  EXPECT_EQ(m.provenance.at("status"), "fitted");
  // The synthetic truth of cases/data/fit/generate.py.
  EXPECT_EQ(m.axial.model, bridge::AxialModel::Bilinear);
  EXPECT_NEAR(m.axial.stiffness_N_m, 4e6, 0.02 * 4e6);
  EXPECT_NEAR(m.axial.yield_force_N, 6e4, 0.02 * 6e4);
  EXPECT_NEAR(m.lateral.reaction_coefficient, 0.4, 0.01);
  EXPECT_NEAR(m.interface.friction, 0.55, 0.01);
  EXPECT_EQ(m.impact.model, bridge::AxialModel::ElasticPerfectlyPlastic);
  EXPECT_NEAR(m.impact.yield_force_N, 1.2e5, 0.02 * 1.2e5);
  const auto& fitted = m.provenance.at("fitted");
  EXPECT_EQ(fitted.at("axial").at("inputs").at(0).at("sha256").get<std::string>().size(), 64u);
  EXPECT_TRUE(fitted.at("axial").at("parameters").at("stiffness_N_m").at("profile_95").is_array());
  const json summary = json::parse(std::ifstream(out / "summary.json"));
  for (const char* t : {"axial", "lateral", "interface", "impact"}) {
    EXPECT_GT(summary.at("fit").at(t).at("evaluations").get<int>(), 0) << t;
    EXPECT_LT(summary.at("fit").at(t).at("wall_time_s").get<double>(), 1.0) << t;
    EXPECT_TRUE(fs::exists(out / (std::string("fit_") + t + ".png"))) << t;
  }
}

TEST(FitCli, PartialFitFromIllustrativeBaseIsIllustrative) {
  const auto out = testing::scratchDir("fit_cli_partial");
  const auto r = runGabion("run " + (kCases / "fit_lab_cc.json").string() + " -q -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto law = bridge::loadLawFile(out / "law.json");
  const auto& m = law.materials.at("limestone_cell");
  EXPECT_EQ(m.provenance.at("status"), "illustrative");
  EXPECT_EQ(m.provenance.at("from_base_law").at("laws"), json({"interface", "impact"}));
}

// The softening impact law through a fit case: a curve of that law (a peak
// held, a fall, a residual; 1 % noise) as CSV, the softening model among the
// candidates with only the stiffness and peak bounded (the onset, falling
// tangent and residual ratio take their default bounds), ISRES as the search:
// law.json gets the softening law near the truth, readable by the macro model.
TEST(FitCli, ASofteningImpactLawIsFittedWithItsDefaultBounds) {
  const auto out = testing::scratchDir("fit_cli_softening");
  bridge::AxialLawParams truth{bridge::AxialModel::Softening, 1.6e6, 8e4, 0.0};
  truth.softening_onset_m = 0.025;
  truth.softening_stiffness_N_m = 5e6;
  truth.residual_force_N = 1e4;
  std::ofstream csv(out / "impact.csv");
  csv << "penetration_m,force_N\n";
  double plastic = 0.0;
  for (int i = 0; i <= 190; ++i) {
    const double u = 0.001 * i;
    const auto r = bridge::axialResponse(truth, u, plastic);
    plastic = r.plastic_m;
    csv << u << "," << r.force_N + 800.0 * std::sin(7.0 * i) << "\n";  // +-1 % of the peak, deterministic
  }
  csv.close();
  const json c = impactFitCase({"elastic_perfectly_plastic", "softening"},
                               {{{"file", (out / "impact.csv").string()}, {"velocity_m_s", 10}}}, 4000);
  std::ofstream(out / "case.json") << c.dump(2);
  const auto r = runGabion("run " + (out / "case.json").string() + " -q -o " + (out / "fit").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto law = bridge::loadLawFile(out / "fit" / "law.json");
  const auto& m = law.materials.at("cell");
  ASSERT_EQ(m.impact.model, bridge::AxialModel::Softening);
  EXPECT_NEAR(m.impact.stiffness_N_m, 1.6e6, 0.05 * 1.6e6);
  EXPECT_NEAR(m.impact.yield_force_N, 8e4, 0.02 * 8e4);
  EXPECT_NEAR(m.impact.softening_onset_m, 0.025, 0.1 * 0.025);
  EXPECT_NEAR(m.impact.softening_stiffness_N_m, 5e6, 0.2 * 5e6);
  EXPECT_NEAR(m.impact.residual_force_N, 1e4, 0.05 * 1e4);
}

// The rate law end to end: two impact curves in CSV with their time axis
// (`t_column`), the law written with its rate coefficient; a time axis that
// does not increase is refused naming the file, the column and the line.
TEST(FitCli, ARateImpactLawIsFittedFromCurvesWithTheirTimeAxis) {
  const auto out = testing::scratchDir("fit_cli_rate");
  bridge::AxialLawParams truth{bridge::AxialModel::Softening, 1.6e6, 3e4, 0.0};
  truth.softening_onset_m = 0.02;
  truth.softening_stiffness_N_m = 1e6;
  truth.residual_force_N = 6e3;
  truth.rate_coefficient_N_s2_m2 = 500.0;
  truth.rate_growth_m = 0.02;
  json curves = json::array();
  for (double v0 : {6.0, 10.0}) {
    const std::string name = "impact_" + std::to_string(static_cast<int>(v0)) + ".csv";
    std::ofstream csv(out / name);
    csv.precision(12);
    csv << "time_s,penetration_m,force_N\n";
    double plastic = 0.0;
    const double T = 0.03;
    for (int i = 0; i <= 300; ++i) {
      const double t = T * i / 300, u = v0 * (t - 0.5 * t * t / T), rate = v0 * (1.0 - t / T);
      const auto r = bridge::axialResponse(truth, u, plastic, rate);
      plastic = r.plastic_m;
      csv << t << "," << u << "," << r.force_N + 300.0 * std::sin(7.0 * i) << "\n";  // +-1 % of the peak
    }
    curves.push_back({{"file", (out / name).string()}, {"velocity_m_s", v0}, {"t_column", "time_s"}});
  }
  json c = impactFitCase({"softening_rate"}, curves, 10000);
  std::ofstream(out / "case.json") << c.dump(2);
  const auto r = runGabion("run " + (out / "case.json").string() + " -q -o " + (out / "fit").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto law = bridge::loadLawFile(out / "fit" / "law.json");
  const auto& m = law.materials.at("cell").impact;
  EXPECT_NEAR(m.rate_coefficient_N_s2_m2, 500.0, 0.05 * 500.0);
  EXPECT_NEAR(m.rate_growth_m, 0.02, 0.1 * 0.02);
  // (10 %: the peak, F_y + c r^2 at the rate of first yield, is what the
  // curves fix, and F_y and c trade along it under the data's ripple; the
  // recovery itself is LawFit.RateTermIsIdentifiedAcrossSpeeds')
  EXPECT_NEAR(m.yield_force_N, 3e4, 0.1 * 3e4);
  // A time that goes back at the data's line 5 (the header is line 1).
  std::ofstream(out / "back.csv") << "time_s,penetration_m,force_N\n0,0,0\n0.001,0.01,1000\n0.002,0.02,2000\n"
                                     "0.0015,0.03,3000\n0.004,0.04,4000\n0.005,0.05,5000\n";
  c["impact"]["curves"][0]["file"] = (out / "back.csv").string();
  std::ofstream(out / "back.json") << c.dump(2);
  const auto bad = runGabion("check " + (out / "back.json").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("back.csv"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("line 5, column 1 (time_s)"), std::string::npos) << bad.output;
}

// The axial law from a slow compression, its momentum flux from two fast
// ones (CSV curves with their time axis): law.json carries both, the flux
// within 5 % of the curves' truth; the chart is written. A rate curve
// without its time axis, or rate curves on another law, are named.
TEST(FitCli, TheAxialMomentumFluxIsFittedFromFastCompressions) {
  const auto out = testing::scratchDir("fit_cli_flux");
  bridge::AxialLawParams truth{bridge::AxialModel::Bilinear, 4e5, 2e3, 1e5};
  truth.momentum_flux_kg_m = 1200.0;
  truth.momentum_flux_growth_m = 0.03;
  const auto write = [&](const std::string& name, double v) {
    std::ofstream csv(out / name);
    csv.precision(12);
    csv << "time_s,displacement_m,force_N\n";
    double plastic = 0.0;
    for (int i = 0; i <= 200; ++i) {
      const double u = 0.06 * i / 200;
      const auto r = bridge::axialResponse(truth, u, plastic);
      plastic = r.plastic_m;
      const double flux = bridge::fillRateForce(0.0, 1200.0, 0.03, u, v, r.force_N);
      csv << (i + 1) * 0.06 / 200 / v << "," << u << "," << r.force_N + flux + 50.0 * std::sin(7.0 * i) << "\n";
    }
  };
  write("slow.csv", 0.01);
  write("fast_2.csv", 2.0);
  write("fast_4.csv", 4.0);
  json c = {
      {"format", "gabion.case/1"},
      {"kind", "fit"},
      {"material", {{"name", "cell"}}},
      {"base_law", {{"file", (kCases / "data/fit/illustrative_law.json").string()}, {"material", "limestone_cell"}}},
      {"lockup", {{"strain", 0.5}}},
      {"axial",
       {{"models", {"bilinear"}},
        {"curves", {{{"file", (out / "slow.csv").string()}}}},
        {"rate_curves",
         {{{"file", (out / "fast_2.csv").string()}, {"t_column", "time_s"}},
          {{"file", (out / "fast_4.csv").string()}, {"t_column", "time_s"}}}},
        {"bounds",
         {{"stiffness_N_m", {1e5, 1e7}}, {"yield_force_N", {1e2, 1e5}}, {"hardening_stiffness_N_m", {0, 1e6}}}}}}};
  std::ofstream(out / "case.json") << c.dump(2);
  const auto r = runGabion("run " + (out / "case.json").string() + " -q -o " + (out / "fit").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto law = bridge::loadLawFile(out / "fit" / "law.json");
  const auto& axial = law.materials.at("cell").axial;
  EXPECT_NEAR(axial.momentum_flux_kg_m, 1200.0, 0.05 * 1200.0);
  EXPECT_NEAR(axial.momentum_flux_growth_m, 0.03, 0.05 * 0.03);
  EXPECT_NEAR(axial.stiffness_N_m, 4e5, 0.05 * 4e5);  // (the law from the slow curve alone)
  EXPECT_TRUE(fs::exists(out / "fit" / "fit_momentum_flux.png"));
  const json summary = json::parse(std::ifstream(out / "fit" / "summary.json"));
  EXPECT_EQ(summary["fit"]["momentum_flux"]["inputs"].size(), 2u) << summary["fit"].dump();

  json bad = c;
  bad["axial"]["rate_curves"][1].erase("t_column");
  std::ofstream(out / "bad.json") << bad.dump(2);
  auto e = runGabion("check " + (out / "bad.json").string());
  EXPECT_EQ(e.exit_code, 2) << e.output;
  EXPECT_NE(e.output.find("/axial/rate_curves/1/t_column"), std::string::npos) << e.output;
  bad = c;
  bad["lateral"] = {{"curves", c["axial"]["curves"]},
                    {"rate_curves", c["axial"]["rate_curves"]},
                    {"bounds", {{"reaction_coefficient", {0, 2}}}}};
  std::ofstream(out / "bad.json") << bad.dump(2);
  e = runGabion("check " + (out / "bad.json").string());
  EXPECT_EQ(e.exit_code, 2) << e.output;
  EXPECT_NE(e.output.find("/lateral/rate_curves"), std::string::npos) << e.output;
}

// The joint law through a fit case: the curves of one cell and of a row of
// two (CSV; the row's two cells with a joint closing as 2 mm (F / 1 kN)^0.6
// between them) go into the law file with the base law's other laws, its
// provenance and its figure. A row that is just two cells has no joint to
// fit: exit 2, naming the field.
TEST(FitCli, AJointFromTwoCompressionsGoesIntoTheLawFile) {
  const auto out = testing::scratchDir("fit_cli_joint");
  const auto write = [&](const std::string& name, double joint_c1_m) {
    std::ofstream csv(out / name);
    csv.precision(12);
    csv << "displacement_m,force_N\n";
    for (int k = 0; k <= 2000; ++k) {
      const double f = 60.0 * k, cell = 0.08 * std::pow(f / 6e4, 0.4);
      csv << 2.0 * cell + joint_c1_m * std::pow(f / 1e3, 0.6) << "," << f << "\n";
    }
  };
  {
    std::ofstream csv(out / "cell.csv");
    csv.precision(12);
    csv << "displacement_m,force_N\n";
    for (int k = 0; k <= 2000; ++k) csv << 0.08 * std::pow(60.0 * k / 6e4, 0.4) << "," << 60.0 * k << "\n";
  }
  write("row.csv", 2e-3);
  write("row_no_joint.csv", 0.0);
  json c = {
      {"format", "gabion.case/1"},
      {"kind", "fit"},
      {"material", {{"name", "cell"}}},
      {"base_law", {{"file", (kCases / "data/fit/illustrative_law.json").string()}, {"material", "limestone_cell"}}},
      {"joint", {{"cell", {{"file", "cell.csv"}}}, {"row", {{"file", "row.csv"}}}, {"cells_in_series", 2}}}};
  std::ofstream(out / "case.json") << c.dump(2);
  const auto r = runGabion("run " + (out / "case.json").string() + " -q -o " + (out / "fit").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto law = bridge::loadLawFile(out / "fit" / "law.json");
  const auto& m = law.materials.at("cell");
  ASSERT_TRUE(m.joint.has_value());
  EXPECT_NEAR(m.joint->closure_at_1kN_m, 2e-3, 1e-3 * 2e-3);
  EXPECT_NEAR(m.joint->exponent, 0.6, 1e-3);
  EXPECT_EQ(m.joint_info.at("provenance").at("fitted_from").at(1).at("sha256").get<std::string>().size(), 64u);
  EXPECT_EQ(m.joint_info.at("force_range_N").at(1).get<double>(), 1.2e5);
  const auto& base = bridge::loadLawFile(kCases / "data/fit/illustrative_law.json").materials.at("limestone_cell");
  EXPECT_EQ(m.axial.stiffness_N_m, base.axial.stiffness_N_m) << "the other laws are the base law's";
  EXPECT_TRUE(fs::exists(out / "fit" / "fit_joint.png"));
  const json summary = json::parse(std::ifstream(out / "fit" / "summary.json"));
  EXPECT_GT(summary.at("fit").at("joint").at("r2_log_log").get<double>(), 0.999);
  EXPECT_NE(r.output.find("fit: joint"), std::string::npos) << r.output;

  c["joint"]["row"]["file"] = "row_no_joint.csv";
  std::ofstream(out / "bad.json") << c.dump(2);
  const auto bad = runGabion("run " + (out / "bad.json").string() + " -q -o " + (out / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("/joint"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("no joint"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace gabion::fitting
