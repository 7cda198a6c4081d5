#include "macro/case_reader.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/units.hpp"

namespace gabion::macro {

using bridge::Check;
using bridge::InputError;
using bridge::JsonDocument;
using bridge::JsonReader;

namespace {

// The most cells a structure may have.
constexpr double kMaxCells = 1e7;

int readInt(const JsonReader& r, const std::string& key, double v, int minimum) {
  if (v != std::floor(v) || v < minimum || v > 1e6) r.fail(key, "expected integers >= " + std::to_string(minimum));
  return static_cast<int>(v);
}

StructureSpec readStructure(const JsonReader& st) {
  StructureSpec s;
  const auto cells = st.numbers("cells", Check::Positive, 3);
  if (cells.size() != 3) st.fail("cells", "expected [x (depth), y (width), z (height)] cell counts");
  s.nx = readInt(st, "cells", cells[0], 1);
  s.ny = readInt(st, "cells", cells[1], 1);
  s.nz = readInt(st, "cells", cells[2], 1);
  // (the model takes about 450 B a cell: `gabion check` on 100 x 100 x 100
  // cells peaks at 459 MB; each snapshot of a run adds 32 B a cell)
  const double count = static_cast<double>(s.nx) * s.ny * s.nz;
  if (count > kMaxCells) {
    std::ostringstream m;
    m << bridge::showNumber(count) << " cells, more than " << bridge::showNumber(kMaxCells)
      << ": the model alone would take about " << bridge::showNumber(count * 450.0 / 1e9) << " GB";
    st.fail("cells", m.str());
  }
  if (st.has("front_offset_cells")) {
    const auto off = st.numbers("front_offset_cells", Check::NonNegative, 1);
    if (static_cast<int>(off.size()) != s.nz)
      st.fail("front_offset_cells", "expected one offset per z layer (" + std::to_string(s.nz) + ")");
    for (double o : off) {
      const int v = readInt(st, "front_offset_cells", o, 0);
      if (v >= s.nx)
        st.fail("front_offset_cells",
                "an offset must leave at least one cell in the layer (< " + std::to_string(s.nx) + ")");
      s.front_offset_cells.push_back(v);
    }
  }
  if (const auto m = st.optionalObject("material")) {
    if (m->has("cells")) {
      const auto& list = m->raw("cells");
      if (!list.is_array() || list.empty()) m->fail("cells", "expected a non-empty array of material names");
      for (std::size_t i = 0; i < list.size(); ++i) {
        if (!list[i].is_string())
          throw InputError(m->file(), m->pointer("cells") + "/" + std::to_string(i), "expected a material name");
        s.material.cells.push_back(list[i].get<std::string>());
      }
      if (m->has("front") || m->has("core")) m->fail("cells", "give either 'cells' or the rule 'front'/'core'");
    } else {
      s.material.front = m->string("front");
      s.material.core = m->string("core");
      s.material.front_depth_cells = static_cast<int>(m->integer("front_depth_cells", 1, 0));
    }
  }
  if (const auto sup = st.optionalObject("support")) {
    s.support.fixed_back = sup->choice("back", {"fixed", "free"}, "fixed") == "fixed";
    s.support.ground_friction = sup->choice("ground", {"none", "friction"}, "none") == "friction";
    if (sup->has("ground_friction")) {
      if (!s.support.ground_friction) sup->fail("ground_friction", "only with \"ground\": \"friction\"");
      s.support.ground_friction_coefficient = sup->number("ground_friction", Check::NonNegative);
    }
    s.support.gravity_m_s2 = sup->number("gravity_m_s2", 9.81, Check::Positive);
    if (sup->has("ground_tangential_stiffness_N_m"))
      s.support.ground_tangential_stiffness_N_m = sup->number("ground_tangential_stiffness_N_m", Check::Positive);
  }
  return s;
}

// The velocity is a number (speed along `direction`, default +x, normal to the
// front face) or an array [vx, vy, vz]; the JSON type tells them apart.
void readVelocity(const JsonReader& r, BoulderSpec& b, bool required) {
  Vec3 dir(1, 0, 0);
  const bool has_dir = r.has("direction");
  if (has_dir) {
    dir = r.vec3("direction");
    if (dir.norm() == 0.0) r.fail("direction", "must not be zero");
    dir.normalize();
  }
  if (!r.has("velocity_m_s")) {
    if (required) r.number("velocity_m_s");  // throws "missing required key"
    if (has_dir) b.velocity_m_s = b.velocity_m_s.norm() * dir;
    return;
  }
  if (r.value().at("velocity_m_s").is_array()) {
    if (has_dir) r.fail("direction", "give either a velocity vector or a speed with a direction");
    b.velocity_m_s = r.vec3("velocity_m_s");
  } else {
    b.velocity_m_s = r.number("velocity_m_s", Check::Positive) * dir;
  }
  if (!(b.velocity_m_s.x() > 0.0)) r.fail("velocity_m_s", "the boulder must move towards the front face (+x)");
}

void readAim(const JsonReader& r, BoulderSpec& b, bool& given) {
  if (!r.has("aim_point_m")) return;
  const auto a = r.numbers("aim_point_m", Check::Finite, 2);
  if (a.size() != 2) r.fail("aim_point_m", "expected [y, z] on the front face (m)");
  b.aim_y_m = a[0];
  b.aim_z_m = a[1];
  given = true;
}

BoulderSpec readBoulder(const JsonReader& r, bool& aim_given) {
  BoulderSpec b;
  // Any two of diameter, mass and density give the third; all three must agree.
  const int given = int{r.has("diameter_m")} + int{r.has("mass_kg")} + int{r.has("density_kg_m3")};
  if (given < 2) r.failHere("give two of diameter_m, mass_kg and density_kg_m3 (the third follows)");
  const double volume_per_d3 = M_PI / 6.0;  // a sphere's volume over its diameter cubed
  if (!r.has("diameter_m")) {
    b.mass_kg = r.number("mass_kg", Check::Positive);
    b.density_kg_m3 = r.number("density_kg_m3", Check::Positive);
    b.diameter_m = std::cbrt(b.mass_kg / (b.density_kg_m3 * volume_per_d3));
  } else {
    b.diameter_m = r.number("diameter_m", Check::Positive);
    const double volume = volume_per_d3 * b.diameter_m * b.diameter_m * b.diameter_m;
    if (r.has("mass_kg")) {
      b.mass_kg = r.number("mass_kg", Check::Positive);
      b.density_kg_m3 = b.mass_kg / volume;
      if (r.has("density_kg_m3")) {
        const double rho = r.number("density_kg_m3", Check::Positive);
        if (std::fabs(rho - b.density_kg_m3) > 1e-3 * rho)
          r.fail("density_kg_m3", "disagrees with mass_kg and diameter_m (they give " +
                                      std::to_string(b.density_kg_m3) + " kg/m3): give two of the three");
      }
    } else {
      b.density_kg_m3 = r.number("density_kg_m3", Check::Positive);
      b.mass_kg = b.density_kg_m3 * volume;
    }
  }
  readVelocity(r, b, true);
  readAim(r, b, aim_given);
  b.initial_gap_m = r.number("initial_gap_m", 1e-3, Check::NonNegative);
  b.face_friction = r.number("face_friction", b.face_friction, Check::NonNegative);
  if (r.has("face_tangential_stiffness_N_m"))
    b.face_tangential_stiffness_N_m = r.number("face_tangential_stiffness_N_m", Check::Positive);
  return b;
}

RunSettings readRun(const JsonReader& root, bool sweep) {
  RunSettings s;
  const auto r = root.optionalObject("run");
  if (!r) return s;
  s.kinematics = r->choice("kinematics", {"x-only", "3d"}, "x-only") == "3d" ? Kinematics::ThreeD : Kinematics::XOnly;
  s.duration_s = r->number("duration_s", s.duration_s, Check::Positive);
  s.max_duration_s = r->number("max_duration_s", 20.0 * s.duration_s, Check::Positive);
  if (s.max_duration_s < s.duration_s) r->fail("max_duration_s", "must be >= duration_s");
  s.rebound_restitution = r->number("rebound_restitution", s.rebound_restitution, Check::UnitOpen);
  s.time_step_fraction = r->number("time_step_fraction", s.time_step_fraction, Check::Positive);
  if (s.time_step_fraction > 1.0) r->fail("time_step_fraction", "must be <= 1 (a fraction of the critical time step)");
  if (r->has("time_step_s")) s.time_step_s = r->number("time_step_s", Check::Positive);
  s.series_every_steps = static_cast<int>(r->integer("series_every_steps", s.series_every_steps, 1));
  s.snapshots = static_cast<int>(r->integer("snapshots", s.snapshots, 2));
  s.max_balance_error = r->number("max_balance_error", s.max_balance_error, Check::Positive);
  s.gravity_m_s2 = r->number("gravity_m_s2", s.gravity_m_s2, Check::NonNegative);
  if (s.gravity_m_s2 > 0.0 && s.kinematics == Kinematics::XOnly)
    r->fail("gravity_m_s2", "gravity on the boulder needs \"kinematics\": \"3d\" (x-only guides it along x)");
  if (sweep) {
    s.relax = false;
  } else {
    s.relax = r->boolean("relax", s.relax);
    s.relax_max_steps = r->integer("relax_max_steps", s.relax_max_steps, 0);
    s.relax_tolerance = r->number("relax_tolerance", s.relax_tolerance, Check::Positive);
  }
  return s;
}

}  // namespace

std::pair<double, double> defaultAim(const StructureSpec& s, double edge_m) {
  return {(s.ny / 2 + 0.5) * edge_m, (s.nz / 2 + 0.5) * edge_m};
}

// Every material the structure names is in the case's laws: an error names
// the key, the law file and the materials it has.
void checkMaterialNames(const JsonDocument& doc, const ImpactCase& c) {
  std::string have;
  for (const auto& [name, m] : c.laws.materials) have += (have.empty() ? "'" : ", '") + name + "'";
  const auto check = [&](const std::string& name, const std::string& pointer) {
    if (!name.empty() && c.laws.materials.count(name) == 0)
      throw InputError(doc.file(), pointer,
                       "material '" + name + "' is not in the laws (" + c.law_source + "), which have " + have);
  };
  const MaterialRule& m = c.structure.material;
  check(m.front, "/structure/material/front");
  check(m.core, "/structure/material/core");
  for (std::size_t i = 0; i < m.cells.size(); ++i) check(m.cells[i], "/structure/material/cells/" + std::to_string(i));
}

ImpactCase readImpactCase(const JsonDocument& doc, bool sweep) {
  const JsonReader root = doc.root();
  ImpactCase c;
  // Laws: embedded, or a law file relative to the case file.
  if (root.has("laws") && root.has("law_file")) root.fail("law_file", "give either 'laws' or 'law_file'");
  if (root.has("laws")) {
    c.laws = bridge::readLawMaterials(root.object("laws").object("materials"));
    c.law_source = "embedded";
  } else if (root.has("law_file")) {
    const std::filesystem::path p = std::filesystem::path(doc.file()).parent_path() / root.string("law_file");
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p, ec)) root.fail("law_file", "no such law file " + p.string());
    c.laws = bridge::loadLawFile(p);
    c.law_source = p.string();
  } else {
    root.fail("law_file", "missing: a case needs 'laws' (embedded materials) or 'law_file'");
  }

  c.structure = readStructure(root.object("structure"));
  checkMaterialNames(doc, c);
  bool aim = false;
  const BoulderSpec base = readBoulder(root.object("boulder"), aim);
  if (!sweep && root.has("impacts")) {
    const auto list = root.objects("impacts", true);
    if (list.empty()) root.fail("impacts", "expected at least one impact (or leave 'impacts' out)");
    for (const auto& r : list) {
      BoulderSpec b = base;
      bool given = aim;
      readVelocity(r, b, false);
      readAim(r, b, given);
      if (r.has("mass_kg")) b.setMass(r.number("mass_kg", Check::Positive), r.boolean("keep_diameter", false));
      c.impacts.push_back(b);
      c.aim_given.push_back(given);
    }
  } else {
    c.impacts.push_back(base);
    c.aim_given.push_back(aim);
  }
  c.run = readRun(root, sweep);
  for (auto& b : c.impacts) b.gravity_m_s2 = c.run.gravity_m_s2;
  if (c.run.kinematics == Kinematics::XOnly)
    for (std::size_t i = 0; i < c.impacts.size(); ++i) {
      const Vec3& v = c.impacts[i].velocity_m_s;
      if (v.y() != 0.0 || v.z() != 0.0) {
        const std::string where = root.has("impacts") && !sweep ? "/impacts/" + std::to_string(i) : "/boulder";
        throw InputError(doc.file(), where + "/velocity_m_s",
                         "x-only kinematics needs a normal impact (velocity along x); set run.kinematics to '3d'");
      }
    }
  return c;
}

