#include "micro/engine.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "bridge/laws/contact_local_damping.hpp"
#include "micro/rigid_body.hpp"

#if defined(__AVX512F__) && defined(__AVX512VL__)
#include <immintrin.h>
#endif

namespace gabion::micro {

namespace {
constexpr double kPi = 3.14159265358979323846;
// Spheres larger than this many times the median radius stay out of the cell
// grid (a boulder among grains would otherwise set the cell size for all).
constexpr double kBigRadiusFactor = 2.0;
// Touching pairs evaluated together by the vectorised contact law.
constexpr std::size_t kChunk = 128;

template <class T>
void permute(std::vector<T>& v, const std::vector<std::uint32_t>& order, std::vector<T>& tmp) {
  tmp.resize(v.size());
  for (std::size_t k = 0; k < order.size(); ++k) tmp[k] = v[order[k]];
  v.swap(tmp);
}
}  // namespace

/// A rigid multi-sphere block: state of the centre of mass, orientation of
/// the principal frame, angular momentum (world), member offsets.
struct Engine::Block {
  double mass = 0.0, inv_mass = 0.0, volume = 0.0, alpha = 0.0;
  Vec3 inertia = Vec3::Ones();  // principal moments (kg m^2)
  Vec3 x = Vec3::Zero(), v = Vec3::Zero(), L = Vec3::Zero(), omega = Vec3::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();          // principal -> world
  Eigen::Quaterniond principal_axes = Eigen::Quaterniond::Identity();  // principal -> input body frame
  std::vector<Vec3> offsets;  // member centres in the principal frame (m)
  std::vector<std::uint32_t> pids;
  bool fixed = false;
};

/// A planar wall with its candidate list (particles within reach) and the
/// contact history aligned to it.
struct Engine::Wall {
  Vec3 p0 = Vec3::Zero(), n = Vec3::UnitZ(), v = Vec3::Zero();
  int mat = 0;
  Vec3 force_N = Vec3::Zero();
  Vec3 position = Vec3::Zero();  // point at the last force evaluation
  std::vector<std::uint32_t> cand;
  History hist;
  double t_ref = 0.0;  // time of the last rebuild
};

namespace {
/// A worker's sums over its free spheres in integrate().
struct SphereSums {
  double local = 0.0, ke_t = 0.0, ke_r = 0.0, pe = 0.0, finite = 0.0, max_d2 = 0.0;
};

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
}  // namespace

/// Per-worker scratch: the force buffer for partners beyond the particles of
/// its partition (none for the last partition), the contact sets of its
/// partition (the last step's and this step's), its share of the wall
/// contacts, energy sums and the first failure seen.
struct Engine::WorkerScratch {
  std::vector<double> fx, fy, fz, tx, ty, tz;
  ContactSet sets[2];
  std::vector<std::uint32_t> touch_i, touch_k;  // a chunk of touching pairs (+ one list row)
  // wall contacts of this worker's particle range
  std::vector<Vec3> wall_force;  // per wall, force exerted on it (N)
  ContactEnergy wall_energy;
  double wall_work = 0.0;
  std::size_t wall_contacts = 0;
  std::string wall_failure;
  SphereSums spheres;  // integrate(): sums over the free spheres of its partition
  std::uint32_t lo = 0, hi = 0;
  ContactEnergy energy;
  std::size_t contacts = 0;
  bool failed = false;
  std::uint32_t fail_i = 0, fail_j = 0;
  double fail_ratio = 0.0;
};

void Engine::History::resize(std::size_t m) {
  ux.assign(m, 0.0);
  uy.assign(m, 0.0);
  uz.assign(m, 0.0);
  plastic.assign(m, 0.0);
  viscous.assign(m, 0.0);
  stamp.assign(m, std::numeric_limits<std::int64_t>::min() / 2);
}

namespace {
std::vector<MassProperties> blockMassProperties(const Scene& scene) {
  std::vector<MassProperties> out;
  out.reserve(scene.blocks.size());
  for (const BlockSpec& b : scene.blocks)
    out.push_back(clusterMassProperties(b.member_centers_m, b.member_radii_m,
                                        scene.materials[static_cast<std::size_t>(b.material)].density_kg_m3));
  return out;
}

// Critical step: each free body against the stiffest contact it can meet
// (docs/micro.md): sqrt(m / k_n) and sqrt(I / (k l^2)) with l the farthest
// reach of the body from its centre (R for a sphere, I = 0.4 m R^2).
double criticalStep(const Scene& scene, const std::vector<MassProperties>& block_props) {
  const std::size_t nmat = scene.materials.size();
  std::vector<PairLaw> laws(nmat * nmat);
  for (std::size_t a = 0; a < nmat; ++a)
    for (std::size_t b = 0; b < nmat; ++b) laws[a * nmat + b] = mixMaterials(scene.materials[a], scene.materials[b]);
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
  for (const auto& sp : scene.spheres) {
    if (sp.fixed) continue;
    const auto m = static_cast<std::size_t>(sp.material);
    const double mass = scene.materials[m].density_kg_m3 * sphereVolume(sp.radius_m);
    dt = std::min({dt, std::sqrt(mass / kn_max[m]), std::sqrt(0.4 * mass / ks_max[m])});
  }
  for (std::size_t bi = 0; bi < scene.blocks.size(); ++bi) {
    const BlockSpec& spec = scene.blocks[bi];
    if (spec.fixed) continue;
    const MassProperties& props = block_props[bi];
    const std::vector<Vec3> offsets = principalFrameOffsets(props, spec.member_centers_m);
    const auto m = static_cast<std::size_t>(spec.material);
    double lever = 0.0;
    for (std::size_t k = 0; k < offsets.size(); ++k) lever = std::max(lever, offsets[k].norm() + spec.member_radii_m[k]);
    dt = std::min({dt, std::sqrt(props.mass_kg / kn_max[m]),
                   std::sqrt(props.principal_moments_kg_m2.minCoeff() / (k_max[m] * lever * lever))});
  }
  return dt;
}
}  // namespace

double criticalTimeStep(const Scene& scene) { return criticalStep(scene, blockMassProperties(scene)); }

Engine::Engine(const Scene& scene, int threads) {
  materials_ = scene.materials;
  nmat_ = materials_.size();
  laws_.resize(nmat_ * nmat_);
  for (std::size_t a = 0; a < nmat_; ++a)
    for (std::size_t b = 0; b < nmat_; ++b) laws_[a * nmat_ + b] = mixMaterials(materials_[a], materials_[b]);
  for (const PairLaw& l : laws_) {
    law_kn_.push_back(l.normal.stiffness_N_m);
    law_flim_.push_back(l.normal.force_limit_N);
    law_ks_.push_back(l.tangential.stiffness_N_m);
    law_mu_ks_.push_back(l.tangential.friction / l.tangential.stiffness_N_m);
    law_zeta_.push_back(l.damping_ratio);
    any_plastic_ = any_plastic_ || std::isfinite(l.normal.force_limit_N);
    any_viscous_ = any_viscous_ || l.damping_ratio > 0.0;
  }
  gravity_ = scene.gravity_m_s2;
  max_overlap_ratio_ = scene.run.max_overlap_ratio;
  runaway_factor_ = scene.run.energy_runaway_factor;

  sphere_count_ = scene.spheres.size();
  std::size_t members = 0;
  for (const auto& b : scene.blocks) members += b.member_radii_m.size();
  n_ = sphere_count_ + members;
  for (auto* v : {&x_, &y_, &z_, &vx_, &vy_, &vz_, &wx_, &wy_, &wz_, &fx_, &fy_, &fz_, &tx_, &ty_, &tz_, &r_,
                  &inv_body_mass_, &mass_, &inv_mass_, &inv_inertia_, &alpha_, &x0_, &y0_, &z0_})
    v->assign(n_, 0.0);
  block_.assign(n_, -1);
  mat_.assign(n_, 0);
  pid_.resize(n_);
  slot_.resize(n_);
  std::iota(pid_.begin(), pid_.end(), 0u);
  std::iota(slot_.begin(), slot_.end(), 0u);

  const auto setParticle = [&](std::size_t i, const Vec3& x, const Vec3& v, const Vec3& w) {
    x_[i] = x.x(), y_[i] = x.y(), z_[i] = x.z();
    vx_[i] = v.x(), vy_[i] = v.y(), vz_[i] = v.z();
    wx_[i] = w.x(), wy_[i] = w.y(), wz_[i] = w.z();
  };
  for (std::size_t s = 0; s < sphere_count_; ++s) {
    const SphereSpec& sp = scene.spheres[s];
    const Material& m = materials_[sp.material];
    const double mass = m.density_kg_m3 * sphereVolume(sp.radius_m);
    r_[s] = sp.radius_m;
    mat_[s] = static_cast<std::uint32_t>(sp.material);
    if (sp.fixed) {
      setParticle(s, sp.center_m, Vec3::Zero(), Vec3::Zero());
    } else {
      setParticle(s, sp.center_m, sp.velocity_m_s, sp.angular_velocity_rad_s);
      mass_[s] = mass;
      inv_mass_[s] = 1.0 / mass;
      inv_inertia_[s] = 1.0 / (0.4 * mass * sp.radius_m * sp.radius_m);
      inv_body_mass_[s] = 1.0 / mass;
      alpha_[s] = m.local_damping;
    }
  }
  std::size_t next = sphere_count_;
  const std::vector<MassProperties> block_props = blockMassProperties(scene);
  for (std::size_t bi = 0; bi < scene.blocks.size(); ++bi) {
    const BlockSpec& spec = scene.blocks[bi];
    const Material& m = materials_[spec.material];
    const MassProperties& props = block_props[bi];
    Block b;
    b.mass = props.mass_kg;
    b.volume = props.volume_m3;
    b.inertia = props.principal_moments_kg_m2;
    b.principal_axes = props.principal_axes;
    b.offsets = principalFrameOffsets(props, spec.member_centers_m);
    b.q = (spec.orientation * props.principal_axes).normalized();
    b.x = spec.position_m + spec.orientation * props.center_m;
    b.fixed = spec.fixed;
    b.alpha = m.local_damping;
    if (!b.fixed) {
      b.inv_mass = 1.0 / b.mass;
      b.v = spec.velocity_m_s;
      const Eigen::Matrix3d R = b.q.toRotationMatrix();
      b.L = R * b.inertia.asDiagonal() * R.transpose() * spec.angular_velocity_rad_s;
      b.omega = angularVelocityWorld(b.q, b.L, b.inertia);
    }
    for (std::size_t k = 0; k < b.offsets.size(); ++k, ++next) {
      const Vec3 arm = b.q * b.offsets[k];
      setParticle(next, b.x + arm, b.v + b.omega.cross(arm), b.omega);
      r_[next] = spec.member_radii_m[k];
      mat_[next] = static_cast<std::uint32_t>(spec.material);
      block_[next] = static_cast<std::int32_t>(bi);
      inv_body_mass_[next] = b.inv_mass;
      b.pids.push_back(static_cast<std::uint32_t>(next));
    }
    blocks_.push_back(std::move(b));
  }

  for (const auto& ws : scene.walls) {
    Wall w;
    w.p0 = ws.point_m;
    w.n = ws.normal;
    w.v = ws.velocity_m_s;
    w.mat = ws.material;
    w.position = ws.point_m;
    walls_.push_back(std::move(w));
  }

  uniform_material_ = n_ > 0 && std::all_of(mat_.begin(), mat_.end(), [&](std::uint32_t m) { return m == mat_[0]; });

  // Grid spheres vs oversized ones; the skin is a fraction of the mean grid radius.
  std::vector<double> sorted_r = r_;
  std::nth_element(sorted_r.begin(), sorted_r.begin() + static_cast<long>(n_ / 2), sorted_r.end());
  big_radius_m_ = kBigRadiusFactor * sorted_r[n_ / 2];
  is_big_.assign(n_, 0);
  double sum_r = 0.0;
  std::size_t small = 0;
  for (std::size_t i = 0; i < n_; ++i) {
    is_big_[i] = r_[i] > big_radius_m_ ? 1 : 0;
    if (!is_big_[i]) sum_r += r_[i], ++small;
  }
  skin_m_ = scene.run.verlet_skin_ratio * sum_r / static_cast<double>(std::max<std::size_t>(small, 1));

  dt_critical_ = criticalStep(scene, block_props);

  pool_ = std::make_unique<WorkerPool>(threads);
  scratch_.resize(static_cast<std::size_t>(pool_->size()));
  profile_.partition_busy_s.resize(scratch_.size());
  for (std::size_t t = 0; t + 1 < scratch_.size(); ++t)  // partners beyond partition t's particles
    for (auto* v : {&scratch_[t].fx, &scratch_[t].fy, &scratch_[t].fz, &scratch_[t].tx, &scratch_[t].ty,
                    &scratch_[t].tz})
      v->assign(n_, 0.0);
}

Engine::~Engine() = default;

// ---------------------------------------------------------------------------
// The step.

bool Engine::step(bool measure) {
  using S = StageProfile;
  failure_.clear();
  lap_ = std::chrono::steady_clock::now();
  updateNeighbours();
  lap(S::kNeighbours);
  computeContactForces(measure);
  lap(S::kContacts);
  // (The netting stage, wire links between node particles, goes here.)
  applyWallsAndLoads(measure);
  lap(S::kWalls);
  if (!failure_.empty()) return false;
  integrate(measure);
  lap(S::kIntegrate);
  if (!failure_.empty()) return false;
  if (measure) measureEnergy();
  lap(S::kEnergy);
  ++step_;
  return failure_.empty();
}

const char* StageProfile::name(int stage) {
  static const char* const names[kStageCount] = {"neighbours", "contacts", "walls", "integrate", "energy"};
  return names[stage];
}

void Engine::lap(StageProfile::Stage stage) {
  const auto now = std::chrono::steady_clock::now();
  profile_.wall_s[stage] += std::chrono::duration<double>(now - lap_).count();
  lap_ = now;
}

template <class Job>
void Engine::parallel(StageProfile::Stage stage, const Job& job) {
  pool_->run([&](int t) {
    const auto start = std::chrono::steady_clock::now();
    job(t);
    profile_.partition_busy_s[static_cast<std::size_t>(t)][stage] +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  });
}

template <class Fn>
void Engine::forBlocks(StageProfile::Stage stage, std::size_t blocks, const Fn& fn) {
  std::atomic<std::size_t> next{0};
  parallel(stage, [&](int) {
    for (std::size_t b = next.fetch_add(1, std::memory_order_relaxed); b < blocks;
         b = next.fetch_add(1, std::memory_order_relaxed))
      fn(b);
  });
}

// ---------------------------------------------------------------------------
// updateNeighbours: rebuilds the Verlet list when a particle (or wall) has
// moved more than half the skin since the last build.

void Engine::updateNeighbours() {
  if (!need_rebuild_) return;
  rebuildNeighbourList();
  need_rebuild_ = false;
  ++rebuilds_;
}

void Engine::rebuildNeighbourList() {
  const double t_now = time();
  // 1. Note the contacts that touched at the last step by stable ids: list
  // pairs by where their history is (partition, index in its contact set),
  // which stays untouched until step 4 copies it; oversized-sphere and wall
  // pairs with their history.
  struct SavedContact {
    std::uint32_t a, b, t, c;
  };
  const std::size_t workers = scratch_.size();
  std::vector<std::size_t> saved_base(workers + 1, 0);
  for (std::size_t t = 0; t < workers; ++t) saved_base[t + 1] = saved_base[t] + scratch_[t].sets[hcur_].n;
  std::vector<SavedContact> saved(saved_base[workers]);
  parallel(StageProfile::kNeighbours, [&](int task) {
    const auto t = static_cast<std::size_t>(task);
    const ContactSet& cs = scratch_[t].sets[hcur_];
    SavedContact* const out = saved.data() + saved_base[t];
    std::size_t i = cs.n > 0 ? part_begin_[t] : 0;
    for (std::size_t c = 0; c < cs.n; ++c) {
      const std::uint32_t k = cs.k[c];
      while (row_begin_[i + 1] <= k) ++i;
      out[c] = {pid_[i], pid_[nbr_[k]], static_cast<std::uint32_t>(t), static_cast<std::uint32_t>(c)};
    }
  });
  struct Saved {
    std::uint32_t a, b;
    History::Entry h;
  };
  std::vector<Saved> saved_big;
  const std::int64_t last = step_ - 1;
  for (std::size_t q = 0; q < big_i_.size(); ++q)
    if (big_hist_.touched(q, last)) saved_big.push_back({pid_[big_i_[q]], pid_[big_j_[q]], big_hist_.get(q, last)});
  std::vector<std::vector<Saved>> saved_wall(walls_.size());
  for (std::size_t w = 0; w < walls_.size(); ++w) {
    const Wall& wall = walls_[w];
    for (std::size_t k = 0; k < wall.cand.size(); ++k)
      if (wall.hist.touched(k, last)) saved_wall[w].push_back({pid_[wall.cand[k]], 0, wall.hist.get(k, last)});
  }

  // 2. Cell grid over the grid spheres; sort particles into cell order
  // (oversized spheres last) so that neighbours are close in memory. The
  // per-particle passes of the rebuild go in blocks of particles that the
  // workers claim as they come free; a block writes only its own output, so
  // the result does not depend on who ran it.
  const std::size_t nblocks = workers == 1 ? 1 : std::min<std::size_t>(16 * workers, n_ / 256 + 1);
  const auto blockBegin = [&](std::size_t b) { return n_ * b / nblocks; };
  struct Box {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    double rmax = 0.0;
  };
  std::vector<Box> boxes(nblocks);
  forBlocks(StageProfile::kNeighbours, nblocks, [&](std::size_t b) {
    Box& box = boxes[b];
    for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i) {
      if (is_big_[i]) continue;
      box.lo = box.lo.cwiseMin(Vec3(x_[i], y_[i], z_[i]));
      box.hi = box.hi.cwiseMax(Vec3(x_[i], y_[i], z_[i]));
      box.rmax = std::max(box.rmax, r_[i]);
    }
  });
  Vec3 lo = boxes[0].lo, hi = boxes[0].hi;
  double rmax = 0.0;
  for (const Box& box : boxes) lo = lo.cwiseMin(box.lo), hi = hi.cwiseMax(box.hi), rmax = std::max(rmax, box.rmax);
  double h = 2.0 * rmax + skin_m_;
  std::size_t ncells[3] = {1, 1, 1}, ncell = 1;  // per axis x, y, z
  if (rmax > 0.0) {
    const Vec3 ext = hi - lo;
    for (;;) {  // keep the grid at most a few cells per particle (scattered clouds)
      for (int a = 0; a < 3; ++a) ncells[a] = static_cast<std::size_t>(ext[a] / h) + 1;
      ncell = ncells[0] * ncells[1] * ncells[2];
      if (ncell <= 4 * n_ + 64) break;
      h *= 1.26;
    }
  }
  // Cell order: the axis with the most cells varies slowest, so the row
  // partitions (contiguous runs of cells) cut the grid across its smallest
  // cross-section, and the band of partners beyond a partition's rows (they
  // go through its buffer and are shared by two cores) is smallest: for a
  // bed 0.1 m deep on a 0.6 m floor, a slab across x instead of a layer.
  const int slow_axis = static_cast<int>(std::max_element(ncells, ncells + 3) - ncells);
  const int fast_axis = slow_axis == 0 ? 1 : 0, mid_axis = 3 - slow_axis - fast_axis;
  // The grid has a layer of empty cells all round, so that the neighbour
  // cells of any occupied cell exist (no bounds tests in the search).
  const std::size_t pf = ncells[fast_axis] + 2, pm = ncells[mid_axis] + 2;
  ncell = pf * pm * (ncells[slow_axis] + 2);
  const double inv_h = 1.0 / h;
  std::vector<std::uint32_t> cell(n_);
  const double* const pos[3] = {x_.data(), y_.data(), z_.data()};
  const auto cellOf = [&](std::size_t i) {
    std::size_t c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(ncells[a] - 1, static_cast<std::size_t>((pos[a][i] - lo[a]) * inv_h));
    return static_cast<std::uint32_t>(((c[slow_axis] + 1) * pm + (c[mid_axis] + 1)) * pf + (c[fast_axis] + 1));
  };
  forBlocks(StageProfile::kNeighbours, nblocks, [&](std::size_t b) {
    for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i)
      cell[i] = is_big_[i] ? static_cast<std::uint32_t>(ncell) : cellOf(i);
  });
  std::vector<std::uint32_t> cell_start(ncell + 2, 0);
  for (std::size_t i = 0; i < n_; ++i) ++cell_start[cell[i] + 1];
  for (std::size_t c = 0; c + 1 < cell_start.size(); ++c) cell_start[c + 1] += cell_start[c];
  std::vector<std::uint32_t> order(n_);
  {
    std::vector<std::uint32_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (std::size_t i = 0; i < n_; ++i) order[fill[cell[i]]++] = static_cast<std::uint32_t>(i);
  }
  reorderParticles(order);
  std::vector<std::uint32_t> new_cell(n_);
  for (std::size_t k = 0; k < n_; ++k) new_cell[k] = cell[order[k]];

  const auto pairAllowed = [&](std::size_t i, std::size_t j) {
    if (block_[i] >= 0 && block_[i] == block_[j]) return false;
    return inv_body_mass_[i] > 0.0 || inv_body_mass_[j] > 0.0;
  };

  // 3. Half neighbour list, CSR by row; rows come out sorted by j because
  // cells are visited in increasing index order. A partner j > i lies in a
  // cell at or after i's: of the 27 cells around i's, only the rest of its
  // own row along the fast axis and the four rows (mid+1), (slow+1,
  // mid-1..mid+1) can hold one. Each
  // block of rows goes into its own buffer; the buffers are joined in block
  // order, so the list is the same for any thread count.
  row_begin_.assign(n_ + 1, 0);
  list_blocks_.resize(nblocks);
  forBlocks(StageProfile::kNeighbours, nblocks, [&](std::size_t blk) {
    // One worker writes the list itself (no second copy in memory). The
    // three cells along the fast axis of one row of the stencil hold one
    // contiguous range of particles (cell order), so each particle scans 5
    // ranges, branch-free, appending in place.
    std::vector<std::uint32_t>& out = nblocks == 1 ? nbr_ : list_blocks_[blk];
    std::size_t len = 0;
    const std::size_t i0 = blockBegin(blk), i1 = blockBegin(blk + 1);
    const double *__restrict X = x_.data(), *__restrict Y = y_.data(), *__restrict Z = z_.data(),
                 *__restrict R = r_.data(), *__restrict IMB = inv_body_mass_.data();
    const std::int32_t* __restrict BLK = block_.data();
    const double skin = skin_m_;
    const std::size_t row_offset[5] = {0, pf, pf * pm - pf, pf * pm, pf * pm + pf};
    for (std::size_t i = i0; i < i1; ++i) {
      row_begin_[i] = static_cast<std::uint32_t>(len);  // local offset, made global below
      if (is_big_[i]) continue;
      const std::size_t c = new_cell[i];
      const double xi = X[i], yi = Y[i], zi = Z[i], ri = R[i] + skin;
      const std::int32_t bi = BLK[i];
      const bool free_i = IMB[i] > 0.0;
      for (std::size_t r = 0; r < 5; ++r) {
        const std::size_t centre = c + row_offset[r];  // middle cell of the row
        const std::uint32_t jb = r == 0 ? static_cast<std::uint32_t>(i + 1) : cell_start[centre - 1];
        const std::uint32_t je = cell_start[centre + 2];
        if (jb >= je) continue;
        if (out.size() < len + (je - jb))  // grows by a quarter (the list is the largest array)
          out.resize(std::max<std::size_t>(len + (je - jb), out.size() + out.size() / 4 + 1024));
        std::uint32_t* __restrict o = out.data() + len;
        std::size_t cnt = 0;
        for (std::uint32_t j = jb; j < je; ++j) {
          const double ex = X[j] - xi, ey = Y[j] - yi, ez = Z[j] - zi, reach = ri + R[j];
          // pairAllowed, branch-free
          const bool near = ex * ex + ey * ey + ez * ez < reach * reach;
          const bool allowed = (bi < 0 || BLK[j] != bi) && (free_i || IMB[j] > 0.0);
          o[cnt] = j;
          cnt += static_cast<std::size_t>(near & allowed);
        }
        len += cnt;
      }
    }
    out.resize(len);
  });
  if (nblocks > 1) {
    std::vector<std::size_t> base(nblocks + 1, 0);
    for (std::size_t b = 0; b < nblocks; ++b) base[b + 1] = base[b] + list_blocks_[b].size();
    nbr_.resize(base[nblocks]);
    forBlocks(StageProfile::kNeighbours, nblocks, [&](std::size_t b) {
      const auto shift = static_cast<std::uint32_t>(base[b]);
      for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i) row_begin_[i] += shift;
      std::copy(list_blocks_[b].begin(), list_blocks_[b].end(), nbr_.begin() + static_cast<long>(base[b]));
    });
  }
  row_begin_[n_] = static_cast<std::uint32_t>(nbr_.size());
  std::uint32_t longest_row = 0;
  for (std::size_t i = 0; i < n_; ++i) longest_row = std::max(longest_row, row_begin_[i + 1] - row_begin_[i]);
  for (auto& sc : scratch_) {
    sc.touch_i.resize(kChunk + longest_row);
    sc.touch_k.resize(kChunk + longest_row);
  }

  // Oversized spheres: tested against every particle by bounding box.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> big;
  for (std::size_t b = 0; b < n_; ++b) {
    if (!is_big_[b]) continue;
    for (std::size_t j = 0; j < n_; ++j) {
      if (j == b || (is_big_[j] && j < b)) continue;
      const double reach = r_[b] + r_[j] + skin_m_;
      const double ex = x_[j] - x_[b], ey = y_[j] - y_[b], ez = z_[j] - z_[b];
      if (std::fabs(ex) >= reach || std::fabs(ey) >= reach || std::fabs(ez) >= reach) continue;
      if (ex * ex + ey * ey + ez * ez < reach * reach && pairAllowed(b, j))
        big.emplace_back(static_cast<std::uint32_t>(std::min(b, j)), static_cast<std::uint32_t>(std::max(b, j)));
    }
  }
  std::sort(big.begin(), big.end());
  big_i_.resize(big.size());
  big_j_.resize(big.size());
  for (std::size_t q = 0; q < big.size(); ++q) big_i_[q] = big[q].first, big_j_[q] = big[q].second;
  big_hist_.resize(big.size());

  // Walls: candidates within reach of the plane (the wall may move half a
  // skin), in particle order: each block of particles lists its own, then
  // the blocks are joined in order.
  const std::size_t nwalls = walls_.size();
  std::vector<std::vector<std::uint32_t>> wall_blocks(nblocks * nwalls);
  forBlocks(StageProfile::kNeighbours, nblocks, [&](std::size_t b) {
    for (std::size_t wi = 0; wi < nwalls; ++wi) {
      const Wall& w = walls_[wi];
      const Vec3 p = w.p0 + w.v * t_now;
      std::vector<std::uint32_t>& out = wall_blocks[b * nwalls + wi];
      for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i) {
        if (inv_body_mass_[i] == 0.0) continue;
        const double d = (x_[i] - p.x()) * w.n.x() + (y_[i] - p.y()) * w.n.y() + (z_[i] - p.z()) * w.n.z();
        if (d < r_[i] + skin_m_) out.push_back(static_cast<std::uint32_t>(i));
      }
    }
  });
  for (std::size_t wi = 0; wi < nwalls; ++wi) {
    Wall& w = walls_[wi];
    w.cand.clear();
    for (std::size_t b = 0; b < nblocks; ++b)
      w.cand.insert(w.cand.end(), wall_blocks[b * nwalls + wi].begin(), wall_blocks[b * nwalls + wi].end());
    w.hist.resize(w.cand.size());
    w.t_ref = t_now;
  }
  // Particle ranges with about equal numbers of wall candidates (the
  // candidates crowd into the index ranges of the cells next to the walls; a
  // wall across the slowest axis has all of its own at one end): boundary t
  // is the smallest index with at least total t / T candidates below it.
  {
    const auto below = [&](std::uint32_t b) {
      std::size_t c = 0;
      for (const auto& w : walls_)
        c += static_cast<std::size_t>(std::lower_bound(w.cand.begin(), w.cand.end(), b) - w.cand.begin());
      return c;
    };
    const std::size_t total = below(static_cast<std::uint32_t>(n_));
    wall_part_.assign(workers + 1, static_cast<std::uint32_t>(n_));
    wall_part_[0] = 0;
    for (std::size_t t = 1; t < workers; ++t) {
      std::uint32_t first = wall_part_[t - 1], past = static_cast<std::uint32_t>(n_);
      while (first < past) {
        const std::uint32_t mid = first + (past - first) / 2;
        if (below(mid) * workers >= total * t) past = mid; else first = mid + 1;
      }
      wall_part_[t] = first;
    }
  }

  // 4. Carry the history of touching contacts over to the new lists. A pair
  // that touched is within reach, so it is in the new list (both grid
  // spheres) or in the oversized-pair list (one oversized): is_big_ does not
  // change during a run.
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> from(nbr_.size(), kNone);  // list entry -> index in saved
  // each pair has its own list entry: no two blocks write the same
  forBlocks(StageProfile::kNeighbours, nblocks, [&](std::size_t blk) {
    for (std::size_t q = saved.size() * blk / nblocks; q < saved.size() * (blk + 1) / nblocks; ++q) {
      const std::uint32_t a = slot_[saved[q].a], b = slot_[saved[q].b];
      const std::uint32_t i = std::min(a, b), j = std::max(a, b);
      const auto first = nbr_.begin() + row_begin_[i], end = nbr_.begin() + row_begin_[i + 1];
      const auto it = std::lower_bound(first, end, j);
      if (it != end && *it == j) from[static_cast<std::size_t>(it - nbr_.begin())] = static_cast<std::uint32_t>(q);
    }
  });
  for (const Saved& s : saved_big) {
    const std::uint32_t a = slot_[s.a], b = slot_[s.b];
    const auto pair = std::make_pair(std::min(a, b), std::max(a, b));
    const auto bt = std::lower_bound(big.begin(), big.end(), pair);
    if (bt == big.end() || *bt != pair) continue;
    big_hist_.set(static_cast<std::size_t>(bt - big.begin()), s.h, last);
  }
  for (std::size_t w = 0; w < walls_.size(); ++w) {
    Wall& wall = walls_[w];
    for (const Saved& s : saved_wall[w]) {
      const std::uint32_t i = slot_[s.a];
      const auto it = std::lower_bound(wall.cand.begin(), wall.cand.end(), i);
      if (it == wall.cand.end() || *it != i) continue;
      wall.hist.set(static_cast<std::size_t>(it - wall.cand.begin()), s.h, last);
    }
  }

  // 5. Reference positions for the displacement test; row partitions with
  // equal estimated work for the workers: per row, per list entry (touch
  // scan) and per pair that touched at the last step (contact law), in the
  // ratio 1 : 2 : 13 of their costs (per-step partition times of the
  // settling benchmark on two threads, fitted: 1.4, 2.6-2.9 and 17-18 ns).
  // They depend only on the state, so runs stay deterministic for a given
  // thread count.
  x0_ = x_, y0_ = y_, z0_ = z_;
  const std::size_t T = scratch_.size();
  part_begin_.assign(T + 1, static_cast<std::uint32_t>(n_));
  part_begin_[0] = 0;
  if (T > 1) {
    constexpr std::size_t kRowWeight = 1, kEntryWeight = 2, kTouchWeight = 13;
    const auto rowWeight = [&](std::size_t i) {
      std::size_t w = kRowWeight;
      for (std::uint32_t k = row_begin_[i]; k < row_begin_[i + 1]; ++k)
        w += kEntryWeight + (from[k] != kNone ? kTouchWeight : 0);
      return w;
    };
    // Block sums in parallel; the boundaries are then found row by row only
    // inside the blocks that hold them (the same boundaries as a serial scan).
    std::vector<std::size_t> block_weight(nblocks, 0);
    forBlocks(StageProfile::kNeighbours, nblocks, [&](std::size_t b) {
      for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i) block_weight[b] += rowWeight(i);
    });
    const std::size_t total = std::accumulate(block_weight.begin(), block_weight.end(), std::size_t{0});
    std::size_t t = 1, acc = 0;
    for (std::size_t b = 0; b < nblocks && t < T; ++b) {
      if (acc + block_weight[b] < total * t / T) {
        acc += block_weight[b];
        continue;
      }
      for (std::size_t i = blockBegin(b); i < blockBegin(b + 1) && t < T; ++i) {
        while (t < T && acc >= total * t / T) part_begin_[t++] = static_cast<std::uint32_t>(i);
        acc += rowWeight(i);
      }
    }
  }
  // Each partition's carried contacts, in list order, become its "last step"
  // contact set; the history is copied from where step 1 noted it.
  const int next = hcur_ ^ 1;
  parallel(StageProfile::kNeighbours, [&](int task) {
    const auto t = static_cast<std::size_t>(task);
    ContactSet& out = scratch_[t].sets[next];
    const std::uint32_t k0 = row_begin_[part_begin_[t]], k1 = row_begin_[part_begin_[t + 1]];
    std::size_t count = 0;
    for (std::uint32_t k = k0; k < k1; ++k) count += from[k] != kNone ? 1 : 0;
    out.ensure(count, any_plastic_, any_viscous_);
    out.n = 0;
    for (std::uint32_t k = k0; k < k1; ++k) {
      if (from[k] == kNone) continue;
      const SavedContact& sc = saved[from[k]];
      const ContactSet& in = scratch_[sc.t].sets[hcur_];
      out.k[out.n] = k;
      out.ux[out.n] = in.ux[sc.c], out.uy[out.n] = in.uy[sc.c], out.uz[out.n] = in.uz[sc.c];
      if (any_plastic_) out.plastic[out.n] = in.plastic[sc.c];
      if (any_viscous_) out.viscous[out.n] = in.viscous[sc.c];
      ++out.n;
    }
  });
  hcur_ = next;
}

