#pragma once
// Scene pieces shared by the micro tests: a material and a sphere.
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

}  // namespace gabion::micro::test
