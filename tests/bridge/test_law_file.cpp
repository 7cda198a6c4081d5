// Law files: a written file reads back identically; invalid fields are named.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <utility>
#include <vector>

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
  c.axial.lockup_shortening_m = 0.1;
  c.axial.lockup_stiffness_N_m = 3e7;
  c.lateral.reaction_coefficient = 0.4;
  c.interface = {0.6, 1e6};
  c.impact = {AxialModel::Densifying, 3e6, 6e4, 1e5, 0.04, 2e6, 0.12, 5e7};
  c.provenance = {{"status", "illustrative"}, {"note", "test"}};
  laws.materials["front"] = c;
  return laws;
}

// `j` written to `path` is refused, the error naming `pointer` (and, where
// given, its message saying `why`).
void expectRefused(const std::string& path, const nlohmann::json& j, const std::string& pointer,
                   const std::string& why = "") {
  writeJsonAtomic(path, j);
  try {
    loadLawFile(path);
    ADD_FAILURE() << "no error for " << pointer << " in " << j.dump();
  } catch (const InputError& e) {
    EXPECT_EQ(e.pointer(), pointer) << e.what();
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(LawFile, RoundTrip) {
  const std::string path = ::testing::TempDir() + "law_roundtrip.json";
  writeJsonAtomic(path, toJson(sampleLaws()));
  const LawFile back = loadLawFile(path);
  ASSERT_EQ(back.materials.count("front"), 1u);
  const auto& c = back.materials.at("front");
  EXPECT_DOUBLE_EQ(c.axial.stiffness_N_m, 2e6);
  EXPECT_DOUBLE_EQ(c.axial.lockup_shortening_m, 0.1);
  EXPECT_DOUBLE_EQ(c.axial.lockup_stiffness_N_m, 3e7);
  EXPECT_EQ(c.impact.model, AxialModel::Densifying);
  EXPECT_DOUBLE_EQ(c.impact.hardening_stiffness_N_m, 1e5);
  EXPECT_DOUBLE_EQ(c.impact.densification_onset_m, 0.04);
  EXPECT_DOUBLE_EQ(c.impact.densification_stiffness_N_m, 2e6);
  EXPECT_DOUBLE_EQ(c.impact.lockup_shortening_m, 0.12);
  EXPECT_EQ(back.version, 2);
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
  for (const auto& [key, value] :
       std::vector<std::pair<std::string, double>>{{"densification_onset_m", 0.13},  // at or past the lock-up
                                                   {"lockup_shortening_m", 0.5}}) {  // the whole cell edge
    j = toJson(sampleLaws());
    j["materials"]["front"]["impact"][key] = value;
    writeJsonAtomic(path, j);
    try {
      loadLawFile(path);
      FAIL() << key;
    } catch (const InputError& e) {
      EXPECT_EQ(e.pointer(), "/materials/front/impact/" + key);
    }
  }
}

// A file of the earlier version gabion.law/1 (no lock-up, no densifying
// model) is read: its laws get the documented default lock-up. Lock-up keys
// or the densifying model in a version-1 file are refused by name.
TEST(LawFile, Version1IsReadWithTheDefaultLockup) {
  auto j = toJson(sampleLaws());
  j["format"] = "gabion.law/1";
  auto& m = j["materials"]["front"];
  m["axial"].erase("lockup_shortening_m");
  m["axial"].erase("lockup_stiffness_N_m");
  m["impact"] = {
      {"model", "bilinear"}, {"stiffness_N_m", 3e6}, {"yield_force_N", 6e4}, {"hardening_stiffness_N_m", 1e5}};
  const std::string path = ::testing::TempDir() + "law_v1.json";
  writeJsonAtomic(path, j);
  const LawFile v1 = loadLawFile(path);
  EXPECT_EQ(v1.version, 1);
  const auto& c = v1.materials.at("front");
  EXPECT_DOUBLE_EQ(c.axial.lockup_shortening_m, kDefaultLockupStrain * 0.5);
  EXPECT_DOUBLE_EQ(c.axial.lockup_stiffness_N_m, kDefaultLockupStiffnessRatio * 2e6);
  EXPECT_DOUBLE_EQ(c.impact.lockup_stiffness_N_m, kDefaultLockupStiffnessRatio * 3e6);
  EXPECT_NEAR(lockupStrain(0.436, 0.25), 0.248, 1e-3);  // the default's origin

  m["axial"]["lockup_shortening_m"] = 0.1;
  writeJsonAtomic(path, j);
  try {
    loadLawFile(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.pointer(), "/materials/front/axial/lockup_shortening_m");
    EXPECT_NE(std::string(e.what()).find("gabion.law/2"), std::string::npos) << e.what();
  }
  m["axial"].erase("lockup_shortening_m");
  m["impact"]["model"] = "densifying";
  writeJsonAtomic(path, j);
  try {
    loadLawFile(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.pointer(), "/materials/front/impact/model");
  }
}

// The softening model: an impact law of that model reads back as written; in
// an axial law, with its keys on another model, or with a residual above the
// peak, it is refused by name.
TEST(LawFile, ASofteningImpactLawReadsBackAndIsRefusedElsewhere) {
  LawFile laws = sampleLaws();
  auto& imp = laws.materials.at("front").impact;
  imp = {AxialModel::Softening, 8e5, 8e4, 0.0};
  imp.softening_stiffness_N_m = 4e5;
  imp.residual_force_N = 1.2e4;
  imp.softening_onset_m = 0.03;
  imp.lockup_shortening_m = 0.25;
  imp.lockup_stiffness_N_m = 8e6;
  const std::string path = ::testing::TempDir() + "law_softening.json";
  writeJsonAtomic(path, toJson(laws));
  const LawFile read = loadLawFile(path);
  const auto& back = read.materials.at("front").impact;
  EXPECT_EQ(back.model, AxialModel::Softening);
  EXPECT_DOUBLE_EQ(back.softening_stiffness_N_m, 4e5);
  EXPECT_DOUBLE_EQ(back.residual_force_N, 1.2e4);
  EXPECT_DOUBLE_EQ(back.softening_onset_m, 0.03);
  EXPECT_DOUBLE_EQ(back.yield_force_N, 8e4);
  EXPECT_DOUBLE_EQ(back.lockup_shortening_m, 0.25);

  const auto refused = [&](const nlohmann::json& j, const std::string& pointer) { expectRefused(path, j, pointer); };
  auto j = toJson(laws);
  j["materials"]["front"]["axial"] = j["materials"]["front"]["impact"];
  refused(j, "/materials/front/axial/model");
  j = toJson(laws);
  j["materials"]["front"]["impact"]["residual_force_N"] = 9e4;
  refused(j, "/materials/front/impact/residual_force_N");
  j = toJson(sampleLaws());
  j["materials"]["front"]["impact"]["residual_force_N"] = 1e3;
  refused(j, "/materials/front/impact/residual_force_N");
}

// The impact law's rate term reads back; an axial law has no indentation
// rate and refuses it by name, and a negative coefficient is refused.
TEST(LawFile, TheImpactLawsRateTermReadsBackAndIsRefusedOnTheAxialLaw) {
  LawFile laws = sampleLaws();
  laws.materials.at("front").impact.rate_coefficient_N_s2_m2 = 650.0;
  laws.materials.at("front").impact.rate_growth_m = 0.06;
  const std::string path = ::testing::TempDir() + "law_rate.json";
  writeJsonAtomic(path, toJson(laws));
  const LawFile read = loadLawFile(path);
  EXPECT_DOUBLE_EQ(read.materials.at("front").impact.rate_coefficient_N_s2_m2, 650.0);
  EXPECT_DOUBLE_EQ(read.materials.at("front").impact.rate_growth_m, 0.06);
  EXPECT_EQ(read.materials.at("front").axial.rate_coefficient_N_s2_m2, 0.0);
  EXPECT_FALSE(toJson(sampleLaws())["materials"]["front"]["impact"].contains("rate_coefficient_N_s2_m2"));
  for (const std::string key : {"rate_coefficient_N_s2_m2", "rate_growth_m"})
    for (const auto& [law, value] : {std::pair<std::string, double>{"axial", 0.5}, {"impact", -1.0}}) {
      auto j = toJson(laws);
      j["materials"]["front"][law][key] = value;
      expectRefused(path, j, "/materials/front/" + law + "/" + key);
    }
}

// Plastic densification reads back on a densifying axial law; it is refused
// by name on the impact law, on another model, as an unknown word, and where
// the densification would start before first yield (the compaction is read
// from the plastic shortening: bridge/laws/cell_axial_law.hpp).
TEST(LawFile, PlasticDensificationReadsBackAndIsRefusedWhereItCannotHold) {
  LawFile laws = sampleLaws();
  auto& axial = laws.materials.at("front").axial;
  axial = {AxialModel::Densifying, 2e6, 5e4, 1e5, 0.04, 2e6, 0.1, 3e7};
  axial.plastic_densification = true;
  const std::string path = ::testing::TempDir() + "law_plastic_densification.json";
  writeJsonAtomic(path, toJson(laws));
  EXPECT_TRUE(loadLawFile(path).materials.at("front").axial.plastic_densification);
  EXPECT_EQ(toJson(laws)["materials"]["front"]["axial"]["densification"], "plastic");
  EXPECT_FALSE(toJson(sampleLaws())["materials"]["front"]["axial"].contains("densification"));
  const auto refusedAt = [&](const nlohmann::json& j, const std::string& pointer) { expectRefused(path, j, pointer); };
  auto j = toJson(laws);
  j["materials"]["front"]["impact"]["densification"] = "plastic";
  refusedAt(j, "/materials/front/impact/densification");
  j = toJson(laws);
  j["materials"]["front"]["axial"]["densification"] = "crushed";
  refusedAt(j, "/materials/front/axial/densification");
  j = toJson(laws);
  j["materials"]["front"]["axial"]["densification_onset_m"] = 0.01;  // first yield: 5e4 / 2e6 = 0.025 m
  refusedAt(j, "/materials/front/axial/densification");
  j = toJson(sampleLaws());
  j["materials"]["front"]["axial"]["densification"] = "plastic";  // (elastic_perfectly_plastic)
  refusedAt(j, "/materials/front/axial/densification");
}

// The axial law's viscosity reads back; the impact law has its rate term and
// refuses it by name, as a negative value is refused.
TEST(LawFile, AxialViscosityReadsBackAndIsRefusedOnTheImpactLaw) {
  LawFile laws = sampleLaws();
  laws.materials.at("front").axial.viscosity_N_s_m = 1.5e4;
  const std::string path = ::testing::TempDir() + "law_viscosity.json";
  writeJsonAtomic(path, toJson(laws));
  EXPECT_DOUBLE_EQ(loadLawFile(path).materials.at("front").axial.viscosity_N_s_m, 1.5e4);
  EXPECT_FALSE(toJson(sampleLaws())["materials"]["front"]["axial"].contains("viscosity_N_s_m"));
  for (const auto& [law, value] : {std::pair<std::string, double>{"impact", 1e4}, {"axial", -1.0}}) {
    auto j = toJson(laws);
    j["materials"]["front"][law]["viscosity_N_s_m"] = value;
    expectRefused(path, j, "/materials/front/" + law + "/viscosity_N_s_m");
  }
}

// The dense part's unloading stiffness reads back with plastic
// densification; without it, or below the densification stiffness, it is
// refused by name.
TEST(LawFile, TheDenseUnloadingStiffnessNeedsPlasticDensification) {
  LawFile laws = sampleLaws();
  auto& axial = laws.materials.at("front").axial;
  axial = {AxialModel::Densifying, 2e6, 5e4, 1e5, 0.04, 2e6, 0.1, 3e7};
  axial.plastic_densification = true;
  axial.densification_unloading_stiffness_N_m = 5e6;
  const std::string path = ::testing::TempDir() + "law_dense_unloading.json";
  writeJsonAtomic(path, toJson(laws));
  const LawFile read = loadLawFile(path);
  EXPECT_DOUBLE_EQ(read.materials.at("front").axial.densification_unloading_stiffness_N_m, 5e6);
  for (const auto& [edit, why] : {std::pair<std::string, std::string>{"elastic", "plastic"}, {"soft", "at least"}}) {
    auto j = toJson(laws);
    if (edit == "elastic") j["materials"]["front"]["axial"].erase("densification");
    if (edit == "soft") j["materials"]["front"]["axial"]["densification_unloading_stiffness_N_m"] = 1e6;
    expectRefused(path, j, "/materials/front/axial/densification_unloading_stiffness_N_m", why);
  }
}

// The axial momentum flux and its growth read back; on the impact law, as a
// negative number, or a growth without a flux, they are refused by name.
TEST(LawFile, AxialMomentumFluxReadsBackAndIsRefusedWhereItCannotHold) {
  LawFile laws = sampleLaws();
  laws.materials.at("front").axial.momentum_flux_kg_m = 1700.0;
  laws.materials.at("front").axial.momentum_flux_growth_m = 0.05;
  const std::string path = ::testing::TempDir() + "law_flux.json";
  writeJsonAtomic(path, toJson(laws));
  const LawFile file = loadLawFile(path);
  const auto& read = file.materials.at("front").axial;
  EXPECT_DOUBLE_EQ(read.momentum_flux_kg_m, 1700.0);
  EXPECT_DOUBLE_EQ(read.momentum_flux_growth_m, 0.05);
  EXPECT_FALSE(toJson(sampleLaws())["materials"]["front"]["axial"].contains("momentum_flux_kg_m"));
  struct Bad {
    std::string law, key;
    double value;
  };
  for (const Bad& b : {Bad{"impact", "momentum_flux_kg_m", 1000.0}, Bad{"impact", "momentum_flux_growth_m", 0.05},
                       Bad{"axial", "momentum_flux_kg_m", -1.0}, Bad{"axial", "momentum_flux_growth_m", -0.01}}) {
    auto j = toJson(laws);
    j["materials"]["front"][b.law][b.key] = b.value;
    expectRefused(path, j, "/materials/front/" + b.law + "/" + b.key);
  }
  auto j = toJson(laws);
  j["materials"]["front"]["axial"].erase("momentum_flux_kg_m");
  expectRefused(path, j, "/materials/front/axial/momentum_flux_growth_m", "needs momentum_flux_kg_m");
}

// The joint law (optional): reads back with its range and provenance, is
// absent where not given, and a bad value or model is named.
TEST(LawFile, TheJointLawReadsBackAndBadValuesAreNamed) {
  const std::string path = ::testing::TempDir() + "law_joint.json";
  LawFile laws = sampleLaws();
  writeJsonAtomic(path, toJson(laws));
  EXPECT_FALSE(loadLawFile(path).materials.at("front").joint.has_value());
  laws.materials["front"].joint = JointLawParams{1.5e-3, 0.61};
  laws.materials["front"].joint_info = {{"force_range_N", {3e3, 6e4}}, {"provenance", {{"from", "test"}}}};
  writeJsonAtomic(path, toJson(laws));
  const CellMaterial back = loadLawFile(path).materials.at("front");
  ASSERT_TRUE(back.joint.has_value());
  EXPECT_DOUBLE_EQ(back.joint->closure_at_1kN_m, 1.5e-3);
  EXPECT_DOUBLE_EQ(back.joint->exponent, 0.61);
  EXPECT_EQ(back.joint_info["force_range_N"], nlohmann::json({3e3, 6e4}));
  EXPECT_EQ(back.joint_info["provenance"]["from"], "test");
  nlohmann::json j = toJson(laws);
  j["materials"]["front"]["joint"]["exponent"] = -1;
  expectRefused(path, j, "/materials/front/joint/exponent");
  j = toJson(laws);
  j["materials"]["front"]["joint"]["model"] = "table";
  expectRefused(path, j, "/materials/front/joint/model");
  j = toJson(laws);
  j["materials"]["front"]["joint"]["closure"] = 1;
  expectRefused(path, j, "/materials/front/joint/closure");
}
