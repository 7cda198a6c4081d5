#include "micro/lab/shear_test.hpp"

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

struct ShearCase {
  LabSetup setup;
  double normal_stress_Pa = 10000.0;  // on the top cell's face, by the servo plate
  double speed_m_s = 0.05;            // of the pushing plate
  double displacement_m = 0.1;        // its travel once the normal load holds
  double settle_s = 1.0;              // the longest the normal load may take to hold
  double max_kinetic_ratio = 0.01;
};

ShearCase parseCase(const bridge::JsonDocument& doc) {
  const JsonReader root = doc.root();
  ShearCase c;
  if (const auto s = root.optionalObject("shear")) {
    c.normal_stress_Pa = s->number("normal_stress_Pa", c.normal_stress_Pa, Check::Positive);
    if (c.normal_stress_Pa > 2e6)
      s->fail("normal_stress_Pa", "above 2 MPa on a cell's face: more than any wall of cells puts on one");
    c.speed_m_s = s->number("velocity_m_s", c.speed_m_s, Check::Positive);
    c.displacement_m = s->number("displacement_m", c.displacement_m, Check::Positive);
    c.settle_s = s->number("max_settle_s", c.settle_s, Check::Positive);
  }
  if (const auto q = root.optionalObject("quasi_static"))
    c.max_kinetic_ratio = q->number("max_kinetic_ratio", c.max_kinetic_ratio, Check::Positive);
  c.setup = parseLabSetup(root, 8.0, c.settle_s + 1.2 * c.displacement_m / c.speed_m_s, 1e-3);
  return c;
}

struct Rig {
  Scene scene;
  double top_mass_kg = 0.0;
  std::size_t pusher = 0, lid = 0;
};

// Two copies of the cell, one on the other. The lower one in a box of
// plates, the upper one between two guides (y) and pushed along +x by a
// plate, pressed down by a servo lid. Every plate is a whole plane that
// touches one cell only: the upper cell's bodies are in contact groups of
// their own (kUpperGroup + the group they had), which the lower cell's
// plates skip, and the other way round. (A plate with an edge near the
// interface would meet a node bulging over its edge deep inside it once the
// node slid past the edge: a plate's edge has no contact of its own.)
constexpr int kUpperGroup = 3;

Rig buildRig(const ShearCase& c, const Sample& sample) {
  Rig rig;
  Scene& s = rig.scene;
  s = sample.scene;
  const double h = sample.hi.z() - sample.lo.z();
  const Vec3 up(0, 0, h);
  const std::size_t first = s.spheres.size();  // (the upper copy's spheres come after the lower's)
  std::uint32_t lower_groups = 0, upper_groups = 0;
  for (SphereSpec sp : sample.scene.spheres) {
    lower_groups |= 1u << sp.group;
    sp.center_m += up, sp.group += kUpperGroup;
    upper_groups |= 1u << sp.group;
    s.spheres.push_back(sp);
  }
  for (BlockSpec b : sample.scene.blocks) {
    lower_groups |= 1u << b.group;
    b.position_m += up, b.group += kUpperGroup;
    upper_groups |= 1u << b.group;
    s.blocks.push_back(b);
  }
  for (LinkSpec l : sample.scene.links) l.a += first, l.b += first, s.links.push_back(l);
  rig.top_mass_kg = sample.mass_kg;
  const Vec3 lo = sample.lo, hi = sample.hi, mid = 0.5 * (lo + hi);
  const int m = sample.plate_material;
  const auto lowerPlate = [&](const std::string& name, const Vec3& point, const Vec3& normal) {
    s.walls.push_back(fixedWall(name, point, normal, m));
    s.walls.back().skip_groups = upper_groups;
  };
  const auto upperPlate = [&](const std::string& name, const Vec3& point, const Vec3& normal) {
    s.walls.push_back(fixedWall(name, point, normal, m));
    s.walls.back().skip_groups = lower_groups;
  };
  lowerPlate("base", lo, Vec3::UnitZ());
  lowerPlate("x_minus", lo, Vec3::UnitX());
  lowerPlate("x_plus", hi, -Vec3::UnitX());
  lowerPlate("y_minus", lo, Vec3::UnitY());
  lowerPlate("y_plus", hi, -Vec3::UnitY());
  upperPlate("guide_y_minus", lo + up, Vec3::UnitY());
  upperPlate("guide_y_plus", hi + up, -Vec3::UnitY());
  rig.pusher = s.walls.size();
  upperPlate("pusher", lo + up, Vec3::UnitX());
  // The lid: a servo holding the normal force on the upper cell's top face.
  rig.lid = s.walls.size();
  WallSpec lid = fixedWall("lid", Vec3(mid.x(), mid.y(), hi.z() + h), -Vec3::UnitZ(), m);
  lid.skip_groups = lower_groups;
  const double force = c.normal_stress_Pa * (hi.x() - lo.x()) * (hi.y() - lo.y());
  lid.program.kind = WallProgram::Kind::Servo;
  lid.program.target_force_N = force;
  // Down at up to 0.2 m/s through the slack of the netting over the fill,
  // slowing as the force comes (0.025 m/s at 5 % short of it).
  lid.program.max_speed_m_s = 0.2;
  lid.program.gain_m_s_N = 0.5 / force;
  s.walls.push_back(lid);
  return rig;
}

