#pragma once
/// \file
/// The energy ledger of the fine DEM: dissipations and the work of moving
/// walls and driven spheres accumulate every step; the stored terms
/// (kinetic, potential, elastic) and the wires' plastic work (a function of
/// their state) are taken on measuring steps. The balance
/// E = kinetic + gravity + elastic + dissipated - wall work - driven work is constant in
/// an exact integration; its relative drift is reported, and stored energy
/// far above all the energy ever supplied is a runaway (docs/micro.md).
#include <string>
#include <utility>
#include <vector>

#include "bridge/state_archive.hpp"

namespace gabion::micro {

/// Energy terms of the whole system (J). balance_rel_error is
/// (E(t) - E(0)) / scale with E = kinetic + gravity + elastic + dissipated - wall work - driven work,
/// and scale the most energy moved around so far (a running maximum: it never vanishes).
struct EnergyTotals {
  double kinetic_translational_J = 0.0;
  double kinetic_rotational_J = 0.0;
  double gravity_potential_J = 0.0;  ///< -sum m g.x (zero at the origin)
  double elastic_contact_J = 0.0;    ///< normal + shear springs of all contacts
  double elastic_link_J = 0.0;       ///< links (micro/links.hpp)
  double friction_dissipation_J = 0.0;
  double plastic_dissipation_J = 0.0;  ///< F_lim normal cap
  double local_damping_dissipation_J = 0.0;
  double viscous_damping_dissipation_J = 0.0;
  double link_rupture_dissipation_J = 0.0;  ///< energy held by links when they broke
  double link_plastic_dissipation_J = 0.0;  ///< plastic work of the wires (bridge/laws/wire.hpp)
  double wall_work_J = 0.0;                 ///< work done by moving walls on the bodies
  double driven_work_J = 0.0;  ///< work done by driven spheres (fixed, moving) and wires pulled tight on the bodies
  double total_J = 0.0;        ///< E above
  double balance_rel_error = 0.0;
};

/// Every term of EnergyTotals with its name, in the order of the output
/// series (`/series/<name>` in result.h5, `energy` in summary.json).
const std::vector<std::pair<std::string, double EnergyTotals::*>>& energyTerms();

class EnergyLedger {
 public:
  // Running sums since the start (J).
  double friction = 0.0, plastic = 0.0, viscous = 0.0, local = 0.0, wall_work = 0.0, driven_work = 0.0,
         link_rupture = 0.0;
  // Terms of the current measuring step (J): stored, and the wires' plastic
  // work (a function of their state, summed over the links like the stored terms).
  double elastic_contact = 0.0, elastic_link = 0.0, ke_t = 0.0, ke_r = 0.0, pe = 0.0, link_plastic = 0.0;
  /// The kinetic energy at the latest half step, (1/2) m v+^2 + (1/2) I w+^2
  /// (J): how fast the bodies move now, what a stage's "at rest" criterion
  /// reads (the balance uses the time-centred ke_t and ke_r).
  double kinetic_now = 0.0;

  /// Closes a measuring step: fills totals() and the balance. Returns false
  /// when the stored energy exceeds runaway_factor x the energy supplied.
  bool close(double runaway_factor);
  const EnergyTotals& totals() const { return totals_; }
  /// The stored (kinetic + elastic) energy and the energy supplied of the
  /// last close(), for a runaway message.
  double stored() const { return stored_; }
  double supplied() const { return supplied_; }
  /// The name of the first term of the last close() that is NaN or infinite
  /// (a stiffness that underflows, a force that overflows), or nullptr.
  const char* nonFiniteTerm() const;
  /// Every sum and reference of the ledger, into or out of a checkpoint.
  void archive(bridge::StateArchive& a);

 private:
  EnergyTotals totals_;
  double e0_ = 0.0, scale0_ = 0.0, pe0_ = 0.0, stored_ = 0.0, supplied_ = 0.0, scale_ = 0.0;
  bool have_e0_ = false;
};

}  // namespace gabion::micro
