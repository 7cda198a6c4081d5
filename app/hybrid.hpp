#pragma once
/// \file
/// The hybrid structure (docs/resolved.md, Hybrid): a `macro.impact` case
/// with `"resolve"`. The cells within `resolve.within_m` of the aim point
/// are resolved at the fine scale (copies of a cell file, as
/// `micro.structure` lays them out); the others stay macro nodes. Each face
/// a resolved cell shares with a macro cell is a rigid plate in the fine
/// scene that moves with that cell's node, and the force the bodies exert
/// on the plate acts on the node: forces and displacements pass both ways,
/// and the work one side gives is exactly what the other receives (the
/// balance is reported). The two scales step together at the fine step.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "bridge/run.hpp"

namespace gabion::app {

/// macro.impact, with `"resolve"` run as the hybrid structure.
bridge::CaseKind withHybrid(const bridge::CaseKind& macro_impact);

/// Macro laws stand for resolved cells only if those are as large: the
/// cell's nominal edge (`cell_edge_m` of a micro.structure summary, for cells
/// made since their file records it) within 5 % of the laws' edge, or else
/// its extent (`cell_pitch_m`: the edge, the nodes and the netting's bulge)
/// within 20 %. The warning naming `who` (the macro model) where they
/// differ, none where they agree or `law_edge_m` is not known (<= 0).
std::optional<std::string> cellSizeMismatch(double law_edge_m, const nlohmann::json& fine_summary,
                                            const std::string& who);

}  // namespace gabion::app
