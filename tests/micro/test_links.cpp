// The link stage and contact groups: a chain's analytic frequency, partners
// that survive the re-sort, rupture recorded once, pairs that never touch.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "micro/cell/cell_file.hpp"
#include "micro/engine.hpp"
#include "micro/scene_run.hpp"
#include "micro_test_util.hpp"

namespace {

using gabion::micro::Engine;
using gabion::micro::LinkSpec;
using gabion::micro::Scene;
using gabion::micro::SphereSpec;
using gabion::micro::StepStatus;
using gabion::micro::Vec3;
using gabion::micro::WallProgram;
using gabion::micro::WallSpec;
using gabion::micro::test::kPi;
using gabion::micro::test::sphere;
const auto rock = [] { return gabion::micro::test::material(); };

LinkSpec link(std::size_t a, std::size_t b, double k, double rest, double rupture = INFINITY) {
  LinkSpec l;
  l.a = a;
  l.b = b;
  l.linear.stiffness_N_m = k;
  l.linear.rest_length_m = rest;
  l.linear.rupture_strain = rupture;
  return l;
}

// N free masses between two fixed ends, joined by springs k: the lowest
// longitudinal mode has omega_1 = 2 sqrt(k / m) sin(pi / (2 (N + 1))). The
// chain starts in that mode's shape at rest; the middle mass crosses its rest
// position every half period. Leapfrog's period error is (omega dt)^2 / 24 ~ 2e-4 here.
TEST(MicroLinks, ChainOscillatesAtItsAnalyticFrequency) {
  constexpr int N = 5;
  const double k = 1e3, L0 = 0.05, r = 0.005, amp = 1e-3;
  Scene s;
  s.gravity_m_s2.setZero();
  s.materials = {rock()};
  s.spheres.push_back(sphere(Vec3(0, 0, 0), r, true));
  for (int j = 1; j <= N; ++j) s.spheres.push_back(sphere(Vec3(j * L0 + amp * std::sin(j * kPi / (N + 1)), 0, 0), r));
  s.spheres.push_back(sphere(Vec3((N + 1) * L0, 0, 0), r, true));
  for (int j = 0; j <= N; ++j) s.links.push_back(link(j, j + 1, k, L0));
  Engine e(s, 1);
  const double m = 2500.0 * 4.0 / 3.0 * kPi * r * r * r;
  const double omega = 2.0 * std::sqrt(k / m) * std::sin(kPi / (2.0 * (N + 1)));
  e.setDt(2.0 * kPi / omega / 400.0);
  ASSERT_LT(e.dt(), e.criticalDt());
  const int mid = (N + 1) / 2;
  double last = e.body(mid).position_m.x() - mid * L0, first_cross = -1.0, last_cross = -1.0;
  int crossings = 0;
  while (crossings < 9) {
    ASSERT_EQ(e.step(false), StepStatus::Ok) << e.failure();
    const double u = e.body(mid).position_m.x() - mid * L0;
    if ((u > 0) != (last > 0)) {
      // linear interpolation of the crossing time
      const double t = e.time() - e.dt() * u / (u - last);
      if (crossings == 0) first_cross = t;
      last_cross = t;
      ++crossings;
    }
    last = u;
  }
  const double period = 2.0 * (last_cross - first_cross) / (crossings - 1);
  EXPECT_NEAR(period, 2.0 * kPi / omega, 1e-3 * 2.0 * kPi / omega);
  EXPECT_EQ(e.contactCount(), 0u);  // linked neighbours never touch through the contact law
}

// A gas of spheres in a box with random links: the re-sorts at each list
// rebuild move the particles in memory, but every link keeps its partners.
// The tension of each link, computed by the engine at a step, equals
// k (|x_b - x_a| - L0) from the positions of the spheres the link names,
// taken by their input index before that step.
TEST(MicroLinks, ResortingKeepsEveryLinksPartners) {
  Scene s;
  s.gravity_m_s2.setZero();
  s.materials = {rock()};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.002, 0.002), vel(-0.5, 0.5);
  for (int i = 0; i < 300; ++i) {  // a jittered lattice, 0.04 m apart
    const Vec3 c(0.03 + 0.04 * (i % 7), 0.03 + 0.04 * ((i / 7) % 7), 0.02 + 0.04 * (i / 49));
    SphereSpec sp = sphere(c + Vec3(jitter(rng), jitter(rng), jitter(rng)), i % 10 == 0 ? 0.008 : 0.003);
    sp.velocity_m_s = Vec3(vel(rng), vel(rng), vel(rng));
    s.spheres.push_back(sp);
  }
  std::uniform_int_distribution<std::size_t> pick(0, 299);
  for (int l = 0; l < 60; ++l) {
    const std::size_t a = pick(rng), b = (a + 1 + pick(rng) % 298) % 300;
    s.links.push_back(link(a, b, 10.0, 0.1));
  }
  for (int f = 0; f < 3; ++f) {  // a closed box
    gabion::micro::WallSpec lo, hi;
    lo.normal = Vec3::Unit(f);
    hi.point_m = Vec3::Constant(0.3);
    hi.normal = -Vec3::Unit(f);
    s.walls.push_back(lo);
    s.walls.push_back(hi);
  }
  Engine e(s, 2);
  e.setDt(0.2 * e.criticalDt());
  for (int n = 0; n < 3000; ++n) {
    std::vector<Vec3> x(300);
    for (std::size_t i = 0; i < 300; ++i) x[i] = e.body(i).position_m;
    ASSERT_EQ(e.step(false), StepStatus::Ok) << e.failure();
    if (n % 100 != 99) continue;
    for (std::size_t l = 0; l < e.linkCount(); ++l) {
      const auto [a, b] = e.linkEnds(l);
      ASSERT_EQ(a, s.links[l].a);
      ASSERT_EQ(b, s.links[l].b);
      EXPECT_NEAR(e.linkTension(l), 10.0 * ((x[b] - x[a]).norm() - 0.1), 1e-12) << "link " << l;
    }
  }
  EXPECT_GE(e.neighbourRebuilds(), 3u);
  EXPECT_EQ(e.sizeClassCount(), 2);
}

