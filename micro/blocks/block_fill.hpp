#pragma once
/// \file
/// Block fills in a micro.scene (`"block_fills": [...]`, docs/blocks.md):
/// angular blocks of one shape, sized to a grading table or a Gaussian until
/// a mass of rock, placed without overlap in a region (largest first, side
/// by side in rows and layers, each block laid flat, its long edge along x
/// or y and either way up as the seed draws), ready to fall. The generated grading is reported beside its
/// target.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// Appends the block fills of `root` (if any) to the scene; returns one
/// report per fill (blocks, mass, and the grading against its target).
nlohmann::json addBlockFills(const bridge::JsonReader& root, Scene& scene);

/// Writes one figure per fill, grading_<k>.png in `outdir`: the % passing
/// made and, for a grading table, its target, against the sieve size.
/// Returns the files written.
std::vector<std::string> writeGradingFigures(const std::filesystem::path& outdir, const nlohmann::json& reports);

}  // namespace gabion::micro
