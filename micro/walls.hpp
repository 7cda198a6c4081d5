#pragma once
/// \file
/// Rigid walls of the fine DEM: named planes, infinite or bounded
/// (rectangular plates), that move by a program (WallProgram: fixed,
/// constant velocity, velocity table, sinusoid, force servo). The motion is
/// integrated: each step adds the program's exact displacement over the
/// step, so the time step may change during a run, and a servo follows the
/// force the bodies exert. Their contacts with the particles use the pair
/// contact law (laneContact), one SIMD lane per candidate.
#include <cstdint>
#include <string>
#include <vector>

#include "micro/material_laws.hpp"
#include "micro/neighbour_grid.hpp"
#include "micro/particles.hpp"
#include "micro/scene.hpp"
#include "micro/worker_scratch.hpp"

namespace gabion::micro {

/// The contact history of a wall's candidates, with the step each last
/// touched (a candidate that did not touch at the last step starts afresh).
struct StampedHistory {
  /// One contact's history: shear spring (m), plastic overlap (m), dashpot force (N).
  struct Entry {
    double u[3] = {0.0, 0.0, 0.0};
    double plastic = 0.0, viscous = 0.0;
  };
  std::vector<double> ux, uy, uz, plastic, viscous;
  std::vector<std::int64_t> stamp;  // last step the pair touched
  void resize(std::size_t m);
  bool touched(std::size_t k, std::int64_t step) const { return stamp[k] == step; }
  Entry get(std::size_t k) const { return {{ux[k], uy[k], uz[k]}, plastic[k], viscous[k]}; }
  void set(std::size_t k, const Entry& e, std::int64_t step) {
    ux[k] = e.u[0], uy[k] = e.u[1], uz[k] = e.u[2], plastic[k] = e.plastic, viscous[k] = e.viscous;
    stamp[k] = step;
  }
};

/// The displacement (m) of a wall program over [t0, t1] (s), exact for every
/// kind but the servo (whose velocity comes from the force: Wall::plan).
Vec3 programDisplacement(const WallProgram& program, double t0, double t1);

struct Wall {
  std::string name;
  Vec3 n = Vec3::UnitZ();  ///< unit normal, towards the bodies
  int mat = 0;
  WallProgram program;
  bool bounded = false;
  bool rounded = false;                       ///< a bounded wall with rounded edges (WallSpec::rounded_edges)
  Vec3 u = Vec3::UnitX(), v = Vec3::UnitY();  ///< in-plane axes of a bounded wall
  double half_u = 0.0, half_v = 0.0;          ///< half-lengths (m)
  std::uint32_t skip_groups = 0;              ///< contact groups it does not touch (bits)
  double untouched_s = 1e300;                 ///< how long a servo has felt no force (s)

  Vec3 origin = Vec3::Zero();             ///< point at t = 0 (m)
  Vec3 position = Vec3::Zero();           ///< point now (m)
  Vec3 velocity = Vec3::Zero();           ///< over the current step: its displacement / dt (m/s)
  Vec3 step_displacement = Vec3::Zero();  ///< over the current step (m)
  Vec3 force_N = Vec3::Zero();            ///< exerted by the bodies at the last step
  Vec3 force_position = Vec3::Zero();     ///< point when force_N was evaluated (m)
  Vec3 at_rebuild = Vec3::Zero();         ///< point at the last neighbour-list build

  std::vector<std::uint32_t> cand;  ///< particles within reach at the last build, in index order
  StampedHistory hist;              ///< aligned with cand
  /// Aligned with cand: each candidate's dashpot coefficient against the
  /// wall (N s/m; with a viscous law only; wallDamping).
  std::vector<double> cand_damping;

  explicit Wall(const WallSpec& spec);
  /// Sets the motion of the step [t, t + dt]: from the program, or for a
  /// servo from the normal force of the last step.
  void plan(double t, double dt);
  /// Moves the wall by the step's displacement.
  void advance() { position += step_displacement; }
  /// Normal force the bodies exert on the wall (N; > 0 in compression).
  double normalForce() const { return -force_N.dot(n); }
  /// What changes during a run (program, motion, force, candidates and
  /// their history), into or out of a checkpoint.
  void archive(bridge::StateArchive& a);
};

/// Each wall candidate's dashpot coefficient (bridge::dashpotCoefficient of
/// the law of its material against the wall's and of its body mass): it does
/// not change while the candidate list lasts, so the wall kernel reads it
/// instead of taking a division and a square root per candidate and step.
void wallDamping(const Particles& p, std::vector<Wall>& walls, const MaterialLaws& laws);

/// Lists each wall's candidates: particles that move, within reach of the
/// plane (radius + skin) and, for a bounded wall, over its rectangle (with a
/// skin's margin). Blocks of particles list their own, joined in order.
void wallCandidates(const Particles& p, std::vector<Wall>& walls, double skin, std::size_t nblocks,
                    const ForBlocks& for_blocks);

/// The contacts of every wall with its candidates in the particle range
/// [b, e): forces onto the particles (the range is the worker's own), the
/// force on each wall, energies and work into s.
void wallPartition(Particles& p, std::vector<Wall>& walls, const MaterialLaws& laws, double dt,
                   double max_overlap_ratio, std::int64_t step, std::uint32_t b, std::uint32_t e, bool measure,
                   WorkerScratch& s);

}  // namespace gabion::micro
