#pragma once
/// \file
/// The fine-scale DEM engine: spheres, rigid multi-sphere blocks, links
/// between spheres and programmed rigid walls under gravity, linear spring /
/// Coulomb contacts with an optional normal force cap, local and viscous
/// damping, O(N) neighbour search for any mix of sizes (a grid per size class
/// + Verlet list), full energy bookkeeping.
/// One step() = updateNeighbours -> computeContactForces -> applyWallsAndLoads
/// -> integrate -> advanceLinkedNodes -> checkStep -> (measureEnergy)
/// (with loose spheres only, each partition's spheres move inside the
/// contact job, once the forces on them are complete);
/// docs/architecture.md says what each stage reads and writes. Each stage
/// lives in its own file: neighbour_grid, contact_kernel, walls, integrator,
/// linked_nodes and links, energy.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "micro/energy.hpp"
#include "micro/integrator.hpp"
#include "micro/linked_nodes.hpp"
#include "micro/links.hpp"
#include "micro/material_laws.hpp"
#include "micro/neighbour_grid.hpp"
#include "micro/particles.hpp"
#include "micro/scene.hpp"
#include "micro/step_status.hpp"
#include "micro/tick_clock.hpp"
#include "micro/walls.hpp"
#include "micro/worker_pool.hpp"
#include "micro/worker_scratch.hpp"

namespace gabion::micro {

/// One body's state (centre of mass for blocks).
struct BodyState {
  Vec3 position_m, velocity_m_s, angular_velocity_rad_s;
};

/// Where the stepping time went (docs/micro.md, Speed): wall-clock seconds
/// of each stage of step() since the engine was built, and for each thread
/// the seconds it was busy in the stage's partitions. A stage's wall time
/// above its threads' busy times shows the waiting and the serial parts.
/// Costs a few clock reads per partition and step.
struct StageProfile {
  enum Stage { kNeighbours, kContacts, kLinks, kWalls, kIntegrate, kEnergy, kStageCount };
  static const char* name(int stage);
  std::array<double, kStageCount> wall_s{};
  std::vector<std::array<double, kStageCount>> thread_busy_s;  // per thread
};

/// Critical time step of a scene (s), as Engine::criticalDt() gives it,
/// without building the engine (docs/micro.md).
double criticalTimeStep(const Scene& scene);

class Engine {
 public:
  /// Builds the state from a scene with `threads` workers (>= 1) for the
  /// parallel stages. The scene is validated first (validateScene): one
  /// built in code is checked like one read from JSON.
  Engine(const Scene& scene, int threads);
  ~Engine();

  /// Critical time step estimate (s): min over bodies of sqrt(m / k) with k
  /// the stiffest contact, and sqrt(I_min / (k l^2)) (docs/micro.md). The
  /// links' stiffness is left to the link nodes' sub-steps.
  double criticalDt() const { return dt_critical_; }
  /// Critical step of the link nodes against their links (s; criticalLinkStep).
  double linkCriticalDt() const { return dt_link_critical_; }
  double dt() const { return dt_; }
  /// Sets the step (s), also during a run; the caller checks it against
  /// criticalDt(). The link nodes take as many sub-steps as keep theirs
  /// within the run's dt_safety x linkCriticalDt().
  void setDt(double dt_s);
  /// Sub-steps of the link nodes per step (1: none).
  int linkSubsteps() const { return substeps_; }

  /// Advances one step. `measure`: also compute the stored energies (elastic,
  /// kinetic, potential) for energy(). On anything but Ok, failure() says
  /// what, when and which bodies; the state is then the one reached.
  StepStatus step(bool measure);

  long long steps() const { return step_; }
  /// Simulated time (s): the sum of the steps taken.
  double time() const { return time_; }
  const std::string& failure() const { return failure_; }