// Two spheres fly apart on a link that breaks at 10 % strain: once broken it
// stops acting (the spheres then move at constant velocity), its event is
// recorded once (time, link, midpoint), and the energy it held is counted as
// dissipated (the balance holds).
TEST(MicroLinks, BrokenLinkStopsActingAndIsRecordedOnce) {
  Scene s;
  s.gravity_m_s2.setZero();
  s.materials = {rock()};
  SphereSpec a = sphere(Vec3(0, 0, 0), 0.005), b = sphere(Vec3(0.05, 0, 0), 0.005);
  a.velocity_m_s = Vec3(-1, 0, 0);
  b.velocity_m_s = Vec3(1, 0, 0);
  s.spheres = {a, b};
  s.links = {link(0, 1, 50.0, 0.05, 0.1)};
  Engine e(s, 1);
  e.setDt(0.05 * e.criticalDt());
  while (!e.linkBroken(0)) {
    ASSERT_EQ(e.step(true), StepStatus::Ok) << e.failure();
    ASSERT_LT(e.time(), 1.0) << "the link never broke";
  }
  ASSERT_EQ(e.linkEvents().size(), 1u);
  const auto ev = e.linkEvents()[0];
  EXPECT_EQ(ev.link, 0u);
  EXPECT_NEAR(ev.time_s, e.time() - e.dt(), 1e-12);
  EXPECT_NEAR(ev.position_m.x(), 0.025, 1e-9);  // symmetric: the midpoint stays put
  const Vec3 v = e.body(1).velocity_m_s;
  for (int n = 0; n < 1000; ++n) ASSERT_EQ(e.step(n == 999), StepStatus::Ok);
  EXPECT_EQ(e.body(1).velocity_m_s, v);
  EXPECT_EQ(e.linkTension(0), 0.0);
  EXPECT_EQ(e.linkEvents().size(), 1u);
  EXPECT_GT(e.energy().link_rupture_dissipation_J, 0.0);
  EXPECT_LT(std::fabs(e.energy().balance_rel_error), 1e-3);
}

