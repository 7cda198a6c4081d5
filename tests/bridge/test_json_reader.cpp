// JSON reading: every error names the file and the JSON pointer; unknown keys
// are rejected; --set overrides reach nested values.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
#include <stdexcept>

#include "bridge/errors.hpp"
#include "bridge/json_reader.hpp"

using gabion::bridge::Check;
using gabion::bridge::InputError;
using gabion::bridge::JsonDocument;
using gabion::bridge::JsonReader;
using nlohmann::json;

namespace {

JsonDocument doc(const char* text) {
  return JsonDocument(json::parse(text), "case.json");
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(JsonReader, ReadsValuesAndNamesPointerOnError) {
  auto d = doc(R"({"spheres":[{"radius_m":0.1},{"radius_m":-2}]})");
  const auto spheres = d.root().objects("spheres", true);
  EXPECT_DOUBLE_EQ(spheres[0].number("radius_m", Check::Positive), 0.1);
  EXPECT_EQ(errorOf([&] { spheres[1].number("radius_m", Check::Positive); }),
            "case.json: /spheres/1/radius_m: must be > 0 (got -2)");
}

TEST(JsonReader, MissingAndWrongType) {
  auto d = doc(R"({"a":{"b":"x"}})");
  const auto a = d.root().object("a");
  EXPECT_EQ(errorOf([&] { a.number("c"); }), "case.json: /a/c: missing required key");
  EXPECT_EQ(errorOf([&] { a.number("b"); }), "case.json: /a/b: expected a number, got a string");
  EXPECT_EQ(errorOf([&] { a.vec3("b"); }), "case.json: /a/b: expected an array of 3 numbers");
}

TEST(JsonReader, UnknownKeyIsRejectedAfterReading) {
  auto d = doc(R"({"known":1,"nested":{"ok":true,"typo_m":3}})");
  d.root().number("known");
  d.root().object("nested").boolean("ok");
  EXPECT_EQ(errorOf([&] { d.finish(); }), "case.json: /nested/typo_m: unknown key 'typo_m'");
}

TEST(JsonReader, UnknownKeyInsideArrayOfObjectsAndRawSubtrees) {
  // Keys are tracked by the address of the value read: the same key name in
  // another array element is a different key.
  auto d = doc(R"({"list":[{"v":1},{"v":2,"w":3}],"free":{"any":{"thing":1}}})");
  for (const auto& r : d.root().objects("list")) r.number("v");
  d.root().raw("free");  // read as a whole: nothing inside is checked
  EXPECT_EQ(errorOf([&] { d.finish(); }), "case.json: /list/1/w: unknown key 'w'");
  d.root().objects("list")[1].number("w");
  EXPECT_NO_THROW(d.finish());
}

TEST(JsonReader, ReleaseFreesTheValue) {
  auto d = doc(R"({"x":2})");
  EXPECT_DOUBLE_EQ(d.root().number("x"), 2.0);
  d.finish();
  d.releaseValue();
  EXPECT_TRUE(d.json().is_null());
  EXPECT_EQ(d.file(), "case.json");
}

// A record lent the whole value (run.json) gets it without a copy, and the
// document has it back afterwards, also when the use throws; readers made
// before still read it (its nodes did not move).
TEST(JsonReader, ALentValueComesBack) {
  auto d = doc(R"({"spheres":[{"r":1},{"r":2}]})");
  const auto spheres = d.root().objects("spheres");
  const nlohmann::json* before = &d.json().at("spheres");
  nlohmann::json record = {{"format", "x"}};
  d.lendValue(record, "case", [&](const nlohmann::json& r) {
    EXPECT_EQ(r.at("case").at("spheres").size(), 2u);
    EXPECT_EQ(&r.at("case").at("spheres"), before);
    EXPECT_TRUE(d.json().is_null());
  });
  EXPECT_EQ(&d.json().at("spheres"), before);
  EXPECT_DOUBLE_EQ(spheres[1].number("r"), 2.0);
  EXPECT_THROW(d.lendValue(record, "case", [](const nlohmann::json&) { throw std::runtime_error("disk full"); }),
               std::runtime_error);
  EXPECT_EQ(d.json().at("spheres").size(), 2u);
  EXPECT_DOUBLE_EQ(spheres[0].number("r"), 1.0);
  EXPECT_NO_THROW(d.finish());
}

// One reader at a time over an array: the same values, the same pointers in
// errors as objects(); a finished document reads on (unrecorded) and
// finishes again without complaint.
TEST(JsonReader, ForEachObjectAndReadingAfterFinish) {
  auto d = doc(R"({"spheres":[{"r":1},{"r":2},{"r":-3}]})");
  EXPECT_EQ(d.root().arraySize("spheres"), 3u);
  EXPECT_EQ(d.root().arraySize("none"), 0u);
  double sum = 0.0;
  EXPECT_EQ(errorOf([&] {
              d.root().forEachObject("spheres", [&](const JsonReader& r) { sum += r.number("r", Check::Positive); });
            }),
            "case.json: /spheres/2/r: must be > 0 (got -3)");
  EXPECT_DOUBLE_EQ(sum, 3.0);
  EXPECT_NO_THROW(d.finish());
  auto bad = doc(R"({"spheres":[{"r":1}, 7]})");
  EXPECT_EQ(errorOf([&] { bad.root().forEachObject("spheres", [](const JsonReader&) {}); }),
            "case.json: /spheres/1: expected an object, got a number");
  // (after finish: reads go on, nothing recorded, finish passes again)
  EXPECT_DOUBLE_EQ(d.root().objects("spheres")[1].number("r"), 2.0);
  EXPECT_NO_THROW(d.finish());
}

TEST(JsonReader, DefaultsDoNotMarkAbsentKeys) {
  auto d = doc(R"({"x":2})");
  EXPECT_DOUBLE_EQ(d.root().number("y", 5.0), 5.0);
  EXPECT_DOUBLE_EQ(d.root().number("x", 5.0), 2.0);
  EXPECT_NO_THROW(d.finish());
}

TEST(JsonReader, ChoiceListsOptions) {
  auto d = doc(R"({"model":"quadratic"})");
  EXPECT_EQ(errorOf([&] {
              d.root().choice("model", {"linear", "bilinear"});
            }),
            "case.json: /model: 'quadratic' is not one of 'linear', 'bilinear'");
}

TEST(JsonReader, SetOverridesNestedValueAndArrayElement) {
  auto d = doc(R"({"boulder":{"velocity_m_s":10},"list":[{"v":1},{"v":2}]})");
  d.applySet("boulder.velocity_m_s=25");
  d.applySet("list.1.v=7.5");
  d.applySet("boulder.name=rock");
  EXPECT_DOUBLE_EQ(d.root().object("boulder").number("velocity_m_s"), 25.0);
  EXPECT_DOUBLE_EQ(d.root().objects("list")[1].number("v"), 7.5);
  EXPECT_EQ(d.root().object("boulder").string("name"), "rock");
  EXPECT_THROW(d.applySet("list.5.v=1"), InputError);
  EXPECT_THROW(d.applySet("novalue"), InputError);
  EXPECT_THROW(d.applySet("boulder.velocity_m_s.x=1"), InputError);  // (not an object)
  // An object the case lacks is made; if no reader takes it, it is unknown.
  EXPECT_NO_THROW(d.applySet("lacing.at_s=0.15"));
  EXPECT_DOUBLE_EQ(d.root().object("lacing").number("at_s"), 0.15);
  EXPECT_NO_THROW(d.applySet("lacng.at_s=0.15"));
  EXPECT_EQ(errorOf([&] { d.finish(); }), "case.json: /lacng: unknown key 'lacng'");
}

TEST(JsonReader, UnreadableAndInvalidFiles) {
  EXPECT_NE(
      errorOf([] { JsonDocument::load("/nonexistent/case.json"); }).find("/nonexistent/case.json: file does not exist"),
      std::string::npos);
  const std::string bad = ::testing::TempDir() + "bad.json";
  FILE* f = std::fopen(bad.c_str(), "w");
  std::fputs("{\"a\": 1,\n \"b\": }", f);
  std::fclose(f);
  const std::string msg = errorOf([&] { JsonDocument::load(bad); });
  EXPECT_NE(msg.find("invalid JSON"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
}

namespace {

std::string writeText(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  FILE* f = std::fopen(path.c_str(), "w");
  std::fputs(text.c_str(), f);
  std::fclose(f);
  return path;
}

}  // namespace

// A key given twice in one object is refused with its pointer (the last one
// would silently win), in a file and in a --set value; nesting deeper than
// 64 levels is refused before it can be written back recursively; a FIFO
// (which would block) is not read.
TEST(JsonReader, DuplicateKeysDeepNestingAndNonRegularFilesAreRefused) {
  const std::string dup = writeText("dup.json", R"({"run": {"a": 1, "b": [0, {"c": 1, "c": 2}]}})");
  EXPECT_EQ(errorOf([&] { JsonDocument::load(dup); }),
            dup + ": /run/b/1/c: duplicate key 'c' (each key once per object)");
  const std::string same_elsewhere = writeText("same.json", R"({"a": {"x": 1}, "b": {"x": 2}})");
  EXPECT_NO_THROW(JsonDocument::load(same_elsewhere));

  const std::string deep = writeText("deep.json", "{\"x\": " + std::string(200, '[') + std::string(200, ']') + "}");
  const std::string msg = errorOf([&] { JsonDocument::load(deep); });
  EXPECT_NE(msg.find("nested deeper than 64 levels"), std::string::npos) << msg;
  const std::string ok = writeText("deep_ok.json", "{\"x\": " + std::string(60, '[') + std::string(60, ']') + "}");
  EXPECT_NO_THROW(JsonDocument::load(ok));

  auto d = doc(R"({"a": 1})");
  EXPECT_EQ(errorOf([&] { d.applySet(R"(b={"k": 1, "k": 2})"); }),
            "case.json: --set 'b={\"k\": 1, \"k\": 2}': /k: duplicate key 'k' (each key once per object)");

  const std::string fifo = ::testing::TempDir() + "case_fifo.json";
  std::remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(errorOf([&] { JsonDocument::load(fifo); }), fifo + ": not a regular file");
  std::remove(fifo.c_str());
}

// Integers are checked in 64 bits before anything narrows them: a count
// past 2^31 - 1 is refused (it would wrap in an int), a seed may use 63
// bits, and a number beyond double is an input error.
TEST(JsonReader, IntegersAreRangeCheckedBeforeNarrowing) {
  auto d = doc(R"({"n": 4294967297, "m": 2147483647, "seed": 9223372036854775807, "big": 18446744073709551615})");
  EXPECT_EQ(errorOf([&] { d.root().integer("n", 1); }), "case.json: /n: must be <= 2147483647 (got 4294967297)");
  EXPECT_EQ(d.root().integer("m", 1), 2147483647);
  EXPECT_EQ(d.root().seed("seed", 1), 9223372036854775807ULL);
  EXPECT_EQ(errorOf([&] { d.root().seed("big", 1); }),
            "case.json: /big: must be <= 9223372036854775807 (got 18446744073709551615)");
  EXPECT_EQ(errorOf([&] { d.root().integer("big", 1); }),
            "case.json: /big: must be <= 2147483647 (got 18446744073709551615)");
  EXPECT_EQ(d.root().seed("absent", 7), 7u);
  const std::string huge = writeText("huge.json", R"({"x": 1e400})");
  EXPECT_NE(errorOf([&] { JsonDocument::load(huge); }).find("number overflow parsing '1e400'"), std::string::npos);
}
