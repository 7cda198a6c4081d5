#pragma once
/// \file
/// Tangential contact law of the fine DEM (Cundall & Strack 1979): an
/// incremental linear shear spring k_s whose force is limited by Coulomb
/// friction |F_t| <= f F_n. The shear displacement u_s is carried in the
/// contact history; every step it is first rotated into the current tangent
/// plane (its length kept), then incremented by the relative tangential
/// displacement. On sliding, u_s is scaled back to the Coulomb limit and the
/// sliding force times the slip is counted as friction dissipation.
/// Pure, branch-free functions of value types (selects, no branches on
/// data): the SIMD kernels and the scalar paths call the same code. Used for
/// particle-particle and particle-wall contacts alike.
#include <cmath>

namespace gabion::bridge {

/// Three Cartesian components (a plain aggregate: it stays in registers, one
/// SIMD lane per contact, inside vectorised loops).
struct Xyz {
  double x, y, z;
};

inline double dot(const Xyz& a, const Xyz& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

/// Parameters of the tangential law.
struct TangentialContactParams {
  double stiffness_N_m = 0.0;  ///< k_s (N/m), > 0
  double friction = 0.0;       ///< Coulomb coefficient f (-), >= 0
};

/// The tangential law in the form its update uses (the SIMD kernels store
/// f / k_s per material pair): no division per contact.
struct ShearSpring {
  double stiffness_N_m = 0.0;  ///< k_s (N/m)
  double reach_m_N = 0.0;      ///< f / k_s: the spring's stretch at the Coulomb limit per newton of normal force (m/N)
};

inline ShearSpring shearSpring(const TangentialContactParams& p) {
  return {p.stiffness_N_m, p.friction / p.stiffness_N_m};
}

/// The shear displacement `u` (m) rotated into the plane normal to the unit
/// vector `n`, its length kept (the contact frame turned with the bodies; the
/// spring neither gains nor loses energy by the rotation). A history already
/// in the plane (a fresh contact's zero history included) is returned
/// unchanged; one along n becomes its (zero) projection.
inline Xyz rotateShearIntoPlane(const Xyz& u, const Xyz& n) {
  const double un = dot(u, n);
  const double before = dot(u, u);
  const Xyz p{u.x - un * n.x, u.y - un * n.y, u.z - un * n.z};
  const double after = dot(p, p);
  const bool turn = un != 0.0;
  // sqrt of a safe argument: the select must not feed sqrt(x / 0) to lanes that do not turn
  const double s = turn && after > 0.0 ? std::sqrt(before / (after > 0.0 ? after : 1.0)) : 1.0;
  return {turn ? p.x * s : u.x, turn ? p.y * s : u.y, turn ? p.z * s : u.z};
}

/// Relative tangential displacement over a step (m): the tangential part of
/// the relative velocity `v` (m/s) of the partner's contact point, times dt.
inline Xyz shearIncrement(const Xyz& v, const Xyz& n, double dt_s) {
  const double vn = dot(v, n);
  return {(v.x - vn * n.x) * dt_s, (v.y - vn * n.y) * dt_s, (v.z - vn * n.z) * dt_s};
}

/// Result of a Coulomb update.
struct ShearUpdate {
  Xyz u;                   ///< the updated shear displacement (m)
  double friction_work_J;  ///< friction dissipation of this update (J)
};

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
inline ShearUpdate coulombShearUpdate(const ShearSpring& p, double normal_force_N, const Xyz& u, const Xyz& du) {
  Xyz t{u.x + du.x, u.y + du.y, u.z + du.z};
  const double u2 = dot(t, t);
  const double umax = p.reach_m_N * normal_force_N;
  const bool slide = u2 > umax * umax;
  const double s = slide ? umax / std::sqrt(slide ? u2 : 1.0) : 1.0;
  t.x *= s, t.y *= s, t.z *= s;
  const double work = 0.5 * ((u.x + t.x) * du.x + (u.y + t.y) * du.y + (u.z + t.z) * du.z);
  const double stored = 0.5 * (umax * umax - dot(u, u));
  return {t, slide ? p.stiffness_N_m * (work - stored) : 0.0};
}

/// Elastic energy of the shear spring at shear displacement `u` (J).
inline double tangentialElasticEnergy(const ShearSpring& p, const Xyz& u) {
  return 0.5 * p.stiffness_N_m * dot(u, u);
}

}  // namespace gabion::bridge
