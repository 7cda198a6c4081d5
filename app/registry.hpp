#pragma once
/// \file
/// All case kinds known to the `gabion` command, gathered from the modules.
#include <string>
#include <vector>

#include "bridge/run.hpp"

namespace gabion::app {

const std::vector<bridge::CaseKind>& allKinds();
/// nullptr when no module runs `kind`.
const bridge::CaseKind* findKind(const std::string& kind);
/// "a, b, c" for messages.
std::string kindList();

}  // namespace gabion::app
