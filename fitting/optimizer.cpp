#include "fitting/optimizer.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <nlopt.hpp>
#include <sstream>
#include <stdexcept>

namespace gabion::fitting {

namespace {

// Gradient-free algorithms that accept bounds; the names NLopt's
// nlopt_algorithm_from_string understands (without the NLOPT_ prefix).
const std::vector<std::string> kGlobal = {"GN_DIRECT",  "GN_DIRECT_L", "GN_DIRECT_L_RAND",
                                          "GN_CRS2_LM", "GN_ISRES",    "GN_ESCH"};
const std::vector<std::string> kLocal = {"LN_SBPLX", "LN_BOBYQA", "LN_NELDERMEAD", "LN_COBYLA", "LN_NEWUOA_BOUND"};

nlopt::algorithm algorithmFromName(const std::string& name) {
  const int a = nlopt_algorithm_from_string(name.c_str());
  if (a < 0) throw std::invalid_argument("unknown NLopt algorithm '" + name + "'");
  return static_cast<nlopt::algorithm>(a);
}

std::string resultText(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS:
      return "success";
    case nlopt::STOPVAL_REACHED:
      return "stopval_reached";
    case nlopt::FTOL_REACHED:
      return "ftol_reached";
    case nlopt::XTOL_REACHED:
      return "xtol_reached";
    case nlopt::MAXEVAL_REACHED:
      return "maxeval_reached";
    case nlopt::MAXTIME_REACHED:
      return "maxtime_reached";
    case nlopt::ROUNDOFF_LIMITED:
      return "roundoff_limited";
    case nlopt::FORCED_STOP:
      return "forced_stop";
    default:
      return "failure";
  }
}

// State shared with the C-style NLopt callback through its void* data pointer
// (NLopt 2.7's C++ API has no std::function overload).
struct CallbackData {
  const std::vector<Parameter>* params = nullptr;
  const Objective* f = nullptr;
  const OptimizerSettings* settings = nullptr;
  OptimizationResult* result = nullptr;
  std::vector<double> best_unit;
  double best = std::numeric_limits<double>::infinity();
};

double callback(unsigned n, const double* u, double* /*grad*/, void* data) {
  auto& d = *static_cast<CallbackData*>(data);
  std::vector<double> x(n);
  for (unsigned i = 0; i < n; ++i) x[i] = fromUnit((*d.params)[i], u[i]);
  ++d.result->evaluations;
  double value = 0.0;
  std::string failure;
  try {
    value = (*d.f)(x);
    if (!std::isfinite(value)) failure = "objective is not finite";
  } catch (const Infeasible&) {
    ++d.result->infeasible_evaluations;
    value = d.settings->penalty;
  } catch (const std::exception& e) {
    failure = e.what();
  } catch (...) {
    failure = "unknown exception";
  }
  if (!failure.empty()) {
    ++d.result->failed_evaluations;
    if (d.result->failures.size() < 10) {
      std::ostringstream msg;
      msg.precision(10);
      msg << "evaluation " << d.result->evaluations << " at (";
      for (unsigned i = 0; i < n; ++i) msg << (i ? ", " : "") << (*d.params)[i].name << "=" << x[i];
      msg << "): " << failure;
      d.result->failures.push_back(msg.str());
    }
    value = d.settings->penalty;
  }
  if (value < d.best) {
    d.best = value;
    d.best_unit.assign(u, u + n);
  }
  return value;
}

// Runs one NLopt stage from `u` (updated to the best point seen by this stage).
std::string runStage(const std::string& name, int max_evaluations, std::vector<double>& u, CallbackData& data) {
  const unsigned n = static_cast<unsigned>(u.size());
  nlopt::opt opt(algorithmFromName(name), n);
  opt.set_lower_bounds(std::vector<double>(n, 0.0));
  opt.set_upper_bounds(std::vector<double>(n, 1.0));
  opt.set_min_objective(callback, &data);
  opt.set_xtol_rel(data.settings->xtol_rel);
  opt.set_ftol_rel(data.settings->ftol_rel);
  opt.set_maxeval(max_evaluations);
  if (name.rfind("LN_", 0) == 0) opt.set_initial_step(std::vector<double>(n, 0.05));
  nlopt::srand(data.settings->seed);
  data.best = std::numeric_limits<double>::infinity();
  double value = 0.0;
  std::string status;
  try {
    status = resultText(opt.optimize(u, value));
  } catch (const nlopt::roundoff_limited&) {
    status = "roundoff_limited";
  } catch (const nlopt::forced_stop&) {
    status = "forced_stop";
  } catch (const std::exception& e) {
    status = std::string("failure: ") + e.what();
  }
  // Keep the best point evaluated, whatever the algorithm returned.
  if (!data.best_unit.empty()) u = data.best_unit;
  return status;
}

}  // namespace

Parameter makeParameter(const std::string& name, double lower, double upper) {
  Parameter p{name, lower, upper, false};
  p.log_scale = lower > 0.0 && upper > 10.0 * lower;
  return p;
}

double toUnit(const Parameter& p, double value) {
  const double u =
      p.log_scale ? std::log(value / p.lower) / std::log(p.upper / p.lower) : (value - p.lower) / (p.upper - p.lower);
  return std::min(1.0, std::max(0.0, u));
}

double fromUnit(const Parameter& p, double u) {
  return p.log_scale ? p.lower * std::pow(p.upper / p.lower, u) : p.lower + u * (p.upper - p.lower);
}

bool isNloptAlgorithm(const std::string& name, bool global) {
  const auto& list = global ? kGlobal : kLocal;
  for (const auto& a : list)
    if (a == name) return true;
  return false;
}

OptimizationResult minimise(const std::vector<Parameter>& params, const Objective& f, const OptimizerSettings& s,
                            const std::vector<double>& start) {
  const auto t0 = std::chrono::steady_clock::now();
  OptimizationResult result;
  CallbackData data;
  data.params = &params;
  data.f = &f;
  data.settings = &s;
  data.result = &result;

  std::vector<double> u(params.size(), 0.5);
  if (!start.empty())
    for (std::size_t i = 0; i < params.size(); ++i) u[i] = toUnit(params[i], start[i]);
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_u = u;
  if (s.global_algorithm != "none") {
    result.global_status = runStage(s.global_algorithm, s.global_max_evaluations, u, data);
    best = data.best;
    best_u = u;
  }
  if (s.local_algorithm != "none") {
    result.local_status = runStage(s.local_algorithm, s.local_max_evaluations, u, data);
    if (data.best <= best) best = data.best, best_u = u;
  }
  result.value = best;
  for (std::size_t i = 0; i < params.size(); ++i) result.parameters.push_back(fromUnit(params[i], best_u[i]));
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace gabion::fitting
