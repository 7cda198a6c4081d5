#include "micro/engine.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>
#include <thread>
#include <tuple>
#include <type_traits>
#include <utility>

#include "micro/contact_kernel.hpp"
#include "micro/rigid_body.hpp"

namespace gabion::micro {

namespace {
/// Part t of [0, n) split evenly into `parts` contiguous ranges: [first, end).
struct Range {
  std::size_t first, end;
};
Range evenPart(std::size_t n, std::size_t t, std::size_t parts) {
  return {n * t / parts, n * (t + 1) / parts};
}

// The first particle of a worker's range, boundary k rounded down to a whole
// cache line of the store's fields (kParticlesPerLine; the fields are
// line-aligned, micro/particles.hpp), not before `previous`: two workers
// never write one line.
std::uint32_t lineStart(std::size_t k, std::uint32_t previous) {
  return std::max(previous, static_cast<std::uint32_t>(k / kParticlesPerLine * kParticlesPerLine));
}

// With several threads, the rows are cut into this many partitions per
// thread; a thread runs its own share, then takes over partitions left in
// the others' (micro/worker_pool.hpp). On virtual CPUs whose speeds differ
// (one sharing its host core with other work) a fixed half each waits for
// the slower: on the settling benchmark at N = 20,000 on two such CPUs, one
// thread was busy 377 us a step in the contact stage and the other 292 us;
// with four partitions each, both about 300 us. Each boundary sends its
// pairs through a buffer. Against one partition per thread
// (bench/settle/compare.sh -t 2, paired by round), four: N = 5,000 1.03x,
// mixed scene 0.99x, N = 20,000 1.15x; two: N = 5,000 0.87x (a thread's
// last partition is too large a share to hand over).
// The partitions depend on the state only, never on who runs them: the
// arrays are the same for a given thread count.
constexpr int kPartitionsPerThread = 4;

// Blocks of the same shape and density (a wall of copies of one cell, each
// block a copy of its cell's) share one computation: the key is the exact
// bytes of the shape, so each block gets what it would get alone.
std::vector<MassProperties> blockMassProperties(const Scene& scene) {
  std::vector<MassProperties> out;
  out.reserve(scene.blocks.size());
  std::map<std::string, MassProperties> computed;
  for (const BlockSpec& b : scene.blocks) {
    const double density = scene.materials[static_cast<std::size_t>(b.material)].density_kg_m3;
    if (b.member_centers_m.size() != b.member_radii_m.size()) {  // (refused, with its message, by the computation)
      out.push_back(clusterMassProperties(b.member_centers_m, b.member_radii_m, density));
      continue;
    }
    std::string key(sizeof(double) * (1 + 4 * b.member_radii_m.size()), '\0');
    char* at = key.data();
    const auto put = [&at](double v) {
      std::memcpy(at, &v, sizeof v);
      at += sizeof v;
    };
    put(density);
    for (std::size_t k = 0; k < b.member_radii_m.size(); ++k)
      put(b.member_radii_m[k]), put(b.member_centers_m[k].x()), put(b.member_centers_m[k].y()),
          put(b.member_centers_m[k].z());
    const auto it = computed.find(key);
    if (it != computed.end()) {
      out.push_back(it->second);
      continue;
    }
    out.push_back(clusterMassProperties(b.member_centers_m, b.member_radii_m, density));
    computed.emplace(std::move(key), out.back());
  }
  return out;
}

// Critical step: each free body against the stiffest contact it can meet
// (docs/micro.md): sqrt(m / k_n) and sqrt(I / (k l^2)) with l the farthest
// reach of the body from its centre (R for a sphere, I = 0.4 m R^2).
double criticalStep(const Scene& scene, const std::vector<MassProperties>& block_props) {
  const std::size_t nmat = scene.materials.size();
  const std::vector<PairLaw> laws = pairLawTable(scene.materials, scene.contact_pairs);
  std::vector<bool> present(nmat, false);
  for (const auto& sp : scene.spheres) present[static_cast<std::size_t>(sp.material)] = true;
  for (const auto& b : scene.blocks) present[static_cast<std::size_t>(b.material)] = true;
  for (const auto& w : scene.walls) present[static_cast<std::size_t>(w.material)] = true;
  std::vector<double> kn_max(nmat, 0.0), k_max(nmat, 0.0), ks_max(nmat, 0.0);
  for (std::size_t a = 0; a < nmat; ++a)
    for (std::size_t b = 0; b < nmat; ++b)
      if (present[b]) {
        const PairLaw& l = laws[a * nmat + b];
        kn_max[a] = std::max(kn_max[a], l.normal.stiffness_N_m);
        ks_max[a] = std::max(ks_max[a], l.tangential.stiffness_N_m);
        k_max[a] = std::max({k_max[a], l.normal.stiffness_N_m, l.tangential.stiffness_N_m});
      }
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < scene.spheres.size(); ++s) {
    const SphereSpec& sp = scene.spheres[s];
    if (sp.fixed) continue;
    const auto m = static_cast<std::size_t>(sp.material);
    const double mass = sphereInertialMass(scene, sp);
    const double inertia = sphereInertialMoment(scene, sp);  // (turning against a contact at its surface)
    dt = std::min({dt, std::sqrt(mass / kn_max[m]), std::sqrt(inertia / (ks_max[m] * sp.radius_m * sp.radius_m))});
  }
  for (std::size_t bi = 0; bi < scene.blocks.size(); ++bi) {
    const BlockSpec& spec = scene.blocks[bi];
    if (spec.fixed) continue;
    const MassProperties& props = block_props[bi];
    const std::vector<Vec3> offsets = principalFrameOffsets(props, spec.member_centers_m);
    const auto m = static_cast<std::size_t>(spec.material);
    double lever = 0.0;
    for (std::size_t k = 0; k < offsets.size(); ++k)
      lever = std::max(lever, offsets[k].norm() + spec.member_radii_m[k]);
    dt = std::min({dt, std::sqrt(props.mass_kg / kn_max[m]),
                   std::sqrt(props.principal_moments_kg_m2.minCoeff() / (k_max[m] * lever * lever))});
  }
  // Netting nodes against their bending wires (which act once per step).
  return std::min(dt, criticalBeamStep(scene));
}
}  // namespace

double criticalTimeStep(const Scene& scene) {
  return criticalStep(scene, blockMassProperties(scene));
}

