// The macro.impact case kind: read, build, run the impacts one after the
// other, write summary results, result.h5 and result.xdmf.
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "bridge/units.hpp"
#include "macro/case_reader.hpp"
#include "macro/runs.hpp"

namespace gabion::macro {

using bridge::InputError;
using bridge::JsonDocument;
using nlohmann::json;

namespace {

// Reads and builds everything a run needs; checks each boulder against the structure.
struct Prepared {
  ImpactCase c;
  Structure structure;
};

Prepared prepare(const JsonDocument& doc) {
  Prepared p{readImpactCase(doc, false), {}};
  p.structure = buildCaseStructure(doc, p.c);
  resolveAims(doc, p.c, p.structure);
  for (std::size_t i = 0; i < p.c.impacts.size(); ++i) {
    Model probe(p.structure, p.c.run.kinematics);
    try {
      probe.placeBoulder(p.c.impacts[i]);
    } catch (const std::invalid_argument& e) {
      throw InputError(doc.file(), doc.root().has("impacts") ? "/impacts/" + std::to_string(i) : "/boulder", e.what());
    }
    checkImpactCost(doc, p.c.run, p.structure, probe.criticalTimeStep());
  }
  return p;
}

void writeResults(const std::filesystem::path& outdir, const Structure& s, const Recording& rec,
                  const std::vector<ImpactResult>& results) {
  bridge::H5Writer h5(outdir / "result.h5");
  h5.attribute("/", "format", "gabion.macro.result/1");
  h5.write("/series/time_s", rec.time_s, "s");
  h5.write("/series/impact", rec.impact);
  h5.write("/series/boulder_force_N", rec.force_N, "N");
  h5.write("/series/boulder_force_x_N", rec.force_x_N, "N");
  h5.write("/series/boulder_velocity_x_m_s", rec.velocity_x_m_s, "m/s");
  h5.write("/series/boulder_speed_m_s", rec.speed_m_s, "m/s");
  h5.write("/series/penetration_m", rec.penetration_m, "m");
  h5.write("/series/indentation_m", rec.indentation_m, "m");
  h5.write("/series/contacts", rec.contacts);
  h5.write("/series/energy_kinetic_J", rec.kinetic_J, "J");
  h5.write("/series/energy_elastic_J", rec.elastic_J, "J");
  h5.write("/series/energy_plastic_J", rec.plastic_J, "J");
  h5.write("/series/energy_friction_J", rec.friction_J, "J");
  h5.write("/series/back_face_displacement_m", rec.back_displacement_m, "m");

  const std::size_t n = s.nodeCount(), nt = rec.snap_time_s.size();
  std::vector<double> pos(rec.snap_displacement_m.size());
  for (std::size_t t = 0; t < nt; ++t)
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t o = (t * n + i) * 3;
      pos[o] = s.x0[i] + rec.snap_displacement_m[o];
      pos[o + 1] = s.y0[i] + rec.snap_displacement_m[o + 1];
      pos[o + 2] = s.z0[i] + rec.snap_displacement_m[o + 2];
    }
  h5.write("/snapshots/time_s", rec.snap_time_s, "s");
  h5.write("/snapshots/displacement_m", rec.snap_displacement_m, {nt, n, 3}, "m");
  h5.write("/snapshots/position_m", pos, {nt, n, 3}, "m");
  h5.write("/snapshots/axial_force_N", rec.snap_axial_force_N, {nt, n}, "N");

