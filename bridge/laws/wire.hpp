#pragma once
/// \file
/// Wire law of the netting (Bertrand et al. 2008, as summarised in
/// docs/netting.md): the force a wire carries between two nodes as a function
/// of their distance only. Tension only, elastoplastic with rupture:
///
/// - the backbone is a piecewise-linear force-strain curve through the
///   points (strain_k, force_k), from the origin to the first point (elastic,
///   stiffness E_F = force_0 / strain_0 per unit strain) and on through the
///   others; engineering strain eps = (L - L0) / L0;
/// - loading beyond the largest strain reached follows the backbone;
/// - below it the wire unloads and reloads elastically, F = E_F (eps - eps_p),
///   from the current plastic strain eps_p; a wire shorter than its plastic
///   length is slack (F = 0);
/// - past the last point the wire breaks for good.
///
/// The plastic work is a function of the state: a wire that reached strain
/// eps_r on the backbone has dissipated L0 (area under the backbone up to
/// eps_r - F_b(eps_r)^2 / (2 E_F)), so the energy ledger is exact at any step.
///
/// Curves come from a stress-strain table times the wire section
/// (wireCurve), and for a double twist from the two-wire rule
/// (doubleTwistCurve): stiffness scaled by lambda_k, failure strains by
/// lambda_eps.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace gabion::bridge {

/// Engineering stress-strain table of one wire (the law's input).
struct WireStressStrain {
  std::vector<double> strain;     ///< strictly increasing, > 0 (-)
  std::vector<double> stress_Pa;  ///< >= 0, first > 0 (Pa)
};

/// The published single-wire table of 2.7 mm gabion mesh wire
/// (../shared/reference/wire-netting.md): E = 130 GPa, rupture after 35 %.
inline WireStressStrain defaultWireTable() {
  return {{0.0019231, 0.0192, 0.05, 0.15, 0.25, 0.30, 0.35},
          {250.0e6, 321.95e6, 382.92e6, 512.19e6, 558.54e6, 565.85e6, 565.85e6}};
}

/// What is wrong with a table, or empty if nothing is. `at` names the point
/// (index) the message speaks of, -1 for the whole table.
struct WireTableIssue {
  std::string message;
  int at = -1;
  bool strain = true;  ///< the strain (true) or the stress (false) of point `at`
};
inline WireTableIssue checkWireTable(const WireStressStrain& t) {
  if (t.strain.empty() || t.strain.size() != t.stress_Pa.size())
    return {"needs at least one point, as many strains as stresses", -1, true};
  for (std::size_t k = 0; k < t.strain.size(); ++k) {
    const int i = static_cast<int>(k);
    if (!(t.strain[k] > 0.0) || !std::isfinite(t.strain[k])) return {"strain must be finite and > 0", i, true};
    if (k > 0 && !(t.strain[k] > t.strain[k - 1]))
      return {"strains must increase strictly from point to point", i, true};
    if (!(t.stress_Pa[k] >= 0.0) || !std::isfinite(t.stress_Pa[k])) return {"stress must be finite and >= 0", i, false};
  }
  if (!(t.stress_Pa[0] > 0.0)) return {"the first stress sets the elastic modulus and must be > 0", 0, false};
  const double E = t.stress_Pa[0] / t.strain[0];
  for (std::size_t k = 1; k < t.strain.size(); ++k) {
    const double slope = (t.stress_Pa[k] - t.stress_Pa[k - 1]) / (t.strain[k] - t.strain[k - 1]);
    if (slope > E * (1.0 + 1e-12))
      return {
          "stress rises faster than the elastic modulus (first point) before this point: elastic unloading "
          "from such a curve is not defined",
          static_cast<int>(k), false};
  }
  return {};
}

