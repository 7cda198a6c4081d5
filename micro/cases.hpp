#pragma once
/// \file
/// The case kinds the `micro` module runs (registered with the `gabion` app).
#include <vector>

#include "bridge/run.hpp"

namespace gabion::micro {

/// Case kinds of this module, each with its check and run functions.
std::vector<bridge::CaseKind> caseKinds();

}  // namespace gabion::micro
