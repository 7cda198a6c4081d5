#include "micro/neighbour_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
#include <immintrin.h>
#endif

namespace gabion::micro {

int NeighbourGrid::assignClasses(Particles& p) {
  const std::size_t n = p.size();
  std::vector<double> radii(p.r.begin(), p.r.end());
  std::sort(radii.begin(), radii.end());
  radii.erase(std::unique(radii.begin(), radii.end()), radii.end());
  // Class c holds radii in [lo_c, kClassRatio lo_c]; lo_c is the smallest
  // radius above the previous class.
  std::vector<double> class_lo;
  class_rmax_.clear();
  for (const double r : radii) {
    if (class_lo.empty() || r > kClassRatio * class_lo.back()) {
      class_lo.push_back(r);
      class_rmax_.push_back(r);
    }
    class_rmax_.back() = r;
  }
  double sum = 0.0;
  std::size_t finest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c =
        static_cast<std::size_t>(std::upper_bound(class_lo.begin(), class_lo.end(), p.r[i]) - class_lo.begin()) - 1;
    p.size_class[i] = static_cast<std::uint8_t>(c);
    if (c == 0) sum += p.r[i], ++finest;
  }
  finest_mean_r_ = finest > 0 ? sum / static_cast<double>(finest) : 0.0;
  grids_.resize(class_rmax_.size());
  return classCount();
}

void NeighbourGrid::Grid::coords(double x, double y, double z, std::size_t c[3]) const {
  const double pos[3] = {x, y, z};
  for (int a = 0; a < 3; ++a) {
    const double s = (pos[a] - lo[a]) * inv_h;
    // (clamped: a particle of a smaller class lies inside this grid's box;
    // the clamp keeps a rounding at the far face inside too)
    c[a] = s <= 0.0 ? 0 : std::min(ncells[a] - 1, static_cast<std::size_t>(s));
  }
}

std::uint32_t NeighbourGrid::Grid::cellOf(double x, double y, double z) const {
  std::size_t c[3];
  coords(x, y, z, c);
  return static_cast<std::uint32_t>(base + ((c[slow] + 1) * pm + (c[mid] + 1)) * pf + (c[fast] + 1));
}

