#pragma once
/// \file
/// The `netting` object of a case: mesh geometry, wires, nodes and the
/// contact parameters of the nodes (docs/netting.md has every key).
#include "bridge/json_reader.hpp"
#include "micro/netting/mesh.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

struct NettingInput {
  MeshSpec mesh;
  /// How the nodes touch other bodies (density: the steel's; unused, the
  /// node masses are the netting's).
  Material contact;
};

/// Parses and checks a `netting` object; errors name the key. `defaults`:
/// the mesh whose values the keys left out take (a sheet's netting is the
/// paper's pin-jointed one unless asked; a cell's bends, has beads and
/// scaled node masses: micro/cell/cell_assembly.cpp).
NettingInput parseNetting(const bridge::JsonReader& r, const MeshSpec& defaults = MeshSpec{});

}  // namespace gabion::micro
