#pragma once
/// \file
/// Bounded minimisation with NLopt: a global stage (GN_DIRECT_L, GN_CRS2_LM, ...)
/// then a local polish (LN_SBPLX, LN_BOBYQA, ...), on parameters mapped to the
/// unit box (log scale for positive bounds spanning more than a decade). An
/// evaluation that throws or returns a non-finite value scores `penalty` and is
/// recorded as a failure; it never stops the search.
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace gabion::fitting {

/// Thrown by an objective for a point outside the model's domain (e.g. a bilinear
/// hardening tangent above the elastic stiffness): scored `penalty`, counted as
/// infeasible, not as a failure.
struct Infeasible : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// One identified parameter with its search bounds (SI units, as named).
struct Parameter {
  std::string name;        ///< e.g. "stiffness_N_m"
  double lower = 0.0;      ///< lower bound
  double upper = 1.0;      ///< upper bound (> lower)
  bool log_scale = false;  ///< search in log(value); needs lower > 0
};

/// Makes a parameter, choosing the log scale when 0 < lower and upper > 10 lower.
Parameter makeParameter(const std::string& name, double lower, double upper);

/// Search settings (case key "optimizer", docs/fitting.md).
struct OptimizerSettings {
  std::string global_algorithm = "GN_DIRECT_L";  ///< NLopt name without "NLOPT_", or "none"
  std::string local_algorithm = "LN_SBPLX";      ///< NLopt name, or "none"
  int global_max_evaluations = 400;
  int local_max_evaluations = 2000;
  double xtol_rel = 1e-8;   ///< relative tolerance on the parameters (unit-box coordinates)
  double ftol_rel = 1e-12;  ///< relative tolerance on the objective
  unsigned long seed = 1;   ///< nlopt::srand before each stage (stochastic algorithms)
  double penalty = 1e6;     ///< objective value given to a failed evaluation
};

/// The objective: parameters in physical units -> value. May throw or return NaN.
using Objective = std::function<double(const std::vector<double>& parameters)>;

/// What a minimisation found.
struct OptimizationResult {
  std::vector<double> parameters;           ///< best point (physical units)
  double value = 0.0;                       ///< objective there
  int evaluations = 0;                      ///< all evaluations, both stages
  int failed_evaluations = 0;               ///< evaluations that threw or were not finite
  int infeasible_evaluations = 0;           ///< points outside the model's domain (Infeasible)
  std::vector<std::string> failures;        ///< the first few failure messages, with parameters
  std::string global_status, local_status;  ///< NLopt result codes as text
  double wall_time_s = 0.0;
};

/// Minimises `f` within the bounds. `start` (physical units, optional) is where the
/// local stage begins when the global stage is "none". Throws std::invalid_argument
/// for an unknown algorithm name (cases validate names with isNloptAlgorithm).
OptimizationResult minimise(const std::vector<Parameter>& params, const Objective& f, const OptimizerSettings& s,
                            const std::vector<double>& start = {});

/// True when `name` is an NLopt algorithm (e.g. "LN_SBPLX") usable without gradients
/// and with bounds; `global` selects GN_* names, else LN_* names.
bool isNloptAlgorithm(const std::string& name, bool global);

/// Unit-box coordinate of a physical value and back.
double toUnit(const Parameter& p, double value);
double fromUnit(const Parameter& p, double u);

}  // namespace gabion::fitting
