#pragma once
/// \file
/// Identification of the joint law (bridge/laws/cell_joint_law.hpp) from two
/// confined compressions along the same axis: one cell, and a row of n copies
/// of it (micro.cc, loading.cells_in_series). At each force level the row's
/// shortening less n times the cell's is the closure of its n - 1 joints; a
/// power law c = c_1 (F / 1 kN)^b is fitted to the closure of one joint by
/// least squares in log-log (closed form).
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bridge/curve.hpp"
#include "bridge/laws/cell_joint_law.hpp"

namespace gabion::fitting {

struct JointFit {
  bridge::JointLawParams law;
  /// Every force level (N, log-spaced), one joint's closure there (m;
  /// may be <= 0 where the curves' scatter outweighs the joint), and which
  /// levels the fit used (those that show the joint).
  std::vector<double> force_N, closure_m;
  std::vector<bool> used;
  double force_lo_N = 0.0, force_hi_N = 0.0;  ///< the levels' range
  double r2 = 0.0;                            ///< of the log-log fit
  std::size_t points = 0;                     ///< levels used
};

/// The shortening (m) at which a loading curve first carries `force_N`
/// (linear between its points, on the running largest force: the first
/// loading, seen from the force), or NaN beyond the curve's largest force.
double shorteningAtForce(const bridge::Curve& c, double force_N);

/// Fits the joint law from the cell's and the row's curves (displacement,
/// force; the first loading is read) at `levels` force levels from
/// `lowest_fraction` to 1 of the smaller of the two curves' largest forces.
/// A level shows the joint where its closure exceeds a thousandth of the
/// row's shortening there. Throws std::runtime_error (with what to check)
/// where fewer than half the levels (or three) show it.
JointFit fitJoint(const bridge::Curve& cell, const bridge::Curve& row, int cells_in_series, std::size_t levels = 40,
                  double lowest_fraction = 0.05);

/// One line on a fitted joint, from its summary entry (the fit case's
/// `fit.joint`): "joint (power, R2 log-log ..., n of m force levels):
/// closure at 1 kN ... mm, exponent ...; closure at <top> kN ... mm".
std::string describeJointFit(const nlohmann::json& entry);

}  // namespace gabion::fitting