// The rig as the test runs it: long enough for the normal load to come and
// the push to its displacement.
Rig planRig(const ShearCase& c, const Sample& sample) {
  Rig rig = buildRig(c, sample);
  if (!c.setup.duration_given) rig.scene.run.duration_s = c.settle_s + 1.2 * c.displacement_m / c.speed_m_s;
  return rig;
}

void check(const bridge::JsonDocument& doc) {
  const ShearCase c = parseCase(doc);
  checkCells(c.setup);
  if (c.setup.cells.front().generate.empty()) {
    const Sample sample = loadSample(c.setup.cells.front().file, c.setup);
    const Rig rig = buildRig(c, sample);
    validateScene(rig.scene, doc.file());
    chooseDt(rig.scene, criticalTimeStep(rig.scene), doc.file());
  }
}

// Least-squares slope of y against x (through the first point).
double slopeFromStart(const std::vector<double>& x, const std::vector<double>& y, std::size_t n) {
  double xy = 0.0, xx = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double dx = x[k] - x[0], dy = y[k] - y[0];
    xy += dx * dy, xx += dx * dx;
  }
  return xx > 0.0 ? xy / xx : NAN;
}

bridge::RunOutcome runOne(const ShearCase& c, const Sample& sample, const bridge::RunContext& ctx,
                          const std::string& file) {
  Rig rig = planRig(c, sample);
  const double weight = -rig.scene.gravity_m_s2.z() * rig.top_mass_kg;  // the upper cell's, on the interface
  const double target = rig.scene.walls[rig.lid].program.target_force_N;
  struct Series {
    std::vector<double> time, displacement, force, normal, kinetic, work;
    std::vector<double> settle_time, settle_force;  // the lid's force while the normal load comes
  } sr;
  double x0 = NAN, held_since = NAN, t_push = NAN, work0 = 0.0;
  bool pushing = false;
  SceneRunHooks hooks;
  hooks.label = "micro.shear";
  hooks.record = [&](const Engine& e, double) {
    if (!pushing) {
      sr.settle_time.push_back(e.time()), sr.settle_force.push_back(e.wallForce(rig.lid).z());
      return;
    }
    const double u = e.wallPosition(rig.pusher).x() - x0;
    sr.time.push_back(e.time() - t_push);
    sr.displacement.push_back(u);
    sr.force.push_back(-e.wallForce(rig.pusher).x());
    sr.normal.push_back(e.wallForce(rig.lid).z() + weight);
    sr.kinetic.push_back(e.kineticEnergyNow());
    sr.work.push_back(e.energy().wall_work_J - work0);
  };
  // The push starts once the lid has held its force within 10 % for 20 ms
  // (the contacts' chatter is about 5 %), or after max_settle_s.
  hooks.control = [&](Engine& e) {
    if (pushing) return;
    const double f = e.wallForce(rig.lid).z();
    if (std::fabs(f - target) > 0.1 * target)
      held_since = NAN;
    else if (std::isnan(held_since))
      held_since = e.time();
    if ((!std::isnan(held_since) && e.time() - held_since > 0.02) || e.time() > c.settle_s) {
      pushing = true;
      t_push = e.time();
      x0 = e.wallPosition(rig.pusher).x();
      work0 = e.energy().wall_work_J;
      WallProgram p;
      p.kind = WallProgram::Kind::Velocity;
      p.velocity_m_s = Vec3(c.speed_m_s, 0, 0);
      e.setWallProgram(rig.pusher, p);
    }
  };
  hooks.done = [&](const Engine&) {
    return pushing && !sr.displacement.empty() && sr.displacement.back() >= c.displacement_m;
  };
  hooks.archive = [&](bridge::StateArchive& a) {
    a("time_s", sr.time), a("displacement_m", sr.displacement), a("force_N", sr.force), a("normal_N", sr.normal);
    a("kinetic_J", sr.kinetic), a("work_J", sr.work), a("settle_time_s", sr.settle_time);
    a("settle_force_N", sr.settle_force), a("x0", x0), a("held_since", held_since), a("t_push", t_push);
    a("work0", work0), a("pushing", pushing);
  };
  hooks.write = [&](const Engine&, bridge::H5Writer& h5) {
    h5.write("/curves/shear/time_s", sr.time, "s");
    h5.write("/curves/shear/displacement_m", sr.displacement, "m");
    h5.write("/curves/shear/force_N", sr.force, "N");
    h5.write("/curves/shear/normal_force_N", sr.normal, "N");
    h5.write("/curves/shear/settle/time_s", sr.settle_time, "s");
    h5.write("/curves/shear/settle/lid_force_N", sr.settle_force, "N");
  };
  bridge::RunOutcome out = runScene(std::move(rig.scene), file, ctx, hooks);
  nlohmann::json& r = out.results;
  r["normal_stress_Pa"] = c.normal_stress_Pa;
  r["upper_cell_weight_N"] = weight;
  r["lid_force_N"] = target;
  if (sr.force.empty()) {
    r["warnings"] = {"the push never started"};
    return out;
  }
  // Friction: the tangential over the normal force, its peak and its mean
  // over the last fifth of the travel (the sliding); stiffness: the slope
  // of the force against the displacement up to half its peak.
  const std::size_t n = sr.force.size();
  double peak_ratio = 0.0, peak = 0.0, sum = 0.0, normal_mean = 0.0;
  std::size_t count = 0;
  for (std::size_t k = 0; k < n; ++k) {
    peak = std::max(peak, sr.force[k]);
    if (sr.normal[k] > 0.0) peak_ratio = std::max(peak_ratio, sr.force[k] / sr.normal[k]);
    if (sr.displacement[k] >= 0.8 * c.displacement_m && sr.normal[k] > 0.0)
      sum += sr.force[k] / sr.normal[k], normal_mean += sr.normal[k], ++count;
  }
  std::size_t half = 0;
  while (half < n && sr.force[half] < 0.5 * peak) ++half;
  QuasiStatic qs;
  for (std::size_t k = 0; k < n; ++k) qs.add(sr.kinetic[k], sr.work[k]);
  const double ratio = qs.ratio();
  r["friction_coefficient"] = count > 0 ? sum / static_cast<double>(count) : NAN;
  r["peak_friction_coefficient"] = peak_ratio;
  r["peak_tangential_force_N"] = peak;
  r["mean_normal_force_N"] = count > 0 ? normal_mean / static_cast<double>(count) : NAN;
  const double stiffness = slopeFromStart(sr.displacement, sr.force, std::max<std::size_t>(half, 3));
  r["tangential_stiffness_N_m"] = stiffness;
  // Sliding: over the last quarter of the travel the force grows at less
  // than a fifth of the initial stiffness.
  std::vector<double> ul, fl;
  for (std::size_t k = 0; k < n; ++k)
    if (sr.displacement[k] >= 0.75 * c.displacement_m) ul.push_back(sr.displacement[k]), fl.push_back(sr.force[k]);
  const double final_slope = ul.size() >= 3 ? slopeFromStart(ul, fl, ul.size()) : NAN;
  r["final_slope_N_m"] = final_slope;
  r["sliding"] = final_slope < 0.2 * stiffness;
  r["shear_displacement_m"] = sr.displacement.back();
  r["push_started_s"] = t_push;
  // The load held: the lid reached its force before the push (else the
  // upper cell, confined by its netting alone, was still giving way under it).
  const bool held = !std::isnan(held_since);
  r["normal_load_held"] = held;
  r["kinetic_to_work_ratio"] = ratio;
  r["quasi_static"] = ratio <= c.max_kinetic_ratio;
  nlohmann::json warnings = nlohmann::json::array();
  if (!(ratio <= c.max_kinetic_ratio))
    warnings.push_back("the test left its quasi-static range: kinetic energy up to " + std::to_string(ratio) +
                       " of the pusher's work; lower shear.velocity_m_s");
  if (!(final_slope < 0.2 * stiffness))
    warnings.push_back("the interface had not slid by the end: the force still grew at " +
                       std::to_string(final_slope / stiffness).substr(0, 4) +
                       " of its initial stiffness over the last quarter (the friction coefficient is then the one "
                       "mobilised so far); raise shear.displacement_m");
  if (!held)
    warnings.push_back("the lid did not reach its force of " + std::to_string(target) +
                       " N within shear.max_settle_s (" + std::to_string(c.settle_s) +
                       " s): the upper cell, confined by its netting alone, was still giving way under it; lower "
                       "shear.normal_stress_Pa or raise shear.max_settle_s");
  r["warnings"] = warnings;
  {
    bridge::PlotSpec plot;
    plot.title = "Interface shear under " + std::to_string(c.normal_stress_Pa / 1000.0).substr(0, 5) + " kPa";
    plot.x_label = "shear displacement (mm)";
    plot.y_label = "force (kN)";
    plot.series = {bridge::scaledSeries("tangential (pusher)", sr.displacement, sr.force, 1000.0, 1e-3),
                   bridge::scaledSeries("normal on the interface", sr.displacement, sr.normal, 1000.0, 1e-3)};
    bridge::writePlotPng(ctx.outdir / "shear_curve.png", plot);
  }
  std::ostringstream rep;
  rep.precision(4);
  rep << "micro.shear: friction coefficient " << r["friction_coefficient"].get<double>() << " (peak " << peak_ratio
      << "), tangential stiffness " << r["tangential_stiffness_N_m"].get<double>() << " N/m under "
      << r["mean_normal_force_N"].get<double>() << " N; kinetic/work " << ratio << "\n";
  out.answer = rep.str() + out.answer;
  return out;
}

std::optional<bridge::Estimate> estimate(const bridge::JsonDocument& doc) {
  const ShearCase c = parseCase(doc);
  return estimateReplicates(c.setup, 1, [&](const Sample& s, std::size_t) { return planRig(c, s).scene; });
}

std::shared_ptr<const Replicates> replicates(const bridge::JsonDocument& doc) {
  const auto c = std::make_shared<const ShearCase>(parseCase(doc));
  const std::string file = doc.file();
  return std::make_shared<const Replicates>(Replicates{
      c->setup,
      "micro.shear",
      {"test"},
      [c, file](const Sample& s, std::size_t, const bridge::RunContext& rc) { return runOne(*c, s, rc, file); },
      {"friction_coefficient", "peak_friction_coefficient", "tangential_stiffness_N_m", "kinetic_to_work_ratio"}});
}

}  // namespace

bridge::CaseKind interfaceShearKind() {
  return replicateKind("micro.shear",
                       "interface shear: a cell on another under a normal load held by a servo, the upper one pushed "
                       "sideways (docs/lab.md)",
                       check, replicates, estimate);
}

}  // namespace gabion::micro::lab