void resolveAims(const JsonDocument& doc, ImpactCase& c, const Structure& s) {
  const auto [y, z] = defaultAim(c.structure, s.edge_m);
  for (std::size_t i = 0; i < c.impacts.size(); ++i) {
    BoulderSpec& b = c.impacts[i];
    if (!c.aim_given[i]) {
      b.aim_y_m = y;
      b.aim_z_m = z;
    } else if (b.aim_y_m < 0.0 || b.aim_y_m > s.ny * s.edge_m || b.aim_z_m < 0.0 || b.aim_z_m > s.nz * s.edge_m) {
      const std::string where = doc.root().has("impacts") ? "/impacts/" + std::to_string(i) : "/boulder";
      throw InputError(doc.file(), where + "/aim_point_m",
                       "the aim point is outside the front face [0, " + std::to_string(s.ny * s.edge_m) + "] x [0, " +
                           std::to_string(s.nz * s.edge_m) + "] m");
    }
  }
}

Structure buildCaseStructure(const JsonDocument& doc, const ImpactCase& c) {
  try {
    return buildStructure(c.structure, c.laws);
  } catch (const std::invalid_argument& e) {
    throw InputError(doc.file(), "/structure", e.what());
  }
}

bridge::Estimate impactEstimate(const RunSettings& run, const Structure& s, double critical_s) {
  const double dt = run.time_step_s > 0.0 ? run.time_step_s : run.time_step_fraction * critical_s;
  const double steps = std::ceil(run.max_duration_s / dt);
  return bridge::macroRun(static_cast<double>(s.nodeCount()), steps, steps / run.series_every_steps);
}

