// The contact laws of bridge/laws/contact_*.hpp against closed-form answers,
// called one by one and composed by micro::laneContact (the form the kernels
// run). tests/micro/test_law_equivalence.cpp checks that every path gives
// the same numbers.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "bridge/laws/contact_damping.hpp"
#include "bridge/laws/contact_normal.hpp"
#include "bridge/laws/contact_tangential.hpp"
#include "micro/contact.hpp"
#include "micro/material_laws.hpp"

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

// Two bodies meeting head-on along x through laneContact (normal spring and
// dashpot), leapfrog with the dashpot on the half-step velocity as in the
// engine: the restitution coefficient of the linear spring-dashpot,
// exp(-pi zeta / sqrt(1 - zeta^2)) (the dashpot acts, unclipped, until the
// overlap returns to zero), to the integrator's O(dt) error (1e-5 at
// 20,000 steps per half period).
class ContactRestitution : public ::testing::TestWithParam<double> {};

TEST_P(ContactRestitution, MatchesTheSpringDashpotSolution) {
  const double zeta = GetParam(), kn = 1e5, m1 = 0.02, m2 = 0.05, v0 = 0.5;
  const double inv_mass_sum = 1.0 / m1 + 1.0 / m2;
  const double omega = std::sqrt(kn * inv_mass_sum), dt = M_PI / omega / 20000.0;
  double x1 = 0.0, x2 = 1e-9, v1 = v0, v2 = 0.0;  // body 2 (j) is hit by body 1 (i); gap of 1 nm
  double ux = 0.0, uy = 0.0, uz = 0.0, plastic = 0.0, viscous = 0.0;
  bool touched = false;
  for (int step = 0; step < 200000; ++step) {
    const double overlap = x1 - x2;  // radii absorbed in the positions: contact when x1 > x2
    if (touched && overlap <= 0.0) break;
    double f = 0.0;
    if (overlap > 0.0) {
      touched = true;
      const auto c = micro::laneContact<false, true, false>(1, 0, 0, overlap, v2 - v1, 0, 0, kn, 1e4, 0.0, 0.0,
                                                            bridge::dashpotCoefficient({zeta}, kn, inv_mass_sum), dt,
                                                            ux, uy, uz, plastic, viscous);
      f = c.fx;  // force on i
    }
    v1 += dt * f / m1, v2 -= dt * f / m2;
    x1 += dt * v1, x2 += dt * v2;
  }
  ASSERT_TRUE(touched);
  const double analytic = std::exp(-M_PI * zeta / std::sqrt(1.0 - zeta * zeta));
  EXPECT_NEAR((v2 - v1) / v0, analytic, 1e-4) << "zeta " << zeta;
  // momentum is exchanged, not created
  EXPECT_NEAR(m1 * v1 + m2 * v2, m1 * v0, 1e-12 * m1 * v0);
}

INSTANTIATE_TEST_SUITE_P(Zeta, ContactRestitution, ::testing::Values(0.0, 0.1, 0.3, 0.6));

// Steady sliding through laneContact: the tangential force settles on the
// Coulomb limit f F_n along the slip, and each step dissipates f F_n times
// the slip of the step.
TEST(ContactTangentialLaw, SteadySlidingAtTheCoulombLimit) {
  const double kn = 1e5, ks = 2.5e4, f = 0.5, overlap = 4e-4, vt = 0.2, dt = 1e-5;
  const double fn = kn * overlap;
  double ux = 0.0, uy = 0.0, uz = 0.0, plastic = 0.0, viscous = 0.0;
  micro::LaneContact c{};
  for (int step = 0; step < 1000; ++step)  // 2 mm of slip: well past the spring's reach of 0.8 mm
    c = micro::laneContact<true, false, false>(0, 0, 1, overlap, vt, 0, 0, kn, ks, f / ks, 0.0, 0.0, dt, ux, uy, uz,
                                               plastic, viscous);
  EXPECT_NEAR(c.fx, f * fn, 1e-12 * f * fn);  // drags i along with the partner
  EXPECT_EQ(c.fy, 0.0);
  EXPECT_DOUBLE_EQ(c.fz, -fn);
  EXPECT_NEAR(c.friction_J, f * fn * vt * dt, 1e-12 * f * fn * vt * dt);
  EXPECT_NEAR(c.elastic_J, 0.5 * fn * fn / kn + 0.5 * (f * fn) * (f * fn) / ks, 1e-12 * c.elastic_J);
}

