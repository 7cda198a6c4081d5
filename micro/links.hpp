#pragma once
/// \file
/// The link stage of the fine DEM: pairs of spheres joined by a force law of
/// their distance only (remote interactions: the wires of the netting), with
/// per-link state and a broken flag. The spheres links join are the link
/// nodes, numbered 0 .. nodeCount()-1 in increasing stable id; the links read
/// the nodes' positions from node-indexed arrays (micro/linked_nodes.hpp
/// holds them), so re-sorting the particle store never touches them. Linked
/// particles never touch through the contact law (their pair is excluded
/// from the neighbour list). Forces are computed per link (workers take
/// ranges of links), then summed per node over its links in a fixed order:
/// the same for any thread count. A link whose
/// law says it broke stops acting for good, and its event (time, link,
/// position) is recorded once. Two laws: linear springs
/// (bridge/laws/link_linear.hpp) and the elastoplastic wires of the netting
/// (bridge/laws/wire.hpp), whose plastic work joins the energy ledger. A
/// wire may also bend as a beam between its nodes (bridge/laws/wire_beam.hpp:
/// a shear force and torques on the nodes from their relative motion and
/// turn), until it breaks.
#include <cstdint>
#include <vector>

#include "bridge/laws/link_linear.hpp"
#include "bridge/laws/wire.hpp"
#include "bridge/laws/wire_beam.hpp"
#include "micro/neighbour_grid.hpp"
#include "micro/particles.hpp"
#include "micro/scene.hpp"
#include "micro/worker_scratch.hpp"

namespace gabion::micro {

class Links {
 public:
  Links() = default;
  /// The links of a scene; sphere k has stable id k. `particles`: how many
  /// particles there are (ids 0 .. particles-1).
  Links(const std::vector<LinkSpec>& specs, std::size_t particles);

  std::size_t size() const { return a_.size(); }
  bool empty() const { return a_.empty(); }
  /// Pairs that the contact law leaves alone (the linked ones).
  ExcludedPairs excludedPairs() const;

  /// Pass 1, links [l0, l1): the links' axial forces from the nodes'
  /// positions (X, Y, Z, indexed by node); a link that breaks is marked, its
  /// stored energy counted as dissipated, and its event appended to
  /// s.link_events. Stored energy into s.link_elastic, and the wires'
  /// plastic work so far into s.link_plastic, when `measure`.
  void evaluate(const double* X, const double* Y, const double* Z, std::size_t l0, std::size_t l1, double time_s,
                bool measure, WorkerScratch& s);
  /// Whether any wire is being pulled tight (LinkSpec::pulled).
  bool pulls() const { return !pull_.empty(); }
  /// Rest length of link l now (m): a wire being pulled tight, as it would
  /// be tied now (the distance it closed to, at least its shortest).
  double restLength(std::size_t l) const;

  /// Pass 2, nodes [k0, k1): the axial force of its links on each node (N),
  /// summed in link order, into FX, FY, FZ (indexed by node).
  void nodeForces(double* FX, double* FY, double* FZ, std::size_t k0, std::size_t k1) const;

  /// Whether any link bends (bridge/laws/wire_beam.hpp).
  bool hasBeams() const { return beams_.size() > 0; }
  /// The beams' pass, links [l0, l1), once per step: their increments are
  /// the change of each wire's chord since the last call (positions X, Y, Z)
  /// and the turn of its nodes over that time (RX, RY, RZ, rad; indexed by
  /// node). Stored energy and plastic work so far as in evaluate().
  void evaluateBeams(const double* X, const double* Y, const double* Z, const double* RX, const double* RY,
                     const double* RZ, std::size_t l0, std::size_t l1, bool measure, WorkerScratch& s);
  /// Nodes [k0, k1): the beams' force (N) and torque (N m) on each node,
  /// summed in link order, added to F* and T* (indexed by node).
  void addNodeBeams(double* FX, double* FY, double* FZ, double* TX, double* TY, double* TZ, std::size_t k0,
                    std::size_t k1) const;
  std::size_t nodeCount() const { return node_id_.size(); }
  /// The stable particle id of each node, increasing.
  const std::vector<std::uint32_t>& nodeIds() const { return node_id_; }

  bool broken(std::size_t l) const { return broken_[l] != 0; }
  std::uint32_t idA(std::size_t l) const { return a_[l]; }
  std::uint32_t idB(std::size_t l) const { return b_[l]; }
  /// Tension of link l at the last step (N; < 0 in compression, 0 once broken).
  double tension(std::size_t l) const { return tension_[l]; }
  /// State of link l if it is a wire (plastic strain, strain reached).
  const bridge::WireState& wireState(std::size_t l) const { return wire_state_[l]; }
  /// State of link l's beam (zero if it does not bend).
  bridge::WireBeamState beamState(std::size_t l) const {
    return beam_of_[l] == kNoBeam ? bridge::WireBeamState{} : beams_.state(beam_of_[l]);
  }
  /// The links' state (wires, beams, broken flags, this step's forces), into
  /// or out of a checkpoint.
  void archive(bridge::StateArchive& a);

