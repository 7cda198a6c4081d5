// Wires that bend (bridge/laws/wire_beam.hpp): the beam's stiffness matrix,
// rigid motions that store nothing, the plastic hinge, and in the engine a
// cantilever's deflection against Euler-Bernoulli and its energy ledger.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "bridge/laws/wire_beam.hpp"
#include "micro/engine.hpp"
#include "micro/links.hpp"
#include "micro_test_util.hpp"

namespace {

using gabion::bridge::WireBeamParams;
using gabion::bridge::WireBeamState;
using gabion::micro::Engine;
using gabion::micro::LinkSpec;
using gabion::micro::Scene;
using gabion::micro::SphereSpec;
using gabion::micro::StepStatus;
using gabion::micro::Vec3;
using gabion::micro::test::kPi;
using gabion::micro::test::sphere;

// 2.7 mm wire of the default table: E = 130 GPa, yield 250 MPa.
constexpr double kE = 130e9, kYield = 250e6, kD = 0.0027;
const double kEI = kE * kPi * std::pow(kD, 4) / 64.0;

// One end turned by phi with the other held: 4 EI phi / L at the turned end,
// 2 EI phi / L at the held one, shear 6 EI phi / L^2; a sway delta: 12 EI
// delta / L^3 and end moments 6 EI delta / L^2 (the beam's stiffness matrix).
TEST(WireBeamLaw, TurnAndSwayGiveTheBeamStiffnessMatrix) {
  const double L = 0.05, phi = 1e-4, delta = 1e-5;
  const WireBeamParams p = gabion::bridge::wireBeam(kE, kYield, kD, L);
  const Vec3 n = Vec3::UnitX();
  {
    WireBeamState s;
    const auto r = gabion::bridge::wireBeamStep(p, s, L * n, L * n, Vec3::Zero(), Vec3(0, 0, phi));
    EXPECT_NEAR(r.torque_b.z(), -4 * kEI * phi / L, 1e-9 * kEI * phi / L);
    EXPECT_NEAR(r.torque_a.z(), -2 * kEI * phi / L, 1e-9 * kEI * phi / L);
    EXPECT_NEAR(r.force_b.y(), 6 * kEI * phi / (L * L), 1e-9 * kEI * phi / (L * L));
    // Work done = stored energy: (1/2) tau phi.
    EXPECT_NEAR(gabion::bridge::wireBeamElasticEnergy(p, s, n), 0.5 * 4 * kEI * phi * phi / L,
                1e-9 * kEI * phi * phi / L);
  }
  {
    WireBeamState s;
    const auto r = gabion::bridge::wireBeamStep(p, s, L * n, L * n + Vec3(0, delta, 0), Vec3::Zero(), Vec3::Zero());
    // (the sway turns the chord by delta / L: a relative change of order (delta / L)^2)
    EXPECT_NEAR(r.force_b.y(), -12 * kEI * delta / (L * L * L), 1e-6 * kEI * delta / (L * L * L));
    EXPECT_NEAR(r.torque_a.z(), 6 * kEI * delta / (L * L), 1e-6 * kEI * delta / (L * L));
    EXPECT_NEAR(r.torque_b.z(), 6 * kEI * delta / (L * L), 1e-6 * kEI * delta / (L * L));
  }
}

// One end spun by phi about the wire with the other held: the torsion G J
// phi / L = E I phi / ((1 + nu) L) on both ends (opposite), no shear, and
// the energy (1/2) k_t phi^2. Spun both together (the pair turning rigidly
// about the wire), nothing is stored: a bead keeps no free spin and gains
// no spurious one.
TEST(WireBeamLaw, SpinAboutTheWireGivesTheTorsionOfARoundWire) {
  const double L = 0.025, phi = 1e-4;
  const WireBeamParams p = gabion::bridge::wireBeam(kE, kYield, kD, L);
  const double kt = kEI / (1.3 * L);
  const Vec3 n = Vec3::UnitX();
  WireBeamState s;
  const auto r = gabion::bridge::wireBeamStep(p, s, L * n, L * n, Vec3::Zero(), Vec3(phi, 0, 0));
  EXPECT_NEAR(r.torque_b.x(), -kt * phi, 1e-9 * kt * phi);
  EXPECT_NEAR(r.torque_a.x(), kt * phi, 1e-9 * kt * phi);
  EXPECT_NEAR(r.force_b.norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.torque_b.y(), 0.0, 1e-12);
  EXPECT_NEAR(gabion::bridge::wireBeamElasticEnergy(p, s, n), 0.5 * kt * phi * phi, 1e-9 * kt * phi * phi);
  WireBeamState rigid;
  gabion::bridge::wireBeamStep(p, rigid, L * n, L * n, Vec3(phi, 0, 0), Vec3(phi, 0, 0));
  EXPECT_EQ(rigid.moment_N_m.norm(), 0.0);
}

// A bent beam turned rigidly (chord and both nodes by the same rotation, in
// many small increments) keeps its actions' sizes and turns them with it.
// The update is second-order accurate: 10,000 increments of 1.3e-4 rad
// change the stored energy by about 3e-6 of itself (1,000 of 1.3e-3: 3e-4).
TEST(WireBeamLaw, RigidRotationStoresNothingAndTurnsTheActions) {
  const double L = 0.05;
  const WireBeamParams p = gabion::bridge::wireBeam(kE, kYield, kD, L);
  WireBeamState s;
  gabion::bridge::wireBeamStep(p, s, L * Vec3::UnitX(), L * Vec3::UnitX(), Vec3::Zero(), Vec3(0, 0.001, 0));
  const double e0 = gabion::bridge::wireBeamElasticEnergy(p, s, Vec3::UnitX());
  const Vec3 axis = Vec3(1, 2, 3).normalized();
  const int n = 10000;
  const double total = 1.3;  // rad
  Vec3 chord = L * Vec3::UnitX();
  const Eigen::AngleAxisd inc(total / n, axis);
  for (int k = 0; k < n; ++k) {
    const Vec3 next = inc * chord;
    const Vec3 turn = axis * (total / n);
    gabion::bridge::wireBeamStep(p, s, chord, next, turn, turn);
    chord = next;
  }
  EXPECT_NEAR(gabion::bridge::wireBeamElasticEnergy(p, s, chord.normalized()), e0, 1e-5 * e0);
  WireBeamState ref;
  gabion::bridge::wireBeamStep(p, ref, L * Vec3::UnitX(), L * Vec3::UnitX(), Vec3::Zero(), Vec3(0, 0.001, 0));
  const Eigen::AngleAxisd all(total, axis);
  EXPECT_NEAR((s.moment_N_m - all * ref.moment_N_m).norm(), 0.0, 1e-3 * ref.moment_N_m.norm());
  EXPECT_NEAR((s.shear_N - all * ref.shear_N).norm(), 0.0, 1e-3 * ref.shear_N.norm());
}

// Turned far past its yield, the turned end's torque stays at M_p =
// sigma_y d^3 / 6 and the beam dissipates the work beyond what it stores.
TEST(WireBeamLaw, PlasticHingeHoldsThePlasticMomentAndDissipatesTheRest) {
  const double L = 0.05;
  const WireBeamParams p = gabion::bridge::wireBeam(kE, kYield, kD, L);
  const double Mp = kYield * kD * kD * kD / 6.0;
  EXPECT_DOUBLE_EQ(p.plastic_moment_N_m, Mp);
  WireBeamState s;
  const double dphi = 1e-4;
  double work = 0.0, tau = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const auto r =
        gabion::bridge::wireBeamStep(p, s, L * Vec3::UnitX(), L * Vec3::UnitX(), Vec3::Zero(), Vec3(0, 0, dphi));
    // work done on b: -(torque on b) . dphi (trapezoid over the increment)
    work += -0.5 * (tau + r.torque_b.z()) * dphi;
    tau = r.torque_b.z();
  }
  EXPECT_NEAR(-tau, Mp, 1e-9 * Mp);
  EXPECT_GT(s.dissipated_J, 0.0);
  EXPECT_NEAR(gabion::bridge::wireBeamElasticEnergy(p, s, Vec3::UnitX()) + s.dissipated_J, work, 2e-3 * work);
}