std::vector<std::uint32_t> NeighbourGrid::sortOrder(const Particles& p, double skin, std::size_t nblocks,
                                                    const ForBlocks& for_blocks) {
  const std::size_t n = p.size(), nclass = grids_.size();
  const auto blockBegin = [&](std::size_t b) { return n * b / nblocks; };
  // Bounding box and count of each class, per block of particles, then joined.
  struct Box {
    double lo[3], hi[3];
    std::size_t count;
  };
  const double inf = std::numeric_limits<double>::infinity();
  const Box empty{{inf, inf, inf}, {-inf, -inf, -inf}, 0};
  std::vector<Box> boxes(nblocks * nclass, empty);
  for_blocks(nblocks, [&](std::size_t b) {
    Box* const mine = boxes.data() + b * nclass;
    const double* __restrict X = p.x.data(), * __restrict Y = p.y.data(), * __restrict Z = p.z.data();
    const std::uint8_t* __restrict C = p.size_class.data();
    // A run of one class at a time into locals (the particles are in class
    // order since the last sort): kept in registers, where the array's
    // entries, which may alias the coordinates, went to memory at every
    // particle.
    for (std::size_t i = blockBegin(b), end = blockBegin(b + 1); i < end;) {
      const std::uint8_t c = C[i];
      double lx = inf, ly = inf, lz = inf, hx = -inf, hy = -inf, hz = -inf;
      const std::size_t first = i;
      for (; i < end && C[i] == c; ++i) {
        lx = std::min(lx, X[i]), ly = std::min(ly, Y[i]), lz = std::min(lz, Z[i]);
        hx = std::max(hx, X[i]), hy = std::max(hy, Y[i]), hz = std::max(hz, Z[i]);
      }
      Box& box = mine[c];
      box.lo[0] = std::min(box.lo[0], lx), box.lo[1] = std::min(box.lo[1], ly), box.lo[2] = std::min(box.lo[2], lz);
      box.hi[0] = std::max(box.hi[0], hx), box.hi[1] = std::max(box.hi[1], hy), box.hi[2] = std::max(box.hi[2], hz);
      box.count += i - first;
    }
  });
  // Grid c covers classes 0 .. c (they all search it).
  Box cover = empty;
  std::size_t cells = 0;
  for (std::size_t c = 0; c < nclass; ++c) {
    for (std::size_t b = 0; b < nblocks; ++b) {
      const Box& box = boxes[b * nclass + c];
      for (int a = 0; a < 3; ++a)
        cover.lo[a] = std::min(cover.lo[a], box.lo[a]), cover.hi[a] = std::max(cover.hi[a], box.hi[a]);
      cover.count += box.count;
    }
    Grid& g = grids_[c];
    double h = 2.0 * class_rmax_[c] + skin;
    if (cover.count == 0) {  // no particle so far: a one-cell grid
      for (int a = 0; a < 3; ++a) g.lo[a] = 0.0, g.ncells[a] = 1;
    } else {
      for (;;) {  // at most a few cells per particle (scattered clouds)
        std::size_t total = 1;
        for (int a = 0; a < 3; ++a) {
          g.lo[a] = cover.lo[a];
          g.ncells[a] = static_cast<std::size_t>((cover.hi[a] - cover.lo[a]) / h) + 1;
          total *= g.ncells[a];
        }
        if (total <= 4 * cover.count + 64) break;
        h *= 1.26;
      }
    }
    g.inv_h = 1.0 / h;
    // The axis with the most cells varies slowest, so that row partitions
    // (contiguous runs of cells) cut the grid across its smallest
    // cross-section and share the fewest particles.
    g.slow = static_cast<int>(std::max_element(g.ncells, g.ncells + 3) - g.ncells);
    g.fast = g.slow == 0 ? 1 : 0;
    g.mid = 3 - g.slow - g.fast;
    g.pf = g.ncells[g.fast] + 2;
    g.pm = g.ncells[g.mid] + 2;
    g.count = g.pf * g.pm * (g.ncells[g.slow] + 2);
    g.base = cells;
    cells += g.count;
  }
  std::vector<std::uint32_t> cell(n);
  for_blocks(nblocks, [&](std::size_t b) {
    for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i)
      cell[i] = grids_[p.size_class[i]].cellOf(p.x[i], p.y[i], p.z[i]);
  });
  // Counting sort by global cell (classes in order, then cells): cell c's
  // count at c + 2, so that after the prefix sum c + 1 holds its start; the
  // placement advances that to its end, the start of c + 1 (no copy of the
  // starts to fill from).
  cell_start_.assign(cells + 2, 0);
  std::uint32_t* const start = cell_start_.data();
  for (std::size_t i = 0; i < n; ++i) ++start[cell[i] + 2];
  for (std::size_t c = 2; c < cells + 2; ++c) start[c] += start[c - 1];
  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[start[cell[i] + 1]++] = static_cast<std::uint32_t>(i);
  cell_.resize(n);
  for (std::size_t k = 0; k < n; ++k) cell_[k] = cell[order[k]];
  return order;
}