// Overlapping spheres in a pair of groups that never touch, and an
// overlapping linked pair (the link at its rest length): no force at all.
// The same pair in touching groups is pushed apart (the control).
TEST(MicroLinks, ExcludedPairsFeelNoForce) {
  for (const bool excluded : {true, false}) {
    Scene s;
    s.gravity_m_s2.setZero();
    s.materials = {rock()};
    SphereSpec a = sphere(Vec3(0, 0, 0), 0.01), b = sphere(Vec3(0.017, 0, 0), 0.01);
    a.group = 1;
    b.group = 2;
    s.spheres = {a, b, sphere(Vec3(1, 0, 0), 0.01), sphere(Vec3(1.017, 0, 0), 0.01)};
    s.links = {link(2, 3, 1e3, (s.spheres[3].center_m - s.spheres[2].center_m).norm())};
    if (excluded) s.no_contact_groups = {{1, 2}};
    Engine e(s, 1);
    e.setDt(0.1 * e.criticalDt());
    for (int n = 0; n < 100; ++n) ASSERT_EQ(e.step(false), StepStatus::Ok);
    EXPECT_EQ(e.body(2).velocity_m_s.norm(), 0.0);  // the linked pair never touches
    if (excluded) {
      EXPECT_EQ(e.body(0).velocity_m_s.norm(), 0.0);
      EXPECT_EQ(e.contactCount(), 0u);
    } else {
      EXPECT_LT(e.body(0).velocity_m_s.x(), 0.0);
    }
  }
}

}  // namespace

