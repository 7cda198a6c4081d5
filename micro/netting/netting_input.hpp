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

/// Parses and checks a `netting` object; errors name the key. `bending`: the
/// default of its `bending` key (a cell's netting bends, a sheet's is the
/// paper's pin-jointed one unless asked).
NettingInput parseNetting(const bridge::JsonReader& r, bool bending = false);

}  // namespace gabion::micro
