// The macro model's links use the one elastic-plastic return mapping of
// bridge/laws/elastic_plastic.hpp (the same as the fine DEM's F_lim cap): at
// every step of an impact, the force and plastic memory of each axial,
// boulder-face, lateral and ground link equal the bridge function evaluated
// on that link's compression and previous plastic state (bridge::axialSpring
// of the link's law parameters), and the model's plastic and elastic energy
// equal the sums of the bridge's plastic work and stored energy. Tolerance
// 1e-14 relative; the floor for a value near zero (a force k (u - u_p) or a
// plastic part u - F/k after cancellation) is 1e-14 of the terms it is the
// difference of, k |u| and |u|.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bridge/laws/elastic_plastic.hpp"
#include "macro/model.hpp"
#include "macro_test_util.hpp"

using namespace gabion;
using namespace gabion::macro;
using namespace gabion::macro::testing;

namespace {

struct Tally {
  int compared = 0, equal = 0;
};

void expectClose(double model, double bridge, double scale, const std::string& what, Tally& t) {
  ++t.compared;
  if (model == bridge) {
    ++t.equal;
    return;
  }
  const double tol = 1e-14 * std::max({std::fabs(model), std::fabs(bridge), scale});
  EXPECT_LE(std::fabs(model - bridge), tol) << what << ": model " << model << ", bridge " << bridge;
}

// The law of a link, from the law parameters (not the model's own table).
bridge::ElasticPlasticParams spring(const Structure& s, int law) {
  return bridge::axialSpring(s.axial_laws[static_cast<std::size_t>(law)]);
}

// One link: the model's force and plastic part against the bridge function;
// returns the bridge's response so that the caller can sum the energies.
bridge::ElasticPlasticResponse expectLink(const bridge::ElasticPlasticParams& p, double u, double plastic_before,
                                          double force, double plastic_after, const std::string& what, Tally& t,
                                          int& flows) {
  const auto r = bridge::elasticPlasticResponse(p, u, plastic_before);
  expectClose(force, r.force_N, p.stiffness_N_m * std::max(std::fabs(u), std::fabs(plastic_before)), what + " force",
              t);
  expectClose(plastic_after, r.plastic_m, std::max(std::fabs(u), std::fabs(plastic_before)), what + " plastic", t);
  flows += r.plastic_work_J > 0.0;
  return r;
}

class MacroLawEquivalence : public ::testing::TestWithParam<bool> {};

// x-only, no friction: the axial links and the boulder face, and the energies.
TEST_P(MacroLawEquivalence, AxialAndImpactLinksAndEnergies) {
  const bool bilinear = GetParam();
  bridge::AxialLawParams axial = epp(1e7, 2e4), impact = epp(2e7, 2e5);
  if (bilinear) {
    axial = {bridge::AxialModel::Bilinear, 1e7, 2e4, 3e6};
    impact = {bridge::AxialModel::Bilinear, 2e7, 2e5, 5e6};
  }
  const Structure s = buildStructure(grid(3, 1, 1), oneMaterial(axial, impact, 183.0, 0.4, 0.0));
  Model model(s, Kinematics::XOnly);
  model.placeBoulder(boulderAt(s, 0, 0, 170.0, 20.0));
  const double dt = 0.1 * model.criticalTimeStep();
  Tally t;
  int axial_flows = 0, front_flows = 0, front_contacts = 0;
  double plastic_sum = 0.0;
  for (int step = 0; step < 2000; ++step) {
    const std::vector<double> ux = model.ux(), axial_up = model.axialPlastic(), front_up = model.frontPlastic();
    ASSERT_EQ(model.step(dt), StepStatus::Ok) << model.failure();
    const std::string at = "step " + std::to_string(step);
    double plastic = 0.0, elastic = 0.0;
    for (std::size_t l = 0; l < s.axial.a.size(); ++l) {
      const int b = s.axial.b[l];
      const double u = ux[static_cast<std::size_t>(s.axial.a[l])] - (b >= 0 ? ux[static_cast<std::size_t>(b)] : 0.0);
      const auto p = spring(s, s.axial.law[l]);
      const auto r = expectLink(p, u, axial_up[l], model.axialForce()[l], model.axialPlastic()[l],
                                at + ", axial link " + std::to_string(l), t, axial_flows);
      plastic += r.plastic_work_J;
      elastic += bridge::elasticPlasticEnergy(p, r.force_N);
    }
    const double axial_plastic = plastic;
    plastic = 0.0;
    // The boulder on the single front element, head-on: the indentation is
    // the model's, the force on the boulder -F along x.
    if (model.contacts() == 1) {
      ++front_contacts;
      const auto p = spring(s, s.front.law[0]);
      const auto r = expectLink(p, model.indentation(), front_up[0], -model.boulderForce().x(), model.frontPlastic()[0],
                                at + ", boulder face", t, front_flows);
      plastic += r.plastic_work_J;
      elastic += bridge::elasticPlasticEnergy(p, r.force_N);
    } else {
      EXPECT_EQ(model.frontPlastic()[0], front_up[0]) << at;
    }
    // The model sums the stage's plastic work, then adds it (axial stage, then
    // the boulder stage); the same order here.
    plastic_sum += axial_plastic;
    plastic_sum += plastic;
    expectClose(model.energy().plastic_J, plastic_sum, 0.0, at + ", plastic energy", t);
    expectClose(model.energy().elastic_J, elastic, 0.0, at + ", elastic energy", t);
  }
  EXPECT_GT(axial_flows, 0);
  EXPECT_GT(front_flows, 0);
  EXPECT_GT(front_contacts, 10);
  EXPECT_GT(t.equal, 0);
  std::printf("%d values compared, %d exactly equal\n", t.compared, t.equal);
}

// 3-D: the boulder strikes the top side edge of a front cell, so that it
// pushes the cell sideways and down: the lateral links' normal springs and the
// ground links' springs against sinking yield (and the axial links).
TEST_P(MacroLawEquivalence, LateralAndGroundLinks3d) {
  const bool bilinear = GetParam();
  bridge::AxialLawParams axial = epp(1e7, 1e4);
  if (bilinear) axial = {bridge::AxialModel::Bilinear, 1e7, 1e4, 3e6};
  StructureSpec spec = grid(2, 2, 2);
  spec.support.ground_friction = true;
  const Structure s = buildStructure(spec, oneMaterial(axial, epp(2e7, 1e12), 183.0));
  Model model(s, Kinematics::ThreeD);
  BoulderSpec b = boulderAt(s, 0, 1, 170.0, 20.0);
  b.aim_y_m = -0.1;  // beside the cube (y < 0) and above it (z > 1 m): its edge is struck
  b.aim_z_m = 2 * s.edge_m + 0.1;
  model.placeBoulder(b);
  const double dt = 0.1 * model.criticalTimeStep();
  Tally t;
  int axial_flows = 0, lateral_flows = 0, ground_flows = 0;
  for (int step = 0; step < 3000; ++step) {
    const std::vector<double> ux = model.ux(), uy = model.uy(), uz = model.uz();
    const std::vector<double> axial_up = model.axialPlastic(), lat_up = model.lateralPlastic(),
                              gnd_up = model.groundPlastic();
    ASSERT_EQ(model.step(dt), StepStatus::Ok) << model.failure();
    const std::string at = "step " + std::to_string(step);
    for (std::size_t l = 0; l < s.axial.a.size(); ++l) {
      const int bn = s.axial.b[l];
      const double u = ux[static_cast<std::size_t>(s.axial.a[l])] - (bn >= 0 ? ux[static_cast<std::size_t>(bn)] : 0.0);
      expectLink(spring(s, s.axial.law[l]), u, axial_up[l], model.axialForce()[l], model.axialPlastic()[l],
                 at + ", axial link " + std::to_string(l), t, axial_flows);
    }
    for (std::size_t l = 0; l < s.lateral.a.size(); ++l) {
      const auto& un = s.lateral.dir[l] == 1 ? uy : uz;
      const double u = un[static_cast<std::size_t>(s.lateral.a[l])] - un[static_cast<std::size_t>(s.lateral.b[l])];
      expectLink(spring(s, s.lateral.law[l]), u, lat_up[l], model.lateralForce()[l], model.lateralPlastic()[l],
                 at + ", lateral link " + std::to_string(l), t, lateral_flows);
    }
    for (std::size_t l = 0; l < s.ground.node.size(); ++l) {
      const double u = -uz[static_cast<std::size_t>(s.ground.node[l])];
      expectLink(spring(s, s.ground.law[l]), u, gnd_up[l], model.groundForce()[l], model.groundPlastic()[l],
                 at + ", ground link " + std::to_string(l), t, ground_flows);
    }
  }
  EXPECT_GT(axial_flows, 0);
  EXPECT_GT(lateral_flows, 0);
  EXPECT_GT(ground_flows, 0);
  std::printf("%d values compared, %d exactly equal\n", t.compared, t.equal);
}

INSTANTIATE_TEST_SUITE_P(Laws, MacroLawEquivalence, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return i.param ? std::string("Bilinear") : std::string("ElasticPerfectlyPlastic");
                         });

}  // namespace
