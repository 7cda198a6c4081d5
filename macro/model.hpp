#pragma once
/// \file
/// The macro model in motion: the state of the nodes and interactions of a
/// Structure, an optional boulder, and one readable step():
///
///   clearForces -> computeAxialForces -> computeBoulderContacts (with face friction)
///     -> computeLateralForces -> computeGroundForces -> integrate -> checkState
///
/// Integration is the leapfrog (velocity at half steps, positions at full
/// steps). Energy is accounted per step: kinetic energy as 1/2 m v(n-1/2).v(n+1/2)
/// (a quantity the leapfrog conserves exactly for a linear system), elastic
/// energy from the current forces, plastic and friction dissipation from the
/// laws' own history variables. Their sum stays equal to the initial energy
/// up to the integrator's error at contact kinks, which is what
/// balance_rel_error measures.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "bridge/state_archive.hpp"
#include "macro/structure.hpp"

namespace gabion::macro {

using Vec3 = Eigen::Vector3d;

/// A spherical boulder about to strike the front face.
struct BoulderSpec {
  double diameter_m = 0.5;        ///< (m)
  double mass_kg = 170.0;         ///< (kg)
  double density_kg_m3 = 2597.0;  ///< mass over the sphere's volume (kg/m3)
  /// Gives it another mass: its diameter follows at its density, unless
  /// `keep_diameter` (its density follows).
  void setMass(double mass, bool keep_diameter);
  Vec3 velocity_m_s{20.0, 0, 0};  ///< velocity vector (m/s); its x component must be > 0
  double aim_y_m = 0.0;           ///< where the centre's path meets the front plane (m)
  double aim_z_m = 0.0;           ///< (m)
  double initial_gap_m = 1e-3;    ///< gap between the sphere and the front plane at t = 0 (m)
  /// Boulder-face friction (3-D kinematics; x-only guides the boulder along
  /// x): Coulomb coefficient, and the tangential spring (N/m; 0: each face's
  /// impact-law stiffness).
  double face_friction = 0.5;
  double face_tangential_stiffness_N_m = 0.0;
  double gravity_m_s2 = 0.0;  ///< gravity on the boulder, along -z (3-D kinematics only)
};

/// What step() found. Perforation: the boulder's centre went past the middle
/// of a front cell (or nearer an open side than the front), or a cell was
/// crushed beyond its lock-up (failure() says which).
enum class StepStatus { Ok, NonFinite, Perforation };

/// Energy of the model (J). Plastic and friction are accumulated since the
/// model was built; kinetic includes the boulder.
struct Energy {
  double kinetic_J = 0.0;  ///< translation of the nodes and the boulder, and the boulder's rotation
  double elastic_J = 0.0;
  double plastic_J = 0.0;
  double friction_J = 0.0;
  double potential_J = 0.0;  ///< the boulder's weight: M g (z - z at placement) (J)
  /// Work of the external node forces (setExternalForce) since the model was
  /// built, sum of F(n) . (u(n+1) - u(n)) (J): energy that came in, so
  /// total() - external_work_J stays at the initial energy. Not in total().
  double external_work_J = 0.0;
  double total() const { return kinetic_J + elastic_J + plastic_J + friction_J + potential_J; }
};

class Model {
 public:
  Model(Structure structure, Kinematics kinematics);

  const Structure& structure() const { return s_; }
  Kinematics kinematics() const { return kin_; }

  /// Upper bound of the leapfrog's stability limit dt_crit = 2 / omega_max,
  /// with omega_max^2 bounded by Gershgorin's theorem: max over degrees of
  /// freedom of 2 (sum of the tangent stiffnesses acting on it) / mass (s).
  /// Includes the boulder's contacts when a boulder is placed.
  double criticalTimeStep() const;

  /// Puts a boulder in front of the structure on the line through the aim
  /// point (on the foremost front plane) along its velocity, `initial_gap_m`
  /// from that plane. Throws std::invalid_argument for an impossible boulder.
  void placeBoulder(const BoulderSpec& b);
  void removeBoulder();
  /// Sets every node's velocity to zero (kinetic damping while relaxing).
  void stopNodes();
  bool hasBoulder() const { return boulder_.present; }

  /// Applies a force (N) to node `node` at every step from the next one on,
  /// until changed: what a part of the structure resolved at the fine scale
  /// exerts on its macro neighbours (the hybrid structure). x-only
  /// kinematics takes its x component (the others go to the constraint).
  void setExternalForce(std::size_t node, const Vec3& force_N);
  void clearExternalForces();

  /// The state that changes during a run (nodes, links' history, boulder,
  /// energy, time), into or out of a checkpoint (bridge/state_archive.hpp):
  /// a model built from the same structure, then loaded, steps on exactly as
  /// the one saved would have.
  void archive(bridge::StateArchive& a);

  /// Advances by dt (s). `damping_rate_1_s` > 0 adds mass-proportional viscous
  /// damping (used only to bring the structure to rest between impacts; the
  /// energy it removes is not part of the balance).
  StepStatus step(double dt, double damping_rate_1_s = 0.0);

