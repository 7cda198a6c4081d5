// The porosity measurement against closed forms: one sphere, a sphere cut by
// the box, two overlapping spheres (their lens counted once), and a block's
// member spheres against the block's own union volume.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../support/run_gabion.hpp"
#include "micro/blocks/angular_block.hpp"
#include "micro/cell/porosity.hpp"
#include "micro/rigid_body.hpp"

namespace {

using gabion::micro::solidFraction;
using V = Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;

double ball(double r) {
  return 4.0 / 3.0 * kPi * r * r * r;
}

TEST(Porosity, OneSphereAndASphereHalfOutsideTheBox) {
  const V lo(0, 0, 0), hi(0.2, 0.2, 0.2);
  const double r = 0.05, box = 0.008;
  // (h / r)^1.5 = (1 mm / 50 mm)^1.5 = 0.3 %: the count's error is within it.
  EXPECT_NEAR(solidFraction({V(0.1, 0.1, 0.1)}, {r}, lo, hi, 0.001) * box, ball(r), 0.003 * ball(r));
  // Centred on the face z = 0: half of it is in the box.
  EXPECT_NEAR(solidFraction({V(0.1, 0.1, 0.0)}, {r}, lo, hi, 0.001) * box, 0.5 * ball(r), 0.003 * ball(r));
  // Wholly outside: nothing.
  EXPECT_EQ(solidFraction({V(0.5, 0.1, 0.1)}, {r}, lo, hi, 0.001), 0.0);
}

TEST(Porosity, OverlapIsCountedOnce) {
  // Two spheres of radius r, centres d apart: union = 2 V - lens, with the
  // lens pi (4 r + d) (2 r - d)^2 / 12.
  const double r = 0.04, d = 0.05;
  const double lens = kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0, uni = 2.0 * ball(r) - lens;
  const V lo(0, 0, 0), hi(0.2, 0.15, 0.15);
  const double f = solidFraction({V(0.075, 0.075, 0.075), V(0.125, 0.075, 0.075)}, {r, r}, lo, hi, 0.0008);
  EXPECT_NEAR(f * 0.2 * 0.15 * 0.15, uni, 0.003 * uni);
  EXPECT_GT(2.0 * ball(r) - uni, 10.0 * 0.003 * uni);  // counting it twice would fail
}

TEST(Porosity, ABlockFillsItsUnionVolume) {
  // The member spheres of an angular block (overlapping: 0.75 diameters
  // apart) against the union volume the rigid-body code integrates.
  const gabion::micro::BlockGeometry g = gabion::micro::angularBlock({}, 0.1);
  const double v = gabion::micro::clusterMassProperties(g.centers_m, g.radii_m, 1.0, 1e-5).volume_m3;
  const V lo(-0.1, -0.1, -0.1), hi(0.1, 0.1, 0.1);
  const double f = solidFraction(g.centers_m, g.radii_m, lo, hi, 0.0005);
  EXPECT_NEAR(f * 0.008, v, 0.005 * v);
}

}  // namespace

namespace {

// The scene's `porosity` box: measured at the end of the run, reported in
// the summary; a measurement that would take billions of cells is refused.
TEST(Porosity, SceneReportsThePorosityOfItsBox) {
  const auto dir = gabion::testing::scratchDir("porosity_scene");
  const auto scene = [](const std::string& porosity) {
    return R"({"format": "gabion.case/1", "kind": "micro.scene", "gravity_m_s2": [0, 0, 0],
 "materials": {"rock": {"density_kg_m3": 2600, "normal_stiffness_N_m": 1e6, "shear_stiffness_N_m": 2.5e5, "friction": 0.5}},
 "spheres": [{"center_m": [0.1, 0.1, 0.1], "radius_m": 0.05, "material": "rock", "fixed": true}],
 "blocks": [{"material": "rock", "position_m": [0.1, 0.1, 0.3], "fixed": true,
             "spheres": [{"center_m": [0, 0, 0], "radius_m": 0.04}]}],
 "porosity": )" +
           porosity + R"(, "run": {"duration_s": 0.001}})";
  };
  const auto porosityOf = [&](const std::string& name, const std::string& box) {
    gabion::testing::writeFile(dir / (name + ".json"), scene(box));
    const auto r =
        gabion::testing::runGabion("run " + (dir / (name + ".json")).string() + " -q -o " + (dir / name).string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(dir / name / "summary.json");
    return nlohmann::json::parse(in)["porosity"].get<double>();
  };
  // The free sphere alone in the lower box; the block alone in the upper one,
  // or the whole column with the blocks only.
  EXPECT_NEAR(porosityOf("low", R"({"min_m": [0, 0, 0], "max_m": [0.2, 0.2, 0.2]})"), 1.0 - ball(0.05) / 0.008,
              0.003 * ball(0.05) / 0.008);
  EXPECT_NEAR(porosityOf("blocks", R"({"min_m": [0, 0, 0], "max_m": [0.2, 0.2, 0.4], "of": "blocks"})"),
              1.0 - ball(0.04) / 0.016, 0.004 * ball(0.04) / 0.016);
  gabion::testing::writeFile(dir / "fine.json",
                             scene(R"({"min_m": [0, 0, 0], "max_m": [2, 2, 2], "spacing_m": 1e-4})"));
  const auto bad = gabion::testing::runGabion("check " + (dir / "fine.json").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("/porosity/spacing_m"), std::string::npos) << bad.output;
}

}  // namespace
