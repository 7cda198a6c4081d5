// How the struck cell of a resolved wall, or of a hybrid, gives way along x
// (docs/resolved.md, What the 4-cell hybrid misses at rest):
//   bench_struck_cell RUN_DIR ...
// RUN_DIR is a micro.structure run (a macro.resolved run's resolved/ or
// hybrid_<k>/): its summary.json, result.h5 and settle/result.h5. For each
// snapshot of the impact it prints, along x and from the impact's start:
//   centre  the struck cell's blocks' mean move;
//   back    its back face's: the mean move of its netting's nodes within
//           30 mm of its rearmost node at the impact's start;
//   behind  what stands behind it: the resolved cell behind's front face
//           (its nodes within 30 mm of its foremost), or, in a hybrid, the
//           interface plate on the struck cell's back (the macro node
//           behind it; cut in tiles, their mean), or the back support (0);
//   joint   back less behind: how far the meeting of the two cells closed;
// then the same at the struck cell's largest move, each one's largest, how
// much the struck cell's netting (and the resolved cell behind's) grew
// along x, y and z from the impact's start to its end (its two faces'
// nodes apart along each axis), and how far the resolved cells beside the
// struck cell and beside the cell behind it moved aside, along y away from
// them (their blocks' mean; nan where those cells are macro nodes).
// The cells are told apart by their bodies' laid-out positions (the
// settling's first snapshot), the boulder by its radius.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/output.hpp"

