#pragma once
/// \file
/// The damping laws of the fine DEM. Pure, branch-free functions of value
/// types (selects, no branches on data): the SIMD kernels and the scalar
/// paths call the same code.
///
/// - Viscous normal dashpot of a contact: F_v = c d(delta)/dt with
///   c = 2 zeta sqrt(m* k_n), zeta the damping ratio (fraction of critical)
///   and m* the reduced mass of the two bodies. It is not clipped: with a
///   linear spring-dashpot the analytic restitution
///   exp(-pi zeta / sqrt(1 - zeta^2)) assumes the dashpot acts until the
///   overlap returns to zero, so F_v may pull while the bodies separate.
/// - Cundall's local non-viscous damping (Cundall 1987; PFC, Yade
///   NewtonIntegrator): each component of the unbalanced force (or torque) on
///   a body is reduced by alpha |F_i| against the sign of the body's velocity
///   component, F_i - alpha |F_i| sign(v_i). Used in quasi-static runs. It
///   acts on the whole unbalanced force, gravity included, so a free fall
///   accelerates at (1 - alpha) g.
#include <cmath>

namespace gabion::bridge {

/// Parameters of the viscous normal dashpot.
struct ViscousDampingParams {
  double ratio = 0.0;  ///< zeta (-), fraction of critical damping, >= 0; 0: no dashpot
};

/// Viscous damping coefficient c = 2 zeta sqrt(m* k_n) (N s/m) for a damping
/// ratio zeta (fraction of critical) and reduced mass m* (kg).
inline double normalDampingCoefficient(double ratio, double stiffness_N_m, double reduced_mass_kg) {
  return 2.0 * ratio * std::sqrt(reduced_mass_kg * stiffness_N_m);
}

/// One step of the dashpot.
struct DashpotResponse {
  double force_N;  ///< F_v (N), positive (repulsive) while the overlap grows; 0 without dashpot
  double work_J;   ///< work it dissipated over the step (J)
};

/// The dashpot coefficient c (N s/m) of a contact of normal stiffness k_n
/// between bodies with 1/m_i + 1/m_j = `inv_mass_sum_1_kg` (1/kg; 0 for two
/// immovable bodies); 0 without a dashpot (computed for every input and
/// selected: without a dashpot c may be 0 * inf). It depends only on the
/// pair, so a kernel may compute it once per pair and keep it.
inline double dashpotCoefficient(const ViscousDampingParams& p, double stiffness_N_m, double inv_mass_sum_1_kg) {
  const double c = normalDampingCoefficient(p.ratio, stiffness_N_m, 1.0 / inv_mass_sum_1_kg);
  return p.ratio > 0.0 ? c : 0.0;
}

/// One step of a dashpot of coefficient c (dashpotCoefficient) at overlap
/// rate d(delta)/dt (m/s), over a step dt. Its work over the step takes the
/// mean of the previous force `previous_force_N` (the history) and the
/// current one, times the overlap increment: the work the staggered explicit
/// scheme does on the bodies.
inline DashpotResponse dashpotStep(double coefficient_N_s_m, double overlap_rate_m_s, double dt_s,
                                   double previous_force_N) {
  const double f = coefficient_N_s_m * overlap_rate_m_s;
  return {f, 0.5 * (f + previous_force_N) * overlap_rate_m_s * dt_s};
}

/// The dashpot of a contact (dashpotCoefficient, then dashpotStep).
inline DashpotResponse viscousNormalDashpot(const ViscousDampingParams& p, double stiffness_N_m,
                                            double inv_mass_sum_1_kg, double overlap_rate_m_s, double dt_s,
                                            double previous_force_N) {
  return dashpotStep(dashpotCoefficient(p, stiffness_N_m, inv_mass_sum_1_kg), overlap_rate_m_s, dt_s, previous_force_N);
}

/// Parameters of local damping.
struct LocalDampingParams {
  double alpha = 0.0;  ///< damping coefficient (-), in [0, 1)
};

/// The local damping force component -alpha |f| sign(v) (N or N m) for
/// unbalanced force `f` and velocity component `v` (m/s or rad/s).
/// sign(0) = 0: a body at rest is not pushed.
inline double localDampingForce(const LocalDampingParams& p, double f, double v) {
  const double s = v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0);
  return -p.alpha * std::fabs(f) * s;
}

/// The damped force component f - alpha |f| sign(v) (N or N m).
inline double locallyDampedForce(const LocalDampingParams& p, double f, double v) {
  return f + localDampingForce(p, f, v);
}

}  // namespace gabion::bridge
