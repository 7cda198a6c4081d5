// The macro.capacity case kind: the largest impact energy a structure takes
// with every acceptance criterion met (the boulder held, the back face and
// the penetration within their limits), found by bisection over the
// boulder's velocity or mass (docs/macro.md, Capacity).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "bridge/units.hpp"
#include "macro/case_reader.hpp"
#include "macro/criteria.hpp"
#include "macro/runs.hpp"

namespace gabion::macro {

using bridge::Check;
using bridge::JsonDocument;
using bridge::JsonReader;
using nlohmann::json;

namespace {

struct CapacitySpec {
  bool over_mass = false;  // else over velocity
  double lo = 0.0, hi = 0.0;
  Criteria criteria;
  double tolerance = 0.01;  // on the energy bracket, relative
  int max_evaluations = 60;
  bool keep_diameter = false;
};

struct Plan {
  ImpactCase c;
  CapacitySpec spec;
  Structure structure;
};

Plan plan(const JsonDocument& doc) {
  Plan p;
  p.c = readImpactCase(doc, true);
  const JsonReader r = doc.root().object("capacity");
  CapacitySpec& s = p.spec;
  const std::string over = r.choice("over", {"velocity_m_s", "mass_kg"}, "velocity_m_s");
  s.over_mass = over == "mass_kg";
  const std::vector<double> range = r.numbers("range", Check::Positive, 2);
  if (range.size() != 2) r.fail("range", "expected [lowest, highest] of " + over);
  if (!(range[0] < range[1])) r.fail("range", "the lowest must be below the highest");
  s.lo = range[0], s.hi = range[1];
  if (const auto c = r.optionalObject("criteria")) {
    s.criteria.max_back_face_m = c->number("max_back_face_displacement_m", s.criteria.max_back_face_m, Check::Positive);
    s.criteria.max_penetration_m = c->number("max_penetration_m", s.criteria.max_penetration_m, Check::Positive);
  }
  s.tolerance = r.number("tolerance", s.tolerance, Check::Positive);
  if (s.tolerance >= 0.5) r.fail("tolerance", "must be < 0.5 (the bracket's width over its energy)");
  s.max_evaluations = static_cast<int>(r.integer("max_evaluations", s.max_evaluations, 3));
  s.keep_diameter = r.boolean("keep_diameter", false);
  try {
    p.structure = buildStructure(p.c.structure, p.c.laws);
  } catch (const std::invalid_argument& e) {
    throw bridge::InputError(doc.file(), "/structure", e.what());
  }
  resolveAims(doc, p.c, p.structure);
  {
    Model probe(p.structure, p.c.run.kinematics);
    probe.placeBoulder(p.c.impacts.front());
    checkImpactCost(doc, p.c.run, p.structure, probe.criticalTimeStep());
  }
  return p;
}

// One impact at x (a velocity or a mass) and what it says of the criteria.
CapacityEvaluation evaluate(const Plan& p, double x) {
  CapacityEvaluation ev;
  ev.x = x;
  BoulderSpec b = p.c.impacts.front();
  if (p.spec.over_mass)
    b.setMass(x, p.spec.keep_diameter);
  else
    b.velocity_m_s = b.velocity_m_s.normalized() * x;
  ev.energy_J = 0.5 * b.mass_kg * b.velocity_m_s.squaredNorm();
  Model model(p.structure, p.c.run.kinematics);
  ev.result = runImpact(model, b, p.c.run, 0, nullptr);
  if (!ev.result.ok)
    throw bridge::NumericalError(0, 0.0, "the impact at " + std::to_string(x) + " failed: " + ev.result.message);
  ev.verdict = judge(ev.result, p.spec.criteria);
  return ev;
}

json toJson(const CapacityEvaluation& e, const CapacitySpec& s) {
  json j = {{s.over_mass ? "mass_kg" : "velocity_m_s", e.x}, {"energy_J", e.energy_J}, {"met", e.verdict.met}};
  if (!e.result.ok) {
    j["status"] = "failed", j["message"] = e.result.message;
    return j;
  }
  j["outcome"] = outcomeName(e.result.outcome);
  j["max_penetration_m"] = e.result.max_penetration_m;
  j["max_back_face_displacement_m"] = e.result.max_back_face_displacement_m;
  j["peak_force_N"] = e.result.peak_force_N;
  if (!e.verdict.failed.empty()) j["failed"] = e.verdict.failed;
  return j;
}

}  // namespace

std::optional<bridge::Estimate> estimateCapacityCase(const JsonDocument& doc) {
  const Plan p = plan(doc);
  Model probe(p.structure, p.c.run.kinematics);
  probe.placeBoulder(p.c.impacts.front());
  bridge::Estimate e =
      bridge::times(impactEstimate(p.c.run, p.structure, probe.criticalTimeStep()), p.spec.max_evaluations);
  e.output_bytes = 1e4 * p.spec.max_evaluations;  // (a table of the evaluations; no series)
  return e;
}

void checkCapacityCase(const JsonDocument& doc) {
  plan(doc);
}

bridge::RunOutcome runCapacityCase(const JsonDocument& doc, const bridge::RunContext& ctx) {
  const Plan p = plan(doc);
  const CapacitySpec& s = p.spec;
  bridge::RunOutcome out;
  const CapacitySearch search =
      searchCapacity([&](double x) { return evaluate(p, x); }, s.lo, s.hi, s.over_mass, s.tolerance, s.max_evaluations);
  const std::vector<CapacityEvaluation>& evals = search.evaluations;
  json& r = out.results;
  const char* key = s.over_mass ? "mass_kg" : "velocity_m_s";
  std::ostringstream answer;
  answer.precision(4);
  if (search.kind == CapacitySearch::Kind::NoneMet) {
    const CapacityEvaluation& lo = evals[search.bad];
    r["capacity_energy_J"] = nullptr;
    r["governing_criterion"] = lo.verdict.failed;
    answer << "no impact in the range meets the criteria: at the lowest, " << s.lo << " (" << lo.energy_J / 1e3
           << " kJ), " << criterionText(lo.verdict.failed) << " already fails";
  } else if (search.kind == CapacitySearch::Kind::AllMet) {
    const CapacityEvaluation& hi = evals[search.good];
    r["capacity_energy_J"] = hi.energy_J;
    r[key] = s.hi;
    r["governing_criterion"] = nullptr;
    r["capacity_is_at_least"] = true;
    answer << "every criterion is met up to the highest of the range, " << s.hi << " (" << hi.energy_J / 1e3
           << " kJ): the capacity is at least that";
  } else {
    const CapacityEvaluation &good = evals[search.good], &bad = evals[search.bad];
    r["capacity_energy_J"] = good.energy_J;
    r[key] = good.x;
    r["bracket_energy_J"] = {good.energy_J, bad.energy_J};
    r["governing_criterion"] = bad.verdict.failed;
    r["converged"] = search.converged;
    const ImpactResult& g = good.result;
    json margin = json::object();
    if (std::isfinite(s.criteria.max_back_face_m))
      margin["back_face"] = 1.0 - g.max_back_face_displacement_m / s.criteria.max_back_face_m;
    if (std::isfinite(s.criteria.max_penetration_m))
      margin["penetration"] = 1.0 - g.max_penetration_m / s.criteria.max_penetration_m;
    r["margins_at_capacity"] = margin;
    const bridge::DisplayUnit u = bridge::displayUnit(key);  // (the boulder's velocity or mass at the capacity)
    answer << "capacity " << good.energy_J / 1e3 << " kJ (" << u.stem << " " << u.scale * good.x << " " << u.unit
           << "; " << outcomeName(g.outcome) << ", penetration " << 1e3 * g.max_penetration_m << " mm, back face "
           << 1e3 * g.max_back_face_displacement_m << " mm); above it " << criterionText(bad.verdict.failed)
           << " governs (at " << bad.energy_J / 1e3 << " kJ)";
  }
  r["answer"] = answer.str();
  r["criteria"] = {{"held", true},
                   {"max_back_face_displacement_m",
                    std::isfinite(s.criteria.max_back_face_m) ? json(s.criteria.max_back_face_m) : json(nullptr)},
                   {"max_penetration_m",
                    std::isfinite(s.criteria.max_penetration_m) ? json(s.criteria.max_penetration_m) : json(nullptr)}};
  json list = json::array();
  for (const CapacityEvaluation& e : evals) list.push_back(toJson(e, s));
  r["evaluations"] = list;
  r["tolerance"] = s.tolerance;
  double worst = 0.0;  // (the energy balance of every impact run)
  for (const CapacityEvaluation& e : evals) worst = std::max(worst, e.result.balance_rel_error);
  r["balance_rel_error"] = worst;

  // The evaluations against energy, with the limits.
  std::vector<CapacityEvaluation> sorted = evals;
  std::sort(sorted.begin(), sorted.end(),
            [](const CapacityEvaluation& x, const CapacityEvaluation& y) { return x.energy_J < y.energy_J; });
  bridge::PlotSpec plot;
  plot.title = "Capacity: the impacts the search ran";
  plot.x_label = "impact energy (kJ)";
  plot.y_label = "displacement (mm)";
  bridge::PlotSeries pen{"max penetration", {}, {}, bridge::PlotSeries::Style::LineMarkers};
  bridge::PlotSeries back{"max back-face displacement", {}, {}, bridge::PlotSeries::Style::LineMarkers};
  for (const CapacityEvaluation& e : sorted) {
    pen.x.push_back(e.energy_J / 1e3), pen.y.push_back(1e3 * e.result.max_penetration_m);
    back.x.push_back(e.energy_J / 1e3), back.y.push_back(1e3 * e.result.max_back_face_displacement_m);
  }
  plot.series = {pen, back};
  const double e0 = sorted.front().energy_J / 1e3, e1 = sorted.back().energy_J / 1e3;
  if (std::isfinite(s.criteria.max_penetration_m))
    plot.series.push_back({"penetration limit",
                           {e0, e1},
                           {1e3 * s.criteria.max_penetration_m, 1e3 * s.criteria.max_penetration_m},
                           bridge::PlotSeries::Style::Line});
  if (std::isfinite(s.criteria.max_back_face_m))
    plot.series.push_back({"back-face limit",
                           {e0, e1},
                           {1e3 * s.criteria.max_back_face_m, 1e3 * s.criteria.max_back_face_m},
                           bridge::PlotSeries::Style::Line});
  bridge::PlotSeries held{"not held (perforated or unfinished)", {}, {}, bridge::PlotSeries::Style::Markers};
  for (const CapacityEvaluation& e : sorted)
    if (e.verdict.failed == "held")
      held.x.push_back(e.energy_J / 1e3), held.y.push_back(1e3 * e.result.max_penetration_m);
  if (!held.x.empty()) plot.series.push_back(held);
  bridge::writePlotPng(ctx.outdir / "capacity.png", plot);
  out.answer = "macro.capacity: " + answer.str() + " (" + std::to_string(evals.size()) + " impacts)\n";
  return out;
}

}  // namespace gabion::macro