void Engine::reorderParticles(const std::vector<std::uint32_t>& order) {
  // One array per task, tasks dealt to the workers in turn.
  std::vector<std::vector<double>*> arrays = {&x_,  &y_,  &z_,  &vx_, &vy_,           &vz_,  &wx_,      &wy_,
                                              &wz_, &r_,  &inv_body_mass_, &mass_, &inv_mass_, &inv_inertia_, &alpha_};
  const std::size_t workers = scratch_.size(), tasks = arrays.size() + 4;
  parallel(StageProfile::kNeighbours, [&](int t) {
    std::vector<double> tmp;
    for (std::size_t a = static_cast<std::size_t>(t); a < tasks; a += workers) {
      if (a < arrays.size()) {
        permute(*arrays[a], order, tmp);
      } else if (a == arrays.size()) {
        std::vector<std::int32_t> ti;
        permute(block_, order, ti);
      } else if (a == arrays.size() + 1) {
        std::vector<std::uint32_t> tm;
        permute(mat_, order, tm);
      } else if (a == arrays.size() + 2) {
        std::vector<std::uint8_t> tb;
        permute(is_big_, order, tb);
      } else {
        std::vector<std::uint32_t> tp;
        permute(pid_, order, tp);
        for (std::size_t k = 0; k < n_; ++k) slot_[pid_[k]] = static_cast<std::uint32_t>(k);
      }
    }
  });
}

