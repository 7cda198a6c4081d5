#pragma once
/// \file
/// Time integration of the fine DEM: leapfrog (velocities at half steps) with
/// Cundall local damping on each force and torque component. Free spheres
/// go in one vectorised pass over their arrays per worker; rigid blocks
/// (kick of v and L, drift of x, free rotation of q, members then placed
/// rigidly) in parallel, one block at a time. Each pass returns its energy
/// sums and the largest displacement since the last neighbour-list build.
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "micro/particles.hpp"
#include "micro/scene.hpp"
#include "micro/worker_scratch.hpp"

namespace gabion::micro {

/// A rigid multi-sphere block: state of the centre of mass, orientation of
/// the principal frame, angular momentum (world), member offsets.
struct RigidBlock {
  double mass = 0.0, inv_mass = 0.0, volume = 0.0, alpha = 0.0;
  Vec3 inertia = Vec3::Ones();  ///< principal moments (kg m^2)
  Vec3 x = Vec3::Zero(), v = Vec3::Zero(), L = Vec3::Zero(), omega = Vec3::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();               ///< principal -> world
  Eigen::Quaterniond principal_axes = Eigen::Quaterniond::Identity();  ///< principal -> input body frame
  Vec3 frame_center = Vec3::Zero();                                    ///< centre of mass in the input body frame (m)
  std::vector<Vec3> offsets;                                           ///< member centres in the principal frame (m)
  std::vector<std::uint32_t> ids;                                      ///< stable ids of the members
  bool fixed = false;
  /// Where the block was at the last neighbour-list build (its members'
  /// x0 are x0 + R0 offsets): a member's move since is (x - x0) + (R - R0)
  /// offset, from the block's own state and the offsets already read.
  Vec3 x0 = Vec3::Zero();
  Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();
  /// Takes the block's state now as the list build's reference.
  void markListBuild() { x0 = x, R0 = q.toRotationMatrix(); }
};

/// Advances the free spheres [b, e) of `p` by one step under gravity g.
/// Also sums the kinetic and potential energy (kMeasure), the local damping
/// work, a finiteness probe and the largest squared displacement since the
/// last list build. `maybe_damped`: whether any particle of `p` may have
/// local damping (false skips the test of the range's coefficients).
/// `one_body`: every sphere of the range has one mass, inertial mass and
/// moment (they are then read once; the same sums).
SphereSums integrateSpheres(Particles& p, std::size_t b, std::size_t e, double dt, const Vec3& g, bool measure,
                            bool maybe_damped, bool one_body = false);

/// The forces of a link-node sub-step (micro/linked_nodes.hpp): the step's
/// held contact and wall force and torque (h*, t*) and the links' force of
/// this sub-step (l*), per node; the kick carries `held` times the held force
/// and torque (the step's impulse in the first sub-step, none after), while
/// local damping sees the physical force h + l.
struct HeldForces {
  const double *hx, *hy, *hz, *tx, *ty, *tz, *lx, *ly, *lz;
  double held;
  double *rx, *ry, *rz;  ///< each node's turn over the step so far (rad): the sub-step adds h times its new spin
};

/// Advances the link nodes [b, e) of their own store `n` by one sub-step h,
/// as integrateSpheres does the free spheres.
SphereSums integrateHeld(Particles& n, const HeldForces& f, std::size_t b, std::size_t e, double h, const Vec3& g,
                         bool measure);

/// Advances one block by one step (forces and torques of its members in
/// `p`) and places its members; the same sums as integrateSpheres.
SphereSums integrateBlock(RigidBlock& block, Particles& p, double dt, const Vec3& g, bool measure);

}  // namespace gabion::micro
