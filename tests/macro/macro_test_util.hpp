#pragma once
// Small structures and laws for the macro tests.
#include "bridge/law_file.hpp"
#include "macro/impact.hpp"
#include "macro/structure.hpp"

namespace gabion::macro::testing {

inline bridge::AxialLawParams epp(double k, double fy) {
  return {bridge::AxialModel::ElasticPerfectlyPlastic, k, fy, 0.0};
}

/// One material with the given laws (elastic unless the yield forces are reached).
inline bridge::LawFile oneMaterial(const bridge::AxialLawParams& axial, const bridge::AxialLawParams& impact,
                                   double mass_kg, double reaction = 0.4, double friction = 0.5, double kt = 3e6,
                                   double edge_m = 0.5) {
  bridge::CellMaterial c;
  c.edge_m = edge_m;
  c.mass_kg = mass_kg;
  c.axial = axial;
  c.impact = impact;
  c.lateral.reaction_coefficient = reaction;
  c.interface = {friction, kt};
  c.provenance = {{"status", "illustrative"}};
  bridge::LawFile f;
  f.materials["cell"] = c;
  return f;
}

inline StructureSpec grid(int nx, int ny, int nz) {
  StructureSpec s;
  s.nx = nx;
  s.ny = ny;
  s.nz = nz;
  return s;
}

/// A boulder aimed at the centre of front cell (j, k), touching at t = 0.
inline BoulderSpec boulderAt(const Structure& s, int j, int k, double mass_kg, double speed_m_s,
                             double diameter_m = 0.5) {
  BoulderSpec b;
  b.diameter_m = diameter_m;
  b.mass_kg = mass_kg;
  b.velocity_m_s = {speed_m_s, 0, 0};
  b.aim_y_m = (j + 0.5) * s.edge_m;
  b.aim_z_m = (k + 0.5) * s.edge_m;
  b.initial_gap_m = 0.0;
  return b;
}

inline RunSettings quickRun(double duration_s, double fraction = 0.05) {
  RunSettings r;
  r.duration_s = duration_s;
  r.time_step_fraction = fraction;
  r.relax = false;
  return r;
}

}  // namespace gabion::macro::testing
