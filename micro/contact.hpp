#pragma once
/// \file
/// One contact of the fine DEM: the material mixing rule and the composition
/// of the contact laws of bridge/laws/contact_*.hpp for given kinematics.
/// The laws themselves are written once, in bridge/laws; laneContact only
/// composes them, and every path (the SIMD kernels, evaluateContact) goes
/// through laneContact. The same function serves particle-particle and
/// particle-wall contacts.
#include <algorithm>
#include <limits>
#include <type_traits>

#include "bridge/laws/contact_damping.hpp"
#include "bridge/laws/contact_normal.hpp"
#include "bridge/laws/contact_tangential.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// The laws of one pair of materials.
struct PairLaw {
  bridge::NormalContactParams normal;
  bridge::TangentialContactParams tangential;
  double damping_ratio = 0.0;  ///< viscous normal damping, fraction of critical (-)
};

/// Mixing rule (docs/micro.md): stiffnesses in series, k = 2 k1 k2 / (k1 + k2)
/// (a material with itself keeps its own k; two springs of the same material
/// meeting at a contact, each "half" of the contact); friction and F_lim take
/// the smaller value (the weaker surface slips or crushes first); the viscous
/// damping ratio is the mean.
inline PairLaw mixMaterials(const Material& a, const Material& b) {
  PairLaw p;
  // (as 2 / (1/k1 + 1/k2): 2 k1 k2 underflows to 0 below k = 1e-154, and a
  // zero stiffness makes the stored energy F^2 / 2k a NaN)
  const auto series = [](double x, double y) { return x == y ? x : 2.0 / (1.0 / x + 1.0 / y); };
  p.normal.stiffness_N_m = series(a.normal_stiffness_N_m, b.normal_stiffness_N_m);
  p.normal.force_limit_N = std::min(a.normal_force_limit_N, b.normal_force_limit_N);
  p.tangential.stiffness_N_m = series(a.shear_stiffness_N_m, b.shear_stiffness_N_m);
  p.tangential.friction = std::min(a.friction, b.friction);
  p.damping_ratio = 0.5 * (a.viscous_damping_ratio + b.viscous_damping_ratio);
  return p;
}

/// Energy increments of contacts, accumulated per worker (J).
struct ContactEnergy {
  double friction_J = 0.0;
  double plastic_J = 0.0;
  double viscous_J = 0.0;
  double elastic_J = 0.0;  ///< stored energy, accumulated only on measuring steps
};

/// What laneContact gives for one contact: the force on i (N) without the
/// contact's on/off factor, the elastic normal force, and the energy
/// increments (J) of this step, to be counted only for a contact that touches.
struct LaneContact {
  double fx, fy, fz;
  double elastic_normal_N;
  double friction_J, plastic_J, viscous_J, elastic_J;
};