Engine::Engine(const Scene& scene, int threads) {
  validateScene(scene);
  laws_ = MaterialLaws(scene.materials, scene.contact_pairs);
  gravity_ = scene.gravity_m_s2;
  max_overlap_ratio_ = scene.run.max_overlap_ratio;
  runaway_factor_ = scene.run.energy_runaway_factor;
  max_balance_error_ = scene.run.max_balance_error;

  // Particles: free spheres (ids 0 .. spheres-1), then the members of each block.
  sphere_count_ = scene.spheres.size();
  std::vector<bool> linked(sphere_count_, false);  // link nodes: the link stage moves them (LinkedNodes)
  for (const LinkSpec& l : scene.links) linked[l.a] = linked[l.b] = true;
  std::size_t members = 0;
  for (const auto& b : scene.blocks) members += b.member_radii_m.size();
  p_.resize(sphere_count_ + members);
  const auto place = [&](std::size_t i, const Vec3& x, const Vec3& v, const Vec3& w) {
    p_.x[i] = x.x(), p_.y[i] = x.y(), p_.z[i] = x.z();
    p_.vx[i] = v.x(), p_.vy[i] = v.y(), p_.vz[i] = v.z();
    p_.wx[i] = w.x(), p_.wy[i] = w.y(), p_.wz[i] = w.z();
  };
  for (std::size_t s = 0; s < sphere_count_; ++s) {
    const SphereSpec& sp = scene.spheres[s];
    const Material& m = scene.materials[static_cast<std::size_t>(sp.material)];
    p_.r[s] = sp.radius_m;
    p_.mat[s] = static_cast<std::uint32_t>(sp.material);
    p_.group[s] = static_cast<std::uint8_t>(sp.group);
    if (sp.fixed) {
      // Infinite mass, its own constant velocity (a clamp, or a driven node).
      place(s, sp.center_m, sp.velocity_m_s, Vec3::Zero());
      if (sp.velocity_m_s != Vec3::Zero() && !linked[s]) driven_.push_back(static_cast<std::uint32_t>(s));
      continue;
    }
    // (its weight from its mass, its motion from its inertial mass: mass scaling)
    const double inertial = sphereInertialMass(scene, sp);
    place(s, sp.center_m, sp.velocity_m_s, sp.angular_velocity_rad_s);
    p_.mass[s] = sphereMass(scene, sp);
    p_.inv_mass[s] = 1.0 / inertial;
    p_.inv_inertia[s] = 1.0 / sphereInertialMoment(scene, sp);
    p_.inv_body_mass[s] = 1.0 / inertial;
    p_.alpha[s] = m.local_damping;
  }
  for (std::size_t s = 0; s < sphere_count_; ++s)
    if (!linked[s]) loose_.push_back(static_cast<std::uint32_t>(s));
  all_loose_ = loose_.size() == members + sphere_count_;
  any_local_damping_ = std::any_of(p_.alpha.begin(), p_.alpha.end(), [](double a) { return a != 0.0; });
  std::size_t next = sphere_count_;
  const std::vector<MassProperties> block_props = blockMassProperties(scene);
  for (std::size_t bi = 0; bi < scene.blocks.size(); ++bi) {
    const BlockSpec& spec = scene.blocks[bi];
    const MassProperties& props = block_props[bi];
    RigidBlock b;
    b.mass = props.mass_kg;
    b.volume = props.volume_m3;
    b.inertia = props.principal_moments_kg_m2;
    b.principal_axes = props.principal_axes;
    b.frame_center = props.center_m;
    b.offsets = principalFrameOffsets(props, spec.member_centers_m);
    b.q = (spec.orientation * props.principal_axes).normalized();
    b.x = spec.position_m + spec.orientation * props.center_m;
    b.markListBuild();  // (as its members' x0, until the first build)
    b.fixed = spec.fixed;
    b.alpha = scene.materials[static_cast<std::size_t>(spec.material)].local_damping;
    if (!b.fixed) {
      b.inv_mass = 1.0 / b.mass;
      b.v = spec.velocity_m_s;
      const Eigen::Matrix3d R = b.q.toRotationMatrix();
      b.L = R * b.inertia.asDiagonal() * R.transpose() * spec.angular_velocity_rad_s;
      b.omega = angularVelocityWorld(b.q, b.L, b.inertia);
    }
    for (std::size_t k = 0; k < b.offsets.size(); ++k, ++next) {
      const Vec3 arm = b.q * b.offsets[k];
      place(next, b.x + arm, b.v + b.omega.cross(arm), b.omega);
      p_.r[next] = spec.member_radii_m[k];
      p_.mat[next] = static_cast<std::uint32_t>(spec.material);
      p_.group[next] = static_cast<std::uint8_t>(spec.group);
      p_.body[next] = static_cast<std::int32_t>(bi);
      p_.inv_body_mass[next] = b.inv_mass;
      b.ids.push_back(static_cast<std::uint32_t>(next));
    }
    blocks_.push_back(std::move(b));
  }
  for (const auto& [g, h] : scene.no_contact_groups) {
    p_.group_mask[g] &= ~(1u << h);
    p_.group_mask[h] &= ~(1u << g);
  }
  for (std::size_t w = 0; w < scene.walls.size(); ++w) {
    walls_.emplace_back(scene.walls[w]);
    walls_.back().name = micro::wallName(scene, w);
  }
  links_ = Links(scene.links, p_.size());
  nodes_ = LinkedNodes(scene, links_, p_);
  excluded_ = links_.excludedPairs();

  // (one material, body mass, radius: the kernels' uniform forms; one mass,
  // inertial mass and moment: the integrator's one-body form)
  const auto allEqual = [](const auto& v) {
    return std::all_of(v.begin(), v.end(), [&](const auto& x) { return x == v.front(); });
  };
  laws_.setUniform(allEqual(p_.mat), p_.mat[0]);
  const double im0 = p_.inv_body_mass.empty() ? 0.0 : p_.inv_body_mass[0];
  laws_.setUniformMass(im0 > 0.0 && allEqual(p_.inv_body_mass), im0);
  laws_.setUniformRadius(allEqual(p_.r), p_.r.empty() ? 0.0 : p_.r[0]);
  one_body_ = all_loose_ && allEqual(p_.mass) && allEqual(p_.inv_mass) && allEqual(p_.inv_inertia);

  // Size classes; the skin is a fraction of the smallest class's mean radius.
  grid_.assignClasses(p_);
  skin_m_ = scene.run.verlet_skin_ratio * grid_.finestMeanRadius();
  tunnel_m_ = p_.r.empty() ? 0.0 : std::max(skin_m_, *std::min_element(p_.r.begin(), p_.r.end()));

  dt_critical_ = criticalStep(scene, block_props);
  dt_link_critical_ = criticalLinkStep(scene);
  link_dt_safety_ = linkDtSafety(scene.run);

  const int T = std::max(1, threads);
  pool_ = std::make_unique<WorkerPool>(T, T == 1 ? 1 : kPartitionsPerThread * T);
  scratch_.resize(static_cast<std::size_t>(pool_->size()));
  thread_ticks_.resize(static_cast<std::size_t>(T));
  shares_from_.resize(static_cast<std::size_t>(T));
  block_next_ = std::make_unique<BlockNext[]>(scratch_.size());
  finished_ = std::make_unique<Finished[]>(scratch_.size());
  waiting_ = std::make_unique<Waiting[]>(static_cast<std::size_t>(T));
  reach_.assign(scratch_.size(), 0);
  reached_from_.assign(scratch_.size(), 0);
}

Engine::~Engine() = default;

void Engine::setDt(double dt_s) {
  dt_ = dt_s;
  substeps_ = micro::linkSubsteps(dt_s, link_dt_safety_, dt_link_critical_);
}

// ---------------------------------------------------------------------------
// The step.

StepStatus Engine::step(bool measure) {
  using S = StageProfile;
  failure_.clear();
  status_ = StepStatus::Ok;
  lap_ = TickClock::now();
  updateNeighbours();
  lap(S::kNeighbours);
  // Loose spheres only: each partition's spheres move in the contact job,
  // as soon as the forces on them are complete (no join between the stages).
  const bool move_spheres = all_loose_;
  computeContactForces(measure, move_spheres);
  lap(S::kContacts);
  applyWallsAndLoads(measure);
  lap(S::kWalls);
  if (status_ != StepStatus::Ok) return status_;
  integrate(measure, move_spheres);
  lap(S::kIntegrate);
  advanceLinkedNodes(measure);
  lap(S::kLinks);
  checkStep(measure);
  if (status_ != StepStatus::Ok) return status_;
  balanceShares();  // the threads' shares of the next steps' partitions
  if (measure) measureEnergy();
  lap(S::kEnergy);
  ++step_;
  time_ += dt_;
  return status_;
}

const char* StageProfile::name(int stage) {
  static const char* const names[kStageCount] = {"neighbours", "contacts", "links", "walls", "integrate", "energy"};
  return names[stage];
}

void Engine::lap(StageProfile::Stage stage) {
  const std::uint64_t now = TickClock::now();
  ticks_[stage] += now - lap_;
  lap_ = now;
}

StageProfile Engine::profile() const {
  StageProfile p;
  const double s = clock_.secondsPerTick();
  for (int k = 0; k < StageProfile::kStageCount; ++k) p.wall_s[k] = s * static_cast<double>(ticks_[k]);
  // One thread: busy for the whole stage (no clock reads of its own).
  // Several: the particle-wall part of each thread's contact jobs goes under walls.
  p.thread_busy_s.resize(thread_ticks_.size());
  for (std::size_t t = 0; t < thread_ticks_.size(); ++t) {
    if (pool_->threads() == 1) {
      p.thread_busy_s[t] = p.wall_s;
      continue;
    }
    const ThreadTicks& c = thread_ticks_[t];
    for (int k = 0; k < StageProfile::kStageCount; ++k) p.thread_busy_s[t][k] = s * static_cast<double>(c.busy[k]);
    p.thread_busy_s[t][StageProfile::kWalls] += s * static_cast<double>(c.walls);
    p.thread_busy_s[t][StageProfile::kContacts] -= s * static_cast<double>(c.walls);
  }
  return p;
}

// A job on every partition, each on whichever thread claims it. In the
// integration a thread takes over another's partitions only if that thread
// has not started its share (a worker not scheduled yet): a partition whose
// contacts its owner has just computed is integrated by that owner, in
// whose cache its particles are (taking over its tail, as the other stages
// do, moved one partition a step from one core to the other and back: it
// cost a third of the integration's time on two threads at N = 5,000).
template <class Job>
void Engine::parallel(StageProfile::Stage stage, const Job& job, const WorkerPool::Then& then) {
  if (pool_->threads() == 1) {
    pool_->run([&](int t, int) { job(t); }, true, then);
    return;
  }
  const bool take_tails = stage != StageProfile::kIntegrate;
  pool_->run(
      [&](int t, int thread) {
        const std::uint64_t start = TickClock::now();
        scratch_[static_cast<std::size_t>(t)].thread = thread;
        job(t);
        const std::uint64_t end = TickClock::now();
        ThreadTicks& c = thread_ticks_[static_cast<std::size_t>(thread)];
        c.busy[stage] += end > start ? end - start : 0;
        if (stage == StageProfile::kContacts) ++c.contact_jobs;
      },
      take_tails, then);
}

