#include "micro/energy.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace gabion::micro {

const std::vector<std::pair<std::string, double EnergyTotals::*>>& energyTerms() {
  static const std::vector<std::pair<std::string, double EnergyTotals::*>> terms = {
      {"kinetic_translational_J", &EnergyTotals::kinetic_translational_J},
      {"kinetic_rotational_J", &EnergyTotals::kinetic_rotational_J},
      {"gravity_potential_J", &EnergyTotals::gravity_potential_J},
      {"elastic_contact_J", &EnergyTotals::elastic_contact_J},
      {"elastic_link_J", &EnergyTotals::elastic_link_J},
      {"friction_dissipation_J", &EnergyTotals::friction_dissipation_J},
      {"plastic_dissipation_J", &EnergyTotals::plastic_dissipation_J},
      {"local_damping_dissipation_J", &EnergyTotals::local_damping_dissipation_J},
      {"viscous_damping_dissipation_J", &EnergyTotals::viscous_damping_dissipation_J},
      {"link_rupture_dissipation_J", &EnergyTotals::link_rupture_dissipation_J},
      {"link_plastic_dissipation_J", &EnergyTotals::link_plastic_dissipation_J},
      {"wall_work_J", &EnergyTotals::wall_work_J},
      {"driven_work_J", &EnergyTotals::driven_work_J},
      {"total_J", &EnergyTotals::total_J},
      {"balance_rel_error", &EnergyTotals::balance_rel_error}};
  return terms;
}

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
  // Scale of the balance: the most energy ever moved around (stored,
  // exchanged with gravity, dissipated, worked). A running maximum, so it
  // never vanishes: a ball at the top of an undamped bounce has almost no
  // energy in motion, and a scale taken at that instant would blow the
  // round-off of the contacts up into a large relative error.
  scale_ = std::max({scale_, scale0_, stored + std::fabs(e.gravity_potential_J - pe0_) + dissipated + std::fabs(work)});
  e.balance_rel_error = scale_ > 0.0 ? (e.total_J - e0_) / scale_ : 0.0;
  stored_ = stored;
  // The energy supplied: the most ever given by the initial motion, gravity
  // and the walls. A running maximum for the same reason: a runaway is
  // stored energy far above anything the system was ever given, not above
  // what it holds at one instant of a conservative motion.
  supplied_ = std::max(supplied_, scale0_ + std::fabs(e.gravity_potential_J - pe0_) + std::fabs(work));
  return !(stored > runaway_factor * supplied_ && stored > 0.0);
}

const char* EnergyLedger::nonFiniteTerm() const {
  for (const auto& [name, member] : energyTerms())
    if (!std::isfinite(totals_.*member)) return name.c_str();
  return nullptr;
}

void EnergyLedger::archive(bridge::StateArchive& a) {
  a("friction", friction), a("plastic", plastic), a("viscous", viscous), a("local", local);
  a("wall_work", wall_work), a("driven_work", driven_work), a("link_rupture", link_rupture);
  a("elastic_contact", elastic_contact), a("elastic_link", elastic_link), a("ke_t", ke_t), a("ke_r", ke_r);
  a("pe", pe), a("link_plastic", link_plastic), a("kinetic_now", kinetic_now);
  bridge::StateArchive t = a.group("totals");
  for (const auto& [name, member] : energyTerms()) t(name, totals_.*member);
  a("e0", e0_), a("scale0", scale0_), a("pe0", pe0_), a("stored", stored_), a("supplied", supplied_);
  a("scale", scale_), a("have_e0", have_e0_);
}

}  // namespace gabion::micro
