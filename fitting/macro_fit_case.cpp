#include "fitting/macro_fit_case.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "bridge/cost.hpp"
#include "bridge/errors.hpp"
#include "bridge/law_file.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"
#include "bridge/units.hpp"
#include "fitting/case_input.hpp"
#include "fitting/sha256.hpp"
#include "fitting/uncertainty.hpp"
#include "gabion_version.hpp"
#include "macro/case_reader.hpp"

namespace gabion::fitting {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::JsonReader;
using nlohmann::json;

namespace {

/// The macro run's series a curve can be compared with (macro/impact.hpp,
/// Recording; docs/fitting.md).
const std::vector<std::string> kQuantities = {"boulder_force_N", "penetration_m", "indentation_m",
                                              "back_face_displacement_m"};

const std::vector<double>& quantityOf(const macro::Recording& r, const std::string& q) {
  if (q == "penetration_m") return r.penetration_m;
  if (q == "indentation_m") return r.indentation_m;
  if (q == "back_face_displacement_m") return r.back_displacement_m;
  return r.force_N;
}

/// A measured history of one scenario and the series it is compared with.
struct History {
  std::string quantity;  ///< one of kQuantities
  CurveSource source;    ///< x: time (s), y: the quantity
  double t0_s = NAN;     ///< lab time of first contact; NaN: where the curve first leaves zero
  std::string pointer;
};

/// One impact: the macro case with `set` applied, and its histories.
struct Scenario {
  std::string name;
  std::vector<std::pair<std::string, json>> set;  ///< key path, value
  std::vector<History> curves;
  std::string pointer;
};

struct MacroFitCase {
  fs::path macro_case;
  std::vector<CaseParameter> params;
  std::vector<Scenario> scenarios;
  OptimizerSettings optimizer;
  LossSettings loss;
  std::size_t grid_points = 200;
  bool plots = true;
  bool profile = false;  ///< profile-likelihood intervals ("uncertainty": {"profile": true})
};

// The macro case with its laws embedded (a law file's materials under
// "laws"), so that every parameter is a key of the case.
bridge::JsonDocument baseDocument(const fs::path& path) {
  const bridge::JsonDocument doc = bridge::JsonDocument::load(path);
  json j = doc.json();
  if (!j.is_object() || j.value("kind", "") != "macro.impact")
    throw bridge::InputError(path.string(), "/kind", "fit.macro runs a macro.impact case");
  if (j.contains("law_file") && !j.contains("laws") && j["law_file"].is_string()) {
    const fs::path file = path.parent_path() / j["law_file"].get<std::string>();
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
      throw bridge::InputError(path.string(), "/law_file", "no such law file " + file.string());
    j["laws"] = {{"materials", bridge::toJson(bridge::loadLawFile(file))["materials"]}};
    j.erase("law_file");
  }
  // The impact is judged on its histories: the structure is not brought to
  // rest after it.
  if (!j.contains("run")) j["run"] = json::object();
  if (j["run"].is_object()) j["run"]["relax"] = false;
  return bridge::JsonDocument(j, doc.file());
}

MacroFitCase readMacroFitCase(const bridge::JsonDocument& doc) {
  const JsonReader root = doc.root();
  const fs::path dir = caseDirectory(doc);
  MacroFitCase c;
  c.macro_case = dir / root.string("macro_case");
  std::error_code ec;
  if (!fs::is_regular_file(c.macro_case, ec)) root.fail("macro_case", "no such case file " + c.macro_case.string());
  c.params = readCaseParameters(root, "laws.materials.front.impact.yield_force_N", false);
  const auto scenarios = root.objects("scenarios", true);
  if (scenarios.empty()) root.fail("scenarios", "at least one scenario is required");
  for (std::size_t i = 0; i < scenarios.size(); ++i) {
    const JsonReader& s = scenarios[i];
    Scenario sc;
    sc.pointer = s.pointer();
    sc.name = s.string("name", "scenario " + std::to_string(i + 1));
    if (s.has("set")) {
      const json& set = s.raw("set");
      if (!set.is_object()) s.fail("set", "must be an object {\"key.path\": value}");
      for (const auto& [k, v] : set.items()) sc.set.emplace_back(k, v);
    }
    const auto curves = s.objects("curves", true);
    if (curves.empty()) s.fail("curves", "at least one curve is required");
    for (std::size_t k = 0; k < curves.size(); ++k) {
      History h;
      h.pointer = curves[k].pointer();
      h.quantity = curves[k].choice("quantity", kQuantities);
      h.source = readCurveSource(curves[k], {"time_s", h.quantity, "/curves/impact", "", true}, k, dir);
      if (h.source.kind == CurveSource::Kind::H5Wall) curves[k].fail("wall", "a history is given by its datasets");
      h.t0_s = curves[k].optionalNumber("t0_s", Check::Finite).value_or(NAN);
      sc.curves.push_back(std::move(h));
    }
    c.scenarios.push_back(std::move(sc));
  }
  c.optimizer = readOptimizer(root.optionalObject("optimizer"), static_cast<unsigned long>(root.seed("seed", 1)),
                              OptimizerSettings{});
  c.loss = readLoss(root.optionalObject("objective"), c.grid_points);
  c.plots = root.boolean("plots", true);
  if (auto u = root.optionalObject("uncertainty")) c.profile = u->boolean("profile", false);
  return c;
}

// The case of one scenario at the parameter values `values`.
bridge::JsonDocument scenarioDocument(const bridge::JsonDocument& base, const MacroFitCase& c, const Scenario& s,
                                      const std::vector<double>& values) {
  bridge::JsonDocument doc(base.json(), base.file());
  for (const auto& [path, value] : s.set) doc.applySet(path + "=" + value.dump());
  return withParameters(doc, c.params, values);
}

struct MacroRun {
  macro::ImpactCase c;
  macro::ImpactResult result;
  macro::Recording rec;
  double contact_s = 0.0;  ///< time of the first contact in rec.time_s
};

// Reads, builds and runs the scenario's impact (the first of the case).
MacroRun runScenario(const bridge::JsonDocument& doc) {
  MacroRun r;
  r.c = macro::readImpactCase(doc, false);
  const macro::Structure s = macro::buildCaseStructure(doc, r.c);
  macro::resolveAims(doc, r.c, s);
  macro::Model model(s, r.c.run.kinematics);
  r.result = macro::runImpact(model, r.c.impacts.front(), r.c.run, 0, &r.rec);
  if (!r.result.ok) throw std::runtime_error("the macro run failed: " + r.result.message);
  const auto first = std::find_if(r.rec.force_N.begin(), r.rec.force_N.end(), [](double f) { return f > 0.0; });
  if (first == r.rec.force_N.end()) throw std::runtime_error("the boulder never touched the structure");
  r.contact_s = r.rec.time_s[static_cast<std::size_t>(first - r.rec.force_N.begin())];
  return r;
}

// The lab curve's time of first contact: given, or where it first leaves zero.
double labContact(const History& h, const PathGrid& g) {
  if (std::isfinite(h.t0_s)) return h.t0_s;
  for (std::size_t i = 0; i < g.raw_x.size(); ++i)
    if (std::abs(g.raw_y[i]) > 1e-6 * g.scale) return g.raw_x[i];
  return g.raw_x.front();
}

// The model's quantity at times `t` from first contact (linear; held at its
// first and last values outside the run).
std::vector<double> modelAt(const MacroRun& r, const std::string& quantity, const std::vector<double>& t) {
  const auto& y = quantityOf(r.rec, quantity);
  std::vector<double> out;
  out.reserve(t.size());
  for (double ti : t) {
    const double at = ti + r.contact_s;
    const auto it = std::lower_bound(r.rec.time_s.begin(), r.rec.time_s.end(), at);
    if (it == r.rec.time_s.begin()) {
      out.push_back(y.front());
    } else if (it == r.rec.time_s.end()) {
      out.push_back(y.back());
    } else {
      const auto j = static_cast<std::size_t>(it - r.rec.time_s.begin());
      const double w = (at - r.rec.time_s[j - 1]) / (r.rec.time_s[j] - r.rec.time_s[j - 1]);
      out.push_back(y[j - 1] + w * (y[j] - y[j - 1]));
    }
  }
  return out;
}

/// The lab histories, resampled, with their times from first contact.
struct LabHistory {
  PathGrid grid;
  std::vector<double> t;  ///< grid.x less the contact time
};

std::vector<std::vector<LabHistory>> labHistories(const MacroFitCase& c) {
  std::vector<std::vector<LabHistory>> out;
  for (const auto& s : c.scenarios) {
    std::vector<LabHistory> hs;
    for (const auto& h : s.curves) hs.push_back({resampleOnPath(loadCurve(h.source), c.grid_points), {}});
    // The scenario's first contact: where its force history leaves zero, for
    // every history of it that does not give its own t0_s (a back face moves
    // later than the contact); without a force history, each its own.
    double contact = NAN;
    for (std::size_t k = 0; k < s.curves.size() && std::isnan(contact); ++k)
      if (s.curves[k].quantity == "boulder_force_N") contact = labContact(s.curves[k], hs[k].grid);
    for (std::size_t k = 0; k < s.curves.size(); ++k) {
      const History& h = s.curves[k];
      const double t0 = std::isfinite(h.t0_s) ? h.t0_s : std::isfinite(contact) ? contact : labContact(h, hs[k].grid);
      for (double x : hs[k].grid.x) hs[k].t.push_back(x - t0);
    }
    out.push_back(std::move(hs));
  }
  return out;
}

struct Objective {
  const bridge::JsonDocument* base;
  const MacroFitCase* c;
  const std::vector<std::vector<LabHistory>>* lab;

