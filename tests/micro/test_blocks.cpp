// Angular blocks and gradings: the cut lattice against its analytic mass
// properties, the cuts doing what they say, and generated gradings against
// their targets within the sampling bound the sampler states.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../support/run_gabion.hpp"
#include "bridge/output.hpp"
#include "micro/blocks/angular_block.hpp"
#include "micro/blocks/grading.hpp"
#include "micro/rigid_body.hpp"

namespace {

using namespace gabion::micro;
constexpr double kPi = 3.14159265358979323846;

TEST(AngularBlock, UncutLatticeFillsTheParallelepipedSymmetrically) {
  BlockShape shape;
  shape.cut = 0.0;
  const BlockGeometry g = angularBlock(shape, 0.1);
  EXPECT_NEAR(g.edges_m.x(), 0.14, 1e-15);
  EXPECT_NEAR(g.edges_m.y(), 0.10, 1e-15);
  EXPECT_NEAR(g.edges_m.z(), 0.07, 1e-15);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo, sum = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < g.centers_m.size(); ++k) {
    lo = lo.cwiseMin(g.centers_m[k] - Eigen::Vector3d::Constant(g.radii_m[k]));
    hi = hi.cwiseMax(g.centers_m[k] + Eigen::Vector3d::Constant(g.radii_m[k]));
    sum += g.centers_m[k];
  }
  // The spheres reach the faces of the parallelepiped exactly, centred on the origin.
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(hi[c], 0.5 * g.edges_m[c], 1e-12) << c;
    EXPECT_NEAR(lo[c], -0.5 * g.edges_m[c], 1e-12) << c;
  }
  EXPECT_LT(sum.norm(), 1e-12);
  // 6 along the long edge, spacing_ratio diameters apart: r = 0.14 / (2 + 2 ratio x 5).
  const double ratio = shape.spacing_ratio, r = 0.14 / (2.0 + 10.0 * ratio), spacing = 2.0 * r * ratio;
  EXPECT_NEAR(g.radii_m[0], r, 1e-15);
  const int ny = 1 + static_cast<int>(std::lround((0.10 - 2 * r) / spacing));
  const int nz = 1 + static_cast<int>(std::lround((0.07 - 2 * r) / spacing));
  EXPECT_EQ(g.centers_m.size(), static_cast<std::size_t>(6 * ny * nz));
}

TEST(AngularBlock, CutsRemoveEdgesAndCornersFirstAndMore) {
  BlockShape shape;
  std::size_t previous = 1000000;
  for (const double cut : {0.0, 0.3, 0.5, 0.6, 0.999}) {
    shape.cut = cut;
    const BlockGeometry g = angularBlock(shape, 0.1);
    ASSERT_FALSE(g.centers_m.empty()) << "cut " << cut;  // the innermost spheres always stay
    if (cut < 0.95) {
      EXPECT_LT(g.centers_m.size(), previous) << "cut " << cut;
    } else {
      EXPECT_LE(g.centers_m.size(), previous) << "cut " << cut;
    }  // deeper cuts, fewer spheres
    previous = g.centers_m.size();
    // Corners go first: no sphere sits at a corner of the lattice once cut.
    const Eigen::Vector3d half = 0.5 * g.edges_m - Eigen::Vector3d::Constant(g.radii_m[0]);
    for (const auto& x : g.centers_m) {
      const bool corner = (half - x.cwiseAbs()).cwiseAbs().maxCoeff() < 1e-12;
      if (cut > 0.0) {
        EXPECT_FALSE(corner);
      }
    }
    // The cut shape keeps the block's symmetry about its three planes.
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& x : g.centers_m) sum += x;
    EXPECT_LT(sum.norm(), 1e-12);
  }
}