// The threads' shares of the partitions, from their speeds in the contact
// stage (partitions run per busy tick) over the last 32 steps: a
// thread on a slower core (a virtual CPU whose host core is busy elsewhere;
// its speed changes over seconds) gets fewer partitions, so that the threads
// end the stage together instead of the faster one taking over the slower
// one's tail at every step, which moves that partition's particles from one
// core's cache to the other's and back. Which thread runs a partition
// changes nothing in its arithmetic: the results do not depend on the shares.
void Engine::balanceShares() {
  const std::size_t T = thread_ticks_.size();
  // (a count of its own: the threads' lines are read only when it is due)
  if (T == 1 || ++steps_since_balance_ < 32) return;
  steps_since_balance_ = 0;
  std::vector<double> speed(T);
  for (std::size_t t = 0; t < T; ++t) {
    const ThreadTicks &now = thread_ticks_[t], &from = shares_from_[t];
    const std::uint64_t busy = now.busy[StageProfile::kContacts] - from.busy[StageProfile::kContacts];
    speed[t] = busy > 0 ? static_cast<double>(now.contact_jobs - from.contact_jobs) / static_cast<double>(busy) : 0.0;
  }
  shares_from_ = thread_ticks_;
  std::vector<int> current(T + 1);
  for (std::size_t u = 0; u <= T; ++u) current[u] = pool_->shareBegin(static_cast<int>(u));
  const std::vector<int> next = sharesForSpeeds(speed, current, pool_->size());
  if (next != current) pool_->setShares(next);
}

// fn(b) for blocks b = 0 .. blocks-1 of the neighbour stage's passes (ranges
// of particles, pairs or rows, in order). Partition t's job runs the blocks
// of its own range first, claiming them from its own counter (one cache line
// each, so uncontended), then helps the others' (in the mixed-size scene the
// last blocks, which hold the large spheres, cost most). A job thus mostly
// reads the particles its thread has in its cache from the last steps; one
// counter shared by all blocks, handed out in turn, spread them over both
// cores and made every claim a transfer of that line between them.
template <class Fn>
void Engine::forBlocks(StageProfile::Stage stage, std::size_t blocks, const Fn& fn) {
  const std::size_t P = scratch_.size();
  for (std::size_t t = 0; t < P; ++t) block_next_[t].b.store(blocks * t / P, std::memory_order_relaxed);
  parallel(stage, [&](int task) {
    for (std::size_t k = 0; k < P; ++k) {
      const std::size_t u = (static_cast<std::size_t>(task) + k) % P, end = blocks * (u + 1) / P;
      std::atomic<std::size_t>& next = block_next_[u].b;
      for (std::size_t b = next.fetch_add(1, std::memory_order_relaxed); b < end;
           b = next.fetch_add(1, std::memory_order_relaxed))
        fn(b);
    }
  });
}

ForBlocks Engine::neighbourBlocks() {
  return [this](std::size_t blocks, const std::function<void(std::size_t)>& fn) {
    forBlocks(StageProfile::kNeighbours, blocks, fn);
  };
}

// A whole number of blocks per partition (up to four: fewer particles than
// 256 a block do not pay for their claims).
std::size_t Engine::rebuildBlocks() const {
  const auto threads = static_cast<std::size_t>(pool_->threads());
  const std::size_t P = scratch_.size();
  return threads == 1 ? 1 : P * std::clamp<std::size_t>(p_.size() / (256 * P), 1, 4);
}

// ---------------------------------------------------------------------------
// updateNeighbours: rebuilds the Verlet list when a particle (or wall) has
// moved more than half the skin since the last build: note the touching
// contacts by stable ids, sort the particles by size class and cell, build
// the list and the wall candidates, carry the contacts' history over, and
// split the rows among the workers.

struct Engine::SavedContacts {
  /// A touching pair of the list by stable ids, and where its history is
  /// (partition t, index c in its last contact set, untouched until restored).
  struct Pair {
    std::uint32_t a, b, t, c;
  };
  std::vector<Pair> pairs;
  /// A wall's touching candidates by stable id, with their history.
  struct WallContact {
    std::uint32_t id;
    StampedHistory::Entry h;
  };
  std::vector<std::vector<WallContact>> walls;
};

void Engine::updateNeighbours() {
  if (!need_rebuild_) return;
  const SavedContacts saved = saveContacts();
  reorderParticles(grid_.sortOrder(p_, skin_m_, rebuildBlocks(), neighbourBlocks()));
  grid_.buildList(p_, skin_m_, excluded_, rebuildBlocks(), neighbourBlocks(), list_);
  sizeTouchBuffers();
  wallCandidates(p_, walls_, skin_m_, rebuildBlocks(), neighbourBlocks());
  if (laws_.any_viscous) wallDamping(p_, walls_, laws_);
  restoreContacts(saved);
  p_.x0 = p_.x, p_.y0 = p_.y, p_.z0 = p_.z;  // reference for the displacement test
  for (RigidBlock& b : blocks_) b.markListBuild();
  need_rebuild_ = false;
  just_rebuilt_ = true;
  ++rebuilds_;
}

// The contact kernel's buffers of touching pairs: a chunk plus 8 (the scan
// flushes a full chunk after each group of eight entries, and the vector
// scan stores eight entries whole).
void Engine::sizeTouchBuffers() {
  const std::size_t size = kChunk + 8 + 8;
  for (auto& sc : scratch_) {
    sc.touch_i.resize(size);
    sc.touch_k.resize(size);
    for (auto* v : {&sc.touch_ex, &sc.touch_ey, &sc.touch_ez}) v->resize(size);
  }
}

Engine::SavedContacts Engine::saveContacts() {
  SavedContacts saved;
  const std::size_t workers = scratch_.size();
  std::vector<std::size_t> base(workers + 1, 0);
  for (std::size_t t = 0; t < workers; ++t) base[t + 1] = base[t] + scratch_[t].sets[hcur_].n;
  saved.pairs.resize(base[workers]);
  parallel(StageProfile::kNeighbours, [&](int task) {
    const auto t = static_cast<std::size_t>(task);
    const ContactSet& cs = scratch_[t].sets[hcur_];
    SavedContacts::Pair* const out = saved.pairs.data() + base[t];
    std::size_t i = cs.n > 0 ? part_begin_[t] : 0;
    for (std::size_t c = 0; c < cs.n; ++c) {
      const std::uint32_t k = cs.k[c];
      while (list_.row_begin[i + 1] <= k) ++i;
      out[c] = {p_.id[i], p_.id[list_.nbr[k]], static_cast<std::uint32_t>(t), static_cast<std::uint32_t>(c)};
    }
  });
  saved.walls.resize(walls_.size());
  for (std::size_t w = 0; w < walls_.size(); ++w) {
    const Wall& wall = walls_[w];
    for (std::size_t k = 0; k < wall.cand.size(); ++k)
      if (wall.hist.touched(k, step_ - 1)) saved.walls[w].push_back({p_.id[wall.cand[k]], wall.hist.get(k)});
  }
  return saved;
}