  // Normalised residuals (model - data) / scale of every history point.
  std::vector<double> residuals(const std::vector<double>& values) const {
    std::vector<double> r;
    for (std::size_t i = 0; i < c->scenarios.size(); ++i) {
      MacroRun run;
      try {
        run = runScenario(scenarioDocument(*base, *c, c->scenarios[i], values));
      } catch (const bridge::InputError& e) {
        throw Infeasible(e.what());  // (a law the values make invalid: outside the model's domain)
      }
      for (std::size_t k = 0; k < c->scenarios[i].curves.size(); ++k) {
        const LabHistory& h = (*lab)[i][k];
        const auto y = modelAt(run, c->scenarios[i].curves[k].quantity, h.t);
        for (std::size_t j = 0; j < y.size(); ++j) r.push_back((y[j] - h.grid.y[j]) / h.grid.scale);
      }
    }
    return r;
  }

  // Each residual row's effective-point factor a_c (as the law fits weight a
  // curve): the histories' alone, in the order of residuals().
  std::vector<double> rowFactors() const {
    std::vector<double> a;
    for (const auto& s : *lab)
      for (const auto& h : s)
        a.insert(a.end(), h.grid.x.size(), h.grid.effectivePoints() / static_cast<double>(h.grid.x.size()));
    return a;
  }

