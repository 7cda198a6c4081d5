#pragma once
/// \file
/// What each partition of the engine's parallel stages keeps for itself
/// between and within steps: its contact sets and force buffer,
/// its share of the wall contacts, link forces and integration sums, and the
/// first failure it saw. Partial results are reduced in partition order, so a
/// run repeats bit for bit for a given thread count.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "micro/contact.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// Touching pairs evaluated together by the vectorised contact law.
constexpr std::size_t kChunk = 128;

/// The contacts of one partition of the neighbour list that touched at one
/// step, in list order: the list index k of the pair and its history (shear
/// spring, plastic overlap, dashpot force). Only touching pairs have an
/// entry; a pair absent from the last step's set starts from a zero history.
struct ContactSet {
  std::vector<std::uint32_t> k;
  std::vector<double> ux, uy, uz, plastic, viscous;  // plastic/viscous: only when a material uses them
  std::size_t n = 0;
  /// Room for m contacts (n is unchanged). Sizes grow by a quarter: the
  /// count changes slowly from step to step, and two sets per partition are
  /// kept, so a doubling would waste memory for the whole run.
  void ensure(std::size_t m, bool with_plastic, bool with_viscous) {
    if (k.size() >= m) return;
    const std::size_t size = std::max(m, k.size() + k.size() / 4 + kChunk);
    k.resize(size);
    for (auto* v : {&ux, &uy, &uz}) v->resize(size);
    if (with_plastic) plastic.resize(size);
    if (with_viscous) viscous.resize(size);
  }
};

/// A worker's sums over its free spheres in the integration.
struct SphereSums {
  double local = 0.0, ke_t = 0.0, ke_r = 0.0, pe = 0.0, finite = 0.0, max_d2 = 0.0;
  double ke_now = 0.0;  ///< (1/2) m v+^2 + (1/2) I w+^2 at the latest half step (EnergyLedger::kinetic_now)
  /// Adds another pass's sums (the largest displacement: the larger).
  void add(const SphereSums& s) {
    local += s.local, ke_t += s.ke_t, ke_r += s.ke_r, pe += s.pe, finite += s.finite, ke_now += s.ke_now;
    max_d2 = std::max(max_d2, s.max_d2);
  }
};

/// A link that broke at this step (micro/links.hpp).
struct LinkEvent {
  double time_s = 0.0;
  std::size_t link = 0;
  Vec3 position_m = Vec3::Zero();  ///< midpoint of its two particles
};

struct WorkerScratch {
  int thread = 0;  ///< the thread that ran the partition's last job

  // contact kernel: the force buffer for partners beyond the particles of
  // its partition (particle i at i - its end; sized at each list
  // build to its rows' farthest partner, empty for the last partition), per
  // cache line of particles (kParticlesPerLine) whether it was written, and
  // the lines written, listed per partition that owns them (a partition's
  // partners beyond its rows can be few and far apart: large spheres at the
  // end of the order); the contact sets (the last step's and this step's);
  // a chunk of touching pairs
  std::vector<double> fx, fy, fz, tx, ty, tz;
  std::vector<std::uint8_t> written;
  std::vector<std::vector<std::uint32_t>> lines_for;
  ContactSet sets[2];
  std::vector<std::uint32_t> touch_i, touch_k;
  std::vector<double> touch_ex, touch_ey, touch_ez;  // x_j - x_i of the collected pairs
  ContactEnergy energy;
  std::size_t contacts = 0;
  bool failed = false;
  std::uint32_t fail_i = 0, fail_j = 0;
  double fail_ratio = 0.0;
  // walls: the contacts of this partition's particles
  std::vector<Vec3> wall_force;  // per wall, force exerted on it (N)
  ContactEnergy wall_energy;
  double wall_work = 0.0;
  std::size_t wall_contacts = 0;
  std::uint64_t wall_ticks = 0;  // the wall part of the contact job, this step (stage profile)
  bool wall_failed = false;      // the candidate that overlaps most: particle, wall, overlap / radius
  std::uint32_t wall_fail_i = 0;
  std::size_t wall_fail_wall = 0;
  double wall_fail_ratio = 0.0;
  // links of this partition's range
  double link_elastic = 0.0, link_rupture = 0.0, link_plastic = 0.0;
  double link_pull_work = 0.0;  // the work of pulling wires tight over this sub-step (J)
  std::vector<LinkEvent> link_events;
  // integration of the free spheres of its partition
  SphereSums spheres;
};

}  // namespace gabion::micro
