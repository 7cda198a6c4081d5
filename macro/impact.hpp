#pragma once
/// \file
/// Boulder impacts on a macro model: one impact run to its end (results,
/// optional recording of series and snapshots), the structure brought to rest
/// between impacts, and a list of impacts applied one after the other on the
/// damaged structure (residual displacements, plastic state, dents and
/// tangential forces carried over).
#include <string>
#include <vector>

#include "macro/model.hpp"

namespace gabion::macro {

/// How an impact ends (docs/macro.md, Outcome).
enum class Outcome {
  Stopped,    ///< the boulder came to rest on the structure, or left it at less than `rebound_restitution` of its speed
  Rebounded,  ///< it left the structure, moving back at `rebound_restitution` of its speed or more
  Perforated,  ///< it passed the back plane, its centre entered a front cell, or it crushed a cell beyond lock-up
  Unfinished   ///< none of these within max_duration_s
};
const char* outcomeName(Outcome o);

/// How an impact is run (defaults documented in docs/macro.md).
struct RunSettings {
  Kinematics kinematics = Kinematics::XOnly;
  /// Simulated time per impact (s): the impact ends at its outcome, before
  /// this time or after it, up to max_duration_s (the results do not depend
  /// on it); the snapshots are spread over it.
  double duration_s = 0.2;
  double max_duration_s = 0.0;        ///< the longest an impact runs (s); 0: 20 x duration_s
  double rebound_restitution = 0.05;  ///< speed back over speed in above which the boulder rebounded
  double separated_for_ratio = 0.5;   ///< the boulder has left for good once away this long over the contact's duration
  double time_step_fraction = 0.25;   ///< dt = fraction x critical time step (docs/macro.md, Time step)
  double time_step_s = 0.0;           ///< explicit dt (s); 0: from the fraction
  int series_every_steps = 1;         ///< series sampling (steps)
  int snapshots = 41;                 ///< node snapshots per impact (evenly spaced, >= 2)
  bool relax = true;                  ///< bring the structure to rest after each impact
  long long relax_max_steps = 200000;
  double relax_tolerance = 1e-10;   ///< rest: structure kinetic energy < this x impact energy
  double max_balance_error = 0.05;  ///< an energy balance error above this stops the run (numerical failure)
  double gravity_m_s2 = 0.0;        ///< gravity on the boulder (3-D only; copied into each BoulderSpec)
};

/// The results of one impact.
struct ImpactResult {
  bool ok = true;
  std::string message;  ///< why it failed
  Outcome outcome = Outcome::Unfinished;
  std::string perforation;                 ///< how it perforated (empty unless perforated)
  double end_time_s = 0.0;                 ///< when the impact ended, from its start (its outcome, or max_duration_s)
  double input_energy_J = 0.0;             ///< boulder kinetic energy before contact (J)
  double peak_force_N = 0.0;               ///< largest contact force on the boulder (N)
  double time_of_peak_s = 0.0;             ///< from the first contact (s)
  double max_penetration_m = 0.0;          ///< boulder travel into the structure after first contact (m)
  double final_penetration_m = 0.0;        ///< where the boulder was at the outcome, from where it touched (>= 0, m)
  double max_indentation_m = 0.0;          ///< largest indentation of the impact law (m)
  double contact_duration_s = 0.0;         ///< the first contact: first touch to first separation (s)
  int contact_episodes = 0;                ///< contacts: 1 + later re-contacts (the boulder catching up with the face)
  double last_separation_s = 0.0;          ///< from the first touch to the end of the last contact (s)
  double rebound_velocity_m_s = 0.0;       ///< boulder speed back along its incoming direction at the end (m/s)
  double final_spin_rad_s = 0.0;           ///< boulder angular speed at the end (rad/s; 3-D face friction)
  Vec3 final_velocity_m_s = Vec3::Zero();  ///< boulder velocity at the end (m/s)
  bool contact_at_end = false;             ///< still in contact when the run ended
  double max_back_face_displacement_m = 0.0;        ///< largest x displacement of a back cell (m)
  double max_front_face_displacement_m = 0.0;       ///< largest x displacement of a front cell (m)
  double residual_back_face_displacement_m = 0.0;   ///< after relaxation (largest back cell, m)
  double residual_front_face_displacement_m = 0.0;  ///< after relaxation (largest front cell, m)
  int front_cells_pushed_in = 0;  ///< after relaxation: front cells pushed back by more than a tenth of an edge
  bool relaxed = false, relax_converged = false;
  long long relax_steps = 0;
  int loaded_cells = 0;  ///< cells whose axial force exceeded 10 % of the peak boulder force
  double kinetic_J = 0.0, elastic_J = 0.0, plastic_J = 0.0, friction_J = 0.0,
         potential_J = 0.0;        ///< at the end of the impact (J); plastic and friction: this impact
  double balance_rel_error = 0.0;  ///< max over the impact of |E(t) - E(0)| / E(0)
  double time_step_s = 0.0, critical_time_step_s = 0.0;
  long long steps = 0;
};

/// What is recorded of an impact for result.h5 (appended to across impacts).
struct Recording {
  // Series, one entry per sample.
  std::vector<double> time_s, impact, force_N, force_x_N, velocity_x_m_s, speed_m_s, penetration_m, indentation_m,
      contacts, kinetic_J, elastic_J, plastic_J, friction_J, back_displacement_m;
  // Snapshots: time and (nodes x 3) displacement and (nodes) axial force per snapshot.
  std::vector<double> snap_time_s, snap_displacement_m, snap_axial_force_N;
  double time_offset_s = 0.0;  ///< added to the impact's own time (impacts follow one another)
};

/// Runs one impact of `boulder` on `model` until its outcome (at most
/// run.max_duration_s); relaxes the structure afterwards when run.relax. A
/// perforation is an outcome; failures (time step above the critical one,
/// non-finite state, energy balance runaway, a boulder that never touches)
/// give ok = false and a message, the model then left as it was.
ImpactResult runImpact(Model& model, const BoulderSpec& boulder, const RunSettings& run, int impact_index,
                       Recording* recording);

/// Brings the structure to rest with mass-proportional damping (no boulder).
/// Returns the number of steps; `converged` tells whether the kinetic energy
/// fell below `tolerance_J` within `max_steps`.
long long relax(Model& model, double dt, long long max_steps, double tolerance_J, bool& converged);

}  // namespace gabion::macro
