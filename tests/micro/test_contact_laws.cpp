// The contact laws of bridge/laws/contact_*.hpp against closed-form answers.
#include <gtest/gtest.h>

#include <cmath>

#include "bridge/laws/contact_damping.hpp"
#include "bridge/laws/contact_normal.hpp"
#include "bridge/laws/contact_tangential.hpp"
#include "micro/contact.hpp"

namespace {

using namespace gabion;

// F_lim cycle (Bertrand et al. 2006, elastic - perfectly plastic normal law):
// load in small increments to delta_max > F_lim / k, unload to zero force.
// The plastic work is F_lim (delta_max - F_lim / k), the permanent overlap
// delta_max - F_lim / k, and the work put in equals plastic work (nothing
// stays elastic after unloading).
TEST(ContactNormalLaw, ForceLimitCycleDissipatesAnalyticPlasticWork) {
  const bridge::NormalContactParams p{1e5, 50.0};
  const double dmax = 2e-3, steps = 20000;
  double plastic = 0.0, work = 0.0, dissipated = 0.0, f_prev = 0.0, d_prev = 0.0;
  const auto go = [&](double d) {
    const auto r = bridge::normalContactForce(p, d, plastic);
    plastic = r.plastic_m;
    dissipated += r.plastic_work_J;
    work += 0.5 * (f_prev + r.force_N) * (d - d_prev);  // trapezoid of the force-overlap curve
    f_prev = r.force_N;
    d_prev = d;
  };
  for (int k = 1; k <= steps; ++k) go(dmax * k / steps);
  EXPECT_DOUBLE_EQ(f_prev, 50.0);
  for (int k = static_cast<int>(steps) - 1; k >= 0; --k) go(dmax * k / steps);
  const double analytic = 50.0 * (dmax - 50.0 / 1e5);
  EXPECT_NEAR(plastic, dmax - 50.0 / 1e5, 1e-15);
  EXPECT_NEAR(dissipated, analytic, 1e-12 * analytic);
  // The trapezoid rule is exact except in the step where the cap is reached.
  EXPECT_NEAR(work, analytic, 1e-4 * analytic);
  EXPECT_EQ(f_prev, 0.0);
  // Reloading is elastic from the plastic overlap on.
  EXPECT_NEAR(bridge::normalContactForce(p, plastic + 1e-4, plastic).force_N, 10.0, 1e-9);
}

TEST(ContactNormalLaw, NoForceLimitIsLinear) {
  const bridge::NormalContactParams p{2e5};
  const auto r = bridge::normalContactForce(p, 1e-3, 0.0);
  EXPECT_DOUBLE_EQ(r.force_N, 200.0);
  EXPECT_EQ(r.plastic_work_J, 0.0);
  EXPECT_EQ(bridge::normalContactForce(p, -1e-3, 0.0).force_N, 0.0);
}

// Shear spring: elastic below the Coulomb limit; sliding dissipates the
// released spring energy; the history keeps its length when rotated.
TEST(ContactTangentialLaw, CoulombLimitAndDissipation) {
  const auto p = bridge::shearSpring({1e4, 0.5});
  const auto stick = bridge::coulombShearUpdate(p, 100.0, {0, 0, 0}, {1e-3, 0, 0});
  EXPECT_EQ(stick.friction_work_J, 0.0);  // |F| = 10 N < 50 N
  EXPECT_DOUBLE_EQ(stick.u.x, 1e-3);
  const auto slide = bridge::coulombShearUpdate(p, 100.0, stick.u, {9e-3, 0, 0});  // trial 100 N > 50 N
  EXPECT_NEAR(slide.u.x * p.stiffness_N_m, 50.0, 1e-12);
  // work k_s (u_old + u_new) du / 2 = 1e4 (1e-3 + 5e-3) 9e-3 / 2 = 0.27 J, less
  // the stored change k_s (5e-3^2 - 1e-3^2) / 2 = 0.12 J
  EXPECT_NEAR(slide.friction_work_J, 0.15, 1e-12);
  const auto w = bridge::rotateShearIntoPlane({3e-3, 0, 4e-3}, {0, 0, 1});
  EXPECT_NEAR(w.x, 5e-3, 1e-15);
  EXPECT_NEAR(w.z, 0.0, 1e-18);
}

TEST(ContactLocalDamping, ReducesForceAgainstVelocity) {
  const bridge::LocalDampingParams p{0.2};
  EXPECT_DOUBLE_EQ(bridge::locallyDampedForce(p, 10.0, 1.0), 8.0);
  EXPECT_DOUBLE_EQ(bridge::locallyDampedForce(p, 10.0, -1.0), 12.0);
  EXPECT_DOUBLE_EQ(bridge::locallyDampedForce(p, -10.0, 1.0), -12.0);
  EXPECT_DOUBLE_EQ(bridge::locallyDampedForce(p, 10.0, 0.0), 10.0);
}

// Mixing rule: a material with itself keeps its values; two materials give
// series stiffness, the smaller friction and force cap, the mean damping ratio.
TEST(ContactMixing, SeriesStiffnessMinFrictionMeanDamping) {
  micro::Material a{"a", 2500, 1e5, 4e4, 0.5, 100.0, 0.0, 0.2};
  micro::Material b{"b", 2500, 3e5, 4e4, 0.3, std::numeric_limits<double>::infinity(), 0.0, 0.4};
  const auto aa = micro::mixMaterials(a, a);
  EXPECT_DOUBLE_EQ(aa.normal.stiffness_N_m, 1e5);
  EXPECT_DOUBLE_EQ(aa.tangential.stiffness_N_m, 4e4);
  const auto ab = micro::mixMaterials(a, b);
  EXPECT_DOUBLE_EQ(ab.normal.stiffness_N_m, 1.5e5);
  EXPECT_DOUBLE_EQ(ab.tangential.friction, 0.3);
  EXPECT_DOUBLE_EQ(ab.normal.force_limit_N, 100.0);
  EXPECT_DOUBLE_EQ(ab.damping_ratio, 0.3);
}

}  // namespace
