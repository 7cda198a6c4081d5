#include "macro/cases.hpp"

namespace gabion::macro {

std::vector<bridge::CaseKind> caseKinds() { return {}; }

}  // namespace gabion::macro