// The links' beam pass (micro/links.cpp) runs every beam through one
// vectorised loop that takes the twist's series, and hands back to the
// whole law (bridge::wireBeamStep) the increments the series cannot answer:
// a first call, a twist beyond 1e-3 rad, a wire of no length, a broken wire.
// A chain of 40 beams, moved and turned at random for 60 steps (a few
// turns large, some beams yielding, two wires broken on the way), against
// the whole law beam by beam: the same states and node sums, the links
// taken in two ranges as two workers take them. (Native builds may fuse
// multiply-adds in one loop and not the other: a few ulps.)
TEST(MicroWireBeam, TheVectorisedPassGivesTheWholeLawsAnswer) {
  using gabion::micro::Links;
  const int n = 41;
  const double L = 0.04;
  std::vector<LinkSpec> specs;
  for (int k = 0; k + 1 < n; ++k) {
    LinkSpec w;
    w.a = static_cast<std::size_t>(k), w.b = static_cast<std::size_t>(k + 1);
    w.law = LinkSpec::Law::Wire;
    w.wire.curve = gabion::bridge::wireCurve(gabion::bridge::defaultWireTable(), kD);
    w.wire.rest_length_m = L;
    w.beam = gabion::bridge::wireBeam(kE, kYield, kD, L);
    specs.push_back(w);
  }
  Links links(specs, n);
  std::vector<double> X(n), Y(n), Z(n), RX(n), RY(n), RZ(n);
  for (int k = 0; k < n; ++k) X[k] = k * L, Y[k] = Z[k] = 0.0;
  std::vector<WireBeamState> ref(n - 1);
  std::vector<Vec3> last(n - 1, Vec3::Zero());
  std::vector<bool> broken(n - 1, false);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  gabion::micro::WorkerScratch scratch;
  int large = 0, yielded = 0;
  for (int step = 0; step < 60; ++step) {
    for (int k = 0; k < n; ++k) {
      const double turn = k % 7 == 3 ? 4e-3 : 2e-4;  // (every 7th node beyond the series)
      RX[k] = turn * u(rng), RY[k] = turn * u(rng), RZ[k] = turn * u(rng);
      if (step > 0) X[k] += 2e-4 * u(rng), Y[k] += 2e-4 * u(rng), Z[k] += 2e-4 * u(rng);
    }
    if (step == 20) X[n - 1] += 0.5 * L, X[12] += 0.5 * L;  // (pulls wires 11 and 39 past rupture)
    // (in two ranges of links, as two workers take them)
    links.evaluateBeams(X.data(), Y.data(), Z.data(), RX.data(), RY.data(), RZ.data(), 0, 17, false, scratch);
    links.evaluateBeams(X.data(), Y.data(), Z.data(), RX.data(), RY.data(), RZ.data(), 17, links.size(), false,
                        scratch);
    std::vector<double> fx(n, 0.0), fy(n, 0.0), fz(n, 0.0), tx(n, 0.0), ty(n, 0.0), tz(n, 0.0);
    links.addNodeBeams(fx.data(), fy.data(), fz.data(), tx.data(), ty.data(), tz.data(), 0, n);
    std::vector<Vec3> f(n, Vec3::Zero()), t(n, Vec3::Zero());
    for (int l = 0; l + 1 < n; ++l) {
      if (broken[l]) continue;
      const Vec3 chord(X[l + 1] - X[l], Y[l + 1] - Y[l], Z[l + 1] - Z[l]);
      const bool started = last[l].squaredNorm() > 0.0;
      const Vec3 ta = started ? Vec3(RX[l], RY[l], RZ[l]) : Vec3::Zero(),
                 tb = started ? Vec3(RX[l + 1], RY[l + 1], RZ[l + 1]) : Vec3::Zero();
      const double before = ref[l].dissipated_J;
      const auto r = gabion::bridge::wireBeamStep(specs[l].beam, ref[l], started ? last[l] : chord, chord, ta, tb);
      large += started && (ta + tb).norm() > 2e-3;
      yielded += ref[l].dissipated_J > before;
      last[l] = chord;
      f[l] -= r.force_b, f[l + 1] += r.force_b, t[l] += r.torque_a, t[l + 1] += r.torque_b;
    }
    for (int l = 0; l + 1 < n; ++l) {
      const WireBeamState got = links.beamState(static_cast<std::size_t>(l));
      const double scale = ref[l].shear_N.norm() + ref[l].moment_N_m.norm() / L + 1e-30;
      EXPECT_LE((got.shear_N - ref[l].shear_N).norm(), 1e-12 * scale) << "beam " << l << ", step " << step;
      EXPECT_LE((got.moment_N_m - ref[l].moment_N_m).norm(), 1e-12 * scale * L) << "beam " << l << ", step " << step;
      EXPECT_LE(std::fabs(got.dissipated_J - ref[l].dissipated_J), 1e-12 * (ref[l].dissipated_J + 1e-30));
    }
    for (int k = 0; k < n; ++k) {
      const double scale = f[k].norm() + t[k].norm() / L + 1e-30;
      EXPECT_LE((Vec3(fx[k], fy[k], fz[k]) - f[k]).norm(), 1e-11 * scale) << "node " << k << ", step " << step;
      EXPECT_LE((Vec3(tx[k], ty[k], tz[k]) - t[k]).norm(), 1e-11 * scale * L) << "node " << k << ", step " << step;
    }
    // The sub-steps' axial pass: a wire pulled past its rupture breaks, and
    // its bending goes with it.
    links.evaluate(X.data(), Y.data(), Z.data(), 0, links.size(), 0.0, false, scratch);
    for (int l = 0; l + 1 < n; ++l)
      if (links.broken(static_cast<std::size_t>(l)) && !broken[l]) {
        broken[l] = true;
        ref[l].shear_N.setZero(), ref[l].moment_N_m.setZero();
      }
  }
  EXPECT_TRUE(broken[11] && broken[39]);
  EXPECT_EQ(std::count(broken.begin(), broken.end(), true), 2);
  EXPECT_GT(large, 100);  // (increments the series cannot answer)
  EXPECT_GT(yielded, 10);
}

