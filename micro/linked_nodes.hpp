#pragma once
/// \file
/// The link nodes (the spheres links join: a netting's nodes) and their
/// integration in sub-steps. A wire is far stiffer than any contact its node
/// makes (a 2.7 mm wire 50 mm long: 1.5e7 N/m on a node of a few grams,
/// against 1e6 N/m for a rock contact), so a step that suits the wires would
/// be twenty times shorter than the rock needs. The nodes therefore advance
/// in `substeps` leapfrog sub-steps of every engine step, each with the link
/// forces of its own positions. The contact and wall forces, computed once
/// per step at the step's positions, give their whole impulse (force x step)
/// in the first sub-step's kick, as leapfrog gives it at that position: the
/// impulse form of multiple time stepping (r-RESPA, Tuckerman et al. 1992),
/// which keeps the energy; holding the force over the sub-steps instead
/// would apply it half a step late and pump energy into every impact
/// (docs/micro.md, Time step). With one sub-step this is the engine's
/// leapfrog exactly.
///
/// The nodes' state lives here (a particle store of their own, node-indexed
/// like Links); the engine's store keeps a copy for contact detection, with
/// no mass, so that its free-sphere pass leaves them to this stage.
#include <cstdint>
#include <optional>
#include <vector>

#include "micro/links.hpp"
#include "micro/particles.hpp"
#include "micro/scene.hpp"
#include "micro/walls.hpp"
#include "micro/worker_scratch.hpp"

namespace gabion::micro {

class LinkedNodes {
 public:
  LinkedNodes() = default;
  /// The nodes of `links` (sphere ids of `scene`), taken over from the store
  /// `p` (whose entries for them lose their mass and local damping).
  LinkedNodes(const Scene& scene, const Links& links, Particles& p);

  std::size_t size() const { return n_.size(); }
  bool empty() const { return n_.size() == 0; }

  /// Takes the step's contact and wall forces and torques of the nodes from
  /// the store, and their positions at the step's start; with `rebuilt`
  /// (the neighbour list was built since the last call) also their positions
  /// at that build. Their turn starts again from zero. For nodes [k0, k1):
  /// each node's copy is its own, so ranges may be held in parallel.
  void hold(const Particles& p, bool rebuilt, std::size_t k0, std::size_t k1);
  /// Sub-step k of `substeps` (each h long) for nodes [k0, k1): the link
  /// forces are in `links` (evaluated on x(), y(), z()); sub-step 0 adds the
  /// held impulse. Kicks and drifts every node by h, and turns it (its turn
  /// over the step). Returns the free-sphere sums (energies when
  /// `measure`). Each node's arithmetic is its own: ranges may advance in
  /// parallel.
  SphereSums advance(const Links& links, int k, int substeps, double h, const Vec3& g, bool measure, std::size_t k0,
                     std::size_t k1);
  /// After advance of every node: adds the work the driven nodes did over
  /// sub-step k to `driven_work`.
  void addDrivenWork(int k, int substeps, double h, double& driven_work) const;
  /// Writes the nodes' positions into the store, with as velocity the mean
  /// over the step of length dt (its displacement / dt), and as spin the
  /// mean over the step (its turn / dt): the contacts' shear increments then
  /// follow the node's real path over the step, whatever the sub-steps did
  /// inside it. (Their force stays here: force().) For nodes [k0, k1),
  /// each into its own slot: ranges may be stored in parallel.
  void store(Particles& p, double dt, std::size_t k0, std::size_t k1) const;
  /// The force on the node of stable id `id` at the last step (the held
  /// contact and wall forces plus the links' of its last sub-step; N), or
  /// nullopt when `id` is not a link node.
  std::optional<Vec3> force(std::uint32_t id) const;

  /// The beams' force and torque (Links::evaluateBeams, at the step's start,
  /// before hold) join the held forces: bending wires are soft beside their
  /// axial stiffness (a node turns against them in tens of microseconds), so
  /// they act once per step, as an impulse, like the contacts. For nodes
  /// [k0, k1) (ranges in parallel).
  void addBeams(const Links& links, std::size_t k0, std::size_t k1);
  /// The riders (nodes of spheres that ride a wall, SphereSpec::rides_wall):
  /// before the step's sub-steps, each takes its wall's displacement over the
  /// step as its velocity (displacement / dt), so that it moves with the wall
  /// exactly, and its force sum starts again from zero.
  void ride(const std::vector<Wall>& walls, double dt);
  /// After sub-step k of `substeps` (advance of every node): adds each
  /// rider's link force to its mean over the step.
  void addRiderForces(int substeps);
  /// The mean force of their links on each wall's riders over the last step
  /// (N), added to forces_N (one per wall).
  void addWallForces(std::vector<Vec3>& forces_N) const;
  bool hasRiders() const { return !riders_.empty(); }

  /// Each node's turn over the last step (rad), until hold.
  const double* turnX() const { return rx_.data(); }
  const double* turnY() const { return ry_.data(); }
  const double* turnZ() const { return rz_.data(); }
  const double* x() const { return n_.x.data(); }
  const double* y() const { return n_.y.data(); }
  const double* z() const { return n_.z.data(); }
  /// Particle id of node k.
  std::uint32_t id(std::size_t k) const { return n_.id[k]; }
  /// The nodes' store and held forces, into or out of a checkpoint.
  void archive(bridge::StateArchive& a);

 private:
  Particles n_;  // the nodes' own store: state, masses, and this sub-step's forces
  std::vector<double> hfx_, hfy_, hfz_, htx_, hty_, htz_;  // held contact and wall forces of the step
  std::vector<double> sx_, sy_, sz_;                       // positions at the step's start
  std::vector<double> rx_, ry_, rz_;                       // turn over the step so far (rad)
  std::vector<double> lfx_, lfy_, lfz_;                    // the links' force of the last sub-step
  std::vector<std::uint32_t> driven_;                      // nodes that are fixed and move
  std::vector<std::uint32_t> riders_, rider_wall_;         // nodes that ride a wall (also driven), and their walls
  std::vector<Vec3> rider_force_;                          // their links' mean force over the last step
};

/// The critical step of the link nodes against their links alone (s): min
/// over free nodes of sqrt(m / sum of their links' stiffness); infinite if
/// there are none.
double criticalLinkStep(const Scene& scene);

/// The critical step of the link nodes against their beams (s): their sway
/// against the shear stiffness and their turn against the end stiffness;
/// infinite without beams. The engine's step respects it (the beams act
/// once per step).
double criticalBeamStep(const Scene& scene);

/// Sub-steps of the link nodes in a step of dt_s: as many as keep each within
/// dt_safety x link_critical_s (1 when there are no free link nodes).
int linkSubsteps(double dt_s, double dt_safety, double link_critical_s);

}  // namespace gabion::micro
