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

/// What laneContact gives for one contact: the force on i (N) without the
/// contact's on/off factor, the elastic normal force, and the energy
/// increments (J) of this step, to be counted only for a contact that touches.
struct LaneContact {
  double fx, fy, fz;
  double elastic_normal_N;
  double friction_J, plastic_J, viscous_J, elastic_J;
};

/// The laws of evaluateContact written branch-free (selects instead of
/// branches) for the vectorised kernels, one SIMD lane per contact: the
/// particle-pair kernel and the wall kernel of micro/engine.cpp. n: unit
/// normal from i to j; overlap_m (> 0 for a contact that acts); v*: velocity
/// of j's contact point relative to i's; kn, ks, mu_ks = friction / ks,
/// flim, zeta: the pair's law; inv_mass_sum: 1/m_i + 1/m_j; ux, uy, uz,
/// plastic, viscous: the contact history, updated. F_lim, viscous damping and
/// the stored energy are compile-time switches (a case pays only for what it
/// uses). The arithmetic is that of bridge/laws/contact_*.hpp; the tests of
/// tests/micro compare both paths with the analytic results.
template <bool kMeasure, bool kViscous, bool kPlastic>
[[gnu::always_inline]] inline LaneContact laneContact(double nx, double ny, double nz, double overlap, double vx,
                                                      double vy, double vz, double kn, double ks, double mu_ks,
                                                      double flim, double zeta, double inv_mass_sum, double dt,
                                                      double& ux, double& uy, double& uz, double& plastic,
                                                      double& viscous) {
  LaneContact out{};
  const double vn = vx * nx + vy * ny + vz * nz;
  // normal spring (bridge::normalContactForce)
  double fel;
  if constexpr (kPlastic) {
    const double pl = plastic;
    const double trial = kn * (overlap - pl);
    const bool cap = trial > flim;
    const double dp = overlap - flim / kn;
    fel = trial <= 0.0 ? 0.0 : (cap ? flim : trial);
    plastic = trial > 0.0 && cap ? dp : pl;
    out.plastic_J = trial > 0.0 && cap ? flim * (dp - pl) : 0.0;
  } else {
    const double trial = kn * overlap;
    fel = trial > 0.0 ? trial : 0.0;
  }
  double fn = fel;
  if constexpr (kViscous) {
    const double vi = viscous;
    const double c = 2.0 * zeta * std::sqrt(1.0 / inv_mass_sum * kn);  // bridge::normalDampingCoefficient
    const double fv = zeta > 0.0 ? c * -vn : vi;
    out.viscous_J = zeta > 0.0 ? 0.5 * (fv + vi) * (-vn) * dt : 0.0;
    viscous = fv;
    fn += zeta > 0.0 ? fv : 0.0;
  }
  // shear history turned into the tangent plane (bridge::rotateShearIntoPlane)
  const double un = ux * nx + uy * ny + uz * nz;
  const double before = ux * ux + uy * uy + uz * uz;
  const double px = ux - un * nx, py = uy - un * ny, pz = uz - un * nz;
  const double after = px * px + py * py + pz * pz;
  const bool turn = un != 0.0;
  const double s = turn && after > 0.0 ? std::sqrt(before / (after > 0.0 ? after : 1.0)) : 1.0;
  ux = turn ? px * s : ux, uy = turn ? py * s : uy, uz = turn ? pz * s : uz;
  // Coulomb update (bridge::coulombShearUpdate)
  const double dux = (vx - vn * nx) * dt, duy = (vy - vn * ny) * dt, duz = (vz - vn * nz) * dt;
  const double u0x = ux, u0y = uy, u0z = uz;
  ux += dux, uy += duy, uz += duz;
  const double u2 = ux * ux + uy * uy + uz * uz;
  const double umax = mu_ks * fel;  // the spring's reach at the Coulomb limit
  const bool slide = u2 > umax * umax;
  const double sc = slide ? umax / std::sqrt(slide ? u2 : 1.0) : 1.0;
  ux *= sc, uy *= sc, uz *= sc;
  const double work = 0.5 * ((u0x + ux) * dux + (u0y + uy) * duy + (u0z + uz) * duz);
  const double stored = 0.5 * (umax * umax - (u0x * u0x + u0y * u0y + u0z * u0z));
  out.friction_J = slide ? ks * (work - stored) : 0.0;
  if constexpr (kMeasure)  // bridge::normalElasticEnergy + tangentialElasticEnergy
    out.elastic_J = 0.5 * fel * fel / kn + 0.5 * ks * (ux * ux + uy * uy + uz * uz);
  out.fx = -fn * nx + ks * ux, out.fy = -fn * ny + ks * uy, out.fz = -fn * nz + ks * uz;
  out.elastic_normal_N = fel;
  return out;
}

}  // namespace gabion::micro