// The pairs of a particle with the particles of the larger classes, found
// from the larger particle j: the cells of each smaller class's grid within
// its reach, r_j + skin + r_max(class), a window of 2k + 1 cells a side.
// From the small particle's side (the 27 cells of the large class's grid,
// each of edge 2 r_max + skin of that class) a 4 mm sphere would test a few
// dozen far spheres of 18 and 70 mm for each one near it. The test is the
// row scan's, with i the smaller particle; the pairs are then put in row
// order (a stable counting sort by i of pairs met in increasing j), so the
// list is the same, entry for entry.
void NeighbourGrid::crossPairs(const Particles& p, double skin, bool groups, std::size_t nblocks,
                               const ForBlocks& for_blocks) {
  const std::size_t n = p.size(), nclass = grids_.size();
  cross_begin_.assign(n + 1, 0);
  cross_j_.clear();
  if (nclass < 2) return;
  const auto blockBegin = [&](std::size_t b) { return n * b / nblocks; };
  cross_blocks_.resize(nblocks);
  for_blocks(nblocks, [&](std::size_t blk) {
    std::vector<std::uint32_t>& found = cross_blocks_[blk];  // (i, j) pairs, flat
    found.clear();
    const double *__restrict X = p.x.data(), *__restrict Y = p.y.data(), *__restrict Z = p.z.data(),
                 *__restrict R = p.r.data(), *__restrict IMB = p.inv_body_mass.data();
    const std::int32_t* __restrict BODY = p.body.data();
    const std::uint8_t* __restrict GRP = p.group.data();
    const std::uint32_t* __restrict START = cell_start_.data();
    for (std::size_t j = blockBegin(blk); j < blockBegin(blk + 1); ++j) {
      const std::size_t d = p.size_class[j];
      for (std::size_t c = 0; c < d; ++c) {
        const Grid& g = grids_[c];
        std::size_t at[3];
        g.coords(X[j], Y[j], Z[j], at);
        const auto k = static_cast<std::size_t>((R[j] + skin + class_rmax_[c]) * g.inv_h) + 1;
        const auto lo = [&](int a) { return at[a] > k ? at[a] - k : 0; };
        const auto hi = [&](int a) { return std::min(g.ncells[a] - 1, at[a] + k); };
        const std::size_t f0 = lo(g.fast), f1 = hi(g.fast);
        for (std::size_t s = lo(g.slow); s <= hi(g.slow); ++s)
          for (std::size_t m = lo(g.mid); m <= hi(g.mid); ++m) {
            const std::size_t row = g.base + ((s + 1) * g.pm + (m + 1)) * g.pf + 1;
            for (std::uint32_t i = START[row + f0]; i < START[row + f1 + 1]; ++i) {
              const double xi = X[i], yi = Y[i], zi = Z[i], ri = R[i] + skin;
              const std::int32_t bi = BODY[i];
              const double ex = X[j] - xi, ey = Y[j] - yi, ez = Z[j] - zi, reach = ri + R[j];
              const bool near = ex * ex + ey * ey + ez * ez < reach * reach;
              const bool allowed = (bi < 0 || BODY[j] != bi) && (IMB[i] > 0.0 || IMB[j] > 0.0) &&
                                   (!groups || ((p.group_mask[GRP[i]] >> GRP[j]) & 1u));
              if (near && allowed) found.push_back(i), found.push_back(static_cast<std::uint32_t>(j));
            }
          }
      }
    }
  });
  // Rows in order: count per i, then place in block order (increasing j).
  for (const auto& found : cross_blocks_)
    for (std::size_t q = 0; q < found.size(); q += 2) ++cross_begin_[found[q] + 1];
  for (std::size_t i = 0; i < n; ++i) cross_begin_[i + 1] += cross_begin_[i];
  cross_j_.resize(cross_begin_[n]);
  std::vector<std::uint32_t> fill(cross_begin_.begin(), cross_begin_.end() - 1);
  for (const auto& found : cross_blocks_)
    for (std::size_t q = 0; q < found.size(); q += 2) cross_j_[fill[found[q]]++] = found[q + 1];
}

