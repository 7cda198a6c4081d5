#include "fitting/law_fit.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include "bridge/units.hpp"

namespace gabion::fitting {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ModelFit fitModel(LawModel model, const std::vector<PathGrid>& grids, const Bounds& bounds,
                  const LawFitSettings& settings) {
  ModelFit fit;
  fit.model = model;
  for (const auto& name : parameterNames(model)) {
    const auto& b = bounds.at(name);
    fit.params.push_back(makeParameter(name, b.first, b.second));
  }
  CurveSet set{model, grids, settings.loss, settings.lockup, settings.flux_base};
  fit.optimization = minimise(
      fit.params, [&](const std::vector<double>& t) { return misfit(set, t); }, settings.optimizer);
  fit.theta = fit.optimization.parameters;
  fit.misfit = fit.optimization.value;
  try {
    fit.nrms = normalisedRms(set, fit.theta);
  } catch (const Infeasible&) {  // no feasible point found within the bounds: never chosen
    fit.feasible = false;
    fit.nrms = kNaN;
    fit.bic = fit.aicc = std::numeric_limits<double>::infinity();
    return fit;
  }
  // Gaussian likelihood with unknown variance: -2 ln L = n ln(S/n) + const.
  const double n = effectiveObservations(set);
  const double k = static_cast<double>(fit.params.size());
  const double s = std::max(fit.misfit, 1e-14 * n);  // noise-free synthetic data
  const double core = n * std::log(s / n);
  fit.bic = core + k * std::log(n);
  fit.aicc = core + 2.0 * k + (n - k - 1.0 > 0.0 ? 2.0 * k * (k + 1.0) / (n - k - 1.0) : kNaN);
  return fit;
}

void count(LawFitResult& r, const OptimizationResult& o) {
  r.evaluations += o.evaluations;
  r.failed_evaluations += o.failed_evaluations;
  for (const auto& f : o.failures)
    if (r.failures.size() < 20) r.failures.push_back(f);
}

}  // namespace