// ---------------------------------------------------------------------------
// The contact law on the touching pairs of the Verlet list, vectorised, one
// chunk of at most kChunk touching pairs at a time (the scan of the list
// fills the chunk): a scalar merge takes each pair's history from the last
// step's contact set (both in list order, so this is one forward walk); a
// branch-free SIMD pass evaluates the laws of micro/contact.hpp and
// bridge/laws/contact_*.hpp, written out with selects instead of branches,
// into small per-pair buffers; a scalar pass adds the forces to the bodies in
// pair order (a body can appear twice in a SIMD chunk, so this part cannot be
// vectorised; its order keeps the sums deterministic) and appends the
// touching pairs to this step's contact set. History is read and written
// sequentially: no gathers or scatters on arrays as long as the list. The
// rare features (F_lim, viscous damping), the stored energy and a single
// material are compile-time switches, so a case pays only for what it uses.

namespace {
struct KernelIn {
  const double *X, *Y, *Z, *R, *VX, *VY, *VZ, *WX, *WY, *WZ, *IM;
  const std::uint32_t* MAT;
  const std::uint32_t* NBR;
  const double *KN, *FLIM, *KS, *MU_KS, *ZETA;  // MU_KS: friction / k_s (m/N)
  std::size_t nmat;
  std::size_t law0;  // the law of a single-material scene
  double dt, ratio;
};
/// The last step's contact set of a partition (read, with the merge cursor)
/// and this step's (appended to; room for the chunk is made by the caller).
struct KernelHistory {
  const ContactSet* last;
  std::size_t cursor = 0;
  ContactSet* next;
};
/// Where forces go: the global arrays for particles of the partition's own
/// range (below own_end), the partition's buffer for partners beyond it.
struct KernelOut {
  double *FX, *FY, *FZ, *TX, *TY, *TZ;
  double *BFX, *BFY, *BFZ, *BTX, *BTY, *BTZ;
  std::uint32_t own_end;
  ContactEnergy* energy;
  std::size_t contacts = 0;
  std::uint32_t hi = 0;  // largest particle index written to the buffer
  bool failed = false;
  std::uint32_t fail_i = 0, fail_j = 0;
  double fail_ratio = 0.0;
};

template <bool kMeasure, bool kViscous, bool kPlastic, bool kUniform>
void touchingPairs(const KernelIn& in, const std::uint32_t* ci, const std::uint32_t* ck, std::size_t nq,
                   KernelHistory& h, KernelOut& out) {
  const double *__restrict X = in.X, *__restrict Y = in.Y, *__restrict Z = in.Z, *__restrict R = in.R;
  const double *__restrict VX = in.VX, *__restrict VY = in.VY, *__restrict VZ = in.VZ;
  const double *__restrict WX = in.WX, *__restrict WY = in.WY, *__restrict WZ = in.WZ, *__restrict IM = in.IM;
  const std::uint32_t* __restrict MAT = in.MAT;
  const std::uint32_t* __restrict NBR = in.NBR;
  const double *__restrict KN = in.KN, *__restrict FLIM = in.FLIM, *__restrict KS = in.KS, *__restrict MU_KS = in.MU_KS,
               *__restrict ZETA = in.ZETA;
  const std::size_t nmat = in.nmat, law0 = in.law0;
  const double dt = in.dt, ratio = in.ratio;
  alignas(64) double bfx[kChunk], bfy[kChunk], bfz[kChunk];
  alignas(64) double bix[kChunk], biy[kChunk], biz[kChunk];
  alignas(64) double bjx[kChunk], bjy[kChunk], bjz[kChunk];
  alignas(64) double bon[kChunk];  // 1 for a pair that touches
  // per-pair history: the last step's on entry (zero for a new contact), this step's on exit
  alignas(64) double hux[kChunk], huy[kChunk], huz[kChunk], hpl[kChunk], hvi[kChunk];
  double friction = 0.0, plastic_w = 0.0, viscous_w = 0.0, elastic = 0.0;
  {
    const ContactSet& last = *h.last;
    std::size_t p = h.cursor;
    for (std::size_t q = 0; q < nq; ++q) {
      const std::uint32_t k = ck[q];
      while (p < last.n && last.k[p] < k) ++p;
      if (p < last.n && last.k[p] == k) {
        hux[q] = last.ux[p], huy[q] = last.uy[p], huz[q] = last.uz[p];
        if constexpr (kPlastic) hpl[q] = last.plastic[p];
        if constexpr (kViscous) hvi[q] = last.viscous[p];
      } else {
        hux[q] = huy[q] = huz[q] = 0.0;
        if constexpr (kPlastic) hpl[q] = 0.0;
        if constexpr (kViscous) hvi[q] = 0.0;
      }
    }
    h.cursor = p;
  }
  {
    // energies and counts: vector sums (their order is fixed by the chunk, so
    // runs repeat bit for bit)
    double active_n = 0.0, bad = 0.0;
#pragma omp simd reduction(+ : friction, plastic_w, viscous_w, elastic, active_n, bad)
    for (std::size_t q = 0; q < nq; ++q) {
      const std::uint32_t i = ci[q], j = NBR[ck[q]];
      const double ex = X[j] - X[i], ey = Y[j] - Y[i], ez = Z[j] - Z[i];
      const double d = std::sqrt(ex * ex + ey * ey + ez * ez);
      const double ri = R[i], rj = R[j];
      const double overlap = ri + rj - d;
      // Pass 1 found d < ri + rj; rounding may still give overlap <= 0: such a
      // pair does nothing (no force, history stamp unchanged).
      const bool act = overlap > 0.0;
      const double on = act ? 1.0 : 0.0;
      const double inv = d > 0.0 ? 1.0 / d : 0.0;
      const double nx = d > 0.0 ? ex * inv : 0.0, ny = d > 0.0 ? ey * inv : 0.0, nz = d > 0.0 ? ez * inv : 1.0;
      bad += act && overlap > ratio * std::min(ri, rj) ? 1.0 : 0.0;
      const double li = ri - 0.5 * overlap, lj = rj - 0.5 * overlap;
      // velocity of the contact point on j relative to the one on i
      const double ax = lj * WX[j] + li * WX[i], ay = lj * WY[j] + li * WY[i], az = lj * WZ[j] + li * WZ[i];
      const double vx = VX[j] - VX[i] - (ay * nz - az * ny), vy = VY[j] - VY[i] - (az * nx - ax * nz),
                   vz = VZ[j] - VZ[i] - (ax * ny - ay * nx);
      const std::size_t L = kUniform ? law0 : MAT[i] * nmat + MAT[j];
      const double ks = KS[L];
      double ux = hux[q], uy = huy[q], uz = huz[q], pl = 0.0, vi = 0.0;
      if constexpr (kPlastic) pl = hpl[q];
      if constexpr (kViscous) vi = hvi[q];
      const LaneContact c = laneContact<kMeasure, kViscous, kPlastic>(
          nx, ny, nz, overlap, vx, vy, vz, KN[L], ks, MU_KS[L], kPlastic ? FLIM[L] : 0.0, kViscous ? ZETA[L] : 0.0,
          IM[i] + IM[j], dt, ux, uy, uz, pl, vi);
      if constexpr (kPlastic) plastic_w += act ? c.plastic_J : 0.0;
      if constexpr (kViscous) viscous_w += act ? c.viscous_J : 0.0;
      friction += act ? c.friction_J : 0.0;
      if constexpr (kMeasure) elastic += act ? c.elastic_J : 0.0;
      // (a pair that does not touch is not appended to the contact set below)
      hux[q] = ux, huy[q] = uy, huz[q] = uz;
      if constexpr (kPlastic) hpl[q] = pl;
      if constexpr (kViscous) hvi[q] = vi;
      const double fx = on * c.fx, fy = on * c.fy, fz = on * c.fz;
      const double cx = ny * fz - nz * fy, cy = nz * fx - nx * fz, cz = nx * fy - ny * fx;
      bfx[q] = fx, bfy[q] = fy, bfz[q] = fz;
      bix[q] = li * cx, biy[q] = li * cy, biz[q] = li * cz;
      bjx[q] = lj * cx, bjy[q] = lj * cy, bjz[q] = lj * cz;
      bon[q] = on;
      active_n += on;
    }
    double *__restrict FX = out.FX, *__restrict FY = out.FY, *__restrict FZ = out.FZ;
    double *__restrict TX = out.TX, *__restrict TY = out.TY, *__restrict TZ = out.TZ;
    std::uint32_t hi = out.hi;
    ContactSet& next = *h.next;
    std::size_t nn = next.n;
    std::uint32_t* __restrict NK = next.k.data();
    double *__restrict NUX = next.ux.data(), *__restrict NUY = next.uy.data(), *__restrict NUZ = next.uz.data();
    double *__restrict NPL = next.plastic.data(), *__restrict NVI = next.viscous.data();
    const std::uint32_t own_end = out.own_end;
    // This step's contact set: the touching pairs' history, in list order
    // (with AVX-512, eight pairs at a time by compress-stores: the scalar
    // appends were a third of the stores of the force loop below).
#if defined(__AVX512F__) && defined(__AVX512VL__)
    for (std::size_t q = 0; q < nq; q += 8) {
      const std::size_t n = std::min<std::size_t>(8, nq - q);
      const auto valid = static_cast<__mmask8>((1u << n) - 1u);
      const __mmask8 on =
          _mm512_mask_cmp_pd_mask(valid, _mm512_maskz_load_pd(valid, bon + q), _mm512_setzero_pd(), _CMP_GT_OQ);
      _mm256_mask_compressstoreu_epi32(NK + nn, on, _mm256_maskz_loadu_epi32(valid, ck + q));
      _mm512_mask_compressstoreu_pd(NUX + nn, on, _mm512_maskz_load_pd(valid, hux + q));
      _mm512_mask_compressstoreu_pd(NUY + nn, on, _mm512_maskz_load_pd(valid, huy + q));
      _mm512_mask_compressstoreu_pd(NUZ + nn, on, _mm512_maskz_load_pd(valid, huz + q));
      if constexpr (kPlastic) _mm512_mask_compressstoreu_pd(NPL + nn, on, _mm512_maskz_load_pd(valid, hpl + q));
      if constexpr (kViscous) _mm512_mask_compressstoreu_pd(NVI + nn, on, _mm512_maskz_load_pd(valid, hvi + q));
      nn += static_cast<std::size_t>(__builtin_popcount(on));
    }
#else
    for (std::size_t q = 0; q < nq; ++q) {
      // (overwritten by the next pair if this one does not touch)
      NK[nn] = ck[q], NUX[nn] = hux[q], NUY[nn] = huy[q], NUZ[nn] = huz[q];
      if constexpr (kPlastic) NPL[nn] = hpl[q];
      if constexpr (kViscous) NVI[nn] = hvi[q];
      nn += bon[q] > 0.0 ? 1 : 0;
    }
#endif
    for (std::size_t q = 0; q < nq; ++q) {
      const std::uint32_t i = ci[q], j = NBR[ck[q]];
      const bool mine = j < own_end;
      hi = mine ? hi : std::max(hi, j);
      double *fjx = mine ? FX : out.BFX, *fjy = mine ? FY : out.BFY, *fjz = mine ? FZ : out.BFZ;
      double *tjx = mine ? TX : out.BTX, *tjy = mine ? TY : out.BTY, *tjz = mine ? TZ : out.BTZ;
      FX[i] += bfx[q], FY[i] += bfy[q], FZ[i] += bfz[q];
      fjx[j] -= bfx[q], fjy[j] -= bfy[q], fjz[j] -= bfz[q];
      TX[i] += bix[q], TY[i] += biy[q], TZ[i] += biz[q];
      tjx[j] += bjx[q], tjy[j] += bjy[q], tjz[j] += bjz[q];
    }
    next.n = nn;
    out.hi = hi;
    out.contacts += static_cast<std::size_t>(active_n);
    if (bad > 0.0 && !out.failed) {  // rare: name the pair of the chunk that overlaps most
      // (the largest ratio, not a re-test of the limit: a scalar re-evaluation
      // may round differently from the vector loop, and the failure must not
      // get lost)
      out.failed = true, out.fail_ratio = -1.0;
      for (std::size_t q = 0; q < nq; ++q) {
        const std::uint32_t i = ci[q], j = NBR[ck[q]];
        const double ex = X[j] - X[i], ey = Y[j] - Y[i], ez = Z[j] - Z[i];
        const double overlap = R[i] + R[j] - std::sqrt(ex * ex + ey * ey + ez * ez);
        const double r = overlap / std::min(R[i], R[j]);
        if (r > out.fail_ratio) out.fail_i = i, out.fail_j = j, out.fail_ratio = r;
      }
    }
  }
  out.energy->friction_J += friction;
  out.energy->plastic_J += plastic_w;
  out.energy->viscous_J += viscous_w;
  out.energy->elastic_J += elastic;
}

using TouchingPairsFn = void (*)(const KernelIn&, const std::uint32_t*, const std::uint32_t*, std::size_t,
                                 KernelHistory&, KernelOut&);
template <bool kMeasure, bool kViscous>
constexpr TouchingPairsFn kPlasticUniform[4] = {
    touchingPairs<kMeasure, kViscous, false, false>, touchingPairs<kMeasure, kViscous, false, true>,
    touchingPairs<kMeasure, kViscous, true, false>, touchingPairs<kMeasure, kViscous, true, true>};
TouchingPairsFn touchingPairsFor(bool measure, bool viscous, bool plastic, bool uniform) {
  const int v = (plastic ? 2 : 0) + (uniform ? 1 : 0);
  if (measure) return viscous ? kPlasticUniform<true, true>[v] : kPlasticUniform<true, false>[v];
  return viscous ? kPlasticUniform<false, true>[v] : kPlasticUniform<false, false>[v];
}
}  // namespace

