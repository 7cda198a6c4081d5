#pragma once
/// \file
/// A rendered view of a particle scene, drawn headless with cairo: spheres
/// as shaded discs and links as lines, seen from a direction (azimuth,
/// elevation) in orthographic projection, painted back to front. Used for
/// the picture of a generated cell (its blocks and netting) in the reports.
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace gabion::bridge {

/// What the view shows.
struct SceneView {
  struct Sphere {
    Eigen::Vector3d center_m;
    double radius_m = 0.0;
    int color = 0;  ///< 0xRRGGBB
  };
  struct Segment {
    Eigen::Vector3d a_m, b_m;
    int color = 0x404040;
    double width_px = 1.0;
  };
  std::vector<Sphere> spheres;
  std::vector<Segment> segments;
  std::string title;
  double azimuth_deg = 35.0;    ///< about z, from +x towards +y
  double elevation_deg = 25.0;  ///< above the horizontal plane (z is up)
  int width_px = 900, height_px = 700;
};

/// Renders `view` to a PNG file (atomically). Throws std::invalid_argument
/// for an empty view or a bad size, std::runtime_error when it cannot be
/// written.
void writeSceneViewPng(const std::filesystem::path& path, const SceneView& view);

}  // namespace gabion::bridge
