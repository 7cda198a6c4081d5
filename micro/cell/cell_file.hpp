#pragma once
/// \file
/// The cell file (`gabion.cell/2`, HDF5; docs/formats.md, Cell files): the
/// state of a packed scene (its spheres, blocks, links with their wire
/// states, and materials) as an engine has it at the end of a run, so that
/// later runs start from the same assembly (`"from_cell"` in a micro.scene).
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "micro/engine.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// The engine's current state of the bodies of `input` (the scene the engine
/// was built from) as a scene: the input's materials, walls, links and run,
/// with the bodies and walls where the engine has them (a wall's program
/// starts again from there) and the wires in their states (a wire being
/// pulled tight tied at the length it closed to, no longer pulled).
/// Broken links are left out (the others keep their indices' spheres).
Scene stateScene(const Scene& input, const Engine& engine);

/// Writes the engine's current state of the bodies of `input` (the scene the
/// engine was built from) to `path` (atomically), with `summary` as an
/// attribute. Broken links are left out.
void writeCellFile(const std::filesystem::path& path, const Scene& input, const Engine& engine,
                   const nlohmann::json& summary);

/// Appends the bodies, links and materials of a cell file to `scene`: the
/// cell's spheres after the scene's own (its links re-numbered), its blocks
/// after the scene's, its materials unless the scene has one of the same
/// name (the scene's wins: a test may change the friction of the cell it
/// starts from). A missing, truncated, foreign or wrong-version file is an
/// InputError naming the file.
void loadCellFile(const std::filesystem::path& path, Scene& scene);

}  // namespace gabion::micro