// ---------------------------------------------------------------------------
// computeContactForces: particle-particle contacts. Each worker takes a fixed
// range of rows (and of the oversized-sphere pairs), writes into its own
// force buffer, and the buffers are added in worker order: the result does
// not depend on timing.

void Engine::computeContactForces(bool measure) {
  // Partition t owns the particles of its rows [p_t, p_t+1): it clears and
  // writes their global force arrays; a partner j beyond them (j > i always)
  // goes to its buffer, added below in partition order.
  parallel(StageProfile::kContacts, [this, measure](int t) { contactKernel(t, measure); });
  hcur_ ^= 1;  // this step's contact sets become the last step's
  contacts_ = 0;
  const std::size_t workers = scratch_.size();
  for (std::size_t t = 0; t < workers; ++t) {
    const WorkerScratch& s = scratch_[t];
    friction_ += s.energy.friction_J;
    plastic_ += s.energy.plastic_J;
    viscous_ += s.energy.viscous_J;
    if (measure) elastic_ += s.energy.elastic_J;
    contacts_ += s.contacts;
  }
  // (The partitions' buffers are added at the start of integrate(), in the
  // same pass over the particles.)
  oversizedContacts(measure);
  for (const WorkerScratch& s : scratch_)
    if (s.failed) {
      std::ostringstream m;
      m << "overlap " << s.fail_ratio << " of the smaller radius (limit " << max_overlap_ratio_ << ") between "
        << bodyName(pid_[s.fail_i]) << " and " << bodyName(pid_[s.fail_j]);
      fail(m.str());
      break;
    }
}

