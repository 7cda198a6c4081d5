#include "micro/energy.hpp"

#include <algorithm>
#include <cmath>

namespace gabion::micro {

bool EnergyLedger::close(double runaway_factor) {
  EnergyTotals& e = totals_;
  e.kinetic_translational_J = ke_t;
  e.kinetic_rotational_J = ke_r;
  e.gravity_potential_J = pe;
  e.elastic_contact_J = elastic_contact;
  e.elastic_link_J = elastic_link;
  e.friction_dissipation_J = friction;
  e.plastic_dissipation_J = plastic;
  e.local_damping_dissipation_J = local;
  e.viscous_damping_dissipation_J = viscous;
  e.link_rupture_dissipation_J = link_rupture;
  e.link_plastic_dissipation_J = link_plastic;
  e.wall_work_J = wall_work;
  e.driven_work_J = driven_work;
  const double stored = e.kinetic_translational_J + e.kinetic_rotational_J + e.elastic_contact_J + e.elastic_link_J;
  const double dissipated = e.friction_dissipation_J + e.plastic_dissipation_J + e.local_damping_dissipation_J +
                            e.viscous_damping_dissipation_J + e.link_rupture_dissipation_J +
                            e.link_plastic_dissipation_J;
  const double work = e.wall_work_J + e.driven_work_J;
  e.total_J = stored + e.gravity_potential_J + dissipated - work;
  if (!have_e0_) {
    have_e0_ = true;
    e0_ = e.total_J;
    pe0_ = e.gravity_potential_J;
    scale0_ = stored;
  }
  // Scale of the balance: all the energy that has been moved around.
  const double scale =
      std::max(scale0_, stored + std::fabs(e.gravity_potential_J - pe0_) + dissipated + std::fabs(work));
  e.balance_rel_error = scale > 0.0 ? (e.total_J - e0_) / scale : 0.0;
  stored_ = stored;
  supplied_ = scale0_ + std::fabs(e.gravity_potential_J - pe0_) + std::fabs(work);
  return !(stored > runaway_factor * supplied_ && stored > 0.0);
}

}  // namespace gabion::micro
