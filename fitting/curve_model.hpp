#pragma once
/// \file
/// Curves on a common grid, the macro-law models evaluated along a loading
/// path, and the robust misfit between them (docs/fitting.md, "Objective").
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "bridge/curve.hpp"
#include "bridge/laws/cell_axial_law.hpp"

namespace gabion::fitting {

/// A curve resampled on its loading path: `points` equal steps of the path
/// length s = sum |dx| (which keeps increasing when x reverses, so loading and
/// unloading branches are both sampled), plus every turning point of x, so the
/// peak of a loading/unloading cycle is never cut off.
struct PathGrid {
  std::string source;                ///< where the curve came from
  std::vector<double> x, y;          ///< resampled, in path order
  double scale = 1.0;                ///< normalisation: max |y| of the data (residual = error / scale)
  std::size_t raw_points = 0;        ///< points of the original curve
  std::vector<double> raw_x, raw_y;  ///< the original curve (for the noise estimate)
  /// The rate dx/dt at each point (m/s), resampled and original (central
  /// differences of the curve's time axis); empty when the curve has none.
  std::vector<double> rate, raw_rate;
  double condition = 0.0;  ///< normal force (interface, N) or impact velocity (m/s); 0 otherwise
  std::string replicate;   ///< replicate label (curves with the same label are fitted together)
  /// Independent observations this grid stands for: min(raw points, grid points).
  double effectivePoints() const;
};

/// Resamples `c` on its path (see PathGrid). Throws bridge::InputError when the
/// curve has no force range (max |y| = 0).
PathGrid resampleOnPath(const bridge::Curve& c, std::size_t points);

/// The closed set of laws the fitting identifies (each a pure function of a path).
enum class LawModel {
  ElasticPerfectlyPlastic,  ///< axial/impact: stiffness_N_m, yield_force_N
  Bilinear,                 ///< axial/impact: + hardening_stiffness_N_m
  Densifying,               ///< axial/impact: + densification_onset_m, densification_stiffness_N_m
  DensifyingPlastic,        ///< axial: densifying with plastic densification, + densification_unloading_stiffness_N_m
                            ///< (the dense part's unloading: a compacted cell keeps part of its compaction)
  Softening,       ///< impact: stiffness_N_m, yield_force_N (the peak), softening_onset_m, softening_stiffness_N_m,
                   ///< residual_ratio (F_r / F_y)
  SofteningRate,   ///< impact: softening's + rate_coefficient_N_s2_m2, rate_growth_m (the overstress
                   ///< c r^2 min(1, u / u_a)); needs the curves' time axis (PathGrid::rate)
  MomentumFlux,    ///< axial: the momentum flux alone, momentum_flux_kg_m and momentum_flux_growth_m, on a
                   ///< law already fitted (CurveSet::base), against curves at other plate speeds; needs
                   ///< their time axis
  LateralLinear,   ///< lateral force = reaction_coefficient * axial force
  InterfaceSlider  ///< shear force: spring tangential_stiffness_N_m capped at friction * normal force
};

/// Parameter names of a model, in the order of the parameter vector.
std::vector<std::string> parameterNames(LawModel m);
/// "elastic_perfectly_plastic", "bilinear", "lateral_linear", "interface_slider".
std::string modelName(LawModel m);

/// The lock-up every axial and impact law carries (bridge/laws/cell_axial_law.hpp):
/// set from the fill's porosity, not fitted, and part of the model the curves
/// are compared with.
struct Lockup {
  double shortening_m = std::numeric_limits<double>::infinity();  ///< u_L (m)
  double stiffness_ratio = 10.0;                                  ///< k_L / bridge::looseStiffness
};

/// The axial/impact law of parameters `theta` of model `m` (one of the four
/// axial models) with the lock-up `lockup`. Throws Infeasible for a hardening
/// tangent not below the stiffness, a densification onset not below the
/// lock-up, or a residual ratio above 1.
bridge::AxialLawParams axialLaw(LawModel m, const std::vector<double>& theta, const Lockup& lockup);

/// True for a model that reads the curves' rate (PathGrid::rate).
inline bool readsRate(LawModel m) {
  return m == LawModel::SofteningRate || m == LawModel::MomentumFlux;
}

/// Model values along the path of `g` (same length as g.x). Axial and impact laws
/// are evaluated by bridge::axialResponse with plastic memory (axialLaw), at
/// the curve's rate where it has one. Throws bridge::InputError for a model
/// that reads the rate on a curve without a time axis.
void evaluateModel(LawModel m, const std::vector<double>& theta, const PathGrid& g, std::vector<double>& out,
                   const Lockup& lockup = {});

/// Loss applied to normalised residuals (docs/fitting.md).
struct LossSettings {
  enum class Kind { L2, SoftL1, Huber };
  Kind kind = Kind::SoftL1;
  double scale = 0.05;  ///< residual (fraction of the curve's force range) where the loss turns linear
};

/// rho(r): r^2 near 0 for every kind; soft-L1: 2 c^2 (sqrt(1 + (r/c)^2) - 1); Huber:
/// r^2 for |r| <= c, else 2 c |r| - c^2.
double lossValue(double r, const LossSettings& loss);
/// IRLS weight rho'(r) / (2 r) (1 for L2), used for the covariance at the optimum.
double lossWeight(double r, const LossSettings& loss);

/// The law `base` with the momentum flux c_m (kg/m) and its growth u_a (m)
/// along the path of `g` at its rate: the law's force
/// (bridge::cellResponse) plus bridge::fillRateForce, as the macro model
/// adds them. Throws bridge::InputError for a curve without a time axis.
void evaluateFluxModel(const bridge::AxialLawParams& base, double flux_kg_m, double growth_m, const PathGrid& g,
                       std::vector<double>& out);

/// One law to fit against a set of curves.
struct CurveSet {
  LawModel model = LawModel::ElasticPerfectlyPlastic;
  std::vector<PathGrid> grids;
  LossSettings loss;
  Lockup lockup;
  bridge::AxialLawParams base;  ///< MomentumFlux: the law whose momentum flux is fitted
};

/// The model of `set` along `g` (evaluateModel; evaluateFluxModel on
/// set.base for MomentumFlux).
void evaluateSet(const CurveSet& set, const std::vector<double>& theta, const PathGrid& g, std::vector<double>& out);

/// Normalised residuals (model - data) / scale of every grid point, curve after curve.
std::vector<double> residuals(const CurveSet& set, const std::vector<double>& theta);
/// Misfit: sum over points of a_c rho(r), a_c = effective/grid points of curve c
/// (so a curve counts for its independent observations, not its grid size).
double misfit(const CurveSet& set, const std::vector<double>& theta);
/// Effective number of observations: sum of effectivePoints().
double effectiveObservations(const CurveSet& set);
/// Noise variance of the normalised residuals, estimated on the ORIGINAL points
/// (resampling interpolates, which would understate it): sum rho(r) / (n_raw - p),
/// with p = theta.size(). Infinite when n_raw <= p.
double residualVariance(const CurveSet& set, const std::vector<double>& theta);
/// Normalised RMS error sqrt(mean r^2) over all grid points (no robust loss).
double normalisedRms(const CurveSet& set, const std::vector<double>& theta);

}  // namespace gabion::fitting
