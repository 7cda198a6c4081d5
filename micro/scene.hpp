#pragma once
/// \file
/// The `micro.scene` case: explicit bodies (spheres, rigid multi-sphere
/// blocks, planar walls), materials and run settings, parsed with full
/// validation (every error names the file and the JSON pointer). The key
/// reference is in docs/micro.md.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bridge/json_reader.hpp"
#include "bridge/laws/link_linear.hpp"
#include "bridge/laws/wire.hpp"
#include "bridge/laws/wire_beam.hpp"

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
  double local_damping = 0.0;                                             ///< Cundall alpha (-), in [0, 1)
  double viscous_damping_ratio = 0.0;                                     ///< zeta, fraction of critical (-), in [0, 1)
};

/// The contact law of one pair of materials, given in place of what the
/// mixing rule makes of them (`contact_pairs` of a scene; docs/micro.md): each
/// value given replaces the mixed one; a normal force limit of infinity
/// removes the cap. (A cap on the rock's own contacts, its crushing, that
/// the wires pressing on it do not take: rock with netting, uncapped.)
struct ContactPair {
  int a = 0, b = 0;  ///< material indices (either order)
  std::optional<double> normal_stiffness_N_m, shear_stiffness_N_m, friction, normal_force_limit_N,
      viscous_damping_ratio;
};

/// A `contact_pairs` entry as read: its two material names, where it is
/// (file, JSON pointer), and its values (pair.a and pair.b not yet set).
struct ContactPairInput {
  std::string name_a, name_b, file, pointer;
  ContactPair pair;
};

/// Reads one entry: {"materials": ["rock", "netting"], and any of
/// normal_stiffness_N_m, shear_stiffness_N_m, friction, normal_force_limit_N
/// (a number, or "none"), viscous_damping_ratio}.
ContactPairInput parseContactPair(const bridge::JsonReader& r);

/// Sets the entry's material indices from the names of `materials`; an
/// unknown name is an InputError naming the entry's file and pointer.
ContactPair resolveContactPair(const ContactPairInput& in, const std::vector<Material>& materials);

/// A free sphere.
struct SphereSpec {
  Vec3 center_m = Vec3::Zero();
  double radius_m = 0.0;
  int material = 0;
  Vec3 velocity_m_s = Vec3::Zero();
  Vec3 angular_velocity_rad_s = Vec3::Zero();
  /// Infinite mass: forces do not move it; it keeps velocity_m_s (zero by
  /// default: a clamp; else a driven node, whose work on the bodies is
  /// EnergyTotals::driven_work_J).
  bool fixed = false;
  int group = 0;         ///< contact group, 0 .. 31 (Scene::no_contact_groups)
  double mass_kg = 0.0;  ///< > 0: this mass (a netting node carrying its wires); 0: density x volume
  /// > 0: this moment of inertia (a netting node turning with the wire it
  /// carries); 0: a solid sphere's, 2/5 m r^2.
  double inertia_kg_m2 = 0.0;
  /// Mass scaling (>= 1): the sphere resists forces and torques with its
  /// mass and moment times this, while its weight stays m g. A quasi-static
  /// run then takes a step sqrt(mass_scale) times longer on this sphere's
  /// account and ends in the same equilibrium (docs/micro.md, Mass scaling).
  double mass_scale = 1.0;
  /// >= 0: a fixed sphere that rides wall `rides_wall` (its index in
  /// Scene::walls): each step it moves as that wall does, and the force of
  /// its links on it acts on the wall (Wall::force_N, from the next step on:
  /// the links act inside the step, after the wall has moved). An end of a
  /// link only: the point of a plate a lacing wire is tied to. -1: none.
  int rides_wall = -1;
};

/// A rigid multi-sphere block. Member centres are in body coordinates; the
/// body frame is placed at `position_m` with `orientation` (body -> world).
struct BlockSpec {
  std::vector<Vec3> member_centers_m;
  std::vector<double> member_radii_m;
  int material = 0;
  Vec3 position_m = Vec3::Zero();                                   ///< world position of the body-frame origin (m)
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< body -> world
  Vec3 velocity_m_s = Vec3::Zero();                                 ///< of the centre of mass
  Vec3 angular_velocity_rad_s = Vec3::Zero();                       ///< world frame
  bool fixed = false;
  int group = 0;  ///< contact group of its member spheres, 0 .. 31
};

