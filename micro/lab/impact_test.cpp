#include "micro/lab/impact_test.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "micro/lab/lab_setup.hpp"
#include "micro/scene_run.hpp"

namespace gabion::micro::lab {
namespace {

using bridge::Check;
using bridge::JsonReader;

constexpr int kBoulderGroup = 2;  // (rock 0, netting 1)

struct ImpactCase {
  LabSetup setup;
  std::vector<double> velocities_m_s{20.0};
  double diameter_m = 0.5, density_kg_m3 = 2600.0;
  MaterialChange boulder;  // its contact material: the rock's, with these changes
  Vec3 aim_offset = Vec3::Zero();
  double gap_m = 0.002;  // between the boulder and the cell's top at the start
  std::string pointer_velocity = "/velocities_m_s";
};

ImpactCase parseCase(const bridge::JsonDocument& doc) {
  const JsonReader root = doc.root();
  ImpactCase c;
  if (root.has("velocity_m_s")) {
    if (root.has("velocities_m_s")) root.fail("velocity_m_s", "give velocity_m_s or velocities_m_s, not both");
    c.velocities_m_s = {root.number("velocity_m_s", Check::Positive)};
    c.pointer_velocity = "/velocity_m_s";
  } else if (root.has("velocities_m_s")) {
    c.velocities_m_s = root.numbers("velocities_m_s", Check::Positive);
  }
  for (const double v : c.velocities_m_s)
    if (v > 100.0) root.fail(c.pointer_velocity.substr(1), "an impact velocity above 100 m/s is no rockfall");
  if (const auto b = root.optionalObject("boulder")) {
    c.diameter_m = b->number("diameter_m", c.diameter_m, Check::Positive);
    c.density_kg_m3 = b->number("density_kg_m3", c.density_kg_m3, Check::Positive);
    const Vec3 aim = b->vec3("aim_offset_m", Vec3::Zero());
    if (aim.z() != 0.0) b->fail("aim_offset_m", "an offset across the top face: [dx, dy, 0]");
    c.aim_offset = aim;
    c.gap_m = b->number("start_gap_m", c.gap_m, Check::NonNegative);
    if (const auto m = b->optionalObject("contact")) c.boulder = parseMaterialChange("boulder", *m);
  }
  // An impact lasts some tens of milliseconds; the series every 0.1 ms. No
  // mass scaling by default: the test is dynamic.
  c.setup = parseLabSetup(root, 1.0, 0.15, 1e-4);
  return c;
}

struct Placement {
  Scene scene;
  std::size_t boulder = 0;
  double mass_kg = 0.0;
  bool dt_limited = false;  ///< the step held down by the boulder's travel
};

Placement buildScene(const ImpactCase& c, const Sample& sample, double velocity) {
  Placement p;
  Scene& s = p.scene;
  s = sample.scene;
  SphereSpec b = boulderSphere(s, sample.rock_material, c.diameter_m, c.density_kg_m3, c.boulder);
  const double r = 0.5 * c.diameter_m;
  const Vec3 mid = 0.5 * (sample.lo + sample.hi);
  b.center_m = Vec3(mid.x() + c.aim_offset.x(), mid.y() + c.aim_offset.y(), sample.hi.z() + r + c.gap_m);
  b.velocity_m_s = Vec3(0, 0, -velocity);
  b.group = kBoulderGroup;
  p.boulder = s.spheres.size();
  p.mass_kg = b.mass_kg;
  s.spheres.push_back(b);
  s.walls.push_back(fixedWall("base", sample.lo, Vec3::UnitZ(), sample.plate_material));
  return p;
}

// The scene as the test runs it: the boulder must not pass a netting node
// within a step, so its travel in a step is held below a tenth of the
// smallest radius (run.dt_s set where that is below the chosen step).
Placement planScene(const ImpactCase& c, const Sample& sample, double v0, const std::string& file) {
  Placement pl = buildScene(c, sample, v0);
  pl.dt_limited = limitStepToSpeed(pl.scene, v0, file);
  return pl;
}

void checkBoulder(const ImpactCase& c, double face_m, const std::string& file) {
  if (c.diameter_m > face_m * (1.0 + 1e-9))
    throw bridge::InputError(file, "/boulder/diameter_m",
                             "a boulder of " + std::to_string(c.diameter_m) + " m is larger than the cell's face (" +
                                 std::to_string(face_m) + " m): it would strike the base beside the cell");
}

void check(const bridge::JsonDocument& doc) {
  const ImpactCase c = parseCase(doc);
  const double face = checkCells(c.setup);
  if (c.setup.cells.front().generate.empty()) {
    const Sample sample = loadSample(c.setup.cells.front().file, c.setup);
    const Vec3 size = sample.hi - sample.lo;
    checkBoulder(c, std::min(size.x(), size.y()), doc.file());
    const Placement p = buildScene(c, sample, c.velocities_m_s.front());
    validateScene(p.scene, doc.file());
    chooseDt(p.scene, criticalTimeStep(p.scene), doc.file());
  } else {
    checkBoulder(c, face, doc.file());
  }
}

std::string variantName(double v) {
  std::ostringstream s;
  s << "v" << v;
  return s.str();
}

bridge::RunOutcome runOne(const ImpactCase& c, const Sample& sample, double v0, const bridge::RunContext& ctx,
                          const std::string& file) {
  {
    const Vec3 size = sample.hi - sample.lo;
    checkBoulder(c, std::min(size.x(), size.y()), file);
  }
  Placement pl = planScene(c, sample, v0, file);
  const std::size_t boulder = pl.boulder;
  const bool limited = pl.dt_limited;

  struct Series {
    std::vector<double> time, force, base_force, penetration, velocity;
  } sr;
  double z_contact = NAN, t_contact = NAN, peak = 0.0, t_last_force = NAN;
  const double weight = -pl.scene.gravity_m_s2.z() * sample.mass_kg;  // the cell's own, on the base
  SceneRunHooks hooks;
  hooks.label = "micro.uci " + variantName(v0);
  hooks.record = [&](const Engine& e, double) {
    const double f = e.sphereForce(boulder).z();  // the cell pushes it up
    const BodyState b = e.body(boulder);
    if (std::isnan(z_contact) && f > 0.0) z_contact = b.position_m.z(), t_contact = e.time();
    sr.time.push_back(e.time());
    sr.force.push_back(f);
    sr.base_force.push_back(-e.wallForce(0).z());
    sr.penetration.push_back(std::isnan(z_contact) ? 0.0 : z_contact - b.position_m.z());
    sr.velocity.push_back(b.velocity_m_s.z());
    peak = std::max(peak, f);
    if (f > 0.01 * peak) t_last_force = e.time();
  };
  // Over: the boulder has left the cell (no force for 5 ms, moving up), or
  // it has come to rest on it.
  hooks.done = [&](const Engine& e) {
    if (std::isnan(t_contact)) return false;
    const double vz = sr.velocity.back();
    if (vz > 0.0 && e.time() - t_last_force > 0.005) return true;
    return e.time() - t_contact > 0.02 && std::fabs(vz) < 0.002 * v0;
  };
  hooks.archive = [&](bridge::StateArchive& a) {
    a("time_s", sr.time), a("force_N", sr.force), a("base_force_N", sr.base_force);
    a("penetration_m", sr.penetration), a("velocity_m_s", sr.velocity), a("z_contact", z_contact);
    a("t_contact", t_contact), a("peak", peak), a("t_last_force", t_last_force);
  };
  hooks.write = [&](const Engine&, bridge::H5Writer& h5) {
    h5.write("/curves/impact/time_s", sr.time, "s");
    h5.write("/curves/impact/penetration_m", sr.penetration, "m");
    h5.write("/curves/impact/force_N", sr.force, "N");
    h5.write("/curves/impact/base_force_N", sr.base_force, "N");
    h5.write("/curves/impact/boulder_velocity_m_s", sr.velocity, "m/s");
    h5.write("/curves/impact/velocity_m_s", std::vector<double>{v0}, "m/s");
  };
  bridge::RunOutcome out = runScene(std::move(pl.scene), file, ctx, hooks);
  // (an overlap at the first step was in the cell as loaded, not the boulder's doing)
  if (out.status != bridge::RunOutcome::Status::Ok && out.message.find("overlap") != std::string::npos &&
      out.message.rfind("step 0,", 0) != 0)
    out.message +=
        " (the boulder crushes what it meets at this contact stiffness: docs/lab.md, Impact velocity "
        "and contact stiffness)";
  nlohmann::json& r = out.results;
  r["velocity_m_s"] = v0;
  r["boulder_mass_kg"] = pl.mass_kg;
  r["boulder_diameter_m"] = c.diameter_m;
  r["impact_energy_J"] = 0.5 * pl.mass_kg * v0 * v0;
  r["dt_limited_by_boulder_speed"] = limited;  // (a step of a tenth of the smallest radius at v0)
  r["cell_mass_kg"] = sample.mass_kg;
  if (sr.time.empty()) return out;
  double peak_base = 0.0, max_pen = 0.0, t_peak = NAN;
  for (std::size_t k = 0; k < sr.time.size(); ++k) {
    peak_base = std::max(peak_base, sr.base_force[k]);
    max_pen = std::max(max_pen, sr.penetration[k]);
    if (sr.force[k] == peak && std::isnan(t_peak)) t_peak = sr.time[k];
  }
  // Contact: from the first force on the boulder to the last above 1 % of
  // its peak; the rebound: its upward speed once the contact is over.
  const bool touched = !std::isnan(t_contact);
  const double duration = touched ? t_last_force - t_contact : 0.0;
  double rebound = 0.0;
  for (std::size_t k = 0; k < sr.time.size(); ++k)
    if (sr.time[k] >= t_last_force) rebound = std::max(rebound, sr.velocity[k]);
  r["peak_force_N"] = peak;
  r["time_of_peak_s"] = touched ? t_peak - t_contact : NAN;
  r["peak_base_force_N"] = peak_base;
  r["base_force_at_rest_N"] = weight;
  r["max_penetration_m"] = max_pen;
  r["final_penetration_m"] = sr.penetration.back();
  r["contact_duration_s"] = duration;
  r["rebound_velocity_m_s"] = rebound;
  r["restitution"] = rebound / v0;
  r["touched"] = touched;
  r["impact_over"] = out.results["ended_by"] == "test";
  nlohmann::json warnings = nlohmann::json::array();
  if (!touched)
    warnings.push_back("the boulder never touched the cell within run.duration_s");
  else if (!r["impact_over"].get<bool>())
    warnings.push_back("the impact was not over at the end of run.duration_s: lengthen it");
  r["warnings"] = warnings;

  // Figures: force against time (boulder and base), and against penetration.
  {
    bridge::PlotSpec plot;
    plot.title = "Unconfined impact (UCI) at " + std::to_string(v0).substr(0, 4) + " m/s";
    plot.x_label = "time from first contact (ms)";
    plot.y_label = "force (kN)";
    bridge::PlotSeries a{"on the boulder", {}, {}, bridge::PlotSeries::Style::Line};
    bridge::PlotSeries b{"on the base", {}, {}, bridge::PlotSeries::Style::Line};
    const double t0 = touched ? t_contact : 0.0;
    for (std::size_t k = 0; k < sr.time.size(); ++k) {
      if (sr.time[k] < t0 - 0.002) continue;
      a.x.push_back(1000.0 * (sr.time[k] - t0)), a.y.push_back(1e-3 * sr.force[k]);
      b.x.push_back(1000.0 * (sr.time[k] - t0)), b.y.push_back(1e-3 * sr.base_force[k]);
    }
    plot.series = {a, b};
    bridge::writePlotPng(ctx.outdir / "uci_force_time.png", plot);
    bridge::PlotSpec pp;
    pp.title = plot.title + ": force against penetration";
    pp.x_label = "penetration (mm)";
    pp.y_label = "force on the boulder (kN)";
    bridge::PlotSeries s{"force", {}, {}, bridge::PlotSeries::Style::Line};
    for (std::size_t k = 0; k < sr.time.size(); ++k)
      if (sr.time[k] >= t0) s.x.push_back(1000.0 * sr.penetration[k]), s.y.push_back(1e-3 * sr.force[k]);
    pp.series = {s};
    bridge::writePlotPng(ctx.outdir / "uci_force_penetration.png", pp);
  }
  std::ostringstream rep;
  rep.precision(4);
  rep << hooks.label << ": peak force " << peak << " N (base " << peak_base << " N), penetration " << 1000.0 * max_pen
      << " mm, contact " << 1000.0 * duration << " ms, rebound " << rebound << " m/s, "
      << out.results["broken_links"].get<std::size_t>() << " broken links\n";
  out.answer = rep.str() + out.answer;
  return out;
}

std::optional<bridge::Estimate> estimate(const bridge::JsonDocument& doc) {
  const ImpactCase c = parseCase(doc);
  return estimateReplicates(c.setup, c.velocities_m_s.size(), [&](const Sample& s, std::size_t v) {
    return planScene(c, s, c.velocities_m_s[v], doc.file()).scene;
  });
}

std::shared_ptr<const Replicates> replicates(const bridge::JsonDocument& doc) {
  const auto c = std::make_shared<const ImpactCase>(parseCase(doc));
  const std::string file = doc.file();
  std::vector<std::string> names;
  for (const double v : c->velocities_m_s) names.push_back(variantName(v));
  return std::make_shared<const Replicates>(
      Replicates{c->setup,
                 "micro.uci",
                 names,
                 [c, file](const Sample& s, std::size_t v, const bridge::RunContext& rc) {
                   return runOne(*c, s, c->velocities_m_s[v], rc, file);
                 },
                 {"peak_force_N", "peak_base_force_N", "max_penetration_m", "contact_duration_s",
                  "rebound_velocity_m_s", "broken_links"}});
}

}  // namespace

bridge::CaseKind unconfinedImpactKind() {
  return replicateKind(
      "micro.uci",
      "unconfined impact: a boulder dropped at a set velocity on a cell standing on a rigid base (docs/lab.md)", check,
      replicates, estimate);
}

}  // namespace gabion::micro::lab