namespace {

namespace fs = std::filesystem;

constexpr double kFaceDepth_m = 0.03;  // a face's nodes: within this of the cell's extreme along x

struct Motion {
  std::vector<double> time, centre, back, behind;
  std::string behind_is;
  double struck_growth[3] = {0.0, 0.0, 0.0}, behind_growth[3] = {NAN, NAN, NAN};  // (x, y, z; NAN: not resolved)
  /// The resolved cells beside the struck cell and beside the cell behind
  /// it (along y): their blocks' mean move along y away from the struck
  /// cell's column over the impact; NAN where no resolved cell is.
  double aside[2][2] = {{NAN, NAN}, {NAN, NAN}};  // [struck, behind][-y, +y]
};

/// The mean x move, from the first snapshot, of `bodies` in each snapshot.
std::vector<double> meanMove(const std::vector<double>& pos, std::size_t n_bodies, std::size_t snapshots,
                             const std::vector<std::size_t>& bodies) {
  std::vector<double> out(snapshots, 0.0);
  if (bodies.empty()) return out;
  for (std::size_t s = 0; s < snapshots; ++s) {
    double sum = 0.0;
    for (const std::size_t b : bodies) sum += pos[(s * n_bodies + b) * 3] - pos[b * 3];
    out[s] = sum / static_cast<double>(bodies.size());
  }
  return out;
}

/// The nodes of `nodes` within kFaceDepth_m of their largest (`far`) or
/// smallest coordinate along `axis` in the first snapshot.
std::vector<std::size_t> face(const std::vector<double>& pos, const std::vector<std::size_t>& nodes, bool far,
                              int axis = 0) {
  std::vector<std::size_t> out;
  if (nodes.empty()) return out;
  double lo = INFINITY, hi = -INFINITY;
  for (const std::size_t b : nodes) lo = std::min(lo, pos[b * 3 + axis]), hi = std::max(hi, pos[b * 3 + axis]);
  for (const std::size_t b : nodes)
    if (far ? pos[b * 3 + axis] > hi - kFaceDepth_m : pos[b * 3 + axis] < lo + kFaceDepth_m) out.push_back(b);
  return out;
}

/// How much a cell's netting grew along `axis` from the impact's start to
/// its end: its two faces' nodes' mean positions apart.
double growth(const std::vector<double>& pos, std::size_t n_bodies, std::size_t snapshots,
              const std::vector<std::size_t>& nodes, int axis) {
  const auto mean = [&](const std::vector<std::size_t>& f, std::size_t s) {
    double sum = 0.0;
    for (const std::size_t b : f) sum += pos[(s * n_bodies + b) * 3 + axis];
    return sum / static_cast<double>(f.size());
  };
  const std::vector<std::size_t> lo = face(pos, nodes, false, axis), hi = face(pos, nodes, true, axis);
  return (mean(hi, snapshots - 1) - mean(lo, snapshots - 1)) - (mean(hi, 0) - mean(lo, 0));
}

Motion struckCell(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  if (!in) throw std::runtime_error((dir / "summary.json").string() + ": cannot open");
  const nlohmann::json s = nlohmann::json::parse(in);
  const auto cells = s.at("cells").get<std::vector<int>>();
  const auto pitch = s.at("cell_pitch_m").get<std::vector<double>>();
  const auto aim = s.at("aim_point_m").get<std::vector<double>>();
  const gabion::bridge::H5Reader run(dir / "result.h5");
  const std::vector<double> pos = run.read("/bodies/position_m"), radius = run.read("/bodies/radius_m");
  const std::size_t n = radius.size(), snapshots = pos.size() / (3 * n);
  const std::size_t boulder = static_cast<std::size_t>(std::max_element(radius.begin(), radius.end()) - radius.begin());
  // Laid out: the settling's first snapshot (no boulder), else the impact's.
  std::vector<double> laid(3 * n);
  if (fs::exists(dir / "settle" / "result.h5")) {
    const std::vector<double> p0 = gabion::bridge::H5Reader(dir / "settle" / "result.h5").read("/bodies/position_m");
    if (p0.size() < 3 * (n - 1)) throw std::runtime_error((dir / "settle").string() + ": not this run's settling");
    for (std::size_t b = 0; b < n; ++b)
      for (int a = 0; a < 3; ++a) laid[3 * b + a] = b == boulder ? 0.0 : p0[3 * (b < boulder ? b : b - 1) + a];
  } else {
    std::copy(pos.begin(), pos.begin() + static_cast<std::ptrdiff_t>(3 * n), laid.begin());
  }
  const auto index = [&](std::size_t b) {
    int idx[3];
    for (int a = 0; a < 3; ++a)
      idx[a] = std::clamp(static_cast<int>(std::floor(laid[3 * b + a] / pitch[a])), 0, cells[a] - 1);
    return idx[0] + cells[0] * (idx[1] + cells[1] * idx[2]);
  };
  const int j = std::clamp(static_cast<int>(aim[0] / pitch[1]), 0, cells[1] - 1);
  const int k = std::clamp(static_cast<int>(aim[1] / pitch[2]), 0, cells[2] - 1);
  const int struck = cells[0] * (j + cells[1] * k), behind = struck + 1;
  // (bodies before the boulder are the nettings' nodes, after it the blocks)
  std::vector<std::size_t> struck_blocks, struck_nodes, behind_nodes, beside_blocks[2][2];
  for (std::size_t b = 0; b < n; ++b) {
    if (b == boulder) continue;
    const int c = index(b);
    if (c == struck) (b < boulder ? struck_nodes : struck_blocks).push_back(b);
    if (c == behind && b < boulder && cells[0] > 1) behind_nodes.push_back(b);
    for (int i = 0; i < 2 && i < cells[0]; ++i)
      for (int side = 0; side < 2; ++side) {
        const int jj = j + (side == 0 ? -1 : 1);
        if (b > boulder && jj >= 0 && jj < cells[1] && c == i + cells[0] * (jj + cells[1] * k))
          beside_blocks[i][side].push_back(b);
      }
  }
  if (struck_blocks.empty()) throw std::runtime_error(dir.string() + ": no blocks in the struck cell");
  Motion m;
  m.time = run.read("/bodies/time_s");
  m.centre = meanMove(pos, n, snapshots, struck_blocks);
  m.back = meanMove(pos, n, snapshots, face(pos, struck_nodes, true));
  // (the plate on its back: one, or the hybrid's joint_tiles x joint_tiles
  // tiles, their mean)
  const std::string plate = "/series/walls/interface_" + std::to_string(struck) + "_x_plus";
  const int tiles = s.contains("hybrid") ? s["hybrid"].value("joint_tiles", 1) : 1;
  std::vector<std::string> plates;
  for (int u = 0; u < tiles; ++u)
    for (int v = 0; v < tiles; ++v) {
      const std::string name = tiles == 1 ? plate : plate + "_tile_" + std::to_string(u) + "_" + std::to_string(v);
      if (run.has(name + "/displacement_m")) plates.push_back(name + "/displacement_m");
    }
  for (int a = 0; a < 3; ++a) m.struck_growth[a] = growth(pos, n, snapshots, struck_nodes, a);
  for (int i = 0; i < 2; ++i)
    for (int side = 0; side < 2; ++side) {
      const std::vector<std::size_t>& blocks = beside_blocks[i][side];
      if (blocks.empty()) continue;
      double sum = 0.0;
      for (const std::size_t b : blocks) sum += pos[((snapshots - 1) * n + b) * 3 + 1] - pos[b * 3 + 1];
      m.aside[i][side] = (side == 0 ? -1.0 : 1.0) * sum / static_cast<double>(blocks.size());
    }
  if (!behind_nodes.empty()) {
    for (int a = 0; a < 3; ++a) m.behind_growth[a] = growth(pos, n, snapshots, behind_nodes, a);
    m.behind = meanMove(pos, n, snapshots, face(pos, behind_nodes, false));
    m.behind_is = "the resolved cell behind's front face";
  } else if (!plates.empty()) {
    const std::vector<double> t = run.read("/series/time_s");
    m.behind.assign(snapshots, 0.0);
    for (const std::string& name : plates) {
      const std::vector<double> d = run.read(name);
      for (std::size_t snap = 0; snap < snapshots; ++snap) {  // (the series sample nearest each snapshot)
        const double at = m.time[snap];
        const std::size_t q = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), at) - t.begin());
        const std::size_t r = q > 0 && (q == t.size() || at - t[q - 1] < t[q] - at) ? q - 1 : q;
        m.behind[snap] += (d[3 * r] - d[0]) / static_cast<double>(plates.size());
      }
    }
    m.behind_is = plates.size() == 1 ? "the interface plate on its back (the macro node behind)"
                                     : "the interface plate on its back (the macro node behind), its " +
                                           std::to_string(plates.size()) + " tiles' mean";
  } else {
    m.behind.assign(snapshots, 0.0);
    m.behind_is = "the back support";
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_struck_cell RUN_DIR ...\n");
    return 2;
  }
  try {
    for (int a = 1; a < argc; ++a) {
      const Motion m = struckCell(argv[a]);
      std::printf("%s: the struck cell along x (mm); behind it, %s\n", argv[a], m.behind_is.c_str());
      std::printf("  t ms  centre    back  behind   joint\n");
      std::size_t at = 0;
      for (std::size_t s = 0; s < m.time.size(); ++s) {
        if (m.centre[s] > m.centre[at]) at = s;
        if (s % 2 == 0 || s + 1 == m.time.size())
          std::printf("%6.0f %7.1f %7.1f %7.1f %7.1f\n", 1e3 * (m.time[s] - m.time[0]), 1e3 * m.centre[s],
                      1e3 * m.back[s], 1e3 * m.behind[s], 1e3 * (m.back[s] - m.behind[s]));
      }
      const auto largest = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
      std::printf("  at the centre's largest move (%.0f ms): centre %.1f, back %.1f, behind %.1f, joint %.1f\n",
                  1e3 * (m.time[at] - m.time[0]), 1e3 * m.centre[at], 1e3 * m.back[at], 1e3 * m.behind[at],
                  1e3 * (m.back[at] - m.behind[at]));
      std::printf("  largest: back %.1f, behind %.1f\n", 1e3 * largest(m.back), 1e3 * largest(m.behind));
      std::printf("  growth over the impact (x, y, z), the struck cell: %.1f, %.1f, %.1f", 1e3 * m.struck_growth[0],
                  1e3 * m.struck_growth[1], 1e3 * m.struck_growth[2]);
      if (!std::isnan(m.behind_growth[0]))
        std::printf("; the cell behind: %.1f, %.1f, %.1f", 1e3 * m.behind_growth[0], 1e3 * m.behind_growth[1],
                    1e3 * m.behind_growth[2]);
      std::printf("\n");
      std::printf(
          "  the resolved cells beside it (-y, +y), moved aside: %.1f, %.1f; beside the cell behind: %.1f, %.1f\n",
          1e3 * m.aside[0][0], 1e3 * m.aside[0][1], 1e3 * m.aside[1][0], 1e3 * m.aside[1][1]);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_struck_cell: %s\n", e.what());
    return 1;
  }
  return 0;
}
