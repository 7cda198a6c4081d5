#include "micro/lab/compression_test.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "micro/lab/force_drops.hpp"
#include "micro/lab/lab_setup.hpp"
#include "micro/scene_run.hpp"

namespace gabion::micro::lab {
namespace {

constexpr long long kMaxCellsInSeries = 4;

using bridge::Check;
using bridge::JsonReader;

// The netting's nodes are group 1 in a micro.cell (nodeSphere); the plates
// touch both rock and netting.
struct CompressionCase {
  bool confined = true;  // micro.cc (six walls) or micro.uc (two plates)
  int axis = 2;          // loading axis: 2 (z, the lid comes down) or 0 (x, the lid pushes along -x)
  int in_series = 1;     // copies of the cell in a row along the loading axis (a joint between each two)
  LabSetup setup;
  double velocity_m_s = 0.1;      // of the lid
  double strain = 0.15;           // the lid's travel over the sample's height
  std::vector<double> unload_at;  // strains where the lid reverses
  double unload_to = 0.1;         // ... until the force is this fraction of the force there
  double max_kinetic_ratio = 0.01;
  bool strict = false;
  double drop_fraction = 0.05, drop_window_s = 0.02;  // micro.uc
};

CompressionCase parseCase(const bridge::JsonDocument& doc, bool confined) {
  const JsonReader root = doc.root();
  CompressionCase c;
  c.confined = confined;
  if (const auto l = root.optionalObject("loading")) {
    c.velocity_m_s = l->number("velocity_m_s", c.velocity_m_s, Check::Positive);
    c.strain = l->number("strain", c.strain, Check::Positive);
    if (c.strain > 0.6) l->fail("strain", "must be <= 0.6 (the lid's travel over the cell's height)");
    if (l->has("unload_at_strain")) {
      c.unload_at = l->numbers("unload_at_strain", Check::Positive, 0);
      for (std::size_t k = 0; k < c.unload_at.size(); ++k)
        if (c.unload_at[k] >= c.strain || (k > 0 && c.unload_at[k] <= c.unload_at[k - 1]))
          l->fail("unload_at_strain", "must increase, and stay below the final strain " + std::to_string(c.strain));
    }
    c.unload_to = l->number("unload_to_force_fraction", c.unload_to, Check::UnitOpen);
    c.axis = l->choice("axis", {"z", "x"}, "z") == "x" ? 0 : 2;
    c.in_series = static_cast<int>(l->integer("cells_in_series", 1, 1));
    if (c.in_series > kMaxCellsInSeries)
      l->fail("cells_in_series",
              "must be <= " + std::to_string(kMaxCellsInSeries) + " (cells in a row along the load)");
  }
  if (const auto q = root.optionalObject("quasi_static")) {
    c.max_kinetic_ratio = q->number("max_kinetic_ratio", c.max_kinetic_ratio, Check::Positive);
    c.strict = q->boolean("strict", c.strict);
  }
  if (!confined)
    if (const auto d = root.optionalObject("drops")) {
      c.drop_fraction = d->number("min_fraction", c.drop_fraction, Check::Positive);
      if (c.drop_fraction >= 1.0) d->fail("min_fraction", "must be < 1");
      c.drop_window_s = d->number("window_s", c.drop_window_s, Check::Positive);
    }
  // Long enough for the loading and each unloading-reloading cycle; the test
  // ends when the lid reaches the final strain. The series every 1 ms.
  const double travel = 0.55 * c.in_series * c.strain;  // (m, for cells up to 0.55 m long; longer: give run.duration_s)
  double back = 0.0;
  for (const double s : c.unload_at) back += 2.0 * 0.55 * c.in_series * s;
  c.setup = parseLabSetup(root, 8.0, 1.2 * (travel + back) / c.velocity_m_s, 1e-3);
  return c;
}

// The cells the rig holds: the sample, or with cells_in_series n copies of
// it in a row along the loading axis, one extent apart (the bodies of each
// just touching the next's, as micro.structure lays its cells out). Its
// extent is the row's.
Sample row(const CompressionCase& c, const Sample& sample) {
  if (c.in_series == 1) return sample;
  Sample out = sample;
  Scene& s = out.scene;
  const Scene& cell = sample.scene;
  s.spheres.clear(), s.blocks.clear(), s.links.clear();
  const double pitch = sample.hi[c.axis] - sample.lo[c.axis];
  for (int k = 0; k < c.in_series; ++k) {
    const Vec3 shift = k * pitch * Vec3::Unit(c.axis);
    const std::size_t first = s.spheres.size();
    for (SphereSpec sp : cell.spheres) sp.center_m += shift, s.spheres.push_back(sp);
    for (BlockSpec b : cell.blocks) b.position_m += shift, s.blocks.push_back(b);
    for (LinkSpec l : cell.links) l.a += first, l.b += first, s.links.push_back(l);
  }
  out.hi[c.axis] += (c.in_series - 1) * pitch;
  out.mass_kg *= c.in_series;
  out.netting_nodes *= static_cast<std::size_t>(c.in_series);
  return out;
}

// The rig's walls by their role: the fixed plate facing the lid, the four
// lateral plates (confined), the lid.
struct Rig {
  std::size_t facing = 0, lid = 0;
  std::vector<std::size_t> sides;
};

// Where the walls go: the sample's extent, the lid on the loading axis's
// upper face. Loaded along z: the base faces the lid, and the lateral plates
// are x_minus, x_plus, y_minus, y_plus. Loaded along x: x_minus faces the
// lid; the cell stands on the base, under a fixed top (confined), between
// y_minus and y_plus, the lateral plates (the base and top carry its weight).
Scene buildScene(const CompressionCase& c, const Sample& sample, Rig* rig = nullptr) {
  Scene s = sample.scene;
  Rig r;
  const auto plate = [&](const std::string& name, const Vec3& point, const Vec3& normal) {
    s.walls.push_back(fixedWall(name, point, normal, sample.plate_material));
    return s.walls.size() - 1;
  };
  const Vec3 lo = sample.lo, hi = sample.hi;
  r.facing = plate(c.axis == 2 ? "base" : "x_minus", lo, Vec3::Unit(c.axis));
  if (c.axis == 0) plate("base", lo, Vec3::UnitZ());
  if (c.confined) {
    if (c.axis == 2) r.sides.push_back(plate("x_minus", lo, Vec3::UnitX()));
    if (c.axis == 2) r.sides.push_back(plate("x_plus", hi, -Vec3::UnitX()));
    r.sides.push_back(plate("y_minus", lo, Vec3::UnitY()));
    r.sides.push_back(plate("y_plus", hi, -Vec3::UnitY()));
    if (c.axis == 0) plate("top", hi, -Vec3::UnitZ());
  }
  r.lid = plate("lid", hi, -Vec3::Unit(c.axis));
  s.walls.back().program.kind = WallProgram::Kind::Velocity;
  s.walls.back().program.velocity_m_s = -c.velocity_m_s * Vec3::Unit(c.axis);
  if (rig) *rig = r;
  return s;
}

// The scene as the test runs it: the rig, and a duration long enough for the
// loading and each unloading-reloading cycle at the sample's length.
// `sample`: the rig's cells, row() of the cell.
Scene planScene(const CompressionCase& c, const Sample& sample, Rig* rig = nullptr) {
  Scene scene = buildScene(c, sample, rig);
  const double height = sample.hi[c.axis] - sample.lo[c.axis];
  double travel = c.strain * height;
  for (const double s : c.unload_at) travel += 2.0 * s * height;
  if (!c.setup.duration_given) scene.run.duration_s = 1.2 * travel / c.velocity_m_s;
  return scene;
}

void check(const bridge::JsonDocument& doc, bool confined) {
  const CompressionCase c = parseCase(doc, confined);
  checkCells(c.setup);
  if (c.setup.cells.front().generate.empty()) {
    const Sample sample = loadSample(c.setup.cells.front().file, c.setup);
    const Scene s = planScene(c, row(c, sample));
    validateScene(s, doc.file());
    chooseDt(s, criticalTimeStep(s), doc.file());
  }
}

struct Curves {
  std::vector<double> time, displacement, force, base_force, lateral, kinetic, work;
  std::vector<std::vector<double>> side;  // x_minus, x_plus, y_minus, y_plus
};

// Least-squares slope through the origin of y against x.
double slopeThroughOrigin(const std::vector<double>& x, const std::vector<double>& y) {
  double xy = 0.0, xx = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) xy += x[k] * y[k], xx += x[k] * x[k];
  return xx > 0.0 ? xy / xx : NAN;
}

// The shape of the first loading: the seating displacement u_s, where the
// force first reaches 2 % of its largest value (the lid taking up the slack
// of the netting over the fill), and the exponent b of F = a (u - u_s)^b
// where u - u_s is between a fifth of its largest value and that value
// (log-log least squares): near 1 for a quasi-linear curve, above 1 for a
// convex one.
struct CurveShape {
  double seating_m = NAN, exponent = NAN;
};

CurveShape curveShape(const std::vector<double>& u, const std::vector<double>& f) {
  std::vector<double> lu, lf;  // the first loading (u while it increases)
  for (std::size_t k = 0; k < u.size() && (k == 0 || u[k] >= u[k - 1]); ++k) lu.push_back(u[k]), lf.push_back(f[k]);
  CurveShape out;
  double fmax = 0.0;
  for (const double x : lf) fmax = std::max(fmax, x);
  std::size_t seat = 0;
  while (seat < lf.size() && lf[seat] < 0.02 * fmax) ++seat;
  if (seat >= lf.size()) return out;
  out.seating_m = lu[seat];
  const double span = lu.back() - lu[seat];
  double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
  for (std::size_t k = seat; k < lu.size(); ++k) {
    const double d = lu[k] - lu[seat];
    if (d < 0.2 * span || !(lf[k] > 0.0)) continue;
    const double x = std::log(d), y = std::log(lf[k]);
    sx += x, sy += y, sxx += x * x, sxy += x * y, n += 1;
  }
  const double det = n * sxx - sx * sx;
  if (n >= 3 && det > 0.0) out.exponent = (n * sxy - sx * sy) / det;
  return out;
}

bridge::RunOutcome runOne(const CompressionCase& c, const Sample& cell, const bridge::RunContext& ctx,
                          const std::string& file) {
  Rig rig;
  const Sample sample = row(c, cell);
  Scene scene = planScene(c, sample, &rig);
  const int ax = c.axis;
  const double height = sample.hi[ax] - sample.lo[ax];
  const double target = c.strain * height;
  const std::size_t lid = rig.lid;

  Curves cv;
  cv.side.resize(rig.sides.size());
  std::vector<Vec3> side_normal;
  std::vector<std::string> side_name;
  for (const std::size_t w : rig.sides)
    side_normal.push_back(scene.walls[w].normal), side_name.push_back(scene.walls[w].name);
  struct Cycle {
    double strain, force_N, displacement_m, stiffness_N_m = NAN;
    double u_low = NAN, f_low = NAN;
  };
  std::vector<Cycle> cycles;
  std::size_t next_cycle = 0;
  bool unloading = false;
  SceneRunHooks hooks;
  hooks.label = c.confined ? "micro.cc" : "micro.uc";
  hooks.record = [&](const Engine& e, double) {
    const double u = sample.hi[ax] - e.wallPosition(lid)[ax];  // (the lid started at the sample's upper face)
    cv.time.push_back(e.time());
    cv.displacement.push_back(u);
    cv.force.push_back(e.wallForce(lid)[ax]);
    cv.base_force.push_back(-e.wallForce(rig.facing)[ax]);
    if (c.confined) {
      // (a lateral plate's force on it, outwards: its normal points into the sample)
      double mean = 0.0;
      for (std::size_t k = 0; k < rig.sides.size(); ++k) {
        const std::size_t w = rig.sides[k];
        const double f = -e.wallForce(w).dot(side_normal[k]);
        cv.side[k].push_back(f);
        mean += f / static_cast<double>(rig.sides.size());
      }
      cv.lateral.push_back(mean);
    }
    cv.kinetic.push_back(e.kineticEnergyNow());
    cv.work.push_back(e.energy().wall_work_J);
  };
  // Unloading and reloading: at each unload strain the lid goes back up at
  // its speed until the force falls to unload_to of what it was there.
  hooks.control = [&](Engine& e) {
    const double u = cv.displacement.back(), f = cv.force.back();
    WallProgram p;
    p.kind = WallProgram::Kind::Velocity;
    if (!unloading && next_cycle < c.unload_at.size() && u >= c.unload_at[next_cycle] * height) {
      cycles.push_back({c.unload_at[next_cycle], f, u});
      ++next_cycle;
      unloading = true;
      p.velocity_m_s = c.velocity_m_s * Vec3::Unit(ax);
      e.setWallProgram(lid, p);
    } else if (unloading && f <= c.unload_to * cycles.back().force_N) {
      Cycle& cy = cycles.back();
      cy.u_low = u, cy.f_low = f;
      if (cy.displacement_m > u) cy.stiffness_N_m = (cy.force_N - f) / (cy.displacement_m - u);
      unloading = false;
      p.velocity_m_s = -c.velocity_m_s * Vec3::Unit(ax);
      e.setWallProgram(lid, p);
    }
  };
  hooks.done = [&](const Engine&) { return !unloading && cv.displacement.back() >= target; };
  hooks.archive = [&](bridge::StateArchive& a) {
    a("time_s", cv.time), a("displacement_m", cv.displacement), a("force_N", cv.force);
    a("base_force_N", cv.base_force), a("lateral_N", cv.lateral), a("kinetic_J", cv.kinetic), a("work_J", cv.work);
    for (std::size_t k = 0; k < cv.side.size(); ++k) a("side_N/" + std::to_string(k), cv.side[k]);
    std::vector<double> strain, force, disp, stiff, u_low, f_low;
    for (const Cycle& cy : cycles)
      strain.push_back(cy.strain), force.push_back(cy.force_N), disp.push_back(cy.displacement_m),
          stiff.push_back(cy.stiffness_N_m), u_low.push_back(cy.u_low), f_low.push_back(cy.f_low);
    bridge::StateArchive ca = a.group("cycles");
    ca("strain", strain), ca("force_N", force), ca("displacement_m", disp), ca("stiffness_N_m", stiff);
    ca("u_low", u_low), ca("f_low", f_low);
    a("next_cycle", next_cycle), a("unloading", unloading);
    if (!a.loading()) return;
    cycles.clear();
    for (std::size_t k = 0; k < strain.size() && k < force.size() && k < disp.size(); ++k)
      cycles.push_back({strain[k], force[k], disp[k], stiff.at(k), u_low.at(k), f_low.at(k)});
  };
  hooks.write = [&](const Engine&, bridge::H5Writer& h5) {
    const std::string g = c.confined ? "/curves/axial/" : "/curves/uc/";
    h5.write(g + "time_s", cv.time, "s");
    h5.write(g + "displacement_m", cv.displacement, "m");
    h5.write(g + "force_N", cv.force, "N");
    h5.write(g + "base_force_N", cv.base_force, "N");
    if (c.confined) {
      h5.write("/curves/lateral/axial_force_N", cv.force, "N");
      h5.write("/curves/lateral/lateral_force_N", cv.lateral, "N");
      for (std::size_t k = 0; k < cv.side.size(); ++k)
        h5.write("/curves/lateral/" + side_name[k] + "_N", cv.side[k], "N");
    }
  };
  bridge::RunOutcome out = runScene(std::move(scene), file, ctx, hooks);
  nlohmann::json& r = out.results;
  if (cv.force.empty()) return out;

  QuasiStatic qs;
  for (std::size_t k = 0; k < cv.kinetic.size(); ++k) qs.add(cv.kinetic[k], cv.work[k]);
  const double ratio = qs.ratio();
  const auto peak = std::max_element(cv.force.begin(), cv.force.end()) - cv.force.begin();
  r["loading_axis"] = std::string(1, "xyz"[ax]);
  r["cells_in_series"] = c.in_series;
  r["height_m"] = height;  // (along the loading axis)
  const int across1 = ax == 2 ? 0 : 1, across2 = ax == 2 ? 1 : 2;
  r["width_m"] = {sample.hi[across1] - sample.lo[across1], sample.hi[across2] - sample.lo[across2]};
  r["mass_kg"] = sample.mass_kg;
  r["velocity_m_s"] = c.velocity_m_s;
  r["peak_force_N"] = cv.force[static_cast<std::size_t>(peak)];
  r["displacement_at_peak_m"] = cv.displacement[static_cast<std::size_t>(peak)];
  r["final_displacement_m"] = cv.displacement.back();
  r["final_strain"] = cv.displacement.back() / height;
  r["final_force_N"] = cv.force.back();
  r["secant_stiffness_N_m"] = cv.displacement.back() > 0.0 ? cv.force.back() / cv.displacement.back() : NAN;
  const CurveShape shape = curveShape(cv.displacement, cv.force);
  r["seating_displacement_m"] = shape.seating_m;
  r["power_law_exponent"] = shape.exponent;
  r["kinetic_to_work_ratio"] = ratio;
  r["quasi_static"] = ratio <= c.max_kinetic_ratio;
  r["reached_strain"] = out.results["ended_by"] == "test";
  nlohmann::json warnings = nlohmann::json::array();
  if (!(ratio <= c.max_kinetic_ratio)) {
    std::ostringstream w;
    w << "the test left its quasi-static range: kinetic energy up to " << ratio << " of the lid's work (limit "
      << c.max_kinetic_ratio << "); lower loading.velocity_m_s or raise netting_mass_scale";
    warnings.push_back(w.str());
  }
  if (c.confined) {
    std::vector<double> fa, fl;
    double reached = 0.0;
    for (std::size_t k = 0; k < cv.force.size(); ++k)
      if (cv.displacement[k] >= reached)
        reached = cv.displacement[k], fa.push_back(cv.force[k]), fl.push_back(cv.lateral[k]);
    r["lateral_reaction_coefficient"] = slopeThroughOrigin(fa, fl);
    nlohmann::json cy = nlohmann::json::array();
    for (const Cycle& k : cycles)
      cy.push_back({{"strain", k.strain},
                    {"displacement_m", k.displacement_m},
                    {"force_N", k.force_N},
                    {"unloaded_to_N", k.f_low},
                    {"unloaded_to_displacement_m", k.u_low},
                    {"unloading_stiffness_N_m", k.stiffness_N_m}});
    r["cycles"] = cy;
  } else {
    double fmax = 0.0;
    for (const double f : cv.force) fmax = std::max(fmax, f);
    const auto drops = forceDrops(cv.time, cv.displacement, cv.force, c.drop_fraction, c.drop_window_s, 0.02 * fmax);
    nlohmann::json d = nlohmann::json::array();
    for (const ForceDrop& x : drops)
      d.push_back({{"time_s", x.time_s},
                   {"displacement_m", x.displacement_m},
                   {"force_before_N", x.force_before_N},
                   {"force_after_N", x.force_after_N},
                   {"size_N", x.size_N()}});
    r["force_drops"] = d;
    r["drop_count"] = drops.size();
  }
  r["warnings"] = warnings;

  // Figures: the axial curve (with the drops), and the lateral reactions.
  {
    bridge::PlotSpec plot;
    plot.title = c.confined ? "Confined compression (CC)" : "Unconfined compression (UC)";
    plot.x_label = "lid displacement (mm)";
    plot.y_label = "axial force (kN)";
    plot.series.push_back(bridge::scaledSeries("lid force", cv.displacement, cv.force, 1000.0, 1e-3));
    if (!c.confined && !r["force_drops"].empty()) {
      bridge::PlotSeries d{"force drops", {}, {}, bridge::PlotSeries::Style::Markers};
      for (const auto& x : r["force_drops"])
        d.x.push_back(1000.0 * x["displacement_m"].get<double>()),
            d.y.push_back(1e-3 * x["force_before_N"].get<double>());
      plot.series.push_back(d);
    }
    bridge::writePlotPng(ctx.outdir / (c.confined ? "cc_curve.png" : "uc_curve.png"), plot);
  }
  if (c.confined) {
    bridge::PlotSpec plot;
    plot.title = "CC: lateral wall reactions";
    plot.x_label = "axial force (kN)";
    plot.y_label = "lateral force (kN)";
    plot.series.push_back(bridge::scaledSeries("mean of the four lateral walls", cv.force, cv.lateral, 1e-3, 1e-3));
    const double kr = r["lateral_reaction_coefficient"].get<double>();
    double fmax = 0.0;
    for (const double f : cv.force) fmax = std::max(fmax, f);
    plot.series.push_back({"coefficient " + std::to_string(kr).substr(0, 5),
                           {0.0, 1e-3 * fmax},
                           {0.0, 1e-3 * kr * fmax},
                           bridge::PlotSeries::Style::Line});
    bridge::writePlotPng(ctx.outdir / "cc_lateral.png", plot);
  }
  std::ostringstream rep;
  rep.precision(4);
  rep << hooks.label << ": peak " << r["peak_force_N"].get<double>() << " N at "
      << 1000.0 * r["displacement_at_peak_m"].get<double>() << " mm; final strain " << r["final_strain"].get<double>()
      << ", force " << r["final_force_N"].get<double>() << " N";
  if (c.confined)
    rep << "; lateral reaction coefficient " << r["lateral_reaction_coefficient"].get<double>();
  else
    rep << "; " << r["drop_count"].get<std::size_t>() << " force drops";
  rep << "; kinetic/work " << ratio << (r["quasi_static"].get<bool>() ? " (quasi-static)" : " (NOT quasi-static)")
      << "\n";
  out.answer = rep.str() + out.answer;
  if (c.strict && !r["quasi_static"].get<bool>() && out.status == bridge::RunOutcome::Status::Ok) {
    out.status = bridge::RunOutcome::Status::NumericalFailure;
    out.message = warnings.front().get<std::string>() + " (quasi_static.strict)";
  }
  return out;
}

std::shared_ptr<const Replicates> replicates(const bridge::JsonDocument& doc, bool confined) {
  const auto c = std::make_shared<const CompressionCase>(parseCase(doc, confined));
  const std::string file = doc.file();
  std::vector<std::string> keys =
      confined
          ? std::vector<std::string>{"peak_force_N", "final_force_N", "secant_stiffness_N_m",
                                     "lateral_reaction_coefficient", "kinetic_to_work_ratio"}
          : std::vector<std::string>{"peak_force_N", "displacement_at_peak_m", "drop_count", "kinetic_to_work_ratio"};
  return std::make_shared<const Replicates>(Replicates{
      c->setup,
      confined ? "micro.cc" : "micro.uc",
      {"test"},
      [c, file](const Sample& s, std::size_t, const bridge::RunContext& rc) { return runOne(*c, s, rc, file); },
      std::move(keys)});
}

std::optional<bridge::Estimate> estimate(const bridge::JsonDocument& doc, bool confined) {
  const CompressionCase c = parseCase(doc, confined);
  return estimateReplicates(c.setup, 1, [&](const Sample& s, std::size_t) { return planScene(c, row(c, s)); });
}

}  // namespace

bridge::CaseKind confinedCompressionKind() {
  return replicateKind(
      "micro.cc", "confined compression of a cell between six rigid walls, the lid driven down (docs/lab.md)",
      [](const bridge::JsonDocument& d) { check(d, true); },
      [](const bridge::JsonDocument& d) { return replicates(d, true); },
      [](const bridge::JsonDocument& d) { return estimate(d, true); });
}

bridge::CaseKind unconfinedCompressionKind() {
  return replicateKind(
      "micro.uc", "unconfined compression of a cell between two plates, the netting alone confining (docs/lab.md)",
      [](const bridge::JsonDocument& d) { check(d, false); },
      [](const bridge::JsonDocument& d) { return replicates(d, false); },
      [](const bridge::JsonDocument& d) { return estimate(d, false); });
}

}  // namespace gabion::micro::lab
