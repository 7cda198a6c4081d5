#pragma once
/// \file
/// Porosity of a packing inside a box (docs/blocks.md, Porosity): the volume
/// the union of the spheres fills, each point counted once however many
/// member spheres (of one block or of touching blocks) cover it.
#include <Eigen/Core>
#include <vector>

namespace gabion::micro {

/// Fraction of the box [lo, hi] inside the union of the spheres, by the
/// midpoint rule on a regular grid of about `spacing_m`: a grid cell is solid
/// when its centre is inside some sphere. Spheres partly outside the box count
/// with their part inside. With spacing h and spheres of radius r the error
/// of one sphere's volume is of the order of (h / r)^1.5 and of random sign,
/// so a packing of many spheres is measured far better (tests/micro/test_porosity.cpp).
double solidFraction(const std::vector<Eigen::Vector3d>& centers_m, const std::vector<double>& radii_m,
                     const Eigen::Vector3d& lo_m, const Eigen::Vector3d& hi_m, double spacing_m);

}  // namespace gabion::micro