  /// Energy terms as of the last measuring step.
  const EnergyTotals& energy() const { return energy_.totals(); }
  /// The bodies' kinetic energy at the latest half step of the last
  /// measuring step, (1/2) m v+^2 (J): what "at rest" criteria read.
  double kineticEnergyNow() const { return energy_.kinetic_now; }
  /// Number of bodies: spheres (input order) then blocks.
  std::size_t bodyCount() const;
  std::size_t blockCount() const;
  BodyState body(std::size_t b) const;
  /// Orientation of block b (body input frame -> world).
  Eigen::Quaterniond blockOrientation(std::size_t b) const;
  /// World position of block b's input body-frame origin (m): with
  /// blockOrientation, the pose a BlockSpec gives it.
  Vec3 blockFrameOrigin(std::size_t b) const;
  /// Every sphere in contact detection (free spheres in input order, then the
  /// members of each block): centres and radii, e.g. for a porosity.
  void sphereGeometry(std::vector<Vec3>& centers_m, std::vector<double>& radii_m) const;
  /// Sphere radius, or for a block the radius of the sphere of equal volume (m).
  double bodyRadius(std::size_t b) const;

  /// Force the other bodies, links and walls exerted on sphere s (input
  /// order) at the last step, gravity excluded (N): for a clamped or driven
  /// sphere, the reaction it takes.
  Vec3 sphereForce(std::size_t s) const;

  std::size_t wallCount() const;
  const std::string& wallName(std::size_t w) const { return walls_[w].name; }
  /// Index of the wall called `name`, or wallCount() if none is.
  std::size_t wallIndex(const std::string& name) const;
  /// Force exerted by the bodies on wall w at the last step (N).
  Vec3 wallForce(std::size_t w) const;
  /// Position of wall w's point at the time of the last force evaluation (m).
  Vec3 wallPosition(std::size_t w) const;
  /// Gives wall w a new program from the next step on; it moves on from
  /// where it is (a test that reverses its plate, or stops it).
  void setWallProgram(std::size_t w, const WallProgram& program);
  /// Moves the walls whose program is Driven: called once a step, after the
  /// forces and before the bodies move, with the force the bodies exert on
  /// each driven wall at this step (walls in index order); it fills each one's
  /// displacement over the step (m). The walls' work in the energy ledger is
  /// then -force . displacement, exactly what a coupled model receives. A
  /// wall that spheres ride (SphereSpec::rides_wall) also passes on their
  /// links' force of the last step: the ledger counts their work at this
  /// step's force (as the riders' driven work), so that share of the
  /// coupling lags a step.
  using WallDriver =
      std::function<void(double t, double dt, const std::vector<Vec3>& forces_N, std::vector<Vec3>& displacements_m)>;
  /// Installs (or, with an empty function, removes: the walls stand still)
  /// the driver of the Driven walls.
  void setWallDriver(WallDriver driver) { driver_ = std::move(driver); }

  std::size_t linkCount() const { return links_.size(); }
  bool linkBroken(std::size_t l) const { return links_.broken(l); }
  /// State of link l if it is a wire.
  const bridge::WireState& linkWireState(std::size_t l) const { return links_.wireState(l); }
  bridge::WireBeamState linkBeamState(std::size_t l) const { return links_.beamState(l); }
  /// Tension of link l at the last step (N).
  double linkTension(std::size_t l) const { return links_.tension(l); }
  /// Rest length of link l now (m): a wire being pulled tight, as it would be tied now.
  double linkRestLength(std::size_t l) const { return links_.restLength(l); }
  /// The sphere indices (input order) link l joins.
  std::pair<std::size_t, std::size_t> linkEnds(std::size_t l) const { return {links_.idA(l), links_.idB(l)}; }
  /// Every link that broke so far, in the order they broke (link order within a step).
  const std::vector<LinkEvent>& linkEvents() const { return link_events_; }

  /// The whole state between two steps (bodies in their current order,
  /// walls, links, contact histories, neighbour list and its partitions,
  /// energy ledger, step and time), into or out of a checkpoint
  /// (bridge/state_archive.hpp), or hashed. An engine built from the same
  /// scene with the same number of threads, then loaded, steps on exactly as
  /// the one saved would have: the same arrays, bit for bit.
  void archive(bridge::StateArchive& a);

