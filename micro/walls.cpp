#include "micro/walls.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
#include <immintrin.h>
#endif

namespace gabion::micro {

void StampedHistory::resize(std::size_t m) {
  for (auto* v : {&ux, &uy, &uz, &plastic, &viscous}) v->assign(m, 0.0);
  stamp.assign(m, std::numeric_limits<std::int64_t>::min() / 2);
}

namespace {
constexpr double kPi = 3.14159265358979323846;

// Displacement of a velocity table from 0 to t: the integral of the
// piecewise-linear velocity (the last value holds after the table).
Vec3 tableDisplacement(const WallProgram& p, double t) {
  const std::vector<double>& T = p.table_time_s;
  const std::vector<Vec3>& V = p.table_velocity_m_s;
  Vec3 d = Vec3::Zero();
  for (std::size_t k = 0; k + 1 < T.size(); ++k) {
    if (t <= T[k]) return d;
    const double span = T[k + 1] - T[k], s = std::min(t, T[k + 1]) - T[k];
    d += V[k] * s + 0.5 * (V[k + 1] - V[k]) * (s * s / span);
  }
  return t > T.back() ? Vec3(d + V.back() * (t - T.back())) : d;
}
}  // namespace

Vec3 programDisplacement(const WallProgram& p, double t0, double t1) {
  using K = WallProgram::Kind;
  switch (p.kind) {
    case K::Fixed:
    case K::Servo:
    case K::Driven:
      return Vec3::Zero();
    case K::Velocity:
      return p.velocity_m_s * (t1 - t0);
    case K::VelocityTable:
      return tableDisplacement(p, t1) - tableDisplacement(p, t0);
    case K::Sinusoid: {
      const double w = 2.0 * kPi * p.frequency_hz;
      // sin a - sin b = 2 cos((a + b) / 2) sin((a - b) / 2): no cancellation for a small step
      const double a = w * t1 + p.phase_rad, b = w * t0 + p.phase_rad;
      return p.direction * (p.amplitude_m * 2.0 * std::cos(0.5 * (a + b)) * std::sin(0.5 * (a - b)));
    }
  }
  return Vec3::Zero();
}

Wall::Wall(const WallSpec& spec)
    : name(spec.name),
      n(spec.normal),
      mat(spec.material),
      program(spec.program),
      bounded(spec.bounded),
      skip_groups(spec.skip_groups),
      origin(spec.point_m),
      position(spec.point_m),
      force_position(spec.point_m),
      at_rebuild(spec.point_m) {
  if (bounded) {
    rounded = spec.rounded_edges;
    u = spec.axis_u;
    v = n.cross(u);
    half_u = spec.half_u_m;
    half_v = spec.half_v_m;
  }
}

void Wall::plan(double t, double dt) {
  if (program.kind == WallProgram::Kind::Servo) {
    // Velocity along the normal from the force error, at most max_speed:
    // a wall that feels too little force moves towards the bodies. A wall
    // that has touched nothing for approach_after_s closes in at max_speed;
    // a shorter loss of contact keeps it on its gain (a wall that rushed back
    // at max_speed whenever its bodies fell away from it, shaken, would
    // hammer them).
    const double force = normalForce();
    untouched_s = force != 0.0 ? 0.0 : untouched_s + dt;
    const double speed = untouched_s > program.approach_after_s
                             ? program.max_speed_m_s
                             : std::clamp(program.gain_m_s_N * (program.target_force_N - force), -program.max_speed_m_s,
                                          program.max_speed_m_s);
    velocity = speed * n;
    step_displacement = velocity * dt;
    return;
  }
  if (program.kind == WallProgram::Kind::Driven) {
    // (the driver sets the step's displacement once the forces are known;
    // until then the contacts see the last step's velocity, as the bodies'
    // own velocities are those of the last half step)
    step_displacement.setZero();
    return;
  }
  step_displacement = programDisplacement(program, t, t + dt);
  velocity = step_displacement / dt;
}

void Wall::archive(bridge::StateArchive& a) {
  bridge::StateArchive pa = a.group("program");
  pa("kind", program.kind);
  pa("velocity_m_s", program.velocity_m_s);
  pa("table_time_s", program.table_time_s);
  pa("table_velocity_m_s", program.table_velocity_m_s);
  pa("direction", program.direction);
  pa("amplitude_m", program.amplitude_m);
  pa("frequency_hz", program.frequency_hz);
  pa("phase_rad", program.phase_rad);
  pa("target_force_N", program.target_force_N);
  pa("max_speed_m_s", program.max_speed_m_s);
  pa("gain_m_s_N", program.gain_m_s_N);
  pa("approach_after_s", program.approach_after_s);
  a("untouched_s", untouched_s);
  a("position", position);
  a("velocity", velocity);
  a("step_displacement", step_displacement);
  a("force_N", force_N);
  a("force_position", force_position);
  a("at_rebuild", at_rebuild);
  a("candidates", cand);
  bridge::StateArchive h = a.group("history");
  h("ux", hist.ux), h("uy", hist.uy), h("uz", hist.uz), h("plastic", hist.plastic), h("viscous", hist.viscous);
  h("stamp", hist.stamp);
}

void wallCandidates(const Particles& p, std::vector<Wall>& walls, double skin, std::size_t nblocks,
                    const ForBlocks& for_blocks) {
  const std::size_t n = p.size(), nwalls = walls.size();
  const auto blockBegin = [&](std::size_t b) { return n * b / nblocks; };
  std::vector<std::vector<std::uint32_t>> lists(nblocks * nwalls);
  for_blocks(nblocks, [&](std::size_t b) {
    const std::size_t i0 = blockBegin(b), i1 = blockBegin(b + 1);
    const std::unique_ptr<std::uint32_t[]> buffer(new std::uint32_t[i1 - i0 + 8]);
    std::uint32_t* __restrict const o = buffer.get();
    const double *__restrict X = p.x.data(), *__restrict Y = p.y.data(), *__restrict Z = p.z.data(),
                 *__restrict R = p.r.data(), *__restrict IMB = p.inv_body_mass.data();
    const std::uint8_t* __restrict GRP = p.group.data();
    for (std::size_t wi = 0; wi < nwalls; ++wi) {
      const Wall& w = walls[wi];
      const double px = w.position.x(), py = w.position.y(), pz = w.position.z();
      const double nx = w.n.x(), ny = w.n.y(), nz = w.n.z();
      const double ux = w.u.x(), uy = w.u.y(), uz = w.u.z(), vx = w.v.x(), vy = w.v.y(), vz = w.v.z();
      // the wall may move half a skin before the next build
      const double inf = std::numeric_limits<double>::infinity();
      const double lim_u = w.bounded ? w.half_u + skin : inf, lim_v = w.bounded ? w.half_v + skin : inf;
      const bool bounded = w.bounded, rounded = w.rounded;
      const std::uint32_t skip = w.skip_groups;
      // Branch-free (the test decides whether the write is kept): the
      // particles are in cell order, so a wall's candidates come in short
      // runs, and a branch on each mispredicted at every run's ends.
      std::size_t cnt = 0, i = i0;
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
      // Eight particles at a time, the block's tail masked, the kept ones
      // compressed in a register and stored whole (the buffer holds eight
      // more): the same test, operation for operation.
      {
        const __m512d vpx = _mm512_set1_pd(px), vpy = _mm512_set1_pd(py), vpz = _mm512_set1_pd(pz);
        const __m512d vnx = _mm512_set1_pd(nx), vny = _mm512_set1_pd(ny), vnz = _mm512_set1_pd(nz);
        const __m512d vux = _mm512_set1_pd(ux), vuy = _mm512_set1_pd(uy), vuz = _mm512_set1_pd(uz);
        const __m512d vvx = _mm512_set1_pd(vx), vvy = _mm512_set1_pd(vy), vvz = _mm512_set1_pd(vz);
        const __m512d vskin = _mm512_set1_pd(skin), vnskin = _mm512_set1_pd(-skin), zero = _mm512_setzero_pd();
        const __m512d vlim_u = _mm512_set1_pd(lim_u), vlim_v = _mm512_set1_pd(lim_v);
        const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
                      vskip = _mm256_set1_epi32(static_cast<int>(skip));
        for (; i < i1; i += 8) {
          const __mmask8 valid = i1 - i >= 8 ? __mmask8{0xFF} : static_cast<__mmask8>((1u << (i1 - i)) - 1u);
          const __m512d dx = _mm512_sub_pd(_mm512_maskz_loadu_pd(valid, X + i), vpx);
          const __m512d dy = _mm512_sub_pd(_mm512_maskz_loadu_pd(valid, Y + i), vpy);
          const __m512d dz = _mm512_sub_pd(_mm512_maskz_loadu_pd(valid, Z + i), vpz);
          const __m512d r = _mm512_maskz_loadu_pd(valid, R + i);
          const __m512d dist = _mm512_fmadd_pd(dz, vnz, _mm512_fmadd_pd(dy, vny, _mm512_mul_pd(dx, vnx)));
          __mmask8 keep = _mm512_mask_cmp_pd_mask(valid, _mm512_maskz_loadu_pd(valid, IMB + i), zero, _CMP_NEQ_UQ);
          const __m256i g = _mm256_cvtepu8_epi32(_mm_maskz_loadu_epi8(valid, GRP + i));
          keep = _mm256_mask_testn_epi32_mask(keep, _mm256_srlv_epi32(vskip, g), _mm256_set1_epi32(1));
          keep = _mm512_mask_cmp_pd_mask(keep, dist, _mm512_add_pd(r, vskin), _CMP_LT_OQ);
          if (rounded)
            keep = _mm512_mask_cmp_pd_mask(keep, dist, _mm512_sub_pd(_mm512_sub_pd(zero, r), vskin), _CMP_GT_OQ);
          else if (bounded)
            keep = _mm512_mask_cmp_pd_mask(keep, dist, vnskin, _CMP_GE_OQ);
          if (bounded) {
            const __m512d edge = rounded ? r : zero;
            const __m512d du = _mm512_fmadd_pd(dz, vuz, _mm512_fmadd_pd(dy, vuy, _mm512_mul_pd(dx, vux)));
            const __m512d dv = _mm512_fmadd_pd(dz, vvz, _mm512_fmadd_pd(dy, vvy, _mm512_mul_pd(dx, vvx)));
            keep = _mm512_mask_cmp_pd_mask(keep, _mm512_abs_pd(du), _mm512_add_pd(vlim_u, edge), _CMP_LE_OQ);
            keep = _mm512_mask_cmp_pd_mask(keep, _mm512_abs_pd(dv), _mm512_add_pd(vlim_v, edge), _CMP_LE_OQ);
          }
          const __m256i is = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(i)), lanes);
          _mm256_storeu_si256(reinterpret_cast<__m256i*>(o + cnt), _mm256_maskz_compress_epi32(keep, is));
          cnt += static_cast<std::size_t>(__builtin_popcount(keep));
        }
      }
#endif
      for (; i < i1; ++i) {
        const double dx = X[i] - px, dy = Y[i] - py, dz = Z[i] - pz, r = R[i];
        const double dist = dx * nx + dy * ny + dz * nz;
        const bool loose = IMB[i] != 0.0, grouped = ((skip >> GRP[i]) & 1u) == 0;
        // (a rounded plate also meets a particle beyond its rectangle, at
        // its rim, and one behind it)
        const double edge = rounded ? r : 0.0;
        const bool front = dist < r + skin, behind = rounded ? dist > -r - skin : !bounded || dist >= -skin;
        const bool over = !bounded || ((std::fabs(dx * ux + dy * uy + dz * uz) <= lim_u + edge) &
                                       (std::fabs(dx * vx + dy * vy + dz * vz) <= lim_v + edge));
        const bool keep = loose & grouped & front & behind & over;
        o[cnt] = static_cast<std::uint32_t>(i);
        cnt += keep ? 1 : 0;
      }
      lists[b * nwalls + wi].assign(o, o + cnt);
    }
  });
  for (std::size_t wi = 0; wi < nwalls; ++wi) {
    Wall& w = walls[wi];
    w.cand.clear();
    for (std::size_t b = 0; b < nblocks; ++b)
      w.cand.insert(w.cand.end(), lists[b * nwalls + wi].begin(), lists[b * nwalls + wi].end());
    w.hist.resize(w.cand.size());
    w.at_rebuild = w.position;
  }
}

