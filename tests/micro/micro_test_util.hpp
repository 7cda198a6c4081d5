#pragma once
// Scene pieces shared by the micro tests: a material and a sphere.
#include <random>

#include "micro/scene.hpp"

namespace gabion::micro::test {

constexpr double kPi = 3.14159265358979323846;

/// A rock-like material: density 2,500 kg/m3, k_n, k_s (N/m), friction f,
/// viscous damping ratio zeta, local damping alpha.
inline Material material(double kn = 1e5, double ks = 2.5e4, double f = 0.5, double zeta = 0.0, double alpha = 0.0) {
  Material m;
  m.name = "m";
  m.density_kg_m3 = 2500;
  m.normal_stiffness_N_m = kn;
  m.shear_stiffness_N_m = ks;
  m.friction = f;
  m.viscous_damping_ratio = zeta;
  m.local_damping = alpha;
  return m;
}

/// A sphere of material 0 at rest.
inline SphereSpec sphere(const Vec3& center_m, double radius_m, bool fixed = false) {
  SphereSpec s;
  s.center_m = center_m;
  s.radius_m = radius_m;
  s.fixed = fixed;
  return s;
}

/// Mass of a sphere of density 2,500 kg/m3 (kg).
inline double sphereMass(double r) {
  return 2500.0 * 4.0 / 3.0 * kPi * r * r * r;
}

/// A scene with every stage of the engine: two size classes, a block,
/// breakable links, a vibrating floor, a servo lid, friction and damping.
inline Scene everyStage() {
  Scene s;
  s.materials = {material(1e5, 2.5e4, 0.5, 0.05, 0.1)};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.001, 0.001);
  for (int i = 0; i < 400; ++i) {
    SphereSpec sp;
    sp.center_m = Vec3(0.02 + 0.025 * (i % 8), 0.02 + 0.025 * ((i / 8) % 8), 0.02 + 0.025 * (i / 64)) +
                  Vec3(jitter(rng), jitter(rng), jitter(rng));
    sp.radius_m = i % 9 == 0 ? 0.011 : 0.004;
    s.spheres.push_back(sp);
  }
  for (std::size_t i = 1; i + 1 < 64; i += 2) {
    LinkSpec l;
    l.a = i;
    l.b = i + 1;
    l.linear.stiffness_N_m = 500.0;
    l.linear.rest_length_m = (s.spheres[i + 1].center_m - s.spheres[i].center_m).norm();
    l.linear.rupture_strain = 0.05;
    s.links.push_back(l);
  }
  BlockSpec b;
  b.member_centers_m = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0, 0.01, 0)};
  b.member_radii_m = {0.006, 0.006, 0.006};
  b.position_m = Vec3(0.1, 0.1, 0.25);
  s.blocks = {b};
  for (int f = 0; f < 2; ++f) {
    WallSpec lo, hi;
    lo.normal = Vec3::Unit(f);
    hi.point_m = Vec3::Constant(0.21);
    hi.normal = -Vec3::Unit(f);
    s.walls.push_back(lo);
    s.walls.push_back(hi);
  }
  WallSpec floor, lid;
  floor.name = "floor";
  floor.program.kind = WallProgram::Kind::Sinusoid;
  floor.program.amplitude_m = 5e-4;
  floor.program.frequency_hz = 30.0;
  lid.name = "lid";
  lid.point_m = Vec3(0, 0, 0.3);
  lid.normal = -Vec3::UnitZ();
  lid.program.kind = WallProgram::Kind::Servo;
  lid.program.target_force_N = 5.0;
  lid.program.max_speed_m_s = 0.5;
  lid.program.gain_m_s_N = 0.01;
  s.walls.push_back(floor);
  s.walls.push_back(lid);
  return s;
}

}  // namespace gabion::micro::test