// The store's state fields are gathered in the new order into spare buffers
// of their type and swapped with them, each worker a range of the new order:
// the range its partitions will hold, so that it writes the lines it reads
// at the next steps (one field to a worker, half of every field's lines went
// from one core to the other at each rebuild, and back at the next step).
// The spares: the scratch fields (forces, torques, the positions at the
// last build: each rewritten after a rebuild before it is read) for the
// doubles, and kept buffers for the other types; a field swapped out is the
// spare of a later one. Two rounds (a job each): nine doubles, then the
// rest. No buffer is allocated (a new one per field and rebuild fragmented
// the heap under aligned allocations: the settling run at N = 20,000 grew
// by 6 MB over its rebuilds).
void Engine::reorderParticles(const std::vector<std::uint32_t>& order) {
  const std::size_t n = p_.size(), P = scratch_.size();
  reorder_spares_.resize(n);
  using I32 = std::vector<std::int32_t>;
  using U32 = std::vector<std::uint32_t>;
  using U8 = std::vector<std::uint8_t>;
  std::tuple<std::vector<Field<double>*>, std::vector<I32*>, std::vector<U32*>, std::vector<U8*>> spares;
  p_.forEachScratchField([&](const char*, Field<double>& f) { std::get<0>(spares).push_back(&f); });
  std::get<1>(spares) = {&reorder_spares_.i32};
  std::get<2>(spares) = {&reorder_spares_.u32[0], &reorder_spares_.u32[1]};
  std::get<3>(spares) = {&reorder_spares_.u8[0], &reorder_spares_.u8[1]};
  // A round: fields paired with their spares.
  std::tuple<std::vector<std::pair<Field<double>*, Field<double>*>>, std::vector<std::pair<I32*, I32*>>,
             std::vector<std::pair<U32*, U32*>>, std::vector<std::pair<U8*, U8*>>>
      round;
  const auto eachType = [&](auto&& fn) { std::apply([&](auto&... pairs) { (fn(pairs), ...); }, round); };
  const auto runRound = [&] {
    parallel(StageProfile::kNeighbours, [&](int task) {
      const auto t = static_cast<std::size_t>(task);
      const std::size_t k0 = n * t / P, k1 = n * (t + 1) / P;
      const std::uint32_t* __restrict const from = order.data();
      eachType([&](auto& pairs) {
        for (auto& [field, spare] : pairs) {
          const auto* __restrict const v = field->data();
          auto* __restrict const w = spare->data();
          for (std::size_t k = k0; k < k1; ++k) w[k] = v[from[k]];
        }
      });
    });
    eachType([&](auto& pairs) {
      for (auto& [field, spare] : pairs) {
        std::swap(*field, *spare);
        std::get<std::vector<std::remove_pointer_t<decltype(spare)>*>>(spares).push_back(spare);
      }
      pairs.clear();
    });
  };
  p_.forEachStateField([&](const char*, auto& field) {
    using V = std::remove_reference_t<decltype(field)>;
    auto& free = std::get<std::vector<V*>>(spares);
    if (free.empty()) runRound();
    V* const spare = free.back();
    free.pop_back();
    std::get<std::vector<std::pair<V*, V*>>>(round).emplace_back(&field, spare);
  });
  runRound();
  for (std::size_t k = 0; k < n; ++k) p_.slot[p_.id[k]] = static_cast<std::uint32_t>(k);
}

// Carries the history of touching contacts over to the new list: a pair that
// touched is within reach, so it is in the new list; then splits the rows
// among the workers and gives each partition its carried contacts, in list
// order, as its "last step" contact set.
void Engine::restoreContacts(const SavedContacts& saved) {
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> from(list_.nbr.size(), kNone);  // list entry -> index in saved.pairs
  const std::size_t nblocks = rebuildBlocks();
  // each pair has its own list entry: no two blocks write the same
  forBlocks(StageProfile::kNeighbours, nblocks, [&](std::size_t blk) {
    const std::size_t m = saved.pairs.size();
    for (std::size_t q = m * blk / nblocks; q < m * (blk + 1) / nblocks; ++q) {
      const std::uint32_t a = p_.slot[saved.pairs[q].a], b = p_.slot[saved.pairs[q].b];
      const std::uint32_t i = std::min(a, b), j = std::max(a, b);
      const auto first = list_.nbr.begin() + list_.row_begin[i], end = list_.nbr.begin() + list_.row_begin[i + 1];
      const auto it = std::lower_bound(first, end, j);
      if (it != end && *it == j) from[static_cast<std::size_t>(it - list_.nbr.begin())] = static_cast<std::uint32_t>(q);
    }
  });
  for (std::size_t w = 0; w < walls_.size(); ++w) {
    Wall& wall = walls_[w];
    for (const auto& s : saved.walls[w]) {
      const std::uint32_t i = p_.slot[s.id];
      const auto it = std::lower_bound(wall.cand.begin(), wall.cand.end(), i);
      if (it == wall.cand.end() || *it != i) continue;
      wall.hist.set(static_cast<std::size_t>(it - wall.cand.begin()), s.h, step_ - 1);
    }
  }
  partitionRows(from);
  line_partition_.resize(p_.size() / kParticlesPerLine + 1);
  const int next = hcur_ ^ 1;
  parallel(StageProfile::kNeighbours, [&](int task) {
    const auto t = static_cast<std::size_t>(task);
    sizeForceBuffer(t);
    ContactSet& out = scratch_[t].sets[next];
    const std::uint32_t k0 = list_.row_begin[part_begin_[t]], k1 = list_.row_begin[part_begin_[t + 1]];
    std::size_t count = 0;
    for (std::uint32_t k = k0; k < k1; ++k) count += from[k] != kNone ? 1 : 0;
    out.ensure(count, laws_.any_plastic, laws_.any_viscous);
    out.n = 0;
    for (std::uint32_t k = k0; k < k1; ++k) {
      if (from[k] == kNone) continue;
      const SavedContacts::Pair& sc = saved.pairs[from[k]];
      const ContactSet& in = scratch_[sc.t].sets[hcur_];
      out.k[out.n] = k;
      out.ux[out.n] = in.ux[sc.c], out.uy[out.n] = in.uy[sc.c], out.uz[out.n] = in.uz[sc.c];
      if (laws_.any_plastic) out.plastic[out.n] = in.plastic[sc.c];
      if (laws_.any_viscous) out.viscous[out.n] = in.viscous[sc.c];
      ++out.n;
    }
  });
  findReachedFrom();
  hcur_ = next;
}

// Partition t's buffer for the forces on partners beyond its rows: from its
// end to the line of the largest partner of its rows (each row's partners
// increase, so the last of each row), at least that long. Zero when unused: the
// integration clears what it adds, so a buffer that only grows, or whose
// first particle moves, needs no clearing.
void Engine::sizeForceBuffer(std::size_t t) {
  WorkerScratch& s = scratch_[t];
  const std::uint32_t r0 = part_begin_[t], r1 = part_begin_[t + 1];
  std::uint32_t reach = 0;
  for (std::uint32_t i = r0; i < r1; ++i)
    if (list_.row_begin[i + 1] > list_.row_begin[i]) reach = std::max(reach, list_.nbr[list_.row_begin[i + 1] - 1]);
  reach_[t] = reach;  // (findReachedFrom)
  s.lines_for.resize(scratch_.size());
  for (std::uint32_t g = r0 / kParticlesPerLine; g * kParticlesPerLine < r1; ++g)  // (boundaries start lines)
    line_partition_[g] = static_cast<std::uint32_t>(t);
  // (whole lines: the integration adds them whole)
  constexpr std::size_t kLine = kParticlesPerLine;
  const std::size_t span = reach >= r1 ? (std::size_t{reach} - r1 + kLine) / kLine * kLine : 0;
  if (span <= s.fx.size()) return;
  for (auto* v : {&s.fx, &s.fy, &s.fz, &s.tx, &s.ty, &s.tz}) v->resize(span, 0.0);
  s.written.resize(span / kParticlesPerLine + 1, 0);
}

// Per partition u, the first partition whose rows reach into it (every one
// from there to u then may have: computeContactForces moves u's spheres
// once those are done), from the partitions' reaches (sizeForceBuffer).
void Engine::findReachedFrom() {
  for (std::size_t u = 0; u < scratch_.size(); ++u) {
    std::size_t t = 0;
    while (t < u && reach_[t] < part_begin_[u]) ++t;
    reached_from_[u] = static_cast<std::uint32_t>(t);
  }
}

// Row partitions with equal estimated work, several per thread
// (kPartitionsPerThread). A partition holds its rows' contacts, the wall
// candidates among its particles and, after the join, the integration of its
// particles (their lines stay in the cache of the core that ran it). The
// work per row (scan and integration), per list entry (touch scan), per pair
// that touched at the last step (contact law) and per wall candidate is in the
// ratio 2 : 2 : 13 : 9 of their costs (per-step partition times of the
// settling benchmark, fitted: 2.5, 2.6-2.9, 17-18 and 12 ns). They depend
// only on the state, so runs stay deterministic for a given thread count:
// which thread runs a partition changes nothing in its arithmetic.
void Engine::partitionRows(const std::vector<std::uint32_t>& from) {
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const std::size_t n = p_.size(), T = scratch_.size(), nblocks = rebuildBlocks();
  part_begin_.assign(T + 1, static_cast<std::uint32_t>(n));
  part_begin_[0] = 0;
  if (T == 1) return;
  constexpr std::size_t kRowWeight = 2, kEntryWeight = 2, kTouchWeight = 13, kWallWeight = 9;
  std::vector<std::uint32_t> cand(n, 0);  // per particle: of how many walls a candidate
  for (const Wall& w : walls_)
    for (const std::uint32_t i : w.cand) ++cand[i];
  // The weight of the rows [i0, i1), as flat counts over the rows and over
  // their list entries (loops without a branch on each row's length, which
  // a row-by-row sum mispredicted at most rows).
  const auto weightOf = [&](std::size_t i0, std::size_t i1) {
    const std::uint32_t* __restrict const C = cand.data();
    const std::uint32_t* __restrict const F = from.data();
    std::size_t walls = 0, touching = 0;
    for (std::size_t i = i0; i < i1; ++i) walls += C[i];
    const std::size_t k0 = list_.row_begin[i0], k1 = list_.row_begin[i1];
    for (std::size_t k = k0; k < k1; ++k) touching += F[k] != kNone ? 1 : 0;
    return kRowWeight * (i1 - i0) + kWallWeight * walls + kEntryWeight * (k1 - k0) + kTouchWeight * touching;
  };
  const auto blockBegin = [&](std::size_t b) { return n * b / nblocks; };
  // Block sums in parallel; the boundaries are then found row by row only
  // inside the blocks that hold them (the same boundaries as a serial scan).
  std::vector<std::size_t> block_weight(nblocks, 0);
  forBlocks(StageProfile::kNeighbours, nblocks,
            [&](std::size_t b) { block_weight[b] = weightOf(blockBegin(b), blockBegin(b + 1)); });
  const std::size_t total = std::accumulate(block_weight.begin(), block_weight.end(), std::size_t{0});
  std::size_t t = 1, acc = 0;
  for (std::size_t b = 0; b < nblocks && t < T; ++b) {
    if (acc + block_weight[b] < total * t / T) {
      acc += block_weight[b];
      continue;
    }
    for (std::size_t i = blockBegin(b); i < blockBegin(b + 1) && t < T; ++i) {
      while (t < T && acc >= total * t / T) part_begin_[t] = lineStart(i, part_begin_[t - 1]), ++t;
      acc += weightOf(i, i + 1);
    }
  }
}

