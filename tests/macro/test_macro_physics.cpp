// The macro model against closed-form solutions and conservation laws.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <numeric>

#include "macro/impact.hpp"
#include "macro/model.hpp"
#include "macro_test_util.hpp"

using namespace gabion::macro;
using namespace gabion::macro::testing;

namespace {

// Two masses, boulder M and cell m, the contact spring k1 between them and
// the cell's half-cell spring k2 to the wall: x(t) by modal superposition,
// x(0) = 0, v(0) = (v0, 0). The contact force is k1 (x_b - x_c).
struct TwoMass {
  double M, m, k1, k2, v0;
  Eigen::Vector2d omega;
  Eigen::Matrix2d modes;  // mass-normalised
  TwoMass(double M_, double m_, double k1_, double k2_, double v0_) : M(M_), m(m_), k1(k1_), k2(k2_), v0(v0_) {
    // A = M^-1/2 K M^-1/2 is symmetric; its eigenvectors w give the modes M^-1/2 w.
    const double a = k1 / M, b = -k1 / std::sqrt(M * m), c = (k1 + k2) / m;
    const double mean = 0.5 * (a + c), rad = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
    const double lam[2] = {mean - rad, mean + rad};
    for (int i = 0; i < 2; ++i) {
      Eigen::Vector2d w(b, lam[i] - a);  // (A - lam I) w = 0, first row
      w.normalize();
      omega[i] = std::sqrt(lam[i]);
      modes.col(i) = Eigen::Vector2d(w[0] / std::sqrt(M), w[1] / std::sqrt(m));
    }
  }
  Eigen::Vector2d x(double t) const {
    const Eigen::Vector2d Mv(M * v0, 0.0);
    Eigen::Vector2d out = Eigen::Vector2d::Zero();
    for (int i = 0; i < 2; ++i) out += modes.col(i) * (modes.col(i).dot(Mv) / omega[i] * std::sin(omega[i] * t));
    return out;
  }
  double force(double t) const {
    const auto p = x(t);
    return k1 * (p[0] - p[1]);
  }
};

}  // namespace

// One elastic cell between the boulder and a fixed support: peak force and
// contact duration against the closed-form two-mass solution within 0.5 %.
TEST(MacroAnalytic, ElasticCellTwoMassSolution) {
  const double M = 170.0, m = 183.0, k_axial = 1e7, k_imp = 2e7, v0 = 10.0;
  Structure s = buildStructure(grid(1, 1, 1), oneMaterial(epp(k_axial, 1e12), epp(k_imp, 1e12), m));
  Model model(s, Kinematics::XOnly);
  const ImpactResult r = runImpact(model, boulderAt(s, 0, 0, M, v0), quickRun(0.03, 0.02), 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;

  // The model's wall link is half a cell: stiffness 2 k.
  const TwoMass exact(M, m, k_imp, 2.0 * k_axial, v0);
  double peak = 0.0, t_end = 0.0;
  const double h = 1e-7;
  for (double t = h; t < 0.05; t += h) {
    const double f = exact.force(t);
    ASSERT_GE(exact.x(t)[1], 0.0) << "the wall spring must stay in compression for this comparison";
    if (f <= 0.0) {  // bisection of the separation
      double a = t - h, b = t;
      for (int i = 0; i < 60; ++i) (exact.force(0.5 * (a + b)) > 0.0 ? a : b) = 0.5 * (a + b);
      t_end = 0.5 * (a + b);
      break;
    }
    peak = std::max(peak, f);
  }
  ASSERT_GT(t_end, 0.0);
  EXPECT_NEAR(r.peak_force_N, peak, 0.005 * peak);
  EXPECT_NEAR(r.contact_duration_s, t_end, 0.005 * t_end);
  EXPECT_LT(r.balance_rel_error, 1e-3);
}

// The boulder against an elastic-perfectly-plastic (and a bilinear) face on a
// rigid support: dissipated energy and rebound speed from the law alone.
// EPP: D = 1/2 M v^2 - F_y^2 / (2k); rebound speed F_y / sqrt(k M).
// Bilinear: F_max^2 = F_y^2 + k_h (M v^2 - F_y^2 / k); D = 1/2 M v^2 - F_max^2 / (2k).
// A boulder of mass M at v0 against one cell whose face follows `face`: a
// very heavy cell on a very stiff support, so the face does not move; the
// step `fraction` of the critical one.
namespace {
ImpactResult strikeRigidFace(const gabion::bridge::AxialLawParams& face, double M, double v0, double fraction) {
  Structure s = buildStructure(grid(1, 1, 1), oneMaterial(epp(1e13, 1e15), face, 1e9));
  Model model(s, Kinematics::XOnly);
  return runImpact(model, boulderAt(s, 0, 0, M, v0), quickRun(0.05, fraction), 0, nullptr);
}
}  // namespace

class MacroPlastic : public ::testing::TestWithParam<bool> {};

TEST_P(MacroPlastic, DissipatedEnergyAndRebound) {
  const bool bilinear = GetParam();
  const double M = 170.0, v0 = 10.0, k = 2e7, fy = 1e5, kh = 4e6;
  gabion::bridge::AxialLawParams imp = epp(k, fy);
  if (bilinear) {
    imp.model = gabion::bridge::AxialModel::Bilinear;
    imp.hardening_stiffness_N_m = kh;
  }
  const ImpactResult r = strikeRigidFace(imp, M, v0, 0.02);
  ASSERT_TRUE(r.ok) << r.message;
  const double e0 = 0.5 * M * v0 * v0;
  const double fmax = bilinear ? std::sqrt(fy * fy + kh * (M * v0 * v0 - fy * fy / k)) : fy;
  const double dissipated = e0 - fmax * fmax / (2.0 * k);
  EXPECT_NEAR(r.plastic_J, dissipated, 0.005 * dissipated);
  EXPECT_NEAR(r.rebound_velocity_m_s, fmax / std::sqrt(k * M), 0.005 * fmax / std::sqrt(k * M));
  EXPECT_NEAR(r.peak_force_N, fmax, 0.005 * fmax);
  EXPECT_EQ(r.contact_episodes, 1);
}
INSTANTIATE_TEST_SUITE_P(Laws, MacroPlastic, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& p) {
                           return p.param ? "Bilinear" : "ElasticPerfectlyPlastic";
                         });

// The boulder against a softening face (peak F_y, falling tangent -k_s to the
// residual F_r) on a rigid support: it stops where the work of the backbone,
// F_y^2 / (2k) + (F_y + F_r) (F_y - F_r) / (2 k_s) + F_r (u - u_r), is its
// energy; it rebounds from F_r elastically: speed F_r / sqrt(k M), and the
// plastic work is the rest. The peak force is F_y.
TEST(MacroPlastic, SofteningFaceStopsTheBoulderWhereTheBackboneTakesItsEnergy) {
  const double M = 170.0, v0 = 10.0, k = 2e7, fy = 1e5, ks = 2e6, fr = 5e4;
  gabion::bridge::AxialLawParams imp = epp(k, fy);
  imp.model = gabion::bridge::AxialModel::Softening;
  imp.softening_stiffness_N_m = ks;
  imp.residual_force_N = fr;
  // (a step of 0.002 of the critical one: the force is sampled at the steps,
  // and past the peak it falls by k_s v dt a step)
  const ImpactResult r = strikeRigidFace(imp, M, v0, 0.002);
  ASSERT_TRUE(r.ok) << r.message;
  const double e0 = 0.5 * M * v0 * v0;
  const double uy = fy / k, ur = uy + (fy - fr) / ks;
  const double stop = ur + (e0 - 0.5 * fy * uy - 0.5 * (fy + fr) * (ur - uy)) / fr;  // 0.158 m, short of the centre
  ASSERT_LT(stop, 0.2);
  EXPECT_NEAR(r.max_penetration_m, stop, 0.005 * stop);
  EXPECT_NEAR(r.peak_force_N, fy, 0.005 * fy);
  const double dissipated = e0 - fr * fr / (2.0 * k);
  EXPECT_NEAR(r.plastic_J, dissipated, 0.005 * dissipated);
  EXPECT_NEAR(r.rebound_velocity_m_s, fr / std::sqrt(k * M), 0.01 * fr / std::sqrt(k * M));
  EXPECT_LT(r.balance_rel_error, 1e-3);
}

