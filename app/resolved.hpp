#pragma once
/// \file
/// The `macro.resolved` case kind (docs/resolved.md): how far the
/// one-node-per-cell model is from the structure it stands for. One case
/// names a structure, a boulder, a cell file and the laws fitted from that
/// cell; it runs the structure twice, through the modules' public kinds:
///   - resolved: `micro.structure`, every cell a copy of the generated cell
///     (blocks and netting), into OUTDIR/resolved;
///   - the macro twin: `macro.impact` with the fitted laws, into
///     OUTDIR/macro_twin;
/// and reports both on the same keys, the relative errors of the twin, the
/// wall times and their ratio, and a figure of both force histories.
#include "bridge/run.hpp"

namespace gabion::app {

bridge::CaseKind resolvedKind();

}  // namespace gabion::app