// ---------------------------------------------------------------------------
// computeContactForces: each wall's motion over this step planned, then one
// job per row partition: the particle-particle contacts of its rows
// (micro/contact_kernel.cpp), then the particle-wall contacts of its
// particles (micro/walls.cpp, same law). Its particles' forces are its own
// to add to; those on partners beyond its rows go to its buffer, added at
// the start of integrate(), in the same pass over the particles. (One join
// a step fewer than walls on ranges of their own, and the walls' particles
// are in the cache of the worker that just wrote their forces.)
//
// With move_spheres (every particle a loose sphere), each thread then moves
// the spheres of the partitions it ran (integratePartition), each as soon as
// the partitions whose rows reach into it are done: no join between the two
// stages, so the thread that the contacts with another's particles slowed
// does not wait at it for the one that the moves of the shared particles
// slow. The arithmetic is that of the two stages apart (the same buffers
// added in the same order), and every partition moves whatever its
// contacts found: a step that fails (an overlap beyond the limit) still
// moves the loose spheres, the same way for any thread count.

void Engine::computeContactForces(bool measure, bool move_spheres) {
  for (Wall& w : walls_) w.plan(time_, dt_);
  const std::uint64_t job = ++contact_job_;
  if (move_spheres)
    for (ThreadTicks& c : thread_ticks_) c.moved = 0;
  WorkerPool::Then then;
  if (move_spheres)
    then = [this, measure](int thread, const std::vector<int>& ran) { integrateWhenReady(thread, ran, measure); };
  parallel(
      StageProfile::kContacts,
      [this, measure, move_spheres, job](int task) {
        const auto t = static_cast<std::size_t>(task);
        const std::uint32_t r0 = part_begin_[t], r1 = part_begin_[t + 1];
        WorkerScratch& s = scratch_[t];
        contactPartition(p_, list_, laws_, dt_, max_overlap_ratio_, r0, r1, hcur_, measure, line_partition_, s);
        const std::uint64_t walls_from = TickClock::now();
        wallPartition(p_, walls_, laws_, dt_, max_overlap_ratio_, step_, r0, r1, measure, s);
        const std::uint64_t walls_to = TickClock::now();
        s.wall_ticks = walls_to > walls_from ? walls_to - walls_from : 0;  // (0 if moved to a core whose count lags)
        if (move_spheres) finished_[t].job.store(job, std::memory_order_release);
      },
      then);
  // The profile keeps the walls and the moves apart: their partitions' part
  // of the job, and the mean of those of the stage (the step's next lap
  // counts from it: no partition is then busier in any stage than the stage
  // lasted).
  std::uint64_t walls = 0, moved = 0;
  for (const WorkerScratch& s : scratch_)
    walls += s.wall_ticks, thread_ticks_[static_cast<std::size_t>(s.thread)].walls += s.wall_ticks;
  if (move_spheres)
    for (const ThreadTicks& c : thread_ticks_) moved += c.moved;
  std::uint64_t now = TickClock::now();
  walls = std::min(walls / thread_ticks_.size(), now > lap_ ? now - lap_ : 0);
  ticks_[StageProfile::kWalls] += walls;
  lap_ += walls;
  moved = std::min(moved / thread_ticks_.size(), now > lap_ ? now - lap_ : 0);
  ticks_[StageProfile::kIntegrate] += moved;
  lap_ += moved;
  hcur_ ^= 1;  // this step's contact sets become the last step's
  contacts_ = 0;
  for (const WorkerScratch& s : scratch_) {
    energy_.friction += s.energy.friction_J;
    energy_.plastic += s.energy.plastic_J;
    energy_.viscous += s.energy.viscous_J;
    if (measure) energy_.elastic_contact += s.energy.elastic_J;
    contacts_ += s.contacts;
  }
  for (const WorkerScratch& s : scratch_)
    if (s.failed) {
      std::ostringstream m;
      m << "overlap " << s.fail_ratio << " of the smaller radius (limit " << max_overlap_ratio_ << ") between "
        << bodyName(p_.id[s.fail_i]) << " and " << bodyName(p_.id[s.fail_j]);
      fail(StepStatus::Overlap, m.str());
      break;
    }
}

// ---------------------------------------------------------------------------
// advanceLinkedNodes (micro/linked_nodes.cpp, micro/links.cpp): the link
// nodes in `substeps_` sub-steps, each with the link forces of its positions
// (per link over ranges of links, then summed per node) and the contact and
// wall forces of the step held, with the bending wires' forces and torques
// (once per step, from the step's start).

namespace {
// Below these a sub-step's work is shorter than handing it to a worker (a
// small sheet of netting). A cell's netting (1,578 wires, 1,245 nodes) is
// split: its CC test on two threads took 2.0 s instead of 2.6 s.
constexpr std::size_t kSerialLinks = 512, kSerialNodes = 512;
}  // namespace

void Engine::advanceLinkedNodes(bool measure) {
  if (nodes_.empty()) return;
  const std::size_t nl = links_.size();
  const std::size_t parts = nl < kSerialLinks ? 1 : scratch_.size();
  // The nodes' sums and kicks, by ranges of nodes on the workers likewise
  // (each node's arithmetic is its own; the ranges' energy sums add in
  // range order).
  const std::size_t nn = nodes_.size(), node_parts = nn < kSerialNodes ? 1 : scratch_.size();
  std::vector<SphereSums>& part_sums = node_sums_;
  part_sums.resize(node_parts);
  const auto overLinks = [&](const auto& job) {  // job(scratch, first link, end)
    for (WorkerScratch& s : scratch_)
      s.link_elastic = s.link_rupture = s.link_plastic = s.link_pull_work = 0.0, s.link_events.clear();
    const auto part = [&](int task) {
      const auto t = static_cast<std::size_t>(task);
      const Range r = evenPart(nl, t, parts);
      job(scratch_[t], r.first, r.end);
    };
    if (parts == 1)
      part(0);
    else
      parallel(StageProfile::kLinks, part);
  };
  // The beams from the nodes' turn over the last step, then the held forces.
  if (links_.hasBeams()) {
    overLinks([&](WorkerScratch& s, std::size_t l0, std::size_t l1) {
      links_.evaluateBeams(nodes_.x(), nodes_.y(), nodes_.z(), nodes_.turnX(), nodes_.turnY(), nodes_.turnZ(), l0, l1,
                           measure, s);
    });
    if (measure)
      for (const WorkerScratch& s : scratch_)
        energy_.elastic_link += s.link_elastic, energy_.link_plastic += s.link_plastic;
  }
  // The nodes' copies, sums and kicks by ranges of nodes (each node's are
  // its own).
  const auto overNodes = [&](const auto& job) {  // job(range, first node, end)
    if (node_parts == 1) return job(std::size_t{0}, std::size_t{0}, nn);
    parallel(StageProfile::kLinks, [&](int task) {
      const auto t = static_cast<std::size_t>(task);
      const Range r = evenPart(nn, t, node_parts);
      job(t, r.first, r.end);
    });
  };
  const bool rebuilt = rebuilds_ != nodes_rebuilds_;
  overNodes([&](std::size_t, std::size_t k0, std::size_t k1) {
    nodes_.hold(p_, rebuilt, k0, k1);
    if (links_.hasBeams()) nodes_.addBeams(links_, k0, k1);
  });
  nodes_rebuilds_ = rebuilds_;
  if (nodes_.hasRiders()) nodes_.ride(walls_, dt_);
  const double h = dt_ / substeps_;
  for (int k = 0; k < substeps_; ++k) {
    const bool last = k + 1 == substeps_, m = measure && last;
    overLinks([&](WorkerScratch& s, std::size_t l0, std::size_t l1) {
      links_.evaluate(nodes_.x(), nodes_.y(), nodes_.z(), l0, l1, time_ + k * h, m, s);
    });
    for (const WorkerScratch& s : scratch_) {
      if (m) energy_.elastic_link += s.link_elastic, energy_.link_plastic += s.link_plastic;
      energy_.link_rupture += s.link_rupture;
      energy_.driven_work += s.link_pull_work;  // (the pull's work: an agent outside the bodies, as a driven sphere's)
      link_events_.insert(link_events_.end(), s.link_events.begin(), s.link_events.end());
    }
    overNodes([&](std::size_t t, std::size_t k0, std::size_t k1) {
      part_sums[t] = nodes_.advance(links_, k, substeps_, h, gravity_, m, k0, k1);
    });
    SphereSums s;
    if (node_parts == 1)
      s = part_sums[0];
    else
      for (const SphereSums& p : part_sums) s.add(p);  // (in part order)
    nodes_.addDrivenWork(k, substeps_, h, energy_.driven_work);
    if (nodes_.hasRiders()) nodes_.addRiderForces(substeps_);
    sums_.local += s.local, sums_.finite += s.finite, sums_.max_d2 = std::max(sums_.max_d2, s.max_d2);
    if (m) sums_.ke_t += s.ke_t, sums_.ke_r += s.ke_r, sums_.pe += s.pe, sums_.ke_now += s.ke_now;
  }
  overNodes([&](std::size_t, std::size_t k0, std::size_t k1) { nodes_.store(p_, dt_, k0, k1); });
}