// Pairs with an oversized sphere (a boulder among grains: a short list),
// serially with the scalar law and a history per pair.
void Engine::oversizedContacts(bool measure) {
  const std::int64_t last = step_ - 1;
  ContactEnergy e;
  for (std::size_t q = 0; q < big_i_.size(); ++q) {
    const std::uint32_t i = big_i_[q], j = big_j_[q];
    const double ex = x_[j] - x_[i], ey = y_[j] - y_[i], ez = z_[j] - z_[i];
    const double d = std::sqrt(ex * ex + ey * ey + ez * ez);
    const double ri = r_[i], rj = r_[j];
    const double overlap = ri + rj - d;
    if (overlap <= 0.0) continue;
    double n[3] = {0.0, 0.0, 1.0};
    if (d > 0.0) {
      const double inv = 1.0 / d;
      n[0] = ex * inv, n[1] = ey * inv, n[2] = ez * inv;
    }
    if (overlap > max_overlap_ratio_ * std::min(ri, rj)) {
      std::ostringstream m;
      m << "overlap " << overlap / std::min(ri, rj) << " of the smaller radius (limit " << max_overlap_ratio_
        << ") between " << bodyName(pid_[i]) << " and " << bodyName(pid_[j]);
      fail(m.str());
    }
    const double li = ri - 0.5 * overlap, lj = rj - 0.5 * overlap;
    // velocity of the contact point on j relative to the one on i; the angular
    // velocities enter as lj w_j + li w_i: one cross product with n
    const double ax = lj * wx_[j] + li * wx_[i], ay = lj * wy_[j] + li * wy_[i], az = lj * wz_[j] + li * wz_[i];
    const double vrel[3] = {vx_[j] - vx_[i] - (ay * n[2] - az * n[1]), vy_[j] - vy_[i] - (az * n[0] - ax * n[2]),
                            vz_[j] - vz_[i] - (ax * n[1] - ay * n[0])};
    History::Entry h = big_hist_.get(q, last);
    double f[3];
    evaluateContact(laws_[mat_[i] * nmat_ + mat_[j]], inv_body_mass_[i] + inv_body_mass_[j], n, overlap, vrel, dt_,
                    h.u, h.plastic, h.viscous, f, e, measure);
    big_hist_.set(q, h, step_);
    fx_[i] += f[0], fy_[i] += f[1], fz_[i] += f[2];
    fx_[j] -= f[0], fy_[j] -= f[1], fz_[j] -= f[2];
    const double c[3] = {n[1] * f[2] - n[2] * f[1], n[2] * f[0] - n[0] * f[2], n[0] * f[1] - n[1] * f[0]};
    tx_[i] += li * c[0], ty_[i] += li * c[1], tz_[i] += li * c[2];
    tx_[j] += lj * c[0], ty_[j] += lj * c[1], tz_[j] += lj * c[2];
    ++contacts_;
  }
  friction_ += e.friction_J;
  plastic_ += e.plastic_J;
  viscous_ += e.viscous_J;
  if (measure) elastic_ += e.elastic_J;
}