 private:
  /// Links [l0, l1), their lengths len_ now: each wire being pulled tight
  /// takes its pull's force in place of its law's while its nodes are
  /// further apart than its shortest, none closer; the pull's work since
  /// the last evaluation (the force times the distance closed above the
  /// shortest) into s.link_pull_work.
  void pull(std::size_t l0, std::size_t l1, WorkerScratch& s);
  struct Pull;
  /// A wire pulled until its nodes came to its shortest length is tied
  /// there: its law acts from then on, at that rest length.
  void tie(Pull& p);
  void evaluateOne(std::size_t l, const double* X, const double* Y, const double* Z, double time_s, bool measure,
                   double& elastic, double& rupture, double& plastic, WorkerScratch& s);
  std::size_t particles_ = 0;
  std::vector<std::uint32_t> a_, b_;    // stable ids
  std::vector<std::uint32_t> ka_, kb_;  // their node indices
  // Law of each link: linear_[law_index_[l]] or wires_[law_index_[l]] (wire
  // curves shared by the links that have the same one), and a wire's state.
  std::vector<LinkSpec::Law> law_;
  std::vector<std::uint32_t> law_index_;
  std::vector<bridge::LinearLinkParams> linear_;
  std::vector<bridge::WireCurve> wires_;
  std::vector<double> wire_rest_, wire_inv_rest_;
  std::vector<bridge::WireState> wire_state_;
  // The wires being pulled tight, in link order: link, force, shortest
  // length, length at the last evaluation (0 before the first); and which
  // links they are (their laws wait).
  struct Pull {
    std::uint32_t link;
    double force_N, min_m, last_m;
  };
  std::vector<Pull> pull_;
  std::vector<std::uint8_t> pulled_;
  // Each link's wire constants for the elastic pass (E A, first and rupture
  // strains of its curve), whether it always takes the whole law (a linear
  // spring: law_ again, as bytes beside broken_ so that the pass vectorises;
  // reading law_ there made the sheet benchmark 15 % slower), and whether it
  // took it at this sub-step.
  std::vector<double> wire_elastic_, wire_first_, wire_rupture_;
  std::vector<std::uint8_t> general_, slow_;
  std::vector<std::uint8_t> broken_;
  std::vector<double> fx_, fy_, fz_, tension_;  // force on a (N) at this step; -f on b
  std::vector<double> len_, ux_, uy_, uz_;      // length and unit vector a -> b at this step
  // incidence: node k is particle id node_id_[k]; its links are
  // node_link_[node_begin_[k] .. node_begin_[k + 1]), with the sign of the force on it
  std::vector<std::uint32_t> node_id_, node_begin_, node_link_;
  std::vector<double> node_sign_;
  // The same, padded to node_degree_ entries a node (nodeForces).
  std::size_t node_degree_ = 0;
  std::vector<std::uint32_t> padded_link_;
  std::vector<double> padded_sign_;
  // Beams: link l bends if beam_of_[l] != kNoBeam. They are numbered in
  // link order, each field an array over them (evaluateBeams' vectorised
  // pass).
  static constexpr std::uint32_t kNoBeam = 0xffffffffu;
  std::vector<std::uint32_t> beam_of_;
  struct Beams {
    std::vector<std::uint32_t> link, ka, kb;  // its link and that link's nodes
    std::vector<double> shear_k, bending_k;   // its parameters, side by side for the vectorised pass
    std::vector<double> plastic_moment, length;
    std::vector<double> sx, sy, sz, mx, my, mz, dissipated;  // state: shear force, moment, plastic work
    std::vector<double> cx, cy, cz;                          // chord at the last evaluation (zero before the first)
    // Actions at this step: the force on b (-it on a), one entry more (zero,
    // the padding's); the torques on a, then on b (as many again).
    std::vector<double> fx, fy, fz, tx, ty, tz;
    std::vector<std::uint8_t> broken;  // its wire broke (as broken_ of its link)
    std::vector<std::uint8_t> slow;    // took the whole law at this evaluation
    std::size_t size() const { return link.size(); }
    /// Beam b's parameters, for the whole law, its energy and its rupture.
    bridge::WireBeamParams params(std::size_t b) const {
      bridge::WireBeamParams p;
      p.shear_N_m = shear_k[b], p.bending_N_m_rad = bending_k[b];
      p.plastic_moment_N_m = plastic_moment[b], p.length_m = length[b];
      return p;
    }
    bridge::WireBeamState state(std::size_t b) const {
      return {Vec3(sx[b], sy[b], sz[b]), Vec3(mx[b], my[b], mz[b]), dissipated[b]};
    }
    void setState(std::size_t b, const bridge::WireBeamState& s);
    void setActions(std::size_t b, const bridge::WireBeamResponse& r);
  };
  Beams beams_;
  // Each node's beams for addNodeBeams, padded to the same count at every
  // node: the index of the force (into Beams::fx) and of the torque (into
  // Beams::tx), and the force's sign on the node; a padding entry points at
  // the zero entries.
  std::size_t beam_degree_ = 0;
  std::vector<std::uint32_t> beam_force_at_, beam_torque_at_;
  std::vector<double> beam_sign_;
  /// The whole law of beam b (a first evaluation, a wire of no length, a
  /// large twist, a broken wire), as evaluateBeams' vectorised pass would
  /// give it where it can.
  void evaluateBeam(std::size_t b, const double* X, const double* Y, const double* Z, const double* RX,
                    const double* RY, const double* RZ);
};

}  // namespace gabion::micro
