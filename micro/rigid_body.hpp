#pragma once
/// \file
/// Rigid multi-sphere bodies ("blocks"): mass properties of a cluster of
/// possibly overlapping spheres, and the torque-free rotation drift used by
/// the engine's splitting integrator. Method, accuracy and references are in
/// docs/rigid_bodies.md.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace gabion::micro {

/// Volume of a sphere of radius r (m^3).
inline double sphereVolume(double r) {
  return 4.0 / 3.0 * 3.14159265358979323846 * r * r * r;
}

/// Mass properties of a rigid cluster of spheres; overlapping volume counted once (union).
struct MassProperties {
  double mass_kg = 0;                                  ///< density * volume_m3 (kg)
  double volume_m3 = 0;                                ///< volume of the union of the spheres (m^3)
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();  ///< centre of mass, in the input (body) coordinates (m)
  Eigen::Matrix3d inertia_kg_m2 =
      Eigen::Matrix3d::Zero();  ///< inertia tensor about center_m, axes of the input coordinates (kg m^2)
  Eigen::Vector3d principal_moments_kg_m2 = Eigen::Vector3d::Zero();  ///< principal moments, ascending (kg m^2)
  Eigen::Quaterniond principal_axes =
      Eigen::Quaterniond::Identity();  ///< rotation principal frame -> input coordinates (right-handed, unit)
};

/// Mass, centre and inertia of the union of the spheres (centers_m, radii_m)
/// of uniform density_kg_m3 (kg/m^3).
/// Without overlaps the result is exact (sum of spheres + parallel-axis
/// theorem). With overlaps: exact sphere sums minus the overlap correction,
/// integrated as slices x = const whose union-of-disks moments are exact
/// (Green's theorem on the boundary arcs) and adaptive Gauss-Kronrod along x.
/// rel_tol bounds the estimated error of volume, of the centre (relative to
/// the body's radius of gyration) and of the inertia tensor (relative to its
/// trace). Throws std::invalid_argument on empty/mismatched/non-finite input,
/// radius <= 0, density <= 0 or rel_tol outside [1e-12, 0.1]; throws
/// std::runtime_error if the tolerance cannot be reached (not expected).
MassProperties clusterMassProperties(const std::vector<Eigen::Vector3d>& centers, const std::vector<double>& radii,
                                     double density_kg_m3, double rel_tol = 1e-4);

/// Member sphere centres expressed in the principal frame of `props`
/// (origin at the centre of mass): offset_i = R^T (centers[i] - center_m),
/// R = props.principal_axes. A block with orientation q (principal -> world)
/// and position x (centre of mass) has its member i at x + q * offset_i.
std::vector<Eigen::Vector3d> principalFrameOffsets(const MassProperties& props,
                                                   const std::vector<Eigen::Vector3d>& centers);

/// Torque-free rotation drift over dt of a rigid body with principal moments I, orientation q (principal frame ->
/// world) and constant world angular momentum L: second-order symmetric splitting (Dullweber, Reich & Leimkuhler 1997,
/// J. Chem. Phys. 107, 5840) so |L| and L are conserved exactly and the energy error stays bounded (no drift).
/// Body-frame sub-rotations: half step about principal axis 1, half about 2,
/// full about 3, half about 2, half about 1; each is the exact flow of
/// L_i^2 / (2 I_i). An isotropic inertia (all three moments equal to 1e-12
/// relative) is rotated exactly about L instead. q is returned normalised.
/// Units: I (kg m^2), L (kg m^2/s), dt (s). Throws std::invalid_argument if a
/// moment is not finite and > 0.
void freeRotate(Eigen::Quaterniond& q, const Eigen::Vector3d& L_world, const Eigen::Vector3d& I_principal, double dt);

/// World angular velocity (rad/s) omega = q I^-1 q^-1 L of a body with
/// orientation q (principal -> world), world angular momentum L (kg m^2/s)
/// and principal moments I (kg m^2).
Eigen::Vector3d angularVelocityWorld(const Eigen::Quaterniond& q, const Eigen::Vector3d& L_world,
                                     const Eigen::Vector3d& I_principal);

/// Rotational kinetic energy (J) L . omega / 2 of the same body.
double rotationalKineticEnergy(const Eigen::Quaterniond& q, const Eigen::Vector3d& L_world,
                               const Eigen::Vector3d& I_principal);

}  // namespace gabion::micro
