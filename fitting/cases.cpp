#include "fitting/cases.hpp"

namespace gabion::fitting {

std::vector<bridge::CaseKind> caseKinds() { return {}; }

}  // namespace gabion::fitting
