#pragma once
/// \file
/// Interface between two cells (or a cell and the ground): a linear
/// tangential spring limited by Coulomb friction, with the elastic tangential
/// force carried from step to step (the slip history). Bertrand et al. 2006,
/// Fig. 12: the friction between a cell and its lateral neighbours spreads the
/// impact sideways. A pure function of value types, used by the macro model.
///
/// Convention: `force_N` is the tangential force that the first body exerts on
/// the second along the tangent (N); the second body's displacement relative to
/// the first is -du, i.e. du = increment of (u_first - u_second) (m).
#include <algorithm>
#include <cmath>

namespace gabion::bridge {

/// Parameters of the interface: Coulomb coefficient and tangential stiffness.
struct FrictionParams {
  double friction = 0.5;                  ///< Coulomb coefficient mu (dimensionless)
  double tangential_stiffness_N_m = 0.0;  ///< k_t (N/m), > 0
};

/// One incremental update of a 1-D tangential force (in place): trial force
/// F + k_t du, limited to mu N (N >= 0 the current normal force). When the
/// limit acts, the slip of the step is du - (F_new - F_old) / k_t and the
/// energy it dissipates is taken at the mean force of the step,
/// (F_old + F_new) / 2 * slip: the trapezoidal rule, second-order accurate
/// and consistent with a leapfrog integrator's work while sliding under a
/// changing normal force. Returns the energy dissipated (J, >= 0 up to round-off).
inline double frictionUpdate1d(const FrictionParams& p, double normal_N, double du_m, double& force_N) {
  const double k = p.tangential_stiffness_N_m;
  const double limit = p.friction * std::max(normal_N, 0.0);
  const double old = force_N;
  const double trial = old + k * du_m;
  if (std::abs(trial) <= limit) {
    force_N = trial;
    return 0.0;
  }
  force_N = std::copysign(limit, trial);
  return 0.5 * (old + force_N) * (du_m - (force_N - old) / k);
}

/// The same for a tangential force with two components (3-D kinematics): the
/// limit applies to the magnitude, the force is scaled back along the trial force.
inline double frictionUpdate2d(const FrictionParams& p, double normal_N, double du1_m, double du2_m, double& f1_N,
                               double& f2_N) {
  const double k = p.tangential_stiffness_N_m;
  const double limit = p.friction * std::max(normal_N, 0.0);
  const double o1 = f1_N, o2 = f2_N;
  const double t1 = o1 + k * du1_m, t2 = o2 + k * du2_m;
  const double mag = std::hypot(t1, t2);
  if (mag <= limit) {
    f1_N = t1;
    f2_N = t2;
    return 0.0;
  }
  const double s = limit / mag;
  f1_N = t1 * s;
  f2_N = t2 * s;
  return 0.5 * ((o1 + f1_N) * (du1_m - (f1_N - o1) / k) + (o2 + f2_N) * (du2_m - (f2_N - o2) / k));
}

/// Elastic energy stored in the tangential spring at force magnitude F (J).
inline double frictionElasticEnergy(const FrictionParams& p, double force_N) {
  return 0.5 * force_N * force_N / p.tangential_stiffness_N_m;
}

}  // namespace gabion::bridge
