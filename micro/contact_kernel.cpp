#include "micro/contact_kernel.hpp"

#include <algorithm>
#include <cmath>

#if defined(__AVX512F__) && defined(__AVX512VL__)
#include <immintrin.h>
#endif

namespace gabion::micro {

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
// material (and body mass) are compile-time switches, so a case pays only
// for what it uses.

namespace {
/// What the kernel reads: the particles, the list's partners, the laws.
struct KernelIn {
  const Particles& p;
  const std::uint32_t* nbr;
  const MaterialLaws& laws;
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
/// range (below own_end), the partition's buffer for partners beyond it
/// (particle j at j - own_end).
struct KernelOut {
  double *FX, *FY, *FZ, *TX, *TY, *TZ;
  double *BFX, *BFY, *BFZ, *BTX, *BTY, *BTZ;
  std::uint8_t* written;  // per cache line of particles (kParticlesPerLine) of the buffer
  std::uint32_t own_end;
  ContactEnergy* energy;
  std::size_t contacts = 0;
  const std::uint32_t* line_partition;    // per line of particles: the partition that owns it
  std::vector<std::uint32_t>* lines_for;  // per partition: the lines of its particles first written
  bool failed = false;
  std::uint32_t fail_i = 0, fail_j = 0;
  double fail_ratio = 0.0;
};

// kUniform: 0, a law per pair of materials; 1, one material (law0); 2, one
// material and one body mass (and so one dashpot coefficient); 3, as 2 and
// one radius (no radii gathered).
template <bool kMeasure, bool kViscous, bool kPlastic, int kUniform>
void touchingPairs(const KernelIn& in, const std::uint32_t* ci, const std::uint32_t* ck, const double* cex,
                   const double* cey, const double* cez, std::size_t nq, KernelHistory& h, KernelOut& out) {
  const Particles& P = in.p;
  const double* __restrict X = P.x.data(), * __restrict Y = P.y.data(), * __restrict Z = P.z.data(), * __restrict R = P.r.data();
  const double* __restrict VX = P.vx.data(), * __restrict VY = P.vy.data(), * __restrict VZ = P.vz.data();
  const double *__restrict WX = P.wx.data(), *__restrict WY = P.wy.data(), *__restrict WZ = P.wz.data(),
               *__restrict IM = P.inv_body_mass.data();
  const std::uint32_t* __restrict MAT = P.mat.data();
  const std::uint32_t* __restrict NBR = in.nbr;
  const MaterialLaws& laws = in.laws;
  const double *__restrict KN = laws.kn.data(), *__restrict FLIM = laws.flim.data(), *__restrict KS = laws.ks.data(),
               *__restrict MU_KS = laws.mu_ks.data(), *__restrict ZETA = laws.zeta.data();
  const std::size_t nmat = laws.nmat, law0 = laws.law0;
  const double dt = in.dt, ratio = in.ratio, uniform_damping = laws.uniform_damping, r0 = laws.uniform_radius_m;
  // Per-pair buffers, one row each, addressed from one base (so that the
  // scalar loops keep their pointers in registers), rows padded by 64 bytes
  // so that they do not alias modulo 4 KiB (false store-to-load
  // dependencies): the force on i, the torques on i and on j, 1 for a pair
  // that touches, and the history: the last step's on entry (zero for a new
  // contact), this step's on exit.
  enum { kFx, kFy, kFz, kIx, kIy, kIz, kJx, kJy, kJz, kOn, kUx, kUy, kUz, kPl, kVi, kRows };
  alignas(64) double b[kRows][kChunk + 8];
  double friction = 0.0, plastic_w = 0.0, viscous_w = 0.0, elastic = 0.0;
  {
    const ContactSet& last = *h.last;
    std::size_t p = h.cursor;
    for (std::size_t q = 0; q < nq; ++q) {
      const std::uint32_t k = ck[q];
      while (p < last.n && last.k[p] < k) ++p;
      if (p < last.n && last.k[p] == k) {
        b[kUx][q] = last.ux[p], b[kUy][q] = last.uy[p], b[kUz][q] = last.uz[p];
        if constexpr (kPlastic) b[kPl][q] = last.plastic[p];
        if constexpr (kViscous) b[kVi][q] = last.viscous[p];
      } else {
        b[kUx][q] = b[kUy][q] = b[kUz][q] = 0.0;
        if constexpr (kPlastic) b[kPl][q] = 0.0;
        if constexpr (kViscous) b[kVi][q] = 0.0;
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
      const double ex = cex[q], ey = cey[q], ez = cez[q];
      const double d = std::sqrt(ex * ex + ey * ey + ez * ez);
      const double ri = kUniform == 3 ? r0 : R[i], rj = kUniform == 3 ? r0 : R[j];
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
      const std::size_t L = kUniform > 0 ? law0 : MAT[i] * nmat + MAT[j];
      const double ks = KS[L];
      double ux = b[kUx][q], uy = b[kUy][q], uz = b[kUz][q], pl = 0.0, vi = 0.0;
      if constexpr (kPlastic) pl = b[kPl][q];
      if constexpr (kViscous) vi = b[kVi][q];
      const LaneContact c = laneContact<kMeasure, kViscous, kPlastic>(
          nx, ny, nz, overlap, vx, vy, vz, KN[L], ks, MU_KS[L], kPlastic ? FLIM[L] : 0.0,
          !kViscous       ? 0.0
          : kUniform >= 2 ? uniform_damping
                          : bridge::dashpotCoefficient({ZETA[L]}, KN[L], IM[i] + IM[j]),
          dt, ux, uy, uz, pl, vi);
      if constexpr (kPlastic) plastic_w += act ? c.plastic_J : 0.0;
      if constexpr (kViscous) viscous_w += act ? c.viscous_J : 0.0;
      friction += act ? c.friction_J : 0.0;
      if constexpr (kMeasure) elastic += act ? c.elastic_J : 0.0;
      // (a pair that does not touch is not appended to the contact set below)
      b[kUx][q] = ux, b[kUy][q] = uy, b[kUz][q] = uz;
      if constexpr (kPlastic) b[kPl][q] = pl;
      if constexpr (kViscous) b[kVi][q] = vi;
      const double fx = on * c.fx, fy = on * c.fy, fz = on * c.fz;
      const double cx = ny * fz - nz * fy, cy = nz * fx - nx * fz, cz = nx * fy - ny * fx;
      b[kFx][q] = fx, b[kFy][q] = fy, b[kFz][q] = fz;
      b[kIx][q] = li * cx, b[kIy][q] = li * cy, b[kIz][q] = li * cz;
      b[kJx][q] = lj * cx, b[kJy][q] = lj * cy, b[kJz][q] = lj * cz;
      b[kOn][q] = on;
      active_n += on;
    }
    double* __restrict FX = out.FX, * __restrict FY = out.FY, * __restrict FZ = out.FZ;
    double* __restrict TX = out.TX, * __restrict TY = out.TY, * __restrict TZ = out.TZ;
    ContactSet& next = *h.next;
    std::size_t nn = next.n;
    std::uint32_t* __restrict NK = next.k.data();
    double* __restrict NUX = next.ux.data(), * __restrict NUY = next.uy.data(), * __restrict NUZ = next.uz.data();
    double* __restrict NPL = next.plastic.data(), * __restrict NVI = next.viscous.data();
    const std::uint32_t own_end = out.own_end;
    // This step's contact set: the touching pairs' history, in list order
    // (with AVX-512, eight pairs at a time: compressed in a register, then
    // stored whole; the next group overwrites the tail. A compress straight
    // to memory is microcoded and slow on some cores. The scalar appends
    // were a third of the stores of the force loop below.)
#if defined(__AVX512F__) && defined(__AVX512VL__)
    for (std::size_t q = 0; q < nq; q += 8) {
      const std::size_t n = std::min<std::size_t>(8, nq - q);
      const auto valid = static_cast<__mmask8>((1u << n) - 1u);
      const __mmask8 on =
          _mm512_mask_cmp_pd_mask(valid, _mm512_maskz_load_pd(valid, b[kOn] + q), _mm512_setzero_pd(), _CMP_GT_OQ);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(NK + nn),
                          _mm256_maskz_compress_epi32(on, _mm256_maskz_loadu_epi32(valid, ck + q)));
      _mm512_storeu_pd(NUX + nn, _mm512_maskz_compress_pd(on, _mm512_maskz_load_pd(valid, b[kUx] + q)));
      _mm512_storeu_pd(NUY + nn, _mm512_maskz_compress_pd(on, _mm512_maskz_load_pd(valid, b[kUy] + q)));
      _mm512_storeu_pd(NUZ + nn, _mm512_maskz_compress_pd(on, _mm512_maskz_load_pd(valid, b[kUz] + q)));
      if constexpr (kPlastic)
        _mm512_storeu_pd(NPL + nn, _mm512_maskz_compress_pd(on, _mm512_maskz_load_pd(valid, b[kPl] + q)));
      if constexpr (kViscous)
        _mm512_storeu_pd(NVI + nn, _mm512_maskz_compress_pd(on, _mm512_maskz_load_pd(valid, b[kVi] + q)));
      nn += static_cast<std::size_t>(__builtin_popcount(on));
    }
#else
    for (std::size_t q = 0; q < nq; ++q) {
      // (overwritten by the next pair if this one does not touch)
      NK[nn] = ck[q], NUX[nn] = b[kUx][q], NUY[nn] = b[kUy][q], NUZ[nn] = b[kUz][q];
      if constexpr (kPlastic) NPL[nn] = b[kPl][q];
      if constexpr (kViscous) NVI[nn] = b[kVi][q];
      nn += b[kOn][q] > 0.0 ? 1 : 0;
    }
#endif
    // The forces, added in pair order. A partner beyond the partition's own
    // rows goes to its buffer: a branch, not a select of pointers, so the
    // common case (the partner is the partition's own) keeps its pointers
    // in registers.
    double* __restrict BFX = out.BFX, * __restrict BFY = out.BFY, * __restrict BFZ = out.BFZ;
    double* __restrict BTX = out.BTX, * __restrict BTY = out.BTY, * __restrict BTZ = out.BTZ;
    std::uint8_t* __restrict written = out.written;
    for (std::size_t q = 0; q < nq; ++q) {
      const std::uint32_t i = ci[q], j = NBR[ck[q]];
      FX[i] += b[kFx][q], FY[i] += b[kFy][q], FZ[i] += b[kFz][q];
      TX[i] += b[kIx][q], TY[i] += b[kIy][q], TZ[i] += b[kIz][q];
      if (j < own_end) {
        FX[j] -= b[kFx][q], FY[j] -= b[kFy][q], FZ[j] -= b[kFz][q];
        TX[j] += b[kJx][q], TY[j] += b[kJy][q], TZ[j] += b[kJz][q];
      } else {
        const std::uint32_t q_j = j - own_end;        // (the buffer starts at the partition's end)
        if (written[q_j / kParticlesPerLine] == 0) {  // a line first written: noted for its owner's integration
          written[q_j / kParticlesPerLine] = 1;
          const std::uint32_t line = j / kParticlesPerLine;
          out.lines_for[out.line_partition[line]].push_back(line);
        }
        BFX[q_j] -= b[kFx][q], BFY[q_j] -= b[kFy][q], BFZ[q_j] -= b[kFz][q];
        BTX[q_j] += b[kJx][q], BTY[q_j] += b[kJy][q], BTZ[q_j] += b[kJz][q];
      }
    }
    next.n = nn;
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

using TouchingPairsFn = void (*)(const KernelIn&, const std::uint32_t*, const std::uint32_t*, const double*,
                                 const double*, const double*, std::size_t, KernelHistory&, KernelOut&);
template <bool kMeasure, bool kViscous>
constexpr TouchingPairsFn kPlasticUniform[8] = {
    touchingPairs<kMeasure, kViscous, false, 0>, touchingPairs<kMeasure, kViscous, false, 1>,
    touchingPairs<kMeasure, kViscous, false, 2>, touchingPairs<kMeasure, kViscous, false, 3>,
    touchingPairs<kMeasure, kViscous, true, 0>,  touchingPairs<kMeasure, kViscous, true, 1>,
    touchingPairs<kMeasure, kViscous, true, 2>,  touchingPairs<kMeasure, kViscous, true, 3>};
TouchingPairsFn touchingPairsFor(bool measure, const MaterialLaws& laws) {
  const int v = (laws.any_plastic ? 4 : 0) + (laws.uniform_radius ? 3 : laws.uniform_mass ? 2 : laws.uniform ? 1 : 0);
  if (measure) return laws.any_viscous ? kPlasticUniform<true, true>[v] : kPlasticUniform<true, false>[v];
  return laws.any_viscous ? kPlasticUniform<false, true>[v] : kPlasticUniform<false, false>[v];
}
}  // namespace

void contactPartition(Particles& p, const NeighbourList& list, const MaterialLaws& laws, double dt,
                      double max_overlap_ratio, std::uint32_t r0, std::uint32_t r1, int hcur, bool measure,
                      const std::vector<std::uint32_t>& line_partition, WorkerScratch& s) {
  s.energy = ContactEnergy{};
  s.contacts = 0;
  s.failed = false;
  for (auto* v : {&p.fx, &p.fy, &p.fz, &p.tx, &p.ty, &p.tz}) std::fill(v->begin() + r0, v->begin() + r1, 0.0);
  const double* __restrict const X = p.x.data();
  const double* __restrict const Y = p.y.data();
  const double* __restrict const Z = p.z.data();
  const double* __restrict const R = p.r.data();

  // The scan (branch-free, cache friendly) collects the touching list
  // entries of this partition's rows into a chunk; each full chunk goes
  // through the contact law (touchingPairs).
  const KernelIn in{p, list.nbr.data(), laws, dt, max_overlap_ratio};
  // The last partition has no partner beyond its range and no buffer (empty vectors).
  KernelOut out;
  out.FX = p.fx.data(), out.FY = p.fy.data(), out.FZ = p.fz.data();
  out.TX = p.tx.data(), out.TY = p.ty.data(), out.TZ = p.tz.data();
  out.BFX = s.fx.data(), out.BFY = s.fy.data(), out.BFZ = s.fz.data();
  out.BTX = s.tx.data(), out.BTY = s.ty.data(), out.BTZ = s.tz.data();
  out.written = s.written.data();
  out.line_partition = line_partition.data();
  out.lines_for = s.lines_for.data();
  out.own_end = r1;
  out.energy = &s.energy;
  ContactSet& next = s.sets[hcur ^ 1];
  next.n = 0;
  KernelHistory hist{&s.sets[hcur], 0, &next};
  const TouchingPairsFn law = touchingPairsFor(measure, laws);
  std::uint32_t* __restrict const ti = s.touch_i.data();
  std::uint32_t* __restrict const tk = s.touch_k.data();
  double* __restrict const tx = s.touch_ex.data();
  double* __restrict const ty = s.touch_ey.data();
  double* __restrict const tz = s.touch_ez.data();
  std::size_t m = 0;
  // Evaluates the first nq collected pairs and keeps the rest for the next chunk.
  const auto flush = [&](std::size_t nq) {
    next.ensure(next.n + nq + 8, laws.any_plastic, laws.any_viscous);  // (+ 8: whole-vector stores)
    law(in, ti, tk, tx, ty, tz, nq, hist, out);
    std::copy(ti + nq, ti + m, ti);
    std::copy(tk + nq, tk + m, tk);
    std::copy(tx + nq, tx + m, tx);
    std::copy(ty + nq, ty + m, ty);
    std::copy(tz + nq, tz + m, tz);
    m -= nq;
  };
  const std::uint32_t* __restrict const NBR = list.nbr.data();
  const std::uint32_t* __restrict const OWN = list.owner.data();
  // The partition's list entries in one run, row after row: each entry
  // carries its row (the list's owner), so the vector scan fills every lane
  // whatever the rows' lengths (a row has three or four entries in a
  // settled packing: a scan row by row would leave half the lanes empty
  // and mispredict its loop's end at every row).
  const std::uint32_t kb = list.row_begin[r0], ke = list.row_begin[r1];
  // (one radius: the reach of every pair is 2 r, no radii gathered)
  const bool one_radius = laws.uniform_radius;
  const double reach0 = laws.uniform_radius_m + laws.uniform_radius_m;
#if defined(__AVX512F__) && defined(__AVX512VL__)
  // Eight entries at a time: both bodies' coordinates gathered, the
  // touching entries compressed in registers and stored whole (the next
  // group overwrites the tail; the buffers hold kChunk + 8). The same
  // differences as the scalar loop below, so the same pairs' kinematics: a
  // pair on the edge that the two loops classify apart has no overlap and
  // does nothing in touchingPairs.
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m512d vreach0 = _mm512_set1_pd(reach0 * reach0), zero = _mm512_setzero_pd();
  for (std::uint32_t k = kb; k < ke; k += 8) {
    const std::uint32_t n = std::min<std::uint32_t>(8, ke - k);
    const auto valid = static_cast<__mmask8>((1u << n) - 1u);
    const __m256i i = _mm256_maskz_loadu_epi32(valid, OWN + k), j = _mm256_maskz_loadu_epi32(valid, NBR + k);
    const __m512d ex =
        _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, valid, j, X, 8), _mm512_mask_i32gather_pd(zero, valid, i, X, 8));
    const __m512d ey =
        _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, valid, j, Y, 8), _mm512_mask_i32gather_pd(zero, valid, i, Y, 8));
    const __m512d ez =
        _mm512_sub_pd(_mm512_mask_i32gather_pd(zero, valid, j, Z, 8), _mm512_mask_i32gather_pd(zero, valid, i, Z, 8));
    __m512d reach2 = vreach0;
    if (!one_radius) {
      const __m512d rs =
          _mm512_add_pd(_mm512_mask_i32gather_pd(zero, valid, i, R, 8), _mm512_mask_i32gather_pd(zero, valid, j, R, 8));
      reach2 = _mm512_mul_pd(rs, rs);
    }
    const __m512d d2 = _mm512_fmadd_pd(ez, ez, _mm512_fmadd_pd(ey, ey, _mm512_mul_pd(ex, ex)));
    const __mmask8 touch = _mm512_mask_cmp_pd_mask(valid, d2, reach2, _CMP_LT_OQ);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(ti + m), _mm256_maskz_compress_epi32(touch, i));
    _mm256_storeu_si256(
        reinterpret_cast<__m256i*>(tk + m),
        _mm256_maskz_compress_epi32(touch, _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(k)), lanes)));
    _mm512_storeu_pd(tx + m, _mm512_maskz_compress_pd(touch, ex));
    _mm512_storeu_pd(ty + m, _mm512_maskz_compress_pd(touch, ey));
    _mm512_storeu_pd(tz + m, _mm512_maskz_compress_pd(touch, ez));
    m += static_cast<std::size_t>(__builtin_popcount(touch));
    if (m >= kChunk) flush(kChunk);  // leaves fewer than 8
  }
#else
  for (std::uint32_t k = kb; k < ke; ++k) {  // the buffers hold kChunk + 8
    const std::uint32_t i = OWN[k], j = NBR[k];
    const double ex = X[j] - X[i], ey = Y[j] - Y[i], ez = Z[j] - Z[i];
    const double rs = one_radius ? reach0 : R[i] + R[j];
    ti[m] = i;
    tk[m] = k;
    tx[m] = ex, ty[m] = ey, tz[m] = ez;
    m += (ex * ex + ey * ey + ez * ez < rs * rs) ? 1 : 0;
    if (m >= kChunk) flush(kChunk);
  }
#endif
  if (m > 0) flush(m);
  s.contacts += out.contacts;
  if (out.failed) s.failed = true, s.fail_i = out.fail_i, s.fail_j = out.fail_j, s.fail_ratio = out.fail_ratio;
}

}  // namespace gabion::micro
