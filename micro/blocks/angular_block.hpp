#pragma once
/// \file
/// Angular rock blocks as rigid multi-sphere bodies (the paper's fill): a
/// parallelepiped lattice of equal spheres whose edges and corners are cut
/// away to set the angularity (docs/blocks.md). Mass, centre and inertia come
/// from micro/rigid_body (the union of the member spheres).
#include <Eigen/Core>
#include <string>
#include <vector>

namespace gabion::micro {

/// The shape of a block, independent of its size.
struct BlockShape {
  /// Edge lengths relative to the intermediate one: long >= 1 >= short.
  double long_ratio = 1.4, short_ratio = 0.7;
  /// Member spheres along the longest edge (>= 1): the resolution of the shape.
  int spheres_along_long = 6;
  /// Spacing of the lattice over the sphere diameter, in (0, 1]: 1 puts the
  /// spheres side by side, less overlaps them for a smoother surface. The
  /// default 0.5 gives the gravity-filled porosity of the paper's model
  /// (about 0.50; docs/blocks.md).
  double spacing_ratio = 0.5;
  /// How deep edges and corners are cut, in [0, 1): 0 keeps the whole
  /// parallelepiped. With d_c the depth of a lattice centre below face c
  /// (each axis: its largest centre coordinate minus |x_c|), d*_c the
  /// deepest d_c of the lattice and the depth D = cut x the smallest
  /// d*_i + d*_j, a sphere stays when d_i + d_j >= D for every pair of axes
  /// (edges) and d_x + d_y + d_z >= 1.5 D (corners; at most the innermost
  /// sphere's sum): the innermost spheres stay for any cut below 1. The
  /// lattice is discrete, so the cut acts in steps (default lattice: 72
  /// spheres uncut, 36 with the edges chamfered for cut 0.1 - 0.4, 24 at 0.5,
  /// 8 at 0.6 - 0.9).
  double cut = 0.3;
};

/// What is wrong with a shape, with the name of the key, or empty.
struct BlockShapeIssue {
  std::string key, message;
};
BlockShapeIssue checkBlockShape(const BlockShape& shape);

/// The member spheres of a block of sieve size `size_m` (its intermediate
/// edge), centred on the origin, edges along x (long), y (intermediate), z
/// (short).
struct BlockGeometry {
  std::vector<Eigen::Vector3d> centers_m;
  std::vector<double> radii_m;
  Eigen::Vector3d edges_m = Eigen::Vector3d::Zero();  ///< outer edge lengths of the lattice (m)
};
BlockGeometry angularBlock(const BlockShape& shape, double size_m);
/// The unit block (intermediate edge 1): every size is it, scaled.
BlockGeometry angularBlock(const BlockShape& shape);

}  // namespace gabion::micro
