#include "micro/scene.hpp"

#include <cmath>
#include <map>

namespace gabion::micro {
namespace {

using bridge::Check;
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

}  // namespace

Scene parseScene(const JsonReader& root) {
  Scene s;
  s.gravity_m_s2 = root.vec3("gravity_m_s2");

  std::map<std::string, int> names;
  for (const auto& [name, r] : root.object("materials").members()) {
    names[name] = static_cast<int>(s.materials.size());
    s.materials.push_back(parseMaterial(name, r));
  }
  if (s.materials.empty()) root.fail("materials", "at least one material is required");

  const std::vector<bridge::JsonReader> sphere_readers = root.objects("spheres");
  s.spheres.reserve(sphere_readers.size());
  for (const auto& r : sphere_readers) {
    SphereSpec sp;
    sp.center_m = r.vec3("center_m");
    sp.radius_m = r.number("radius_m", Check::Positive);
    sp.material = materialIndex(r, names);
    sp.velocity_m_s = r.vec3("velocity_m_s", Vec3::Zero());
    sp.angular_velocity_rad_s = r.vec3("angular_velocity_rad_s", Vec3::Zero());
    sp.fixed = r.boolean("fixed", false);
    s.spheres.push_back(sp);
  }

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
    s.blocks.push_back(b);
  }

  for (const auto& r : root.objects("walls")) {
    WallSpec w;
    w.point_m = r.vec3("point_m");
    const Vec3 n = r.vec3("normal");
    if (!(n.norm() > 1e-12)) r.fail("normal", "must not be the zero vector");
    w.normal = n.normalized();
    w.material = materialIndex(r, names);
    w.velocity_m_s = r.vec3("velocity_m_s", Vec3::Zero());
    s.walls.push_back(w);
  }
  if (s.spheres.empty() && s.blocks.empty()) root.failHere("the scene has no spheres and no blocks");

  const JsonReader run = root.object("run");
  RunSpec& rs = s.run;
  rs.duration_s = run.number("duration_s", Check::Positive);
  if (run.has("dt_s")) rs.dt_s = run.number("dt_s", Check::Positive);
  rs.dt_safety = run.number("dt_safety", 0.2, Check::Positive);
  if (rs.dt_safety > 1.0) run.fail("dt_safety", "must be <= 1 (a fraction of the critical step)");
  rs.allow_dt_above_critical = run.boolean("allow_dt_above_critical", false);
  rs.output_interval_s = run.number("output_interval_s", rs.duration_s / 100.0, Check::Positive);
  rs.series_interval_s = run.number("series_interval_s", rs.output_interval_s, Check::Positive);
  rs.max_overlap_ratio = run.number("max_overlap_ratio", 0.5, Check::Positive);
  if (rs.max_overlap_ratio > 1.0) run.fail("max_overlap_ratio", "must be <= 1");
  rs.energy_runaway_factor = run.number("energy_runaway_factor", 10.0, Check::Positive);
  if (rs.energy_runaway_factor <= 1.0) run.fail("energy_runaway_factor", "must be > 1");
  rs.verlet_skin_ratio = run.number("verlet_skin_ratio", 0.2, Check::Positive);
  if (rs.verlet_skin_ratio > 2.0) run.fail("verlet_skin_ratio", "must be <= 2");
  return s;
}

}  // namespace gabion::micro