void NeighbourGrid::buildList(const Particles& p, double skin, const ExcludedPairs& excluded, std::size_t nblocks,
                              const ForBlocks& for_blocks, NeighbourList& out) {
  const std::size_t n = p.size();
  const auto blockBegin = [&](std::size_t b) { return n * b / nblocks; };
  const bool groups =
      std::any_of(std::begin(p.group_mask), std::end(p.group_mask), [](std::uint32_t m) { return m != ~0u; });
  crossPairs(p, skin, groups, nblocks, for_blocks);
  out.row_begin.assign(n + 1, 0);
  list_blocks_.resize(nblocks);
  for_blocks(nblocks, [&](std::size_t blk) {
    // With one block the list itself is written (no second copy in memory).
    std::vector<std::uint32_t>& list = nblocks == 1 ? out.nbr : list_blocks_[blk];
    std::size_t len = 0;
    const double *__restrict X = p.x.data(), *__restrict Y = p.y.data(), *__restrict Z = p.z.data(),
                 *__restrict R = p.r.data(), *__restrict IMB = p.inv_body_mass.data();
    const std::int32_t* __restrict BODY = p.body.data();
    const std::uint8_t* __restrict GRP = p.group.data();
    const std::uint32_t* __restrict START = cell_start_.data();
    // Appends the particles of [jb, je) within reach of i that may touch it,
    // branch-free (the test decides whether the write is kept).
    const auto scan = [&](std::size_t i, std::uint32_t jb, std::uint32_t je) {
      if (jb >= je) return;
      // (room for eight more: the vector scan stores eight entries whole)
      if (list.size() < len + (je - jb) + 8)  // grows by a quarter (the list is the largest array)
        list.resize(std::max<std::size_t>(len + (je - jb) + 8, list.size() + list.size() / 4 + 1024));
      const double xi = X[i], yi = Y[i], zi = Z[i], ri = R[i] + skin;
      const std::int32_t bi = BODY[i];
      const bool free_i = IMB[i] > 0.0;
      const std::uint32_t mask_i = p.group_mask[GRP[i]];
      std::uint32_t* __restrict o = list.data() + len;
      std::size_t cnt = 0;
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
      // Eight candidates at a time, the run's tail masked: the kept ones
      // compressed in a register and stored whole (the next group
      // overwrites the rest). A run holds three cells, a handful of
      // candidates: one group each, where the scalar loop's exit, after a
      // varying count, was mispredicted at most runs. The test is the
      // scalar one, operation for operation (the same list).
      const __m512d vxi = _mm512_set1_pd(xi), vyi = _mm512_set1_pd(yi), vzi = _mm512_set1_pd(zi),
                    vri = _mm512_set1_pd(ri), zero = _mm512_setzero_pd();
      const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), vbi = _mm256_set1_epi32(bi),
                    vmask = _mm256_set1_epi32(static_cast<int>(mask_i)), one = _mm256_set1_epi32(1);
      for (std::uint32_t j = jb; j < je; j += 8) {
        const __mmask8 valid = je - j >= 8 ? __mmask8{0xFF} : static_cast<__mmask8>((1u << (je - j)) - 1u);
        const __m512d ex = _mm512_sub_pd(_mm512_maskz_loadu_pd(valid, X + j), vxi);
        const __m512d ey = _mm512_sub_pd(_mm512_maskz_loadu_pd(valid, Y + j), vyi);
        const __m512d ez = _mm512_sub_pd(_mm512_maskz_loadu_pd(valid, Z + j), vzi);
        const __m512d reach = _mm512_add_pd(vri, _mm512_maskz_loadu_pd(valid, R + j));
        const __m512d d2 = _mm512_fmadd_pd(ez, ez, _mm512_fmadd_pd(ey, ey, _mm512_mul_pd(ex, ex)));
        __mmask8 keep = _mm512_mask_cmp_pd_mask(valid, d2, _mm512_mul_pd(reach, reach), _CMP_LT_OQ);
        if (bi >= 0) keep = _mm256_mask_cmpneq_epi32_mask(keep, _mm256_maskz_loadu_epi32(valid, BODY + j), vbi);
        if (!free_i) keep = _mm512_mask_cmp_pd_mask(keep, _mm512_maskz_loadu_pd(valid, IMB + j), zero, _CMP_GT_OQ);
        if (groups) {
          const __m256i gj = _mm256_cvtepu8_epi32(_mm_maskz_loadu_epi8(valid, GRP + j));
          keep = _mm256_mask_test_epi32_mask(keep, _mm256_srlv_epi32(vmask, gj), one);
        }
        const __m256i js = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(j)), lanes);
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(o + cnt), _mm256_maskz_compress_epi32(keep, js));
        cnt += static_cast<std::size_t>(__builtin_popcount(keep));
      }
      len += cnt;
