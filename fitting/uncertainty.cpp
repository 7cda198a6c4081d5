#include "fitting/uncertainty.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace gabion::fitting {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

double studentT975(double dof) {
  // Table for small dof (Abramowitz & Stegun 26.7), then the Cornish-Fisher
  // expansion in 1/dof about z = 1.959964, good to 1e-4 beyond 30.
  static const double table[] = {12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646, 2.3060, 2.2622, 2.2281,
                                 2.2010,  2.1788, 2.1604, 2.1448, 2.1314, 2.1199, 2.1098, 2.1009, 2.0930, 2.0860,
                                 2.0796,  2.0739, 2.0687, 2.0639, 2.0595, 2.0555, 2.0518, 2.0484, 2.0452, 2.0423};
  if (!(dof >= 1.0)) return kNaN;
  if (dof <= 30.0) return table[static_cast<int>(std::floor(dof)) - 1];
  const double z = 1.959963984540054, z3 = z * z * z, z5 = z3 * z * z;
  return z + (z3 + z) / (4.0 * dof) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof * dof);
}

std::vector<Interval> linearisedIntervals(const ResidualFunction& residuals, const std::vector<double>& row_factor,
                                          const LossSettings& loss, double n_eff, double s2,
                                          const std::vector<Parameter>& params, const std::vector<double>& theta,
                                          std::vector<double>& stderr_out, std::vector<double>* covariance_out,
                                          std::string* why_none) {
  const std::size_t p = theta.size();
  if (covariance_out != nullptr) covariance_out->clear();
  const auto none = [&](const std::string& why) {
    if (why_none != nullptr) *why_none = why;
  };
  const auto r0 = residuals(theta);
  const std::size_t m = r0.size();
  // Row weights: the row's factor (effective points of its curve) times the robust weight.
  Eigen::VectorXd w(static_cast<Eigen::Index>(m));
  for (std::size_t row = 0; row < m; ++row)
    w[static_cast<Eigen::Index>(row)] = row_factor[row] * lossWeight(r0[row], loss);
  Eigen::MatrixXd J(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(p));
  std::vector<double> scale(p, 1.0);
  for (std::size_t j = 0; j < p; ++j) {
    const double range = params[j].upper - params[j].lower;
    const double h = std::max(1e-5 * std::abs(theta[j]), 1e-8 * range);
    auto plus = theta, minus = theta;
    plus[j] += h;
    minus[j] -= h;
    // A side outside the model's domain (the best point on its edge, e.g. a
    // hardening tangent just below the stiffness): a one-sided difference;
    // both sides outside: no linearised interval.
    const auto at = [&](const std::vector<double>& t, std::vector<double>& r) {
      try {
        r = residuals(t);
        return r.size() == m;
      } catch (const Infeasible&) {
        return false;
      }
    };
    std::vector<double> rp, rm;
    const bool ok_p = at(plus, rp), ok_m = at(minus, rm);
    if (!ok_p && !ok_m) {
      none("both sides of " + params[j].name + " leave the model's domain at the best point");
      stderr_out.assign(p, kNaN);
      return std::vector<Interval>(p, Interval{kNaN, kNaN});
    }
    if (!ok_p) rp = r0;
    if (!ok_m) rm = r0;
    const double span = (ok_p ? h : 0.0) + (ok_m ? h : 0.0);
    // Columns in relative units (d r / d ln theta) so that parameters of very
    // different magnitudes (friction ~1, stiffness ~1e6) do not look singular.
    const double d = theta[j] != 0.0 ? std::abs(theta[j]) : range;
    scale[j] = d;
    for (std::size_t i = 0; i < m; ++i)
      J(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = d * (rp[i] - rm[i]) / span;
  }
  const double dof = n_eff - static_cast<double>(p);
  std::vector<Interval> out(p, Interval{kNaN, kNaN});
  stderr_out.assign(p, kNaN);
  if (!(dof >= 1.0)) {
    none("fewer than one degree of freedom");
    return out;
  }
  if (!std::isfinite(s2)) {
    none("the misfit is not finite");
    return out;
  }
  const Eigen::MatrixXd A = J.transpose() * w.asDiagonal() * J;
  Eigen::FullPivLU<Eigen::MatrixXd> lu(A);
  lu.setThreshold(1e-12);
  if (!lu.isInvertible()) {
    // The direction the curves do not see: A's smallest eigenvector.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
    Eigen::Index worst = 0;
    eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&worst);
    none(
        "the curves do not determine every parameter at the best point (the linearised covariance is singular; "
        "the direction they do not see is mostly " +
        params[static_cast<std::size_t>(worst)].name + ")");
    return out;
  }
  const Eigen::MatrixXd cov = s2 * lu.inverse();
  if (covariance_out != nullptr) {
    covariance_out->resize(p * p);
    for (std::size_t i = 0; i < p; ++i)
      for (std::size_t j = 0; j < p; ++j)
        (*covariance_out)[i * p + j] =
            scale[i] * scale[j] * cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  }
  const double t = studentT975(dof);
  for (std::size_t j = 0; j < p; ++j) {
    const double var = cov(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j));
    if (!(var >= 0.0) || !std::isfinite(var)) continue;
    stderr_out[j] = scale[j] * std::sqrt(var);
    out[j] = {theta[j] - t * stderr_out[j], theta[j] + t * stderr_out[j]};
  }
  return out;
}