// The boulder against an elastic-perfectly plastic face with a rate term on a
// rigid support. Elastic to F_y + c v1^2 (v1 the speed there: 1/2 M v0^2 =
// 1/2 M v1^2 + F1^2 / (2k)); then the face flows and the boulder obeys
// M dv/dt = -(F_y + c v^2): it travels M / (2c) ln(F1 / F_y) beyond F1 / k
// and stops there, the face back at F_y. Peak force F1; it rebounds from
// F_y: speed F_y / sqrt(k M); the rest is plastic work.
TEST(MacroPlastic, RateTermHoldsTheFaceAtItsOverstressUntilTheBoulderStops) {
  const double M = 170.0, v0 = 10.0, k = 2e8, fy = 2e4, c = 600.0;
  gabion::bridge::AxialLawParams imp = epp(k, fy);
  imp.rate_coefficient_N_s2_m2 = c;
  const ImpactResult r = strikeRigidFace(imp, M, v0, 0.02);
  ASSERT_TRUE(r.ok) << r.message;
  double v1 = v0;  // fixed point of the elastic phase's energy balance
  for (int i = 0; i < 50; ++i) {
    const double f1 = fy + c * v1 * v1;
    v1 = std::sqrt(v0 * v0 - f1 * f1 / (k * M));
  }
  const double f1 = fy + c * v1 * v1;
  const double stop = f1 / k + M / (2.0 * c) * std::log(f1 / fy);
  EXPECT_NEAR(r.peak_force_N, f1, 0.005 * f1);
  EXPECT_NEAR(r.max_penetration_m, stop, 0.005 * stop);
  const double e0 = 0.5 * M * v0 * v0, dissipated = e0 - fy * fy / (2.0 * k);
  EXPECT_NEAR(r.plastic_J, dissipated, 0.005 * dissipated);
  EXPECT_NEAR(r.rebound_velocity_m_s, fy / std::sqrt(k * M), 0.01 * fy / std::sqrt(k * M));
  EXPECT_LT(r.balance_rel_error, 1e-3);
  // At the default step, a quarter of the critical one (about 30 steps of
  // flow), the plastic work takes the overstress at the mean of each step's
  // two ends, the trapezoidal rule of the leapfrog's work: the balance closes
  // to 3.4e-3. With each step's own overstress alone it was 1.3e-2.
  const ImpactResult coarse = strikeRigidFace(imp, M, v0, 0.25);
  ASSERT_TRUE(coarse.ok) << coarse.message;
  EXPECT_LT(coarse.balance_rel_error, 5e-3);
}

