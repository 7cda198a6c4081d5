#pragma once
/// \file
/// `gabion plot RESULT.h5`: the standard figure of any run's result file,
/// chosen by what the file holds (docs/formats.md):
///   - a lab test's curves (`/curves/axial`, `/curves/uc`, `/curves/impact`,
///     `/curves/shear`): force (kN) against displacement or penetration (mm);
///   - a structure impact (`/series/boulder_force_N`): the boulder force (kN)
///     against time (ms), one line per impact;
///   - a sweep's table (`/table/impact_energy_J`): the peak force (kN)
///     against the impact energy (kJ);
///   - a fine-DEM scene (`/series/total_J`): its energy ledger (J) against
///     time (s).
#include <filesystem>

namespace gabion::app {

/// Writes the standard figure of `result` to `figure` (PNG, or SVG when its
/// name ends in .svg). Throws bridge::InputError naming the file when it
/// holds none of the above.
void writeStandardFigure(const std::filesystem::path& result, const std::filesystem::path& figure);

}  // namespace gabion::app