// With the spheres side by side (spacing = diameter) they do not overlap, so
// the block's mass and inertia are the sums over its spheres: m = rho V per
// sphere and I = sum (2/5 m r^2 1 + m (|x|^2 1 - x x^T)).
TEST(AngularBlock, MassPropertiesOfACutLatticeAreTheAnalyticSums) {
  BlockShape shape;
  shape.spacing_ratio = 1.0;
  shape.cut = 0.6;
  const BlockGeometry g = angularBlock(shape, 0.12);
  const double rho = 2600.0;
  double mass = 0.0;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < g.centers_m.size(); ++k) {
    const double r = g.radii_m[k], m = rho * 4.0 / 3.0 * kPi * r * r * r;
    const Eigen::Vector3d& x = g.centers_m[k];
    mass += m;
    inertia += 0.4 * m * r * r * Eigen::Matrix3d::Identity() +
               m * (x.squaredNorm() * Eigen::Matrix3d::Identity() - x * x.transpose());
  }
  const MassProperties p = clusterMassProperties(g.centers_m, g.radii_m, rho, 1e-5);
  EXPECT_NEAR(p.mass_kg, mass, 1e-4 * mass);
  EXPECT_LT(p.center_m.norm(), 1e-4 * g.edges_m.x());
  EXPECT_LT((p.inertia_kg_m2 - inertia).norm(), 2e-4 * inertia.norm());
}

GradingTable paperLike() {
  // A gabion fill of 50 - 150 mm blocks (a grading in the manner of the paper's Fig. 5).
  return {{0.05, 0.063, 0.08, 0.1, 0.125, 0.15}, {0.0, 8.0, 25.0, 55.0, 85.0, 100.0}};
}

TEST(Grading, SampleMatchesItsTargetWithinTheStatedBoundAndRepeatsWithItsSeed) {
  const GradingTable g = paperLike();
  ASSERT_TRUE(checkGrading(g).message.empty());
  const auto mass_of = [](double d) { return 2600.0 * 0.45 * d * d * d; };  // a block of 0.45 d^3
  const double target = 183.0;                                              // kg: a 0.5 m cell at n = 0.436
  const std::vector<double> sizes = sampleGrading(g, target, mass_of, 7);
  std::vector<double> masses;
  double total = 0.0;
  for (const double d : sizes) masses.push_back(mass_of(d)), total += masses.back();
  EXPECT_NEAR(total, target, 0.5 * mass_of(0.15) * static_cast<double>(g.sieve_m.size() - 1));
  const std::vector<double> got = passingPercent(sizes, masses, g.sieve_m);
  // The sampler's bound (micro/blocks/grading.hpp): half the largest block of
  // each class, summed up to the sieve and over all.
  double H = 0.0;
  for (std::size_t k = 1; k < g.sieve_m.size(); ++k) H += 0.5 * mass_of(g.sieve_m[k]);
  double Hk = 0.0;
  for (std::size_t k = 0; k < g.sieve_m.size(); ++k) {
    if (k > 0) Hk += 0.5 * mass_of(g.sieve_m[k]);
    const double bound = 100.0 * (Hk + g.passing_percent[k] / 100.0 * H) / (target - H);
    EXPECT_NEAR(got[k], g.passing_percent[k], bound) << "sieve " << g.sieve_m[k];
  }
  EXPECT_LT(std::fabs(got[3] - g.passing_percent[3]), 2.0);  // and in fact within 2 points
  EXPECT_EQ(sampleGrading(g, target, mass_of, 7), sizes);
  EXPECT_NE(sampleGrading(g, target, mass_of, 8), sizes);
}

TEST(Grading, GaussianSizesHaveTheirMeanAndSpread) {
  const auto mass_of = [](double d) { return 2600.0 * 0.45 * d * d * d; };
  const std::vector<double> sizes = sampleGaussian(0.1, 0.02, 5000.0, mass_of, 3);
  ASSERT_GT(sizes.size(), 1000u);
  double mean = 0.0, var = 0.0;
  for (const double d : sizes) mean += d;
  mean /= static_cast<double>(sizes.size());
  for (const double d : sizes) var += (d - mean) * (d - mean);
  const double sd = std::sqrt(var / static_cast<double>(sizes.size() - 1));
  // Truncated at +-2.5 sd the spread is 0.96 of the parent's; the sample
  // mean is within 4 standard errors.
  EXPECT_NEAR(mean, 0.1, 4.0 * 0.02 / std::sqrt(static_cast<double>(sizes.size())));
  EXPECT_NEAR(sd, 0.96 * 0.02, 0.05 * 0.02);
  for (const double d : sizes) EXPECT_TRUE(d >= 0.05 - 1e-15 && d <= 0.15 + 1e-15);
}

