#include "fitting/cases.hpp"

#include "fitting/fit_case.hpp"
#include "fitting/macro_fit_case.hpp"
#include "fitting/micro_case.hpp"

namespace gabion::fitting {

std::vector<bridge::CaseKind> caseKinds() {
  return {fitCaseKind(), fitMicroCaseKind(), fitMacroCaseKind()};
}

}  // namespace gabion::fitting
