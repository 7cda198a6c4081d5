#pragma once
/// \file
/// The joint between two cells pressed together: how much closer their
/// centres come than the two cells' own shortenings account for, as their
/// nettings bed into each other (the stones of one push the netting into the
/// other's surface). A cell against a flat rigid plate makes almost none; two
/// cells make a joint that closes with the force across it and stays closed.
/// Identified from two confined compressions along the same axis, a row of n
/// cells and one cell (fitting/joint_fit.hpp): the row's shortening at a
/// force, less n times the cell's, is the closure of its n - 1 joints.
///
/// Law: closure c(F) = c_1 (F / 1 kN)^b, F >= 0 the force across the joint;
/// its loading curve. The joint is plastic: it never opens again (the
/// closure a joint reached is kept when the force falls).
#include <algorithm>
#include <cmath>

namespace gabion::bridge {

struct JointLawParams {
  double closure_at_1kN_m = 0.0;  ///< c_1: the closure at 1 kN across the joint (m), > 0
  double exponent = 1.0;          ///< b (dimensionless), > 0: below 1 the joint stiffens as it closes
};

/// The closure (m) at which the joint carries `force_N` on its loading curve (0 for no force).
inline double jointClosure(const JointLawParams& p, double force_N) {
  return force_N > 0.0 ? p.closure_at_1kN_m * std::pow(force_N / 1000.0, p.exponent) : 0.0;
}

/// The force (N) the joint carries at `closure_m` on its loading curve (the inverse of jointClosure).
inline double jointForce(const JointLawParams& p, double closure_m) {
  return closure_m > 0.0 ? 1000.0 * std::pow(closure_m / p.closure_at_1kN_m, 1.0 / p.exponent) : 0.0;
}

}  // namespace gabion::bridge