/// A link between two spheres (micro/links.hpp): a force of their distance
/// only, with its own law; the two never touch through the contact law.
struct LinkSpec {
  enum class Law {
    Linear,  ///< bridge/laws/link_linear.hpp
    Wire     ///< bridge/laws/wire.hpp: elastoplastic, tension only, breaks
  };
  std::size_t a = 0, b = 0;  ///< sphere indices (input order)
  Law law = Law::Linear;
  bridge::LinearLinkParams linear;  ///< Law::Linear
  bridge::WireLinkParams wire;      ///< Law::Wire
  bridge::WireState wire_state;     ///< Law::Wire: its state at the start (a cell file's wires keep theirs)
  /// Law::Wire: the wire's bending as a beam between its nodes (inactive by
  /// default: a pin-jointed wire), and the beam's state at the start.
  bridge::WireBeamParams beam;
  bridge::WireBeamState beam_state;
  /// Law::Wire: a lacing wire being pulled tight (> 0): while its nodes
  /// are further apart than pull_min_m it slides through its loops under
  /// this tension (N), pulling them together (a constant force: its work,
  /// the force times the distance closed, is EnergyTotals::driven_work_J),
  /// and its own law does not act; closer, it pulls no more. Tied (a state
  /// taken from the engine, stateScene), its rest length is the distance
  /// it closed to, at least pull_min_m. 0: an ordinary wire.
  double pull_force_N = 0.0;
  double pull_min_m = 0.0;
  bool pulled() const { return law == Law::Wire && pull_force_N > 0.0; }
  /// Elastic stiffness (N/m), for the critical time step.
  double stiffness() const { return law == Law::Wire ? wire.stiffness() : linear.stiffness_N_m; }
};

/// How a wall moves (micro/walls.hpp). The motion is integrated step by step
/// (each step adds the program's displacement over that step), so a change
/// of the time step does not move the wall, and a servo can follow a force.
struct WallProgram {
  enum class Kind {
    Fixed,          ///< never moves
    Velocity,       ///< constant velocity `velocity_m_s`
    VelocityTable,  ///< velocity piecewise linear in time through (table_time_s, table_velocity_m_s); the last value
                    ///< holds after the table
    Sinusoid,       ///< displacement amplitude_m sin(2 pi f t + phase) - sin(phase), along `direction`
    Servo,          ///< along the wall normal, speed gain x (target - measured normal force), at most max_speed;
                    ///< at max_speed towards the bodies once it has touched nothing for approach_after_s
    Driven          ///< moved at each step by the engine's wall driver (Engine::setWallDriver) from the force
                    ///< of that step: the face of a coupled model (the hybrid structure). Set in code only;
                    ///< without a driver it stands still
  };
  Kind kind = Kind::Fixed;
  Vec3 velocity_m_s = Vec3::Zero();
  std::vector<double> table_time_s;      ///< strictly increasing, from 0 (s)
  std::vector<Vec3> table_velocity_m_s;  ///< one velocity per time (m/s)
  Vec3 direction = Vec3::UnitZ();        ///< unit vector of the sinusoid
  double amplitude_m = 0.0;
  double frequency_hz = 0.0;
  double phase_rad = 0.0;
  double target_force_N = 0.0;  ///< normal force the bodies exert on the wall (N), >= 0
  double max_speed_m_s = 0.0;   ///< servo speed limit (m/s), > 0
  double gain_m_s_N = 0.0;      ///< servo gain (m/s per N), > 0
  /// A servo that has felt no force for this long (s) closes in at
  /// max_speed; a shorter loss of contact (bodies shaken away from it and
  /// back) keeps it on its gain, so that it does not hammer them.
  double approach_after_s = 0.02;
};

/// A rigid plane; bodies stay on the side `normal` points to. Infinite, or
/// a rectangle (`bounded`) centred on point_m, with half-lengths along `axis_u`
/// and along normal x axis_u: a plate acts on a particle whose centre is in
/// front of it and projects inside the rectangle.
struct WallSpec {
  std::string name;             ///< unique; names its series in the output (empty: wall_<index>)
  Vec3 point_m = Vec3::Zero();  ///< a point of the plane at t = 0 (m)
  Vec3 normal = Vec3::UnitZ();  ///< unit normal (normalised on input)
  int material = 0;
  WallProgram program;
  bool bounded = false;
  Vec3 axis_u = Vec3::UnitX();            ///< unit, in the plane (bounded walls)
  double half_u_m = 0.0, half_v_m = 0.0;  ///< half-lengths of the rectangle (m)
  /// Contact groups the wall does not touch (bit g: group g), as a plate
  /// over a cell passes over its netting.
  std::uint32_t skip_groups = 0;
  /// A bounded wall that is a thin rigid rectangle (set in code: the
  /// hybrid's interface plates): a particle meets the nearest point of it,
  /// on either face or at its rim, so that its force changes continuously
  /// wherever it goes, where a plain plate's force would jump to the overlap
  /// it finds on sliding over an edge (two plates side by side that moved
  /// apart make a step).
  bool rounded_edges = false;
};