// A wire cantilever of n segments along x, clamped at the root (a fixed
// node: it neither moves nor turns), loaded by gravity on its lumped node
// masses. Beam elements with nodal loads give Euler-Bernoulli's nodal
// deflections exactly: the tip's is sum_i P_i x_i^2 (3 L - x_i) / (6 E I).
Scene cantilever(int n, double L, double node_mass, double damping) {
  Scene s;
  s.materials = {gabion::micro::test::material(1e5, 2.5e4, 0.5, 0.0, damping)};
  s.gravity_m_s2 = Vec3(0, 0, -9.81);
  for (int j = 0; j <= n; ++j) {
    SphereSpec sp = sphere(Vec3(j * L / n, 0, 0), 0.002, j == 0);
    sp.mass_kg = node_mass;
    s.spheres.push_back(sp);
  }
  const gabion::bridge::WireCurve curve = gabion::bridge::wireCurve(gabion::bridge::defaultWireTable(), kD);
  for (int j = 0; j < n; ++j) {
    LinkSpec l;
    l.a = j, l.b = j + 1;
    l.law = LinkSpec::Law::Wire;
    l.wire.curve = curve;
    l.wire.rest_length_m = L / n;
    l.beam = gabion::bridge::wireBeam(kE, kYield, kD, L / n);
    s.links.push_back(l);
  }
  s.no_contact_groups = {{0, 0}};
  return s;
}