// A viscous axial law (a dashpot eta in parallel while the cell is in
// contact, never pulling): one cell on its half-cell link to the back
// support (2k, 2 eta), struck through a stiff elastic face. The model's
// peak force, the boulder's rebound speed and its travel follow the same
// two-mass system integrated apart (RK4, 1e-7 s steps) to 1 %; the dashpot's
// work closes the energy balance to 1e-2 at 2 % of the critical step. A
// damped node takes a shorter critical step: 2 / w (sqrt(1 + z^2) - z).
TEST(MacroPlastic, ViscousAxialLinkFollowsItsTwoMassSystem) {
  const double M = 170.0, m = 183.0, v0 = 5.0, k = 1e7, eta = 2e4, ki = 2e7;
  gabion::bridge::AxialLawParams axial = epp(k, 1e12);
  axial.viscosity_N_s_m = eta;
  const Structure s = buildStructure(grid(1, 1, 1), oneMaterial(axial, epp(ki, 1e12), m));
  Model model(s, Kinematics::XOnly);
  const ImpactResult r = runImpact(model, boulderAt(s, 0, 0, M, v0), quickRun(0.05, 0.02), 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;
  // The reference: boulder xb, node xn (from contact), face force ki (xb - xn)+,
  // link 2k xn+ plus the dashpot 2 eta vn while 2k xn > 0, never below zero.
  const double kh = 2.0 * k, eh = 2.0 * eta;
  struct State {
    double xb, vb, xn, vn;
  };
  const auto accel = [&](const State& q, double& ab, double& an, double& face) {
    face = ki * std::max(0.0, q.xb - q.xn);
    const double fl = kh * std::max(0.0, q.xn);
    const double link = fl + gabion::bridge::fillRateForce(eh, 0.0, 0.0, q.xn, q.vn, fl);
    ab = -face / M;
    an = (face - link) / m;
  };
  State q{0.0, v0, 0.0, 0.0};
  double peak = 0.0, deepest = 0.0;
  const double h = 1e-7;
  for (double t = 0.0; t < r.end_time_s; t += h) {  // (to where the model's impact ended)
    const auto deriv = [&](const State& x) {
      double ab, an, f;
      accel(x, ab, an, f);
      return State{x.vb, ab, x.vn, an};
    };
    const auto add = [](const State& a, const State& b, double c) {
      return State{a.xb + c * b.xb, a.vb + c * b.vb, a.xn + c * b.xn, a.vn + c * b.vn};
    };
    const State k1 = deriv(q), k2 = deriv(add(q, k1, h / 2)), k3 = deriv(add(q, k2, h / 2)), k4 = deriv(add(q, k3, h));
    q.xb += h / 6 * (k1.xb + 2 * k2.xb + 2 * k3.xb + k4.xb);
    q.vb += h / 6 * (k1.vb + 2 * k2.vb + 2 * k3.vb + k4.vb);
    q.xn += h / 6 * (k1.xn + 2 * k2.xn + 2 * k3.xn + k4.xn);
    q.vn += h / 6 * (k1.vn + 2 * k2.vn + 2 * k3.vn + k4.vn);
    double ab, an, f;
    accel(q, ab, an, f);
    peak = std::max(peak, f);
    deepest = std::max(deepest, q.xb);
  }
  EXPECT_NEAR(r.peak_force_N, peak, 0.01 * peak);
  EXPECT_NEAR(r.max_penetration_m, deepest, 0.01 * deepest);
  EXPECT_NEAR(r.rebound_velocity_m_s, -q.vb, 0.01 * std::fabs(q.vb));
  EXPECT_LT(-q.vb, 0.8 * v0);  // (the dashpot took its share)
  EXPECT_LT(r.balance_rel_error, 1e-2);
  EXPECT_GT(r.plastic_J, 0.1 * 0.5 * M * v0 * v0);  // (its work: the only dissipation here)
  // The critical step of the damped node (w^2 = 2 kh / m, beta = 2 eh / m):
  // the boulder absent, only the node's link.
  Model alone(s, Kinematics::XOnly);
  gabion::bridge::AxialLawParams stiff = axial;
  stiff.viscosity_N_s_m = 5e5;  // (zeta about 2.9: the damping sets the step)
  Model damped(buildStructure(grid(1, 1, 1), oneMaterial(stiff, epp(ki, 1e12), m)), Kinematics::XOnly);
  const double w2 = 2.0 * kh / m, beta = 2.0 * 2.0 * 5e5 / m;
  EXPECT_NEAR(damped.criticalTimeStep(), (std::sqrt(beta * beta + 4.0 * w2) - beta) / w2, 1e-12);
  EXPECT_NEAR(alone.criticalTimeStep(),
              std::min(2.0 / std::sqrt(w2), (std::sqrt(4.0 * eh * eh / (m * m) + 4.0 * w2) - 2.0 * eh / m) / w2),
              1e-12);
  EXPECT_LT(damped.criticalTimeStep(), alone.criticalTimeStep());
}

// The structure keeps one table of link laws, equal laws sharing an entry:
// an impact law that differs from the axial law of the link behind it only
// in its rate term keeps its rate term (it was once merged into the axial
// law, which compared only the older fields).
TEST(MacroPlastic, LawsThatDifferOnlyInTheirRateTermAreNotMerged) {
  gabion::bridge::AxialLawParams impact = epp(2e7, 2e4);
  impact.rate_coefficient_N_s2_m2 = 600.0;
  const Structure s = buildStructure(grid(2, 1, 1), oneMaterial(epp(2e7, 2e4), impact, 183.0));
  const auto& front = s.axial_laws[static_cast<std::size_t>(s.front.law[0])];
  EXPECT_EQ(front.rate_coefficient_N_s2_m2, 600.0);
  EXPECT_EQ(s.axial_springs[static_cast<std::size_t>(s.front.law[0])].rate_N_s2_m2, 600.0);
  for (const int law : s.axial.law)
    EXPECT_EQ(s.axial_laws[static_cast<std::size_t>(law)].rate_coefficient_N_s2_m2, 0.0);
}

// Plastic densification in the wall: a column of two cells struck hard
// enough to compact both links past the densification onset. At every step
// each axial link's force and the model's elastic energy are the bridge
// law's (bridge::cellResponse on the link's shortening and previous plastic
// part: the compaction travels in the plastic part, no other state), to
// 1e-14; the energy balances; and the compacted column keeps what it took:
// the compaction dissipates most of the impact energy, where the same law
// with elastic densification stores it and gives it back.
TEST(MacroPlastic, CompactedCellsKeepTheirCompaction) {
  gabion::bridge::AxialLawParams axial{gabion::bridge::AxialModel::Densifying, 3e5, 1e3, 3e4, 0.03, 4e5, 0.12, 4e6};
  const auto strike = [&](bool plastic, bool check_links) {
    axial.plastic_densification = plastic;
    const Structure s = buildStructure(grid(2, 1, 1), oneMaterial(axial, epp(2e7, 1e9), 183.0, 0.4, 0.0));
    Model model(s, Kinematics::XOnly);
    if (check_links) {
      model.placeBoulder(boulderAt(s, 0, 0, 170.0, 6.0));
      const double dt = 0.1 * model.criticalTimeStep();
      double worst = 0.0, deepest = 0.0;
      for (int step = 0; step < 4000; ++step) {
        const std::vector<double> ux = model.ux(), up = model.axialPlastic();
        EXPECT_EQ(model.step(dt), StepStatus::Ok) << model.failure();
        double elastic = 0.0;
        for (std::size_t l = 0; l < s.axial.a.size(); ++l) {
          const int b = s.axial.b[l];
          const double u =
              ux[static_cast<std::size_t>(s.axial.a[l])] - (b >= 0 ? ux[static_cast<std::size_t>(b)] : 0.0);
          const auto r =
              gabion::bridge::cellResponse(s.axial_springs[static_cast<std::size_t>(s.axial.law[l])], u, up[l]);
          worst = std::max(worst, std::fabs(model.axialForce()[l] - r.force_N) / std::max(1.0, r.force_N));
          elastic += r.elastic_J;
          deepest = std::max(deepest, u);
        }
        if (model.contacts() == 0) {
          EXPECT_NEAR(model.energy().elastic_J, elastic, 1e-12 * std::max(1.0, elastic));
        }
      }
      EXPECT_LT(worst, 1e-14);
      EXPECT_GT(deepest, 0.03);  // (past the onset of the half-cell and the whole-cell links)
    }
    Model fresh(s, Kinematics::XOnly);
    return runImpact(fresh, boulderAt(s, 0, 0, 170.0, 6.0), quickRun(0.3, 0.1), 0, nullptr);
  };
  const ImpactResult elastic = strike(false, false), plastic = strike(true, true);
  ASSERT_TRUE(elastic.ok) << elastic.message;
  ASSERT_TRUE(plastic.ok) << plastic.message;
  EXPECT_LT(plastic.balance_rel_error, 2e-3);
  EXPECT_LT(elastic.balance_rel_error, 2e-3);
  // 3.06 kJ in: the compaction keeps 86 % of it, the elastic densification
  // gives all but 15 % back to the column (which the boulder has left by
  // then, at the same 0.23 m/s in both).
  const double input = 0.5 * 170.0 * 6.0 * 6.0;
  EXPECT_GT(plastic.plastic_J, 0.8 * input);
  EXPECT_LT(elastic.plastic_J, 0.2 * input);
  // With the dense part's own unloading stiffness (softer than k_d + k_L:
  // part of the compaction given back), the links are still the bridge
  // law's, the balance holds, and the column keeps less than with k_d + k_L.
  axial.densification_unloading_stiffness_N_m = 9e5;
  const ImpactResult partly = strike(true, true);
  ASSERT_TRUE(partly.ok) << partly.message;
  // (the leapfrog's error at a tenth of the critical step: 3.6e-3, the
  // unloading's kink sharper than with k_d + k_L; under 2e-3 at a twentieth)
  EXPECT_LT(partly.balance_rel_error, 5e-3) << partly.balance_rel_error;
  EXPECT_LT(partly.plastic_J, plastic.plastic_J);
  EXPECT_GT(partly.plastic_J, elastic.plastic_J);
}

// The momentum flux of an axial law in the wall. Two half cells in series
// share the rate so that both carry the same flux: 1 / sqrt(c_m) adds up (a
// link between two equal cells is one cell, c_m; a half cell against the
// back support, 4 c_m, the force going with the strain rate squared; the
// growth a shortening, halved). In a struck column of two cells with
// plastic densification, every link's force at every step is the bridge
// law's plus bridge::fillRateForce at the link's shortening rate, the energy
// balances (the flux's work dissipated), and the flux holds the column
// back: the back link shortens less than without it.
TEST(MacroPlastic, MomentumFluxFollowsTheBridgeLaw) {
  using gabion::bridge::AxialLawParams;
  AxialLawParams a{gabion::bridge::AxialModel::Densifying, 3e5, 1e3, 3e4, 0.03, 4e5, 0.12, 4e6};
  a.plastic_densification = true;
  a.momentum_flux_growth_m = 0.05;
  AxialLawParams b = a;
  a.momentum_flux_kg_m = 2000.0;
  b.momentum_flux_kg_m = 500.0;
  b.momentum_flux_growth_m = 0.03;
  EXPECT_NEAR(seriesAxialLaw(a, a).momentum_flux_kg_m, 2000.0, 1e-9);
  EXPECT_NEAR(seriesAxialLaw(a, b).momentum_flux_kg_m,
              4.0 / std::pow(1.0 / std::sqrt(2000.0) + 1.0 / std::sqrt(500.0), 2), 1e-9);
  EXPECT_NEAR(seriesAxialLaw(a, b).momentum_flux_growth_m, 0.04, 1e-15);
  EXPECT_NEAR(halfCellLaw(a).momentum_flux_kg_m, 8000.0, 1e-9);
  EXPECT_NEAR(halfCellLaw(a).momentum_flux_growth_m, 0.025, 1e-15);
  b.momentum_flux_kg_m = 0.0;
  EXPECT_EQ(seriesAxialLaw(a, b).momentum_flux_kg_m, 0.0);

  const auto strike = [&](double flux, double& back_shortening) {
    a.momentum_flux_kg_m = flux;
    const Structure s = buildStructure(grid(2, 1, 1), oneMaterial(a, epp(2e7, 1e9), 183.0, 0.4, 0.0));
    Model model(s, Kinematics::XOnly);
    model.placeBoulder(boulderAt(s, 0, 0, 170.0, 6.0));
    const double dt = 0.05 * model.criticalTimeStep();
    const std::size_t nl = s.axial.a.size();
    double worst = 0.0, largest = 0.0;
    back_shortening = 0.0;
    const double e0 = 0.5 * 170.0 * 6.0 * 6.0;
    for (int step = 0; step < 8000; ++step) {
      const std::vector<double> ux = model.ux(), vx = model.vx(), up = model.axialPlastic();
      EXPECT_EQ(model.step(dt), StepStatus::Ok) << model.failure();
      for (std::size_t l = 0; l < nl; ++l) {
        const auto na = static_cast<std::size_t>(s.axial.a[l]);
        const int nb = s.axial.b[l];
        const double u = ux[na] - (nb >= 0 ? ux[static_cast<std::size_t>(nb)] : 0.0);
        const double rate = vx[na] - (nb >= 0 ? vx[static_cast<std::size_t>(nb)] : 0.0);
        const auto& law = s.axial_springs[static_cast<std::size_t>(s.axial.law[l])];
        const double f = gabion::bridge::cellResponse(law, u, up[l]).force_N;
        const double fd = gabion::bridge::fillRateForce(0.0, law.flux_kg_m, law.flux_growth_m, u, rate, f);
        worst = std::max(worst, std::fabs(model.axialForce()[l] - (f + fd)) / std::max(1.0, f + fd));
        largest = std::max(largest, fd);
        if (nb < 0) back_shortening = std::max(back_shortening, u);
      }
    }
    EXPECT_LT(worst, 1e-14) << flux;
    EXPECT_LT(std::fabs(model.energy().total() - e0), 2e-3 * e0) << flux;
    return largest;
  };
  double with = 0.0, without = 0.0;
  EXPECT_GT(strike(2000.0, with), 1e3) << "the flux acts (N)";
  EXPECT_EQ(strike(0.0, without), 0.0);
  EXPECT_LT(with, 0.9 * without);
}

// A 1-D chain pushed at its front at constant speed: the compression front
// reaches the fixed back face after N e / c with c = e sqrt(k/m) (the long-wave
// speed of the lattice). The discrete lattice smears the step over an Airy
// front about n^(1/3) cells wide whose half-amplitude point lags the ray by a
// fraction of that width; with n = 200 the lag is below 1 % of the travel time.
TEST(MacroAnalytic, ChainWaveArrivalTime) {
  const int n = 200;
  const double m = 183.0, k = 1e7, v0 = 1.0;
  // Impact spring 2k: the face-to-node half cell, so the front is uniform too.
  Structure s = buildStructure(grid(n, 1, 1), oneMaterial(epp(k, 1e12), epp(2 * k, 1e12), m));
  Model model(s, Kinematics::XOnly);
  model.placeBoulder(boulderAt(s, 0, 0, 1e7, v0));  // a piston: its speed barely changes
  const double dt = 0.05 * model.criticalTimeStep();
  const std::size_t wall = s.axial.a.size() - 1;
  ASSERT_EQ(s.axial.b[wall], kWall);
  const double f_incident = v0 * std::sqrt(k * m);  // lattice impedance sqrt(k m) times speed
  const double expected = n * std::sqrt(m / k);
  double arrival = -1.0;
  while (model.time_s() < 2.0 * expected) {
    ASSERT_EQ(model.step(dt), StepStatus::Ok);
    // The reflected step doubles the force: its midpoint is the incident force.
    if (model.axialForce()[wall] >= f_incident) {
      arrival = model.time_s() - dt;
      break;
    }
  }
  EXPECT_NEAR(arrival, expected, 0.01 * expected);
}

// A centred impact on a symmetric wall gives a symmetric displacement field.
TEST(MacroSymmetry, CentredImpactIsSymmetric) {
  for (auto kin : {Kinematics::XOnly, Kinematics::ThreeD}) {
    Structure s = buildStructure(grid(3, 5, 5), oneMaterial(epp(1e7, 5e4), epp(2e7, 2e5), 183.0));
    Model model(s, kin);
    model.placeBoulder(boulderAt(s, 2, 2, 170.0, 20.0));
    const double dt = 0.1 * model.criticalTimeStep();
    double umax = 0.0;
    for (int step = 0; step < 200; ++step) ASSERT_EQ(model.step(dt), StepStatus::Ok);
    for (double u : model.ux()) umax = std::max(umax, std::abs(u));
    ASSERT_GT(umax, 1e-4);
    for (int k = 0; k < 5; ++k)
      for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 3; ++i) {
          const auto a = static_cast<std::size_t>(s.nodeAt(i, j, k));
          const auto by = static_cast<std::size_t>(s.nodeAt(i, 4 - j, k));
          const auto bz = static_cast<std::size_t>(s.nodeAt(i, j, 4 - k));
          EXPECT_NEAR(model.ux()[a], model.ux()[by], 1e-9 * umax);
          EXPECT_NEAR(model.ux()[a], model.ux()[bz], 1e-9 * umax);
          if (kin == Kinematics::ThreeD) {
            EXPECT_NEAR(model.uy()[a], -model.uy()[by], 1e-9 * umax);
            EXPECT_NEAR(model.uz()[a], -model.uz()[bz], 1e-9 * umax);
          }
        }
  }
}