TEST(Grading, BadTablesAreNamed) {
  GradingTable g = paperLike();
  g.sieve_m[2] = g.sieve_m[1];
  EXPECT_EQ(checkGrading(g).key, "sieve_m");
  EXPECT_EQ(checkGrading(g).at, 2);
  g = paperLike();
  g.passing_percent[3] = 20.0;
  EXPECT_EQ(checkGrading(g).key, "passing_percent");
  EXPECT_EQ(checkGrading(g).at, 3);
  g = paperLike();
  g.passing_percent[0] = 5.0;
  EXPECT_EQ(checkGrading(g).at, 0);
  g = paperLike();
  g.passing_percent.back() = 90.0;
  EXPECT_EQ(checkGrading(g).at, 5);
}

}  // namespace

namespace {

using gabion::testing::runGabion;
using gabion::testing::scratchDir;
using gabion::testing::writeFile;

std::string fillCase(const std::string& fill_extra, const std::string& grading) {
  return R"({"format": "gabion.case/1", "kind": "micro.scene", "gravity_m_s2": [0, 0, -9.81],
 "materials": {"limestone": {"density_kg_m3": 2600, "normal_stiffness_N_m": 1e6, "shear_stiffness_N_m": 2.5e5, "friction": 0.5}},
 "block_fills": [{"material": "limestone", "region": {"min_m": [0, 0, 0], "max_m": [0.3, 0.3, 0.6]},
                  "grading": )" +
         grading + R"(, "seed": 4)" + fill_extra + R"(}],
 "walls": [{"point_m": [0, 0, 0], "normal": [0, 0, 1], "material": "limestone"}],
 "run": {"duration_s": 0.002}})";
}
const std::string kGrading = R"({"sieve_m": [0.04, 0.06, 0.08], "passing_percent": [0, 40, 100]})";

// A fill in a scene: the summary reports what was made against the target,
// the same seed makes the same blocks, and bad fills are named.
TEST(BlockFill, SceneReportsTheGradingItMadeAndNamesBadFills) {
  const auto dir = scratchDir("block_fill");
  writeFile(dir / "fill.json", fillCase(R"(, "mass_kg": 8)", kGrading));
  for (const char* out : {"a", "b"}) {
    const auto r = runGabion("run " + (dir / "fill.json").string() + " -q -o " + (dir / out).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  std::ifstream in(dir / "a" / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  const nlohmann::json& f = s["block_fills"][0];
  EXPECT_EQ(f["blocks"], s["blocks"]);
  EXPECT_NEAR(f["mass_kg"].get<double>(), 8.0, 0.5);
  EXPECT_NEAR(f["passing_percent"][1].get<double>(), 40.0, 10.0);  // a handful of blocks: coarse
  EXPECT_EQ(f["passing_percent"][2], 100.0);
  EXPECT_GT(std::filesystem::file_size(dir / "a" / "grading_0.png"), 1000u);  // the figure beside the table
  const gabion::bridge::H5Reader a(dir / "a" / "result.h5"), b(dir / "b" / "result.h5");
  EXPECT_EQ(a.read("/bodies/position_m"), b.read("/bodies/position_m"));

  const auto bad = [&](const std::string& name, const std::string& text, const std::string& pointer) {
    writeFile(dir / (name + ".json"), text);
    const auto r = runGabion("check " + (dir / (name + ".json")).string());
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.output;
    EXPECT_NE(r.output.find(pointer), std::string::npos) << name << ": " << r.output;
  };
  bad("first_not_zero", fillCase(R"(, "mass_kg": 8)", R"({"sieve_m": [0.04, 0.08], "passing_percent": [10, 100]})"),
      "/block_fills/0/grading/passing_percent/0");
  bad("too_much", fillCase(R"(, "mass_kg": 500)", kGrading), "/block_fills/0/region");
  bad("both", fillCase(R"(, "mass_kg": 8, "solid_fraction": 0.5)", kGrading), "/block_fills/0");
  bad("cut", fillCase(R"(, "mass_kg": 8, "shape": {"cut": 1.2})", kGrading), "/block_fills/0/shape/cut");
}

}  // namespace
