#pragma once
/// \file
/// Tangential contact law of the fine DEM (Cundall & Strack 1979): an
/// incremental linear shear spring k_s whose force is limited by Coulomb
/// friction |F_t| <= f F_n. The shear displacement u_s is carried in the
/// contact history; every step it is first rotated into the current tangent
/// plane (its length kept), then incremented by the relative tangential
/// displacement. On sliding, u_s is scaled back to the Coulomb limit and the
/// sliding force times the slip is counted as friction dissipation.
/// Pure functions of value types; used for particle-particle and
/// particle-wall contacts alike.
#include <cmath>

namespace gabion::bridge {

/// Parameters of the tangential law.
struct TangentialContactParams {
  double stiffness_N_m = 0.0;  ///< k_s (N/m), > 0
  double friction = 0.0;       ///< Coulomb coefficient f (-), >= 0
};

/// Rotates the shear displacement `u` (m, 3 components) into the plane normal
/// to the unit vector `n`, keeping its length (the contact frame turned with
/// the bodies; the spring neither gains nor loses energy by the rotation).
inline void rotateShearIntoPlane(double u[3], const double n[3]) {
  const double un = u[0] * n[0] + u[1] * n[1] + u[2] * n[2];
  if (un == 0.0) return;  // already in the plane (and a fresh contact's zero history)
  const double before = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
  u[0] -= un * n[0];
  u[1] -= un * n[1];
  u[2] -= un * n[2];
  const double after = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
  if (after > 0.0) {
    const double s = std::sqrt(before / after);
    u[0] *= s;
    u[1] *= s;
    u[2] *= s;
  }
}

/// Adds the tangential displacement increment `du` (m) to `u`, applies the
/// Coulomb limit for the normal force `normal_force_N` (>= 0) and returns the
/// friction dissipation of this update (J): the work of the spring force
/// over the increment, with the force taken as the mean of the forces before
/// and after (k_s (u_old + u_new) . du / 2, which matches the work the
/// staggered explicit scheme does on the bodies), less the change of stored
/// energy k_s (|u_new|^2 - |u_old|^2) / 2. It is exactly zero while the
/// spring sticks, f F_n x slip in steady sliding, and zero for f = 0.
/// The tangential spring force acting on the body "i" whose partner moves by
/// +du relative to it is +k_s u (it drags i along).
inline double coulombShearUpdate(const TangentialContactParams& p, double normal_force_N, double u[3],
                                 const double du[3]) {
  const double u0[3] = {u[0], u[1], u[2]};
  u[0] += du[0];
  u[1] += du[1];
  u[2] += du[2];
  const double u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
  const double umax = p.friction * normal_force_N / p.stiffness_N_m;
  if (u2 <= umax * umax) return 0.0;
  const double s = umax / std::sqrt(u2);
  u[0] *= s;
  u[1] *= s;
  u[2] *= s;
  const double work = 0.5 * ((u0[0] + u[0]) * du[0] + (u0[1] + u[1]) * du[1] + (u0[2] + u[2]) * du[2]);
  const double stored = 0.5 * (umax * umax - (u0[0] * u0[0] + u0[1] * u0[1] + u0[2] * u0[2]));
  return p.stiffness_N_m * (work - stored);
}

/// Elastic energy of the shear spring (J) for shear displacement length^2 u2 (m^2).
inline double tangentialElasticEnergy(const TangentialContactParams& p, double u2) {
  return 0.5 * p.stiffness_N_m * u2;
}

}  // namespace gabion::bridge