  double effectiveObservations() const {
    double n = 0.0;
    for (const auto& s : *lab)
      for (const auto& h : s) n += h.grid.effectivePoints();
    return n;
  }

  // Robust misfit of every history, per effective observation.
  double operator()(const std::vector<double>& values) const {
    const auto r = residuals(values);
    const auto a = rowFactors();
    double total = 0.0;
    for (std::size_t j = 0; j < r.size(); ++j) total += a[j] * lossValue(r[j], c->loss);
    return total / effectiveObservations();
  }
};

std::vector<double> midpoint(const MacroFitCase& c) {
  return midpoint(c.params);
}

// An InputError of the case with the parameters (and a scenario's keys)
// substituted, moved to the fit case's key it comes from.
[[noreturn]] void rethrowAsCaseError(const bridge::JsonDocument& doc, const MacroFitCase& c, std::size_t scenario,
                                     const bridge::InputError& e) {
  std::string at = "/macro_case";
  for (std::size_t k = 0; k < c.params.size(); ++k)
    for (const std::string& set : c.params[k].set)
      if (setPathMatches(set, e.pointer())) at = "/parameters/" + std::to_string(k) + "/set";
  for (const auto& [key, value] : c.scenarios[scenario].set)
    if (setPathMatches(key, e.pointer()))
      at = c.scenarios[scenario].pointer + "/set/" + bridge::escapePointerToken(key);
  throw bridge::InputError(doc.file(), at,
                           "the macro case of " + c.scenarios[scenario].name +
                               " with the parameters at the middle of their bounds is not valid: " + e.what());
}

// Each scenario's case, with the parameters at the middle of their bounds,
// read and built as the run will: the case's errors before anything runs.
void checkScenarios(const bridge::JsonDocument& doc, const MacroFitCase& c, const bridge::JsonDocument& base) {
  for (std::size_t i = 0; i < c.scenarios.size(); ++i) {
    try {
      const bridge::JsonDocument trial = scenarioDocument(base, c, c.scenarios[i], midpoint(c));
      macro::ImpactCase ic = macro::readImpactCase(trial, false);
      const macro::Structure s = macro::buildCaseStructure(trial, ic);
      macro::resolveAims(trial, ic, s);
      if (ic.impacts.size() != 1)
        throw bridge::InputError(trial.file(), "/impacts", "fit.macro runs one impact per scenario");
      // Every key of the case must be one macro.impact reads (a parameter's
      // key misspelt is an error, not a key silently added).
      for (const char* k : {"format", "kind", "description"})
        if (trial.root().has(k)) trial.root().string(k);
      trial.finish();
    } catch (const bridge::InputError& e) {
      rethrowAsCaseError(doc, c, i, e);
    }
  }
}

void checkCase(const bridge::JsonDocument& doc) {
  const MacroFitCase c = readMacroFitCase(doc);
  labHistories(c);
  checkScenarios(doc, c, baseDocument(c.macro_case));
}

// The evaluations the search may take (both stages' limits) times the
// scenarios' impacts, each as the macro case estimates it.
std::optional<bridge::Estimate> estimateCase(const bridge::JsonDocument& doc) {
  const MacroFitCase c = readMacroFitCase(doc);
  const bridge::JsonDocument base = baseDocument(c.macro_case);
  bridge::Estimate all;
  for (const auto& sc : c.scenarios) {
    const bridge::JsonDocument d = scenarioDocument(base, c, sc, midpoint(c));
    macro::ImpactCase ic = macro::readImpactCase(d, false);
    const macro::Structure s = macro::buildCaseStructure(d, ic);
    macro::resolveAims(d, ic, s);
    macro::Model probe(s, ic.run.kinematics);
    probe.placeBoulder(ic.impacts.front());
    const bridge::Estimate one = macro::impactEstimate(ic.run, s, probe.criticalTimeStep());
    bridge::addRun(all, one);
  }
  const double evaluations = static_cast<double>(c.optimizer.global_max_evaluations) +
                             static_cast<double>(c.optimizer.local_max_evaluations) + 1.0;
  bridge::Estimate e = bridge::times(all, evaluations);
  // The runs stay in memory: the files are the law, the summary and a chart
  // per history (about 100 kB each).
  std::size_t histories = 0;
  for (const auto& sc : c.scenarios) histories += sc.curves.size();
  e.snapshots = 0.0;
  e.output_bytes = 2e4 + 1e5 * static_cast<double>(histories);
  return e;
}

void plotHistory(const fs::path& file, const std::string& title, const std::string& quantity, const LabHistory& lab,
                 const MacroRun& run) {
  bridge::PlotSpec spec;
  spec.title = title;
  const bridge::DisplayUnit u = bridge::displayUnit(quantity);
  spec.x_label = "time from first contact (ms)";
  spec.y_label = u.stem + " (" + u.unit + ")";
  spec.series.push_back(
      bridge::scaledSeries("measured", lab.t, lab.grid.y, 1e3, u.scale, bridge::PlotSeries::Style::Markers));
  std::vector<double> t;
  for (double x : run.rec.time_s) t.push_back(x - run.contact_s);
  spec.series.push_back(bridge::scaledSeries("macro model, fitted", t, quantityOf(run.rec, quantity), 1e3, u.scale));
  bridge::writePlotPng(file, spec);
}

bridge::RunOutcome runCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx) {
  const MacroFitCase c = readMacroFitCase(doc);
  const auto lab = labHistories(c);
  const bridge::JsonDocument base = baseDocument(c.macro_case);
  checkScenarios(doc, c, base);

  std::vector<Parameter> params;
  for (const auto& p : c.params) params.push_back(p.param);
  const Objective objective{&base, &c, &lab};
  const OptimizationResult best = minimise(params, objective, c.optimizer);
  if (!std::isfinite(best.value) || best.value >= c.optimizer.penalty) {
    bridge::RunOutcome failed;
    failed.status = bridge::RunOutcome::Status::NumericalFailure;
    failed.message = "fit.macro: no evaluation succeeded within the bounds (" +
                     std::to_string(best.failed_evaluations) + " failed, " +
                     std::to_string(best.infeasible_evaluations) + " outside the laws' domain)" +
                     (best.failures.empty() ? "" : ": " + best.failures.front());
    return failed;
  }

  // The best point's runs: the histories, the twins' summaries, the charts.
  bridge::RunOutcome out;
  json scenarios = json::array(), plots = json::array();
  double sum2 = 0.0, count = 0.0;
  bridge::LawFile laws;
  for (std::size_t i = 0; i < c.scenarios.size(); ++i) {
    const MacroRun r = runScenario(scenarioDocument(base, c, c.scenarios[i], best.parameters));
    if (i == 0) laws = r.c.laws;
    json curves = json::array();
    for (std::size_t k = 0; k < c.scenarios[i].curves.size(); ++k) {
      const LabHistory& h = lab[i][k];
      const std::string& q = c.scenarios[i].curves[k].quantity;
      const auto y = modelAt(r, q, h.t);
      double e2 = 0.0;
      for (std::size_t j = 0; j < y.size(); ++j) e2 += std::pow((y[j] - h.grid.y[j]) / h.grid.scale, 2);
      sum2 += e2, count += static_cast<double>(y.size());
      curves.push_back({{"quantity", q},
                        {"file", c.scenarios[i].curves[k].source.file.string()},
                        {"sha256", sha256File(c.scenarios[i].curves[k].source.file)},
                        {"nrms", std::sqrt(e2 / static_cast<double>(y.size()))}});
      if (c.plots) {
        const std::string png = "fit_macro_" + std::to_string(i + 1) + "_" + q + ".png";
        plotHistory(ctx.outdir / png, c.scenarios[i].name + ": " + bridge::displayUnit(q).stem, q, h, r);
        plots.push_back(png);
      }
    }
    scenarios.push_back({{"name", c.scenarios[i].name},
                         {"outcome", macro::outcomeName(r.result.outcome)},
                         {"peak_force_N", r.result.peak_force_N},
                         {"max_penetration_m", r.result.max_penetration_m},
                         {"max_back_face_displacement_m", r.result.max_back_face_displacement_m},
                         {"balance_rel_error", r.result.balance_rel_error},
                         {"curves", curves}});
  }
  // 95 % intervals, linearised at the best point (fitting/uncertainty.hpp):
  // the noise variance from the robust misfit over the degrees of freedom.
  std::vector<double> stderr_;
  std::string no_intervals;
  const std::vector<double> row_factor = objective.rowFactors();
  const double n_eff = objective.effectiveObservations();
  const double dof = n_eff - static_cast<double>(params.size());
  const double s2 = dof > 0.0 ? best.value * n_eff / dof : NAN;
  const auto intervals =
      linearisedIntervals([&](const std::vector<double>& v) { return objective.residuals(v); }, row_factor, c.loss,
                          n_eff, s2, params, best.parameters, stderr_, nullptr, &no_intervals);
  // Profile-likelihood intervals where asked: every parameter pushed out
  // from the best point, the others re-fitted at each value (local search,
  // twin runs inside), until the misfit has grown by chi2_1 (95 %) of the
  // noise; they exist where the linearised ones do not (a direction the
  // histories do not see gives an end at its bound).
  std::vector<Interval> profile(params.size(), Interval{NAN, NAN});
  int profile_evaluations = 0;
  if (c.profile && std::isfinite(s2))
    profile = profileIntervals([&](const std::vector<double>& v) { return objective(v); }, n_eff, s2, params,
                               best.parameters, stderr_, c.optimizer, profile_evaluations);
  json parameters = json::array();
  std::ostringstream answer;
  const double nrms = std::sqrt(sum2 / count);
  answer << "fit.macro: nRMS " << bridge::showNumber(nrms) << " over " << c.scenarios.size() << " scenario"
         << (c.scenarios.size() == 1 ? "" : "s");
  for (std::size_t k = 0; k < c.params.size(); ++k) {
    const Parameter& p = c.params[k].param;
    const bool at_bound = std::abs(toUnit(p, best.parameters[k]) - 0.5) > 0.499;
    const bool finite = std::isfinite(intervals[k].lower) && std::isfinite(intervals[k].upper);
    const bool profiled = std::isfinite(profile[k].lower) && std::isfinite(profile[k].upper);
    parameters.push_back({{"name", p.name},
                          {"set", c.params[k].set},
                          {"value", best.parameters[k]},
                          {"standard_error", std::isfinite(stderr_[k]) ? json(stderr_[k]) : json(nullptr)},
                          {"jacobian_95", finite ? json{intervals[k].lower, intervals[k].upper} : json(nullptr)},
                          {"profile_95", profiled ? json{profile[k].lower, profile[k].upper} : json(nullptr)},
                          {"profile_at_bound", profiled && profile[k].at_bound},
                          {"bounds", {p.lower, p.upper}},
                          {"at_bound", at_bound}});
    // (in engineers' units, from the unit suffix of the key it sets; the
    // profile interval where there is one)
    const std::string& key = c.params[k].set.front();
    answer << "; " << p.name << " "
           << describeValue(key.substr(key.find_last_of('.') + 1), best.parameters[k],
                            reportedInterval(parameters.back()))
           << (at_bound ? " (at its bound)" : "");
  }
  answer << "\n";
  if (!no_intervals.empty())
    answer << (c.profile ? "  no linearised 95 % intervals (the profile ones above): " : "  no 95 % intervals: ")
           << no_intervals << (c.profile ? "" : " (\"uncertainty\": {\"profile\": true} gives profile-likelihood ones)")
           << "\n";

  json law_json = bridge::toJson(laws);
  law_json["description"] = "Cell laws identified by `gabion run " + ctx.case_file.string() + "` (fit.macro)";
  for (auto& [name, m] : law_json["materials"].items())
    m["provenance"]["fit_macro"] = {{"case_file", ctx.case_file.string()},
                                    {"macro_case", c.macro_case.string()},
                                    {"parameters", parameters},
                                    {"software", std::string("gabion ") + gabion::kVersion}};
  bridge::writeJsonAtomic(ctx.outdir / "law.json", law_json);
  bridge::loadLawFile(ctx.outdir / "law.json");  // what we write must read back

  out.results["parameters"] = parameters;
  out.results["nrms"] = nrms;
  if (!no_intervals.empty()) out.results["intervals_note"] = no_intervals;
  out.results["misfit"] = best.value;
  out.results["scenarios"] = scenarios;
  out.results["evaluations"] = best.evaluations;
  out.results["profile_evaluations"] = profile_evaluations;
  out.results["failed_evaluations"] = best.failed_evaluations;
  out.results["infeasible_evaluations"] = best.infeasible_evaluations;
  out.results["failures"] = best.failures;
  out.results["search"] = {{"global", c.optimizer.global_algorithm},
                           {"local", c.optimizer.local_algorithm},
                           {"global_status", best.global_status},
                           {"local_status", best.local_status},
                           {"seed", c.optimizer.seed}};
  out.results["fit_wall_time_s"] = best.wall_time_s;
  out.results["law_file"] = "law.json";
  out.results["plots"] = plots;
  out.answer = answer.str();
  return out;
}

}  // namespace

bridge::CaseKind fitMacroCaseKind() {
  return {"fit.macro",
          "identify macro law parameters so that a macro.impact case matches measured histories (force, "
          "penetration against time)",
          checkCase, runCase, estimateCase};
}

}  // namespace gabion::fitting