  std::vector<double> p0(3 * n), mat(n);
  std::vector<long long> grid(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    p0[3 * i] = s.x0[i];
    p0[3 * i + 1] = s.y0[i];
    p0[3 * i + 2] = s.z0[i];
    mat[i] = s.material[i];
    grid[3 * i] = s.gi[i];
    grid[3 * i + 1] = s.gj[i];
    grid[3 * i + 2] = s.gk[i];
  }
  h5.write("/nodes/initial_position_m", p0, {n, 3}, "m");
  h5.write("/nodes/material", mat);
  h5.writeInts("/nodes/grid_index", grid, {n, 3});
  std::vector<double> peak, pen, dur;
  for (const auto& r : results) {
    peak.push_back(r.peak_force_N);
    pen.push_back(r.max_penetration_m);
    dur.push_back(r.contact_duration_s);
  }
  h5.write("/impacts/peak_force_N", peak, "N");
  h5.write("/impacts/max_penetration_m", pen, "m");
  h5.write("/impacts/contact_duration_s", dur, "s");
  h5.commit();
  if (nt > 0)
    bridge::writeXdmfPoints(outdir / "result.xdmf", "result.h5", rec.snap_time_s, n, "/snapshots/position_m",
                            {{"displacement_m", "/snapshots/displacement_m", 3, true},
                             {"axial_force_N", "/snapshots/axial_force_N", 1, true},
                             {"material", "/nodes/material", 1, false}});
}

// A relaxation that ran out of steps: the residual displacements are a
// moving structure's (a cell thrown out of the wall by the rebound drifts
// with no force to stop it: the cells carry no tension). (A perforated
// structure is not relaxed at all: its outcome says why.)
bool relaxCutShort(const ImpactResult& r) {
  return r.ok && r.relaxed && !r.relax_converged && r.outcome != Outcome::Perforated;
}

std::string relaxWarning(const ImpactResult& r) {
  return "the structure was not at rest after " + std::to_string(r.relax_steps) +
         " steps of relaxation (run.relax_max_steps): its residual displacements are those of a structure still "
         "moving";
}

}  // namespace

json toJson(const ImpactResult& r) {
  json j;
  j["status"] = r.ok ? "ok" : "failed";
  if (!r.message.empty()) j["message"] = r.message;
  if (r.ok) j["outcome"] = outcomeName(r.outcome);
  if (r.ok && !r.perforation.empty()) j["perforation"] = r.perforation;
  j["end_time_s"] = r.end_time_s;
  j["input_energy_J"] = r.input_energy_J;
  j["peak_force_N"] = r.peak_force_N;
  j["time_of_peak_s"] = r.time_of_peak_s;
  j["max_penetration_m"] = r.max_penetration_m;
  j["final_penetration_m"] = r.final_penetration_m;
  j["max_indentation_m"] = r.max_indentation_m;
  j["contact_duration_s"] = r.contact_duration_s;
  j["contact_episodes"] = r.contact_episodes;
  j["last_separation_s"] = r.last_separation_s;
  j["contact_at_end"] = r.contact_at_end;
  j["rebound_velocity_m_s"] = r.rebound_velocity_m_s;
  j["max_back_face_displacement_m"] = r.max_back_face_displacement_m;
  j["max_front_face_displacement_m"] = r.max_front_face_displacement_m;
  if (r.relaxed) {
    j["residual_back_face_displacement_m"] = r.residual_back_face_displacement_m;
    j["residual_front_face_displacement_m"] = r.residual_front_face_displacement_m;
    j["front_cells_pushed_in"] = r.front_cells_pushed_in;
    j["relax_steps"] = r.relax_steps;
    j["relax_converged"] = r.relax_converged;
  }
  j["loaded_cells"] = r.loaded_cells;
  j["kinetic_energy_J"] = r.kinetic_J;
  j["elastic_energy_J"] = r.elastic_J;
  j["plastic_energy_J"] = r.plastic_J;
  j["friction_energy_J"] = r.friction_J;
  j["potential_energy_J"] = r.potential_J;
  j["final_spin_rad_s"] = r.final_spin_rad_s;
  j["balance_rel_error"] = r.balance_rel_error;
  j["time_step_s"] = r.time_step_s;
  j["critical_time_step_s"] = r.critical_time_step_s;
  j["steps"] = r.steps;
  return j;
}

std::optional<bridge::Estimate> estimateImpactCase(const JsonDocument& doc) {
  const Prepared p = prepare(doc);
  bridge::Estimate e;
  for (const BoulderSpec& b : p.c.impacts) {
    Model probe(p.structure, p.c.run.kinematics);
    probe.placeBoulder(b);
    bridge::addRun(e, impactEstimate(p.c.run, p.structure, probe.criticalTimeStep()));
  }
  return e;
}

