#pragma once
/// \file
/// Normal contact law of the fine DEM: linear spring k_n with an optional
/// normal force cap F_lim (elastic - perfectly plastic with plastic overlap
/// memory, Bertrand et al. 2006 Sec. 3.2 "CC" test: while F_n = F_lim and the
/// overlap grows the whole increment is plastic; otherwise dF_n = k_n dU_n),
/// plus viscous normal damping given as a ratio of critical damping.
/// Pure functions of value types; used for particle-particle and
/// particle-wall contacts alike.
///
/// Convention: overlap delta > 0 in contact (m); the elastic force F_n >= 0
/// pushes the bodies apart (N). The plastic overlap delta_p >= 0 is the part
/// of the overlap that is permanent: F_n = k_n (delta - delta_p), capped at
/// F_lim, and zero (no adhesion) when delta < delta_p.
#include <cmath>
#include <limits>

namespace gabion::bridge {

/// Parameters of the normal law.
struct NormalContactParams {
  double stiffness_N_m = 0.0;                                         ///< k_n (N/m), > 0
  double force_limit_N = std::numeric_limits<double>::infinity();     ///< F_lim (N); infinity: purely elastic
};

/// One evaluation of the elastic(-plastic) part.
struct NormalContactResponse {
  double force_N = 0.0;           ///< elastic normal force F_n >= 0 (N)
  double plastic_overlap_m = 0.0; ///< updated plastic overlap delta_p (m)
  double plastic_work_J = 0.0;    ///< work dissipated plastically in this update, F_lim * d(delta_p) (J)
};

/// Return mapping of the elastic - perfectly plastic normal spring: exact for
/// any overlap increment (the plastic overlap only grows, by the part of the
/// increment carried at F_lim).
inline NormalContactResponse normalContactForce(const NormalContactParams& p, double overlap_m,
                                                double plastic_overlap_m) {
  const double trial = p.stiffness_N_m * (overlap_m - plastic_overlap_m);
  if (trial <= 0.0) return {0.0, plastic_overlap_m, 0.0};
  if (trial <= p.force_limit_N) return {trial, plastic_overlap_m, 0.0};
  const double dp = overlap_m - p.force_limit_N / p.stiffness_N_m;
  return {p.force_limit_N, dp, p.force_limit_N * (dp - plastic_overlap_m)};
}

/// Elastic energy stored in the normal spring at force F_n (J).
inline double normalElasticEnergy(const NormalContactParams& p, double force_N) {
  return 0.5 * force_N * force_N / p.stiffness_N_m;
}

/// Viscous damping coefficient c = 2 zeta sqrt(m* k_n) (N s/m) for a damping
/// ratio zeta (fraction of critical) and reduced mass m* (kg).
inline double normalDampingCoefficient(double ratio, double stiffness_N_m, double reduced_mass_kg) {
  return 2.0 * ratio * std::sqrt(reduced_mass_kg * stiffness_N_m);
}

/// Viscous normal force c * d(delta)/dt (N), positive (repulsive) while the
/// overlap grows. It is not clipped: with a linear spring-dashpot the analytic
/// restitution exp(-pi zeta / sqrt(1 - zeta^2)) assumes the dashpot acts until
/// the overlap returns to zero.
inline double viscousNormalForce(double coefficient_N_s_m, double overlap_rate_m_s) {
  return coefficient_N_s_m * overlap_rate_m_s;
}

}  // namespace gabion::bridge
