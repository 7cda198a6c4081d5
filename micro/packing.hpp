#pragma once
/// \file
/// Loose random packings of spheres in a box, the starting point of a virtual
/// cell test before gravity settles them: random sequential addition with a
/// fixed seed (deterministic), a minimum gap between spheres and to the walls,
/// and radii drawn from a truncated Gaussian (the paper's grading model,
/// Bertrand et al. 2006 Sec. 3.1).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace gabion::micro {

/// What to pack and where.
struct PackingSpec {
  Eigen::Vector3d box_min_m = Eigen::Vector3d::Zero();         ///< lower corner of the box (m)
  Eigen::Vector3d box_max_m = Eigen::Vector3d::Constant(0.5);  ///< upper corner (m)
  double mean_radius_m = 0.03;                                 ///< mean sphere radius (m)
  double radius_std_rel = 0.0;       ///< standard deviation / mean (Gaussian, truncated at +-2 sigma)
  double solid_fraction = 0.3;       ///< target solid volume / box volume (must be reachable by RSA: <= 0.35)
  double min_gap_m = 0.0;            ///< free gap between spheres and to the box faces (m)
  std::uint64_t seed = 1;            ///< random seed
  long long max_attempts = 2000000;  ///< RSA placement attempts before giving up
};

/// A packing: sphere centres and radii.
struct Packing {
  std::vector<Eigen::Vector3d> centers_m;
  std::vector<double> radii_m;
  double solid_fraction = 0.0;  ///< achieved solid volume / box volume
};

/// Random sequential addition until `solid_fraction` is reached.
/// Throws std::invalid_argument for an impossible spec (bad box, radius larger
/// than the box, fraction out of range) and std::runtime_error when the target
/// is not reached within max_attempts (the message says what was reached).
Packing randomPacking(const PackingSpec& spec);

}  // namespace gabion::micro
