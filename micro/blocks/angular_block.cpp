#include "micro/blocks/angular_block.hpp"

#include <algorithm>
#include <cmath>

namespace gabion::micro {

BlockShapeIssue checkBlockShape(const BlockShape& s) {
  if (!(s.long_ratio >= 1.0 && std::isfinite(s.long_ratio)))
    return {"long_ratio", "must be >= 1 (the long edge over the intermediate one)"};
  if (!(s.short_ratio > 0.0 && s.short_ratio <= 1.0)) return {"short_ratio", "must be in (0, 1]"};
  if (s.spheres_along_long < 1 || s.spheres_along_long > 64) return {"spheres_along_long", "must be in 1 .. 64"};
  if (!(s.spacing_ratio > 0.0 && s.spacing_ratio <= 1.0)) return {"spacing_ratio", "must be in (0, 1]"};
  if (!(s.cut >= 0.0 && s.cut < 1.0)) return {"cut", "must be in [0, 1)"};
  return {};
}

BlockGeometry angularBlock(const BlockShape& shape, double size_m) {
  // The lattice is laid out for the unit block and scaled, so that every
  // size has the same spheres (a count rounded from each size's own edges
  // would flip at a tie, 1.5 for the default shape, between sizes).
  BlockGeometry g = angularBlock(shape);
  g.edges_m *= size_m;
  for (Eigen::Vector3d& c : g.centers_m) c *= size_m;
  for (double& r : g.radii_m) r *= size_m;
  return g;
}

BlockGeometry angularBlock(const BlockShape& shape) {
  const Eigen::Vector3d edges(shape.long_ratio, 1.0, shape.short_ratio);
  // Equal spheres: n along the long edge at spacing s = 2 r x spacing_ratio,
  // so that the lattice's outer length is (n - 1) s + 2 r = long edge.
  const int n_long = shape.spheres_along_long;
  const double r = edges.x() / (2.0 + 2.0 * shape.spacing_ratio * (n_long - 1));
  const double s = 2.0 * r * shape.spacing_ratio;
  BlockGeometry g;
  g.edges_m = edges;
  int n[3];
  for (int c = 0; c < 3; ++c)  // as many spheres as fit along the edge (at least one; a tie rounds up)
    n[c] = c == 0 ? n_long : std::max(1, 1 + static_cast<int>(std::floor((edges[c] - 2.0 * r) / s + 0.5 + 1e-9)));
  // The lattice spans exactly the edges: spacing per axis from its own count.
  Eigen::Vector3d half, step;
  for (int c = 0; c < 3; ++c) {
    half[c] = 0.5 * edges[c] - r;  // largest centre coordinate
    if (half[c] < 0.0) half[c] = 0.0;
    step[c] = n[c] > 1 ? 2.0 * half[c] / (n[c] - 1) : 0.0;
  }
  // Chamfer depth: the cut times the smallest sum of two axes' deepest
  // lattice depths, so that the innermost spheres stay for any cut < 1.
  Eigen::Vector3d deepest;
  for (int c = 0; c < 3; ++c) {
    deepest[c] = 0.0;
    for (int q = 0; q < n[c]; ++q) deepest[c] = std::max(deepest[c], half[c] - std::fabs(-half[c] + q * step[c]));
  }
  const double depth =
      shape.cut * std::min({deepest.x() + deepest.y(), deepest.y() + deepest.z(), deepest.x() + deepest.z()});
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        const Eigen::Vector3d x(-half.x() + i * step.x(), -half.y() + j * step.y(), -half.z() + k * step.z());
        // Depth inside each face, and the chamfers of edges and corners.
        Eigen::Vector3d d;
        for (int c = 0; c < 3; ++c) d[c] = half[c] - std::fabs(x[c]);
        const double eps = 1e-9;  // (the unit block)
        const bool edge_ok =
            d.x() + d.y() >= depth - eps && d.y() + d.z() >= depth - eps && d.x() + d.z() >= depth - eps;
        const bool corner_ok = d.sum() >= std::min(1.5 * depth, deepest.sum()) - eps;
        if (!edge_ok || !corner_ok) continue;
        g.centers_m.push_back(x);
        g.radii_m.push_back(r);
      }
  return g;
}

}  // namespace gabion::micro
