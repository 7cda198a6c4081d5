// The macro cell law and the fine DEM's F_lim cap are one return mapping
// (bridge/laws/elastic_plastic.hpp): the elastic-perfectly-plastic cell law
// (bridge::axialResponse, the general path with its hardening terms, H = 0)
// and the contact's normal spring (bridge::normalContactForce, the path with
// the hardening terms dropped at compile time) give the same force, plastic
// part and plastic work, exactly, for a table of compressions below, at and
// above the yield force, loading from a plastic state, unloading and
// separated (no tension).
#include <gtest/gtest.h>

#include "bridge/laws/cell_axial_law.hpp"
#include "bridge/laws/contact_normal.hpp"

using namespace gabion::bridge;

TEST(ElasticPlasticEquivalence, PerfectlyPlasticCellLawIsTheContactCap) {
  const double k = 1e5, fy = 40.0, uy = fy / k;
  const AxialLawParams cell{AxialModel::ElasticPerfectlyPlastic, k, fy, 0.0};
  const NormalContactParams contact{k, fy};
  const double plastic_states[] = {0.0, 3e-4, 1.7e-3};
  const double stretches[] = {-1e-4, 0.0, 0.25, 0.5, 1.0, 1.0 + 1e-12, 1.5, 3.0, 40.0};  // (u - u_p) / (F_y / k)
  int flows = 0, separated = 0;
  for (const double up : plastic_states)
    for (const double s : stretches) {
      const double u = up + s * uy;
      const auto a = axialResponse(cell, u, up);
      const auto c = normalContactForce(contact, u, up);
      EXPECT_EQ(a.force_N, c.force_N) << "u " << u << ", u_p " << up;
      EXPECT_EQ(a.plastic_m, c.plastic_m) << "u " << u << ", u_p " << up;
      EXPECT_EQ(a.plastic_work_J, c.plastic_work_J) << "u " << u << ", u_p " << up;
      EXPECT_EQ(elasticPlasticEnergy(axialSpring(cell), a.force_N), normalElasticEnergy(contact, c.force_N));
      flows += c.plastic_work_J > 0.0;
      separated += c.force_N == 0.0;
    }
  EXPECT_GT(flows, 0);
  EXPECT_GT(separated, 0);
}

// With hardening the yield force grows as F_y + H u_p: after a plastic step
// the force lies on that line, and the plastic work is the yield force
// integrated over the plastic increment (trapezoid, exact for a linear line).
TEST(ElasticPlasticEquivalence, HardeningReturnLandsOnTheYieldLine) {
  const ElasticPlasticParams p = hardeningSpring(1e7, 5e4, 3e6);
  EXPECT_NEAR(p.tangent_ratio, 0.3, 1e-15);
  EXPECT_NEAR(p.hardening_N_m, 1e7 * 3e6 / 7e6, 1e-6);
  const double up = 2e-3, u = 0.02;
  const auto r = elasticPlasticResponse(p, u, up);
  EXPECT_NEAR(r.force_N, p.yield_force_N + p.hardening_N_m * r.plastic_m, 1e-12 * r.force_N);
  EXPECT_NEAR(r.force_N, p.stiffness_N_m * (u - r.plastic_m), 1e-9 * r.force_N);
  const double y0 = p.yield_force_N + p.hardening_N_m * up;
  EXPECT_NEAR(r.plastic_work_J, 0.5 * (y0 + r.force_N) * (r.plastic_m - up), 1e-12 * r.plastic_work_J);
}