void wallDamping(const Particles& p, std::vector<Wall>& walls, const MaterialLaws& laws) {
  for (Wall& w : walls) {
    w.cand_damping.resize(w.cand.size());
    for (std::size_t k = 0; k < w.cand.size(); ++k) {
      const std::uint32_t i = w.cand[k];
      const std::size_t L = p.mat[i] * laws.nmat + static_cast<std::size_t>(w.mat);
      w.cand_damping[k] = bridge::dashpotCoefficient({laws.zeta[L]}, laws.kn[L], p.inv_body_mass[i]);
    }
  }
}

namespace {
/// One wall's contacts with the candidates [k0, k1) of its list, one SIMD
/// lane per candidate (a particle is at most once in a wall's list, so the
/// force writes do not collide): the same law as the pairs (laneContact),
/// the history per candidate with the step it last touched.
struct WallLanes {
  Particles& p;
  const MaterialLaws& laws;
  std::size_t wall_mat;
  double dt, ratio;
  std::size_t one_law = 0;  // the law of the wall's material with the particles' one material
};
struct WallSums {
  double fx = 0.0, fy = 0.0, fz = 0.0, work = 0.0;  // force on the wall (N), work of its motion (J)
  double friction = 0.0, plastic = 0.0, viscous = 0.0, elastic = 0.0, contacts = 0.0, bad = 0.0;
};
/// The shape a wall's contacts see.
enum Shape { kInfinite, kBounded, kRounded };
// kOne: 0, each candidate's law gathered by its material; 1, the particles'
// one material (one law per wall); 2, as 1 and one radius (no radii gathered).
template <bool kMeasure, bool kViscous, bool kPlastic, int kShape, int kOne>
WallSums wallLanes(const WallLanes& a, const Wall& w, std::size_t k0, std::size_t k1, std::int64_t step,
                   StampedHistory& h) {
  const std::uint32_t* __restrict cand = w.cand.data();
  const Vec3 &point = w.position, &normal = w.n, &velocity = w.velocity;
  const std::int64_t last = step - 1;
  double *__restrict HUX = h.ux.data(), *__restrict HUY = h.uy.data(), *__restrict HUZ = h.uz.data(),
         *__restrict HPL = h.plastic.data(), *__restrict HVI = h.viscous.data();
  std::int64_t* __restrict STAMP = h.stamp.data();
  const double* __restrict DW = w.cand_damping.data();
  // A bounded wall acts on a particle whose centre is in front of it and
  // over its rectangle; an infinite one on every candidate (a particle
  // behind it has tunnelled: its overlap stops the run).
  const double inf = std::numeric_limits<double>::infinity();
  const double lim_u = w.bounded ? w.half_u : inf, lim_v = w.bounded ? w.half_v : inf;
  const double min_dist = w.bounded ? 0.0 : -inf;
  const double ux_ = w.u.x(), uy_ = w.u.y(), uz_ = w.u.z(), vx_ = w.v.x(), vy_ = w.v.y(), vz_ = w.v.z();
  Particles& P = a.p;
  const double* __restrict X = P.x.data(), * __restrict Y = P.y.data(), * __restrict Z = P.z.data(), * __restrict R = P.r.data();
  const double* __restrict VX = P.vx.data(), * __restrict VY = P.vy.data(), * __restrict VZ = P.vz.data();
  const double* __restrict WX = P.wx.data(), * __restrict WY = P.wy.data(), * __restrict WZ = P.wz.data();
  const std::uint32_t* __restrict MAT = P.mat.data();
  double* __restrict FX = P.fx.data(), * __restrict FY = P.fy.data(), * __restrict FZ = P.fz.data();
  double* __restrict TX = P.tx.data(), * __restrict TY = P.ty.data(), * __restrict TZ = P.tz.data();
  const MaterialLaws& laws = a.laws;
  const std::size_t L1 = a.one_law;
  const double r1 = laws.uniform_radius_m;
  const double px = point.x(), py = point.y(), pz = point.z();
  const double wnx = normal.x(), wny = normal.y(), wnz = normal.z();
  const double nx0 = -wnx, ny0 = -wny, nz0 = -wnz;  // from the particle to the wall
  const double wvx = velocity.x(), wvy = velocity.y(), wvz = velocity.z();
  const double dt = a.dt, ratio = a.ratio;
  double sfx = 0.0, sfy = 0.0, sfz = 0.0, work = 0.0, fr = 0.0, pw = 0.0, vw = 0.0, el = 0.0, on_n = 0.0, bad = 0.0;
#pragma omp simd reduction(+ : sfx, sfy, sfz, work, fr, pw, vw, el, on_n, bad)
  for (std::size_t k = k0; k < k1; ++k) {
    const std::uint32_t i = cand[k];
    const double ri = kOne == 2 ? r1 : R[i];
    const double ex = X[i] - px, ey = Y[i] - py, ez = Z[i] - pz;
    double dist = ex * wnx + ey * wny + ez * wnz;
    // the normal, from the particle to the wall (for a rounded plate's edge, to its nearest point)
    double nx = nx0, ny = ny0, nz = nz0;
    bool act;
    if constexpr (kShape == kRounded) {
      const double du = ex * ux_ + ey * uy_ + ez * uz_, dv = ex * vx_ + ey * vy_ + ez * vz_;
      const double cu = std::clamp(du, -lim_u, lim_u), cv = std::clamp(dv, -lim_v, lim_v);
      const double rx = ex - cu * ux_ - cv * vx_, ry = ey - cu * uy_ - cv * vy_, rz = ez - cu * uz_ - cv * vz_;
      // (a thin rigid rectangle, met on either face and at its rim: the
      // force is continuous wherever a particle goes)
      dist = std::sqrt(rx * rx + ry * ry + rz * rz);
      const double inv = dist > 0.0 ? 1.0 / dist : 0.0;
      nx = -rx * inv, ny = -ry * inv, nz = -rz * inv;
      act = ri - dist > 0.0;
    } else {
      act = ri - dist > 0.0;
    }
    const double overlap = ri - dist;
    if constexpr (kShape == kBounded) {
      const double du = ex * ux_ + ey * uy_ + ez * uz_, dv = ex * vx_ + ey * vy_ + ez * vz_;
      act = act && dist > min_dist && std::fabs(du) <= lim_u && std::fabs(dv) <= lim_v;
    }
    bad += act && overlap > ratio * ri ? 1.0 : 0.0;
    const double li = dist;
    // velocity of the wall's contact point relative to the particle's
    const double vx = wvx - VX[i] - li * (WY[i] * nz - WZ[i] * ny), vy = wvy - VY[i] - li * (WZ[i] * nx - WX[i] * nz),
                 vz = wvz - VZ[i] - li * (WX[i] * ny - WY[i] * nx);
    const bool had = STAMP[k] == last;  // touched at the last step: its history goes on
    double ux = had ? HUX[k] : 0.0, uy = had ? HUY[k] : 0.0, uz = had ? HUZ[k] : 0.0, pl = 0.0, vi = 0.0;
    if constexpr (kPlastic) pl = had ? HPL[k] : 0.0;
    if constexpr (kViscous) vi = had ? HVI[k] : 0.0;
    const std::size_t L = kOne > 0 ? L1 : MAT[i] * laws.nmat + a.wall_mat;
    const LaneContact c = laneContact<kMeasure, kViscous, kPlastic>(
        nx, ny, nz, overlap, vx, vy, vz, laws.kn[L], laws.ks[L], laws.mu_ks[L], kPlastic ? laws.flim[L] : 0.0,
        kViscous ? DW[k] : 0.0, dt, ux, uy, uz, pl, vi);
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
using WallLanesFn = WallSums (*)(const WallLanes&, const Wall&, std::size_t, std::size_t, std::int64_t,
                                 StampedHistory&);
template <int kShape, int kOne>
WallLanesFn wallLanesFor(bool measure, bool viscous, bool plastic) {
  static constexpr WallLanesFn fns[8] = {
      wallLanes<false, false, false, kShape, kOne>, wallLanes<false, false, true, kShape, kOne>,
      wallLanes<false, true, false, kShape, kOne>,  wallLanes<false, true, true, kShape, kOne>,
      wallLanes<true, false, false, kShape, kOne>,  wallLanes<true, false, true, kShape, kOne>,
      wallLanes<true, true, false, kShape, kOne>,   wallLanes<true, true, true, kShape, kOne>};
  return fns[(measure ? 4 : 0) + (viscous ? 2 : 0) + (plastic ? 1 : 0)];
}
/// The kernel of a wall's shape, for the scene's materials and radii.
template <int kShape>
WallLanesFn wallLanesFor(bool measure, const MaterialLaws& laws) {
  const bool v = laws.any_viscous, pl = laws.any_plastic;
  if (laws.uniform_radius) return wallLanesFor<kShape, 2>(measure, v, pl);
  if (laws.uniform) return wallLanesFor<kShape, 1>(measure, v, pl);
  return wallLanesFor<kShape, 0>(measure, v, pl);
}
}  // namespace

void wallPartition(Particles& p, std::vector<Wall>& walls, const MaterialLaws& laws, double dt,
                   double max_overlap_ratio, std::int64_t step, std::uint32_t b, std::uint32_t e, bool measure,
                   WorkerScratch& s) {
  s.wall_force.assign(walls.size(), Vec3::Zero());
  s.wall_energy = ContactEnergy{};
  s.wall_work = 0.0;
  s.wall_contacts = 0;
  s.wall_failed = false;
  // (an infinite wall skips the rectangle test: a compile-time switch)
  const WallLanesFn infinite = wallLanesFor<kInfinite>(measure, laws);
  const WallLanesFn bounded = wallLanesFor<kBounded>(measure, laws);
  const WallLanesFn rounded = wallLanesFor<kRounded>(measure, laws);
  WallLanes in{p, laws, 0, dt, max_overlap_ratio};
  for (std::size_t wi = 0; wi < walls.size(); ++wi) {
    Wall& w = walls[wi];
    in.wall_mat = static_cast<std::size_t>(w.mat);
    in.one_law = laws.uniform ? static_cast<std::size_t>(p.mat.empty() ? 0 : p.mat[0]) * laws.nmat + in.wall_mat : 0;
    // candidates are in particle order
    const auto k0 = static_cast<std::size_t>(std::lower_bound(w.cand.begin(), w.cand.end(), b) - w.cand.begin());
    const auto k1 = static_cast<std::size_t>(std::lower_bound(w.cand.begin(), w.cand.end(), e) - w.cand.begin());
    if (k0 == k1) continue;  // (its force stays zero: no contact of this range)
    const WallSums sum = (w.rounded ? rounded : w.bounded ? bounded : infinite)(in, w, k0, k1, step, w.hist);
    s.wall_force[wi] = Vec3(sum.fx, sum.fy, sum.fz);
    s.wall_work += sum.work;
    s.wall_energy.friction_J += sum.friction;
    s.wall_energy.plastic_J += sum.plastic;
    s.wall_energy.viscous_J += sum.viscous;
    s.wall_energy.elastic_J += sum.elastic;
    s.wall_contacts += static_cast<std::size_t>(sum.contacts);
    if (sum.bad > 0.0 && !s.wall_failed) {  // rare: name the candidate that overlaps most
      s.wall_failed = true;
      s.wall_fail_wall = wi;
      s.wall_fail_ratio = -std::numeric_limits<double>::infinity();
      for (std::size_t k = k0; k < k1; ++k) {
        const std::uint32_t i = w.cand[k];
        const Vec3 d(p.x[i] - w.position.x(), p.y[i] - w.position.y(), p.z[i] - w.position.z());
        const double r = (p.r[i] - d.dot(w.n)) / p.r[i];
        if (r > s.wall_fail_ratio) s.wall_fail_i = i, s.wall_fail_ratio = r;
      }
    }
  }
}

}  // namespace gabion::micro
