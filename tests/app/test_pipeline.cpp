// The calibration pipeline end to end on the default case (one boulder
// velocity to keep it short): every stage leaves its files, the law file it
// writes is valid and says what was fitted and what was carried over, the
// structure run with it balances energy, and bad input names the field.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "bridge/law_file.hpp"
#include "tests/support/run_gabion.hpp"

using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::writeFile;
namespace fs = std::filesystem;

namespace {
nlohmann::json readJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}
const std::string kCase = std::string(GABION_SOURCE_DIR) + "/cases/pipeline.json";
}  // namespace

TEST(Pipeline, DefaultCaseRunsEndToEnd) {
  const auto out = scratchDir("pipeline");
  const auto r = runGabion("run " + kCase + " -q -o " + out.string() + " --set structure.velocities_m_s=[15]");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"summary.json", "law.json", "report.md", "impact_force_time.png", "1_settle/result.h5",
                        "2_compression/result.h5", "3_curves/axial.csv", "3_curves/lateral.csv", "4_fit/law.json",
                        "4_fit/fit_axial.png", "5_impact_15_m_s/result.h5"})
    EXPECT_TRUE(fs::exists(out / f)) << f;

  const auto s = readJson(out / "summary.json");
  EXPECT_EQ(s.at("status"), "ok");
  // The CC scene names its walls; the curves are read by those names.
  const auto cc = readJson(out / "2_compression/case.json");
  std::vector<std::string> walls;
  for (const auto& w : cc.at("walls")) walls.push_back(w.at("name"));
  EXPECT_EQ(walls, (std::vector<std::string>{"z_minus", "x_minus", "x_plus", "y_minus", "y_plus", "lid"}));
  // A settled random packing of spheres in a box: looser than the densest
  // random packing (porosity 0.36) and denser than the loose cloud (0.75).
  const double porosity = s.at("cell").at("settled_porosity").get<double>();
  EXPECT_GT(porosity, 0.36);
  EXPECT_LT(porosity, 0.6);
  // The CC test loads the lateral walls: a positive reaction coefficient.
  const double K = s.at("fit").at("fit").at("lateral").at("parameters").at("reaction_coefficient").at("value");
  EXPECT_GT(K, 0.0);
  ASSERT_EQ(s.at("impacts").size(), 1u);
  EXPECT_LT(std::abs(s.at("impacts")[0].at("balance_rel_error").get<double>()), 5e-3);
  EXPECT_GT(s.at("impacts")[0].at("peak_force_N").get<double>(), 0.0);
  // 0.5 m limestone boulder (170 kg) at 15 m/s: E = m v^2 / 2 = 19.1 kJ (shared/reference).
  EXPECT_NEAR(s.at("impacts")[0].at("input_energy_J").get<double>(), 19.1e3, 0.2e3);

  // The law file: the calibrated material is replaced, the others carried;
  // it stays "illustrative" because interface and impact come from an
  // illustrative base law, and its provenance says which laws were fitted.
  const auto laws = gabion::bridge::loadLawFile(out / "law.json");
  ASSERT_EQ(laws.materials.count("front"), 1u);
  ASSERT_EQ(laws.materials.count("core"), 1u);
  const auto& front = laws.materials.at("front");
  EXPECT_EQ(front.provenance.at("status"), "illustrative");
  EXPECT_TRUE(front.provenance.at("fitted").contains("axial"));
  EXPECT_TRUE(front.provenance.at("fitted").contains("lateral"));
  EXPECT_DOUBLE_EQ(front.lateral.reaction_coefficient, K);
  EXPECT_EQ(laws.materials.at("core").provenance.at("status"), "illustrative");
}

TEST(Pipeline, BadInputNamesTheField) {
  const auto dir = scratchDir("pipeline_bad");
  auto j = readJson(kCase);
  j["structure"]["case"] = "no_such_case.json";
  writeFile(dir / "missing_structure.json", j.dump());
  auto r = runGabion("check " + (dir / "missing_structure.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no_such_case.json: file does not exist"), std::string::npos) << r.output;

  j = readJson(kCase);
  j["structure"]["case"] = std::string(GABION_SOURCE_DIR) + "/cases/wall_impact.json";
  j["compression"]["strain"] = -0.1;
  writeFile(dir / "bad_strain.json", j.dump());
  r = runGabion("run " + (dir / "bad_strain.json").string() + " -q -o " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/compression/strain: must be > 0"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}
