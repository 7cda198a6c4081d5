#pragma once
/// \file
/// The `fit` case kind: identifies the macro cell laws (axial, lateral,
/// interface, impact) from curves, writes law.json (gabion.law/2), plots and
/// the summary entries. No DEM inside the loop. Format: docs/fitting.md.
#include "bridge/run.hpp"

namespace gabion::fitting {

/// The `fit` case kind.
bridge::CaseKind fitCaseKind();

}  // namespace gabion::fitting
