#include "micro/cell/porosity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace gabion::micro {

double solidFraction(const std::vector<Eigen::Vector3d>& centers, const std::vector<double>& radii,
                     const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double spacing) {
  const Eigen::Vector3d size = hi - lo;
  if (!(size.minCoeff() > 0.0) || !(spacing > 0.0)) throw std::invalid_argument("solidFraction: empty box or spacing");
  // Cells per axis, the spacing adjusted so that they tile the box exactly.
  long n[3];
  Eigen::Vector3d h;
  for (int c = 0; c < 3; ++c) {
    n[c] = std::max(1L, std::lround(size[c] / spacing));
    h[c] = size[c] / static_cast<double>(n[c]);
  }
  const auto total = static_cast<std::size_t>(n[0] * n[1] * n[2]);
  std::vector<std::uint64_t> solid((total + 63) / 64, 0);
  // Each sphere marks the cells whose centres it holds, row by row in x.
  for (std::size_t s = 0; s < centers.size(); ++s) {
    const Eigen::Vector3d& x = centers[s];
    const double r = radii[s], r2 = r * r;
    long from[3], to[3];
    for (int c = 0; c < 3; ++c) {
      from[c] = std::max(0L, static_cast<long>(std::ceil((x[c] - r - lo[c]) / h[c] - 0.5)));
      to[c] = std::min(n[c] - 1, static_cast<long>(std::floor((x[c] + r - lo[c]) / h[c] - 0.5)));
    }
    for (long k = from[2]; k <= to[2]; ++k) {
      const double dz = lo.z() + (static_cast<double>(k) + 0.5) * h.z() - x.z();
      for (long j = from[1]; j <= to[1]; ++j) {
        const double dy = lo.y() + (static_cast<double>(j) + 0.5) * h.y() - x.y();
        const double rest = r2 - dy * dy - dz * dz;
        if (rest < 0.0) continue;
        // The cells of this row whose centres are within sqrt(rest) of x.
        const double half = std::sqrt(rest);
        const long i0 = std::max(from[0], static_cast<long>(std::ceil((x.x() - half - lo.x()) / h.x() - 0.5)));
        const long i1 = std::min(to[0], static_cast<long>(std::floor((x.x() + half - lo.x()) / h.x() - 0.5)));
        const std::size_t row = static_cast<std::size_t>((k * n[1] + j) * n[0]);
        for (long i = i0; i <= i1; ++i) {
          const std::size_t cell = row + static_cast<std::size_t>(i);
          solid[cell / 64] |= std::uint64_t{1} << (cell % 64);
        }
      }
    }
  }
  std::size_t count = 0;
  for (const std::uint64_t w : solid) count += static_cast<std::size_t>(__builtin_popcountll(w));
  return static_cast<double>(count) / static_cast<double>(total);
}

}  // namespace gabion::micro
