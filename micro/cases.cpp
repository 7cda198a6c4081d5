#include "micro/cases.hpp"

namespace gabion::micro {

std::vector<bridge::CaseKind> caseKinds() { return {}; }

}  // namespace gabion::micro
