#include "micro/netting/tensile_test.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "micro/linked_nodes.hpp"
#include "micro/netting/mesh.hpp"
#include "micro/netting/netting_input.hpp"
#include "micro/scene_run.hpp"

namespace gabion::micro {
namespace {

using bridge::Check;
using bridge::JsonReader;

struct TensileCase {
  NettingInput netting;
  double width_m = 0.52, length_m = 0.96;  // requested sheet (whole meshes are fitted in)
  double pull_speed_m_s = 0.05;
  double max_displacement_m = 0.3;
  Vec3 gravity = Vec3::Zero();
  RunSpec run;
};

TensileCase parseCase(const bridge::JsonDocument& doc) {
  const JsonReader root = doc.root();
  TensileCase c;
  c.netting = parseNetting(root.object("netting"));
  if (const auto s = root.optionalObject("sheet")) {
    c.width_m = s->number("width_m", c.width_m, Check::Positive);
    c.length_m = s->number("length_m", c.length_m, Check::Positive);
    const MeshSpec& m = c.netting.mesh;
    if (c.width_m < m.opening_m) s->fail("width_m", "the sheet must be at least one mesh opening wide");
    if (c.length_m < 3.0 * m.twist_length_m + 2.0 * m.wire_rise_m)
      s->fail("length_m", "the sheet must be at least one mesh long (3 twists + 2 rises)");
  }
  if (const auto t = root.optionalObject("test")) {
    c.pull_speed_m_s = t->number("pull_speed_m_s", c.pull_speed_m_s, Check::Positive);
    c.max_displacement_m = t->number("max_displacement_m", c.max_displacement_m, Check::Positive);
  }
  c.gravity = root.vec3("gravity_m_s2", Vec3::Zero());
  c.run = parseRun(root.object("run"), c.max_displacement_m / c.pull_speed_m_s);
  return c;
}

// The sheet as a scene: nodes as spheres carrying their wire's mass, the
// bottom edge fixed, the top edge driven along +y.
Scene buildScene(const TensileCase& c, const Netting& net) {
  Scene s;
  s.gravity_m_s2 = c.gravity;
  s.materials.push_back(c.netting.contact);
  s.run = c.run;
  for (std::size_t k = 0; k < net.node_m.size(); ++k) {
    SphereSpec sp;
    sp.center_m = net.node_m[k];
    sp.radius_m = net.node_radius_m;
    sp.mass_kg = net.node_mass_kg[k];
    sp.inertia_kg_m2 = net.node_inertia_kg_m2[k];
    sp.mass_scale = c.netting.mesh.node_mass_scale;
    s.spheres.push_back(sp);
  }
  for (const std::uint32_t k : net.bottom_edge) s.spheres[k].fixed = true;
  for (const std::uint32_t k : net.top_edge) {
    s.spheres[k].fixed = true;
    s.spheres[k].velocity_m_s = Vec3(0.0, c.pull_speed_m_s, 0.0);
  }
  for (const NettingLink& l : net.links) s.links.push_back(linkSpec(c.netting.mesh, l, 0));
  return s;
}

// Whether some path of intact links joins a node of `from` to a node of `to`.
bool connected(const Netting& net, const Engine& e, const std::vector<std::uint32_t>& from,
               const std::vector<std::uint32_t>& to) {
  std::vector<std::vector<std::uint32_t>> next(net.node_m.size());
  for (std::size_t l = 0; l < net.links.size(); ++l)
    if (!e.linkBroken(l))
      next[net.links[l].a].push_back(net.links[l].b), next[net.links[l].b].push_back(net.links[l].a);
  std::vector<char> seen(net.node_m.size(), 0), goal(net.node_m.size(), 0);
  for (const std::uint32_t k : to) goal[k] = 1;
  std::vector<std::uint32_t> stack(from.begin(), from.end());
  for (const std::uint32_t k : from) seen[k] = 1;
  while (!stack.empty()) {
    const std::uint32_t k = stack.back();
    stack.pop_back();
    if (goal[k]) return true;
    for (const std::uint32_t q : next[k])
      if (!seen[q]) seen[q] = 1, stack.push_back(q);
  }
  return false;
}

Netting generate(const TensileCase& c, const std::string& file) {
  try {
    return flatSheet(c.netting.mesh, c.width_m, c.length_m);
  } catch (const std::invalid_argument& e) {
    throw bridge::InputError(file, "/sheet", e.what());
  }
}

void check(const bridge::JsonDocument& doc) {
  const TensileCase c = parseCase(doc);
  const Scene s = buildScene(c, generate(c, doc.file()));
  validateScene(s, doc.file());
  chooseDt(s, criticalTimeStep(s), doc.file());
}

// The netting in the benchmark's exchange format (bench/netting/README.md):
// nodes, links with their kind and elastic stiffness, the wire table, the
// clamped and pulled nodes, the step and the number of steps.
nlohmann::json exchangeFile(const TensileCase& c, const Netting& net, const Scene& s, double dt, long long steps) {
  nlohmann::json j;
  j["format"] = "gabion.netting/1";
  nlohmann::json pos = nlohmann::json::array(), radius = nlohmann::json::array(), mass = nlohmann::json::array();
  for (std::size_t k = 0; k < net.node_m.size(); ++k) {
    pos.push_back({net.node_m[k].x(), net.node_m[k].y(), net.node_m[k].z()});
    radius.push_back(net.node_radius_m);
    mass.push_back(net.node_mass_kg[k]);
  }
  j["nodes"] = {{"position_m", pos}, {"radius_m", radius}, {"mass_kg", mass}};
  nlohmann::json a = nlohmann::json::array(), b = a, kind = a, rest = a, k = a;
  for (std::size_t l = 0; l < net.links.size(); ++l) {
    a.push_back(net.links[l].a);
    b.push_back(net.links[l].b);
    kind.push_back(wireKindName(net.links[l].kind));
    rest.push_back(net.links[l].rest_length_m);
    k.push_back(s.links[l].stiffness());
  }
  j["links"] = {{"a", a}, {"b", b}, {"kind", kind}, {"rest_length_m", rest}, {"elastic_stiffness_N_m", k}};
  const MeshSpec& m = c.netting.mesh;
  j["wire"] = {{"strain", m.table.strain},
               {"stress_Pa", m.table.stress_Pa},
               {"lambda_k", m.twist.lambda_k},
               {"lambda_eps", m.twist.lambda_eps},
               {"mesh_diameter_m", m.wire_diameter_m},
               {"selvedge_diameter_m", m.selvedge_diameter_m}};
  j["test"] = {{"clamped", net.bottom_edge},
               {"pulled", net.top_edge},
               {"pull_velocity_m_s", {0.0, c.pull_speed_m_s, 0.0}},
               {"dt_s", dt},
               {"steps", steps},
               {"local_damping", c.netting.contact.local_damping}};
  return j;
}

std::optional<bridge::Estimate> estimate(const bridge::JsonDocument& doc) {
  const TensileCase c = parseCase(doc);
  const Scene s = buildScene(c, generate(c, doc.file()));
  return sceneEstimate(s, chooseDt(s, criticalTimeStep(s), doc.file()));
}

bridge::RunOutcome run(const bridge::JsonDocument& doc, const bridge::RunContext& ctx) {
  const TensileCase c = parseCase(doc);
  const Netting net = generate(c, doc.file());
  Scene scene = buildScene(c, net);
  validateScene(scene, doc.file());
  const double dt = chooseDt(scene, criticalTimeStep(scene), doc.file());
  const auto steps = static_cast<long long>(std::ceil(scene.run.duration_s / dt - 1e-9));
  // The other engine integrates the wires at the step the nodes take here (a sub-step of dt).
  const int substeps = linkSubsteps(dt, linkDtSafety(scene.run), criticalLinkStep(scene));
  bridge::writeJsonAtomic(ctx.outdir / "netting.json", exchangeFile(c, net, scene, dt / substeps, steps * substeps));

  // The pulling force: what the netting exerts on the pulled nodes, against the pull.
  struct Curve {
    std::vector<double> time, displacement, force;
    double peak = 0.0, at_peak = 0.0;
    std::optional<LinkEvent> first_rupture;
  };
  Curve curve;
  SceneRunHooks hooks;
  hooks.label = "micro.netting_tensile";
  hooks.record = [&](const Engine& e, double) {
    double f = 0.0;
    for (const std::uint32_t k : net.top_edge) f -= e.sphereForce(k).y();
    const double u = c.pull_speed_m_s * e.time();
    curve.time.push_back(e.time());
    curve.displacement.push_back(u);
    curve.force.push_back(f);
    if (f > curve.peak) curve.peak = f, curve.at_peak = u;
    if (!curve.first_rupture && !e.linkEvents().empty()) curve.first_rupture = e.linkEvents().front();
  };
  // Torn: no path of intact links joins the pulled edge to the clamped one
  // (checked when links have broken since the last check).
  std::size_t checked = 0;
  hooks.done = [&](const Engine& e) {
    if (e.linkEvents().size() == checked) return false;
    checked = e.linkEvents().size();
    return !connected(net, e, net.top_edge, net.bottom_edge);
  };
  hooks.archive = [&](bridge::StateArchive& a) {
    a("time_s", curve.time), a("displacement_m", curve.displacement), a("force_N", curve.force);
    a("peak", curve.peak), a("at_peak", curve.at_peak), a("checked", checked);
    // (the first rupture is the first of the engine's link events, which the engine's state holds)
  };
  hooks.write = [&](const Engine&, bridge::H5Writer& h5) {
    h5.write("/series/pull/time_s", curve.time, "s");
    h5.write("/series/pull/displacement_m", curve.displacement, "m");
    h5.write("/series/pull/force_N", curve.force, "N");
    std::vector<long long> kind, clamped(net.bottom_edge.begin(), net.bottom_edge.end()),
        pulled(net.top_edge.begin(), net.top_edge.end());
    for (const NettingLink& l : net.links) kind.push_back(static_cast<long long>(l.kind));
    h5.writeInts("/netting/link_kind", kind);
    h5.attribute("/netting/link_kind", "values", "0 single, 1 double_twist, 2 selvedge, 3 lacing");
    h5.writeInts("/netting/clamped", clamped);
    h5.writeInts("/netting/pulled", pulled);
  };
  bridge::RunOutcome out = runScene(std::move(scene), doc.file(), ctx, hooks);
  {
    bridge::PlotSpec plot;
    plot.title = "Sheet tensile test: " + std::to_string(net.width_m).substr(0, 4) + " m wide, " +
                 std::to_string(net.length_m).substr(0, 4) + " m long";
    plot.x_label = "pull displacement (mm)";
    plot.y_label = "pulling force (kN)";
    plot.series.push_back(bridge::scaledSeries("force", curve.displacement, curve.force, 1000.0, 1e-3));
    bridge::writePlotPng(ctx.outdir / "tensile_curve.png", plot);
  }

  nlohmann::json& r = out.results;
  r["sheet_width_m"] = net.width_m;
  r["sheet_length_m"] = net.length_m;
  r["nodes"] = net.node_m.size();
  double mass = 0.0;
  for (const double m : net.node_mass_kg) mass += m;
  r["node_mass_mean_kg"] = mass / static_cast<double>(net.node_m.size());
  r["node_radius_m"] = net.node_radius_m;
  r["peak_force_N"] = curve.peak;
  r["peak_force_per_width_N_m"] = curve.peak / net.width_m;
  r["displacement_at_peak_m"] = curve.at_peak;
  r["torn"] = out.results["ended_by"] == "test";
  // Where the tearing started: the first link to break (the engine's link
  // index is the netting's), its kind and place.
  r["first_rupture_s"] = nullptr;
  r["first_rupture_link_kind"] = nullptr;
  r["first_rupture_position_m"] = nullptr;
  if (const auto& ev = curve.first_rupture) {
    r["first_rupture_s"] = ev->time_s;
    r["first_rupture_link_kind"] = wireKindName(net.links[ev->link].kind);
    r["first_rupture_position_m"] = {ev->position_m.x(), ev->position_m.y(), ev->position_m.z()};
  }
  return out;
}

}  // namespace

bridge::CaseKind nettingTensileKind() {
  return {"micro.netting_tensile",
          "tensile test of a sheet of double-twisted hexagonal wire netting to rupture (docs/netting.md)", check, run,
          estimate};
}

}  // namespace gabion::micro