void Engine::contactKernel(int t, bool measure) {
  WorkerScratch& s = scratch_[static_cast<std::size_t>(t)];
  s.energy = ContactEnergy{};
  s.contacts = 0;
  s.failed = false;
  s.lo = static_cast<std::uint32_t>(n_);
  s.hi = 0;
  const std::uint32_t r0 = part_begin_[static_cast<std::size_t>(t)], r1 = part_begin_[static_cast<std::size_t>(t) + 1];
  for (auto* v : {&fx_, &fy_, &fz_, &tx_, &ty_, &tz_}) std::fill(v->begin() + r0, v->begin() + r1, 0.0);
  double* const FX = fx_.data();
  double* const FY = fy_.data();
  double* const FZ = fz_.data();
  double* const TX = tx_.data();
  double* const TY = ty_.data();
  double* const TZ = tz_.data();
  const double* __restrict const X = x_.data();
  const double* __restrict const Y = y_.data();
  const double* __restrict const Z = z_.data();
  const double* __restrict const R = r_.data();
  const double* __restrict const VX = vx_.data();
  const double* __restrict const VY = vy_.data();
  const double* __restrict const VZ = vz_.data();
  const double* __restrict const WX = wx_.data();
  const double* __restrict const WY = wy_.data();
  const double* __restrict const WZ = wz_.data();
  const double* __restrict const IM = inv_body_mass_.data();
  const std::uint32_t* __restrict const MAT = mat_.data();
  const std::size_t nmat = nmat_;
  const double dt = dt_;
  const double ratio = max_overlap_ratio_;

  // The scan (branch-free, cache friendly) collects the touching list
  // entries of this partition's rows into a chunk; each full chunk goes
  // through the contact law (touchingPairs).
  KernelIn in{X, Y, Z, R, VX, VY, VZ, WX, WY, WZ, IM, MAT, nbr_.data(),
              law_kn_.data(), law_flim_.data(), law_ks_.data(), law_mu_ks_.data(), law_zeta_.data(),
              nmat, uniform_material_ ? mat_[0] * (nmat + 1) : 0, dt, ratio};
  // The last partition has no partner beyond its range and no buffer (empty vectors).
  KernelOut out{FX,          FY,          FZ,          TX,          TY,          TZ,
                s.fx.data(), s.fy.data(), s.fz.data(), s.tx.data(), s.ty.data(), s.tz.data(),
                r1,          &s.energy};
  ContactSet& next = s.sets[hcur_ ^ 1];
  next.n = 0;
  KernelHistory hist{&s.sets[hcur_], 0, &next};
  const TouchingPairsFn law = touchingPairsFor(measure, any_viscous_, any_plastic_, uniform_material_);
  std::uint32_t* __restrict const ti = s.touch_i.data();
  std::uint32_t* __restrict const tk = s.touch_k.data();
  std::size_t m = 0;
  // Evaluates the first nq collected pairs and keeps the rest for the next chunk.
  const auto flush = [&](std::size_t nq) {
    next.ensure(next.n + nq, any_plastic_, any_viscous_);
    law(in, ti, tk, nq, hist, out);
    std::copy(ti + nq, ti + m, ti);
    std::copy(tk + nq, tk + m, tk);
    m -= nq;
  };
  const std::uint32_t* __restrict const NBR = nbr_.data();
  const std::uint32_t* __restrict const ROW = row_begin_.data();
  for (std::uint32_t i = r0; i < r1; ++i) {
    const double xi = X[i], yi = Y[i], zi = Z[i], ri = R[i];
    const std::uint32_t kb = ROW[i], ke = ROW[i + 1];
    for (std::uint32_t k = kb; k < ke; ++k) {  // the buffers hold kChunk + the longest row
      const std::uint32_t j = NBR[k];
      const double ex = X[j] - xi, ey = Y[j] - yi, ez = Z[j] - zi, rs = ri + R[j];
      ti[m] = i;
      tk[m] = k;
      m += (ex * ex + ey * ey + ez * ez < rs * rs) ? 1 : 0;
    }
    while (m >= kChunk) flush(kChunk);  // leaves fewer than kChunk, so the next row fits
  }
  if (m > 0) flush(m);
  s.contacts += out.contacts;
  if (out.failed) s.failed = true, s.fail_i = out.fail_i, s.fail_j = out.fail_j, s.fail_ratio = out.fail_ratio;
  if (out.hi >= r1) s.lo = r1, s.hi = out.hi;  // the band of its buffer that the partition wrote
}

// ---------------------------------------------------------------------------
// applyWallsAndLoads: particle-wall contacts (same law), the force on each
// wall and the work of moving walls. Gravity is applied in integrate().

void Engine::applyWallsAndLoads(bool measure) {
  const double t_now = time();
  for (auto& w : walls_) w.position = w.p0 + w.v * t_now;
  // Each worker takes the candidates of its particle range (particles are
  // disjoint, so it adds to the global force arrays); wall forces, energies
  // and work are summed in worker order.
  parallel(StageProfile::kWalls, [this, measure](int t) { wallContacts(t, measure); });
  for (auto& w : walls_) w.force_N.setZero();
  for (WorkerScratch& s : scratch_) {
    for (std::size_t w = 0; w < walls_.size(); ++w) walls_[w].force_N += s.wall_force[w];
    friction_ += s.wall_energy.friction_J;
    plastic_ += s.wall_energy.plastic_J;
    viscous_ += s.wall_energy.viscous_J;
    if (measure) elastic_ += s.wall_energy.elastic_J;
    wall_work_ += s.wall_work;
    contacts_ += s.wall_contacts;
    if (!s.wall_failure.empty()) fail(s.wall_failure);
  }
}

namespace {
/// One wall's contacts with the candidates [k0, k1) of its list, one SIMD
/// lane per candidate (a particle is at most once in a wall's list, so the
/// force writes do not collide): the same law as the pairs (laneContact),
/// the history per candidate with the step it last touched.
struct WallLanes {
  const double *X, *Y, *Z, *R, *VX, *VY, *VZ, *WX, *WY, *WZ, *IM;
  const std::uint32_t* MAT;
  const double *KN, *FLIM, *KS, *MU_KS, *ZETA;
  std::size_t nmat, wall_mat;
  double dt, ratio;
  double *FX, *FY, *FZ, *TX, *TY, *TZ;
};
struct WallSums {
  double fx = 0.0, fy = 0.0, fz = 0.0, work = 0.0;  // force on the wall (N), work of its motion (J)
  double friction = 0.0, plastic = 0.0, viscous = 0.0, elastic = 0.0, contacts = 0.0, bad = 0.0;
};
template <bool kMeasure, bool kViscous, bool kPlastic>
WallSums wallLanes(const WallLanes& a, const std::uint32_t* cand, std::size_t k0, std::size_t k1, const Vec3& point,
                   const Vec3& normal, const Vec3& velocity, std::int64_t last, std::int64_t step, double* HUX,
                   double* HUY, double* HUZ, double* HPL, double* HVI, std::int64_t* STAMP) {
  const double *__restrict X = a.X, *__restrict Y = a.Y, *__restrict Z = a.Z, *__restrict R = a.R;
  const double *__restrict VX = a.VX, *__restrict VY = a.VY, *__restrict VZ = a.VZ;
  const double *__restrict WX = a.WX, *__restrict WY = a.WY, *__restrict WZ = a.WZ, *__restrict IM = a.IM;
  double *__restrict FX = a.FX, *__restrict FY = a.FY, *__restrict FZ = a.FZ;
  double *__restrict TX = a.TX, *__restrict TY = a.TY, *__restrict TZ = a.TZ;
  const double px = point.x(), py = point.y(), pz = point.z();
  const double wnx = normal.x(), wny = normal.y(), wnz = normal.z();
  const double nx = -wnx, ny = -wny, nz = -wnz;  // from the particle to the wall
  const double wvx = velocity.x(), wvy = velocity.y(), wvz = velocity.z();
  const double dt = a.dt, ratio = a.ratio;
  double sfx = 0.0, sfy = 0.0, sfz = 0.0, work = 0.0, fr = 0.0, pw = 0.0, vw = 0.0, el = 0.0, on_n = 0.0, bad = 0.0;
#pragma omp simd reduction(+ : sfx, sfy, sfz, work, fr, pw, vw, el, on_n, bad)
  for (std::size_t k = k0; k < k1; ++k) {
    const std::uint32_t i = cand[k];
    const double dist = (X[i] - px) * wnx + (Y[i] - py) * wny + (Z[i] - pz) * wnz;
    const double overlap = R[i] - dist;
    const bool act = overlap > 0.0;
    bad += act && overlap > ratio * R[i] ? 1.0 : 0.0;
    const double li = dist;
    // velocity of the wall's contact point relative to the particle's
    const double vx = wvx - VX[i] - li * (WY[i] * nz - WZ[i] * ny), vy = wvy - VY[i] - li * (WZ[i] * nx - WX[i] * nz),
                 vz = wvz - VZ[i] - li * (WX[i] * ny - WY[i] * nx);
    const bool had = STAMP[k] == last;  // touched at the last step: its history goes on
    double ux = had ? HUX[k] : 0.0, uy = had ? HUY[k] : 0.0, uz = had ? HUZ[k] : 0.0, pl = 0.0, vi = 0.0;
    if constexpr (kPlastic) pl = had ? HPL[k] : 0.0;
    if constexpr (kViscous) vi = had ? HVI[k] : 0.0;
    const std::size_t L = a.MAT[i] * a.nmat + a.wall_mat;
    const LaneContact c = laneContact<kMeasure, kViscous, kPlastic>(
        nx, ny, nz, overlap, vx, vy, vz, a.KN[L], a.KS[L], a.MU_KS[L], kPlastic ? a.FLIM[L] : 0.0,
        kViscous ? a.ZETA[L] : 0.0, IM[i], dt, ux, uy, uz, pl, vi);
    HUX[k] = act ? ux : HUX[k], HUY[k] = act ? uy : HUY[k], HUZ[k] = act ? uz : HUZ[k];
    if constexpr (kPlastic) HPL[k] = act ? pl : HPL[k];
    if constexpr (kViscous) HVI[k] = act ? vi : HVI[k];
    STAMP[k] = act ? step : STAMP[k];
    const double fx = act ? c.fx : 0.0, fy = act ? c.fy : 0.0, fz = act ? c.fz : 0.0;
    FX[i] += fx, FY[i] += fy, FZ[i] += fz;
    TX[i] += li * (ny * fz - nz * fy), TY[i] += li * (nz * fx - nx * fz), TZ[i] += li * (nx * fy - ny * fx);
    sfx -= fx, sfy -= fy, sfz -= fz;
    work += (fx * wvx + fy * wvy + fz * wvz) * dt;
    fr += act ? c.friction_J : 0.0;
    if constexpr (kPlastic) pw += act ? c.plastic_J : 0.0;
    if constexpr (kViscous) vw += act ? c.viscous_J : 0.0;
    if constexpr (kMeasure) el += act ? c.elastic_J : 0.0;
    on_n += act ? 1.0 : 0.0;
  }
  return {sfx, sfy, sfz, work, fr, pw, vw, el, on_n, bad};
}
using WallLanesFn = WallSums (*)(const WallLanes&, const std::uint32_t*, std::size_t, std::size_t, const Vec3&,
                                 const Vec3&, const Vec3&, std::int64_t, std::int64_t, double*, double*, double*,
                                 double*, double*, std::int64_t*);
WallLanesFn wallLanesFor(bool measure, bool viscous, bool plastic) {
  static constexpr WallLanesFn fns[8] = {wallLanes<false, false, false>, wallLanes<false, false, true>,
                                         wallLanes<false, true, false>,  wallLanes<false, true, true>,
                                         wallLanes<true, false, false>,  wallLanes<true, false, true>,
                                         wallLanes<true, true, false>,   wallLanes<true, true, true>};
  return fns[(measure ? 4 : 0) + (viscous ? 2 : 0) + (plastic ? 1 : 0)];
}
}  // namespace

