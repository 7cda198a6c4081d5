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

/// One incremental update of a tangential force of N components (in place):
/// trial force F + k_t du, its magnitude limited to mu N (N >= 0 the current
/// normal force), scaled back along the trial force. When the limit acts, the
/// slip of the step is du - (F_new - F_old) / k_t and the energy it dissipates
/// is taken at the mean force of the step, (F_old + F_new) / 2 . slip: the
/// trapezoidal rule, second-order accurate and consistent with a leapfrog
/// integrator's work while sliding under a changing normal force. Returns the
/// energy dissipated (J, >= 0 up to round-off). N = 1: the force along x of
/// x-only kinematics; 2: a face's two tangent axes; 3: the boulder on a face,
/// its tangent plane any plane (the caller keeps the force in it).
template <int N>
inline double frictionUpdate(const FrictionParams& p, double normal_N, const double* du_m, double* force_N) {
  const double k = p.tangential_stiffness_N_m;
  const double limit = p.friction * std::max(normal_N, 0.0);
  double old[N], trial[N], mag2 = 0.0;
  for (int i = 0; i < N; ++i) {
    old[i] = force_N[i];
    trial[i] = old[i] + k * du_m[i];
    mag2 += trial[i] * trial[i];
  }
  if (mag2 <= limit * limit) {
    for (int i = 0; i < N; ++i) force_N[i] = trial[i];
    return 0.0;
  }
  const double s = limit / std::sqrt(mag2);
  double dissipated = 0.0;
  for (int i = 0; i < N; ++i) {
    force_N[i] = trial[i] * s;
    dissipated += 0.5 * (old[i] + force_N[i]) * (du_m[i] - (force_N[i] - old[i]) / k);
  }
  return dissipated;
}

/// The 1-D update (frictionUpdate<1>) on scalars.
inline double frictionUpdate1d(const FrictionParams& p, double normal_N, double du_m, double& force_N) {
  return frictionUpdate<1>(p, normal_N, &du_m, &force_N);
}

/// The 2-D update (frictionUpdate<2>) on two scalars.
inline double frictionUpdate2d(const FrictionParams& p, double normal_N, double du1_m, double du2_m, double& f1_N,
                               double& f2_N) {
  const double du[2] = {du1_m, du2_m};
  double f[2] = {f1_N, f2_N};
  const double d = frictionUpdate<2>(p, normal_N, du, f);
  f1_N = f[0];
  f2_N = f[1];
  return d;
}

/// Elastic energy stored in the tangential spring at force magnitude F (J).
inline double frictionElasticEnergy(const FrictionParams& p, double force_N) {
  return 0.5 * force_N * force_N / p.tangential_stiffness_N_m;
}

}  // namespace gabion::bridge