  // Read access to the state (SI units).
  double time_s() const { return time_; }
  long long steps() const { return steps_; }
  const Energy& energy() const { return energy_; }
  const std::vector<double>& ux() const { return ux_; }
  const std::vector<double>& uy() const { return uy_; }
  const std::vector<double>& uz() const { return uz_; }
  const std::vector<double>& vx() const { return vx_; }
  const std::vector<double>& vy() const { return vy_; }
  const std::vector<double>& vz() const { return vz_; }
  /// Axial (x) compressive force of each cell: mean of its front and back loads (N).
  const std::vector<double>& cellAxialForce() const { return cell_axial_; }
  /// Force of each axial link (x-neighbours and back supports, Structure::axial order) (N).
  const std::vector<double>& axialForce() const { return axial_force_; }
  /// Plastic shortening of each axial link (m).
  const std::vector<double>& axialPlastic() const { return axial_plastic_; }
  /// Plastic indentation of each front element (m).
  const std::vector<double>& frontPlastic() const { return front_plastic_; }
  /// Normal spring force and plastic shortening of each lateral link (3-D only;
  /// Structure::lateral order) (N, m).
  const std::vector<double>& lateralForce() const { return lat_force_; }
  const std::vector<double>& lateralPlastic() const { return lat_plastic_; }
  /// Force and plastic sinking of each ground link's normal spring (3-D only;
  /// Structure::ground order) (N, m).
  const std::vector<double>& groundForce() const { return gnd_force_; }
  const std::vector<double>& groundPlastic() const { return gnd_plastic_; }

  const Vec3& boulderPosition() const { return bpos_; }
  /// Boulder centre where the last step evaluated the forces, x(n) (m).
  const Vec3& boulderPositionAtForces() const { return bpos_force_; }
  /// Boulder velocity at the last full step, mean of the two half steps (m/s).
  const Vec3& boulderVelocity() const { return bvel_full_; }
  /// Total contact force on the boulder at the last step (N).
  const Vec3& boulderForce() const { return bforce_; }
  /// Boulder angular velocity at the last full step (rad/s; 3-D only).
  const Vec3& boulderSpin() const { return bspin_full_; }
  /// Deepest indentation of the boulder into a front element at the last step (m).
  double indentation() const { return max_indent_; }
  /// Number of front elements in contact at the last step.
  int contacts() const { return n_contacts_; }
  const std::string& failure() const { return failure_; }

 private:
  void clearForces();
  void computeAxialForces(double dt);
  void computeBoulderContacts(double dt);
  double faceFriction(std::size_t el, std::size_t node, const Vec3& n, double fn, double dt, double& elastic);
  double openSideDistance(std::size_t el, double y0, double z0) const;
  void computeLateralForces(double dt);
  void computeGroundForces(double dt);
  void integrate(double dt, double damping_rate_1_s);
  StepStatus checkState();

  Structure s_;
  Kinematics kin_;
  bool three_d_;

  // Nodes.
  std::vector<double> ux_, uy_, uz_, vx_, vy_, vz_, fx_, fy_, fz_, cell_axial_;
  // External node forces (empty: none).
  std::vector<double> ext_x_, ext_y_, ext_z_;
  // Axial links: plastic shortening, force, tangential face forces (3-D).
  std::vector<double> axial_plastic_, axial_force_, axial_ft1_, axial_ft2_;
  std::vector<double> axial_dashpot_;  // the fill's rate term at the last step (N), for its work
  double flux_rate_bound_m_s_ = 0.0;   // the fastest boulder placed: bounds the links' shortening rates
  // Lateral links: tangential force along x and along the other lateral axis
  // (3-D), normal spring plastic shortening and force (3-D).
  std::vector<double> lat_ftx_, lat_fto_, lat_plastic_, lat_force_;
  // Ground links.
  std::vector<double> gnd_ftx_, gnd_fty_, gnd_plastic_, gnd_force_;
  // Front elements: plastic indentation; boulder-face tangential force on the
  // boulder and tangential stiffness (3-D).
  std::vector<double> front_plastic_;
  std::vector<double> front_overstress_;  // the rate term's overstress at the last evaluation (N)
  std::vector<Vec3> front_ft_;
  std::vector<double> front_kt_;

  struct Boulder {
    bool present = false;
    double radius_m = 0.0, mass_kg = 0.0;
    double inertia_kg_m2 = 0.0;  // 2/5 M R^2
    double friction = 0.0;       // boulder-face Coulomb coefficient
    double gravity_m_s2 = 0.0;
    double z0_m = 0.0;  // height at placement (potential energy's zero)
  } boulder_;
  Vec3 bpos_ = Vec3::Zero(), bpos_force_ = Vec3::Zero(), bvel_ = Vec3::Zero(), bvel_full_ = Vec3::Zero(),
       bforce_ = Vec3::Zero();
  Vec3 bspin_ = Vec3::Zero(), bspin_full_ = Vec3::Zero(), btorque_ = Vec3::Zero();  // rotation (3-D)
  double max_indent_ = 0.0;
  int n_contacts_ = 0;
  int lost_front_ = -1;  // front element whose cube the boulder's centre went deeper into than the model follows
  bool lost_past_middle_ = false;  // (or nearer an open side than the front)
  int crushed_link_ = -1;          // first axial link shortened past its crushing shortening (-1: none)
  int crushed_front_ = -1;         // first front element indented past it (-1: none)

  double time_ = 0.0;
  long long steps_ = 0;
  Energy energy_;
  double elastic_acc_ = 0.0;  // elastic energy summed during the force stages
  std::string failure_;
};

}  // namespace gabion::macro
