#pragma once
/// \file
/// Bending of a wire between two netting nodes: the wire as a beam clamped
/// in its nodes, which turn (docs/netting.md, Bending). The pin-jointed
/// netting of the paper carries force along its wires only, so its
/// hexagons change shape under no force at all and a filled basket slumps
/// like a bag; a real mesh resists through the bending of its wires between
/// the twists that clamp them.
///
/// The beam is the parallel bond of bonded-particle models (Potyondy and
/// Cundall 2004), with the stiffnesses of an Euler-Bernoulli beam of
/// bending stiffness E I and length L:
///
/// - a shear force F_s (normal to the wire, on node b; -F_s on a) grows
///   with the relative displacement of the wire's mid-point as each node
///   carries it, k_s = 12 E I / L^3;
/// - a bending moment M_b (normal to the wire, on b; -M_b on a) grows with
///   the relative turn of the nodes, k_b = E I / L;
/// - the torques on the nodes are tau_b = M_b - (L/2) n x F_s and
///   tau_a = -M_b - (L/2) n x F_s (n: unit vector a -> b), so that one node
///   turned by phi with the other held gives 4 E I phi / L at the turned end
///   and 2 E I phi / L at the held one, and a sway delta gives 12 E I
///   delta / L^3 with end moments 6 E I delta / L^2: the beam's exact
///   stiffness matrix for small deformations.
///
/// - a torsional moment T (along the wire, on b; -T on a) grows with the
///   relative spin of the nodes about the wire, k_t = G J / L = E I / ((1 +
///   nu) L) for round wires (J = 2 I, G = E / (2 (1 + nu)), nu = 0.3 for
///   steel). Without it a node on a straight wire (a bead) spins freely
///   about the wire and keeps any spin it is given. T is held as the axial
///   part of the moment vector.
///
/// All actions are updated incrementally and turned with the wire (the
/// minimal rotation from its last direction to its new one, and its mean
/// spin about itself), so a rigid motion of the pair stores nothing.
///
/// Plastic hinge: an end torque is at most the section's plastic moment
/// M_p = sigma_y d^3 / 6 (times the wires in a twist). A step that would
/// exceed it scales both actions back until the larger end torque is M_p;
/// the energy this takes from the beam is dissipated (plastic work), so
/// the ledger stays exact.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "bridge/small_angle.hpp"

