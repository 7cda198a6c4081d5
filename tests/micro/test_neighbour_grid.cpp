// The neighbour list against its definition: row i holds every j > i within
// reach (r_i + r_j + skin) that may touch i and is not excluded, in
// increasing order. A polydisperse cloud of four size classes (0.3, 1, 3 and
// 25 mm), with blocks, fixed particles, a group that does not touch itself
// and linked pairs, built with one block of rows and with three: the list is
// the same, entry for entry, as the brute-force one (O(N^2)). Pairs of two
// classes are found from the larger particle (micro/neighbour_grid.cpp),
// pairs of one class from the smaller index: both must meet the definition.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "micro/neighbour_grid.hpp"
#include "micro/particles.hpp"

namespace {

using gabion::micro::ExcludedPairs;
using gabion::micro::NeighbourGrid;
using gabion::micro::NeighbourList;
using gabion::micro::Particles;

Particles cloud(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::pair<int, double> kinds[] = {{80, 0.0003}, {2400, 0.001}, {400, 0.003}, {20, 0.025}};
  Particles p;
  std::size_t n = 0;
  for (const auto& [count, r] : kinds) n += static_cast<std::size_t>(count);
  p.resize(n);
  std::size_t k = 0;
  for (const auto& [count, r] : kinds)
    for (int c = 0; c < count; ++c, ++k) {
      // (a 6 cm box: the 1 mm class at a solid fraction of about 0.05, the
      // 25 mm spheres overlapping the others: every search path has pairs)
      p.x[k] = 0.06 * u(rng), p.y[k] = 0.06 * u(rng), p.z[k] = 0.06 * u(rng);
      p.r[k] = r * (1.0 + 0.3 * u(rng));
      p.inv_body_mass[k] = u(rng) < 0.05 ? 0.0 : 1.0;                               // some fixed
      p.body[k] = r == 0.001 && k % 7 < 3 ? static_cast<std::int32_t>(k / 7) : -1;  // blocks of three
      p.group[k] = static_cast<std::uint8_t>(k % 5 == 0 ? 1 : 0);
    }
  p.group_mask[1] &= ~(1u << 1);  // group 1 does not touch group 1
  return p;
}

// Linked pairs by stable id: each 1 mm sphere with the next one.
ExcludedPairs links(std::size_t n) {
  std::vector<std::vector<std::uint32_t>> by(n);
  for (std::uint32_t a = 80; a + 1 < 2480; a += 2) by[a].push_back(a + 1), by[a + 1].push_back(a);
  ExcludedPairs e;
  e.begin.assign(n + 1, 0);
  for (std::size_t a = 0; a < n; ++a) {
    std::sort(by[a].begin(), by[a].end());
    e.begin[a + 1] = e.begin[a] + static_cast<std::uint32_t>(by[a].size());
    e.ids.insert(e.ids.end(), by[a].begin(), by[a].end());
  }
  return e;
}

void permute(Particles& p, const std::vector<std::uint32_t>& order) {
  p.forEachStateField([&](const char*, auto& v) {
    auto old = v;
    for (std::size_t k = 0; k < order.size(); ++k) v[k] = old[order[k]];
  });
  for (std::size_t k = 0; k < p.size(); ++k) p.slot[p.id[k]] = static_cast<std::uint32_t>(k);
}

TEST(NeighbourGrid, TheListIsItsDefinitionForEverySizeClassAndBlockCount) {
  const double skin = 0.0002;
  for (const std::size_t blocks : {std::size_t{1}, std::size_t{3}}) {
    Particles p = cloud(20261127);
    const ExcludedPairs excluded = links(p.size());
    NeighbourGrid grid;
    ASSERT_EQ(grid.assignClasses(p), 4);
    const gabion::micro::ForBlocks serial = [](std::size_t nb, const std::function<void(std::size_t)>& fn) {
      for (std::size_t b = 0; b < nb; ++b) fn(b);
    };
    permute(p, grid.sortOrder(p, skin, blocks, serial));
    NeighbourList list;
    grid.buildList(p, skin, excluded, blocks, serial, list);

    const auto linked = [&](std::size_t i, std::size_t j) {
      const auto b = excluded.ids.begin() + excluded.begin[p.id[i]],
                 e = excluded.ids.begin() + excluded.begin[p.id[i] + 1];
      return std::binary_search(b, e, p.id[j]);
    };
    std::size_t pairs = 0, cross = 0, rows_checked = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      std::vector<std::uint32_t> want;
      for (std::size_t j = i + 1; j < p.size(); ++j) {
        const double ex = p.x[j] - p.x[i], ey = p.y[j] - p.y[i], ez = p.z[j] - p.z[i];
        const double reach = p.r[i] + skin + p.r[j];
        if (ex * ex + ey * ey + ez * ez < reach * reach && p.mayTouch(i, j) && !linked(i, j))
          want.push_back(static_cast<std::uint32_t>(j));
      }
      const std::vector<std::uint32_t> got(list.nbr.begin() + list.row_begin[i],
                                           list.nbr.begin() + list.row_begin[i + 1]);
      ASSERT_EQ(got, want) << "row " << i << " (class " << int(p.size_class[i]) << "), " << blocks << " blocks";
      pairs += want.size();
      for (const auto j : want) cross += p.size_class[j] != p.size_class[i];
      ++rows_checked;
    }
    EXPECT_EQ(rows_checked, p.size());
    // (the cloud exercises both paths)
    EXPECT_GT(cross, 1000u) << pairs;
    EXPECT_GT(pairs - cross, 1000u);
  }
}

}  // namespace
