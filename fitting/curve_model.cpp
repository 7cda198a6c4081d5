#include "fitting/curve_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "bridge/errors.hpp"
#include "bridge/laws/cell_axial_law.hpp"
#include "fitting/optimizer.hpp"

namespace gabion::fitting {

double PathGrid::effectivePoints() const {
  return static_cast<double>(std::min(raw_points, x.size()));
}

PathGrid resampleOnPath(const bridge::Curve& c, std::size_t points) {
  PathGrid g;
  g.source = c.source;
  g.raw_points = c.size();
  g.raw_x = c.x;
  g.raw_y = c.y;
  if (!c.t.empty()) {
    // central differences inside, one-sided at the ends
    const std::size_t m = c.size();
    g.raw_rate.resize(m);
    for (std::size_t i = 0; i < m; ++i) {
      const std::size_t a = i > 0 ? i - 1 : 0, b = i + 1 < m ? i + 1 : m - 1;
      g.raw_rate[i] = (c.x[b] - c.x[a]) / (c.t[b] - c.t[a]);
    }
  }
  g.scale = 0.0;
  for (double v : c.y) g.scale = std::max(g.scale, std::abs(v));
  if (!(g.scale > 0.0)) throw bridge::InputError(c.source, "", "the curve's " + c.y_name + " is zero everywhere");

  const std::size_t n = c.size();
  std::vector<double> s(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) s[i] = s[i - 1] + std::abs(c.x[i] - c.x[i - 1]);
  const double length = s.back();
  // Sample positions: a uniform grid in s plus the turning points of x.
  std::vector<double> at;
  for (std::size_t k = 0; k < points; ++k)
    at.push_back(length * static_cast<double>(k) / static_cast<double>(points - 1));
  for (std::size_t i = 1; i + 1 < n; ++i)
    if ((c.x[i] - c.x[i - 1]) * (c.x[i + 1] - c.x[i]) < 0.0) at.push_back(s[i]);
  std::sort(at.begin(), at.end());
  at.erase(std::unique(at.begin(), at.end()), at.end());

  std::size_t j = 0;
  for (double sk : at) {
    while (j + 2 < n && s[j + 1] < sk) ++j;
    // Among points at the same s (a pause in x), take the last one: the force it settled to.
    while (j + 2 < n && s[j + 1] == sk && s[j + 2] == sk) ++j;
    const double ds = s[j + 1] - s[j];
    const double t = ds > 0.0 ? std::min(1.0, std::max(0.0, (sk - s[j]) / ds)) : 1.0;
    g.x.push_back(c.x[j] + t * (c.x[j + 1] - c.x[j]));
    g.y.push_back(c.y[j] + t * (c.y[j + 1] - c.y[j]));
    if (!g.raw_rate.empty()) g.rate.push_back(g.raw_rate[j] + t * (g.raw_rate[j + 1] - g.raw_rate[j]));
  }
  return g;
}

std::vector<std::string> parameterNames(LawModel m) {
  switch (m) {
    case LawModel::ElasticPerfectlyPlastic:
      return {"stiffness_N_m", "yield_force_N"};
    case LawModel::Bilinear:
      return {"stiffness_N_m", "yield_force_N", "hardening_stiffness_N_m"};
    case LawModel::Densifying:
      return {"stiffness_N_m", "yield_force_N", "hardening_stiffness_N_m", "densification_onset_m",
              "densification_stiffness_N_m"};
    case LawModel::DensifyingPlastic:
      return {"stiffness_N_m",
              "yield_force_N",
              "hardening_stiffness_N_m",
              "densification_onset_m",
              "densification_stiffness_N_m",
              "densification_unloading_stiffness_N_m"};
    case LawModel::Softening:
      return {"stiffness_N_m", "yield_force_N", "softening_onset_m", "softening_stiffness_N_m", "residual_ratio"};
    case LawModel::SofteningRate:
      return {"stiffness_N_m",     "yield_force_N",
              "softening_onset_m", "softening_stiffness_N_m",
              "residual_ratio",    "rate_coefficient_N_s2_m2",
              "rate_growth_m"};
    case LawModel::MomentumFlux:
      return {"momentum_flux_kg_m", "momentum_flux_growth_m"};
    case LawModel::LateralLinear:
      return {"reaction_coefficient"};
    case LawModel::InterfaceSlider:
      return {"friction", "tangential_stiffness_N_m"};
  }
  return {};
}

std::string modelName(LawModel m) {
  switch (m) {
    case LawModel::ElasticPerfectlyPlastic:
      return "elastic_perfectly_plastic";
    case LawModel::Bilinear:
      return "bilinear";
    case LawModel::Densifying:
      return "densifying";
    case LawModel::DensifyingPlastic:
      return "densifying_plastic";
    case LawModel::Softening:
      return "softening";
    case LawModel::SofteningRate:
      return "softening_rate";
    case LawModel::MomentumFlux:
      return "momentum_flux";
    case LawModel::LateralLinear:
      return "lateral_linear";
    case LawModel::InterfaceSlider:
      return "interface_slider";
  }
  return "";
}

namespace {

// Coulomb slider with a tangential spring and plastic slip memory, both
// directions (cyclic shear): T = k_t (s - s_p), |T| <= mu N.
void evaluateSlider(double mu, double kt, const PathGrid& g, std::vector<double>& out) {
  const double cap = mu * std::abs(g.condition);
  double slip = 0.0;
  for (std::size_t i = 0; i < g.x.size(); ++i) {
    const double trial = kt * (g.x[i] - slip);
    if (std::abs(trial) > cap) {
      const double sign = trial > 0.0 ? 1.0 : -1.0;
      slip = g.x[i] - sign * cap / kt;
      out[i] = sign * cap;
    } else {
      out[i] = trial;
    }
  }
}

}  // namespace

bridge::AxialLawParams axialLaw(LawModel m, const std::vector<double>& theta, const Lockup& lockup) {
  bridge::AxialLawParams p;
  p.model = m == LawModel::Bilinear                                         ? bridge::AxialModel::Bilinear
            : m == LawModel::Densifying || m == LawModel::DensifyingPlastic ? bridge::AxialModel::Densifying
            : m == LawModel::Softening || m == LawModel::SofteningRate      ? bridge::AxialModel::Softening
                                                                       : bridge::AxialModel::ElasticPerfectlyPlastic;
  p.stiffness_N_m = theta[0];
  p.yield_force_N = theta[1];
  if (m == LawModel::SofteningRate) {
    p.rate_coefficient_N_s2_m2 = theta[5];
    p.rate_growth_m = theta[6];
  }
  if (m == LawModel::Softening || m == LawModel::SofteningRate) {
    p.softening_onset_m = theta[2];
    p.softening_stiffness_N_m = theta[3];
    // (fitted as a fraction of the peak: every point of the box is a law)
    p.residual_force_N = theta[4] * theta[1];
    if (!(theta[4] >= 0.0 && theta[4] <= 1.0)) throw Infeasible("residual_ratio must lie in [0, 1]");
  } else if (m != LawModel::ElasticPerfectlyPlastic) {
    p.hardening_stiffness_N_m = theta[2];
    if (!(theta[2] < theta[0])) throw Infeasible("hardening_stiffness_N_m must be below stiffness_N_m");
  }
  if (m == LawModel::Densifying || m == LawModel::DensifyingPlastic) {
    p.densification_onset_m = theta[3];
    p.densification_stiffness_N_m = theta[4];
    if (!(theta[3] < lockup.shortening_m)) throw Infeasible("densification_onset_m must be below the lock-up");
  }
  if (m == LawModel::DensifyingPlastic) {
    // (the law file's conditions: bridge/law_file.cpp)
    p.plastic_densification = true;
    p.densification_unloading_stiffness_N_m = theta[5];
    if (!(theta[5] >= theta[4]))
      throw Infeasible("densification_unloading_stiffness_N_m must be at least densification_stiffness_N_m");
    if (!(theta[3] >= theta[1] / theta[0]))
      throw Infeasible("plastic densification needs densification_onset_m at or past first yield");
  }
  p.lockup_shortening_m = lockup.shortening_m;
  p.lockup_stiffness_N_m = lockup.stiffness_ratio * bridge::looseStiffness(p);
  return p;
}

void evaluateModel(LawModel m, const std::vector<double>& theta, const PathGrid& g, std::vector<double>& out,
                   const Lockup& lockup) {
  out.resize(g.x.size());
  switch (m) {
    case LawModel::ElasticPerfectlyPlastic:
    case LawModel::Bilinear:
    case LawModel::Densifying:
    case LawModel::DensifyingPlastic:
    case LawModel::Softening:
    case LawModel::SofteningRate: {
      const bridge::AxialLawParams p = axialLaw(m, theta, lockup);
      const bool rate = !g.rate.empty();
      if (readsRate(m) && !rate)
        throw bridge::InputError(g.source, "", "the model " + modelName(m) + " needs the curve's time axis");
      double plastic = 0.0;
      for (std::size_t i = 0; i < g.x.size(); ++i) {
        const auto r = bridge::axialResponse(p, g.x[i], plastic, rate ? g.rate[i] : 0.0);
        out[i] = r.force_N;
        plastic = r.plastic_m;
      }
      return;
    }
    case LawModel::MomentumFlux:
      throw std::logic_error("the momentum_flux model is evaluated on its base law (evaluateSet)");
    case LawModel::LateralLinear:
      for (std::size_t i = 0; i < g.x.size(); ++i) out[i] = theta[0] * g.x[i];
      return;
    case LawModel::InterfaceSlider:
      evaluateSlider(theta[0], theta[1], g, out);
      return;
  }
}

void evaluateFluxModel(const bridge::AxialLawParams& base, double flux_kg_m, double growth_m, const PathGrid& g,
                       std::vector<double>& out) {
  if (g.rate.size() != g.x.size())
    throw bridge::InputError(g.source, "", "the momentum flux needs the curve's time axis");
  const bridge::CellSpring law = bridge::cellSpring(base);
  out.resize(g.x.size());
  double plastic = 0.0;
  for (std::size_t i = 0; i < g.x.size(); ++i) {
    const auto r = bridge::cellResponse(law, g.x[i], plastic);
    out[i] = r.force_N + bridge::fillRateForce(0.0, flux_kg_m, growth_m, g.x[i], g.rate[i], r.force_N);
    plastic = r.plastic_m;
  }
}

void evaluateSet(const CurveSet& set, const std::vector<double>& theta, const PathGrid& g, std::vector<double>& out) {
  if (set.model == LawModel::MomentumFlux)
    evaluateFluxModel(set.base, theta.at(0), theta.at(1), g, out);
  else
    evaluateModel(set.model, theta, g, out, set.lockup);
}

double lossValue(double r, const LossSettings& loss) {
  const double c = loss.scale;
  switch (loss.kind) {
    case LossSettings::Kind::L2:
      return r * r;
    case LossSettings::Kind::SoftL1:
      return 2.0 * c * c * (std::sqrt(1.0 + (r / c) * (r / c)) - 1.0);
    case LossSettings::Kind::Huber:
      return std::abs(r) <= c ? r * r : 2.0 * c * std::abs(r) - c * c;
  }
  return r * r;
}

double lossWeight(double r, const LossSettings& loss) {
  const double c = loss.scale;
  switch (loss.kind) {
    case LossSettings::Kind::L2:
      return 1.0;
    case LossSettings::Kind::SoftL1:
      return 1.0 / std::sqrt(1.0 + (r / c) * (r / c));
    case LossSettings::Kind::Huber:
      return std::abs(r) <= c ? 1.0 : c / std::abs(r);
  }
  return 1.0;
}

std::vector<double> residuals(const CurveSet& set, const std::vector<double>& theta) {
  std::vector<double> r, model;
  for (const auto& g : set.grids) {
    evaluateSet(set, theta, g, model);
    for (std::size_t i = 0; i < g.x.size(); ++i) r.push_back((model[i] - g.y[i]) / g.scale);
  }
  return r;
}

double misfit(const CurveSet& set, const std::vector<double>& theta) {
  double total = 0.0;
  std::vector<double> model;
  for (const auto& g : set.grids) {
    evaluateSet(set, theta, g, model);
    const double a = g.effectivePoints() / static_cast<double>(g.x.size());
    double sum = 0.0;
    for (std::size_t i = 0; i < g.x.size(); ++i) sum += lossValue((model[i] - g.y[i]) / g.scale, set.loss);
    total += a * sum;
  }
  return total;
}

double effectiveObservations(const CurveSet& set) {
  double n = 0.0;
  for (const auto& g : set.grids) n += g.effectivePoints();
  return n;
}

double residualVariance(const CurveSet& set, const std::vector<double>& theta) {
  double sum = 0.0, n = 0.0;
  std::vector<double> model;
  for (const auto& g : set.grids) {
    PathGrid raw = g;
    raw.x = g.raw_x;
    raw.y = g.raw_y;
    raw.rate = g.raw_rate;
    evaluateSet(set, theta, raw, model);
    for (std::size_t i = 0; i < model.size(); ++i) sum += lossValue((model[i] - raw.y[i]) / g.scale, set.loss);
    n += static_cast<double>(model.size());
  }
  const double dof = n - static_cast<double>(theta.size());
  return dof > 0.0 ? sum / dof : std::numeric_limits<double>::infinity();
}

double normalisedRms(const CurveSet& set, const std::vector<double>& theta) {
  const auto r = residuals(set, theta);
  double sum = 0.0;
  for (double v : r) sum += v * v;
  return std::sqrt(sum / static_cast<double>(r.size()));
}

}  // namespace gabion::fitting