namespace gabion::bridge {

struct WireBeamParams {
  double shear_N_m = 0.0;                                               ///< k_s = 12 E I / L^3 (N/m)
  double bending_N_m_rad = 0.0;                                         ///< k_b = E I / L (N m/rad); 0: no beam
  double plastic_moment_N_m = std::numeric_limits<double>::infinity();  ///< M_p (N m)
  double length_m = 0.0;                                                ///< L, the lever of the shear force (m)
  bool active() const { return bending_N_m_rad > 0.0; }
  /// Torsional stiffness (N m/rad): G J / L = E I / ((1 + nu) L), nu = 0.3.
  double torsion_N_m_rad() const { return bending_N_m_rad * (1.0 / 1.3); }
  /// Rotational stiffness at one end with the other held (N m/rad): 4 E I / L.
  double endStiffness() const { return bending_N_m_rad + 0.25 * shear_N_m * length_m * length_m; }
};

/// A beam's state: its actions now (on node b) and its plastic work so far.
struct WireBeamState {
  Eigen::Vector3d shear_N = Eigen::Vector3d::Zero();
  Eigen::Vector3d moment_N_m = Eigen::Vector3d::Zero();  ///< bending (normal to the wire) + torsion (along it)
  double dissipated_J = 0.0;
};

/// The beam of `wires` round wires of diameter d side by side (a double
/// twist: two), Young's modulus E and yield stress sigma_y, length L.
inline WireBeamParams wireBeam(double youngs_modulus_Pa, double yield_stress_Pa, double diameter_m, double length_m,
                               double wires = 1.0) {
  const double I = 3.14159265358979323846 * std::pow(diameter_m, 4) / 64.0;
  const double EI = wires * youngs_modulus_Pa * I;
  WireBeamParams p;
  p.shear_N_m = 12.0 * EI / (length_m * length_m * length_m);
  p.bending_N_m_rad = EI / length_m;
  p.plastic_moment_N_m = wires * yield_stress_Pa * diameter_m * diameter_m * diameter_m / 6.0;
  p.length_m = length_m;
  return p;
}

struct WireBeamResponse {
  Eigen::Vector3d force_b = Eigen::Vector3d::Zero();   ///< on b (N); a takes minus it
  Eigen::Vector3d torque_a = Eigen::Vector3d::Zero();  ///< on a (N m)
  Eigen::Vector3d torque_b = Eigen::Vector3d::Zero();  ///< on b (N m)
};

/// A vector of three doubles for the beam's arithmetic: plain members, so
/// that a loop over beams keeps each in registers and vectorises (Eigen's
/// fixed vectors are copied there as aggregates, which stops it). Dot and
/// cross products in Eigen's order of operations.
struct BeamVec {
  double x = 0.0, y = 0.0, z = 0.0;
  BeamVec() = default;
  BeamVec(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  explicit BeamVec(const Eigen::Vector3d& v) : x(v.x()), y(v.y()), z(v.z()) {}
  Eigen::Vector3d eigen() const { return {x, y, z}; }
};
[[gnu::always_inline]] inline BeamVec operator+(const BeamVec& a, const BeamVec& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
[[gnu::always_inline]] inline BeamVec operator-(const BeamVec& a, const BeamVec& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
[[gnu::always_inline]] inline BeamVec operator-(const BeamVec& a) {
  return {-a.x, -a.y, -a.z};
}
[[gnu::always_inline]] inline BeamVec operator*(double s, const BeamVec& a) {
  return {s * a.x, s * a.y, s * a.z};
}
[[gnu::always_inline]] inline double dot(const BeamVec& a, const BeamVec& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
[[gnu::always_inline]] inline BeamVec cross(const BeamVec& a, const BeamVec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// The turn of a wire from n0 to n1 (unit vectors) applied to v, normal to
/// the wire: the minimal rotation taking n0 to n1 (axis = n0 x n1, c = n0 .
/// n1, k = 1 / (1 + c), or 0 for a wire turned back on itself: no turn),
/// then a twist about n1 of cosine ct and sine st. Branch-free.
[[gnu::always_inline]] inline BeamVec wireTurn(const BeamVec& v, const BeamVec& n1, const BeamVec& axis, double c,
                                               double k, double ct, double st) {
  // Rodrigues with the unnormalised axis: c v + a x v + a (a . v) / (1 + c).
  const BeamVec r = c * v + cross(axis, v) + (dot(axis, v) * k) * axis;
  const bool turns = k > 0.0;
  BeamVec w(turns ? r.x : v.x, turns ? r.y : v.y, turns ? r.z : v.z);
  w = w - dot(w, n1) * n1;  // stays normal to the wire (rounding)
  return ct * w + st * cross(n1, w);
}

/// A beam's actions (BeamVec) while an increment is computed.
struct WireBeamActions {
  BeamVec shear, moment;
  double dissipated = 0.0;
};

/// Elastic energy of actions on a wire along the unit vector n (J).
[[gnu::always_inline]] inline double wireBeamElasticEnergy(const WireBeamParams& p, const WireBeamActions& s,
                                                           const BeamVec& n) {
  // (the bending part |M|^2 - T^2 over k_b and the torsion's T^2 over k_t
  // = k_b / 1.3 in one division: a beam's loop is bound by its divisions)
  const double t = dot(s.moment, n);
  return 0.5 * dot(s.shear, s.shear) / p.shear_N_m +
         0.5 * (dot(s.moment, s.moment) + 0.3 * (t * t)) / p.bending_N_m_rad;
}

/// Elastic energy held by a beam whose wire lies along the unit vector n
/// (J): |F_s|^2 / (2 k_s) + |M_b|^2 / (2 k_b) + T^2 / (2 k_t).
inline double wireBeamElasticEnergy(const WireBeamParams& p, const WireBeamState& s, const Eigen::Vector3d& n) {
  return wireBeamElasticEnergy(p, WireBeamActions{BeamVec(s.shear_N), BeamVec(s.moment_N_m), s.dissipated_J},
                               BeamVec(n));
}

/// One increment of the beam, the arithmetic of every path: the chord (a
/// -> b) went from c0 to c1 (both of some length), the nodes turned by
/// dtheta_a and dtheta_b; `trig(twist, st, ct)` gives the sine and cosine
/// of the step's twist (bridge/small_angle.hpp: stepSinCos, or
/// smallAngleSinCos where the caller checks the twist after). The actions are turned with the wire, the
/// increments added, the plastic hinge's cap applied. Branch-free (selects
/// only), so that a loop over beams vectorises. Returns the force on b; the
/// torques on a and b into torque_a and torque_b, the twist into `twist`.
template <class Trig>
[[gnu::always_inline]] inline BeamVec wireBeamIncrement(const WireBeamParams& p, WireBeamActions& s, const BeamVec& c0,
                                                        const BeamVec& c1, const BeamVec& dtheta_a,
                                                        const BeamVec& dtheta_b, Trig trig, BeamVec& torque_a,
                                                        BeamVec& torque_b, double& twist) {
  const double L1 = std::sqrt(dot(c1, c1));
  const BeamVec n0 = (1.0 / std::sqrt(dot(c0, c0))) * c0, n1 = (1.0 / L1) * c1, mid = 0.5 * (c0 + c1);
  const BeamVec sum = dtheta_a + dtheta_b, rel = dtheta_b - dtheta_a;
  // (the mean spin about the wire's middle direction, to second order)
  twist = 0.25 * dot(sum, n0 + n1);
  double ct = 1.0, st = 0.0;
  trig(twist, st, ct);
  const BeamVec axis = cross(n0, n1);
  const double c = dot(n0, n1), k = c > -0.999 ? 1.0 / (1.0 + c) : 0.0;
  // (bending turned, torsion along the wire)
  s.moment = wireTurn(s.moment, n1, axis, c, k, ct, st) + dot(s.moment, n0) * n1;
  s.shear = wireTurn(s.shear, n1, axis, c, k, ct, st);
  // The wire's mid-point as each node carries it: b's relative to a's.
  BeamVec slip = (c1 - c0) - 0.5 * cross(sum, mid);
  slip = slip - dot(slip, n1) * n1;
  s.shear = s.shear - p.shear_N_m * slip;
  const double spin = dot(rel, n1);
  s.moment = s.moment - (p.bending_N_m_rad * (rel - spin * n1) + (p.torsion_N_m_rad() * spin) * n1);
  const BeamVec lever = (0.5 * L1) * cross(n1, s.shear);
  const BeamVec up = s.moment + lever, down = s.moment - lever;
  const double peak2 = std::max(dot(up, up), dot(down, down));
  const bool yields = peak2 > p.plastic_moment_N_m * p.plastic_moment_N_m;
  const double scale = yields ? p.plastic_moment_N_m / std::sqrt(peak2) : 1.0;
  const double lost = (1.0 - scale * scale) * wireBeamElasticEnergy(p, s, n1);
  s.dissipated = yields ? s.dissipated + lost : s.dissipated;
  s.shear = scale * s.shear;  // (by 1: unchanged)
  s.moment = scale * s.moment;
  const BeamVec lv = (0.5 * L1) * cross(n1, s.shear);
  torque_a = -s.moment - lv;
  torque_b = s.moment - lv;
  return s.shear;
}

/// Whether an increment is one that the series path answers exactly as
/// wireBeamStep does: a chord of some length before and after, a twist
/// within the series' range.
[[gnu::always_inline]] inline bool wireBeamSeriesAnswers(double c0_squared, double c1_squared, double twist) {
  return c0_squared > 0.0 && c1_squared > 0.0 && std::fabs(twist) < kSmallAngle;
}

/// One increment of the beam between a and b: the wire's chord (a -> b)
/// went from c0 to c1; the nodes turned by `dtheta_a` and `dtheta_b` (rad,
/// vectors). The turns act on the chord at the increment's middle, (c0 + c1)
/// / 2, so that a rigid rotation of the pair slips by nothing to second
/// order. Updates the state (a yield adds to its dissipation) and returns
/// the actions on the nodes.
inline WireBeamResponse wireBeamStep(const WireBeamParams& p, WireBeamState& s, const Eigen::Vector3d& c0,
                                     const Eigen::Vector3d& c1, const Eigen::Vector3d& dtheta_a,
                                     const Eigen::Vector3d& dtheta_b) {
  if (!(c1.squaredNorm() > 0.0) || !(c0.squaredNorm() > 0.0)) return {};  // a wire of no length has no direction
  WireBeamActions a{BeamVec(s.shear_N), BeamVec(s.moment_N_m), s.dissipated_J};
  BeamVec ta, tb;
  double twist = 0.0;
  const BeamVec f = wireBeamIncrement(p, a, BeamVec(c0), BeamVec(c1), BeamVec(dtheta_a), BeamVec(dtheta_b), stepSinCos,
                                      ta, tb, twist);
  s.shear_N = a.shear.eigen(), s.moment_N_m = a.moment.eigen(), s.dissipated_J = a.dissipated;
  WireBeamResponse r;
  r.force_b = f.eigen(), r.torque_a = ta.eigen(), r.torque_b = tb.eigen();
  return r;
}

}  // namespace gabion::bridge
