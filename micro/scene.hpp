#pragma once
/// \file
/// The `micro.scene` case: explicit bodies (spheres, rigid multi-sphere
/// blocks, planar walls), materials and run settings, parsed with full
/// validation (every error names the file and the JSON pointer). The key
/// reference is in docs/micro.md.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"

namespace gabion::micro {

using Vec3 = Eigen::Vector3d;

/// Contact material. Two materials meet through the mixing rule of
/// mixMaterials() (docs/micro.md).
struct Material {
  std::string name;
  double density_kg_m3 = 0.0;         ///< (kg/m^3), > 0 (walls: unused but validated)
  double normal_stiffness_N_m = 0.0;  ///< k_n (N/m), > 0
  double shear_stiffness_N_m = 0.0;   ///< k_s (N/m), > 0
  double friction = 0.0;              ///< Coulomb f (-), >= 0
  double normal_force_limit_N = std::numeric_limits<double>::infinity();  ///< F_lim (N); absent: elastic
  double local_damping = 0.0;         ///< Cundall alpha (-), in [0, 1)
  double viscous_damping_ratio = 0.0; ///< zeta, fraction of critical (-), in [0, 1)
};

/// A free sphere.
struct SphereSpec {
  Vec3 center_m = Vec3::Zero();
  double radius_m = 0.0;
  int material = 0;
  Vec3 velocity_m_s = Vec3::Zero();
  Vec3 angular_velocity_rad_s = Vec3::Zero();
  bool fixed = false;  ///< never moves (infinite mass)
};

/// A rigid multi-sphere block. Member centres are in body coordinates; the
/// body frame is placed at `position_m` with `orientation` (body -> world).
struct BlockSpec {
  std::vector<Vec3> member_centers_m;
  std::vector<double> member_radii_m;
  int material = 0;
  Vec3 position_m = Vec3::Zero();  ///< world position of the body-frame origin (m)
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< body -> world
  Vec3 velocity_m_s = Vec3::Zero();            ///< of the centre of mass
  Vec3 angular_velocity_rad_s = Vec3::Zero();  ///< world frame
  bool fixed = false;
};

/// A rigid infinite plane; bodies stay on the side `normal` points to.
struct WallSpec {
  Vec3 point_m = Vec3::Zero();      ///< a point of the plane at t = 0 (m)
  Vec3 normal = Vec3::UnitZ();      ///< unit normal (normalised on input)
  int material = 0;
  Vec3 velocity_m_s = Vec3::Zero(); ///< prescribed constant velocity (m/s)
};

/// Run settings (`run` object). Defaults in docs/micro.md.
struct RunSpec {
  double duration_s = 0.0;
  double dt_s = 0.0;                  ///< 0: dt_safety * critical
  double dt_safety = 0.2;             ///< fraction of the critical step used when dt_s is absent
  bool allow_dt_above_critical = false;  ///< run a given dt_s even above the critical step
  double output_interval_s = 0.0;     ///< body snapshots (0: duration / 100)
  double series_interval_s = 0.0;     ///< scalar series (0: output_interval_s)
  double max_overlap_ratio = 0.5;     ///< stop when an overlap exceeds this fraction of the smaller radius
  double energy_runaway_factor = 10.0;  ///< stop when KE + elastic energy exceeds this times the energy scale
  double verlet_skin_ratio = 0.2;     ///< Verlet skin / mean radius of the grid spheres
};

/// A whole scene.
struct Scene {
  Vec3 gravity_m_s2 = Vec3(0, 0, -9.81);
  std::vector<Material> materials;
  std::vector<SphereSpec> spheres;
  std::vector<BlockSpec> blocks;
  std::vector<WallSpec> walls;
  RunSpec run;
};

/// Parses the case root (format and kind are read by the app). Throws
/// bridge::InputError naming the file and JSON pointer of the bad value.
Scene parseScene(const bridge::JsonReader& root);

}  // namespace gabion::micro
