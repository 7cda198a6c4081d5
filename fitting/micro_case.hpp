#pragma once
/// \file
/// The `fit.micro` case kind: identifies micro contact parameters (k_n, k_s,
/// friction, F_lim, ...) so that a micro virtual test matches lab curves, with
/// the DEM run inside the objective. Any micro case kind plugs in: the base
/// case's "kind" is looked up in micro::caseKinds() and run in-process through
/// that public interface only. Format: docs/fitting.md.
#include "bridge/run.hpp"

namespace gabion::fitting {

/// The `fit.micro` case kind.
bridge::CaseKind fitMicroCaseKind();

}  // namespace gabion::fitting