#else
      if (groups) {
        for (std::uint32_t j = jb; j < je; ++j) {
          const double ex = X[j] - xi, ey = Y[j] - yi, ez = Z[j] - zi, reach = ri + R[j];
          const bool near = ex * ex + ey * ey + ez * ez < reach * reach;
          const bool allowed = (bi < 0 || BODY[j] != bi) && (free_i || IMB[j] > 0.0) && ((mask_i >> GRP[j]) & 1u);
          o[cnt] = j;
          cnt += static_cast<std::size_t>(near & allowed);
        }
      } else {  // (no group excludes another: one load less per candidate)
        for (std::uint32_t j = jb; j < je; ++j) {
          const double ex = X[j] - xi, ey = Y[j] - yi, ez = Z[j] - zi, reach = ri + R[j];
          const bool near = ex * ex + ey * ey + ez * ez < reach * reach;
          const bool allowed = (bi < 0 || BODY[j] != bi) && (free_i || IMB[j] > 0.0);
          o[cnt] = j;
          cnt += static_cast<std::size_t>(near & allowed);
        }
      }
      len += cnt;
#endif
    };
    for (std::size_t i = blockBegin(blk); i < blockBegin(blk + 1); ++i) {
      out.row_begin[i] = static_cast<std::uint32_t>(len);  // local offset, made global below
      const std::size_t c = p.size_class[i];
      const Grid& own = grids_[c];
      // Own class: a partner j > i lies in a cell at or after i's: the rest
      // of its own row along the fast axis and the rows (mid+1) and
      // (slow+1, mid-1 .. mid+1); each row of three cells is one run.
      const std::size_t cell = cell_[i];
      const std::size_t row_offset[5] = {0, own.pf, own.pf * own.pm - own.pf, own.pf * own.pm,
                                         own.pf * own.pm + own.pf};
      for (std::size_t r = 0; r < 5; ++r) {
        const std::size_t centre = cell + row_offset[r];
        scan(i, r == 0 ? static_cast<std::uint32_t>(i + 1) : START[centre - 1], START[centre + 2]);
      }
      // Larger classes: the partners found from their side (crossPairs),
      // after the own class's: every larger class's particles come later
      // in the order, in increasing index within the row.
      const std::uint32_t cb = cross_begin_[i], ce = cross_begin_[i + 1];
      if (cb < ce) {
        if (list.size() < len + (ce - cb))
          list.resize(std::max<std::size_t>(len + (ce - cb), list.size() + list.size() / 4 + 1024));
        std::copy(cross_j_.begin() + cb, cross_j_.begin() + ce, list.begin() + static_cast<long>(len));
        len += ce - cb;
      }
      // Linked pairs never touch: drop them from the row (rare rows only).
      if (!excluded.empty()) {
        const std::uint32_t a = p.id[i];
        const auto eb = excluded.ids.begin() + excluded.begin[a], ee = excluded.ids.begin() + excluded.begin[a + 1];
        if (eb != ee) {
          std::uint32_t* row = list.data() + out.row_begin[i];
          const std::size_t count = len - out.row_begin[i];
          std::size_t kept = 0;
          for (std::size_t q = 0; q < count; ++q)
            if (!std::binary_search(eb, ee, p.id[row[q]])) row[kept++] = row[q];
          len = out.row_begin[i] + kept;
        }
      }
    }
    list.resize(len);
  });
  if (nblocks > 1) {
    std::vector<std::size_t> base(nblocks + 1, 0);
    for (std::size_t b = 0; b < nblocks; ++b) base[b + 1] = base[b] + list_blocks_[b].size();
    out.nbr.resize(base[nblocks]);
    out.owner.resize(base[nblocks]);
    out.row_begin[n] = static_cast<std::uint32_t>(out.nbr.size());
    for_blocks(nblocks, [&](std::size_t b) {
      const auto shift = static_cast<std::uint32_t>(base[b]);
      for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i) out.row_begin[i] += shift;
      std::copy(list_blocks_[b].begin(), list_blocks_[b].end(), out.nbr.begin() + static_cast<long>(base[b]));
    });
    // (after every block's shift: a block's last row ends where the next begins)
    for_blocks(nblocks, [&](std::size_t b) { out.indexOwners(blockBegin(b), blockBegin(b + 1)); });
    return;
  }
  out.row_begin[n] = static_cast<std::uint32_t>(out.nbr.size());
  out.indexOwners();
}

}  // namespace gabion::micro