TEST(MicroWireBeam, CantileverDeflectsAsEulerBernoulli) {
  const int n = 8;
  const double L = 0.2, m = 0.004;
  Scene s = cantilever(n, L, m, 0.3);
  Engine e(s, 1);
  e.setDt(s.run.dt_safety * e.criticalDt());
  double expected = 0.0;
  for (int j = 1; j <= n; ++j) {
    const double x = j * L / n, P = m * 9.81;
    expected += P * x * x * (3 * L - x) / (6 * kEI);
  }
  for (int k = 0; k < 200000 && e.time() < 3.0; ++k) ASSERT_EQ(e.step(false), StepStatus::Ok) << e.failure();
  const double tip = -e.body(n).position_m.z();
  // small deformation (tip rotation ~ 0.1 rad): geometric stiffening below 1 %
  EXPECT_NEAR(tip, expected, 0.01 * expected) << "tip deflection " << tip << " m, Euler-Bernoulli " << expected;
}

// Undamped, the same cantilever swings under gravity: kinetic, gravity and
// the beams' stored energy exchange with a ledger that closes. The ledger's
// drift is measured against the largest energy the beams stored (at the top
// of each swing the energy moved is nearly zero, and a relative error there
// is rounding over nothing).
TEST(MicroWireBeam, SwingingCantileverKeepsItsEnergy) {
  Scene s = cantilever(8, 0.2, 0.004, 0.0);
  Engine e(s, 1);
  e.setDt(s.run.dt_safety * e.criticalDt());
  double e0 = 0.0, drift = 0.0, stored = 0.0;
  for (int k = 0; e.time() < 0.5; ++k) {
    ASSERT_EQ(e.step(k % 20 == 0), StepStatus::Ok) << e.failure();
    if (k % 20) continue;
    if (k == 0) e0 = e.energy().total_J;
    drift = std::max(drift, std::fabs(e.energy().total_J - e0));
    stored = std::max(stored, e.energy().elastic_link_J);
  }
  EXPECT_GT(stored, 0.0);
  EXPECT_LT(drift, 1e-3 * stored);
}

}  // namespace
