// Random packings: no overlaps, inside the box with the gap, the target solid
// fraction reached, the same seed gives the same packing.
#include <gtest/gtest.h>

#include "micro/packing.hpp"

using gabion::micro::PackingSpec;
using gabion::micro::randomPacking;

TEST(Packing, NoOverlapInsideBoxTargetReachedDeterministic) {
  PackingSpec s;
  s.box_max_m = Eigen::Vector3d(0.3, 0.3, 0.6);
  s.mean_radius_m = 0.02;
  s.radius_std_rel = 0.15;
  s.solid_fraction = 0.25;
  s.min_gap_m = 0.001;
  s.seed = 7;
  const auto p = randomPacking(s);
  EXPECT_GE(p.solid_fraction, 0.25);
  EXPECT_LT(p.solid_fraction, 0.26);  // overshoots by at most one sphere
  for (std::size_t i = 0; i < p.radii_m.size(); ++i) {
    const double r = p.radii_m[i];
    for (int d = 0; d < 3; ++d) {
      EXPECT_GE(p.centers_m[i][d] - r, s.box_min_m[d] + s.min_gap_m - 1e-12);
      EXPECT_LE(p.centers_m[i][d] + r, s.box_max_m[d] - s.min_gap_m + 1e-12);
    }
    for (std::size_t j = 0; j < i; ++j)
      ASSERT_GE((p.centers_m[i] - p.centers_m[j]).norm(), r + p.radii_m[j] + s.min_gap_m - 1e-12);
  }
  const auto again = randomPacking(s);
  ASSERT_EQ(again.radii_m.size(), p.radii_m.size());
  EXPECT_EQ(again.centers_m.back(), p.centers_m.back());
}

TEST(Packing, ImpossibleSpecsThrow) {
  PackingSpec s;
  s.mean_radius_m = 0.3;  // larger than half the 0.5 m box
  EXPECT_THROW(randomPacking(s), std::invalid_argument);
  s.mean_radius_m = 0.02;
  s.solid_fraction = 0.6;  // beyond what random sequential addition reaches
  EXPECT_THROW(randomPacking(s), std::invalid_argument);
}