// ---------------------------------------------------------------------------
// applyWallsAndLoads (micro/walls.cpp): the force on each wall and the work
// of moving walls from the partitions' particle-wall contacts (summed in
// partition order), the riders' pull, and the driven walls' move. Gravity is
// applied in integrate().

void Engine::applyWallsAndLoads(bool measure) {
  for (auto& w : walls_) w.force_N.setZero(), w.force_position = w.position;
  for (WorkerScratch& s : scratch_) {
    for (std::size_t w = 0; w < walls_.size(); ++w) walls_[w].force_N += s.wall_force[w];
    energy_.friction += s.wall_energy.friction_J;
    energy_.plastic += s.wall_energy.plastic_J;
    energy_.viscous += s.wall_energy.viscous_J;
    if (measure) energy_.elastic_contact += s.wall_energy.elastic_J;
    energy_.wall_work += s.wall_work;
    contacts_ += s.wall_contacts;
    if (s.wall_failed) {
      std::ostringstream m;
      m << "overlap " << s.wall_fail_ratio << " of the radius (limit " << max_overlap_ratio_ << ") between "
        << bodyName(p_.id[s.wall_fail_i]) << " and wall '" << walls_[s.wall_fail_wall].name << "'";
      fail(StepStatus::Overlap, m.str());
    }
  }
  // The links of the spheres that ride the walls pull them too: with the
  // force of their last step (they act inside the step, after the walls
  // moved), whose work the ledger has as the riders' (driven_work).
  rider_force_.assign(walls_.size(), Vec3::Zero());
  if (nodes_.hasRiders()) nodes_.addWallForces(rider_force_);
  driveWalls();
  for (std::size_t w = 0; w < walls_.size(); ++w) walls_[w].force_N += rider_force_[w];
}

void Engine::driveWalls() {
  if (!driver_ || status_ != StepStatus::Ok) return;
  driven_force_.clear();
  for (std::size_t w = 0; w < walls_.size(); ++w)
    if (walls_[w].program.kind == WallProgram::Kind::Driven)
      driven_force_.push_back(walls_[w].force_N + rider_force_[w]);
  if (driven_force_.empty()) return;
  driven_move_.assign(driven_force_.size(), Vec3::Zero());
  driver_(time_, dt_, driven_force_, driven_move_);
  std::size_t k = 0;
  for (Wall& w : walls_) {
    if (w.program.kind != WallProgram::Kind::Driven) continue;
    const Vec3& d = driven_move_[k++];
    // The contacts counted the work at the last step's velocity; the wall
    // moves by d: its work on the bodies is -F . d (F the contacts' force:
    // the riders' work is theirs).
    energy_.wall_work -= w.force_N.dot(d - w.velocity * dt_);
    w.step_displacement = d;
    w.velocity = d / dt_;
  }
}

// ---------------------------------------------------------------------------
// integrate (micro/integrator.cpp): free spheres per worker (its row
// partition, in the same pass as the force buffers; when every particle is
// a loose sphere, already in the contact job: computeContactForces), blocks
// in parallel, walls moved; partial sums in a fixed order (deterministic for
// a given thread count). Also checks for non-finite states and whether the
// list must be rebuilt.

// The contact kernel's partitions t before u left the forces on particles of
// u in their buffers (particle i at i - part_begin_[t + 1]), and listed the lines they
// wrote for u; they are added here, for each particle in partition order,
// and the buffers, marks and lists cleared.
void Engine::addForceBuffers(std::size_t u) {
  constexpr std::size_t kLine = kParticlesPerLine;
  const std::size_t e = part_begin_[u + 1];
  for (std::size_t t = 0; t < u; ++t) {
    WorkerScratch& s = scratch_[t];
    const std::size_t base = part_begin_[t + 1];  // (the buffer starts at the partition's end)
    std::vector<std::uint32_t>& lines = s.lines_for[u];
    double* const to[6] = {p_.fx.data(), p_.fy.data(), p_.fz.data(), p_.tx.data(), p_.ty.data(), p_.tz.data()};
    double* const from[6] = {s.fx.data(), s.fy.data(), s.fz.data(), s.tx.data(), s.ty.data(), s.tz.data()};
    for (const std::uint32_t g : lines) {
      const std::size_t i0 = g * kLine, q0 = i0 - base, m = std::min(e, i0 + kLine) - i0;
      s.written[q0 / kLine] = 0;
      // (a whole line in one vector per field but at the store's end; the
      // same additions, element by element)
      for (int f = 0; f < 6; ++f) {
        double* __restrict const a = to[f] + i0;
        double* __restrict const b = from[f] + q0;
        if (m == kLine) {
#pragma omp simd
          for (std::size_t k = 0; k < kLine; ++k) a[k] += b[k], b[k] = 0.0;
        } else {
          for (std::size_t k = 0; k < m; ++k) a[k] += b[k], b[k] = 0.0;
        }
      }
    }
    lines.clear();
  }
}

// Partition t's loose spheres, once every force on them is in: the
// buffers of the partitions before it, then its own range (vectorised when
// every particle is a loose sphere).
void Engine::integratePartition(std::size_t t, bool measure) {
  const std::size_t b = part_begin_[t], e = part_begin_[t + 1];  // (the partition's own particles)
  addForceBuffers(t);
  if (all_loose_) {
    scratch_[t].spheres = integrateSpheres(p_, b, e, dt_, gravity_, measure, any_local_damping_, one_body_);
    return;
  }
  // Blocks and link nodes move in their own passes: only the loose spheres
  // here (none in a cell of blocks in a netting), each worker those in its
  // range, whose forces it has just completed.
  SphereSums& sum = scratch_[t].spheres;
  sum = SphereSums{};
  for (const std::uint32_t id : loose_) {
    const std::size_t i = p_.slot[id];
    if (i < b || i >= e) continue;
    sum.add(integrateSpheres(p_, i, i + 1, dt_, gravity_, measure, any_local_damping_));
  }
}

// In the contact job, on the thread that ran the partitions `ran`: each
// moves once its contacts and those of the partitions whose rows reach into
// it are done (their buffers hold the rest of its forces, and they read its
// positions). Its own come first; one that waits for another thread's goes
// after the others (the first of a share, past the boundary with the share
// before).
void Engine::integrateWhenReady(int thread, const std::vector<int>& ran, bool measure) {
  const std::uint64_t job = contact_job_;
  const auto ready = [&](int u) {
    for (std::size_t t = reached_from_[static_cast<std::size_t>(u)]; t <= static_cast<std::size_t>(u); ++t)
      if (finished_[t].job.load(std::memory_order_acquire) != job) return false;
    return true;
  };
  std::vector<int>& waiting = waiting_[static_cast<std::size_t>(thread)].list;
  waiting.clear();
  std::uint64_t work = 0;  // (the moves alone, without the waits)
  const auto move = [&](int u) {
    const std::uint64_t from = TickClock::now();
    integratePartition(static_cast<std::size_t>(u), measure);
    const std::uint64_t to = TickClock::now();
    work += to > from ? to - from : 0;
  };
  for (const int u : ran) {
    if (ready(u))
      move(u);
    else
      waiting.push_back(u);
  }
  for (unsigned spins = 0; !waiting.empty();) {
    const auto it = std::find_if(waiting.begin(), waiting.end(), ready);
    if (it == waiting.end()) {
      // (the partitions waited for are running: a few microseconds, unless
      // their thread has lost its core)
      if (++spins % 1024 == 0)
        std::this_thread::yield();
      else
        cpuRelax();
      continue;
    }
    move(*it);
    waiting.erase(it);
  }
  ThreadTicks& c = thread_ticks_[static_cast<std::size_t>(thread)];
  c.moved = work;
  c.busy[StageProfile::kIntegrate] += work;
}