std::vector<Interval> jacobianIntervals(const CurveSet& set, const std::vector<Parameter>& params,
                                        const std::vector<double>& theta, std::vector<double>& stderr_out,
                                        std::vector<double>* covariance_out) {
  std::vector<double> row_factor;
  for (const auto& g : set.grids)
    row_factor.insert(row_factor.end(), g.x.size(), g.effectivePoints() / static_cast<double>(g.x.size()));
  return linearisedIntervals([&](const std::vector<double>& t) { return residuals(set, t); }, row_factor, set.loss,
                             effectiveObservations(set), residualVariance(set, theta), params, theta, stderr_out,
                             covariance_out);
}

namespace {

// Misfit minimised over every parameter but `j`, which is held at `value`.
// `others` (physical units) is the start and receives the minimiser.
double profileMisfit(const MisfitFunction& misfit, const std::vector<Parameter>& params, std::size_t j, double value,
                     std::vector<double>& others, const OptimizerSettings& settings, int& evaluations) {
  const auto full = [&](const std::vector<double>& o) {
    std::vector<double> theta;
    for (std::size_t i = 0, k = 0; i < params.size(); ++i) theta.push_back(i == j ? value : o[k++]);
    return theta;
  };
  if (params.size() == 1) {
    ++evaluations;
    try {
      return misfit(full({}));
    } catch (const Infeasible&) {
      return std::numeric_limits<double>::infinity();
    }
  }
  std::vector<Parameter> sub;
  for (std::size_t i = 0; i < params.size(); ++i)
    if (i != j) sub.push_back(params[i]);
  OptimizerSettings s = settings;
  s.global_algorithm = "none";
  s.local_algorithm = "LN_SBPLX";
  s.local_max_evaluations = 400;
  s.xtol_rel = 1e-7;
  const auto r = minimise(
      sub, [&](const std::vector<double>& o) { return misfit(full(o)); }, s, others);  // (Infeasible: a penalty)
  evaluations += r.evaluations;
  others = r.parameters;
  return r.value >= settings.penalty ? std::numeric_limits<double>::infinity() : r.value;
}

}  // namespace

std::vector<Interval> profileIntervals(const CurveSet& set, const std::vector<Parameter>& params,
                                       const std::vector<double>& theta, const std::vector<double>& initial_steps,
                                       const OptimizerSettings& settings, int& evaluations) {
  // Likelihood ratio with the noise variance estimated on the original points
  // (see residualVariance): (S_prof - S_min) / s^2 ~ chi2_1. The floor keeps a
  // noise-free synthetic curve from dividing by zero.
  const double s2 = std::max(residualVariance(set, theta), 1e-16);
  return profileIntervals([&](const std::vector<double>& t) { return misfit(set, t); }, 1.0, s2, params, theta,
                          initial_steps, settings, evaluations);
}

std::vector<Interval> profileIntervals(const MisfitFunction& misfit, double scale, double s2,
                                       const std::vector<Parameter>& params, const std::vector<double>& theta,
                                       const std::vector<double>& initial_steps, const OptimizerSettings& settings,
                                       int& evaluations) {
  const double s_min = misfit(theta);
  const auto statistic = [&](double s) { return std::max(0.0, scale * (s - s_min)) / s2; };
  std::vector<Interval> out;
  for (std::size_t j = 0; j < params.size(); ++j) {
    std::vector<double> start;
    for (std::size_t i = 0; i < params.size(); ++i)
      if (i != j) start.push_back(theta[i]);
    const double range = params[j].upper - params[j].lower;
    double step = initial_steps.size() > j && std::isfinite(initial_steps[j]) && initial_steps[j] > 0.0
                      ? initial_steps[j]
                      : 0.01 * std::max(std::abs(theta[j]), 1e-3 * range);
    Interval iv{kNaN, kNaN};
    for (int side = -1; side <= 1; side += 2) {
      const double bound = side < 0 ? params[j].lower : params[j].upper;
      std::vector<double> others = start;
      double inside = theta[j], outside = kNaN;
      double t = step;
      for (int k = 0; k < 60; ++k) {
        double v = theta[j] + side * t;
        const bool clamped = side < 0 ? v <= bound : v >= bound;
        if (clamped) v = bound;
        const double stat = statistic(profileMisfit(misfit, params, j, v, others, settings, evaluations));
        if (stat > kChiSquare1_95) {
          outside = v;
          break;
        }
        inside = v;
        if (clamped) break;
        t *= 2.0;
      }
      double end = inside;
      if (std::isnan(outside)) {
        iv.at_bound = true;
      } else {
        // Bisection between the last point inside and the first outside.
        std::vector<double> o2 = others;
        for (int k = 0; k < 30 && std::abs(outside - inside) > 1e-6 * std::max(std::abs(theta[j]), 1e-12); ++k) {
          const double mid = 0.5 * (inside + outside);
          const double stat = statistic(profileMisfit(misfit, params, j, mid, o2, settings, evaluations));
          (stat > kChiSquare1_95 ? outside : inside) = mid;
        }
        end = 0.5 * (inside + outside);
      }
      (side < 0 ? iv.lower : iv.upper) = end;
    }
    out.push_back(iv);
  }
  return out;
}

}  // namespace gabion::fitting
