#pragma once
/// \file
/// Cundall's local non-viscous damping (Cundall 1987; PFC, Yade
/// NewtonIntegrator): each component of the unbalanced force (or torque) on a
/// body is reduced by alpha |F_i| against the sign of the body's velocity
/// component, F_i - alpha |F_i| sign(v_i). Used in quasi-static runs. It acts
/// on the whole unbalanced force, gravity included, so a free fall
/// accelerates at (1 - alpha) g. A pure function of value types.
#include <cmath>

namespace gabion::bridge {

/// Parameters of local damping.
struct LocalDampingParams {
  double alpha = 0.0;  ///< damping coefficient (-), in [0, 1)
};

/// The damped force component (N or N m) for unbalanced force `f` and
/// velocity component `v` (m/s or rad/s). sign(0) = 0: a body at rest is not
/// pushed.
inline double locallyDampedForce(const LocalDampingParams& p, double f, double v) {
  const double s = v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0);
  return f - p.alpha * std::fabs(f) * s;
}

}  // namespace gabion::bridge
