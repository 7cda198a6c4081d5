#include "micro/netting/netting_input.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "micro/netting/wire_input.hpp"

namespace gabion::micro {

using bridge::Check;
using bridge::JsonReader;

NettingInput parseNetting(const JsonReader& r, const MeshSpec& defaults) {
  NettingInput in;
  MeshSpec& m = in.mesh;
  m = defaults;
  r.choice("mesh", {"hexagonal_double_twist"}, "hexagonal_double_twist");
  m.opening_m = r.number("opening_m", m.opening_m, Check::Positive);
  m.twist_length_m = r.number("twist_length_m", m.twist_length_m, Check::Positive);
  m.wire_rise_m = r.number("wire_rise_m", m.wire_rise_m, Check::Positive);
  m.wire_diameter_m = r.number("wire_diameter_m", m.wire_diameter_m, Check::Positive);
  m.selvedge_diameter_m = r.number("selvedge_diameter_m", m.selvedge_diameter_m, Check::Positive);
  m.lacing_diameter_m = r.number("lacing_diameter_m", m.lacing_diameter_m, Check::Positive);
  m.table = parseWireTable(r, "stress_strain");
  m.twist = parseDoubleTwist(r, "double_twist", m.table);
  m.steel_density_kg_m3 = r.number("steel_density_kg_m3", m.steel_density_kg_m3, Check::Positive);
  if (r.has("node_radius_m")) m.node_radius_m = r.number("node_radius_m", Check::Positive);
  if (r.has("node_mass_kg")) m.node_mass_kg = r.number("node_mass_kg", Check::Positive);
  m.node_mass_scale = r.number("node_mass_scale", m.node_mass_scale, Check::Positive);
  m.wire_beads = static_cast<int>(r.integer("wire_beads", m.wire_beads, 0));
  m.bending = r.boolean("bending", m.bending);
  if (m.wire_beads > 8) r.fail("wire_beads", "at most 8 beads per wire");
  if (m.node_mass_scale < 1.0) r.fail("node_mass_scale", "must be >= 1 (it scales the node masses up)");
  // Nodes sit at the ends of the wires: a node wider than half the shortest
  // wire would touch its neighbours' nodes before any load.
  const double shortest = std::min(m.twist_length_m, std::hypot(0.5 * m.opening_m, m.wire_rise_m) / (m.wire_beads + 1));
  if (!(m.nodeRadius() < 0.5 * shortest))
    r.fail(r.has("node_radius_m") ? "node_radius_m" : "wire_diameter_m",
           "the node radius (" + std::to_string(m.nodeRadius()) + " m) must be below half the shortest wire piece (" +
               std::to_string(shortest) + " m)");

  Material& c = in.contact;
  c.name = "netting";
  c.density_kg_m3 = m.steel_density_kg_m3;
  c.normal_stiffness_N_m = 1e6;
  c.shear_stiffness_N_m = 2.5e5;
  c.friction = 0.3;
  if (const auto k = r.optionalObject("contact")) {
    c.normal_stiffness_N_m = k->number("normal_stiffness_N_m", c.normal_stiffness_N_m, Check::Positive);
    c.shear_stiffness_N_m = k->number("shear_stiffness_N_m", c.shear_stiffness_N_m, Check::Positive);
    c.friction = k->number("friction", c.friction, Check::NonNegative);
    c.local_damping = k->number("local_damping", 0.0, Check::UnitOpen);
    c.viscous_damping_ratio = k->number("viscous_damping_ratio", 0.0, Check::UnitOpen);
  }
  return in;
}

}  // namespace gabion::micro