void checkImpactCost(const JsonDocument& doc, const RunSettings& run, const Structure& s, double critical_s) {
  const double dt = run.time_step_s > 0.0 ? run.time_step_s : run.time_step_fraction * critical_s;
  const double steps = run.max_duration_s / dt;
  if (steps <= kMaxImpactSteps) return;
  const double samples = steps / run.series_every_steps;
  std::ostringstream m;
  m << "an impact of up to " << run.max_duration_s << " s at a step of " << dt << " s may take " << steps
    << " steps on " << s.nodeCount() << " cells and record " << samples << " samples (about "
    << bridge::showNumber(samples * 14 * 8 / 1e9) << " GB); at most " << kMaxImpactSteps
    << " steps: shorten run.duration_s or run.max_duration_s";
  const auto r = doc.root().optionalObject("run");
  throw InputError(doc.file(), r && r->has("max_duration_s") ? "/run/max_duration_s" : "/run/duration_s", m.str());
}

SweepSpec readSweep(const JsonReader& sw) {
  SweepSpec s;
  auto axis = [&](const std::string& key, Check check) {
    std::vector<double> v;
    if (!sw.has(key)) return v;
    if (sw.value().at(key).is_object()) {
      const JsonReader r = sw.object(key);
      const double from = r.number("from", check), to = r.number("to", check);
      const auto count = r.integer("count", 1);
      for (long long i = 0; i < count; ++i)
        v.push_back(count == 1 ? from : from + (to - from) * static_cast<double>(i) / static_cast<double>(count - 1));
      return v;
    }
    return sw.numbers(key, check, 1);
  };
  s.velocity_m_s = axis("velocity_m_s", Check::Positive);
  s.mass_kg = axis("mass_kg", Check::Positive);
  s.keep_diameter = sw.boolean("keep_diameter", false);
  if (sw.has("aim_point_m")) {
    const auto& list = sw.raw("aim_point_m");
    if (!list.is_array() || list.empty()) sw.fail("aim_point_m", "expected a list of [y, z] points (m)");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto& p = list[i];
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
        throw InputError(sw.file(), sw.pointer("aim_point_m") + "/" + std::to_string(i), "expected [y, z] (m)");
      s.aim_point_m.emplace_back(p[0].get<double>(), p[1].get<double>());
    }
  }
  if (sw.has("cells")) {
    const auto& list = sw.raw("cells");
    if (!list.is_array() || list.empty()) sw.fail("cells", "expected a list of [x, y, z] cell counts");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto& p = list[i];
      bool ok = p.is_array() && p.size() == 3;
      std::array<int, 3> n{};
      for (std::size_t d = 0; ok && d < 3; ++d) {
        ok = p[d].is_number_integer() && p[d].get<long long>() >= 1 && p[d].get<long long>() <= 100000;
        if (ok) n[d] = static_cast<int>(p[d].get<long long>());
      }
      if (!ok)
        throw InputError(sw.file(), sw.pointer("cells") + "/" + std::to_string(i), "expected [x, y, z] integers >= 1");
      if (static_cast<double>(n[0]) * n[1] * n[2] > kMaxCells)
        throw InputError(sw.file(), sw.pointer("cells") + "/" + std::to_string(i),
                         "more than " + bridge::showNumber(kMaxCells) + " cells");
      s.cells.push_back(n);
    }
  }
  s.chart = sw.boolean("chart", true);
  if (const auto l = sw.optionalObject("limits")) {
    s.limit_peak_force_N = l->number("peak_force_N", s.limit_peak_force_N, Check::Positive);
    s.limit_penetration_m = l->number("max_penetration_m", s.limit_penetration_m, Check::Positive);
    s.limit_back_face_m = l->number("max_back_face_displacement_m", s.limit_back_face_m, Check::Positive);
  }
  return s;
}

}  // namespace gabion::macro