void Engine::wallContacts(int t, bool measure) {
  WorkerScratch& s = scratch_[static_cast<std::size_t>(t)];
  const std::uint32_t b = wall_part_[static_cast<std::size_t>(t)], e = wall_part_[static_cast<std::size_t>(t) + 1];
  s.wall_force.assign(walls_.size(), Vec3::Zero());
  s.wall_energy = ContactEnergy{};
  s.wall_work = 0.0;
  s.wall_contacts = 0;
  s.wall_failure.clear();
  const WallLanesFn lanes = wallLanesFor(measure, any_viscous_, any_plastic_);
  WallLanes in{x_.data(),  y_.data(),  z_.data(),  r_.data(),        vx_.data(),       vy_.data(),
               vz_.data(), wx_.data(), wy_.data(), wz_.data(),       inv_body_mass_.data(), mat_.data(),
               law_kn_.data(), law_flim_.data(), law_ks_.data(), law_mu_ks_.data(), law_zeta_.data(), nmat_,
               0,          dt_,        max_overlap_ratio_, fx_.data(), fy_.data(),   fz_.data(),
               tx_.data(), ty_.data(), tz_.data()};
  for (std::size_t wi = 0; wi < walls_.size(); ++wi) {
    Wall& w = walls_[wi];
    in.wall_mat = static_cast<std::size_t>(w.mat);
    // candidates are in particle order
    const auto k0 = static_cast<std::size_t>(std::lower_bound(w.cand.begin(), w.cand.end(), b) - w.cand.begin());
    const auto k1 = static_cast<std::size_t>(std::lower_bound(w.cand.begin(), w.cand.end(), e) - w.cand.begin());
    History& h = w.hist;
    const WallSums sum = lanes(in, w.cand.data(), k0, k1, w.position, w.n, w.v, step_ - 1, step_, h.ux.data(),
                               h.uy.data(), h.uz.data(), h.plastic.data(), h.viscous.data(), h.stamp.data());
    s.wall_force[wi] = Vec3(sum.fx, sum.fy, sum.fz);
    s.wall_work += sum.work;
    s.wall_energy.friction_J += sum.friction;
    s.wall_energy.plastic_J += sum.plastic;
    s.wall_energy.viscous_J += sum.viscous;
    s.wall_energy.elastic_J += sum.elastic;
    s.wall_contacts += static_cast<std::size_t>(sum.contacts);
    if (sum.bad > 0.0 && s.wall_failure.empty()) {  // rare: name the candidate that overlaps most
      std::uint32_t worst = w.cand[k0];
      double worst_ratio = -std::numeric_limits<double>::infinity();
      for (std::size_t k = k0; k < k1; ++k) {
        const std::uint32_t i = w.cand[k];
        const Vec3 d(x_[i] - w.position.x(), y_[i] - w.position.y(), z_[i] - w.position.z());
        const double r = (r_[i] - d.dot(w.n)) / r_[i];
        if (r > worst_ratio) worst = w.cand[k], worst_ratio = r;
      }
      std::ostringstream m;
      m << "overlap " << worst_ratio << " of the radius (limit " << max_overlap_ratio_ << ") between "
        << bodyName(pid_[worst]) << " and wall " << wi;
      s.wall_failure = m.str();
    }
  }
}

// ---------------------------------------------------------------------------
// integrate: leapfrog (velocities at half steps). Free spheres in one SoA
// loop; blocks by kick (v, L) and drift (x, free rotation of q), members then
// placed rigidly. Local damping on each force/torque component. Also tracks
// the displacement since the last list build and NaN.

namespace {
// The free spheres of one worker's range in one pass over their arrays
// (translation and rotation of the three components, branch-free so that the
// loop vectorises; SoA arrays, no aliasing between them): each array is read
// once per step. Also the largest squared displacement since the last list
// build; block members are placed afterwards and checked there.
struct SphereArrays {
  double *x, *y, *z, *vx, *vy, *vz, *wx, *wy, *wz;
  const double *fx, *fy, *fz, *tx, *ty, *tz, *m, *im, *ii, *alpha, *x0, *y0, *z0;
};

// One component's kick with Cundall local damping
// (bridge/laws/contact_local_damping.hpp, written out branch-free): returns
// the new velocity and adds the damping work to `local`.
[[gnu::always_inline]] inline double dampedKick(double F, double v0, double inv_m, double alpha, double dt,
                                                double& local) {
  const double sgn = static_cast<double>(v0 > 0.0) - static_cast<double>(v0 < 0.0);
  const double Fd = -alpha * std::fabs(F) * sgn;
  const double v1 = v0 + dt * inv_m * (F + Fd);
  local -= Fd * (v0 + v1) * 0.5 * dt;
  return v1;
}

template <bool kMeasure>
SphereSums integrateSpheres(std::size_t b, std::size_t e, double dt, const Vec3& g, const SphereArrays& a) {
  double *__restrict X = a.x, *__restrict Y = a.y, *__restrict Z = a.z;
  double *__restrict VX = a.vx, *__restrict VY = a.vy, *__restrict VZ = a.vz;
  double *__restrict WX = a.wx, *__restrict WY = a.wy, *__restrict WZ = a.wz;
  const double *__restrict FX = a.fx, *__restrict FY = a.fy, *__restrict FZ = a.fz;
  const double *__restrict TX = a.tx, *__restrict TY = a.ty, *__restrict TZ = a.tz;
  const double *__restrict M = a.m, *__restrict IM = a.im, *__restrict II = a.ii, *__restrict AL = a.alpha;
  const double *__restrict X0 = a.x0, *__restrict Y0 = a.y0, *__restrict Z0 = a.z0;
  const double gx = g.x(), gy = g.y(), gz = g.z();
  double local = 0.0, ke_t = 0.0, ke_r = 0.0, pe = 0.0, finite = 0.0, max_d2 = 0.0;
#pragma omp simd reduction(+ : local, ke_t, ke_r, pe, finite) reduction(max : max_d2)
  for (std::size_t i = b; i < e; ++i) {
    const double m = M[i], im = IM[i], ii = II[i], al = AL[i];
    const double vx = dampedKick(FX[i] + m * gx, VX[i], im, al, dt, local);
    const double vy = dampedKick(FY[i] + m * gy, VY[i], im, al, dt, local);
    const double vz = dampedKick(FZ[i] + m * gz, VZ[i], im, al, dt, local);
    const double wx = dampedKick(TX[i], WX[i], ii, al, dt, local);
    const double wy = dampedKick(TY[i], WY[i], ii, al, dt, local);
    const double wz = dampedKick(TZ[i], WZ[i], ii, al, dt, local);
    const double x0 = X[i], y0 = Y[i], z0 = Z[i];
    const double x1 = x0 + dt * vx, y1 = y0 + dt * vy, z1 = z0 + dt * vz;
    if (kMeasure) {
      ke_t += 0.5 * m * (vx * vx + vy * vy + vz * vz);
      pe -= m * (gx * 0.5 * (x0 + x1) + gy * 0.5 * (y0 + y1) + gz * 0.5 * (z0 + z1));
      ke_r += ii > 0.0 ? 0.5 * (wx * wx + wy * wy + wz * wz) / ii : 0.0;
    }
    VX[i] = vx, VY[i] = vy, VZ[i] = vz, WX[i] = wx, WY[i] = wy, WZ[i] = wz;
    X[i] = x1, Y[i] = y1, Z[i] = z1;
    finite += x1 + y1 + z1 + vx + vy + vz + wx + wy + wz;
    const double ex = x1 - X0[i], ey = y1 - Y0[i], ez = z1 - Z0[i];
    max_d2 = std::max(max_d2, ex * ex + ey * ey + ez * ez);
  }
  return {local, ke_t, ke_r, pe, finite, max_d2};
}
}  // namespace