/// One contact, the laws of bridge/laws composed, branch-free (the laws are
/// selects, not branches) so that the vectorised kernels run it one SIMD lane
/// per contact: the particle-pair kernel (micro/contact_kernel.cpp), the wall
/// kernel (micro/walls.cpp), and evaluateContact for the scalar path.
/// n: unit normal from i to j; overlap (> 0 for a contact that acts); v*:
/// velocity of j's contact point relative to i's; kn, ks, mu_ks = friction /
/// ks, flim: the pair's law; damping: the pair's dashpot coefficient
/// (bridge::dashpotCoefficient of its damping ratio, kn and 1/m_i + 1/m_j,
/// N s/m: constant for a pair, so a kernel may compute it once per pair and
/// keep it); ux, uy, uz,
/// plastic, viscous: the contact history, updated. F_lim, viscous damping and
/// the stored energy are compile-time switches (a case pays only for what it
/// uses; without F_lim the spring has no cap and no plastic memory, without
/// viscous damping the dashpot history is left alone). Force on i:
/// -(F_n + F_v) n + k_s u. tests/micro/test_law_equivalence.cpp checks that
/// this, called alone or in a SIMD loop, evaluateContact and the bridge laws
/// called one by one agree.
template <bool kMeasure, bool kViscous, bool kPlastic>
[[gnu::always_inline]] inline LaneContact laneContact(double nx, double ny, double nz, double overlap, double vx,
                                                      double vy, double vz, double kn, double ks, double mu_ks,
                                                      double flim, double damping, double dt, double& ux, double& uy,
                                                      double& uz, double& plastic, double& viscous) {
  const bridge::Xyz n{nx, ny, nz}, v{vx, vy, vz};
  const bridge::NormalContactParams normal_law{kn, kPlastic ? flim : std::numeric_limits<double>::infinity()};
  const bridge::ShearSpring shear{ks, mu_ks};
  LaneContact out{};
  const auto normal = bridge::normalContactForce(normal_law, overlap, kPlastic ? plastic : 0.0);
  if constexpr (kPlastic) {
    plastic = normal.plastic_m;
    out.plastic_J = normal.plastic_work_J;
  }
  double fn = normal.force_N;
  if constexpr (kViscous) {
    const auto dashpot = bridge::dashpotStep(damping, -bridge::dot(v, n), dt, viscous);
    viscous = dashpot.force_N;
    out.viscous_J = dashpot.work_J;
    fn += dashpot.force_N;
  }
  const auto slip = bridge::coulombShearUpdate(shear, normal.force_N, bridge::rotateShearIntoPlane({ux, uy, uz}, n),
                                               bridge::shearIncrement(v, n, dt));
  ux = slip.u.x, uy = slip.u.y, uz = slip.u.z;
  out.friction_J = slip.friction_work_J;
  if constexpr (kMeasure)
    out.elastic_J =
        bridge::normalElasticEnergy(normal_law, normal.force_N) + bridge::tangentialElasticEnergy(shear, slip.u);
  out.fx = -fn * nx + ks * ux, out.fy = -fn * ny + ks * uy, out.fz = -fn * nz + ks * uz;
  out.elastic_normal_N = normal.force_N;
  return out;
}

/// Evaluates one contact between body i and partner j: laneContact with all
/// the laws on (F_lim, viscous damping), for the scalar paths.
/// n: unit normal from i to j; overlap_m > 0; vrel_m_s: velocity of j's
/// contact point relative to i's; inv_reduced_mass: 1/m_i + 1/m_j (1/kg);
/// u_m (3), plastic_m and viscous_N (the dashpot force of the previous
/// step): the contact history, updated in place.
/// Writes the force on i (N) to f; the force on j is -f.
[[gnu::always_inline]] inline void evaluateContact(const PairLaw& law, double inv_reduced_mass, const double n[3],
                                                   double overlap_m, const double vrel_m_s[3], double dt_s,
                                                   double u_m[3], double& plastic_m, double& viscous_N, double f[3],
                                                   ContactEnergy& e, bool measure) {
  const double mu_ks = bridge::shearSpring(law.tangential).reach_m_N;
  const auto lane = [&](auto measuring) {
    return laneContact<decltype(measuring)::value, true, true>(
        n[0], n[1], n[2], overlap_m, vrel_m_s[0], vrel_m_s[1], vrel_m_s[2], law.normal.stiffness_N_m,
        law.tangential.stiffness_N_m, mu_ks, law.normal.force_limit_N,
        bridge::dashpotCoefficient({law.damping_ratio}, law.normal.stiffness_N_m, inv_reduced_mass), dt_s, u_m[0],
        u_m[1], u_m[2], plastic_m, viscous_N);
  };
  const LaneContact c = measure ? lane(std::true_type{}) : lane(std::false_type{});
  f[0] = c.fx, f[1] = c.fy, f[2] = c.fz;
  e.friction_J += c.friction_J;
  e.plastic_J += c.plastic_J;
  e.viscous_J += c.viscous_J;
  if (measure) e.elastic_J += c.elastic_J;
}

}  // namespace gabion::micro
