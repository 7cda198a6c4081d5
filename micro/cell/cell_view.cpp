#include "micro/cell/cell_view.hpp"

#include <array>

#include "bridge/scene_view.hpp"

namespace gabion::micro {

void writeCellView(const std::filesystem::path& file, const Scene& scene, const std::string& title) {
  // Limestone tones, distinct enough for neighbouring blocks.
  constexpr std::array<int, 6> kStone{0xc8b89a, 0xa8987c, 0xd8ccb2, 0xb4a488, 0xbeb095, 0x9c8c72};
  bridge::SceneView v;
  v.title = title;
  for (std::size_t k = 0; k < scene.blocks.size(); ++k) {
    const BlockSpec& b = scene.blocks[k];
    for (std::size_t m = 0; m < b.member_centers_m.size(); ++m)
      v.spheres.push_back(
          {b.position_m + b.orientation * b.member_centers_m[m], b.member_radii_m[m], kStone[k % kStone.size()]});
  }
  // The netting: its wires, and its nodes drawn at a third of their contact
  // radius so that the mesh does not hide the stones.
  for (const SphereSpec& s : scene.spheres) v.spheres.push_back({s.center_m, s.radius_m / 3.0, 0x303030});
  for (const LinkSpec& l : scene.links)
    if (l.a < scene.spheres.size() && l.b < scene.spheres.size())
      v.segments.push_back({scene.spheres[l.a].center_m, scene.spheres[l.b].center_m, 0x262626, 1.3});
  bridge::writeSceneViewPng(file, v);
}

}  // namespace gabion::micro
