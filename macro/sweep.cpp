// The macro.sweep case kind: a grid of impacts over boulder velocity, mass,
// aim point and structure size, run in parallel on ctx.threads worker threads
// (each point on its own fresh model; results stored by point index, so the
// output order does not depend on the threads). Failed points are recorded.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/interrupt.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "bridge/rows.hpp"
#include "bridge/units.hpp"
#include "macro/case_reader.hpp"
#include "macro/runs.hpp"

namespace gabion::macro {

using bridge::InputError;
using bridge::JsonDocument;
using nlohmann::json;

namespace {

struct Point {
  double velocity_m_s = 0.0, mass_kg = 0.0, aim_y_m = 0.0, aim_z_m = 0.0;
  int size = 0;  // index into the structure sizes
  double energy_J = 0.0;
};

struct Plan {
  ImpactCase c;
  SweepSpec sweep;
  std::vector<std::array<int, 3>> sizes;
  std::vector<Structure> structures;
  std::vector<Point> points;
};

Plan plan(const JsonDocument& doc) {
  Plan p;
  p.c = readImpactCase(doc, true);
  p.sweep = readSweep(doc.root().object("sweep"));
  p.sizes = p.sweep.cells;
  if (p.sizes.empty()) p.sizes.push_back({p.c.structure.nx, p.c.structure.ny, p.c.structure.nz});
  for (std::size_t i = 0; i < p.sizes.size(); ++i) {
    ImpactCase sized = p.c;
    sized.structure.nx = p.sizes[i][0];
    sized.structure.ny = p.sizes[i][1];
    sized.structure.nz = p.sizes[i][2];
    if (!p.sweep.cells.empty() && !sized.structure.front_offset_cells.empty() &&
        static_cast<int>(sized.structure.front_offset_cells.size()) != sized.structure.nz)
      throw InputError(doc.file(), "/sweep/cells/" + std::to_string(i),
                       "the structure's front_offset_cells needs one entry per z layer of this size");
    try {
      p.structures.push_back(buildStructure(sized.structure, p.c.laws));
    } catch (const std::invalid_argument& e) {
      throw InputError(doc.file(), p.sweep.cells.empty() ? "/structure" : "/sweep/cells/" + std::to_string(i),
                       e.what());
    }
  }
  const BoulderSpec& b = p.c.impacts.front();
  const std::vector<double> speeds =
      p.sweep.velocity_m_s.empty() ? std::vector<double>{b.velocity_m_s.norm()} : p.sweep.velocity_m_s;
  const std::vector<double> masses = p.sweep.mass_kg.empty() ? std::vector<double>{b.mass_kg} : p.sweep.mass_kg;
  for (std::size_t si = 0; si < p.sizes.size(); ++si) {
    std::vector<std::pair<double, double>> aims = p.sweep.aim_point_m;
    if (aims.empty()) {
      StructureSpec sized = p.c.structure;
      sized.nx = p.sizes[si][0];
      sized.ny = p.sizes[si][1];
      sized.nz = p.sizes[si][2];
      aims.push_back(p.c.aim_given.front() ? std::make_pair(b.aim_y_m, b.aim_z_m)
                                           : defaultAim(sized, p.structures[si].edge_m));
    }
    for (const auto& aim : aims)
      for (double m : masses)
        for (double v : speeds) {
          Point pt;
          pt.velocity_m_s = v;
          pt.mass_kg = m;
          pt.aim_y_m = aim.first;
          pt.aim_z_m = aim.second;
          pt.size = static_cast<int>(si);
          pt.energy_J = 0.5 * m * v * v;
          p.points.push_back(pt);
        }
  }
  return p;
}

ImpactResult runPoint(const Plan& p, const Point& pt) {
  const Structure& s = p.structures[static_cast<std::size_t>(pt.size)];
  ImpactResult r;
  if (pt.aim_y_m < 0.0 || pt.aim_y_m > s.ny * s.edge_m || pt.aim_z_m < 0.0 || pt.aim_z_m > s.nz * s.edge_m) {
    r.ok = false;
    r.message = "aim point outside the front face of this structure";
    return r;
  }
  BoulderSpec b = p.c.impacts.front();
  b.velocity_m_s = b.velocity_m_s.normalized() * pt.velocity_m_s;
  b.setMass(pt.mass_kg, p.sweep.keep_diameter);
  b.aim_y_m = pt.aim_y_m;
  b.aim_z_m = pt.aim_z_m;
  try {
    Model model(s, p.c.run.kinematics);
    return runImpact(model, b, p.c.run, 0, nullptr);
  } catch (const std::exception& e) {
    r.ok = false;
    r.message = e.what();
    return r;
  }
}

std::string csvQuote(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return out + "\"";
}

// The critical step of each structure size, with the first boulder
// placed at the size's default aim.
std::vector<double> criticalSteps(const Plan& p) {
  std::vector<double> out;
  for (std::size_t i = 0; i < p.structures.size(); ++i) {
    StructureSpec sized = p.c.structure;
    sized.nx = p.sizes[i][0], sized.ny = p.sizes[i][1], sized.nz = p.sizes[i][2];
    const auto aim = defaultAim(sized, p.structures[i].edge_m);
    BoulderSpec b = p.c.impacts.front();
    b.aim_y_m = aim.first, b.aim_z_m = aim.second;
    Model probe(p.structures[i], p.c.run.kinematics);
    probe.placeBoulder(b);
    out.push_back(probe.criticalTimeStep());
  }
  return out;
}

// What a row keeps of an impact: what the sweep's table and summary show.
json toRow(const ImpactResult& r) {
  json j = {{"ok", r.ok}};
  if (!r.ok) {
    j["message"] = r.message;
    return j;
  }
  j["outcome"] = static_cast<int>(r.outcome);
  j["peak_force_N"] = r.peak_force_N;
  j["max_penetration_m"] = r.max_penetration_m;
  j["contact_duration_s"] = r.contact_duration_s;
  j["rebound_velocity_m_s"] = r.rebound_velocity_m_s;
  j["max_back_face_displacement_m"] = r.max_back_face_displacement_m;
  j["plastic_J"] = r.plastic_J;
  j["friction_J"] = r.friction_J;
  j["balance_rel_error"] = r.balance_rel_error;
  return j;
}

ImpactResult fromRow(const json& j) {
  ImpactResult r;
  r.ok = j.at("ok").get<bool>();
  if (!r.ok) {
    r.message = j.at("message").get<std::string>();
    return r;
  }
  r.outcome = static_cast<Outcome>(j.at("outcome").get<int>());
  r.peak_force_N = j.at("peak_force_N").get<double>();
  r.max_penetration_m = j.at("max_penetration_m").get<double>();
  r.contact_duration_s = j.at("contact_duration_s").get<double>();
  r.rebound_velocity_m_s = j.at("rebound_velocity_m_s").get<double>();
  r.max_back_face_displacement_m = j.at("max_back_face_displacement_m").get<double>();
  r.plastic_J = j.at("plastic_J").get<double>();
  r.friction_J = j.at("friction_J").get<double>();
  r.balance_rel_error = j.at("balance_rel_error").get<double>();
  return r;
}

// The sweep's points as rows (bridge/rows.hpp): each point on its own fresh
// model, so a point's row depends on its index alone.
class SweepPlan final : public bridge::RowPlan {
 public:
  explicit SweepPlan(const JsonDocument& doc) : p_(plan(doc)), critical_([this] { return criticalSteps(p_); }) {}
  std::size_t size() const override { return p_.points.size(); }
  json describe(std::size_t i) const override {
    const Point& pt = p_.points[i];
    const auto& size = p_.sizes[static_cast<std::size_t>(pt.size)];
    return {{"parameters",
             {{"velocity_m_s", pt.velocity_m_s},
              {"mass_kg", pt.mass_kg},
              {"aim_y_m", pt.aim_y_m},
              {"aim_z_m", pt.aim_z_m},
              {"cells", {size[0], size[1], size[2]}}}},
            {"seed", nullptr}};
  }
  json run(std::size_t i, const bridge::RunContext&) const override { return toRow(runPoint(p_, p_.points[i])); }
  double costS(std::size_t i) const override {
    const auto s = static_cast<std::size_t>(p_.points[i].size);
    return impactEstimate(p_.c.run, p_.structures[s], critical_()[s]).wall_time_s;
  }
  bridge::RunOutcome assemble(const std::vector<std::optional<json>>& rows, const bridge::RowStats& stats,
                              const bridge::RunContext& ctx) const override;

