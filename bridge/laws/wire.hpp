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

/// A wire's backbone in force (N) against engineering strain (-).
struct WireCurve {
  std::vector<double> strain;   ///< as the table (after any double-twist scaling)
  std::vector<double> force_N;  ///< force at each strain
  /// Elastic force per unit strain, E A (N).
  double elasticForce() const { return force_N[0] / strain[0]; }
  /// Strain beyond which the wire breaks.
  double ruptureStrain() const { return strain.back(); }
  bool operator==(const WireCurve& o) const { return strain == o.strain && force_N == o.force_N; }
};

/// Area of a wire of diameter d (m^2).
inline double wireSection(double diameter_m) {
  return 0.25 * 3.14159265358979323846 * diameter_m * diameter_m;
}

/// A single wire of diameter d: the table times the section.
inline WireCurve wireCurve(const WireStressStrain& t, double diameter_m) {
  WireCurve c;
  c.strain = t.strain;
  const double A = wireSection(diameter_m);
  for (const double s : t.stress_Pa) c.force_N.push_back(s * A);
  return c;
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
  WireCurve c = wireCurve(t, diameter_m);
  for (double& f : c.force_N) f *= 2.0;
  c.strain[0] /= p.lambda_k;
  for (std::size_t k = 1; k < c.strain.size(); ++k) c.strain[k] *= p.lambda_eps;
  return c;
}

/// What is wrong with a double twist made from table t, or empty.
inline std::string checkDoubleTwist(const WireStressStrain& t, const DoubleTwistParams& p) {
  if (!(p.lambda_k > 0.0 && p.lambda_k <= 1.0)) return "lambda_k must be in (0, 1]";
  if (!(p.lambda_eps > 0.0 && p.lambda_eps <= 1.0)) return "lambda_eps must be in (0, 1]";
  const WireCurve c = doubleTwistCurve(t, 1.0, p);
  WireStressStrain scaled{c.strain, c.force_N};
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

/// Force on the backbone at strain eps, for curve.strain[0] <= eps <= rupture.
inline double wireBackbone(const WireCurve& c, double eps) {
  std::size_t k = 1;
  while (k + 1 < c.strain.size() && eps > c.strain[k]) ++k;
  const double s0 = c.strain[k - 1], s1 = c.strain[k];
  return c.force_N[k - 1] + (c.force_N[k] - c.force_N[k - 1]) * (eps - s0) / (s1 - s0);
}

/// Plastic work per unit rest length (N) of a wire that reached eps_r on the
/// backbone: area under the backbone up to eps_r minus the elastic triangle
/// F_b(eps_r)^2 / (2 E_F).
inline double wirePlasticWork(const WireCurve& c, double eps_r) {
  if (eps_r <= c.strain[0]) return 0.0;
  double area = 0.5 * c.force_N[0] * c.strain[0];
  std::size_t k = 1;
  for (; k < c.strain.size() && c.strain[k] <= eps_r; ++k)
    area += 0.5 * (c.force_N[k] + c.force_N[k - 1]) * (c.strain[k] - c.strain[k - 1]);
  double f = c.force_N[k - 1];
  if (k < c.strain.size()) {
    f = wireBackbone(c, eps_r);
    area += 0.5 * (f + c.force_N[k - 1]) * (eps_r - c.strain[k - 1]);
  }
  return area - 0.5 * f * f / c.elasticForce();
}

/// The wire's response at length L.
struct WireResponse {
  double force_N = 0.0;    ///< tension >= 0 (pulls the ends together)
  double elastic_J = 0.0;  ///< elastic energy stored; when the wire breaks, what it held at rupture
  bool breaks = false;     ///< strain beyond the last point: the wire stops acting
};

/// Advances the state to length L (m) and returns the force. A wire that
/// breaks leaves its state at the last point of the curve.
inline WireResponse wireResponse(const WireCurve& c, double rest_length_m, WireState& s, double length_m) {
  const double E = c.elasticForce();
  const double eps = (length_m - rest_length_m) / rest_length_m;
  WireResponse out;
  if (eps > c.ruptureStrain()) {
    // It held the elastic energy of its last point when it went.
    const double f = c.force_N.back();
    s.reached_strain = c.ruptureStrain();
    s.plastic_strain = s.reached_strain - f / E;
    out.breaks = true;
    out.elastic_J = 0.5 * f * f / E * rest_length_m;
    return out;
  }
  const double elastic = E * (eps - s.plastic_strain);
  double f = std::max(0.0, elastic);
  if (eps > std::max(s.reached_strain, c.strain[0])) {
    // Beyond the largest strain reached: on the backbone (its slopes never
    // exceed E, so the elastic trial is never below it there).
    f = std::min(f, wireBackbone(c, eps));
    s.reached_strain = eps;
    s.plastic_strain = eps - f / E;
  }
  out.force_N = f;
  out.elastic_J = 0.5 * f * f / E * rest_length_m;
  return out;
}

/// Plastic work dissipated by a wire in state s (J).
inline double wireDissipatedEnergy(const WireCurve& c, double rest_length_m, const WireState& s) {
  return rest_length_m * wirePlasticWork(c, s.reached_strain);
}

}  // namespace gabion::bridge
