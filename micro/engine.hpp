#pragma once
/// \file
/// The fine-scale DEM engine: spheres, rigid multi-sphere blocks and rigid
/// planar walls under gravity, linear spring / Coulomb contacts with an
/// optional normal force cap, local and viscous damping, O(N) neighbour
/// search (cell grid + Verlet list), full energy bookkeeping.
/// One step() = updateNeighbours -> computeContactForces -> applyWallsAndLoads
/// -> integrate -> (measure); docs/micro.md says what each stage reads and writes.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "micro/contact.hpp"
#include "micro/scene.hpp"
#include "micro/worker_pool.hpp"

namespace gabion::micro {

/// Energy terms of the whole system (J). balance_rel_error is
/// (E(t) - E(0)) / scale with E = kinetic + gravity + elastic + dissipated - wall work.
struct EnergyTotals {
  double kinetic_translational_J = 0.0;
  double kinetic_rotational_J = 0.0;
  double gravity_potential_J = 0.0;   ///< -sum m g.x (zero at the origin)
  double elastic_contact_J = 0.0;     ///< normal + shear springs of all contacts
  double friction_dissipation_J = 0.0;
  double plastic_dissipation_J = 0.0; ///< F_lim normal cap
  double local_damping_dissipation_J = 0.0;
  double viscous_damping_dissipation_J = 0.0;
  double wall_work_J = 0.0;           ///< work done by moving walls on the bodies
  double total_J = 0.0;               ///< E above
  double balance_rel_error = 0.0;
};

/// One body's state (centre of mass for blocks).
struct BodyState {
  Vec3 position_m, velocity_m_s, angular_velocity_rad_s;
};

/// Where the stepping time went (docs/micro.md, Speed): wall-clock seconds
/// of each stage of step() since the engine was built, and for each
/// partition of the parallel stages the seconds it was busy. A stage's wall
/// time above its partitions' busiest shows the waiting and the serial parts;
/// busy times that differ show imbalance. Costs a few clock reads per step.
struct StageProfile {
  enum Stage { kNeighbours, kContacts, kWalls, kIntegrate, kEnergy, kStageCount };
  static const char* name(int stage);
  std::array<double, kStageCount> wall_s{};
  std::vector<std::array<double, kStageCount>> partition_busy_s;  // per partition
};

/// Critical time step of a scene (s), as Engine::criticalDt() gives it,
/// without building the engine (docs/micro.md).
double criticalTimeStep(const Scene& scene);

class Engine {
 public:
  /// Builds the state from a parsed scene with `threads` workers (>= 1) for
  /// the parallel stages. The scene is valid by construction (parseScene).
  Engine(const Scene& scene, int threads);
  ~Engine();

  /// Critical time step estimate (s): min over bodies of sqrt(m / k_n) and
  /// sqrt(I_min / (k l^2)) (docs/micro.md).
  double criticalDt() const { return dt_critical_; }
  double dt() const { return dt_; }
  /// Sets the step (s); the caller checks it against criticalDt().
  void setDt(double dt_s) { dt_ = dt_s; }

  /// Advances one step. `measure`: also compute the stored energies (elastic,
  /// kinetic, potential) for energy(). Returns false on numerical trouble
  /// (failure() says what, when and which bodies); the state is then the one
  /// reached.
  bool step(bool measure);

  long long steps() const { return step_; }
  double time() const { return static_cast<double>(step_) * dt_; }
  const std::string& failure() const { return failure_; }

  /// Energy terms as of the last measuring step.
  const EnergyTotals& energy() const { return energy_; }
  /// Number of bodies: spheres (input order) then blocks.
  std::size_t bodyCount() const;
  std::size_t blockCount() const;
  BodyState body(std::size_t b) const;
  /// Orientation of block b (body input frame -> world).
  Eigen::Quaterniond blockOrientation(std::size_t b) const;
  /// Sphere radius, or for a block the radius of the sphere of equal volume (m).
  double bodyRadius(std::size_t b) const;
  std::size_t wallCount() const;
  /// Force exerted by the bodies on wall w at the last step (N).
  Vec3 wallForce(std::size_t w) const;
  /// Position of wall w's point at the time of the last force evaluation (m).
  Vec3 wallPosition(std::size_t w) const;
  std::size_t contactCount() const { return contacts_; }
  const StageProfile& profile() const { return profile_; }
  std::size_t neighbourRebuilds() const { return rebuilds_; }
  /// Spheres kept out of the cell grid (radius > 2 x median radius).
  std::size_t oversizedCount() const;

 private:
  struct Block;
  struct Wall;
  struct WorkerScratch;

  void updateNeighbours();
  void computeContactForces(bool measure);
  void applyWallsAndLoads(bool measure);
  void integrate(bool measure);
  void addForceBuffers(std::size_t b, std::size_t e);
  void measureEnergy();

  void rebuildNeighbourList();
  void reorderParticles(const std::vector<std::uint32_t>& order);
  void contactKernel(int t, bool measure);
  void wallContacts(int t, bool measure);
  void oversizedContacts(bool measure);
  std::string bodyName(std::uint32_t pid) const;
  void fail(const std::string& what);
  /// Runs job(t) for every partition t on the pool, adding each partition's
  /// busy time to the profile of `stage`.
  template <class Job>
  void parallel(StageProfile::Stage stage, const Job& job);
  /// Runs fn(b) for the blocks b = 0 .. blocks-1, each claimed by whichever
  /// worker comes free first (a core slowed by other work takes fewer).
  /// fn(b) must write only what block b owns, so that the result does not
  /// depend on which worker ran which block.
  template <class Fn>
  void forBlocks(StageProfile::Stage stage, std::size_t blocks, const Fn& fn);
  /// Adds the time since the last lap to `stage`'s wall time.
  void lap(StageProfile::Stage stage);