// The contact kernel's partition t left the forces on particles beyond its
// rows in its buffer (the band [lo, hi]); they are added here, for each
// particle in partition order, and the buffers cleared.
void Engine::addForceBuffers(std::size_t b, std::size_t e) {
  for (std::size_t t = 0; t + 1 < scratch_.size(); ++t) {
    WorkerScratch& s = scratch_[t];
    if (s.lo > s.hi) continue;
    const std::size_t lo = std::max<std::size_t>(b, s.lo), hi = std::min<std::size_t>(e, s.hi + std::size_t{1});
    for (std::size_t i = lo; i < hi; ++i) {
      fx_[i] += s.fx[i], fy_[i] += s.fy[i], fz_[i] += s.fz[i];
      tx_[i] += s.tx[i], ty_[i] += s.ty[i], tz_[i] += s.tz[i];
      s.fx[i] = s.fy[i] = s.fz[i] = s.tx[i] = s.ty[i] = s.tz[i] = 0.0;
    }
  }
}

void Engine::integrate(bool measure) {
  const double dt = dt_;
  double local = 0.0, ke_t = 0.0, ke_r = 0.0, pe = 0.0, max_d2 = 0.0, finite = 0.0;
  // Free spheres: the particles of each row partition (the same ranges as
  // the contact kernel's, so a particle's data stays in one core's cache),
  // partial sums added in partition order (deterministic for a given thread
  // count).
  const SphereArrays arrays{x_.data(),  y_.data(),  z_.data(),  vx_.data(), vy_.data(),          vz_.data(),
                            wx_.data(), wy_.data(), wz_.data(), fx_.data(), fy_.data(),          fz_.data(),
                            tx_.data(), ty_.data(), tz_.data(), mass_.data(), inv_mass_.data(), inv_inertia_.data(),
                            alpha_.data(), x0_.data(), y0_.data(), z0_.data()};
  const std::size_t workers = scratch_.size();
  parallel(StageProfile::kIntegrate, [&](int task) {
    const auto t = static_cast<std::size_t>(task);
    const std::size_t b = n_ * t / workers, e = n_ * (t + 1) / workers;
    addForceBuffers(b, e);
    scratch_[t].spheres =
        measure ? integrateSpheres<true>(b, e, dt, gravity_, arrays)
                : integrateSpheres<false>(b, e, dt, gravity_, arrays);
  });
  for (const WorkerScratch& w : scratch_) {
    const SphereSums& p = w.spheres;
    local += p.local, ke_t += p.ke_t, ke_r += p.ke_r, pe += p.pe, finite += p.finite;
    max_d2 = std::max(max_d2, p.max_d2);
  }
  for (auto& b : blocks_) {
    if (b.fixed) continue;
    Vec3 F = b.mass * gravity_, T = Vec3::Zero();
    for (const std::uint32_t pid : b.pids) {
      const std::uint32_t i = slot_[pid];
      const Vec3 f(fx_[i], fy_[i], fz_[i]);
      F += f;
      T += Vec3(x_[i] - b.x.x(), y_[i] - b.x.y(), z_[i] - b.x.z()).cross(f) + Vec3(tx_[i], ty_[i], tz_[i]);
    }
    const bridge::LocalDampingParams ld{b.alpha};
    Vec3 Fd, Td;
    for (int c = 0; c < 3; ++c) {
      Fd[c] = bridge::locallyDampedForce(ld, F[c], b.v[c]) - F[c];
      Td[c] = bridge::locallyDampedForce(ld, T[c], b.omega[c]) - T[c];
    }
    const Vec3 v0 = b.v, w0 = b.omega, x0 = b.x;
    b.v += dt * b.inv_mass * (F + Fd);
    b.L += dt * (T + Td);
    b.x += dt * b.v;
    freeRotate(b.q, b.L, b.inertia, dt);
    b.omega = angularVelocityWorld(b.q, b.L, b.inertia);
    local -= (Fd.dot(v0 + b.v) + Td.dot(w0 + b.omega)) * 0.5 * dt;
    if (measure) {
      ke_t += 0.5 * b.mass * b.v.squaredNorm();
      ke_r += 0.5 * b.L.dot(b.omega);
      pe -= b.mass * gravity_.dot(0.5 * (x0 + b.x));
    }
    finite += b.x.sum() + b.v.sum() + b.L.sum();
    for (std::size_t k = 0; k < b.pids.size(); ++k) {
      const std::uint32_t i = slot_[b.pids[k]];
      const Vec3 arm = b.q * b.offsets[k];
      const Vec3 vm = b.v + b.omega.cross(arm);
      x_[i] = b.x.x() + arm.x(), y_[i] = b.x.y() + arm.y(), z_[i] = b.x.z() + arm.z();
      vx_[i] = vm.x(), vy_[i] = vm.y(), vz_[i] = vm.z();
      wx_[i] = b.omega.x(), wy_[i] = b.omega.y(), wz_[i] = b.omega.z();
      max_d2 = std::max(max_d2, Vec3(x_[i] - x0_[i], y_[i] - y0_[i], z_[i] - z0_[i]).squaredNorm());
    }
  }
  local_work_ += local;
  if (measure) ke_t_ = ke_t, ke_r_ = ke_r, pe_ = pe;

  if (!std::isfinite(finite)) {
    for (std::size_t i = 0; i < n_; ++i)
      if (!std::isfinite(x_[i] + y_[i] + z_[i] + vx_[i] + vy_[i] + vz_[i] + wx_[i] + wy_[i] + wz_[i])) {
        fail("non-finite position or velocity of " + bodyName(pid_[i]));
        return;
      }
    for (std::size_t b = 0; b < blocks_.size(); ++b)
      if (!std::isfinite(blocks_[b].x.sum() + blocks_[b].v.sum() + blocks_[b].L.sum())) {
        fail("non-finite state of block " + std::to_string(b));
        return;
      }
    fail("non-finite state");
    return;
  }
  const double half = 0.5 * skin_m_;
  double wall_move = 0.0;
  const double t_next = time() + dt;
  for (const auto& w : walls_) wall_move = std::max(wall_move, w.v.norm() * (t_next - w.t_ref));
  if (max_d2 > half * half || wall_move > half) need_rebuild_ = true;
}

// ---------------------------------------------------------------------------
// Energy: stored terms come from this (measuring) step; dissipations and wall
// work are running sums since the start.

void Engine::measureEnergy() {
  EnergyTotals& e = energy_;
  e.kinetic_translational_J = ke_t_;
  e.kinetic_rotational_J = ke_r_;
  e.gravity_potential_J = pe_;
  e.elastic_contact_J = elastic_;
  elastic_ = 0.0;
  e.friction_dissipation_J = friction_;
  e.plastic_dissipation_J = plastic_;
  e.local_damping_dissipation_J = local_work_;
  e.viscous_damping_dissipation_J = viscous_;
  e.wall_work_J = wall_work_;
  const double stored = e.kinetic_translational_J + e.kinetic_rotational_J + e.elastic_contact_J;
  const double dissipated =
      e.friction_dissipation_J + e.plastic_dissipation_J + e.local_damping_dissipation_J + e.viscous_damping_dissipation_J;
  e.total_J = stored + e.gravity_potential_J + dissipated - e.wall_work_J;
  if (!have_e0_) {
    have_e0_ = true;
    e0_ = e.total_J;
    pe0_ = e.gravity_potential_J;
    scale_ke_el0_ = stored;
  }
  // Scale of the balance: all the energy that has been moved around.
  const double scale =
      std::max(scale_ke_el0_, stored + std::fabs(e.gravity_potential_J - pe0_) + dissipated + std::fabs(e.wall_work_J));
  e.balance_rel_error = scale > 0.0 ? (e.total_J - e0_) / scale : 0.0;
  const double supply = scale_ke_el0_ + std::fabs(e.gravity_potential_J - pe0_) + std::fabs(e.wall_work_J);
  if (stored > runaway_factor_ * supply && stored > 0.0) {
    std::ostringstream m;
    m << "energy runaway: kinetic + elastic energy " << stored << " J exceeds " << runaway_factor_
      << " x the energy supplied (" << supply << " J)";
    double worst = -1.0;
    std::string who;
    for (std::size_t i = 0; i < n_; ++i) {
      const double ke = mass_[i] * (vx_[i] * vx_[i] + vy_[i] * vy_[i] + vz_[i] * vz_[i]);
      if (ke > worst) worst = ke, who = bodyName(pid_[i]);
    }
    for (std::size_t b = 0; b < blocks_.size(); ++b)
      if (blocks_[b].mass * blocks_[b].v.squaredNorm() > worst)
        worst = blocks_[b].mass * blocks_[b].v.squaredNorm(), who = "block " + std::to_string(b);
    m << "; fastest body: " << who;
    fail(m.str());
  }
}

// ---------------------------------------------------------------------------

void Engine::fail(const std::string& what) {
  if (!failure_.empty()) return;
  std::ostringstream m;
  m << "step " << step_ << ", t = " << time() << " s: " << what;
  failure_ = m.str();
}

std::string Engine::bodyName(std::uint32_t pid) const {
  if (pid < sphere_count_) return "sphere " + std::to_string(pid);
  const std::int32_t b = block_[slot_[pid]];
  const auto& pids = blocks_[static_cast<std::size_t>(b)].pids;
  const auto k = std::find(pids.begin(), pids.end(), pid) - pids.begin();
  return "block " + std::to_string(b) + " (member sphere " + std::to_string(k) + ")";
}

BodyState Engine::body(std::size_t b) const {
  if (b < sphere_count_) {
    const std::uint32_t i = slot_[b];
    return {Vec3(x_[i], y_[i], z_[i]), Vec3(vx_[i], vy_[i], vz_[i]), Vec3(wx_[i], wy_[i], wz_[i])};
  }
  const Block& k = blocks_[b - sphere_count_];
  return {k.x, k.v, k.omega};
}

Eigen::Quaterniond Engine::blockOrientation(std::size_t b) const {
  const Block& k = blocks_[b];
  return (k.q * k.principal_axes.conjugate()).normalized();
}

double Engine::bodyRadius(std::size_t b) const {
  if (b < sphere_count_) return r_[slot_[b]];
  return std::cbrt(3.0 * blocks_[b - sphere_count_].volume / (4.0 * kPi));
}

std::size_t Engine::oversizedCount() const {
  return static_cast<std::size_t>(std::count(is_big_.begin(), is_big_.end(), std::uint8_t{1}));
}
std::size_t Engine::bodyCount() const { return sphere_count_ + blocks_.size(); }
std::size_t Engine::blockCount() const { return blocks_.size(); }
std::size_t Engine::wallCount() const { return walls_.size(); }
Vec3 Engine::wallForce(std::size_t w) const { return walls_[w].force_N; }
Vec3 Engine::wallPosition(std::size_t w) const { return walls_[w].position; }

}  // namespace gabion::micro
