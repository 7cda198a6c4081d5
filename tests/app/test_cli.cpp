// The command line's contract: version, exit code 2 with a message naming the
// file and the field for bad input, and nothing written for a rejected case.
#include <gtest/gtest.h>

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
