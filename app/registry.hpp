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

/// Validates a whole case: "format" (gabion.case/1), "kind" (a registered
/// kind, or `expected_kind` when given), the optional "description", the
/// kind's own keys, and no unknown key. Throws InputError; returns the kind.
const bridge::CaseKind& checkCase(const bridge::JsonDocument& doc, const std::string& expected_kind = "");

}  // namespace gabion::app
