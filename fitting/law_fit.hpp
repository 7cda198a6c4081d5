#pragma once
/// \file
/// Identification of one macro law from its curves: every candidate model is
/// fitted (NLopt global stage then local polish), the model is chosen by an
/// information criterion, and the chosen model's parameters get 95 % intervals
/// from the Jacobian, the profile likelihood and the replicate spread.
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "fitting/curve_model.hpp"
#include "fitting/optimizer.hpp"
#include "fitting/uncertainty.hpp"

namespace gabion::fitting {

/// Model-choice criterion (docs/fitting.md explains the default).
enum class Criterion { Bic, Aicc };

/// Settings of one law identification.
struct LawFitSettings {
  OptimizerSettings optimizer;
  LossSettings loss;
  Criterion criterion = Criterion::Bic;
  bool profile = true;               ///< profile-likelihood intervals (costs evaluations)
  Lockup lockup;                     ///< the axial/impact laws' fixed lock-up
  bridge::AxialLawParams flux_base;  ///< the momentum_flux model's law, whose flux alone is fitted
};

/// One fitted candidate model.
struct ModelFit {
  LawModel model = LawModel::ElasticPerfectlyPlastic;
  std::vector<Parameter> params;
  std::vector<double> theta;  ///< best parameters
  double misfit = 0.0;        ///< robust misfit S at theta
  double nrms = 0.0;          ///< normalised RMS error
  double aicc = 0.0, bic = 0.0;
  bool feasible = true;  ///< false: no feasible point within the bounds (criteria infinite, never chosen)
  OptimizationResult optimization;
};

/// A parameter of the chosen model with its intervals.
struct ParameterEstimate {
  std::string name;
  double value = 0.0;
  double standard_error = 0.0;           ///< from the Jacobian (NaN when singular)
  Interval jacobian{0.0, 0.0};           ///< 95 %, linearised
  Interval profile{0.0, 0.0};            ///< 95 %, profile likelihood (NaN ends when not computed)
  std::vector<double> replicate_values;  ///< one fit per replicate label (when 2 or more)
  Interval replicate{0.0, 0.0};          ///< 95 % interval of the replicate mean (t, R-1 dof)
};

/// Result of identifying one law.
struct LawFitResult {
  std::vector<ModelFit> candidates;
  std::size_t chosen = 0;
  std::vector<ParameterEstimate> parameters;  ///< of candidates[chosen]
  /// Their linearised covariance (p x p, row-major, physical units; empty
  /// when singular): the fitted curve's confidence band.
  std::vector<double> covariance;
  double effective_observations = 0.0;
  std::vector<std::string> replicate_labels;
  int evaluations = 0;  ///< every objective evaluation (fits, profiles, replicates)
  int failed_evaluations = 0;
  std::vector<std::string> failures;
  double wall_time_s = 0.0;
  const ModelFit& best() const { return candidates[chosen]; }
};

/// Bounds by parameter name (physical units).
using Bounds = std::map<std::string, std::pair<double, double>>;

/// Fits every model in `candidates` to `grids`, chooses one, computes intervals.
/// `bounds` must hold every parameter of every candidate. Throws Infeasible
/// when no candidate finds a feasible point within its bounds.
LawFitResult fitLaw(const std::vector<LawModel>& candidates, const std::vector<PathGrid>& grids, const Bounds& bounds,
                    const LawFitSettings& settings);

/// A fit whose normalised RMS error is above this is called poor (warned of).
constexpr double kPoorFitNrms = 0.1;

/// The 95 % interval a parameter's summary entry (toJson) is reported with:
/// the profile likelihood's where it was computed, else the linearised one
/// (null when neither could be).
const nlohmann::json& reportedInterval(const nlohmann::json& parameter);

/// One line for people from a summary entry (toJson): the law, its model,
/// its nRMS error, each parameter in engineers' units with its 95 %
/// interval (profile, else linearised); "poor fit" past kPoorFitNrms.
std::string describeFit(const std::string& law, const nlohmann::json& entry);

/// A value named by its SI key (`yield_force_N`) in engineers' units with its
/// 95 % interval [lower, upper] (a JSON pair; null: none): "81.73 kN [80.05, 83.48]".
std::string describeValue(const std::string& key, double value, const nlohmann::json& interval);

/// The summary.json entry of a result (parameters, intervals, residual,
/// evaluations, wall time, chosen model and criterion values).
nlohmann::json toJson(const LawFitResult& r, Criterion criterion);

}  // namespace gabion::fitting
