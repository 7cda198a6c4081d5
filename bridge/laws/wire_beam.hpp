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

namespace gabion::bridge {

struct WireBeamParams {
  double shear_N_m = 0.0;                                               ///< k_s = 12 E I / L^3 (N/m)
  double bending_N_m_rad = 0.0;                                         ///< k_b = E I / L (N m/rad); 0: no beam
  double plastic_moment_N_m = std::numeric_limits<double>::infinity();  ///< M_p (N m)
  double length_m = 0.0;                                                ///< L, the lever of the shear force (m)
  bool active() const { return bending_N_m_rad > 0.0; }
  /// Torsional stiffness (N m/rad): G J / L = E I / ((1 + nu) L), nu = 0.3.
  double torsion_N_m_rad() const { return bending_N_m_rad / 1.3; }
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

/// Elastic energy held by a beam whose wire lies along the unit vector n
/// (J): |F_s|^2 / (2 k_s) + |M_b|^2 / (2 k_b) + T^2 / (2 k_t).
inline double wireBeamElasticEnergy(const WireBeamParams& p, const WireBeamState& s, const Eigen::Vector3d& n) {
  const double t = s.moment_N_m.dot(n);
  return 0.5 * s.shear_N.squaredNorm() / p.shear_N_m + 0.5 * (s.moment_N_m.squaredNorm() - t * t) / p.bending_N_m_rad +
         0.5 * t * t / p.torsion_N_m_rad();
}

struct WireBeamResponse {
  Eigen::Vector3d force_b = Eigen::Vector3d::Zero();   ///< on b (N); a takes minus it
  Eigen::Vector3d torque_a = Eigen::Vector3d::Zero();  ///< on a (N m)
  Eigen::Vector3d torque_b = Eigen::Vector3d::Zero();  ///< on b (N m)
};

/// The turn of a wire from n0 to n1 (unit vectors): the minimal rotation
/// taking n0 to n1, then `twist` rad about n1. Applied to vectors normal to
/// the wire.
struct WireTurn {
  Eigen::Vector3d n1, axis;   // axis = n0 x n1
  double c = 1.0, k = 0.5;    // n0 . n1, 1 / (1 + c)
  double ct = 1.0, st = 0.0;  // cos and sin of the twist
  WireTurn(const Eigen::Vector3d& n0, const Eigen::Vector3d& to, double twist)
      : n1(to), axis(n0.cross(to)), c(n0.dot(to)) {
    k = c > -0.999 ? 1.0 / (1.0 + c) : 0.0;
    if (std::fabs(twist) < 1e-3) {  // (a step's twist: the series is exact to rounding)
      const double t2 = twist * twist;
      ct = 1.0 - 0.5 * t2 * (1.0 - t2 / 12.0), st = twist * (1.0 - t2 / 6.0);
    } else {
      ct = std::cos(twist), st = std::sin(twist);
    }
  }
  Eigen::Vector3d operator()(const Eigen::Vector3d& v) const {
    // Rodrigues with the unnormalised axis: c v + a x v + a (a . v) / (1 + c).
    Eigen::Vector3d w = k > 0.0 ? Eigen::Vector3d(c * v + axis.cross(v) + axis * (axis.dot(v) * k)) : v;
    w -= w.dot(n1) * n1;  // stays normal to the wire (rounding)
    return ct * w + st * n1.cross(w);
  }
};

/// One increment of the beam between a and b: the wire's chord (a -> b)
/// went from c0 to c1; the nodes turned by `dtheta_a` and `dtheta_b` (rad,
/// vectors). The turns act on the chord at the increment's middle, (c0 + c1)
/// / 2, so that a rigid rotation of the pair slips by nothing to second
/// order. Updates the state (a yield adds to its dissipation) and returns
/// the actions on the nodes.
inline WireBeamResponse wireBeamStep(const WireBeamParams& p, WireBeamState& s, const Eigen::Vector3d& c0,
                                     const Eigen::Vector3d& c1, const Eigen::Vector3d& dtheta_a,
                                     const Eigen::Vector3d& dtheta_b) {
  const double L1sq = c1.squaredNorm(), L0sq = c0.squaredNorm();
  if (!(L1sq > 0.0) || !(L0sq > 0.0)) return {};  // a wire of no length has no direction
  const double L1 = std::sqrt(L1sq);
  const Eigen::Vector3d n0 = c0 / std::sqrt(L0sq), n1 = c1 / L1, mid = 0.5 * (c0 + c1);
  const Eigen::Vector3d sum = dtheta_a + dtheta_b, rel = dtheta_b - dtheta_a;
  // (the mean spin about the wire's middle direction, to second order)
  const WireTurn turn(n0, n1, 0.25 * sum.dot(n0 + n1));
  s.shear_N = turn(s.shear_N);
  s.moment_N_m = turn(s.moment_N_m) + s.moment_N_m.dot(n0) * n1;  // (bending turned, torsion along the wire)
  // The wire's mid-point as each node carries it: b's relative to a's.
  Eigen::Vector3d slip = (c1 - c0) - 0.5 * sum.cross(mid);
  slip -= slip.dot(n1) * n1;
  s.shear_N -= p.shear_N_m * slip;
  const double spin = rel.dot(n1);
  s.moment_N_m -= p.bending_N_m_rad * (rel - spin * n1) + p.torsion_N_m_rad() * spin * n1;
  const Eigen::Vector3d lever = 0.5 * L1 * n1.cross(s.shear_N);
  const double peak2 = std::max((s.moment_N_m + lever).squaredNorm(), (s.moment_N_m - lever).squaredNorm());
  if (peak2 > p.plastic_moment_N_m * p.plastic_moment_N_m) {
    const double scale = p.plastic_moment_N_m / std::sqrt(peak2);
    s.dissipated_J += (1.0 - scale * scale) * wireBeamElasticEnergy(p, s, n1);
    s.shear_N *= scale;
    s.moment_N_m *= scale;
  }
  WireBeamResponse r;
  const Eigen::Vector3d lv = 0.5 * L1 * n1.cross(s.shear_N);
  r.force_b = s.shear_N;
  r.torque_a = -s.moment_N_m - lv;
  r.torque_b = s.moment_N_m - lv;
  return r;
}

}  // namespace gabion::bridge
