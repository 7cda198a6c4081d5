#pragma once
/// \file
/// The `fit.macro` case kind: identifies macro law parameters (the impact
/// law's, the axial law's, any key of a law file) so that a macro.impact
/// case matches measured or resolved histories of the structure (the force
/// on the boulder, its penetration against time), at one or more impact
/// scenarios, with the macro run inside the objective. The macro case is
/// read, built and run in-process through the macro module's public
/// interface (macro/case_reader.hpp, macro/impact.hpp). Format:
/// docs/fitting.md, "fit.macro".
#include "bridge/run.hpp"

namespace gabion::fitting {

/// The `fit.macro` case kind.
bridge::CaseKind fitMacroCaseKind();

}  // namespace gabion::fitting
