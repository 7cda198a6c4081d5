#pragma once
/// \file
/// One contact of the fine DEM: the material mixing rule and the evaluation
/// of the contact laws of bridge/laws/contact_*.hpp for given kinematics.
/// The same function serves particle-particle and particle-wall contacts.
#include <algorithm>
#include <cmath>

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
  const auto series = [](double x, double y) { return 2.0 * x * y / (x + y); };
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

/// Evaluates one contact between body i and partner j.
/// n: unit normal from i to j; overlap_m > 0; vrel_m_s: velocity of j's
/// contact point relative to i's; inv_reduced_mass: 1/m_i + 1/m_j (1/kg);
/// u_m (3), plastic_m and viscous_N (the dashpot force of the previous
/// step): the contact history, updated in place.
/// Writes the force on i (N) to f; the force on j is -f.
[[gnu::always_inline]] inline void evaluateContact(const PairLaw& law, double inv_reduced_mass, const double n[3], double overlap_m,
                            const double vrel_m_s[3], double dt_s, double u_m[3], double& plastic_m, double& viscous_N, double f[3],
                            ContactEnergy& e, bool measure) {
  const double vn = vrel_m_s[0] * n[0] + vrel_m_s[1] * n[1] + vrel_m_s[2] * n[2];
  const auto normal = bridge::normalContactForce(law.normal, overlap_m, plastic_m);
  plastic_m = normal.plastic_overlap_m;
  e.plastic_J += normal.plastic_work_J;
  double fn = normal.force_N;
  if (law.damping_ratio > 0.0) {
    const double c =
        bridge::normalDampingCoefficient(law.damping_ratio, law.normal.stiffness_N_m, 1.0 / inv_reduced_mass);
    const double fv = bridge::viscousNormalForce(c, -vn);
    // Work of the dashpot over this overlap increment, with the mean of the
    // previous and the current force (the work the staggered scheme does).
    e.viscous_J += 0.5 * (fv + viscous_N) * (-vn) * dt_s;
    viscous_N = fv;
    fn += fv;
  }
  bridge::rotateShearIntoPlane(u_m, n);
  const double du[3] = {(vrel_m_s[0] - vn * n[0]) * dt_s, (vrel_m_s[1] - vn * n[1]) * dt_s,
                        (vrel_m_s[2] - vn * n[2]) * dt_s};
  e.friction_J += bridge::coulombShearUpdate(law.tangential, normal.force_N, u_m, du);
  const double ks = law.tangential.stiffness_N_m;
  f[0] = -fn * n[0] + ks * u_m[0];
  f[1] = -fn * n[1] + ks * u_m[1];
  f[2] = -fn * n[2] + ks * u_m[2];
  if (measure)
    e.elastic_J += bridge::normalElasticEnergy(law.normal, normal.force_N) +
                   bridge::tangentialElasticEnergy(law.tangential,
                                                   u_m[0] * u_m[0] + u_m[1] * u_m[1] + u_m[2] * u_m[2]);
}

}  // namespace gabion::micro