LawFitResult fitLaw(const std::vector<LawModel>& candidates, const std::vector<PathGrid>& grids, const Bounds& bounds,
                    const LawFitSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  LawFitResult r;
  for (LawModel m : candidates) {
    r.candidates.push_back(fitModel(m, grids, bounds, settings));
    count(r, r.candidates.back().optimization);
  }
  // Lowest criterion wins; on a tie the first (simplest) candidate stays.
  for (std::size_t i = 1; i < r.candidates.size(); ++i) {
    const auto value = [&](const ModelFit& f) { return settings.criterion == Criterion::Bic ? f.bic : f.aicc; };
    if (value(r.candidates[i]) < value(r.candidates[r.chosen])) r.chosen = i;
  }
  if (!r.candidates[r.chosen].feasible)
    throw Infeasible(
        "no candidate model found a feasible parameter set within the bounds (e.g. a hardening "
        "stiffness below the stiffness): widen or correct the bounds");
  const ModelFit& best = r.candidates[r.chosen];
  const CurveSet set{best.model, grids, settings.loss, settings.lockup, settings.flux_base};
  r.effective_observations = effectiveObservations(set);

  std::vector<double> se;
  const auto jac = jacobianIntervals(set, best.params, best.theta, se, &r.covariance);
  r.evaluations += static_cast<int>(2 * best.theta.size() + 1);
  std::vector<Interval> prof(best.theta.size(), Interval{kNaN, kNaN});
  if (settings.profile) prof = profileIntervals(set, best.params, best.theta, se, settings.optimizer, r.evaluations);

  for (std::size_t j = 0; j < best.theta.size(); ++j) {
    ParameterEstimate e;
    e.name = best.params[j].name;
    e.value = best.theta[j];
    e.standard_error = se[j];
    e.jacobian = jac[j];
    e.profile = prof[j];
    e.replicate = Interval{kNaN, kNaN};
    r.parameters.push_back(e);
  }

  // Replicate spread: one fit per replicate label, then a t interval of the mean.
  std::set<std::string> labels;
  for (const auto& g : grids) labels.insert(g.replicate);
  if (labels.size() >= 2) {
    LawFitSettings single = settings;
    single.profile = false;
    for (const auto& label : labels) {
      std::vector<PathGrid> subset;
      for (const auto& g : grids)
        if (g.replicate == label) subset.push_back(g);
      const ModelFit f = fitModel(best.model, subset, bounds, single);
      count(r, f.optimization);
      r.replicate_labels.push_back(label);
      for (std::size_t j = 0; j < f.theta.size(); ++j) r.parameters[j].replicate_values.push_back(f.theta[j]);
    }
    const double R = static_cast<double>(labels.size());
    for (auto& e : r.parameters) {
      double mean = 0.0, var = 0.0;
      for (double v : e.replicate_values) mean += v / R;
      for (double v : e.replicate_values) var += (v - mean) * (v - mean) / (R - 1.0);
      const double half = studentT975(R - 1.0) * std::sqrt(var / R);
      e.replicate = {mean - half, mean + half};
    }
  }
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

namespace {
nlohmann::json intervalJson(const Interval& iv) {
  if (std::isnan(iv.lower) || std::isnan(iv.upper)) return nullptr;
  nlohmann::json j = nlohmann::json::array({iv.lower, iv.upper});
  return j;
}
}  // namespace

const nlohmann::json& reportedInterval(const nlohmann::json& parameter) {
  const nlohmann::json& profile = parameter.at("profile_95");
  return profile.is_null() ? parameter.at("jacobian_95") : profile;
}

std::string describeValue(const std::string& key, double value, const nlohmann::json& interval) {
  using bridge::showNumber;
  const bridge::DisplayUnit u = bridge::displayUnit(key);
  std::string s = showNumber(u.scale * value, 4) + (u.unit == "-" ? "" : " " + u.unit);
  if (!interval.is_null())
    s += " [" + showNumber(u.scale * interval[0].get<double>(), 4) + ", " +
         showNumber(u.scale * interval[1].get<double>(), 4) + "]";
  return s;
}

std::string describeFit(const std::string& law, const nlohmann::json& entry) {
  using bridge::showNumber;
  const double nrms = entry.at("nrms").get<double>();
  std::ostringstream line;
  line << law << " (" << entry.at("model").get<std::string>() << ", nRMS " << showNumber(nrms)
       << (nrms > kPoorFitNrms ? ", POOR FIT" : "") << "):";
  const char* sep = " ";
  for (const auto& [name, p] : entry.at("parameters").items()) {
    const bridge::DisplayUnit u = bridge::displayUnit(name);
    line << sep << u.stem << " " << describeValue(name, p.at("value").get<double>(), reportedInterval(p));
    if (p.contains("replicate_mean_95") && !p.at("replicate_mean_95").is_null()) {
      const nlohmann::json& rv = p.at("replicate_mean_95");
      line << ", between replicates [" << showNumber(u.scale * rv[0].get<double>(), 4) << ", "
           << showNumber(u.scale * rv[1].get<double>(), 4) << "]";
    }
    sep = "; ";
  }
  return line.str();
}

nlohmann::json toJson(const LawFitResult& r, Criterion criterion) {
  using nlohmann::json;
  json out;
  const ModelFit& best = r.best();
  out["model"] = modelName(best.model);
  out["criterion"] = criterion == Criterion::Bic ? "bic" : "aicc";
  json cands = json::object();
  for (const auto& c : r.candidates) {
    json p = json::object();
    for (std::size_t j = 0; j < c.theta.size(); ++j) p[c.params[j].name] = c.theta[j];
    const auto finite = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
    cands[modelName(c.model)] = {{"parameters", p},
                                 {"feasible", c.feasible},
                                 {"misfit", finite(c.misfit)},
                                 {"nrms", finite(c.nrms)},
                                 {"bic", finite(c.bic)},
                                 {"aicc", finite(c.aicc)},
                                 {"evaluations", c.optimization.evaluations},
                                 {"infeasible_evaluations", c.optimization.infeasible_evaluations},
                                 {"global_status", c.optimization.global_status},
                                 {"local_status", c.optimization.local_status},
                                 {"wall_time_s", c.optimization.wall_time_s}};
  }
  out["candidates"] = cands;
  json params = json::object();
  for (const auto& e : r.parameters) {
    json p = {{"value", e.value},
              {"standard_error", std::isnan(e.standard_error) ? json(nullptr) : json(e.standard_error)},
              {"jacobian_95", intervalJson(e.jacobian)},
              {"profile_95", intervalJson(e.profile)}};
    if (e.profile.at_bound) p["profile_reaches_bound"] = true;
    if (!e.replicate_values.empty()) {
      p["replicate_values"] = e.replicate_values;
      p["replicate_mean_95"] = intervalJson(e.replicate);
    }
    params[e.name] = p;
  }
  out["parameters"] = params;
  if (!r.replicate_labels.empty()) out["replicates"] = r.replicate_labels;
  out["nrms"] = best.nrms;
  out["misfit"] = best.misfit;
  out["effective_observations"] = r.effective_observations;
  out["evaluations"] = r.evaluations;
  out["failed_evaluations"] = r.failed_evaluations;
  if (!r.failures.empty()) out["failures"] = r.failures;
  out["wall_time_s"] = r.wall_time_s;
  return out;
}

}  // namespace gabion::fitting