void Engine::integrate(bool measure, bool spheres_moved) {
  const std::size_t workers = scratch_.size();
  if (!spheres_moved)
    parallel(StageProfile::kIntegrate, [&](int task) { integratePartition(static_cast<std::size_t>(task), measure); });
  SphereSums& sum = sums_;
  sum = SphereSums{};
  for (const WorkerScratch& w : scratch_) sum.add(w.spheres);
  // Driven spheres (fixed, moving): the work they did on the bodies over this step.
  for (const std::uint32_t id : driven_) {
    const std::uint32_t i = p_.slot[id];
    energy_.driven_work -= dt_ * (p_.fx[i] * p_.vx[i] + p_.fy[i] * p_.vy[i] + p_.fz[i] * p_.vz[i]);
  }
  if (!blocks_.empty()) {
    // Each worker a contiguous range of blocks (blocks cost alike: a shared
    // counter handing them out one by one cost more than it balanced).
    std::vector<SphereSums>& per_block = block_sums_;
    per_block.resize(blocks_.size());
    const std::size_t nb = blocks_.size();
    parallel(StageProfile::kIntegrate, [&](int task) {
      const Range r = evenPart(nb, static_cast<std::size_t>(task), workers);
      for (std::size_t b = r.first; b < r.end; ++b)
        per_block[b] = integrateBlock(blocks_[b], p_, dt_, gravity_, measure);
    });
    for (const SphereSums& s : per_block) sum.add(s);
  }
}

// After the bodies and the link nodes moved: the energies they summed, the
// walls' move, the finiteness probe, and whether the neighbour list is stale.
void Engine::checkStep(bool measure) {
  const SphereSums& sum = sums_;
  const std::size_t n = p_.size();
  energy_.local += sum.local;
  if (measure) energy_.ke_t = sum.ke_t, energy_.ke_r = sum.ke_r, energy_.pe = sum.pe, energy_.kinetic_now = sum.ke_now;
  double wall_move = 0.0;
  for (Wall& w : walls_) {
    w.advance();
    wall_move = std::max(wall_move, (w.position - w.at_rebuild).norm());
  }

  if (!std::isfinite(sum.finite)) {
    for (std::size_t i = 0; i < n; ++i)
      if (!std::isfinite(p_.x[i] + p_.y[i] + p_.z[i] + p_.vx[i] + p_.vy[i] + p_.vz[i] + p_.wx[i] + p_.wy[i] +
                         p_.wz[i])) {
        fail(StepStatus::NonFinite, "non-finite position or velocity of " + bodyName(p_.id[i]));
        return;
      }
    for (std::size_t b = 0; b < blocks_.size(); ++b)
      if (!std::isfinite(blocks_[b].x.sum() + blocks_[b].v.sum() + blocks_[b].L.sum())) {
        fail(StepStatus::NonFinite, "non-finite state of block " + std::to_string(b));
        return;
      }
    fail(StepStatus::NonFinite, "non-finite state");
    return;
  }
  // Right after a rebuild the displacement test measures one step: a body
  // that moved more than the smallest radius (and the skin) in it can pass
  // through a sphere with no step in contact (two spheres closing at
  // 1,000 m/s). (A move between half the skin and that is caught otherwise:
  // a contact the list missed for a step shows as a deep overlap.) The
  // members' own x - x0 confirms (a block's moves come from its state, a
  // rounding apart) and names the body.
  if (just_rebuilt_ && sum.max_d2 > tunnel_m_ * tunnel_m_) {
    double worst = -1.0;
    std::size_t who = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double dx = p_.x[i] - p_.x0[i], dy = p_.y[i] - p_.y0[i], dz = p_.z[i] - p_.z0[i];
      if (dx * dx + dy * dy + dz * dz > worst) worst = dx * dx + dy * dy + dz * dz, who = i;
    }
    if (worst > tunnel_m_ * tunnel_m_) {
      std::ostringstream m;
      m << "tunnelling: " << bodyName(p_.id[who]) << " moved " << std::sqrt(worst)
        << " m in one step, more than the smallest radius (" << tunnel_m_
        << " m): bodies can pass through each other unseen; lower run.dt_s (or run.dt_safety)";
      fail(StepStatus::Tunnelling, m.str());
      return;
    }
  }
  just_rebuilt_ = false;
  const double half = 0.5 * skin_m_;
  if (sum.max_d2 > half * half || wall_move > half) need_rebuild_ = true;
}

// ---------------------------------------------------------------------------
// measureEnergy (micro/energy.cpp): closes the ledger of a measuring step.

void Engine::measureEnergy() {
  const bool ok = energy_.close(runaway_factor_);
  energy_.elastic_contact = energy_.elastic_link = energy_.link_plastic = 0.0;
  if (const char* term = energy_.nonFiniteTerm()) {
    fail(StepStatus::NonFinite, std::string("the energy term ") + term +
                                    " is not finite (a stiffness or mass so small or so large that its products "
                                    "underflow or overflow?)");
    return;
  }
  // (from the 20th measurement: over the first few steps the energy moved is
  // so small that the start-up error of the work terms, O(dt) of the first
  // force, is a large fraction of it)
  const double balance = energy_.totals().balance_rel_error;
  if (++measurements_ > kBalanceWarmup && std::fabs(balance) > max_balance_error_) {
    std::ostringstream m;
    m << "energy balance error " << balance << " beyond run.max_balance_error (" << max_balance_error_
      << "): the time step (" << dt_ << " s";
    if (std::isfinite(dt_critical_) && dt_critical_ > 0.0) m << ", " << dt_ / dt_critical_ << " of the critical step";
    m << ") is too large for the stiffness, or the run is unstable";
    fail(StepStatus::EnergyBalance, m.str());
    return;
  }
  if (ok) return;
  std::ostringstream m;
  m << "energy runaway: kinetic + elastic energy " << energy_.stored() << " J exceeds " << runaway_factor_
    << " x the energy supplied (" << energy_.supplied() << " J)";
  double worst = -1.0;
  std::string who;
  for (std::size_t i = 0; i < p_.size(); ++i) {
    const double ke = (p_.inv_mass[i] > 0.0 ? 1.0 / p_.inv_mass[i] : 0.0) *
                      (p_.vx[i] * p_.vx[i] + p_.vy[i] * p_.vy[i] + p_.vz[i] * p_.vz[i]);
    if (ke > worst) worst = ke, who = bodyName(p_.id[i]);
  }
  for (std::size_t b = 0; b < blocks_.size(); ++b)
    if (blocks_[b].mass * blocks_[b].v.squaredNorm() > worst)
      worst = blocks_[b].mass * blocks_[b].v.squaredNorm(), who = "block " + std::to_string(b);
  m << "; fastest body: " << who;
  fail(StepStatus::EnergyRunaway, m.str());
}

// ---------------------------------------------------------------------------
// archive: the state between two steps. What the scene gives (masses,
// laws, shapes, groups) is rebuilt by the constructor; this is what the
// steps change. The last step's contact sets are stored with the list
// they index, so no rebuild is forced: a run that saves a checkpoint takes
// the same steps as one that does not.