  // --- particles (every sphere in contact detection: free spheres and block
  // members), SoA, kept in cell order (re-sorted at every list rebuild).
  std::size_t n_ = 0;
  std::vector<double> x_, y_, z_, vx_, vy_, vz_, wx_, wy_, wz_;
  std::vector<double> fx_, fy_, fz_, tx_, ty_, tz_;
  std::vector<double> r_;
  std::vector<double> inv_body_mass_;  // 1/m of the owning body (0: fixed), for contact damping
  std::vector<double> mass_, inv_mass_, inv_inertia_;  // integrated free spheres only (else 0)
  std::vector<double> alpha_;          // local damping of free spheres
  std::vector<double> x0_, y0_, z0_;   // positions at the last rebuild
  std::vector<std::int32_t> block_;    // owning block, -1 for a free sphere
  std::vector<std::uint32_t> mat_;   // 32-bit: the vectorised contact kernel gathers it
  std::vector<std::uint32_t> pid_;     // stable particle id (input order)
  std::vector<std::uint32_t> slot_;    // pid -> current index
  std::size_t sphere_count_ = 0;

  // --- neighbour list (half list, CSR by row i, j > i); the history of its
  // touching pairs lives in per-partition contact sets (WorkerScratch), one
  // entry per contact, not per list entry. Oversized spheres and walls keep
  // a history per candidate pair (History, with the step it last touched).
  std::vector<std::uint32_t> row_begin_, nbr_;
  std::vector<std::vector<std::uint32_t>> list_blocks_;  // rows of each block while the list is built
  std::vector<std::uint32_t> big_i_, big_j_;
  struct History {
    /// One pair's history: shear spring (m), plastic overlap (m), dashpot force (N).
    struct Entry {
      double u[3] = {0.0, 0.0, 0.0};
      double plastic = 0.0, viscous = 0.0;
    };
    std::vector<double> ux, uy, uz, plastic, viscous;
    std::vector<std::int64_t> stamp;  // last step the pair touched
    void resize(std::size_t m);
    bool touched(std::size_t k, std::int64_t step) const { return stamp[k] == step; }
    /// Pair k's history if it touched at step `last`, else an empty one (contact begins).
    Entry get(std::size_t k, std::int64_t last) const {
      Entry e;
      if (touched(k, last)) e = {{ux[k], uy[k], uz[k]}, plastic[k], viscous[k]};
      return e;
    }
    /// Stores pair k's history as of `step`.
    void set(std::size_t k, const Entry& e, std::int64_t step) {
      ux[k] = e.u[0], uy[k] = e.u[1], uz[k] = e.u[2], plastic[k] = e.plastic, viscous[k] = e.viscous;
      stamp[k] = step;
    }
  };
  History big_hist_;
  int hcur_ = 0;  // which of the two contact sets of each partition holds the last step's contacts
  std::vector<std::uint8_t> is_big_;
  double skin_m_ = 0.0;
  double big_radius_m_ = 0.0;  // spheres above this are kept out of the grid
  bool need_rebuild_ = true;
  std::size_t rebuilds_ = 0;

  // --- materials
  std::size_t nmat_ = 0;
  std::vector<Material> materials_;
  std::vector<PairLaw> laws_;  // nmat x nmat
  // The same laws as flat arrays for the vectorised contact kernel, and
  // which rare features any of them uses (the kernel is compiled without the
  // others): a finite F_lim, viscous damping.
  std::vector<double> law_kn_, law_flim_, law_ks_, law_mu_ks_, law_zeta_;
  bool any_plastic_ = false, any_viscous_ = false;
  // Every particle has the same material: the kernel reads one law instead
  // of gathering it per pair.
  bool uniform_material_ = false;

  std::vector<Block> blocks_;
  std::vector<Wall> walls_;
  Vec3 gravity_;
  double dt_ = 0.0, dt_critical_ = 0.0;
  double max_overlap_ratio_ = 0.5, runaway_factor_ = 10.0;
  long long step_ = 0;
  std::size_t contacts_ = 0;

  // energy: dissipations accumulate every step; stored terms on measuring steps
  EnergyTotals energy_;
  double e0_ = 0.0, scale_ke_el0_ = 0.0, pe0_ = 0.0;
  bool have_e0_ = false;
  double local_work_ = 0.0, wall_work_ = 0.0;
  double friction_ = 0.0, plastic_ = 0.0, viscous_ = 0.0, elastic_ = 0.0;
  double ke_t_ = 0.0, ke_r_ = 0.0, pe_ = 0.0;

  std::unique_ptr<WorkerPool> pool_;
  std::vector<WorkerScratch> scratch_;
  std::vector<std::uint32_t> part_begin_;  // row partitions per worker
  std::vector<std::uint32_t> wall_part_;   // particle ranges per worker with equal wall candidates
  std::string failure_;
  StageProfile profile_;
  std::chrono::steady_clock::time_point lap_;
};

}  // namespace gabion::micro