/// A wire's backbone in force (N) against engineering strain (-), with what
/// the law needs at every step (elastic force per unit strain, its inverse,
/// the slope of each segment) computed once here.
class WireCurve {
 public:
  WireCurve() = default;
  /// Points (strain, force): strains strictly increasing and > 0, forces >= 0
  /// with the first > 0 (checkWireTable says what is wrong otherwise).
  WireCurve(std::vector<double> strain, std::vector<double> force_N)
      : strain_(std::move(strain)), force_(std::move(force_N)) {
    if (strain_.empty() || strain_.size() != force_.size()) return;
    elastic_ = force_[0] / strain_[0];
    inv_elastic_ = 1.0 / elastic_;
    slope_.assign(strain_.size(), elastic_);
    for (std::size_t k = 1; k < strain_.size(); ++k)
      slope_[k] = (force_[k] - force_[k - 1]) / (strain_[k] - strain_[k - 1]);
  }
  const std::vector<double>& strain() const { return strain_; }
  const std::vector<double>& force() const { return force_; }
  /// Elastic force per unit strain, E A (N).
  double elasticForce() const { return elastic_; }
  double inverseElasticForce() const { return inv_elastic_; }
  /// Slope of the segment ending at point k (point 0: the elastic line).
  double slope(std::size_t k) const { return slope_[k]; }
  /// Strain beyond which the wire breaks.
  double ruptureStrain() const { return strain_.back(); }
  bool operator==(const WireCurve& o) const { return strain_ == o.strain_ && force_ == o.force_; }

 private:
  std::vector<double> strain_, force_, slope_;
  double elastic_ = 0.0, inv_elastic_ = 0.0;
};

/// Area of a wire of diameter d (m^2).
inline double wireSection(double diameter_m) {
  return 0.25 * 3.14159265358979323846 * diameter_m * diameter_m;
}

/// A single wire of diameter d: the table times the section.
inline WireCurve wireCurve(const WireStressStrain& t, double diameter_m) {
  const double A = wireSection(diameter_m);
  std::vector<double> force;
  for (const double s : t.stress_Pa) force.push_back(s * A);
  return {t.strain, force};
}

/// Double-twist parameters (Bertrand et al. 2008; ../shared/reference/wire-netting.md).
struct DoubleTwistParams {
  double lambda_k = 0.66;   ///< factor on the elastic stiffness of the two wires (-), in (0, 1]
  double lambda_eps = 0.4;  ///< factor on the strains after the first point (-), in (0, 1]
};

/// The backbone of a double twist: two wires twisted together, so twice the
/// force of one at every point; stiffer than one wire but less than two
/// straight ones (elastic stiffness lambda_k x 2 E A / L0: the first point
/// moves to strain eps_0 / lambda_k), and breaking earlier (the strains of
/// the later points times lambda_eps). Returns an empty curve when the
/// factors push the first point past the second (lambda_k too small for
/// lambda_eps): checkDoubleTwist says so.
inline WireCurve doubleTwistCurve(const WireStressStrain& t, double diameter_m, const DoubleTwistParams& p) {
  const double A = wireSection(diameter_m);
  std::vector<double> strain = t.strain, force;
  for (const double s : t.stress_Pa) force.push_back(2.0 * s * A);
  strain[0] /= p.lambda_k;
  for (std::size_t k = 1; k < strain.size(); ++k) strain[k] *= p.lambda_eps;
  return {strain, force};
}

/// What is wrong with a double twist made from table t, or empty.
inline std::string checkDoubleTwist(const WireStressStrain& t, const DoubleTwistParams& p) {
  if (!(p.lambda_k > 0.0 && p.lambda_k <= 1.0)) return "lambda_k must be in (0, 1]";
  if (!(p.lambda_eps > 0.0 && p.lambda_eps <= 1.0)) return "lambda_eps must be in (0, 1]";
  const WireCurve c = doubleTwistCurve(t, 1.0, p);
  WireStressStrain scaled{c.strain(), c.force()};
  const WireTableIssue issue = checkWireTable(scaled);
  if (!issue.message.empty())
    return "the twist's curve (strain_0 / lambda_k, then strains x lambda_eps) is not a valid curve: " + issue.message +
           " (point " + std::to_string(issue.at) + "); raise lambda_k or lambda_eps";
  return {};
}

/// A wire link: its backbone and rest length.
struct WireLinkParams {
  WireCurve curve;
  double rest_length_m = 0.0;  ///< L0 (m), > 0
  /// Elastic stiffness E A / L0 (N/m).
  double stiffness() const { return curve.elasticForce() / rest_length_m; }
};

/// What a wire remembers between steps.
struct WireState {
  double plastic_strain = 0.0;  ///< eps_p: strain at which the unloaded wire is slack
  double reached_strain = 0.0;  ///< largest strain reached on the backbone (0: still elastic)
};

