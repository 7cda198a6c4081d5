#pragma once
/// \file
/// 95 % confidence intervals of fitted law parameters: from the Jacobian at the
/// optimum (linearised least squares), from the profile likelihood, and from the
/// spread of replicate fits (docs/fitting.md, "Uncertainty").
#include <functional>
#include <string>
#include <vector>

#include "fitting/curve_model.hpp"
#include "fitting/optimizer.hpp"

namespace gabion::fitting {

/// A two-sided interval; both ends NaN when the parameter is not identifiable.
/// `at_bound` when the profile interval reached a search bound on either side.
struct Interval {
  double lower, upper;
  bool at_bound = false;
};

/// Two-sided 95 % quantile of Student's t with `dof` degrees of freedom (t_{0.975}).
double studentT975(double dof);
/// 95 % quantile of chi-square with one degree of freedom (3.841).
constexpr double kChiSquare1_95 = 3.841458820694124;

/// Residuals of a fit as a function of its parameters (physical units):
/// normalised (model - data) / scale, one per observation row; throws
/// Infeasible outside the model's domain.
using ResidualFunction = std::function<std::vector<double>(const std::vector<double>&)>;

/// The linearised intervals of any least-squares fit (jacobianIntervals
/// below is this for a law's curves): J = d r / d theta by central
/// differences of `residuals` (one-sided at the edge of the domain), row
/// weights `row_factor`[i] times the robust IRLS weight at the optimum,
/// cov = s2 (J^T W J)^-1, theta +- t_{n_eff - p} sqrt(cov). `n_eff` is the
/// effective number of observations, `s2` the noise variance of the
/// normalised residuals. Standard errors into `stderr_out` (NaN when
/// singular), the covariance (physical units) into `covariance_out` if given.
/// Where there are no intervals, `why_none` (if given) says why, naming the
/// parameter: one whose both sides leave the model's domain, or the one that
/// dominates the direction the curves do not determine (J^T W J singular:
/// its smallest eigenvector's largest component, in relative units).
std::vector<Interval> linearisedIntervals(const ResidualFunction& residuals, const std::vector<double>& row_factor,
                                          const LossSettings& loss, double n_eff, double s2,
                                          const std::vector<Parameter>& params, const std::vector<double>& theta,
                                          std::vector<double>& stderr_out,
                                          std::vector<double>* covariance_out = nullptr,
                                          std::string* why_none = nullptr);

/// Linearised intervals: cov = s^2 (J^T W J)^-1 with J = d r / d theta (central
/// differences), W = a_c w_i (effective-point factor times the robust IRLS weight
/// at the optimum), s^2 = residualVariance (on the original points, since
/// resampling smooths the noise); theta +- t_{n_eff-p} sqrt(cov).
/// Also returns the standard errors in `stderr_out` (NaN when singular) and,
/// when asked, the covariance (p x p, row-major, physical units; empty when
/// singular) in `covariance_out`, for the fitted curve's confidence band.
std::vector<Interval> jacobianIntervals(const CurveSet& set, const std::vector<Parameter>& params,
                                        const std::vector<double>& theta, std::vector<double>& stderr_out,
                                        std::vector<double>* covariance_out = nullptr);

/// Profile-likelihood intervals: for each parameter, the values where
/// (S_prof - S_min) / s^2 = chi2_{1,0.95}, with S_prof the misfit minimised over
/// the other parameters (local NLopt search), S_min the misfit at the optimum and
/// s^2 = residualVariance (the likelihood ratio with the noise variance estimated).
/// `initial_steps` (physical units; e.g. the Jacobian standard errors) start the
/// outward search. Adds the evaluations it spends to `evaluations`.
std::vector<Interval> profileIntervals(const CurveSet& set, const std::vector<Parameter>& params,
                                       const std::vector<double>& theta, const std::vector<double>& initial_steps,
                                       const OptimizerSettings& settings, int& evaluations);

/// A misfit as a function of the parameters (physical units; throws
/// Infeasible outside the model's domain).
using MisfitFunction = std::function<double(const std::vector<double>&)>;
/// The same profile-likelihood intervals for any least-squares fit: the
/// values of each parameter where (S_prof - S_min) / s2 = chi2_{1,0.95},
/// S = `scale` x `misfit` (the misfit summed over the effective observations
/// when it is given per observation), S_min at `theta`, `s2` the noise
/// variance of the normalised residuals. An end that reaches a bound with
/// the statistic still below the threshold is that bound, `at_bound` set.
std::vector<Interval> profileIntervals(const MisfitFunction& misfit, double scale, double s2,
                                       const std::vector<Parameter>& params, const std::vector<double>& theta,
                                       const std::vector<double>& initial_steps, const OptimizerSettings& settings,
                                       int& evaluations);

}  // namespace gabion::fitting