void checkImpactCase(const JsonDocument& doc) {
  prepare(doc);
}

bridge::RunOutcome runImpactCase(const JsonDocument& doc, const bridge::RunContext& ctx) {
  Prepared p = prepare(doc);
  const Structure& s = p.structure;
  Model model(s, p.c.run.kinematics);
  Recording rec;
  std::vector<ImpactResult> results;
  bridge::RunOutcome out;
  bridge::Progress progress(ctx, "macro.impact");
  for (std::size_t i = 0; i < p.c.impacts.size(); ++i) {
    if (i > 0) rec.time_offset_s += results.back().end_time_s;  // (each impact's series after the last one's)
    results.push_back(runImpact(model, p.c.impacts[i], p.c.run, static_cast<int>(i), &rec));
    progress.update(static_cast<double>(i + 1), static_cast<double>(p.c.impacts.size()), model.steps());
    if (!results.back().ok) {
      out.status = bridge::RunOutcome::Status::NumericalFailure;
      out.message = "impact " + std::to_string(i) + ": " + results.back().message;
      break;
    }
  }
  progress.finish();
  writeResults(ctx.outdir, s, rec, results);

  json& r = out.results;
  const ImpactResult& last = results.back();
  const json last_json = toJson(last);
  for (auto it = last_json.begin(); it != last_json.end(); ++it)
    if (it.key() != "status" && it.key() != "message") r[it.key()] = it.value();
  json list = json::array(), peaks = json::array(), pens = json::array();
  for (const auto& x : results) {
    list.push_back(toJson(x));
    peaks.push_back(x.peak_force_N);
    pens.push_back(x.max_penetration_m);
  }
  r["impacts"] = list;
  r["per_impact_peak_force_N"] = peaks;
  r["per_impact_max_penetration_m"] = pens;
  double worst = 0.0;
  for (const auto& x : results) worst = std::max(worst, x.balance_rel_error);
  r["balance_rel_error"] = worst;
  json warnings = json::array();
  for (std::size_t i = 0; i < results.size(); ++i)
    if (relaxCutShort(results[i])) warnings.push_back("impact " + std::to_string(i) + ": " + relaxWarning(results[i]));
  if (!warnings.empty()) r["warnings"] = warnings;
  r["kinematics"] = p.c.run.kinematics == Kinematics::ThreeD ? "3d" : "x-only";
  r["structure"] = {
      {"cells", {s.nx, s.ny, s.nz}},          {"nodes", s.nodeCount()},          {"edge_m", s.edge_m},
      {"materials", s.material_names},        {"axial_links", s.axial.a.size()}, {"lateral_links", s.lateral.a.size()},
      {"front_elements", s.front.node.size()}};
  r["laws"] = {{"source", p.c.law_source}, {"file", bridge::toJson(p.c.laws)}};
  std::ostringstream answer;
  using bridge::showNumber;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const ImpactResult& x = results[i];
    if (!x.ok) continue;
    answer << "macro.impact" << (results.size() > 1 ? " " + std::to_string(i) : "") << ": " << outcomeName(x.outcome)
           << " (" << showNumber(x.input_energy_J / 1e3) << " kJ): peak force " << showNumber(x.peak_force_N / 1e3)
           << " kN, penetration " << showNumber(1e3 * x.max_penetration_m) << " mm, back face "
           << showNumber(1e3 * x.max_back_face_displacement_m) << " mm, contact "
           << showNumber(1e3 * x.contact_duration_s) << " ms; energy balance error "
           << showNumber(x.balance_rel_error, 2) << "\n";
    if (!x.perforation.empty()) answer << "  " << x.perforation << "\n";
    if (relaxCutShort(x)) answer << "  warning: " << relaxWarning(x) << "\n";
  }
  out.answer = answer.str();
  return out;
}

}  // namespace gabion::macro
