#include "micro/packing.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "micro/rigid_body.hpp"

namespace gabion::micro {

namespace {

// A hash grid of cell size >= the largest diameter + gap: a new sphere only
// has to be tested against the 27 surrounding cells.
struct Grid {
  double h;
  Eigen::Vector3d origin;
  std::unordered_map<long long, std::vector<int>> cells;
  long long key(const Eigen::Vector3i& c) const {
    return (static_cast<long long>(c.x()) * 73856093LL) ^ (static_cast<long long>(c.y()) * 19349663LL) ^
           (static_cast<long long>(c.z()) * 83492791LL);
  }
  Eigen::Vector3i cellOf(const Eigen::Vector3d& p) const { return ((p - origin) / h).array().floor().cast<int>(); }
};

}  // namespace

Packing randomPacking(const PackingSpec& spec) {
  const Eigen::Vector3d size = spec.box_max_m - spec.box_min_m;
  if (!(size.array() > 0).all() || !size.allFinite())
    throw std::invalid_argument("packing box must have positive size");
  if (!(spec.mean_radius_m > 0)) throw std::invalid_argument("mean radius must be > 0");
  if (!(spec.radius_std_rel >= 0 && spec.radius_std_rel < 0.5))
    throw std::invalid_argument("radius_std_rel must be in [0, 0.5)");
  if (!(spec.solid_fraction > 0 && spec.solid_fraction <= 0.35))
    throw std::invalid_argument("solid fraction for random sequential addition must be in (0, 0.35]");
  if (!(spec.min_gap_m >= 0)) throw std::invalid_argument("min gap must be >= 0");
  const double r_max = spec.mean_radius_m * (1.0 + 2.0 * spec.radius_std_rel);
  if (2.0 * (r_max + spec.min_gap_m) >= size.minCoeff()) throw std::invalid_argument("spheres do not fit in the box");

  std::mt19937_64 rng(spec.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double box_volume = size.prod();
  const double target = spec.solid_fraction * box_volume;

  Packing out;
  Grid grid{2.0 * r_max + spec.min_gap_m, spec.box_min_m, {}};
  double solid = 0.0;
  long long attempts = 0;
  double radius = 0.0;
  bool need_radius = true;
  while (solid < target) {
    if (need_radius) {
      double z = 0.0;
      do z = gauss(rng);
      while (std::abs(z) > 2.0);
      radius = spec.mean_radius_m * (1.0 + spec.radius_std_rel * z);
      need_radius = false;
    }
    if (++attempts > spec.max_attempts) {
      std::ostringstream os;
      os << "random packing reached solid fraction " << solid / box_volume << " of " << spec.solid_fraction << " after "
         << spec.max_attempts << " attempts";
      throw std::runtime_error(os.str());
    }
    const double margin = radius + spec.min_gap_m;
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) p[d] = spec.box_min_m[d] + margin + uni(rng) * (size[d] - 2.0 * margin);
    const Eigen::Vector3i c = grid.cellOf(p);
    bool free = true;
    for (int dx = -1; dx <= 1 && free; ++dx)
      for (int dy = -1; dy <= 1 && free; ++dy)
        for (int dz = -1; dz <= 1 && free; ++dz) {
          auto it = grid.cells.find(grid.key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == grid.cells.end()) continue;
          for (int j : it->second) {
            const double dmin = radius + out.radii_m[static_cast<std::size_t>(j)] + spec.min_gap_m;
            if ((out.centers_m[static_cast<std::size_t>(j)] - p).squaredNorm() < dmin * dmin) {
              free = false;
              break;
            }
          }
        }
    if (!free) continue;
    grid.cells[grid.key(c)].push_back(static_cast<int>(out.radii_m.size()));
    out.centers_m.push_back(p);
    out.radii_m.push_back(radius);
    solid += sphereVolume(radius);
    need_radius = true;
  }
  out.solid_fraction = solid / box_volume;
  return out;
}

}  // namespace gabion::micro