  std::size_t contactCount() const { return contacts_; }
  /// Where the steps' time went, stage by stage (seconds).
  StageProfile profile() const;
  std::size_t neighbourRebuilds() const { return rebuilds_; }
  /// Size classes of the neighbour search (micro/neighbour_grid.hpp).
  int sizeClassCount() const { return grid_.classCount(); }

 private:
  // The stages of step().
  void updateNeighbours();
  void computeContactForces(bool measure, bool move_spheres);
  void applyWallsAndLoads(bool measure);
  void driveWalls();
  void integrate(bool measure, bool spheres_moved);
  void integratePartition(std::size_t t, bool measure);
  void integrateWhenReady(int thread, const std::vector<int>& ran, bool measure);
  void advanceLinkedNodes(bool measure);
  void checkStep(bool measure);
  void measureEnergy();

  // The parts of a neighbour-list rebuild.
  struct SavedContacts;
  SavedContacts saveContacts();
  void reorderParticles(const std::vector<std::uint32_t>& order);
  void restoreContacts(const SavedContacts& saved);
  void partitionRows(const std::vector<std::uint32_t>& from);
  void balanceShares();
  void sizeTouchBuffers();
  void sizeForceBuffer(std::size_t t);
  void findReachedFrom();

  void addForceBuffers(std::size_t u);
  std::string bodyName(std::uint32_t id) const;
  StepStatus fail(StepStatus status, const std::string& what);
  /// Runs job(t) for every partition t on the pool, adding each partition's
  /// busy time to the profile of `stage`; then, if given, then(thread, the
  /// partitions it ran) on each thread (WorkerPool::run).
  template <class Job>
  void parallel(StageProfile::Stage stage, const Job& job, const WorkerPool::Then& then = {});
  /// Runs fn(b) for the blocks b = 0 .. blocks-1, each claimed by whichever
  /// worker comes free first (a core slowed by other work takes fewer).
  /// fn(b) must write only what block b owns, so that the result does not
  /// depend on which worker ran which block.
  template <class Fn>
  void forBlocks(StageProfile::Stage stage, std::size_t blocks, const Fn& fn);
  /// forBlocks for the neighbour stage's helpers (NeighbourGrid, walls).
  ForBlocks neighbourBlocks();
  /// Blocks of particles for the rebuild's passes.
  std::size_t rebuildBlocks() const;
  /// Adds the time since the last lap to `stage`'s wall time.
  void lap(StageProfile::Stage stage);

  Particles p_;  // every sphere in contact detection, in cell order
  WallDriver driver_;
  std::vector<Vec3> rider_force_;  // per wall: the force of its riders' links at the last step (LinkedNodes)
  std::vector<Vec3> driven_force_, driven_move_;  // the driver's arguments (kept: no allocation per step)
  std::size_t sphere_count_ = 0;
  std::vector<std::uint32_t> driven_;  // ids of the fixed spheres that move
  // ids of the spheres the free-sphere pass moves (not block members, not
  // link nodes); when that is every particle (all_loose_) the pass runs over
  // the store's ranges, vectorised
  std::vector<std::uint32_t> loose_;
  bool all_loose_ = true;
  bool any_local_damping_ = true;  ///< a sphere has local damping (alpha never changes)
  bool one_body_ = false;          ///< every particle is a loose sphere of one mass, inertial mass and moment
  std::vector<RigidBlock> blocks_;
  std::vector<Wall> walls_;
  Links links_;
  LinkedNodes nodes_;  // the spheres links join, moved by the link stage
  int substeps_ = 1;
  std::size_t nodes_rebuilds_ = ~std::size_t{0};  // the list build the nodes last took x0 from
  SphereSums sums_;                               // of this step's integration (bodies and link nodes)
  std::vector<LinkEvent> link_events_;
  MaterialLaws laws_;

