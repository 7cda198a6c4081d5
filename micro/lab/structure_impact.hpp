#pragma once
/// \file
/// `micro.structure`, a structure resolved at the fine scale (docs/resolved.md):
/// nx x ny x nz copies of one cell (a cell file, or a micro.cell case
/// generated first), side by side at the pitch of the cell's outer extent so
/// that neighbouring cells meet through their nettings, on a rigid base and
/// (by default) against a rigid back support, as a macro.impact structure
/// is laid out: x the depth from the front face, y the width, z the height.
/// The stack first settles under its weight; then a spherical boulder
/// strikes the front face along +x. Its force, penetration and contact
/// time, the front and back cells' displacements and the outcome are
/// those of macro.impact, measured on the resolved cells.
#include "bridge/run.hpp"

namespace gabion::micro::lab {

bridge::CaseKind structureImpactKind();

}  // namespace gabion::micro::lab
