#pragma once
/// \file
/// Neighbour search of the fine DEM for any mix of sizes: a hierarchy of
/// cell grids, one per size class (radii within a factor kClassRatio of the
/// class's smallest), each with cells of 2 r_max(class) + skin. A particle
/// finds the partners of its own class through the half stencil of its own
/// grid (5 runs of cells); a pair of two classes is found from the larger
/// particle, through the cells of the smaller class's grid within its reach,
/// and filed in the smaller particle's row, so each pair is found once, in
/// O(N) for size ratios of 1:200 and more (docs/micro.md, Neighbour search).
/// A boulder among netting nodes is a class of its own; no pair goes to a
/// serial path.
///
/// Particles are sorted by class, then by cell: partners are close in
/// memory, and a row's partners come out in increasing index order.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

#include "micro/particles.hpp"

namespace gabion::micro {

/// Runs fn(b) for the blocks b = 0 .. blocks-1 on the engine's workers; each
/// block writes only what it owns (Engine::forBlocks).
using ForBlocks = std::function<void(std::size_t blocks, const std::function<void(std::size_t)>& fn)>;

/// The half neighbour list: CSR by row i, partners j > i in increasing order;
/// `owner[k]` is the row of entry k (so that a scan of the list can run over
/// its entries, not row by row).
struct NeighbourList {
  std::vector<std::uint32_t> row_begin, nbr, owner;
  /// Fills `owner` (sized to the list) for the rows [first, end): workers
  /// may fill ranges of rows at once.
  void indexOwners(std::size_t first, std::size_t end) {
    for (std::size_t i = first; i < end; ++i)
      std::fill(owner.begin() + row_begin[i], owner.begin() + row_begin[i + 1], static_cast<std::uint32_t>(i));
  }
  /// Sizes `owner` to the list and fills it for every row.
  void indexOwners() {
    owner.resize(nbr.size());
    if (!row_begin.empty()) indexOwners(0, row_begin.size() - 1);
  }
};

/// Pairs that never touch although they may be near (particles joined by a
/// link), by stable id: partners of id a are ids[begin[a] .. begin[a + 1]),
/// sorted. Symmetric.
struct ExcludedPairs {
  std::vector<std::uint32_t> begin, ids;
  bool empty() const { return ids.empty(); }
};

class NeighbourGrid {
 public:
  /// Radii within this factor of a class's smallest radius share its grid.
  static constexpr double kClassRatio = 2.0;

  /// Sets each particle's size class (by radius; classes do not change
  /// during a run) and returns the number of classes.
  int assignClasses(Particles& p);
  int classCount() const { return static_cast<int>(class_rmax_.size()); }
  /// Mean radius of the smallest class (m): the skin is a fraction of it.
  double finestMeanRadius() const { return finest_mean_r_; }

  /// Lays the grids over the particles' current positions and returns the
  /// order that sorts them by class, then cell (order[k] = old index of the
  /// particle that goes to k). `skin` (m) widens the cells.
  std::vector<std::uint32_t> sortOrder(const Particles& p, double skin, std::size_t nblocks,
                                       const ForBlocks& for_blocks);

  /// Builds the half list of the particles, which must be in the order of
  /// the last sortOrder(): pairs within reach (r_i + r_j + skin) that may
  /// touch (Particles::mayTouch) and are not excluded. Row blocks are built
  /// by the workers and joined in block order (same list for any thread count).
  void buildList(const Particles& p, double skin, const ExcludedPairs& excluded, std::size_t nblocks,
                 const ForBlocks& for_blocks, NeighbourList& out);

 private:
  /// One class's grid: cells of edge h over the box of the particles of this
  /// class and all smaller ones (those search it), padded by one empty cell
  /// all round so that every cell of the stencil exists. Cells are numbered
  /// with the axis of most cells varying slowest (docs/micro.md), from `base`
  /// in the global numbering of all grids.
  struct Grid {
    double lo[3] = {0, 0, 0};
    double inv_h = 0.0;
    std::size_t ncells[3] = {1, 1, 1};
    int slow = 2, mid = 1, fast = 0;
    std::size_t pf = 3, pm = 3;  // padded cells along the fast and mid axes
    std::size_t base = 0;        // first global cell
    std::size_t count = 0;       // padded cells in all
    std::uint32_t cellOf(double x, double y, double z) const;
    /// The cell coordinates along x, y, z (unpadded, clamped to the grid).
    void coords(double x, double y, double z, std::size_t c[3]) const;
  };
  void crossPairs(const Particles& p, double skin, bool groups, std::size_t nblocks, const ForBlocks& for_blocks);
  std::vector<double> class_rmax_;
  double finest_mean_r_ = 0.0;
  std::vector<Grid> grids_;
  std::vector<std::uint32_t> cell_start_;  // global cell -> first particle (sorted order); size cells + 2
  std::vector<std::uint32_t> cell_;        // particle -> global cell, in sorted order
  std::vector<std::vector<std::uint32_t>> list_blocks_;
  // The pairs with larger classes, by row i: partners cross_j_[cross_begin_[i] ..
  // cross_begin_[i + 1]), increasing (crossPairs); per block while found.
  std::vector<std::uint32_t> cross_begin_, cross_j_;
  std::vector<std::vector<std::uint32_t>> cross_blocks_;
};

}  // namespace gabion::micro