// More friction between cells spreads the load over more cells.
TEST(MacroFriction, MoreFrictionLoadsMoreCells) {
  auto run = [](double mu) {
    Structure s = buildStructure(grid(3, 9, 9), oneMaterial(epp(1e7, 5e4), epp(2e7, 2e5), 183.0, 0.4, mu, 3e6));
    Model model(s, Kinematics::XOnly);
    return runImpact(model, boulderAt(s, 4, 4, 170.0, 20.0), quickRun(0.03, 0.1), 0, nullptr);
  };
  const ImpactResult low = run(0.05), high = run(1.0);
  ASSERT_TRUE(low.ok && high.ok);
  EXPECT_GT(high.loaded_cells, low.loaded_cells);
  EXPECT_GT(high.friction_J, low.friction_J);
  EXPECT_LT(high.max_penetration_m, low.max_penetration_m);
}

// x-only and 3-D kinematics agree for a normal, centred impact (same dt).
TEST(MacroKinematics, XOnlyEquals3dForNormalImpact) {
  ImpactResult r[2];
  for (int i = 0; i < 2; ++i) {
    Structure s = buildStructure(grid(3, 5, 5), oneMaterial(epp(1e7, 5e4), epp(2e7, 2e5), 183.0));
    Model model(s, i == 0 ? Kinematics::XOnly : Kinematics::ThreeD);
    RunSettings run = quickRun(0.05);
    run.time_step_s = 5e-5;
    r[i] = runImpact(model, boulderAt(s, 2, 2, 170.0, 20.0), run, 0, nullptr);
    ASSERT_TRUE(r[i].ok) << r[i].message;
  }
  EXPECT_NEAR(r[0].peak_force_N, r[1].peak_force_N, 1e-9 * r[0].peak_force_N);
  EXPECT_NEAR(r[0].max_penetration_m, r[1].max_penetration_m, 1e-9 * r[0].max_penetration_m);
  EXPECT_NEAR(r[0].contact_duration_s, r[1].contact_duration_s, 1e-9);
  EXPECT_NEAR(r[0].plastic_J, r[1].plastic_J, 1e-9 * r[0].plastic_J);
  EXPECT_NEAR(r[0].friction_J, r[1].friction_J, 1e-6 * r[0].friction_J + 1e-9);
}