void Engine::archive(bridge::StateArchive& a) {
  const std::size_t n = p_.size();
  a("step", step_), a("time_s", time_), a("dt_s", dt_), a("link_substeps", substeps_);
  a("measurements", measurements_), a("rebuilds", rebuilds_), a("nodes_rebuilds", nodes_rebuilds_);
  a("contact_count", contacts_), a("last_contact_set", hcur_), a("need_rebuild", need_rebuild_);
  a("just_rebuilt", just_rebuilt_);
  bridge::StateArchive pa = a.group("particles");
  p_.archive(pa);
  {
    const std::size_t nb = blocks_.size();
    std::vector<Vec3> x(nb), v(nb), L(nb), omega(nb), x0(nb);
    std::vector<double> q(4 * nb), R0(9 * nb);
    for (std::size_t b = 0; b < nb; ++b) {
      const RigidBlock& k = blocks_[b];
      x[b] = k.x, v[b] = k.v, L[b] = k.L, omega[b] = k.omega, x0[b] = k.x0;
      q[4 * b] = k.q.w(), q[4 * b + 1] = k.q.x(), q[4 * b + 2] = k.q.y(), q[4 * b + 3] = k.q.z();
      Eigen::Map<Eigen::Matrix3d> r0(&R0[9 * b]);
      r0 = k.R0;
    }
    bridge::StateArchive ba = a.group("blocks");
    ba("x", x), ba("v", v), ba("L", L), ba("omega", omega), ba("q", q);
    ba("x_at_list_build", x0), ba("rotation_at_list_build", R0);
    if (a.loading()) {
      if (x.size() != nb || v.size() != nb || L.size() != nb || omega.size() != nb || q.size() != 4 * nb ||
          x0.size() != nb || R0.size() != 9 * nb)
        throw std::invalid_argument("checkpoint: blocks of another number than this run's");
      for (std::size_t b = 0; b < nb; ++b) {
        RigidBlock& k = blocks_[b];
        k.x = x[b], k.v = v[b], k.L = L[b], k.omega = omega[b], k.x0 = x0[b];
        k.q = Eigen::Quaterniond(q[4 * b], q[4 * b + 1], q[4 * b + 2], q[4 * b + 3]);
        k.R0 = Eigen::Map<const Eigen::Matrix3d>(&R0[9 * b]);
      }
    }
  }
  for (Wall& w : walls_) {
    bridge::StateArchive wa = a.group("walls/" + w.name);
    w.archive(wa);
  }
  bridge::StateArchive la = a.group("links"), na = a.group("link_nodes"), ea = a.group("energy");
  links_.archive(la);
  nodes_.archive(na);
  energy_.archive(ea);
  {
    std::vector<double> t, link;
    std::vector<Vec3> at;
    for (const LinkEvent& e : link_events_)
      t.push_back(e.time_s), link.push_back(static_cast<double>(e.link)), at.push_back(e.position_m);
    bridge::StateArchive ev = a.group("link_events");
    ev("time_s", t), ev("link", link), ev("position_m", at);
    if (a.loading()) {
      link_events_.resize(t.size());
      for (std::size_t k = 0; k < t.size(); ++k) link_events_[k] = {t[k], static_cast<std::size_t>(link[k]), at[k]};
    }
  }
  bridge::StateArchive list = a.group("neighbour_list");
  list("row_begin", list_.row_begin), list("neighbour", list_.nbr);
  list("row_partitions", part_begin_);
  // The last step's contacts of each partition, with their history.
  for (std::size_t t = 0; t < scratch_.size(); ++t) {
    ContactSet& cs = scratch_[t].sets[hcur_];
    std::vector<std::uint32_t> k(cs.k.begin(), cs.k.begin() + static_cast<std::ptrdiff_t>(cs.n));
    const auto head = [&](const std::vector<double>& v) {
      return v.size() >= cs.n ? std::vector<double>(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(cs.n))
                              : std::vector<double>();
    };
    std::vector<double> ux = head(cs.ux), uy = head(cs.uy), uz = head(cs.uz), pl = head(cs.plastic),
                        vi = head(cs.viscous);
    bridge::StateArchive ca = a.group("contacts/" + std::to_string(t));
    ca("list_entry", k), ca("ux", ux), ca("uy", uy), ca("uz", uz), ca("plastic", pl), ca("viscous", vi);
    if (!a.loading()) continue;
    const std::size_t m = k.size();
    if (ux.size() != m || uy.size() != m || uz.size() != m || (laws_.any_plastic && pl.size() != m) ||
        (laws_.any_viscous && vi.size() != m))
      throw std::invalid_argument("checkpoint: contact histories of unequal lengths");
    cs.ensure(m, laws_.any_plastic, laws_.any_viscous);
    std::copy(k.begin(), k.end(), cs.k.begin());
    std::copy(ux.begin(), ux.end(), cs.ux.begin());
    std::copy(uy.begin(), uy.end(), cs.uy.begin());
    std::copy(uz.begin(), uz.end(), cs.uz.begin());
    if (laws_.any_plastic) std::copy(pl.begin(), pl.end(), cs.plastic.begin());
    if (laws_.any_viscous) std::copy(vi.begin(), vi.end(), cs.viscous.begin());
    cs.n = m;
  }
  if (!a.loading()) return;
  // A checkpoint of another scene or thread count is refused (runScene
  // compares the digests of the engines first; this guards the rest).
  // (before the first step there is no list yet: the first step builds it)
  const bool listed = rebuilds_ > 0;
  bool sizes_ok = p_.slot.size() == n &&
                  (!listed || (part_begin_.size() == scratch_.size() + 1 && list_.row_begin.size() == n + 1));
  p_.forEachStateField([&](const char*, const auto& v) { sizes_ok = sizes_ok && v.size() == n; });
  p_.forEachScratchField([&](const char*, const auto& v) { sizes_ok = sizes_ok && v.size() == n; });
  if (!sizes_ok) throw std::invalid_argument("checkpoint: a state of another scene or number of threads");
  if (listed) {
    list_.indexOwners(), sizeTouchBuffers();
    line_partition_.resize(n / kParticlesPerLine + 1);
    for (std::size_t t = 0; t < scratch_.size(); ++t) sizeForceBuffer(t);
    findReachedFrom();
  }
  if (listed && laws_.any_viscous) wallDamping(p_, walls_, laws_);
}

// ---------------------------------------------------------------------------

StepStatus Engine::fail(StepStatus status, const std::string& what) {
  if (status_ != StepStatus::Ok) return status_;
  status_ = status;
  std::ostringstream m;
  m << "step " << step_ << ", t = " << time_ << " s: " << what;
  failure_ = m.str();
  return status_;
}

std::string Engine::bodyName(std::uint32_t id) const {
  if (id < sphere_count_) return "sphere " + std::to_string(id);
  const std::int32_t b = p_.body[p_.slot[id]];
  const auto& ids = blocks_[static_cast<std::size_t>(b)].ids;
  const auto k = std::find(ids.begin(), ids.end(), id) - ids.begin();
  return "block " + std::to_string(b) + " (member sphere " + std::to_string(k) + ")";
}

BodyState Engine::body(std::size_t b) const {
  if (b < sphere_count_) {
    const std::uint32_t i = p_.slot[b];
    return {Vec3(p_.x[i], p_.y[i], p_.z[i]), Vec3(p_.vx[i], p_.vy[i], p_.vz[i]), Vec3(p_.wx[i], p_.wy[i], p_.wz[i])};
  }
  const RigidBlock& k = blocks_[b - sphere_count_];
  return {k.x, k.v, k.omega};
}

Eigen::Quaterniond Engine::blockOrientation(std::size_t b) const {
  const RigidBlock& k = blocks_[b];
  return (k.q * k.principal_axes.conjugate()).normalized();
}

void Engine::sphereGeometry(std::vector<Vec3>& centers_m, std::vector<double>& radii_m) const {
  centers_m.resize(p_.size());
  radii_m.resize(p_.size());
  for (std::size_t i = 0; i < p_.size(); ++i)
    centers_m[p_.id[i]] = Vec3(p_.x[i], p_.y[i], p_.z[i]), radii_m[p_.id[i]] = p_.r[i];
}

Vec3 Engine::blockFrameOrigin(std::size_t b) const {
  const RigidBlock& k = blocks_[b];
  return k.x - blockOrientation(b) * k.frame_center;
}

double Engine::bodyRadius(std::size_t b) const {
  if (b < sphere_count_) return p_.r[p_.slot[b]];
  return std::cbrt(3.0 * blocks_[b - sphere_count_].volume / (4.0 * 3.14159265358979323846));
}

std::size_t Engine::bodyCount() const {
  return sphere_count_ + blocks_.size();
}
std::size_t Engine::blockCount() const {
  return blocks_.size();
}
std::size_t Engine::wallCount() const {
  return walls_.size();
}
std::size_t Engine::wallIndex(const std::string& name) const {
  for (std::size_t w = 0; w < walls_.size(); ++w)
    if (walls_[w].name == name) return w;
  return walls_.size();
}
void Engine::setWallProgram(std::size_t w, const WallProgram& program) {
  walls_[w].program = program;
}
Vec3 Engine::sphereForce(std::size_t s) const {
  if (const auto node = nodes_.force(static_cast<std::uint32_t>(s))) return *node;  // (a link node keeps its own)
  const std::uint32_t i = p_.slot[s];
  return {p_.fx[i], p_.fy[i], p_.fz[i]};
}
Vec3 Engine::wallForce(std::size_t w) const {
  return walls_[w].force_N;
}
Vec3 Engine::wallPosition(std::size_t w) const {
  return walls_[w].force_position;
}

}  // namespace gabion::micro
