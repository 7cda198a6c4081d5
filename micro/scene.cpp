#include "micro/scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "bridge/errors.hpp"
#include "micro/blocks/block_fill.hpp"
#include "micro/cell/cell_file.hpp"
#include "micro/netting/scene_nettings.hpp"
#include "micro/netting/wire_input.hpp"
#include "micro/particles.hpp"
#include "micro/rigid_body.hpp"

namespace gabion::micro {
namespace {

using bridge::Check;
constexpr int kMaxGroup = kGroupCount - 1;
constexpr const char* kWallNameRule = "a wall name uses letters, digits, '_' and '-' only (it names the wall's series)";
using bridge::JsonReader;

int materialIndex(const JsonReader& r, const std::map<std::string, int>& names) {
  const std::string name = r.string("material");
  const auto it = names.find(name);
  if (it == names.end()) {
    std::string known;
    for (const auto& [n, i] : names) known += (known.empty() ? "" : ", ") + n;
    r.fail("material", "unknown material '" + name + "' (known: " + known + ")");
  }
  return it->second;
}

}  // namespace

Material parseMaterial(const std::string& name, const JsonReader& r) {
  Material m;
  m.name = name;
  m.density_kg_m3 = r.number("density_kg_m3", Check::Positive);
  m.normal_stiffness_N_m = r.number("normal_stiffness_N_m", Check::Positive);
  m.shear_stiffness_N_m = r.number("shear_stiffness_N_m", Check::Positive);
  m.friction = r.number("friction", Check::NonNegative);
  if (r.has("normal_force_limit_N")) m.normal_force_limit_N = r.number("normal_force_limit_N", Check::Positive);
  m.local_damping = r.number("local_damping", 0.0, Check::UnitOpen);
  m.viscous_damping_ratio = r.number("viscous_damping_ratio", 0.0, Check::UnitOpen);
  return m;
}

ContactPairInput parseContactPair(const JsonReader& r) {
  ContactPairInput in;
  in.file = r.file();
  in.pointer = r.pointer();
  const nlohmann::json& names = r.raw("materials");
  if (!names.is_array() || names.size() != 2 || !names[0].is_string() || !names[1].is_string())
    r.fail("materials", "expected the names of two materials, e.g. [\"rock\", \"netting\"]");
  in.name_a = names[0].get<std::string>(), in.name_b = names[1].get<std::string>();
  ContactPair& p = in.pair;
  p.normal_stiffness_N_m = r.optionalNumber("normal_stiffness_N_m", Check::Positive);
  p.shear_stiffness_N_m = r.optionalNumber("shear_stiffness_N_m", Check::Positive);
  p.friction = r.optionalNumber("friction", Check::NonNegative);
  p.viscous_damping_ratio = r.optionalNumber("viscous_damping_ratio", Check::UnitOpen);
  if (r.has("normal_force_limit_N")) {
    const nlohmann::json& v = r.raw("normal_force_limit_N");
    if (v.is_string()) {
      if (v.get<std::string>() != "none") r.fail("normal_force_limit_N", "a force (N) > 0, or \"none\" (no cap)");
      p.normal_force_limit_N = std::numeric_limits<double>::infinity();
    } else {
      p.normal_force_limit_N = r.number("normal_force_limit_N", Check::Positive);
    }
  }
  return in;
}

ContactPair resolveContactPair(const ContactPairInput& in, const std::vector<Material>& materials) {
  ContactPair p = in.pair;
  std::string known;
  for (const Material& m : materials) known += (known.empty() ? "" : ", ") + m.name;
  const auto index = [&](const std::string& name, int k) {
    for (std::size_t m = 0; m < materials.size(); ++m)
      if (materials[m].name == name) return static_cast<int>(m);
    throw bridge::InputError(in.file, in.pointer + "/materials/" + std::to_string(k),
                             "unknown material '" + name + "' (known: " + known + ")");
  };
  p.a = index(in.name_a, 0), p.b = index(in.name_b, 1);
  return p;
}

WallSpec fixedWall(const std::string& name, const Vec3& point, const Vec3& normal, int material) {
  WallSpec w;
  w.name = name;
  w.point_m = point;
  w.normal = normal;
  w.material = material;
  return w;
}

RunSpec parseRun(const JsonReader& run, double default_duration_s) {
  RunSpec rs;
  rs.duration_s = default_duration_s > 0.0 ? run.number("duration_s", default_duration_s, Check::Positive)
                                           : run.number("duration_s", Check::Positive);
  if (run.has("dt_s")) rs.dt_s = run.number("dt_s", Check::Positive);
  rs.dt_safety = run.number("dt_safety", 0.2, Check::Positive);
  if (rs.dt_safety > 1.0) run.fail("dt_safety", "must be <= 1 (a fraction of the critical step)");
  if (run.has("link_dt_safety")) {
    rs.link_dt_safety = run.number("link_dt_safety", Check::Positive);
    if (rs.link_dt_safety > 1.0)
      run.fail("link_dt_safety", "must be <= 1 (a fraction of the link nodes' critical step)");
  }
  rs.allow_dt_above_critical = run.boolean("allow_dt_above_critical", false);
  rs.output_interval_s = run.number("output_interval_s", rs.duration_s / 100.0, Check::Positive);
  rs.series_interval_s = run.number("series_interval_s", rs.output_interval_s, Check::Positive);
  rs.max_overlap_ratio = run.number("max_overlap_ratio", 0.5, Check::Positive);
  if (rs.max_overlap_ratio > 1.0) run.fail("max_overlap_ratio", "must be <= 1");
  rs.energy_runaway_factor = run.number("energy_runaway_factor", 10.0, Check::Positive);
  if (rs.energy_runaway_factor <= 1.0) run.fail("energy_runaway_factor", "must be > 1");
  rs.max_balance_error = run.number("max_balance_error", rs.max_balance_error, Check::Positive);
  rs.verlet_skin_ratio = run.number("verlet_skin_ratio", 0.2, Check::Positive);
  if (rs.verlet_skin_ratio > 2.0) run.fail("verlet_skin_ratio", "must be <= 2");
  rs.checkpoint_every_s = run.number("checkpoint_every_s", rs.checkpoint_every_s, Check::NonNegative);
  return rs;
}

namespace {

Eigen::Quaterniond quaternion(const JsonReader& r, const std::string& key) {
  if (!r.has(key)) return Eigen::Quaterniond::Identity();
  const auto q = r.numbers(key, Check::Finite, 4);
  if (q.size() != 4) r.fail(key, "expected 4 numbers [w, x, y, z], got " + std::to_string(q.size()));
  Eigen::Quaterniond out(q[0], q[1], q[2], q[3]);
  const double norm = out.norm();
  if (!(norm > 1e-12)) r.fail(key, "quaternion must not be zero");
  if (std::fabs(norm - 1.0) > 1e-6) r.fail(key, "quaternion must have unit length (got " + std::to_string(norm) + ")");
  out.normalize();
  return out;
}

Vec3 unitVector(const JsonReader& r, const std::string& key) {
  const Vec3 n = r.vec3(key);
  if (!(n.norm() > 1e-12)) r.fail(key, "must not be the zero vector");
  return n.normalized();
}

WallProgram parseProgram(const JsonReader& r) {
  WallProgram p;
  using K = WallProgram::Kind;
  const std::string kind = r.choice("kind", {"fixed", "velocity", "velocity_table", "sinusoid", "servo"});
  if (kind == "fixed") {
    p.kind = K::Fixed;
  } else if (kind == "velocity") {
    p.kind = K::Velocity;
    p.velocity_m_s = r.vec3("velocity_m_s");
  } else if (kind == "velocity_table") {
    p.kind = K::VelocityTable;
    p.table_time_s = r.numbers("time_s", Check::NonNegative, 1);
    if (p.table_time_s[0] != 0.0) r.fail("time_s", "the table starts at t = 0");
    for (std::size_t k = 1; k < p.table_time_s.size(); ++k)
      if (!(p.table_time_s[k] > p.table_time_s[k - 1])) r.fail("time_s", "times must increase strictly");
    const nlohmann::json& v = r.raw("velocity_m_s");
    if (!v.is_array() || v.size() != p.table_time_s.size())
      r.fail("velocity_m_s", "expected one [vx, vy, vz] per time (" + std::to_string(p.table_time_s.size()) + ")");
    for (const auto& row : v) {
      if (!row.is_array() || row.size() != 3) r.fail("velocity_m_s", "each velocity is [vx, vy, vz]");
      Vec3 q;
      for (int c = 0; c < 3; ++c) {
        if (!row[static_cast<std::size_t>(c)].is_number()) r.fail("velocity_m_s", "each velocity is 3 numbers");
        q[c] = row[static_cast<std::size_t>(c)].get<double>();
      }
      if (!q.allFinite()) r.fail("velocity_m_s", "velocities must be finite");
      p.table_velocity_m_s.push_back(q);
    }
  } else if (kind == "sinusoid") {
    p.kind = K::Sinusoid;
    p.direction = unitVector(r, "direction");
    p.amplitude_m = r.number("amplitude_m", Check::Positive);
    p.frequency_hz = r.number("frequency_hz", Check::Positive);
    p.phase_rad = r.number("phase_rad", 0.0);
  } else {
    p.kind = K::Servo;
    p.target_force_N = r.number("target_force_N", Check::NonNegative);
    p.max_speed_m_s = r.number("max_speed_m_s", Check::Positive);
    p.gain_m_s_N = r.number("gain_m_s_N", Check::Positive);
    p.approach_after_s = r.number("approach_after_s", p.approach_after_s, Check::NonNegative);
  }
  return p;
}

}  // namespace

Scene parseScene(const JsonReader& root) {
  Scene s;
  s.gravity_m_s2 = root.vec3("gravity_m_s2");

  std::map<std::string, int> names;
  for (const auto& [name, r] : root.object("materials").members()) {
    names[name] = static_cast<int>(s.materials.size());
    s.materials.push_back(parseMaterial(name, r));
  }

  // (one reader at a time: a large case lists tens of thousands)
  s.spheres.reserve(root.arraySize("spheres"));
  root.forEachObject("spheres", [&](const bridge::JsonReader& r) {
    SphereSpec sp;
    sp.center_m = r.vec3("center_m");
    sp.radius_m = r.number("radius_m", Check::Positive);
    sp.material = materialIndex(r, names);
    sp.velocity_m_s = r.vec3("velocity_m_s", Vec3::Zero());
    sp.angular_velocity_rad_s = r.vec3("angular_velocity_rad_s", Vec3::Zero());
    sp.fixed = r.boolean("fixed", false);
    sp.group = static_cast<int>(r.integer("group", 0, 0));
    if (sp.group > kMaxGroup) r.fail("group", "contact groups are 0 .. " + std::to_string(kMaxGroup));
    if (r.has("mass_kg")) sp.mass_kg = r.number("mass_kg", Check::Positive);
    sp.mass_scale = r.number("mass_scale", 1.0, Check::Positive);
    if (sp.mass_scale < 1.0) r.fail("mass_scale", "must be >= 1 (it scales the sphere's inertia up)");
    s.spheres.push_back(sp);
  });

  for (const auto& r : root.objects("blocks")) {
    BlockSpec b;
    for (const auto& m : r.objects("spheres", true)) {
      b.member_centers_m.push_back(m.vec3("center_m"));
      b.member_radii_m.push_back(m.number("radius_m", Check::Positive));
    }
    if (b.member_centers_m.empty()) r.fail("spheres", "a block needs at least one sphere");
    b.material = materialIndex(r, names);
    b.position_m = r.vec3("position_m");
    b.orientation = quaternion(r, "orientation");
    b.velocity_m_s = r.vec3("velocity_m_s", Vec3::Zero());
    b.angular_velocity_rad_s = r.vec3("angular_velocity_rad_s", Vec3::Zero());
    b.fixed = r.boolean("fixed", false);
    b.group = static_cast<int>(r.integer("group", 0, 0));
    if (b.group > kMaxGroup) r.fail("group", "contact groups are 0 .. " + std::to_string(kMaxGroup));
    s.blocks.push_back(b);
  }

  const std::vector<bridge::JsonReader> wall_readers = root.objects("walls");
  for (std::size_t k = 0; k < wall_readers.size(); ++k) {
    const JsonReader& r = wall_readers[k];
    WallSpec w;
    w.name = r.string("name", "wall_" + std::to_string(k));
    // (its characters and uniqueness: validateScene, below)
    if (w.name.empty()) r.fail("name", kWallNameRule);
    w.point_m = r.vec3("point_m");
    w.normal = unitVector(r, "normal");
    w.material = materialIndex(r, names);
    if (r.has("velocity_m_s") && r.has("motion"))
      r.fail("velocity_m_s", "give either velocity_m_s (a constant velocity) or motion, not both");
    if (r.has("velocity_m_s")) {
      w.program.kind = WallProgram::Kind::Velocity;
      w.program.velocity_m_s = r.vec3("velocity_m_s");
    }
    if (const auto m = r.optionalObject("motion")) w.program = parseProgram(*m);
    if (const auto e = r.optionalObject("extent")) {
      w.bounded = true;
      w.axis_u = unitVector(*e, "axis_u");
      if (std::fabs(w.axis_u.dot(w.normal)) > 1e-9)
        e->fail("axis_u", "must lie in the wall's plane (normal to `normal`)");
      const auto half = e->numbers("half_lengths_m", Check::Positive, 2);
      if (half.size() != 2) e->fail("half_lengths_m", "expected 2 numbers [along axis_u, along normal x axis_u]");
      w.half_u_m = half[0], w.half_v_m = half[1];
    }
    s.walls.push_back(w);
  }

  const std::vector<bridge::JsonReader> link_readers = root.objects("links");
  for (const JsonReader& r : link_readers) {
    LinkSpec l;
    const std::string law = r.choice("law", {"linear", "wire"}, "linear");
    l.a = static_cast<std::size_t>(r.integer("a", 0));
    l.b = static_cast<std::size_t>(r.integer("b", 0));
    for (const auto& [key, index] : {std::pair<const char*, std::size_t>{"a", l.a}, {"b", l.b}})
      if (index >= s.spheres.size())
        r.fail(key, "sphere index " + std::to_string(index) + " out of range (" + std::to_string(s.spheres.size()) +
                        " spheres)");
    if (l.a == l.b) r.fail("b", "a link joins two different spheres");
    const double initial = (s.spheres[l.b].center_m - s.spheres[l.a].center_m).norm();
    const double rest = r.number("rest_length_m", initial, Check::Positive);
    if (!(rest > 0.0)) r.fail("rest_length_m", "the spheres coincide: give a rest length > 0");
    if (law == "linear") {
      l.linear.rest_length_m = rest;
      l.linear.stiffness_N_m = r.number("stiffness_N_m", Check::Positive);
      l.linear.tension_only = r.boolean("tension_only", false);
      if (r.has("rupture_strain")) l.linear.rupture_strain = r.number("rupture_strain", Check::Positive);
    } else {
      // A wire (bridge/laws/wire.hpp): its diameter, table and, for a double twist, the twist factors.
      l.law = LinkSpec::Law::Wire;
      l.wire.rest_length_m = rest;
      const double d = r.number("diameter_m", Check::Positive);
      const bridge::WireStressStrain table = parseWireTable(r, "stress_strain");
      l.wire.curve = r.has("double_twist")
                         ? bridge::doubleTwistCurve(table, d, parseDoubleTwist(r, "double_twist", table))
                         : bridge::wireCurve(table, d);
    }
    s.links.push_back(l);
  }

  addNettings(root, s);
  if (root.has("block_fills")) s.generated["block_fills"] = addBlockFills(root, s);
  if (root.has("from_cell")) {
    // A relative path is taken from the case file's folder.
    std::filesystem::path cell = root.string("from_cell");
    if (cell.is_relative()) cell = std::filesystem::path(root.file()).parent_path() / cell;
    loadCellFile(cell, s);
  }
  s.save_cell = root.boolean("save_cell", false);
  if (s.materials.empty()) root.fail("materials", "at least one material is required (in the case or its cell file)");
  if (const auto p = root.optionalObject("porosity")) {
    s.porosity.enabled = true;
    s.porosity.min_m = p->vec3("min_m");
    s.porosity.max_m = p->vec3("max_m");
    if (!((s.porosity.max_m - s.porosity.min_m).minCoeff() > 0.0)) p->fail("max_m", "must exceed min_m in x, y and z");
    s.porosity.spacing_m = p->number("spacing_m", s.porosity.spacing_m, Check::Positive);
    s.porosity.blocks_only = p->choice("of", {"all", "blocks"}, "all") == "blocks";
    const double cells = (s.porosity.max_m - s.porosity.min_m).prod() / std::pow(s.porosity.spacing_m, 3);
    if (cells > 2e9)
      p->fail("spacing_m", "would sample " + std::to_string(cells) + " cells (more than 2e9): give a coarser spacing");
  }

  if (root.has("no_contact_groups")) {
    const nlohmann::json& pairs = root.raw("no_contact_groups");
    const auto bad = [&] {
      root.fail("no_contact_groups",
                "expected an array of [group, group] pairs of integers 0 .. " + std::to_string(kMaxGroup));
    };
    if (!pairs.is_array()) bad();
    for (const auto& p : pairs) {
      if (!p.is_array() || p.size() != 2 || !p[0].is_number_integer() || !p[1].is_number_integer()) bad();
      const long long g = p[0].get<long long>(), h = p[1].get<long long>();
      if (g < 0 || h < 0 || g > kMaxGroup || h > kMaxGroup) bad();
      s.no_contact_groups.emplace_back(static_cast<int>(g), static_cast<int>(h));
    }
  }
  for (const JsonReader& r : root.objects("contact_pairs"))
    s.contact_pairs.push_back(resolveContactPair(parseContactPair(r), s.materials));
  if (s.spheres.empty() && s.blocks.empty()) root.failHere("the scene has no spheres and no blocks");

  s.run = parseRun(root.object("run"));
  validateScene(s, root.file());
  return s;
}

}  // namespace gabion::micro