namespace {

// The link nodes' sub-steps (micro/linked_nodes.hpp). Without contacts, a
// step of dt in n sub-steps is n leapfrog steps of dt / n: the chain of the
// test above, run both ways, is at the same place (to rounding).
TEST(MicroLinkSubsteps, WithoutContactsTheyAreLeapfrogAtTheSubStep) {
  constexpr int N = 5;
  const double k = 1e3, L0 = 0.05, r = 0.005, amp = 1e-3;
  Scene s;
  s.gravity_m_s2 = Vec3(0, 0, -9.81);
  s.materials = {rock()};
  s.spheres.push_back(sphere(Vec3(0, 0, 0), r, true));
  for (int j = 1; j <= N; ++j) s.spheres.push_back(sphere(Vec3(j * L0 + amp * std::sin(j * kPi / (N + 1)), 0, 0), r));
  s.spheres.push_back(sphere(Vec3((N + 1) * L0, 0, 0), r, true));
  for (int j = 0; j <= N; ++j) s.links.push_back(link(j, j + 1, k, L0));
  Engine fine(s, 1), coarse(s, 1);
  const double h = s.run.dt_safety * fine.linkCriticalDt();
  fine.setDt(h);
  coarse.setDt(20 * h);
  ASSERT_EQ(fine.linkSubsteps(), 1);
  ASSERT_EQ(coarse.linkSubsteps(), 20);
  for (int n = 0; n < 2000; ++n) ASSERT_EQ(fine.step(false), StepStatus::Ok);
  for (int n = 0; n < 100; ++n) ASSERT_EQ(coarse.step(false), StepStatus::Ok);
  for (int j = 1; j <= N; ++j)
    EXPECT_NEAR((fine.body(j).position_m - coarse.body(j).position_m).norm(), 0.0, 1e-12) << "node " << j;
}

// What a run costs before it runs counts the links' stage: each link at each
// of the link nodes' sub-steps, on top of the body-steps (the same chain at
// the coarse step: 20 sub-steps).
TEST(MicroLinkSubsteps, TheCostEstimateCountsEachLinkAtEachSubStep) {
  constexpr int N = 5;
  const double k = 1e3, L0 = 0.05, r = 0.005;
  Scene s;
  s.materials = {rock()};
  s.spheres.push_back(sphere(Vec3(0, 0, 0), r, true));
  for (int j = 1; j <= N; ++j) s.spheres.push_back(sphere(Vec3(j * L0, 0, 0), r));
  s.spheres.push_back(sphere(Vec3((N + 1) * L0, 0, 0), r, true));
  for (int j = 0; j <= N; ++j) s.links.push_back(link(j, j + 1, k, L0));
  s.run.duration_s = 1.0;
  Engine e(s, 1);
  const double dt = 20 * s.run.dt_safety * e.linkCriticalDt();
  e.setDt(dt);
  ASSERT_EQ(e.linkSubsteps(), 20);
  const double steps = std::ceil(1.0 / dt), bodies = N + 2.0, links = N + 1.0;
  const gabion::bridge::Estimate est = gabion::micro::sceneEstimate(s, dt);
  EXPECT_EQ(est.steps, steps);
  EXPECT_NEAR(est.wall_time_s,
              gabion::bridge::kMicroSecondsPerBodyStep * bodies * steps +
                  gabion::bridge::kMicroSecondsPerLinkSubstep * links * 20.0 * steps,
              1e-12 * est.wall_time_s);
  s.links.clear();
  EXPECT_NEAR(gabion::micro::sceneEstimate(s, dt).wall_time_s,
              gabion::bridge::kMicroSecondsPerBodyStep * bodies * steps, 1e-12 * est.wall_time_s);
}

// run.link_dt_safety sets the sub-steps apart from run.dt_safety: four times
// the fraction, a quarter of the sub-steps, in the engine and in the cost
// estimate alike; beyond 1 it is refused.
TEST(MicroLinkSubsteps, TheirFractionOfTheCriticalStepIsItsOwn) {
  Scene s;
  s.materials = {rock()};
  s.spheres = {sphere(Vec3(0, 0, 0), 0.005, true), sphere(Vec3(0.05, 0, 0), 0.005)};
  s.links = {link(0, 1, 1e3, 0.05)};
  s.run.duration_s = 1.0;
  Engine probe(s, 1);
  const double dt = 20 * s.run.dt_safety * probe.linkCriticalDt();
  s.run.link_dt_safety = 4.0 * s.run.dt_safety;
  Engine e(s, 1);
  e.setDt(dt);
  EXPECT_EQ(e.linkSubsteps(), 5);
  const double steps = std::ceil(1.0 / dt);
  EXPECT_NEAR(gabion::micro::sceneEstimate(s, dt).wall_time_s,
              gabion::bridge::kMicroSecondsPerBodyStep * 2.0 * steps +
                  gabion::bridge::kMicroSecondsPerLinkSubstep * 5.0 * steps,
              1e-9 * steps);
  s.run.link_dt_safety = 1.5;
  try {
    gabion::micro::validateScene(s, "fraction.json");
    ADD_FAILURE() << "a link_dt_safety over 1 was not refused";
  } catch (const gabion::bridge::InputError& x) {
    EXPECT_EQ(x.pointer(), "/run/link_dt_safety");
  }
}

// The rates hold while a scene fits the core's cache (about one cell's
// bodies) and grow with the bodies past that, as measured on one cell and
// on the resolved 12-cell and 54-cell walls (bridge/cost.hpp): the walls'
// step loops, 12.0 and 64.6 ms a step on one thread there (109,549 bodies
// and 18,936 links; 492,967 and 85,212; 8 sub-steps), are estimated within
// 5 %, where the one-cell rates gave half.
TEST(MicroCost, TheRatesGrowWithTheSceneOutOfTheCache) {
  using namespace gabion::bridge;
  EXPECT_EQ(microSecondsPerBodyStep(9129.0), kMicroSecondsPerBodyStep);
  EXPECT_EQ(microSecondsPerLinkSubstep(9129.0), kMicroSecondsPerLinkSubstep);
  const auto step = [](double bodies, double links) {
    return microRun(bodies, 1.0, 1.0, 1.0, 1.0, 8.0 * links).wall_time_s;
  };
  EXPECT_NEAR(step(109549.0, 18936.0), 12.0e-3, 0.05 * 12.0e-3);
  EXPECT_NEAR(step(492967.0, 85212.0), 64.6e-3, 0.05 * 64.6e-3);
  EXPECT_LT(kMicroSecondsPerBodyStep * 109549.0 + kMicroSecondsPerLinkSubstep * 8.0 * 18936.0, 0.55 * 12.0e-3);
  EXPECT_GT(microSecondsPerBodyStep(1e6), microSecondsPerBodyStep(1e5));
}

// A stone dropped on a taut chain of stiff wires clamped at both ends: the
// contact sets the step, the wires take 20 sub-steps of it. The held contact
// force gives its impulse at the start of the step (r-RESPA), so the energy
// ledger closes as it does without sub-steps (a force held over the sub-steps
// would arrive half a step late and feed energy into the bounce), and the
// stone comes to rest where it does with the wires' own step.
TEST(MicroLinkSubsteps, StoneOnAWireChainKeepsTheEnergyAndTheRestingPlace) {
  constexpr int N = 9;
  const double L0 = 0.05, r = 0.006, k_wire = 2e7;
  Scene s;
  s.materials = {rock()};
  s.materials[0].local_damping = 0.3;
  s.spheres.push_back(sphere(Vec3(0, 0, 0), r, true));
  for (int j = 1; j <= N; ++j) {
    SphereSpec n = sphere(Vec3(j * L0, 0, 0), r);
    n.mass_kg = 0.005;
    s.spheres.push_back(n);
  }
  s.spheres.push_back(sphere(Vec3((N + 1) * L0, 0, 0), r, true));
  for (int j = 0; j <= N; ++j) s.links.push_back(link(j, j + 1, k_wire, 0.999 * L0));  // pre-tensioned
  const std::size_t stone = s.spheres.size();
  s.spheres.push_back(sphere(Vec3(5 * L0, 0, 0.08), 0.03));
  const auto run = [&](double dt, int& substeps, double& balance) {
    Engine e(s, 1);
    e.setDt(dt);
    substeps = e.linkSubsteps();
    const auto steps = static_cast<long long>(0.6 / dt);
    for (long long n = 0; n < steps; ++n) {
      const StepStatus st = e.step(n + 1 == steps || n % 50 == 0);
      if (st != StepStatus::Ok) ADD_FAILURE() << e.failure();
      if (st != StepStatus::Ok) break;
      balance = std::max(balance, std::fabs(e.energy().balance_rel_error));
    }
    return e.body(stone).position_m.z();
  };
  Engine probe(s, 1);
  const double h = s.run.dt_safety * probe.linkCriticalDt(), dt = s.run.dt_safety * probe.criticalDt();
  ASSERT_GT(dt / h, 15.0);
  int n_fine = 0, n_coarse = 0;
  double b_fine = 0.0, b_coarse = 0.0;
  const double z_fine = run(h, n_fine, b_fine), z_coarse = run(dt, n_coarse, b_coarse);
  EXPECT_EQ(n_fine, 1);
  EXPECT_GT(n_coarse, 15);
  // The stone rests on the chain (radii 0.03 + 0.006 above it), which sags.
  const double sag = 0.036 - z_fine;
  EXPECT_GT(sag, 1e-4);
  EXPECT_LT(b_fine, 1e-3);
  EXPECT_LT(b_coarse, 1e-3);
  EXPECT_NEAR(z_coarse, z_fine, 0.01 * sag)
      << "fine " << z_fine << " coarse " << z_coarse << "; balance fine " << b_fine << " coarse " << b_coarse;
}

// A fixed sphere that rides a wall (SphereSpec::rides_wall: a point of a
// plate a lacing wire is tied to) moves with it exactly, and its link pulls
// the wall: the wall's force at each step is the link's force on the rider
// at the step before (the link acts inside the step, after the wall moved).
// The wall swings along y by a sinusoid (10 mm at 5 Hz) and drags a free
// sphere on a spring (44 Hz, one sub-step, omega dt 0.006): the rider's
// place is the program's closed form to round-off (10,000 increments of at
// most 7e-6 m: error ~ 1e-18 m each), the force the spring's law to
// round-off, and the energy the wall pumps in is the riders' driven work
// (leapfrog's balance error ~ (omega dt)^2 = 4e-5; the bound is 1e-3).
TEST(MicroLinks, ASphereThatRidesAWallMovesWithItAndPullsIt) {
  const double k = 100.0, L0 = 0.05, r = 0.005, amp = 0.01, f = 5.0;
  Scene s;
  s.gravity_m_s2.setZero();
  s.materials = {rock()};
  WallSpec plate;
  plate.name = "plate";
  plate.point_m = Vec3(-1.0, 0, 0);  // (far from both spheres: no contact)
  plate.normal = Vec3::UnitX();
  plate.program.kind = WallProgram::Kind::Sinusoid;
  plate.program.direction = Vec3::UnitY();
  plate.program.amplitude_m = amp;
  plate.program.frequency_hz = f;
  s.walls = {plate};
  SphereSpec rider = sphere(Vec3(0, 0, 0), r, true);
  rider.rides_wall = 0;
  s.spheres = {rider, sphere(Vec3(L0 + 0.002, 0, 0), r)};
  s.links = {link(0, 1, k, L0)};
  Engine e(s, 1);
  e.setDt(2e-5);
  ASSERT_EQ(e.linkSubsteps(), 1);
  Vec3 expected = Vec3::Zero();  // the link's force on the rider at the last step
  double worst_place = 0.0, worst_force = 0.0, worst_balance = 0.0, pull = 0.0;
  for (int n = 0; n < 10000; ++n) {
    const Vec3 a = e.body(0).position_m, b = e.body(1).position_m;  // (the step's start: where the link acts)
    ASSERT_EQ(e.step(n % 50 == 0), StepStatus::Ok) << e.failure();
    worst_force = std::max(worst_force, (e.wallForce(0) - expected).norm());
    pull = std::max(pull, std::fabs(e.wallForce(0).y()));
    const Vec3 d = b - a;
    expected = k * (d.norm() - L0) * d.normalized();
    const Vec3 at = Vec3(0, amp * std::sin(2.0 * kPi * f * e.time()), 0);
    worst_place = std::max(worst_place, (e.body(0).position_m - at).norm());
    if (n % 50 == 0) worst_balance = std::max(worst_balance, std::fabs(e.energy().balance_rel_error));
  }
  EXPECT_LT(worst_place, 1e-12);
  EXPECT_LT(worst_force, 1e-9 * k * amp);
  EXPECT_GT(pull, 0.01 * k * amp) << "the spring pulls the plate along y";
  EXPECT_GT(e.energy().kinetic_translational_J + e.energy().elastic_link_J, 1e-4 * k * amp * amp)
      << "the plate pumped energy into the sphere";
  EXPECT_LT(worst_balance, 1e-3);
  EXPECT_NE(e.energy().driven_work_J, 0.0);

  // A sphere that rides must be fixed, an end of a link, on a wall that exists.
  const auto refused = [&](Scene bad, const std::string& why) {
    try {
      gabion::micro::validateScene(bad, "rides.json");
      ADD_FAILURE() << why << ": not refused";
    } catch (const gabion::bridge::InputError& x) {
      EXPECT_EQ(x.pointer(), "/spheres/0/rides_wall") << why;
    }
  };
  Scene loose = s;
  loose.spheres[0].fixed = false;
  refused(loose, "not fixed");
  Scene unlinked = s;
  unlinked.links.clear();
  refused(unlinked, "no link");
  Scene nowhere = s;
  nowhere.spheres[0].rides_wall = 1;
  refused(nowhere, "no such wall");
}

// A lacing wire pulled tight (LinkSpec::pull_force_N): a node held by a
// soft spring (1 kN/m) is laced to a fixed point 0.1 m away, the wire
// pulled with 50 N. It slides through its loops under that tension, its
// law waiting, and the node, damped (local damping 0.7: a pull that comes
// on at once throws a lightly damped node past the spring's place, as a
// step load does), comes to rest where the spring carries it: 50 mm
// closer. The pull's work, 50 N times the 50 mm closed, is the ledger's
// driven work, which closes to 1e-3. Taken from the engine as a state, the
// wire is tied at the distance it closed to, no longer pulled. Pulled with
// 100 N, which the spring never reaches (80 N at most), it closes to its
// shortest length, 20 mm, and is tied there: its law acts from then on.
TEST(MicroLinks, AWirePulledTightClosesUntilItCarriesThePull) {
  const auto run = [](double force_N, double& rest, double& x, double& work, double& balance, Scene& state) {
    Scene s;
    s.gravity_m_s2.setZero();
    s.materials = {rock()};
    s.materials[0].local_damping = 0.7;
    SphereSpec node = sphere(Vec3(0.1, 0, 0), 0.005);
    node.mass_kg = 0.01;
    s.spheres = {sphere(Vec3(0, 0, 0), 0.005, true), node, sphere(Vec3(0.2, 0, 0), 0.005, true)};
    LinkSpec wire;
    wire.a = 0, wire.b = 1;
    wire.law = LinkSpec::Law::Wire;
    wire.wire.curve = gabion::bridge::wireCurve(gabion::bridge::defaultWireTable(), 0.0022);
    wire.wire.rest_length_m = 0.1;
    wire.pull_force_N = force_N, wire.pull_min_m = 0.02;
    s.links = {wire, link(1, 2, 1e3, 0.1)};
    Engine e(s, 1);
    e.setDt(0.2 * e.criticalDt());
    const auto steps = static_cast<int>(0.6 / e.dt());
    for (int n = 0; n < steps; ++n) {
      ASSERT_EQ(e.step(n % 100 == 0 || n + 1 == steps), StepStatus::Ok) << e.failure();
      balance = std::max(balance, std::fabs(e.energy().balance_rel_error));
    }
    rest = e.linkRestLength(0), x = e.body(1).position_m.x(), work = e.energy().driven_work_J;
    state = gabion::micro::stateScene(s, e);
  };
  double rest = 0.0, x = 0.0, work = 0.0, balance = 0.0;
  Scene state;
  ASSERT_NO_FATAL_FAILURE(run(50.0, rest, x, work, balance, state));
  EXPECT_NEAR(x, 0.05, 1e-5);  // the spring carries the pull
  EXPECT_NEAR(rest, x, 1e-8);  // (the length at the last sub-step's start)
  EXPECT_NEAR(work, 50.0 * 0.05, 1e-3);
  EXPECT_LT(balance, 1e-3);
  EXPECT_EQ(state.links[0].wire.rest_length_m, rest);
  EXPECT_FALSE(state.links[0].pulled());
  double r2 = 0.0, x2 = 0.0, w2 = 0.0, b2 = 0.0;
  ASSERT_NO_FATAL_FAILURE(run(100.0, r2, x2, w2, b2, state));
  EXPECT_NEAR(x2, 0.02, 1e-3) << "closed to its shortest length";
  EXPECT_NEAR(r2, 0.02, 1e-3);
  EXPECT_LT(b2, 1e-3);
}

}  // namespace
