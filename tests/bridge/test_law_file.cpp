// Law files: a written file reads back identically; invalid fields are named.
#include <gtest/gtest.h>

#include <fstream>

#include "bridge/errors.hpp"
#include "bridge/law_file.hpp"
#include "bridge/output.hpp"

using namespace gabion::bridge;

namespace {
LawFile sampleLaws() {
  LawFile laws;
  CellMaterial c;
  c.edge_m = 0.5;
  c.mass_kg = 183;
  c.axial = {AxialModel::ElasticPerfectlyPlastic, 2e6, 5e4, 0};
  c.lateral.reaction_coefficient = 0.4;
  c.interface = {0.6, 1e6};
  c.impact = {AxialModel::Bilinear, 3e6, 6e4, 1e5};
  c.provenance = {{"status", "illustrative"}, {"note", "test"}};
  laws.materials["front"] = c;
  return laws;
}
}  // namespace

TEST(LawFile, RoundTrip) {
  const std::string path = ::testing::TempDir() + "law_roundtrip.json";
  writeJsonAtomic(path, toJson(sampleLaws()));
  const LawFile back = loadLawFile(path);
  ASSERT_EQ(back.materials.count("front"), 1u);
  const auto& c = back.materials.at("front");
  EXPECT_DOUBLE_EQ(c.axial.stiffness_N_m, 2e6);
  EXPECT_EQ(c.impact.model, AxialModel::Bilinear);
  EXPECT_DOUBLE_EQ(c.impact.hardening_stiffness_N_m, 1e5);
  EXPECT_DOUBLE_EQ(c.interface.friction, 0.6);
  EXPECT_EQ(c.provenance.at("note"), "test");
}

TEST(LawFile, BadFieldsAreNamed) {
  auto j = toJson(sampleLaws());
  j["materials"]["front"]["axial"]["yield_force_N"] = -1;
  const std::string path = ::testing::TempDir() + "law_bad.json";
  writeJsonAtomic(path, j);
  try {
    loadLawFile(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.pointer(), "/materials/front/axial/yield_force_N");
    EXPECT_EQ(e.file(), path);
  }
  j = toJson(sampleLaws());
  j["materials"]["front"]["lateral"]["reaction_coef"] = 0.3;
  writeJsonAtomic(path, j);
  try {
    loadLawFile(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.pointer(), "/materials/front/lateral/reaction_coef");
  }
}