// An oblique impact in 3-D: energy still balances and the boulder is deflected sideways.
TEST(MacroKinematics, ObliqueImpact3dBalances) {
  Structure s = buildStructure(grid(3, 7, 5), oneMaterial(epp(1e7, 5e4), epp(2e7, 2e5), 183.0));
  Model model(s, Kinematics::ThreeD);
  BoulderSpec b = boulderAt(s, 3, 2, 170.0, 20.0);
  b.velocity_m_s = Eigen::Vector3d(20.0 * std::cos(0.5), 20.0 * std::sin(0.5), 0.0);
  b.aim_y_m += 0.1;
  const ImpactResult r = runImpact(model, b, quickRun(0.05, 0.1), 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_GT(r.peak_force_N, 0.0);
  EXPECT_LT(r.balance_rel_error, 0.005);
  double uy = 0.0;
  for (double u : model.uy()) uy = std::max(uy, std::abs(u));
  EXPECT_GT(uy, 0.0);
}

// An oblique boulder (45 degrees in plan) aimed at a wall far from its
// edge: it glances off. Its penetration and outcome are measured along the
// wall's depth x: it stops or rebounds, having gone no deeper than the same boulder
// striking square on at its full speed. Measured along its path instead, the
// glancing boulder was "perforated" (its projection passed the back plane)
// or "unfinished" (never moving back along its path).
TEST(MacroKinematics, AGlancingObliqueBoulderGoesNoDeeperThanASquareOne) {
  Structure s = buildStructure(grid(4, 11, 5), oneMaterial(epp(1e7, 5e4), epp(2e7, 2e5), 183.0));
  const auto impact = [&](double angle) {
    Model model(s, Kinematics::ThreeD);
    BoulderSpec b = boulderAt(s, 5, 2, 170.0, 20.0);
    b.velocity_m_s = Eigen::Vector3d(20.0 * std::cos(angle), 20.0 * std::sin(angle), 0.0);
    return runImpact(model, b, quickRun(0.05, 0.1), 0, nullptr);
  };
  const ImpactResult oblique = impact(0.25 * M_PI), square = impact(0.0);
  ASSERT_TRUE(oblique.ok && square.ok) << oblique.message << square.message;
  EXPECT_TRUE(oblique.outcome == Outcome::Rebounded || oblique.outcome == Outcome::Stopped)
      << outcomeName(oblique.outcome);
  EXPECT_GT(oblique.max_penetration_m, 0.0);
  EXPECT_LT(oblique.max_penetration_m, square.max_penetration_m);
  EXPECT_LT(oblique.balance_rel_error, 0.005);
}

// The critical time step: a run above it is refused; the leapfrog is stable below it.
TEST(MacroStability, TimeStepAboveCriticalFails) {
  Structure s = buildStructure(grid(2, 3, 3), oneMaterial(epp(1e7, 5e4), epp(2e7, 2e5), 183.0));
  Model model(s, Kinematics::XOnly);
  model.placeBoulder(boulderAt(s, 1, 1, 170.0, 20.0));
  const double dt_crit = model.criticalTimeStep();
  model.removeBoulder();
  RunSettings run = quickRun(0.02);
  run.time_step_s = 1.5 * dt_crit;
  const ImpactResult r = runImpact(model, boulderAt(s, 1, 1, 170.0, 20.0), run, 0, nullptr);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("critical"), std::string::npos) << r.message;
}

// Round-off aside, the same case gives the same result (determinism).
TEST(MacroDeterminism, SameInputSameResult) {
  auto run = [] {
    Structure s = buildStructure(grid(3, 5, 5), oneMaterial(epp(1e7, 5e4), epp(2e7, 2e5), 183.0));
    Model model(s, Kinematics::ThreeD);
    return runImpact(model, boulderAt(s, 2, 2, 170.0, 20.0), quickRun(0.02, 0.1), 0, nullptr);
  };
  const auto a = run(), b = run();
  EXPECT_EQ(a.peak_force_N, b.peak_force_N);
  EXPECT_EQ(a.plastic_J, b.plastic_J);
  EXPECT_EQ(a.max_penetration_m, b.max_penetration_m);
}

// Every impact ends with an outcome (docs/macro.md, Outcome), constructed
// here so that each can only be what it is:
// - an elastic face on a rigid support gives the boulder its speed back:
//   rebounded, at v0 (restitution 1, within the time step's error);
// - at 2 m/s, a face that yields at 3 kN (2.6 % of the force an elastic one
//   would reach) keeps nearly all the energy within 0.11 m, less than the
//   boulder's radius: it comes back at fy / sqrt(k M), 2.6 % of its speed,
//   under the 5 % of a rebound: stopped;
// - a wall of light, weak cells lets the boulder through: its centre passes
//   the middle of a front cell, perforated (an answer, not a failure).
TEST(MacroOutcome, StoppedReboundedPerforatedOnConstructedCases) {
  const double M = 170.0, v0 = 10.0, k = 2e7;
  {
    Structure s = buildStructure(grid(1, 1, 1), oneMaterial(epp(1e13, 1e15), epp(k, 1e12), 1e9));
    Model model(s, Kinematics::XOnly);
    const ImpactResult r = runImpact(model, boulderAt(s, 0, 0, M, v0), quickRun(0.05, 0.02), 0, nullptr);
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_EQ(r.outcome, Outcome::Rebounded);
    EXPECT_NEAR(r.rebound_velocity_m_s, v0, 0.01 * v0);
    EXPECT_EQ(r.final_penetration_m, 0.0);  // (clear of the face)
  }
  {
    const double fy = 3000.0, v = 2.0;
    Structure s = buildStructure(grid(1, 1, 1), oneMaterial(epp(1e13, 1e15), epp(k, fy), 1e9));
    Model model(s, Kinematics::XOnly);
    const ImpactResult r = runImpact(model, boulderAt(s, 0, 0, M, v), quickRun(0.05, 0.02), 0, nullptr);
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_EQ(r.outcome, Outcome::Stopped);
    EXPECT_NEAR(r.rebound_velocity_m_s, fy / std::sqrt(k * M), 0.01 * fy / std::sqrt(k * M));
    EXPECT_NEAR(r.max_penetration_m, 0.5 * M * v * v / fy + 0.5 * fy / k, 0.01 * r.max_penetration_m);
  }
  {
    Structure s = buildStructure(grid(2, 1, 1), oneMaterial(epp(1e6, 1e3), epp(1e6, 1e3), 10.0));
    Model model(s, Kinematics::XOnly);
    const ImpactResult r = runImpact(model, boulderAt(s, 0, 0, 2000.0, 20.0), quickRun(0.05, 0.05), 0, nullptr);
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_EQ(r.outcome, Outcome::Perforated);
    EXPECT_NE(r.perforation.find("past the middle of front cell (0, 0, 0)"), std::string::npos) << r.perforation;
    // Its centre passed the cube's middle: it had sunk by its radius and
    // half an edge at least.
    EXPECT_GT(r.final_penetration_m, 0.5);
    EXPECT_GE(r.max_penetration_m, r.final_penetration_m);
  }
}