// The F_lim plateau through laneContact: while the overlap grows past
// F_lim / k_n the elastic force stays exactly F_lim and the plastic work is
// F_lim times the plastic overlap; unloading is elastic from delta_p.
TEST(ContactNormalLaw, ForceLimitPlateauThroughLaneContact) {
  const double kn = 1e5, flim = 40.0, dmax = 1e-3;
  double ux = 0.0, uy = 0.0, uz = 0.0, plastic = 0.0, viscous = 0.0, work = 0.0;
  for (int k = 1; k <= 1000; ++k) {
    const double d = dmax * k / 1000;
    const auto c = micro::laneContact<false, false, true>(0, 0, 1, d, 0, 0, 0, kn, 1e4, 0.0, flim, 0.0, 1e-5, ux, uy,
                                                          uz, plastic, viscous);
    work += c.plastic_J;
    if (kn * d > flim) {
      EXPECT_EQ(c.elastic_normal_N, flim) << d;
    } else {
      EXPECT_NEAR(c.elastic_normal_N, kn * d, 1e-12 * flim);
    }
  }
  EXPECT_NEAR(plastic, dmax - flim / kn, 1e-18);
  EXPECT_NEAR(work, flim * (dmax - flim / kn), 1e-12 * flim * dmax);
  const auto back = micro::laneContact<false, false, true>(0, 0, 1, plastic + 1e-4, 0, 0, 0, kn, 1e4, 0.0, flim, 0.0,
                                                           1e-5, ux, uy, uz, plastic, viscous);
  EXPECT_NEAR(back.elastic_normal_N, 10.0, 1e-9);
  EXPECT_EQ(back.plastic_J, 0.0);
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

// A contact pair replaces the values it gives for that pair only, in both
// orders; the rest of the table is the mixing rule's. Here: the rock caps
// its own contacts at 100 N, and its contacts with the netting are uncapped.
TEST(ContactMixing, AContactPairReplacesTheMixedValuesOfThatPairOnly) {
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<micro::Material> m = {{"rock", 2600, 1e6, 2.5e5, 0.5, 100.0, 0.1, 0.1},
                                          {"netting", 7850, 1e6, 2.5e5, 0.4, inf, 0.1, 0.0},
                                          {"plates", 7850, 1e6, 2.5e5, 0.0, inf, 0.0, 0.0}};
  micro::ContactPair p;
  p.a = 1, p.b = 0;
  p.normal_force_limit_N = inf;
  p.friction = 0.2;
  const auto mixed = micro::pairLawTable(m), table = micro::pairLawTable(m, {p});
  for (const std::size_t k : {std::size_t{1}, std::size_t{3}}) {  // (rock, netting) and (netting, rock)
    EXPECT_DOUBLE_EQ(mixed[k].normal.force_limit_N, 100.0);
    EXPECT_EQ(table[k].normal.force_limit_N, inf);
    EXPECT_DOUBLE_EQ(table[k].tangential.friction, 0.2);
    EXPECT_DOUBLE_EQ(table[k].normal.stiffness_N_m, mixed[k].normal.stiffness_N_m);
    EXPECT_DOUBLE_EQ(table[k].damping_ratio, mixed[k].damping_ratio);
  }
  for (std::size_t k = 0; k < table.size(); ++k) {
    if (k == 1 || k == 3) continue;
    EXPECT_EQ(table[k].normal.force_limit_N, mixed[k].normal.force_limit_N) << k;
    EXPECT_EQ(table[k].tangential.friction, mixed[k].tangential.friction) << k;
  }
  EXPECT_DOUBLE_EQ(table[0].normal.force_limit_N, 100.0);  // the rock with itself keeps its cap
  const micro::MaterialLaws laws(m, {p});
  EXPECT_EQ(laws.flim[1], inf);
  EXPECT_DOUBLE_EQ(laws.flim[0], 100.0);
}

}  // namespace
