// The wire law of the netting (bridge/laws/wire.hpp) against its definition:
// the published table, elastic unloading and reloading from the plastic
// strain, slack in compression, rupture after the last point, the plastic
// work as a state function, and the double-twist rule.
#include <gtest/gtest.h>

#include <cmath>

#include "bridge/laws/wire.hpp"

using namespace gabion::bridge;

namespace {
constexpr double kD = 0.0027;               // mesh wire (m)
const double kL0 = 0.080 / std::sqrt(3.0);  // 46.19 mm link
double strainToLength(double eps) {
  return kL0 * (1.0 + eps);
}
}  // namespace

TEST(WireLaw, ElasticStiffnessOfTheReferenceLink) {
  // ../shared/reference/wire-netting.md: EA / l0 = 16.115e6 N/m (E = 130 GPa).
  const WireCurve c = wireCurve(defaultWireTable(), kD);
  EXPECT_NEAR(c.elasticForce() / kL0, 16.115e6, 0.001e6);
  WireState s;
  const WireResponse r = wireResponse(c, kL0, s, kL0 + 1e-6);
  EXPECT_NEAR(r.force_N / 1e-6, c.elasticForce() / kL0, 1e-6 * c.elasticForce() / kL0);
}

TEST(WireLaw, LoadUnloadReloadRuptureCycleFollowsTheTableAndTheUnloadingRule) {
  const WireStressStrain t = defaultWireTable();
  const WireCurve c = wireCurve(t, kD);
  const double A = wireSection(kD), E = t.stress_Pa[0] / t.strain[0] * A;
  WireState s;
  // Loading through the table points: the force is the table's, exactly.
  for (std::size_t k = 0; k <= 3; ++k) {  // up to 15 % strain, on the backbone
    const WireResponse r = wireResponse(c, kL0, s, strainToLength(t.strain[k]));
    EXPECT_NEAR(r.force_N, t.stress_Pa[k] * A, 1e-9 * t.stress_Pa[k] * A) << "point " << k;
  }
  // Between points: linear interpolation of the table (10 % lies between 5 and 15 %).
  WireState mid;
  const double eps_mid = 0.10;
  const double f_mid = (382.92e6 + (512.19e6 - 382.92e6) * (0.10 - 0.05) / 0.10) * A;
  EXPECT_NEAR(wireResponse(c, kL0, mid, strainToLength(eps_mid)).force_N, f_mid, 1e-9 * f_mid);

  // Unloading from 15 %: elastic with the initial modulus, from eps_p = 0.15 - F/E.
  const double f15 = 512.19e6 * A, ep = 0.15 - f15 / E;
  EXPECT_NEAR(s.plastic_strain, ep, 1e-12);
  for (const double eps : {0.149, 0.148, ep + 1e-4}) {
    const WireResponse r = wireResponse(c, kL0, s, strainToLength(eps));
    EXPECT_NEAR(r.force_N, E * (eps - ep), 1e-6 * f15) << "unloading at " << eps;
    EXPECT_NEAR(s.plastic_strain, ep, 1e-12);
  }
  // Compression (shorter than the plastic length): slack.
  EXPECT_EQ(wireResponse(c, kL0, s, strainToLength(ep - 0.01)).force_N, 0.0);
  EXPECT_EQ(wireResponse(c, kL0, s, 0.5 * kL0).force_N, 0.0);
  // Reloading: elastic up to the strain reached, then on the backbone again.
  EXPECT_NEAR(wireResponse(c, kL0, s, strainToLength(0.149)).force_N, E * (0.149 - ep), 1e-6 * f15);
  const double f20 = 0.5 * (512.19e6 + 558.54e6) * A;
  EXPECT_NEAR(wireResponse(c, kL0, s, strainToLength(0.20)).force_N, f20, 1e-9 * f20);
  // Rupture after the last point (35 %), not at it.
  WireResponse r = wireResponse(c, kL0, s, strainToLength(0.35 - 1e-12));
  EXPECT_FALSE(r.breaks);
  EXPECT_NEAR(r.force_N, 565.85e6 * A, 1e-9 * 565.85e6 * A);
  r = wireResponse(c, kL0, s, strainToLength(0.3501));
  EXPECT_TRUE(r.breaks);
  EXPECT_EQ(r.force_N, 0.0);
  // Its state stays at the last point (what it held then: that point's elastic energy).
  EXPECT_NEAR(s.reached_strain, 0.35, 1e-15);
  EXPECT_NEAR(wireElasticEnergy(c, kL0, c.force().back()), 0.5 * std::pow(565.85e6 * A, 2) / E * kL0, 1e-12);
}