// A boulder that sinks into a cell by more than its radius is embedded, and
// the model follows it: the indentation goes on as the radius plus the
// centre's depth behind the front face, so against a rigidly held cube of
// impact law k, F_y it comes to rest at M v^2 / (2 F_y) + F_y / (2 k) (the
// same closed form as a shallow stop), here 0.35 m into a 0.5 m cube with
// R = 0.25 m; the energy balance holds across the front face (the force is
// continuous there). Aimed 0.1 m inside the open side of a one-cell-wide
// wall, its centre comes nearer that side than the front once 0.1 m deep: the
// cube no longer says where the fill pushes, and the impact is perforated.
// Aimed as close to the side of a cell whose side the next cell covers (a
// two-cell-wide wall; a little faster, as that cell resists too), it is
// followed to rest.
TEST(MacroOutcome, AnEmbeddedBoulderIsFollowedUntilTheCubeNoLongerHoldsIt) {
  const double M = 170.0, v = 10.0, k = 2e7, depth = 0.35;
  const double fy = 0.5 * M * v * v / depth;
  const auto run = [&](int ny, double aim_y, double speed) {
    Structure s = buildStructure(grid(1, ny, 1), oneMaterial(epp(1e13, 1e15), epp(k, fy), 1e9));
    Model model(s, Kinematics::XOnly);
    BoulderSpec b = boulderAt(s, 0, 0, M, speed);
    b.aim_y_m = aim_y;
    return runImpact(model, b, quickRun(0.1, 0.02), 0, nullptr);
  };
  const ImpactResult centred = run(1, 0.25, v);
  ASSERT_TRUE(centred.ok) << centred.message;
  EXPECT_EQ(centred.outcome, Outcome::Stopped) << centred.perforation;
  const double expected = 0.5 * M * v * v / fy + 0.5 * fy / k;
  EXPECT_NEAR(centred.max_penetration_m, expected, 0.01 * expected);
  EXPECT_GT(centred.max_indentation_m, 0.3);  // (embedded: deeper than the radius)
  EXPECT_LT(centred.balance_rel_error, 1e-3);

  const ImpactResult open = run(1, 0.1, v);
  ASSERT_TRUE(open.ok) << open.message;
  EXPECT_EQ(open.outcome, Outcome::Perforated);
  EXPECT_NE(open.perforation.find("came nearer an open side of front cell (0, 0, 0)"), std::string::npos)
      << open.perforation;

  const ImpactResult covered = run(2, 0.6, 1.2 * v);  // (the first cell resists too)
  ASSERT_TRUE(covered.ok) << covered.message;
  EXPECT_NE(covered.outcome, Outcome::Perforated) << covered.perforation;
  EXPECT_GT(covered.max_indentation_m, 0.25);  // (embedded in the cell it was aimed at)
}

// The results do not depend on the duration asked for: an impact runs to its
// outcome, past duration_s when it must, and stops there when it comes first.
TEST(MacroOutcome, MaximaAndOutcomeDoNotDependOnTheDuration) {
  Structure s = buildStructure(grid(3, 2, 2), oneMaterial(epp(2e7, 1e5), epp(2e7, 8e4), 183.0));
  std::vector<ImpactResult> r;
  for (const double duration : {0.02, 0.1, 0.4}) {
    Model model(s, Kinematics::XOnly);
    r.push_back(runImpact(model, boulderAt(s, 0, 0, 170.0, 15.0), quickRun(duration, 0.05), 0, nullptr));
    ASSERT_TRUE(r.back().ok) << r.back().message;
    EXPECT_NE(r.back().outcome, Outcome::Unfinished);
  }
  for (std::size_t i = 1; i < r.size(); ++i) {
    EXPECT_EQ(r[i].outcome, r[0].outcome);
    EXPECT_EQ(r[i].max_penetration_m, r[0].max_penetration_m);
    EXPECT_EQ(r[i].max_back_face_displacement_m, r[0].max_back_face_displacement_m);
    EXPECT_EQ(r[i].end_time_s, r[0].end_time_s);
    EXPECT_EQ(r[i].peak_force_N, r[0].peak_force_N);
  }
  EXPECT_GT(r[0].end_time_s, 0.02);  // (it ran past the shortest duration)
}

// A run that reaches no outcome within max_duration_s says so.
TEST(MacroOutcome, NoOutcomeWithinTheLongestRunIsUnfinished) {
  Structure s = buildStructure(grid(3, 1, 1), oneMaterial(epp(2e7, 1e5), epp(2e7, 8e4), 183.0));
  Model model(s, Kinematics::XOnly);
  RunSettings run = quickRun(0.001, 0.05);
  run.max_duration_s = 0.001;
  const ImpactResult r = runImpact(model, boulderAt(s, 0, 0, 170.0, 15.0), run, 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.outcome, Outcome::Unfinished);
  EXPECT_GE(r.end_time_s, 0.001);
  EXPECT_LT(r.end_time_s, 0.001 + r.time_step_s * 1.0001);
}

// A column of cells compressed far beyond yield by a heavy boulder stops
// shortening at its lock-up: each link ends within the dense spring's share
// of the force past u_L (F / k_L), far short of the crushing shortening, and
// the energy stays balanced (kinetic + elastic + plastic = the boulder's).
// Without a lock-up, twice that energy (which the column's plastic plateau
// would take over 4 m of travel) drives the column through.
TEST(MacroLockup, ColumnStopsShorteningAtItsLockup) {
  const double k = 1e7, fy = 5e4, uL = 0.125, kL = 1e8, M = 2000.0, v0 = 10.0;  // 100 kJ, ~4x the plastic work
  gabion::bridge::AxialLawParams axial = epp(k, fy);
  axial.lockup_shortening_m = uL;
  axial.lockup_stiffness_N_m = kL;
  const auto impact = epp(2e8, 1e12);  // a stiff elastic face: the column takes the work
  Structure s = buildStructure(grid(4, 1, 1), oneMaterial(axial, impact, 183.0));
  Model model(s, Kinematics::XOnly);
  model.placeBoulder(boulderAt(s, 0, 0, M, v0));
  const double dt = 0.05 * model.criticalTimeStep(), e0 = 0.5 * M * v0 * v0;
  const auto& links = s.axial;
  double max_short = 0.0, max_force = 0.0, max_err = 0.0;
  for (int i = 0; i < 40000 && model.boulderVelocity().x() >= 0.0; ++i) {
    ASSERT_EQ(model.step(dt), StepStatus::Ok) << model.failure();
    for (std::size_t l = 0; l < links.a.size(); ++l) {
      const auto a = static_cast<std::size_t>(links.a[l]);
      const double u = model.ux()[a] - (links.b[l] >= 0 ? model.ux()[static_cast<std::size_t>(links.b[l])] : 0.0);
      const double u_lock = links.b[l] >= 0 ? uL : 0.5 * uL;  // the back link is half a cell
      max_short = std::max(max_short, u / u_lock);
      max_force = std::max(max_force, model.axialForce()[l]);
    }
    max_err = std::max(max_err, std::abs(model.energy().total() - e0) / e0);
  }
  ASSERT_LT(model.boulderVelocity().x(), 0.0) << "the boulder must have been stopped";
  EXPECT_GT(max_short, 1.0);  // it did reach its lock-up ...
  // ... and stopped within the dense spring's share of the force beyond it
  // (in units of u_L; the back link's k_L is doubled, its u_L halved).
  EXPECT_LT(max_short, 1.0 + (max_force - fy) / kL / uL * 1.0001);
  EXPECT_LT(max_short, 1.0 + kCrushFraction * (s.edge_m - uL) / uL);
  EXPECT_LT(max_err, 0.01);

  Structure loose = buildStructure(grid(4, 1, 1), oneMaterial(epp(k, fy), impact, 183.0));
  Model free(loose, Kinematics::XOnly);
  const ImpactResult r =
      runImpact(free, boulderAt(loose, 0, 0, M, v0 * std::sqrt(2.0)), quickRun(0.2, 0.05), 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.outcome, Outcome::Perforated) << "without a lock-up the column is driven through";
}

