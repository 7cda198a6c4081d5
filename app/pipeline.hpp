#pragma once
/// \file
/// The `pipeline` case kind: the whole calibration chain of DESIGN.md in one
/// run, through each module's public case kinds only:
///   1. micro: generate a loose packing of grains in a cell-sized box, settle
///      it under gravity (micro.scene), then drive the lid down with the four
///      lateral walls fixed: the confined compression (CC) test of the paper;
///   2. curves: the lid's force against the cell shortening, and the mean
///      lateral wall force against the axial force, written as CSV;
///   3. fit: the axial law and the lateral reaction coefficient identified
///      from those curves (the `fit` kind), the other laws carried from the
///      structure's base law file and marked so in the provenance;
///   4. macro: the structure case run with the fitted law for each boulder
///      velocity (the `macro.impact` kind);
///   5. report.md with the numbers and the plots.
/// Format and stages: docs/pipeline.md.
#include "bridge/run.hpp"

namespace gabion::app {

/// The `pipeline` case kind.
bridge::CaseKind pipelineKind();

}  // namespace gabion::app
