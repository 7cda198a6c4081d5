#pragma once
/// \file
/// Block fills in a micro.scene (`"block_fills": [...]`, docs/blocks.md):
/// angular blocks of one shape, sized to a grading table or a Gaussian until
/// a mass of rock, placed without overlap in a region (largest first, side
/// by side in rows and layers, each block laid flat, its long edge along x
/// or y and either way up as the seed draws), ready to fall. The generated grading is reported beside its
/// target.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// Appends the block fills of `root` (if any) to the scene; returns one
/// report per fill (blocks, mass, and the grading against its target).
nlohmann::json addBlockFills(const bridge::JsonReader& root, Scene& scene);

/// One fill whose material, region [lo, hi] and mass of rock (kg) the caller
/// gives (a cell's), with its seed; `r` has the other keys of a block_fills
/// entry (shape, grading or gaussian, group). Appends its blocks to the
/// scene and returns its report; calls `too_small` (which throws) if they
/// do not fit.
nlohmann::json addBlockFill(const bridge::JsonReader& r, Scene& scene, int material, const Vec3& lo, const Vec3& hi,
                            double target_mass_kg, std::uint64_t seed,
                            const std::function<void(const std::string&)>& too_small);

/// Writes one figure per fill, grading_<k>.png in `outdir`: the % passing
/// made and, for a grading table, its target, against the sieve size.
/// Returns the files written.
std::vector<std::string> writeGradingFigures(const std::filesystem::path& outdir, const nlohmann::json& reports);

}  // namespace gabion::micro