// A cell pushed past its lock-up by more than kCrushFraction of what remains
// of it is crushed: the impact's outcome is perforated, and says which cell.
TEST(MacroLockup, CellCrushedBeyondItsLockupIsAPerforation) {
  gabion::bridge::AxialLawParams axial = epp(1e7, 5e4);
  axial.lockup_shortening_m = 0.125;
  axial.lockup_stiffness_N_m = 2e7;  // a soft dense fill: a heavy fast boulder crushes it
  Structure s = buildStructure(grid(2, 1, 1), oneMaterial(axial, epp(2e8, 1e12), 183.0));
  Model model(s, Kinematics::XOnly);
  const ImpactResult r = runImpact(model, boulderAt(s, 0, 0, 5000.0, 20.0), quickRun(0.2, 0.05), 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.outcome, Outcome::Perforated);
  EXPECT_NE(r.perforation.find("crushed beyond its lock-up"), std::string::npos) << r.perforation;
}

// Boulder-face friction and rotation (3-D): an oblique impact on an elastic
// face of an immovable cell, with friction low enough that the contact slides
// throughout (mu (1 + e) v_n < 2/7 v_t). Rigid-body impulses then give the
// exit state: the normal impulse J_n = 2 M v_n (elastic), the tangential one
// mu J_n, so v_t drops by 2 mu v_n and the spin is 5/2 mu J_n / (M R), the
// sphere's I = 2/5 M R^2. Tolerance 2 %: the tangential spring's brief stick
// at first touch and the discrete steps.
TEST(MacroBoulder, FaceFrictionSpinsAnObliqueBoulder) {
  const double M = 170.0, vn = 10.0, vt = 10.0, mu = 0.1;
  Structure s = buildStructure(grid(1, 3, 3), oneMaterial(epp(1e13, 1e15), epp(2e7, 1e12), 1e12));
  Model model(s, Kinematics::ThreeD);
  BoulderSpec b = boulderAt(s, 1, 1, M, vn);
  b.velocity_m_s = Vec3(vn, vt, 0.0);
  b.aim_y_m += 0.25;  // the path meets the face plane here; the sphere touches it R vt / vn earlier, mid-cube
  b.face_friction = mu;
  const ImpactResult r = runImpact(model, b, quickRun(0.05, 0.05), 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.outcome, Outcome::Rebounded);
  const double R = 0.5 * b.diameter_m;
  EXPECT_NEAR(r.final_velocity_m_s.x(), -vn, 0.01 * vn);
  EXPECT_NEAR(r.final_velocity_m_s.y(), vt - 2.0 * mu * vn, 0.02 * vt);
  EXPECT_NEAR(r.final_spin_rad_s, 2.5 * mu * 2.0 * vn / R, 0.02 * 2.5 * mu * 2.0 * vn / R);
  EXPECT_NEAR(
      r.friction_J,
      0.5 * M * (vt * vt - std::pow(vt - 2.0 * mu * vn, 2)) - 0.5 * 0.4 * M * R * R * std::pow(r.final_spin_rad_s, 2),
      0.03 * r.friction_J);
  EXPECT_LT(r.balance_rel_error, 1e-3);

  // Without friction the same impact neither spins nor slows sideways.
  Model smooth(s, Kinematics::ThreeD);
  b.face_friction = 0.0;
  const ImpactResult r0 = runImpact(smooth, b, quickRun(0.05, 0.05), 0, nullptr);
  ASSERT_TRUE(r0.ok) << r0.message;
  EXPECT_EQ(r0.final_spin_rad_s, 0.0);
  EXPECT_NEAR(r0.final_velocity_m_s.y(), vt, 1e-9 * vt);
}

// Gravity on the boulder (3-D): it falls while it flies and while it presses
// on the face; its potential energy enters the balance, which stays within
// 0.1 %. x-only kinematics refuse gravity.
TEST(MacroBoulder, GravityActsOnTheBoulderAndKeepsTheBalance) {
  Structure s = buildStructure(grid(2, 3, 3), oneMaterial(epp(1e7, 5e4), epp(2e7, 2e5), 183.0));
  Model model(s, Kinematics::ThreeD);
  BoulderSpec b = boulderAt(s, 1, 1, 170.0, 10.0);
  b.initial_gap_m = 0.5;  // 50 ms of flight before the face
  b.gravity_m_s2 = 9.81;
  const ImpactResult r = runImpact(model, b, quickRun(0.2, 0.05), 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NE(r.outcome, Outcome::Unfinished);
  EXPECT_LT(r.final_velocity_m_s.z(), -9.81 * 0.05);  // (at least the flight's fall)
  EXPECT_LT(r.potential_J, 0.0);
  EXPECT_LT(r.balance_rel_error, 1e-3);
  Model guided(s, Kinematics::XOnly);
  EXPECT_THROW(guided.placeBoulder(b), std::invalid_argument);
}

// A face that yields at once and locks up: its plastic indentation runs past
// the lock-up, and on the way back the dense fill alone pushes the boulder
// out (between u_L and u_p the elastic-plastic part is slack). The energy
// stays balanced through it and the boulder leaves with the dense spring's
// energy: 1/2 M v_r^2 = 1/2 k_L (u_max - u_L)^2 (the plastic part gives
// nothing back).
TEST(MacroLockup, DenseFillPushesTheBoulderBackPastTheDent) {
  const double M = 170.0, v0 = 10.0, uL = 0.05, kL = 4e8;
  gabion::bridge::AxialLawParams face = epp(4e7, 175.0);
  face.lockup_shortening_m = uL;
  face.lockup_stiffness_N_m = kL;
  Structure s = buildStructure(grid(1, 1, 1), oneMaterial(epp(1e13, 1e15), face, 1e9));
  Model model(s, Kinematics::XOnly);
  const ImpactResult r = runImpact(model, boulderAt(s, 0, 0, M, v0), quickRun(0.05, 0.05), 0, nullptr);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.outcome, Outcome::Rebounded);
  EXPECT_GT(model.frontPlastic()[0], uL);  // (the dent is deeper than the lock-up)
  EXPECT_LT(r.balance_rel_error, 2e-3);
  const double over = r.max_indentation_m - uL;
  EXPECT_NEAR(0.5 * M * r.rebound_velocity_m_s * r.rebound_velocity_m_s, 0.5 * kL * over * over,
              0.02 * 0.5 * kL * over * over);
}