namespace gabion::micro {

double sphereMass(const Scene& scene, const SphereSpec& sphere) {
  if (sphere.mass_kg > 0.0) return sphere.mass_kg;
  return scene.materials[static_cast<std::size_t>(sphere.material)].density_kg_m3 * sphereVolume(sphere.radius_m);
}

double sphereInertia(const Scene& scene, const SphereSpec& sphere) {
  if (sphere.inertia_kg_m2 > 0.0) return sphere.inertia_kg_m2;
  return 0.4 * sphereMass(scene, sphere) * sphere.radius_m * sphere.radius_m;
}

double sphereInertialMass(const Scene& scene, const SphereSpec& sphere) {
  return sphere.mass_scale * sphereMass(scene, sphere);
}

double sphereInertialMoment(const Scene& scene, const SphereSpec& sphere) {
  return sphere.mass_scale * sphereInertia(scene, sphere);
}

std::string wallName(const Scene& scene, std::size_t w) {
  const std::string& name = scene.walls[w].name;
  return name.empty() ? "wall_" + std::to_string(w) : name;
}

void validateScene(const Scene& s, const std::string& file) {
  const auto fail = [&](const std::string& pointer, const std::string& message) {
    throw bridge::InputError(file, pointer, message);
  };
  const auto at = [](const char* list, std::size_t k, const char* key) {
    return std::string("/") + list + "/" + std::to_string(k) + "/" + key;
  };
  const auto finite = [](const Vec3& v) { return v.allFinite(); };
  if (!finite(s.gravity_m_s2)) fail("/gravity_m_s2", "must be finite");
  if (s.materials.empty()) fail("/materials", "at least one material is required");
  const int nmat = static_cast<int>(s.materials.size());
  for (const Material& m : s.materials) {
    const std::string p = "/materials/" + bridge::escapePointerToken(m.name) + "/";
    if (!(m.density_kg_m3 > 0.0 && std::isfinite(m.density_kg_m3))) fail(p + "density_kg_m3", "must be > 0");
    if (!(m.normal_stiffness_N_m > 0.0 && std::isfinite(m.normal_stiffness_N_m)))
      fail(p + "normal_stiffness_N_m", "must be > 0");
    if (!(m.shear_stiffness_N_m > 0.0 && std::isfinite(m.shear_stiffness_N_m)))
      fail(p + "shear_stiffness_N_m", "must be > 0");
    if (!(m.friction >= 0.0 && std::isfinite(m.friction))) fail(p + "friction", "must be >= 0");
    if (!(m.normal_force_limit_N > 0.0)) fail(p + "normal_force_limit_N", "must be > 0");
    if (!(m.local_damping >= 0.0 && m.local_damping < 1.0)) fail(p + "local_damping", "must be in [0, 1)");
    if (!(m.viscous_damping_ratio >= 0.0 && m.viscous_damping_ratio < 1.0))
      fail(p + "viscous_damping_ratio", "must be in [0, 1)");
  }
  const auto material = [&](int m, const std::string& p) {
    if (m < 0 || m >= nmat) fail(p, "material index " + std::to_string(m) + " out of range");
  };
  const auto group = [&](int g, const std::string& p) {
    if (g < 0 || g >= kGroupCount) fail(p, "contact groups are 0 .. " + std::to_string(kGroupCount - 1));
  };
  if (s.spheres.empty() && s.blocks.empty()) fail("", "the scene has no spheres and no blocks");
  std::vector<bool> link_end;  // (which spheres links join, when one rides a wall)
  for (std::size_t k = 0; k < s.spheres.size(); ++k) {
    const SphereSpec& sp = s.spheres[k];
    if (!finite(sp.center_m)) fail(at("spheres", k, "center_m"), "must be finite");
    if (!(sp.radius_m > 0.0 && std::isfinite(sp.radius_m))) fail(at("spheres", k, "radius_m"), "must be > 0");
    if (!finite(sp.velocity_m_s)) fail(at("spheres", k, "velocity_m_s"), "must be finite");
    if (!finite(sp.angular_velocity_rad_s)) fail(at("spheres", k, "angular_velocity_rad_s"), "must be finite");
    if (!(sp.mass_kg >= 0.0 && std::isfinite(sp.mass_kg))) fail(at("spheres", k, "mass_kg"), "must be > 0");
    if (!(sp.inertia_kg_m2 >= 0.0 && std::isfinite(sp.inertia_kg_m2)))
      fail(at("spheres", k, "inertia_kg_m2"), "must be > 0");
    if (!(sp.mass_scale >= 1.0 && std::isfinite(sp.mass_scale))) fail(at("spheres", k, "mass_scale"), "must be >= 1");
    material(sp.material, at("spheres", k, "material"));
    group(sp.group, at("spheres", k, "group"));
    if (sp.rides_wall != -1) {
      const std::string key = at("spheres", k, "rides_wall");
      if (sp.rides_wall < 0 || static_cast<std::size_t>(sp.rides_wall) >= s.walls.size())
        fail(key, "no such wall: the scene has " + std::to_string(s.walls.size()));
      if (!sp.fixed) fail(key, "a sphere that rides a wall must be fixed (the wall moves it)");
      if (link_end.empty()) {  // (once, for the first sphere that rides)
        link_end.assign(s.spheres.size(), false);
        for (const LinkSpec& l : s.links)
          if (l.a < link_end.size() && l.b < link_end.size()) link_end[l.a] = link_end[l.b] = true;
      }
      if (!link_end[k]) fail(key, "a sphere that rides a wall must be an end of a link (it ties the link to the wall)");
    }
  }
  for (std::size_t k = 0; k < s.blocks.size(); ++k) {
    const BlockSpec& b = s.blocks[k];
    if (b.member_centers_m.empty() || b.member_centers_m.size() != b.member_radii_m.size())
      fail(at("blocks", k, "spheres"), "a block needs at least one sphere, each with a centre and a radius");
    for (std::size_t q = 0; q < b.member_radii_m.size(); ++q) {
      const std::string p = at("blocks", k, "spheres") + "/" + std::to_string(q) + "/";
      if (!finite(b.member_centers_m[q])) fail(p + "center_m", "must be finite");
      if (!(b.member_radii_m[q] > 0.0 && std::isfinite(b.member_radii_m[q]))) fail(p + "radius_m", "must be > 0");
    }
    if (!finite(b.position_m)) fail(at("blocks", k, "position_m"), "must be finite");
    if (std::fabs(b.orientation.norm() - 1.0) > 1e-6) fail(at("blocks", k, "orientation"), "must have unit length");
    if (!finite(b.velocity_m_s)) fail(at("blocks", k, "velocity_m_s"), "must be finite");
    if (!finite(b.angular_velocity_rad_s)) fail(at("blocks", k, "angular_velocity_rad_s"), "must be finite");
    material(b.material, at("blocks", k, "material"));
    group(b.group, at("blocks", k, "group"));
  }
  for (std::size_t k = 0; k < s.walls.size(); ++k) {
    const WallSpec& w = s.walls[k];
    const std::string name = wallName(s, k);
    if (name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") != std::string::npos)
      fail(at("walls", k, "name"), kWallNameRule);
    for (std::size_t q = 0; q < k; ++q)
      if (wallName(s, q) == name)
        fail(at("walls", k, "name"), "wall name '" + name + "' is used by wall " + std::to_string(q));
    if (!finite(w.point_m)) fail(at("walls", k, "point_m"), "must be finite");
    if (!(std::fabs(w.normal.norm() - 1.0) < 1e-9)) fail(at("walls", k, "normal"), "must be a unit vector");
    material(w.material, at("walls", k, "material"));
    const WallProgram& p = w.program;
    const std::string m = at("walls", k, "motion") + "/";
    using K = WallProgram::Kind;
    if (p.kind == K::Velocity && !finite(p.velocity_m_s)) fail(m + "velocity_m_s", "must be finite");
    if (p.kind == K::VelocityTable) {
      if (p.table_time_s.empty() || p.table_time_s[0] != 0.0 || p.table_time_s.size() != p.table_velocity_m_s.size())
        fail(m + "time_s", "a table starts at t = 0 and has one velocity per time");
      for (std::size_t q = 1; q < p.table_time_s.size(); ++q)
        if (!(p.table_time_s[q] > p.table_time_s[q - 1])) fail(m + "time_s", "times must increase strictly");
    }
    if (p.kind == K::Sinusoid && !(p.amplitude_m > 0.0 && p.frequency_hz > 0.0 && std::isfinite(p.phase_rad) &&
                                   std::fabs(p.direction.norm() - 1.0) < 1e-9))
      fail(m + "amplitude_m", "a sinusoid needs amplitude > 0, frequency > 0 and a unit direction");
    if (p.kind == K::Servo &&
        !(p.target_force_N >= 0.0 && p.max_speed_m_s > 0.0 && p.gain_m_s_N > 0.0 && std::isfinite(p.target_force_N) &&
          std::isfinite(p.max_speed_m_s) && std::isfinite(p.gain_m_s_N)))
      fail(m + "gain_m_s_N", "a servo needs target_force_N >= 0, max_speed_m_s > 0 and gain_m_s_N > 0");
    if (w.bounded && !(w.half_u_m > 0.0 && w.half_v_m > 0.0 && std::fabs(w.axis_u.norm() - 1.0) < 1e-9 &&
                       std::fabs(w.axis_u.dot(w.normal)) < 1e-9))
      fail(at("walls", k, "extent"), "a bounded wall needs a unit axis_u in its plane and half-lengths > 0");
  }
  for (std::size_t k = 0; k < s.links.size(); ++k) {
    const LinkSpec& l = s.links[k];
    if (l.a >= s.spheres.size()) fail(at("links", k, "a"), "sphere index out of range");
    if (l.b >= s.spheres.size() || l.b == l.a) fail(at("links", k, "b"), "sphere index out of range or equal to a");
    if (l.law == LinkSpec::Law::Wire) {
      if (!(l.wire.rest_length_m > 0.0 && std::isfinite(l.wire.rest_length_m)))
        fail(at("links", k, "rest_length_m"), "must be > 0");
      bridge::WireStressStrain as_table{l.wire.curve.strain(), l.wire.curve.force()};
      const bridge::WireTableIssue issue = bridge::checkWireTable(as_table);
      if (!issue.message.empty()) fail(at("links", k, "stress_strain"), "wire curve: " + issue.message);
      if (l.pull_force_N != 0.0 &&
          !(l.pull_force_N > 0.0 && std::isfinite(l.pull_force_N) && l.pull_min_m > 0.0 && std::isfinite(l.pull_min_m)))
        fail(at("links", k, "pull_force_N"), "a wire pulled tight needs a force > 0 and a shortest length > 0");
      continue;
    }
    if (!(l.linear.stiffness_N_m > 0.0 && std::isfinite(l.linear.stiffness_N_m)))
      fail(at("links", k, "stiffness_N_m"), "must be > 0");
    if (!(l.linear.rest_length_m > 0.0 && std::isfinite(l.linear.rest_length_m)))
      fail(at("links", k, "rest_length_m"), "must be > 0");
    if (!(l.linear.rupture_strain > 0.0)) fail(at("links", k, "rupture_strain"), "must be > 0");
  }
  for (std::size_t k = 0; k < s.no_contact_groups.size(); ++k) {
    group(s.no_contact_groups[k].first, "/no_contact_groups/" + std::to_string(k) + "/0");
    group(s.no_contact_groups[k].second, "/no_contact_groups/" + std::to_string(k) + "/1");
  }
  for (std::size_t k = 0; k < s.contact_pairs.size(); ++k) {
    const ContactPair& p = s.contact_pairs[k];
    const std::string at_k = "/contact_pairs/" + std::to_string(k) + "/";
    material(p.a, at_k + "materials/0");
    material(p.b, at_k + "materials/1");
    const auto positive = [&](const std::optional<double>& v, const char* key) {
      if (v && !(*v > 0.0 && std::isfinite(*v))) fail(at_k + key, "must be > 0");
    };
    positive(p.normal_stiffness_N_m, "normal_stiffness_N_m");
    positive(p.shear_stiffness_N_m, "shear_stiffness_N_m");
    if (p.friction && !(*p.friction >= 0.0 && std::isfinite(*p.friction))) fail(at_k + "friction", "must be >= 0");
    if (p.normal_force_limit_N && !(*p.normal_force_limit_N > 0.0)) fail(at_k + "normal_force_limit_N", "must be > 0");
    if (p.viscous_damping_ratio && !(*p.viscous_damping_ratio >= 0.0 && *p.viscous_damping_ratio < 1.0))
      fail(at_k + "viscous_damping_ratio", "must be in [0, 1)");
  }
  const RunSpec& rs = s.run;
  // (0: an engine built in code, stepped by its caller)
  if (!(rs.duration_s >= 0.0 && std::isfinite(rs.duration_s))) fail("/run/duration_s", "must be > 0");
  if (!(rs.dt_s >= 0.0 && std::isfinite(rs.dt_s))) fail("/run/dt_s", "must be > 0");
  if (!(rs.dt_safety > 0.0 && rs.dt_safety <= 1.0)) fail("/run/dt_safety", "must be in (0, 1]");
  if (!(rs.link_dt_safety >= 0.0 && rs.link_dt_safety <= 1.0))
    fail("/run/link_dt_safety", "must be in (0, 1] (0: dt_safety)");
  if (!(rs.max_overlap_ratio > 0.0 && rs.max_overlap_ratio <= 1.0)) fail("/run/max_overlap_ratio", "must be in (0, 1]");
  if (!(rs.energy_runaway_factor > 1.0)) fail("/run/energy_runaway_factor", "must be > 1");
  if (!(rs.max_balance_error > 0.0)) fail("/run/max_balance_error", "must be > 0");
  if (!(rs.verlet_skin_ratio > 0.0 && rs.verlet_skin_ratio <= 2.0)) fail("/run/verlet_skin_ratio", "must be in (0, 2]");
}

}  // namespace gabion::micro