 private:
  Plan p_;
  bridge::Lazy<std::vector<double>> critical_;
};

}  // namespace

void checkSweepCase(const JsonDocument& doc) {
  const Plan p = plan(doc);
  // (an impact of endless steps is refused per size, as a single impact is)
  const std::vector<double> critical = criticalSteps(p);
  for (std::size_t i = 0; i < p.structures.size(); ++i) checkImpactCost(doc, p.c.run, p.structures[i], critical[i]);
}

std::optional<bridge::Estimate> estimateSweepCase(const JsonDocument& doc) {
  const Plan p = plan(doc);
  const std::vector<double> critical = criticalSteps(p);
  bridge::Estimate e;
  for (const Point& pt : p.points) {
    const auto i = static_cast<std::size_t>(pt.size);
    bridge::addRun(e, impactEstimate(p.c.run, p.structures[i], critical[i]));
  }
  e.output_bytes = 400.0 * static_cast<double>(p.points.size()) + 1e6;  // (a row per point, charts; no series)
  return e;
}

std::shared_ptr<const bridge::RowPlan> sweepRows(const JsonDocument& doc) {
  return std::make_shared<SweepPlan>(doc);
}

bridge::RunOutcome runSweepCase(const JsonDocument& doc, const bridge::RunContext& ctx) {
  // The rows an earlier run of this case finished are taken; the rest run,
  // each logged as it ends (bridge/rows.hpp).
  return bridge::runRows(SweepPlan(doc), doc, ctx);
}

namespace {

bridge::RunOutcome SweepPlan::assemble(const std::vector<std::optional<json>>& rows, const bridge::RowStats& stats,
                                       const bridge::RunContext& ctx) const {
  const Plan& p = p_;
  const std::size_t np = p.points.size();
  std::vector<ImpactResult> results(np);
  std::vector<char> missing(np, 0);
  for (std::size_t i = 0; i < np; ++i) {
    if (rows[i]) {
      results[i] = fromRow(*rows[i]);
    } else {
      results[i].ok = false;
      results[i].message = "missing: not run yet";
      missing[i] = 1;
    }
  }
  const double wall = stats.wall_time_s;
  const int nthreads = stats.workers;

  // Table: CSV and HDF5, one row per point in grid order.
  std::ostringstream csv;
  csv << std::setprecision(10);
  csv << "index,velocity_m_s,mass_kg,boulder_diameter_m,aim_y_m,aim_z_m,cells_x,cells_y,cells_z,impact_energy_J,status,"
         "outcome,peak_force_"
         "N,"
         "max_penetration_m,contact_duration_s,rebound_velocity_m_s,max_back_face_displacement_m,plastic_energy_J,"
         "friction_energy_J,balance_rel_error,message\n";
  std::vector<std::vector<double>> cols(19);
  std::size_t failed = 0;
  double worst_balance = 0.0;
  std::vector<double> ok_energy, ok_peak, ok_pen, ok_back, ok_mass;
  std::vector<Outcome> ok_outcome;
  std::map<std::string, int> outcomes;
  for (std::size_t i = 0; i < np; ++i) {
    const Point& pt = p.points[i];
    const ImpactResult& r = results[i];
    const auto& size = p.sizes[static_cast<std::size_t>(pt.size)];
    if (!r.ok && !missing[i]) ++failed;
    const double nan = std::nan("");
    auto val = [&](double v) { return r.ok ? v : nan; };
    BoulderSpec boulder = p.c.impacts.front();  // (its diameter at this mass)
    boulder.setMass(pt.mass_kg, p.sweep.keep_diameter);
    const double row[19] = {static_cast<double>(i),
                            pt.velocity_m_s,
                            pt.mass_kg,
                            boulder.diameter_m,
                            pt.aim_y_m,
                            pt.aim_z_m,
                            static_cast<double>(size[0]),
                            static_cast<double>(size[1]),
                            static_cast<double>(size[2]),
                            pt.energy_J,
                            r.ok ? 0.0 : (missing[i] ? 2.0 : 1.0),
                            val(r.peak_force_N),
                            val(r.max_penetration_m),
                            val(r.contact_duration_s),
                            val(r.rebound_velocity_m_s),
                            val(r.max_back_face_displacement_m),
                            val(r.plastic_J),
                            val(r.friction_J),
                            r.ok ? static_cast<double>(r.outcome) : nan};
    for (std::size_t c = 0; c < 19; ++c) cols[c].push_back(row[c]);
    csv << i << ',' << pt.velocity_m_s << ',' << pt.mass_kg << ',' << boulder.diameter_m << ',' << pt.aim_y_m << ','
        << pt.aim_z_m << ',' << size[0] << ',' << size[1] << ',' << size[2] << ',' << pt.energy_J << ','
        << (r.ok         ? "ok"
            : missing[i] ? "missing"
                         : "failed")
        << ',' << (r.ok ? outcomeName(r.outcome) : "");
    if (r.ok) {
      csv << ',' << r.peak_force_N << ',' << r.max_penetration_m << ',' << r.contact_duration_s << ','
          << r.rebound_velocity_m_s << ',' << r.max_back_face_displacement_m << ',' << r.plastic_J << ','
          << r.friction_J << ',' << r.balance_rel_error << ",\n";
      worst_balance = std::max(worst_balance, r.balance_rel_error);
      ok_energy.push_back(pt.energy_J);
      ok_peak.push_back(r.peak_force_N);
      ok_pen.push_back(r.max_penetration_m);
      ok_back.push_back(r.max_back_face_displacement_m);
      ok_mass.push_back(pt.mass_kg);
      ok_outcome.push_back(r.outcome);
      ++outcomes[outcomeName(r.outcome)];
    } else {
      csv << ",,,,,,,," << csvQuote(r.message) << "\n";
    }
  }
  bridge::writeTextAtomic(ctx.outdir / "sweep.csv", csv.str());
  {
    static const char* names[19] = {"index",
                                    "velocity_m_s",
                                    "mass_kg",
                                    "boulder_diameter_m",
                                    "aim_y_m",
                                    "aim_z_m",
                                    "cells_x",
                                    "cells_y",
                                    "cells_z",
                                    "impact_energy_J",
                                    "failed",
                                    "peak_force_N",
                                    "max_penetration_m",
                                    "contact_duration_s",
                                    "rebound_velocity_m_s",
                                    "max_back_face_displacement_m",
                                    "plastic_energy_J",
                                    "friction_energy_J",
                                    "outcome"};
    static const char* units[19] = {"", "m/s", "kg", "m", "m",   "m", "",  "",  "", "J",
                                    "", "N",   "m",  "s", "m/s", "m", "J", "J", ""};
    bridge::H5Writer h5(ctx.outdir / "result.h5");
    h5.attribute("/", "format", "gabion.macro.sweep/1");
    for (std::size_t c = 0; c < 19; ++c) h5.write(std::string("/table/") + names[c], cols[c], units[c]);
    h5.attribute("/table/outcome", "values", "0 stopped, 1 rebounded, 2 perforated, 3 unfinished");
    h5.attribute("/table/failed", "values",
                 "0 ok, 1 failed, 2 missing (not run yet: a collect before every task ended)");
    h5.commit();
  }
  json files = json::array({"sweep.csv", "result.h5"});
  if (stats.where != "collected") files.push_back("rows.jsonl");
  if (p.sweep.chart && !ok_energy.empty()) {
    // Three design charts against impact energy: one series per boulder
    // mass (up to 8 masses; beyond, one series), perforated points marked
    // over them (their penetration is where the boulder was when it went
    // through), and the sweep's limit where one is given.
    std::vector<double> masses;
    for (std::size_t i = 0; i < ok_mass.size(); ++i)
      if (std::find(masses.begin(), masses.end(), ok_mass[i]) == masses.end()) masses.push_back(ok_mass[i]);
    const bool by_mass = masses.size() <= 8;
    if (!by_mass) masses = {0.0};
    const double e_lo = *std::min_element(ok_energy.begin(), ok_energy.end()) / 1e3;
    const double e_hi = *std::max_element(ok_energy.begin(), ok_energy.end()) / 1e3;
    struct Chart {
      const char *file, *title, *y_label;
      const std::vector<double>* y;
      double scale, limit;
    };
    const Chart charts[3] = {{"chart_peak_force.png", "Peak contact force against impact energy", "peak force (kN)",
                              &ok_peak, 1e-3, p.sweep.limit_peak_force_N},
                             {"chart_penetration.png", "Boulder penetration against impact energy",
                              "max penetration (mm)", &ok_pen, 1e3, p.sweep.limit_penetration_m},
                             {"chart_back_face.png", "Back-face displacement against impact energy",
                              "max back-face displacement (mm)", &ok_back, 1e3, p.sweep.limit_back_face_m}};
    for (const Chart& ch : charts) {
      bridge::PlotSpec plot;
      plot.title = ch.title;
      plot.x_label = "impact energy (kJ)";
      plot.y_label = ch.y_label;
      for (double m : masses) {
        std::ostringstream label;
        label << "m = " << m << " kg";
        bridge::PlotSeries series{by_mass ? label.str() : "sweep points", {}, {}, bridge::PlotSeries::Style::Markers};
        for (std::size_t i = 0; i < ok_energy.size(); ++i)
          if (!by_mass || ok_mass[i] == m)
            series.x.push_back(ok_energy[i] / 1e3), series.y.push_back((*ch.y)[i] * ch.scale);
        plot.series.push_back(series);
      }
      bridge::PlotSeries perforated{"perforated", {}, {}, bridge::PlotSeries::Style::Markers};
      for (std::size_t i = 0; i < ok_energy.size(); ++i)
        if (ok_outcome[i] == Outcome::Perforated)
          perforated.x.push_back(ok_energy[i] / 1e3), perforated.y.push_back((*ch.y)[i] * ch.scale);
      if (!perforated.x.empty()) plot.series.push_back(perforated);
      if (std::isfinite(ch.limit))
        plot.series.push_back(
            {"limit", {e_lo, e_hi}, {ch.limit * ch.scale, ch.limit * ch.scale}, bridge::PlotSeries::Style::Line});
      bridge::writePlotPng(ctx.outdir / ch.file, plot);
      files.push_back(ch.file);
    }
  }

  bridge::RunOutcome out;
  out.results["points"] = np;
  out.results["points_reused"] = stats.reused;  // (found finished in this folder: rows.jsonl, rows/<i>/row.json)
  out.results["failed_points"] = failed;
  out.results["missing_points"] = stats.missing;
  out.results["outcomes"] = outcomes;
  out.results["balance_rel_error"] = worst_balance;
  out.results["sweep_wall_time_s"] = wall;
  out.results["points_per_second"] = wall > 0.0 ? static_cast<double>(stats.run) / wall : 0.0;
  out.results["threads_used"] = nthreads;
  out.results["files"] = files;
  {
    std::ostringstream answer;
    answer << "macro.sweep: " << np << " impacts:";
    for (const auto& [name, count] : outcomes) answer << " " << count << " " << name << ",";
    answer << " " << failed << " failed";
    if (stats.missing > 0) answer << ", " << stats.missing << " missing";
    answer << "; worst energy balance error " << bridge::showNumber(worst_balance, 2) << "\n";
    out.answer = answer.str();
    if (stats.where != "collected")
      out.report = "macro.sweep: " + bridge::showNumber(wall) + " s on " + std::to_string(nthreads) + " " +
                   (stats.where == "mpi" ? "MPI workers" : "threads") + "\n";
  }
  out.results["laws_source"] = p.c.law_source;
  // A sweep in which every point failed has produced nothing usable.
  if (np > 0 && failed == np && !bridge::interrupted()) {
    out.status = bridge::RunOutcome::Status::NumericalFailure;
    out.message = "all " + std::to_string(np) + " points failed; first: " + results.front().message;
  }
  return out;
}

}  // namespace

}  // namespace gabion::macro
