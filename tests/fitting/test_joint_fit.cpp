// The joint law's identification (fitting/joint_fit.hpp): from a cell's
// confined compression and a row's, both made up here with a known joint.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>

#include "bridge/curve.hpp"
#include "bridge/laws/cell_joint_law.hpp"
#include "fitting/joint_fit.hpp"

namespace gabion::fitting {
namespace {

// A loading curve u(F) sampled densely in F (N) up to `top`, then an
// unloading back to a tenth of it (which the identification must not read).
bridge::Curve curveOf(double top, const std::function<double(double)>& u_of_F) {
  bridge::Curve c;
  constexpr int kPoints = 20000;
  for (int k = 0; k <= kPoints; ++k) {
    const double f = top * k / kPoints;
    c.x.push_back(u_of_F(f)), c.y.push_back(f);
  }
  const double u_top = c.x.back();
  for (int k = 1; k <= 100; ++k) c.x.push_back(u_top - 1e-4 * k), c.y.push_back(top * (1.0 - 0.009 * k));
  return c;
}

// The cell: u = 0.08 m (F / 60 kN)^0.4 (a convex curve, as a CC's).
double cellShortening(double f) {
  return 0.08 * std::pow(f / 6e4, 0.4);
}

TEST(JointFit, ShorteningAtForceReadsTheFirstLoading) {
  bridge::Curve c;
  c.x = {0.0, 1.0, 2.0, 3.0, 2.5, 4.0};
  c.y = {0.0, 10.0, 5.0, 20.0, 8.0, 30.0};  // (a dip after 1, an unloading after 3)
  EXPECT_DOUBLE_EQ(shorteningAtForce(c, 5.0), 0.5);
  EXPECT_DOUBLE_EQ(shorteningAtForce(c, 15.0), 2.0);  // (between (1, 10) and (3, 20), the envelope)
  EXPECT_DOUBLE_EQ(shorteningAtForce(c, 25.0), 3.5);
  EXPECT_TRUE(std::isnan(shorteningAtForce(c, 31.0)));
}

// A row of n cells whose n - 1 joints each close as c1 (F / 1 kN)^b: the
// fit finds c1 and b (to the interpolation of the sampled curves), at every
// level, with R2 1.
TEST(JointFit, FindsTheJointOfARowOfCells) {
  const bridge::JointLawParams joint{2e-3, 0.6};
  for (const int n : {2, 3}) {
    const bridge::Curve cell = curveOf(6e4, cellShortening);
    const bridge::Curve row =
        curveOf(6e4, [&](double f) { return n * cellShortening(f) + (n - 1) * bridge::jointClosure(joint, f); });
    const JointFit fit = fitJoint(cell, row, n);
    EXPECT_NEAR(fit.law.closure_at_1kN_m, joint.closure_at_1kN_m, 1e-4 * joint.closure_at_1kN_m) << n;
    EXPECT_NEAR(fit.law.exponent, joint.exponent, 1e-4) << n;
    EXPECT_EQ(fit.points, fit.force_N.size());
    EXPECT_GT(fit.r2, 0.9999);
    EXPECT_DOUBLE_EQ(fit.force_hi_N, 6e4);
    EXPECT_NEAR(fit.force_lo_N, 0.05 * 6e4, 1e-9);
  }
}

// The law and its inverse.
TEST(JointFit, TheLawsClosureAndForceAreInverse) {
  const bridge::JointLawParams j{1.5e-3, 0.614};
  for (const double f : {10.0, 1e3, 2e4, 6e4})
    EXPECT_NEAR(bridge::jointForce(j, bridge::jointClosure(j, f)), f, 1e-9 * f);
  EXPECT_DOUBLE_EQ(bridge::jointClosure(j, 1e3), 1.5e-3);
  EXPECT_EQ(bridge::jointClosure(j, -5.0), 0.0);
  EXPECT_EQ(bridge::jointForce(j, 0.0), 0.0);
}

// No joint (the row is exactly n cells) or a row given as the cell: refused,
// saying why.
TEST(JointFit, RefusesCurvesThatShowNoJoint) {
  const bridge::Curve cell = curveOf(6e4, cellShortening);
  const bridge::Curve row = curveOf(6e4, [](double f) { return 2.0 * cellShortening(f) - 1e-3; });
  try {
    fitJoint(cell, row, 2);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no joint"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fitJoint(cell, cell, 1), std::runtime_error);
}

}  // namespace
}  // namespace gabion::fitting
