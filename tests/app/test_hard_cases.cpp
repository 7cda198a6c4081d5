// The hard cases (cases/hard/, docs/hard-cases.md), each run reduced as
// cases/hard/expected.json says, must end as it says: the exit code, the
// summary's values and bounds, the message. None may crash, hang, or end
// ok over numbers that cannot be trusted. The cases that strike a cell run
// on a small cell generated first (the micro_cell case, shortened as its
// smoke run is).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/run_gabion.hpp"

namespace {

namespace fs = std::filesystem;
using gabion::testing::runGabion;
using gabion::testing::scratchDir;

TEST(HardCases, EachEndsAsExpectedJsonSays) {
  const fs::path hard = fs::path(GABION_SOURCE_DIR) / "cases" / "hard";
  const auto expected = nlohmann::json::parse(std::ifstream(hard / "expected.json"));
  ASSERT_EQ(expected.at("format"), "gabion.hard_cases/1");
  const auto dir = scratchDir("hard_cases");
  std::string cell;  // generated on first need
  std::size_t cases = 0;
  for (const auto& entry : fs::directory_iterator(hard)) {
    const std::string name = entry.path().stem().string();
    if (entry.path().extension() != ".json" || name == "expected") continue;
    ++cases;
    ASSERT_TRUE(expected.at("cases").contains(name)) << name << ": not in expected.json";
    const auto& e = expected.at("cases").at(name);
    std::string args = "run " + entry.path().string() + " -q -o " + (dir / name).string();
    for (std::string set : e.at("reduced")) {
      const auto at = set.find("CELL");
      if (at != std::string::npos) {
        if (cell.empty()) {
          const auto made = runGabion("run " + std::string(GABION_SOURCE_DIR) + "/cases/micro_cell.json -q -o " +
                                      (dir / "cell").string() +
                                      " --set fill.max_duration_s=0.01 --set vibration.max_duration_s=0.005"
                                      " --set standing.max_duration_s=0.005");
          ASSERT_EQ(made.exit_code, 0) << made.output;
          cell = (dir / "cell" / "cell.h5").string();
        }
        set.replace(at, 4, cell);
      }
      args += " --set '" + set + "'";
    }
    const auto r = runGabion(args);
    EXPECT_EQ(r.exit_code, e.at("exit").get<int>()) << name << ": " << r.output;
    if (e.contains("message")) {
      EXPECT_NE(r.output.find(e.at("message").get<std::string>()), std::string::npos) << name << ": " << r.output;
    }
    std::ifstream in(dir / name / "summary.json");
    ASSERT_TRUE(in.good()) << name << ": no summary.json";
    const auto summary = nlohmann::json::parse(in);
    const nlohmann::json equal = e.value("equal", nlohmann::json::object());
    const nlohmann::json max_abs = e.value("max_abs", nlohmann::json::object());
    const nlohmann::json min = e.value("min", nlohmann::json::object());
    for (const auto& [pointer, bound] : min.items())
      EXPECT_GE(summary.at(nlohmann::json::json_pointer(pointer)).get<double>(), bound.get<double>())
          << name << " " << pointer;
    for (const auto& [pointer, value] : equal.items())
      EXPECT_EQ(summary.at(nlohmann::json::json_pointer(pointer)), value) << name << " " << pointer;
    for (const auto& [pointer, bound] : max_abs.items()) {
      const auto& v = summary.at(nlohmann::json::json_pointer(pointer));
      ASSERT_TRUE(v.is_number()) << name << " " << pointer << " = " << v;
      EXPECT_LE(std::fabs(v.get<double>()), bound.get<double>()) << name << " " << pointer;
    }
    // Whatever the end, no summary says ok over numbers that are not numbers.
    if (summary.value("status", "") == "ok") {
      EXPECT_EQ(summary.dump().find("null"), std::string::npos) << name << ": a null in an ok summary";
    }
  }
  EXPECT_EQ(cases, expected.at("cases").size()) << "a case of expected.json has no file";
}

}  // namespace