/// Force on the backbone at strain eps, for strain(0) <= eps <= rupture.
inline double wireBackbone(const WireCurve& c, double eps) {
  const std::vector<double>& strain = c.strain();
  std::size_t k = 1;
  while (k + 1 < strain.size() && eps > strain[k]) ++k;
  return c.force()[k - 1] + c.slope(k) * (eps - strain[k - 1]);
}

/// Plastic work per unit rest length (N) of a wire that reached eps_r on the
/// backbone: area under the backbone up to eps_r minus the elastic triangle
/// F_b(eps_r)^2 / (2 E_F).
inline double wirePlasticWork(const WireCurve& c, double eps_r) {
  const std::vector<double>&strain = c.strain(), &force = c.force();
  if (eps_r <= strain[0]) return 0.0;
  double area = 0.5 * force[0] * strain[0];
  std::size_t k = 1;
  for (; k < strain.size() && strain[k] <= eps_r; ++k)
    area += 0.5 * (force[k] + force[k - 1]) * (strain[k] - strain[k - 1]);
  double f = force[k - 1];
  if (k < strain.size()) {
    f = wireBackbone(c, eps_r);
    area += 0.5 * (f + force[k - 1]) * (eps_r - strain[k - 1]);
  }
  return area - 0.5 * f * f * c.inverseElasticForce();
}

/// Elastic energy (J) of a wire of rest length L0 carrying force F.
inline double wireElasticEnergy(const WireCurve& c, double rest_length_m, double force_N) {
  return 0.5 * force_N * force_N * c.inverseElasticForce() * rest_length_m;
}

/// The wire's response at length L.
struct WireResponse {
  double force_N = 0.0;  ///< tension >= 0 (pulls the ends together)
  bool breaks = false;   ///< strain beyond the last point: the wire stops acting
};

/// The wire's elastic line, F = max(0, E A (eps - eps_p)) (N): its force
/// wherever it is below its backbone (loading again, unloading, slack).
/// Branch-free: the link stage evaluates it in SIMD lanes.
inline double wireElasticLineForce(double elastic_force_N, double eps, double plastic_strain) {
  const double f = elastic_force_N * (eps - plastic_strain);
  return 0.0 < f ? f : 0.0;  // (std::max(0.0, f): 0 for a NaN strain too)
}

/// Whether strain eps takes a wire off its elastic line: past the largest
/// strain it reached on the backbone (at least the curve's first point), or
/// past rupture. Where it does not, wireResponse gives wireElasticLineForce
/// and leaves the state as it is.
inline bool wireLeavesElasticLine(double eps, double reached_strain, double first_strain, double rupture_strain) {
  const double backbone = reached_strain < first_strain ? first_strain : reached_strain;  // (std::max)
  return eps > rupture_strain || eps > backbone;
}

/// Advances the state to strain eps = (L - L0) / L0 and returns the force. A
/// wire that breaks leaves its state at the last point of the curve (the
/// energy it held then: wireElasticEnergy of its last force).
inline WireResponse wireResponse(const WireCurve& c, WireState& s, double eps) {
  WireResponse out;
  if (eps > c.ruptureStrain()) {
    s.reached_strain = c.ruptureStrain();
    s.plastic_strain = s.reached_strain - c.force().back() * c.inverseElasticForce();
    out.breaks = true;
    return out;
  }
  double f = wireElasticLineForce(c.elasticForce(), eps, s.plastic_strain);
  if (eps > std::max(s.reached_strain, c.strain()[0])) {
    // Beyond the largest strain reached: on the backbone (its slopes never
    // exceed E, so the elastic trial is never below it there).
    f = std::min(f, wireBackbone(c, eps));
    s.reached_strain = eps;
    s.plastic_strain = eps - f * c.inverseElasticForce();
  }
  out.force_N = f;
  return out;
}

/// The same at length L (m) of a wire of rest length L0.
inline WireResponse wireResponse(const WireCurve& c, double rest_length_m, WireState& s, double length_m) {
  return wireResponse(c, s, (length_m - rest_length_m) / rest_length_m);
}

/// Plastic work dissipated by a wire in state s (J).
inline double wireDissipatedEnergy(const WireCurve& c, double rest_length_m, const WireState& s) {
  return rest_length_m * wirePlasticWork(c, s.reached_strain);
}

}  // namespace gabion::bridge