/// A box in which the porosity of the final packing is measured (`porosity`
/// object of the scene; micro/cell/porosity.hpp).
struct PorosityBox {
  bool enabled = false;
  Vec3 min_m = Vec3::Zero(), max_m = Vec3::Zero();
  double spacing_m = 0.001;  ///< grid spacing of the measurement
  bool blocks_only = false;  ///< count the blocks' spheres only (the rock, not a netting's nodes)
};

/// Run settings (`run` object). Defaults in docs/micro.md.
struct RunSpec {
  double duration_s = 0.0;
  double dt_s = 0.0;       ///< 0: dt_safety * critical
  double dt_safety = 0.2;  ///< fraction of the critical step used when dt_s is absent
  /// Fraction of the link nodes' critical step a link sub-step may take
  /// (micro/linked_nodes.hpp); 0: dt_safety.
  double link_dt_safety = 0.0;
  bool allow_dt_above_critical = false;  ///< run a given dt_s even above the critical step
  double output_interval_s = 0.0;        ///< body snapshots (0: duration / 100)
  double series_interval_s = 0.0;        ///< scalar series (0: output_interval_s)
  double max_overlap_ratio = 0.5;        ///< stop when an overlap exceeds this fraction of the smaller radius
  double energy_runaway_factor = 10.0;   ///< stop when KE + elastic energy exceeds this times the energy scale
  double max_balance_error = 0.05;       ///< stop when |energy balance error| exceeds this (a step too large)
  double verlet_skin_ratio = 0.2;        ///< Verlet skin / mean radius of the grid spheres
  /// Wall-clock seconds between checkpoints (micro/checkpoint.hpp); 0: none.
  double checkpoint_every_s = 600.0;
};

/// The fraction of the link nodes' critical step their sub-steps take:
/// link_dt_safety, or dt_safety where it is not given.
inline double linkDtSafety(const RunSpec& run) {
  return run.link_dt_safety > 0.0 ? run.link_dt_safety : run.dt_safety;
}

/// A whole scene.
struct Scene {
  Vec3 gravity_m_s2 = Vec3(0, 0, -9.81);
  std::vector<Material> materials;
  std::vector<SphereSpec> spheres;
  std::vector<BlockSpec> blocks;
  std::vector<WallSpec> walls;
  std::vector<LinkSpec> links;
  /// Pairs of contact groups whose particles never touch.
  std::vector<std::pair<int, int>> no_contact_groups;
  /// Laws given for pairs of materials in place of the mixing rule's.
  std::vector<ContactPair> contact_pairs;
  RunSpec run;
  PorosityBox porosity;
  /// Write the final state as OUTDIR/cell.h5 (micro/cell/cell_file.hpp).
  bool save_cell = false;
  /// What the scene's generators made (e.g. `block_fills`: blocks, mass and
  /// grading against its target), copied into the run's summary.
  nlohmann::json generated = nlohmann::json::object();
};

/// Parses the case root (format and kind are read by the app). Throws
/// bridge::InputError naming the file and JSON pointer of the bad value.
Scene parseScene(const bridge::JsonReader& root);

/// A material object (the keys of Material; docs/micro.md) named `name`.
Material parseMaterial(const std::string& name, const bridge::JsonReader& r);

/// The `run` object. duration_s is required unless default_duration_s > 0
/// (a test that knows how long it lasts).
RunSpec parseRun(const bridge::JsonReader& run, double default_duration_s = 0.0);

/// Mass of a free sphere (kg): its own mass_kg, or its material's density x volume.
double sphereMass(const Scene& scene, const SphereSpec& sphere);
/// Moment of inertia of a sphere (kg m^2): its own, or 2/5 m r^2.
double sphereInertia(const Scene& scene, const SphereSpec& sphere);
/// The mass and moment a sphere moves with: sphereMass and sphereInertia x
/// its mass_scale (its weight is sphereMass x g).
double sphereInertialMass(const Scene& scene, const SphereSpec& sphere);
double sphereInertialMoment(const Scene& scene, const SphereSpec& sphere);

/// A fixed, infinite wall: the plane through `point` with unit `normal`
/// (towards the bodies), of `material`.
WallSpec fixedWall(const std::string& name, const Vec3& point, const Vec3& normal, int material);

/// The name of wall w: its own, or wall_<w> if it has none.
std::string wallName(const Scene& scene, std::size_t w);

/// Checks a scene however it was made (read from JSON or built in code) with
/// the rules parseScene applies; throws bridge::InputError naming `file` and
/// the JSON pointer the bad value would have (e.g. /spheres/3/radius_m).
/// The Engine's constructor calls it.
void validateScene(const Scene& scene, const std::string& file = "<scene built in code>");

}  // namespace gabion::micro
