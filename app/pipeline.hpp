#pragma once
/// \file
/// The `pipeline` case kind: the paper's whole chain in one run, through
/// each module's public case kinds only:
///   1. micro.cell: the cell (netting, angular blocks, vibration);
///   2. micro.cc, micro.uc, micro.uci, micro.shear: the virtual lab tests;
///   3. fit: every cell law from their curves, into law.json;
///   4. macro.impact at several velocities, macro.capacity, macro.design
///      with the calibrated law;
///   5. report.html with the numbers and the figures.
/// Each stage runs in its own folder and is reused while its content key
/// (its case and the bytes of its inputs) is unchanged. Format and stages:
/// docs/pipeline.md.
#include "bridge/run.hpp"

namespace gabion::app {

/// The `pipeline` case kind.
bridge::CaseKind pipelineKind();

}  // namespace gabion::app