// The hybrid structure's macro part (app/hybrid.cpp): a resolved cell gets
// no node; the node behind it meets it at its own front face, so its rear
// link spans its whole cell and half of the next (compliance 1/k + 1/(2k)),
// and against the back support its whole cell (1/k). An external force on
// the front node, as a resolved cell's plate exerts: the static shortening
// of the chain is F (3/(2k) + 1/(2k)) = 2F/k, about which the undamped chain
// oscillates; the external work balances the energy (the leapfrog counts the
// work of the step it has just taken: an error of F v dt).
TEST(MacroHybrid, AResolvedCellLeavesItsNeighbourTheWholeOfItsCell) {
  const double k = 1e7, mass = 200.0, F = 1e4;
  const auto laws = oneMaterial(epp(k, 1e9), epp(k, 1e9), mass);
  StructureSpec spec = grid(3, 1, 1);
  spec.resolved_cells = {0};
  const Structure s = buildStructure(spec, laws);
  ASSERT_EQ(s.nodeCount(), 2u);
  EXPECT_EQ(s.gi[0], 1);
  EXPECT_EQ(s.nodeAt(0, 0, 0), -1);
  EXPECT_TRUE(s.front.node.empty()) << "the boulder strikes the resolved cell, not a node";
  ASSERT_EQ(s.axial.a.size(), 2u);
  EXPECT_NEAR(s.axial_laws[static_cast<std::size_t>(s.axial.law[0])].stiffness_N_m, 2.0 * k / 3.0, 1e-6);
  EXPECT_NEAR(s.axial_laws[static_cast<std::size_t>(s.axial.law[1])].stiffness_N_m, 2.0 * k, 1e-6);

  Model m(s, Kinematics::XOnly);
  m.setExternalForce(0, Vec3(F, 123.0, 0.0));  // (x-only: the y component goes to the constraint)
  const double dt = 0.02 * m.criticalTimeStep();
  double umax = 0.0, worst = 0.0, lead = 0.0;
  for (int n = 0; n < 20000; ++n) {
    ASSERT_EQ(m.step(dt), StepStatus::Ok) << m.failure();
    umax = std::max(umax, m.ux()[0]);
    worst = std::max(worst, std::fabs(m.energy().total() - m.energy().external_work_J));
    lead = std::max(lead, std::fabs(F * m.vx()[0] * dt));  // the work of the step just taken
  }
  EXPECT_NEAR(umax, 2.0 * (2.0 * F / k), 0.02 * (2.0 * F / k)) << "twice the static shortening, from rest";
  EXPECT_GT(m.energy().external_work_J, 0.0);
  EXPECT_LT(worst, 1.01 * lead);
  EXPECT_LT(lead, 0.02 * F * 2.0 * F / k);
  // A macro base cell under a resolved one carries its weight to the
  // ground: its ground link's column is both cells (the resolved cell's
  // weight is held by the hybrid's plate, not by the node).
  StructureSpec stacked = grid(1, 1, 2);
  stacked.resolved_cells = {1};
  stacked.support.ground_friction = true;
  const Structure st = buildStructure(stacked, laws);
  ASSERT_EQ(st.nodeCount(), 1u);
  ASSERT_EQ(st.ground.node.size(), 1u);
  EXPECT_DOUBLE_EQ(st.ground.weight_N[0], 2.0 * mass * stacked.support.gravity_m_s2);
  // A resolved cell behind a macro cell of the front layer: that node
  // meets it at its rear face, where the hybrid's plate moves with it, and
  // has no link behind it (nor is it on the back face); with nothing else
  // on it, a force F accelerates it as F / m. Behind a macro cell with
  // another in front it is refused.
  StructureSpec behind = grid(2, 1, 1);
  behind.resolved_cells = {1};
  const Structure b = buildStructure(behind, laws);
  ASSERT_EQ(b.nodeCount(), 1u);
  EXPECT_TRUE(b.axial.a.empty());
  EXPECT_TRUE(b.back_nodes.empty());
  Model free(b, Kinematics::XOnly);
  free.setExternalForce(0, Vec3(F, 0.0, 0.0));
  const double step = 1e-5;
  for (int n = 0; n < 100; ++n) ASSERT_EQ(free.step(step), StepStatus::Ok) << free.failure();
  EXPECT_NEAR(free.vx()[0], F / mass * 100 * step, 1e-9 * F / mass * 100 * step);
  StructureSpec deeper = grid(3, 1, 1);
  deeper.resolved_cells = {2};
  EXPECT_THROW(buildStructure(deeper, laws), std::invalid_argument);
}

// Kinetic damping stops the nodes at each peak of the kinetic energy. A cell
// that has left the structure (the cells carry no tension) drifts with no
// force on it: its kinetic energy stays exactly constant, which is no
// decrease, and the relaxation must still take it as a peak and stop it
// instead of letting it drift until relax_max_steps.
TEST(MacroRelax, AFreeDriftingCellIsBroughtToRest) {
  const double k = 1e7, mass = 200.0;
  const auto laws = oneMaterial(epp(k, 1e9), epp(k, 1e9), mass);
  const Structure s = buildStructure(grid(2, 1, 1), laws);
  Model m(s, Kinematics::XOnly);
  const std::size_t front = static_cast<std::size_t>(s.nodeAt(0, 0, 0));
  const double dt = 0.05 * m.criticalTimeStep();
  m.setExternalForce(front, Vec3(-1e4, 0.0, 0.0));  // pulls the front cell out of the wall
  for (int n = 0; n < 200; ++n) ASSERT_EQ(m.step(dt), StepStatus::Ok) << m.failure();
  m.clearExternalForces();
  for (int n = 0; n < 10; ++n) ASSERT_EQ(m.step(dt), StepStatus::Ok) << m.failure();
  ASSERT_LT(m.vx()[front], -0.1) << "the front cell flies off";
  const double ke = m.energy().kinetic_J;
  ASSERT_GT(ke, 0.0);
  const double u0 = m.ux()[front], v0 = m.vx()[front];
  bool converged = false;
  const long long steps = relax(m, dt, 10000, 1e-12 * ke, converged);
  EXPECT_TRUE(converged) << steps << " steps, kinetic energy " << m.energy().kinetic_J << " J";
  EXPECT_LT(steps, 1000);
  EXPECT_EQ(m.vx()[front], 0.0);
  // It stopped within the first steps of the relaxation, not after a drift.
  EXPECT_LT(std::fabs(m.ux()[front] - u0), 3.0 * std::fabs(v0) * dt);

  // And a loaded structure still relaxes to its static state, not frozen
  // where a stop found it: a force F held on the front node shortens the
  // front-back link (k) and the back support (the back half cell, 2 k).
  Model held(s, Kinematics::XOnly);
  const double F = 1e4;
  held.setExternalForce(front, Vec3(F, 0.0, 0.0));
  const long long n = relax(held, dt, 200000, 1e-14 * F * F / k, converged);
  EXPECT_TRUE(converged) << n << " steps";
  EXPECT_NEAR(held.ux()[front], 1.5 * F / k, 1e-4 * F / k);
}