TEST(WireLaw, WorkOverACycleIsPlasticDissipationPlusStoredEnergy) {
  // Drive one link through load, unload, slack, reload and on to 30 %,
  // integrating the work F dL by the trapezoid rule on a fine path; at
  // every point it equals the plastic work (a function of the state) plus
  // the elastic energy stored. The path's kinks fall on its own points and
  // the table points are hit within 1e-5 of strain, so the trapezoid error
  // is of the order of (F jump x strain step): 1e-6 relative.
  const WireCurve c = wireCurve(defaultWireTable(), kD);
  WireState s;
  std::vector<double> path;
  const auto go = [&](double from, double to, int n) {
    for (int k = 1; k <= n; ++k) path.push_back(from + (to - from) * k / n);
  };
  go(0.0, 0.12, 120000);
  go(0.12, -0.02, 140000);  // unload and go slack
  go(-0.02, 0.30, 320000);  // reload and on along the backbone
  double work = 0.0, f_prev = 0.0, L_prev = kL0;
  double worst = 0.0;
  for (const double eps : path) {
    const double L = strainToLength(eps);
    const WireResponse r = wireResponse(c, kL0, s, L);
    ASSERT_FALSE(r.breaks);
    work += 0.5 * (r.force_N + f_prev) * (L - L_prev);
    f_prev = r.force_N, L_prev = L;
    const double held = wireDissipatedEnergy(c, kL0, s) + wireElasticEnergy(c, kL0, r.force_N);
    worst = std::max(worst, std::fabs(held - work));
  }
  EXPECT_GT(work, 30.0);  // a 46 mm wire of 2.7 mm to 30 % absorbs some 38 J
  EXPECT_LT(worst, 1e-6 * work);
}

TEST(WireLaw, DoubleTwistIsTwoWiresStifferThanOneBreakingEarlier) {
  const WireStressStrain t = defaultWireTable();
  const DoubleTwistParams p{0.66, 0.4};
  const WireCurve single = wireCurve(t, kD), twist = doubleTwistCurve(t, kD, p);
  // Elastic stiffness lambda_k x two wires: stiffer than one wire, softer than two.
  EXPECT_NEAR(twist.elasticForce(), 0.66 * 2.0 * single.elasticForce(), 1e-9 * single.elasticForce());
  // Two wires' force at every point; the strains after the first times lambda_eps.
  for (std::size_t k = 0; k < t.strain.size(); ++k) EXPECT_DOUBLE_EQ(twist.force()[k], 2.0 * single.force()[k]) << k;
  EXPECT_DOUBLE_EQ(twist.strain()[0], t.strain[0] / 0.66);
  EXPECT_DOUBLE_EQ(twist.ruptureStrain(), 0.4 * 0.35);
  EXPECT_TRUE(checkDoubleTwist(t, p).empty());
  // lambda_k so small that the elastic limit passes the next point: refused.
  EXPECT_NE(checkDoubleTwist(t, {0.2, 0.4}).find("raise lambda_k"), std::string::npos);
  EXPECT_FALSE(checkDoubleTwist(t, {0.0, 0.4}).empty());
  EXPECT_FALSE(checkDoubleTwist(t, {0.66, 1.5}).empty());
}

TEST(WireLaw, BadTablesAreNamed) {
  WireStressStrain t = defaultWireTable();
  EXPECT_TRUE(checkWireTable(t).message.empty());
  t.strain[3] = t.strain[2];
  WireTableIssue i = checkWireTable(t);
  EXPECT_EQ(i.at, 3);
  EXPECT_TRUE(i.strain);
  t = defaultWireTable();
  t.stress_Pa[2] = -1.0;
  i = checkWireTable(t);
  EXPECT_EQ(i.at, 2);
  EXPECT_FALSE(i.strain);
  t = defaultWireTable();
  t.stress_Pa[1] = 5e9;  // steeper than E between points 0 and 1
  i = checkWireTable(t);
  EXPECT_EQ(i.at, 1);
  EXPECT_NE(i.message.find("elastic modulus"), std::string::npos);
  t = defaultWireTable();
  t.stress_Pa.pop_back();
  EXPECT_FALSE(checkWireTable(t).message.empty());
}

// The link stage answers most wires with the elastic line alone
// (micro/links.cpp): wherever wireLeavesElasticLine says a strain stays on
// it, wireResponse must give wireElasticLineForce to the last bit and leave
// the state as it was; wherever it says the strain leaves it, wireResponse
// must change the state or break. Checked over states along a loading path
// and strains across the whole curve, slack and rupture included.
TEST(WireLaw, TheElasticLineIsTheLawWhereverItSaysSo) {
  const WireCurve c = wireCurve(defaultWireTable(), kD);
  const double rupture = c.ruptureStrain(), first = c.strain()[0];
  int on = 0, off = 0;
  for (const double reached : {0.0, 0.5 * first, first, 0.01, 0.1, 0.2, 0.34}) {
    WireState state;
    if (reached > 0.0) wireResponse(c, state, reached);  // (to that point of the backbone)
    for (int k = -20; k <= 420; ++k) {
      const double eps = 1e-3 * k;  // -2 % .. 42 %
      WireState s = state;
      const WireResponse r = wireResponse(c, s, eps);
      if (wireLeavesElasticLine(eps, state.reached_strain, first, rupture)) {
        ++off;
        EXPECT_TRUE(r.breaks || s.reached_strain != state.reached_strain) << reached << " " << eps;
      } else {
        ++on;
        EXPECT_FALSE(r.breaks) << eps;
        EXPECT_EQ(r.force_N, wireElasticLineForce(c.elasticForce(), eps, state.plastic_strain))
            << reached << " " << eps;
        EXPECT_EQ(s.plastic_strain, state.plastic_strain);
        EXPECT_EQ(s.reached_strain, state.reached_strain);
      }
    }
  }
  EXPECT_GT(on, 500);
  EXPECT_GT(off, 500);
  // A NaN strain stays on the line with no force (as std::max(0, NaN)).
  EXPECT_FALSE(wireLeavesElasticLine(std::nan(""), 0.0, first, rupture));
  EXPECT_EQ(wireElasticLineForce(c.elasticForce(), std::nan(""), 0.0), 0.0);
}