  // Neighbour search: the grids, the half list (CSR by row i, j > i), the
  // pairs it leaves out; the history of its touching pairs lives in
  // per-partition contact sets (WorkerScratch), one entry per contact.
  NeighbourGrid grid_;
  NeighbourList list_;
  ExcludedPairs excluded_;
  int hcur_ = 0;  // which of the two contact sets of each partition holds the last step's contacts
  double skin_m_ = 0.0;
  bool need_rebuild_ = true;
  bool just_rebuilt_ = false;  ///< the displacement test measures one step's move (the tunnelling check)
  double tunnel_m_ = 0.0;      ///< a larger move in one step is tunnelling: the smallest radius (or the skin)
  std::size_t rebuilds_ = 0;

  Vec3 gravity_;
  double dt_ = 0.0, dt_critical_ = 0.0, dt_link_critical_ = 0.0, link_dt_safety_ = 0.2, time_ = 0.0;
  double max_overlap_ratio_ = 0.5, runaway_factor_ = 10.0, max_balance_error_ = 0.05;
  static constexpr long long kBalanceWarmup = 20;  ///< measurements before run.max_balance_error applies
  long long measurements_ = 0;
  long long step_ = 0;
  std::size_t contacts_ = 0;
  EnergyLedger energy_;

  std::unique_ptr<WorkerPool> pool_;
  std::vector<WorkerScratch> scratch_;
  std::vector<std::uint32_t> part_begin_;      // row partitions (kPartitionsPerThread per thread)
  std::vector<std::uint32_t> line_partition_;  // per line of particles (kParticlesPerLine): its partition
  std::string failure_;
  StepStatus status_ = StepStatus::Ok;
  std::vector<SphereSums> block_sums_;  // integrate(): each block's sums, added in block order
  std::vector<SphereSums> node_sums_;   // advanceLinkedNodes(): each range of nodes' sums, added in order
  TickClock clock_;
  std::array<std::uint64_t, StageProfile::kStageCount> ticks_{};  // per stage (StageProfile::wall_s)
  // Per thread, one cache line each (each thread adds to its own at the end
  // of every partition): the counts it was busy in each stage, and in the
  // wall part of the contact jobs (StageProfile::thread_busy_s).
  struct alignas(64) ThreadTicks {
    std::array<std::uint64_t, StageProfile::kStageCount> busy{};
    std::uint64_t walls = 0;
    std::uint64_t contact_jobs = 0;  // contact partitions it ran (balanceShares)
    std::uint64_t moved = 0;         // its moves in this step's contact job, without waits (computeContactForces)
  };
  std::vector<ThreadTicks> thread_ticks_;
  std::vector<ThreadTicks> shares_from_;  // thread_ticks_ at the last balanceShares()
  int steps_since_balance_ = 0;
  struct alignas(64) BlockNext {
    std::atomic<std::size_t> b{0};
  };
  std::unique_ptr<BlockNext[]> block_next_;  // forBlocks(): per partition, its next block
  // The contact job that also moves the loose spheres (computeContactForces):
  // per partition, the job whose contacts it has finished (one line each);
  // the first partition whose rows reach into it (its particles are then
  // complete and free to move once the partitions from that one to itself
  // are done); per thread, the partitions it ran and has not moved yet.
  struct alignas(64) Finished {
    std::atomic<std::uint64_t> job{0};
  };
  std::unique_ptr<Finished[]> finished_;
  std::uint64_t contact_job_ = 0;
  std::vector<std::uint32_t> reach_;         // per partition: the last particle its rows reach
  std::vector<std::uint32_t> reached_from_;  // per partition: the first partition that reaches into it
  struct alignas(64) Waiting {
    std::vector<int> list;
  };
  std::unique_ptr<Waiting[]> waiting_;
  /// reorderParticles(): kept spare buffers of the state's fields that are
  /// not doubles (the doubles use the scratch fields).
  struct ReorderSpares {
    std::vector<std::int32_t> i32;
    std::vector<std::uint32_t> u32[2];
    std::vector<std::uint8_t> u8[2];
    void resize(std::size_t n) {
      i32.resize(n);
      for (auto& v : u32) v.resize(n);
      for (auto& v : u8) v.resize(n);
    }
  };
  ReorderSpares reorder_spares_;
  std::uint64_t lap_ = 0;
};

}  // namespace gabion::micro
