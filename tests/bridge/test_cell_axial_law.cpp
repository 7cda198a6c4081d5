// The macro axial law against its closed form: elastic branch, yield plateau,
// elastic unloading from the plastic state, no tension, bilinear hardening.
#include <gtest/gtest.h>

#include "bridge/laws/cell_axial_law.hpp"

using namespace gabion::bridge;

TEST(CellAxialLaw, ElasticPerfectlyPlasticCycle) {
  const AxialLawParams p{AxialModel::ElasticPerfectlyPlastic, 1e6, 1e4, 0.0};
  double up = 0.0;
  auto r = axialResponse(p, 0.005, up);  // elastic
  EXPECT_DOUBLE_EQ(r.force_N, 5e3);
  r = axialResponse(p, 0.03, r.plastic_m);  // plateau: u_p = 0.03 - 0.01
  // the return mapping puts a perfectly plastic force exactly on F_y
  EXPECT_EQ(r.force_N, 1e4);
  EXPECT_DOUBLE_EQ(r.plastic_m, 0.02);
  EXPECT_DOUBLE_EQ(r.plastic_work_J, 1e4 * 0.02);
  up = r.plastic_m;
  // Unloading with k from u_p. u_p = u - F_y / k carries the rounding of u
  // (0.03 is not a binary fraction): k (u - u_p) is 5 kN to a few ulps.
  r = axialResponse(p, 0.025, up);
  EXPECT_NEAR(r.force_N, 5e3, 1e-14 * 5e3);
  EXPECT_EQ(r.plastic_work_J, 0.0);
  r = axialResponse(p, 0.015, up);  // below u_p: separated, no tension
  EXPECT_DOUBLE_EQ(r.force_N, 0.0);
  EXPECT_DOUBLE_EQ(r.plastic_m, 0.02);
}

TEST(CellAxialLaw, BilinearTangentAfterYield) {
  const AxialLawParams p{AxialModel::Bilinear, 1e6, 1e4, 2e5};
  // Monotonic loading in small steps must follow F = F_y + k_h (u - u_y).
  double up = 0.0;
  AxialResponse r;
  for (int i = 1; i <= 400; ++i) {
    r = axialResponse(p, 1e-4 * i, up);
    up = r.plastic_m;
  }
  const double u = 0.04, uy = 0.01;
  EXPECT_NEAR(r.force_N, 1e4 + 2e5 * (u - uy), 1e-6);
  // One big step gives the same state (return mapping is exact).
  const auto big = axialResponse(p, u, 0.0);
  EXPECT_NEAR(big.force_N, r.force_N, 1e-6);
  EXPECT_NEAR(big.plastic_m, r.plastic_m, 1e-12);
}
