// The resolved structure (docs/resolved.md): micro.structure lays out copies
// of a generated cell as a wall and strikes it; macro.resolved runs it beside
// its macro twin and compares them. A reduced case (2 x 1 x 1 small cells,
// a few thousand steps), as CI runs it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../support/run_gabion.hpp"
#include "../support/small_cell.hpp"
#include "bridge/output.hpp"

namespace {

using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::summaryOf;
using gabion::testing::writeFile;

const char* kStructure = R"({"format": "gabion.case/1", "kind": "micro.structure", "cell": "cell/cell.h5",
 "structure": {"cells": [2, 1, 1]}, "boulder": {"diameter_m": 0.25, "velocity_m_s": 8},
 "settle": {"duration_s": 0.01}, "run": {"duration_s": 0.03}})";

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
  // The boulder's momentum along x: m (v_end - v_0) = -(integral of the
  // structure's force on it) over the series (trapezoids at 0.1 ms; gravity
  // acts across x). The force is the one each sample read: the rule's error
  // is of the order of the change within a sample.
  {
    const gabion::bridge::H5Reader h(dir / "structure" / "result.h5");
    const auto t = h.read("/curves/impact/time_s"), f = h.read("/curves/impact/force_N"),
               v = h.read("/curves/impact/boulder_velocity_m_s");
    ASSERT_GT(t.size(), 10u);
    const double m = s["boulder_mass_kg"].get<double>();
    double impulse = 0.0;
    for (std::size_t k = 1; k < t.size(); ++k) impulse += 0.5 * (f[k] + f[k - 1]) * (t[k] - t[k - 1]);
    EXPECT_NEAR(m * (v.front() - v.back()), impulse, 0.03 * m * 8.0);
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
 "resolved": {"settle": {"duration_s": 0.01}, "run": {"duration_s": 0.03}}})");
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
  ASSERT_EQ(b["warnings"].size(), 1u);
  EXPECT_NE(b["warnings"][0].get<std::string>().find("not the same structure"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "both" / "resolved_vs_macro.png"));
}

}  // namespace
