// Programmed walls against their programs' closed forms: the integrated
// motion, a change of time step, the force servo, bounded plates.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "bridge/errors.hpp"
#include "micro/engine.hpp"
#include "micro/walls.hpp"
#include "micro_test_util.hpp"

namespace {

using gabion::micro::Engine;
using gabion::micro::Material;
using gabion::micro::Scene;
using gabion::micro::SphereSpec;
using gabion::micro::StepStatus;
using gabion::micro::Vec3;
using gabion::micro::WallProgram;
using gabion::micro::WallSpec;
using gabion::micro::test::kPi;

Material rock(double local_damping = 0.0) {
  return gabion::micro::test::material(1e5, 2.5e4, 0.5, 0.0, local_damping);
}

SphereSpec sphere(const Vec3& c, double r = 0.01) {
  return gabion::micro::test::sphere(c, r);
}

WallSpec floorWall(const std::string& name, const WallProgram& program) {
  WallSpec w;
  w.name = name;
  w.point_m = Vec3::Zero();
  w.normal = Vec3::UnitZ();
  w.program = program;
  return w;
}

// A ball on a plate vibrating vertically (0.5 mm at 20 Hz: peak acceleration
// 7.9 m/s^2 < g, so the ball stays on it). The plate's position after 10^5
// steps, with the step changed by a factor 0.37 half-way, equals the
// program's closed form to round-off: each step adds the exact displacement
// of the program over that step (sum of 10^5 increments of at most 1e-6 m:
// error ~ 1e5 x 1e-16 x 5e-4 m ~ 1e-14 m; the bound is 1e-12 m).
TEST(MicroWalls, VibratingPlateFollowsItsProgramThroughAChangeOfTimeStep) {
  WallProgram vib;
  vib.kind = WallProgram::Kind::Sinusoid;
  vib.direction = Vec3::UnitZ();
  vib.amplitude_m = 5e-4;
  vib.frequency_hz = 20.0;
  vib.phase_rad = 0.3;
  Scene s;
  s.materials = {rock(0.1)};
  s.spheres = {sphere(Vec3(0, 0, 0.0099))};
  s.walls = {floorWall("plate", vib)};
  Engine e(s, 1);
  e.setDt(0.05 * e.criticalDt());
  const double w = 2.0 * kPi * vib.frequency_hz;
  for (int n = 0; n < 100000; ++n) {
    if (n == 50000) e.setDt(0.37 * e.dt());
    ASSERT_EQ(e.step(n % 1000 == 0), StepStatus::Ok) << e.failure();
  }
  // wallPosition: the point when the last force was evaluated, at t - dt
  const double t = e.time() - e.dt();
  const double expected = vib.amplitude_m * (std::sin(w * t + vib.phase_rad) - std::sin(vib.phase_rad));
  EXPECT_NEAR(e.wallPosition(0).z(), expected, 1e-12);
  EXPECT_EQ(e.wallPosition(0).x(), 0.0);
  // the ball rides on the plate: its centre stays within a radius of it
  EXPECT_NEAR(e.body(0).position_m.z() - e.wallPosition(0).z(), 0.01, 1e-3);
  EXPECT_LT(std::fabs(e.energy().balance_rel_error), 1e-2);
}

// A loading-unloading table: v(t) piecewise linear; the displacement is its
// integral (piecewise quadratic), here checked at the end of each segment.
TEST(MicroWalls, VelocityTableDisplacementIsItsIntegral) {
  WallProgram table;
  table.kind = WallProgram::Kind::VelocityTable;
  table.table_time_s = {0.0, 0.01, 0.02, 0.03};
  table.table_velocity_m_s = {Vec3(0, 0, 0), Vec3(0, 0, -0.1), Vec3(0, 0, -0.1), Vec3(0, 0, 0.1)};
  const auto D = [&](double t) { return gabion::micro::programDisplacement(table, 0.0, t).z(); };
  EXPECT_NEAR(D(0.01), -0.5e-3, 1e-15);
  EXPECT_NEAR(D(0.02), -1.5e-3, 1e-15);
  EXPECT_NEAR(D(0.03), -1.5e-3, 1e-15);         // ramps -0.1 -> 0.1: no net displacement
  EXPECT_NEAR(D(0.04), -1.5e-3 + 1e-3, 1e-15);  // the last velocity holds
  // additive over any split of the interval
  EXPECT_NEAR(gabion::micro::programDisplacement(table, 0.0, 0.017).z() +
                  gabion::micro::programDisplacement(table, 0.017, 0.035).z(),
              D(0.035), 1e-16);

  Scene s;
  s.materials = {rock()};
  s.gravity_m_s2.setZero();
  s.spheres = {sphere(Vec3(1, 1, 1))};
  s.walls = {floorWall("lid", table)};
  Engine e(s, 1);
  e.setDt(1e-5);
  while (e.time() < 0.04 - 1e-12) ASSERT_EQ(e.step(false), StepStatus::Ok);
  EXPECT_NEAR(e.wallPosition(0).z(), D(e.time() - e.dt()), 1e-12);
}

// A servo lid presses a sphere on a fixed floor: the normal force on the lid
// reaches the target and holds it within 1 % (an elastic sample, damped).
TEST(MicroWalls, ServoHoldsTheTargetForceOnAnElasticSample) {
  WallProgram servo;
  servo.kind = WallProgram::Kind::Servo;
  servo.target_force_N = 20.0;
  servo.max_speed_m_s = 0.05;
  servo.gain_m_s_N = 2e-3;
  Scene s;
  s.materials = {rock(0.3)};
  s.gravity_m_s2.setZero();
  s.spheres = {sphere(Vec3(0, 0, 0.01))};
  WallSpec lid = floorWall("lid", servo);
  lid.point_m = Vec3(0, 0, 0.021);  // 1 mm above the sphere
  lid.normal = -Vec3::UnitZ();
  s.walls = {floorWall("floor", WallProgram{}), lid};
  Engine e(s, 1);
  e.setDt(0.1 * e.criticalDt());
  while (e.time() < 0.3) ASSERT_EQ(e.step(false), StepStatus::Ok) << e.failure();
  const double lid_force = -e.wallForce(1).dot(-Vec3::UnitZ());
  EXPECT_NEAR(lid_force, 20.0, 0.2);
  EXPECT_NEAR(e.wallForce(0).z(), -20.0, 0.2);  // the floor carries the same
  // and the lid has come down by the gap plus the two overlaps (k = 1e5 N/m each)
  EXPECT_NEAR(e.wallPosition(1).z(), 0.021 - 1e-3 - 2.0 * 20.0 / 1e5, 4e-6);
}

// A plate of 0.1 x 0.1 m: a sphere dropped over it comes to rest on it; one
// dropped beside it falls past.
TEST(MicroWalls, BoundedPlateHoldsWhatIsAboveItOnly) {
  Scene s;
  s.materials = {rock(0.3)};
  s.spheres = {sphere(Vec3(0.02, -0.03, 0.02)), sphere(Vec3(0.08, 0.0, 0.02))};
  WallSpec plate = floorWall("plate", WallProgram{});
  plate.bounded = true;
  plate.axis_u = Vec3::UnitX();
  plate.half_u_m = 0.05;
  plate.half_v_m = 0.05;
  s.walls = {plate};
  Engine e(s, 1);
  e.setDt(0.2 * e.criticalDt());
  while (e.time() < 0.3) ASSERT_EQ(e.step(false), StepStatus::Ok) << e.failure();
  EXPECT_NEAR(e.body(0).position_m.z(), 0.01, 1e-3);
  EXPECT_LT(e.body(1).position_m.z(), -0.2);
  const double weight = 2500.0 * 4.0 / 3.0 * kPi * 1e-6 * 9.81;
  EXPECT_NEAR(e.wallForce(0).z(), -weight, 1e-3 * weight);
}

TEST(MicroWalls, WallsAreFoundByName) {
  Scene s;
  s.materials = {rock()};
  s.spheres = {sphere(Vec3(0, 0, 1))};
  s.walls = {floorWall("", WallProgram{}), floorWall("lid", WallProgram{})};
  Engine e(s, 1);
  EXPECT_EQ(e.wallName(0), "wall_0");
  EXPECT_EQ(e.wallIndex("lid"), 1u);
  EXPECT_EQ(e.wallIndex("none"), 2u);
  s.walls[0].name = "lid";
  EXPECT_THROW(Engine(s, 1), gabion::bridge::InputError);
}

// A driven plate (program Driven) is the face of a model the engine does
// not know: here a 1-degree-of-freedom mass on a spring under the floor
// plate, stepped by the wall driver with the force the sphere exerts. A
// sphere falls on it, bounces, and the plate oscillates. The engine books
// the plate's work as -F . d with the driver's own displacements: its
// ledger's wall work equals the sum the driver makes of the same products
// (to round-off), the plate stands where the driver put it, and the
// energy of both (sphere, contact spring, oscillator) is conserved to the
// leapfrog's error at the contact's kinks (elastic contact, no damping).
TEST(MicroWalls, DrivenPlateAndItsModelExchangeTheWorkTheyDo) {
  Scene s;
  s.materials = {rock()};
  s.materials[0].friction = 0.0;
  s.gravity_m_s2.setZero();
  SphereSpec ball = sphere(Vec3(0, 0, 0.0105));
  ball.velocity_m_s = Vec3(0, 0, -0.2);
  s.spheres = {ball};
  WallProgram driven;
  driven.kind = WallProgram::Kind::Driven;
  s.walls = {floorWall("plate", driven)};
  Engine e(s, 1);
  const double dt = 0.02 * e.criticalDt();
  e.setDt(dt);
  const double M = 0.05, K = 2e4;  // the oscillator: 0.05 kg on 2e4 N/m
  double z = 0.0, v = 0.0, work_fine = 0.0, z_at_force = 0.0, osc_kinetic = 0.0;
  e.setWallDriver([&](double, double h, const std::vector<Vec3>& f, std::vector<Vec3>& d) {
    ASSERT_EQ(f.size(), 1u);
    const double vnew = v + h * (f[0].z() - K * z) / M;
    osc_kinetic = 0.5 * M * v * vnew;  // (the leapfrog's conserved kinetic energy)
    v = vnew;
    d[0] = Vec3(0, 0, h * v);
    work_fine -= f[0].dot(d[0]);
    z_at_force = z;
    z += d[0].z();
  });
  ASSERT_EQ(e.step(true), StepStatus::Ok);
  const double e0 = e.energy().total_J;  // (the plate has not moved yet)
  double worst = 0.0, touched = 0.0;
  for (int n = 0; n < 20000; ++n) {
    ASSERT_EQ(e.step(true), StepStatus::Ok) << e.failure();
    touched = std::max(touched, std::fabs(e.wallForce(0).z()));
    // both parts: the engine's own terms (its wall work taken back out) and the oscillator's
    const double both = e.energy().total_J + e.energy().wall_work_J + osc_kinetic + 0.5 * K * z_at_force * z_at_force;
    worst = std::max(worst, std::fabs(both - e0));
  }
  EXPECT_GT(touched, 1.0) << "the sphere struck the plate";
  EXPECT_GT(e.body(0).velocity_m_s.z(), 0.0) << "and bounced off it";
  EXPECT_NEAR(e.energy().wall_work_J, work_fine, 1e-12 * std::fabs(work_fine) + 1e-18);
  EXPECT_GT(std::fabs(work_fine), 1e-3 * e0) << "energy went into the oscillator";
  EXPECT_NEAR(e.wallPosition(0).z(), z_at_force, 1e-15);
  EXPECT_LT(worst, 2e-3 * e0);
  // Without a driver the plate stands still.
  e.setWallDriver({});
  ASSERT_EQ(e.step(false), StepStatus::Ok);
  ASSERT_EQ(e.step(false), StepStatus::Ok);
  EXPECT_EQ(e.wallPosition(0).z(), z);  // (where the last driven step left it)
}

// A plate with rounded edges is met at its edge: a sphere gliding over one
// plate under gravity towards a second one raised by 1 mm (two plates of
// neighbours that moved apart) hops onto it over its edge, and the energy
// is kept (elastic, frictionless: the balance error is the leapfrog's).
// Plain plates put the sphere 1 mm deep into the second one at once, out of
// nothing: the balance breaks (or the run stops on it).
TEST(MicroWalls, RoundedPlateEdgesMeetASphereWithoutAStep) {
  const auto run = [](bool rounded) {
    Scene s;
    s.materials = {rock()};
    s.materials[0].friction = 0.0;
    SphereSpec ball = sphere(Vec3(-0.05, 0, 0.01));  // on the first plate, under gravity
    ball.velocity_m_s = Vec3(0.3, 0, 0);
    s.spheres = {ball};
    for (const double side : {-1.0, 1.0}) {
      WallSpec w;
      w.name = side < 0 ? "low" : "high";
      w.point_m = Vec3(0.1 * side, 0, side < 0 ? 0.0 : 0.001);
      w.normal = Vec3::UnitZ();
      w.bounded = true;
      w.rounded_edges = rounded;
      w.axis_u = Vec3::UnitX();
      w.half_u_m = 0.1, w.half_v_m = 0.1;
      s.walls.push_back(w);
    }
    Engine e(s, 1);
    e.setDt(0.05 * e.criticalDt());
    double worst = 0.0;
    while (e.time() < 0.4) {
      // (a plain plate's step may stop the run: the energy ran away)
      if (e.step(true) != StepStatus::Ok) return std::numeric_limits<double>::infinity();
      worst = std::max(worst, std::fabs(e.energy().balance_rel_error));
    }
    EXPECT_GT(e.body(0).position_m.x(), 0.01) << "it went over the second plate";
    return worst;
  };
  EXPECT_LT(run(true), 1e-3);
  EXPECT_GT(run(false), 0.1);
}

// Each wall's candidates against their definition (micro/walls.hpp): the
// particles that move, of a group the wall touches, within radius + skin of
// the plane on its side (of either face, for a rounded plate; at most a
// skin behind a plain plate) and, for a bounded wall, over its rectangle
// with a skin's margin (and a radius more for a rounded one), in index
// order. A random cloud about four walls (an infinite plane, a tilted
// plate, a rounded plate, a plane that skips a group), 2,003 particles in
// one block and in three (block ends off the eight-particle groups of the
// vector test): every criterion keeps some particles and drops others.
TEST(MicroWalls, CandidatesAreTheirDefinitionForEveryKindOfWall) {
  std::mt19937_64 rng(20261201);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  gabion::micro::Particles p;
  const std::size_t n = 2003;
  p.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.x[i] = 0.2 * u(rng) - 0.1, p.y[i] = 0.2 * u(rng) - 0.1, p.z[i] = 0.2 * u(rng) - 0.1;
    p.r[i] = 0.002 + 0.008 * u(rng);
    p.inv_body_mass[i] = u(rng) < 0.1 ? 0.0 : 1.0;
    p.group[i] = static_cast<std::uint8_t>(i % 3);
  }
  const double skin = 0.002;
  std::vector<WallSpec> specs(4);
  specs[0].name = "plane";
  specs[1].name = "tilted_plate", specs[1].normal = Vec3(0.3, -0.2, 1.0).normalized();
  specs[1].point_m = Vec3(0.01, 0.0, -0.02), specs[1].bounded = true;
  specs[1].axis_u = specs[1].normal.cross(Vec3::UnitY()).normalized();
  specs[1].half_u_m = 0.08, specs[1].half_v_m = 0.06;
  specs[2] = specs[1], specs[2].name = "rounded_plate", specs[2].rounded_edges = true;
  specs[2].point_m = Vec3(0.0, 0.02, 0.03);
  specs[3].name = "skips_group_1", specs[3].normal = -Vec3::UnitX(), specs[3].skip_groups = 1u << 1;
  const gabion::micro::ForBlocks serial = [](std::size_t nb, const std::function<void(std::size_t)>& fn) {
    for (std::size_t b = 0; b < nb; ++b) fn(b);
  };
  for (const std::size_t blocks : {std::size_t{1}, std::size_t{3}}) {
    std::vector<gabion::micro::Wall> walls;
    for (const WallSpec& s : specs) walls.emplace_back(s);
    gabion::micro::wallCandidates(p, walls, skin, blocks, serial);
    for (const gabion::micro::Wall& w : walls) {
      std::vector<std::uint32_t> want;
      std::size_t beyond_plane = 0, off_rectangle = 0;
      for (std::uint32_t i = 0; i < n; ++i) {
        const Vec3 d = Vec3(p.x[i], p.y[i], p.z[i]) - w.position;
        const double r = p.r[i], dist = d.dot(w.n), edge = w.rounded ? r : 0.0;
        const bool near = dist < r + skin && (w.rounded ? dist > -r - skin : !w.bounded || dist >= -skin);
        const bool over = !w.bounded || (std::fabs(d.dot(w.u)) <= w.half_u + skin + edge &&
                                         std::fabs(d.dot(w.v)) <= w.half_v + skin + edge);
        const bool touches = p.inv_body_mass[i] != 0.0 && ((w.skip_groups >> p.group[i]) & 1u) == 0;
        beyond_plane += !near, off_rectangle += near && !over;
        if (near && over && touches) want.push_back(i);
      }
      EXPECT_EQ(w.cand, want) << w.name << ", " << blocks << " blocks";
      EXPECT_GT(want.size(), 20u) << w.name;
      EXPECT_GT(beyond_plane, 20u) << w.name;
      if (w.bounded) {
        EXPECT_GT(off_rectangle, 20u) << w.name;
      }
    }
  }
}

}  // namespace
