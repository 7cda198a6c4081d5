#pragma once
/// \file
/// Nettings in a micro.scene (`"nettings": [...]`, docs/netting.md): each
/// entry is a `netting` object plus its shape (a flat `sheet` or a closed
/// `box`, placed at `origin_m`), the node sets held fixed and a contact
/// group. Its nodes become spheres after the scene's own, its wires links,
/// its contact parameters a material of its own.
#include "bridge/json_reader.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// Appends the nettings of `root` (if any) to the scene.
void addNettings(const bridge::JsonReader& root, Scene& scene);

}  // namespace gabion::micro
